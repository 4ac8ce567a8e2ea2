//! Paper 002's plant: Liu et al.'s bond-graph spindle + x-axis model, usable as the whole machine.
//!
//! ## Eq 5 as printed, with Table 1
//!
//! Liu et al.'s eq 5 with the evident typesetting errors repaired (ṗ₇ is ṗ₆; the first line's
//! r_s/J_m1 multiplies p₆; q₉ and p₁₇ are q₁₇), plus three terms cutlab adds (zero in the paper's
//! model): the spindle's viscous drag b_s, the cut's torque on the spindle c_T·v and the cut's
//! feed force c_f·v on the table:
//!
//! ```text
//! ṗ₃  = S_e1 − (R_s1/L_q1)·p₃ − (r_s/J_m1)·p₆                          spindle armature
//! ṗ₆  = (r_s/L_q1)·p₃ − (b_s/J_m1)·p₆ − m_s·K_L·q₁₇ − c_T·p₂₀/M        spindle rotor
//! ṗ₁₁ = S_e2 − (R_s2/L_q2)·p₁₁ − (r_x/J_m2)·p₁₄                         x-axis armature
//! ṗ₁₄ = (r_x/L_q2)·p₁₁ − m_x·K_L·q₁₇                                     x-axis rotor
//! q̇₁₇ = (m_s/J_m1)·p₆ + (m_x/J_m2)·p₁₄ − p₂₀/M                           compliance
//! ṗ₂₀ = K_L·q₁₇ − ((C_z + c_f)/M)·p₂₀                                     translating mass
//! ```
//!
//! The currents are i = p₃/L_q1 and p₁₁/L_q2, the speeds p₆/J_m1, p₁₄/J_m2, p₂₀/M, the screw's
//! force K_L·q₁₇. The model is linear, so it is discretised exactly (matrix exponential,
//! zero-order hold) once per load level.
//!
//! With Table 1's values ([`BondGraphParams::default`]) and no cut, at rated voltages from rest
//! it settles in about 3 s to a spindle current of 12.9 A; paper 002 reports "about 3 s" and
//! 12 A (checked against scipy in `tests/plant_reduced.rs`). The same steady state has a table
//! speed of 19 800 mm/min where the paper prints 1440 mm/min, and no machine could run it:
//!
//! * m_s couples the spindle's rotation into the table's speed (q̇₁₇ holds m_s·ω_s), so with the
//!   spindle turning the x axis must turn backwards to hold the table still, and the spindle
//!   draws no current at all while the table stands (its only load is m_s·K_L·q₁₇);
//! * r_x = 0.0561 N·m/A with m_x = 0.014 m (88 mm of table per motor turn) makes the x-axis current
//!   0.25 A per newton on the screw: thousands of amperes for the force of a cut;
//! * the "force" that loads the spindle is the screw's, with no cut behind it.
//!
//! ## The machining centre behind `liu-current-step`
//!
//! [`BondGraphParams::machining_centre`] keeps Table 1's values where they are physical and
//! chooses the others (each field's docs say which and why): the x axis a 12 N·m-class servo on a
//! 10 mm-lead ball screw, the spindle a 15 kW-class DC drive at 1500 rpm with bearing drag, and
//! m_s = 0: the spindle and the table meet in the cut ([`BondGraphCut`]), not in the screw. The
//! cut is a Ø50 mm, 5-insert face mill climb-milling SM45C steel 40 mm wide; its mean chip forces
//! (Altintas' closed form, [`super::mechanics::mean_forces`], without the edge forces so that the
//! force stays proportional to the feed and the model linear) give c_T and c_f at the spindle
//! speed of the reference cut, and the depth is the one at which the spindle draws paper 002's
//! 25 A at 1500 mm/min ([`BondGraphRun::depth_for_current`]). A load step is a step in that depth.
//!
//! Table 1's armature inductances (88/85 mH) with physical torque constants would ring at a few
//! hertz for seconds (damping ratio ≈ 0.03); the machining centre's motors have a few
//! millihenries. What gave eq 5 its "about 3 s" — the x axis's L_q2/R_s2 = 0.57 s — is kept where
//! a machine has it: the control smooths the commanded feed through an exponential
//! acceleration/deceleration of that time constant ([`BondGraphRun::feed_time_constant_s`]), so
//! the feed, and with it the cut's force and the spindle current, settles about 3 s after an
//! override change, as the paper's plant did.
//!
//! As a [`crate::machine::Machine`] the x-axis voltage S_e2 is set, each sample, to the value that
//! gives the smoothed commanded feed in steady state (exact, the model being linear); the
//! transient is the bond graph's own.
//!
//! NaN voltages propagate into the state and stay there.

use serde::{Deserialize, Serialize};
use std::f64::consts::{SQRT_2, TAU};

use super::cnc::{CncConfig, Control, PlanBlock};
use super::feed_drive::{three_phase_rms_a, ThreePhaseWaveform};
use super::linalg::{self, Mat};
use super::materials::{CuttingCoefficients, Material};
use super::mechanics::{mean_forces, Cutter, Immersion, MillingMode, ToolForces};
use super::sensors::{
    AdcConfig, CurrentSensor, CurrentSensorConfig, HallSensorConfig, PhaseWiring,
};
use super::signals::{AxisSignals, PlantSignals};
use super::spindle_drive::SpindleDriveConfig;
use super::{
    non_negative, positive, rpm_from_rad_s, PlantError, PlantModel, PlantSample, Sampling, Tick,
    S_PER_MIN,
};
use crate::machine::{OverrideCommand, PlantTruth, SensorSample};

/// Paper 002's reference current I_ref (§5, Fig. 7).
pub const PAPER_002_REFERENCE_CURRENT_A: f64 = 25.0;

/// Paper 002's programmed feed (§5, Fig. 7).
pub const PAPER_002_FEED_MM_MIN: f64 = 1500.0;

/// Eq 5's parameters: Table 1, and the terms cutlab adds.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BondGraphParams {
    /// Spindle motor voltage S_e1. Table 1: 380 V (rated).
    pub spindle_voltage_v: f64,
    /// x-axis motor rated voltage S_e2. Table 1: 220 V. As a machine the control sets S_e2 for
    /// the commanded feed; this is the voltage of [`BondGraphParams::steady_state`]'s examples.
    pub feed_voltage_v: f64,
    /// Spindle armature resistance R_s1. Table 1: 0.132 Ω.
    pub spindle_resistance_ohm: f64,
    /// x-axis armature resistance R_s2. Table 1: 0.15 Ω.
    pub feed_resistance_ohm: f64,
    /// Spindle armature inductance L_q1. Table 1: 88 mH.
    pub spindle_inductance_h: f64,
    /// x-axis armature inductance L_q2. Table 1: 85 mH.
    pub feed_inductance_h: f64,
    /// Spindle armature (gyrator) coefficient r_s, V·s/rad = N·m/A. Table 1: 9.68.
    pub spindle_armature_coefficient: f64,
    /// x-axis armature coefficient r_x, N·m/A. Table 1: 0.0561.
    pub feed_armature_coefficient: f64,
    /// Spindle drive moment of inertia J_m1. Table 1: 0.0048 kg·m².
    pub spindle_inertia_kg_m2: f64,
    /// x-axis drive moment of inertia J_m2. Table 1: 0.0063 kg·m².
    pub feed_inertia_kg_m2: f64,
    /// Spindle conversion coefficient m_s: how far the spindle's rotation moves the compliance,
    /// m per rad. Table 1: 0.021 m.
    pub spindle_conversion_m: f64,
    /// x-axis conversion coefficient m_x: table travel per motor radian. Table 1: 0.014 m.
    pub feed_conversion_m: f64,
    /// Equivalent compressive stiffness K_L. Table 1: 37 MN/m.
    pub stiffness_n_per_m: f64,
    /// Translational mass M. Table 1: 1100 kg.
    pub mass_kg: f64,
    /// Viscous damping C_z. Table 1: 18 kN·s/m.
    pub damping_n_s_per_m: f64,
    /// Viscous drag b_s on the spindle (bearings, seals, belt, air), N·m·s/rad. Not in eq 5: 0
    /// in Table 1's model.
    pub spindle_drag_n_m_s_per_rad: f64,
}

impl Default for BondGraphParams {
    /// Table 1, as printed.
    fn default() -> Self {
        Self {
            spindle_voltage_v: 380.0,
            feed_voltage_v: 220.0,
            spindle_resistance_ohm: 0.132,
            feed_resistance_ohm: 0.15,
            spindle_inductance_h: 0.088,
            feed_inductance_h: 0.085,
            spindle_armature_coefficient: 9.68,
            feed_armature_coefficient: 0.0561,
            spindle_inertia_kg_m2: 0.0048,
            feed_inertia_kg_m2: 0.0063,
            spindle_conversion_m: 0.021,
            feed_conversion_m: 0.014,
            stiffness_n_per_m: 37e6,
            mass_kg: 1100.0,
            damping_n_s_per_m: 18e3,
            spindle_drag_n_m_s_per_rad: 0.0,
        }
    }
}

/// The cut's load on eq 5, per unit of table speed: at a steady spindle speed the chip's mean
/// forces are proportional to the feed per tooth, hence to the table speed v.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct CutLoad {
    /// Force against the table's motion per table speed, c_f (N per m/s): the mean feed force
    /// is c_f·v.
    pub feed_n_s_per_m: f64,
    /// Cutting torque on the spindle per table speed, c_T (N·m per m/s): the mean cutting
    /// torque is c_T·v.
    pub torque_n_m_s_per_m: f64,
}

impl CutLoad {
    /// No cut: eq 5 as printed.
    pub const NONE: CutLoad = CutLoad {
        feed_n_s_per_m: 0.0,
        torque_n_m_s_per_m: 0.0,
    };
}

impl BondGraphParams {
    /// The machining centre behind `liu-current-step`: Table 1 where it is physical, chosen
    /// values where it is not (see the module docs).
    ///
    /// | parameter | value | from |
    /// |---|---|---|
    /// | S_e1, R_s1 | 380 V, 0.132 Ω | Table 1 |
    /// | r_s | 2.4 N·m/A | chosen: a 15 kW-class spindle motor, 60 N·m at 25 A, 1500 rpm at 380 V |
    /// | L_q1 | 5 mH | chosen: a motor's own inductance (Table 1's 88 mH rings for seconds) |
    /// | J_m1 | 0.1 kg·m² | chosen: the motor's rotor with spindle, pulley and cutter (Table 1's 0.0048 is a small servo's) |
    /// | b_s | 0.03 N·m·s/rad | chosen: 4.7 N·m of drag at 1500 rpm, 2 A and 0.7 kW at idle |
    /// | m_s | 0 | chosen: the spindle meets the table in the cut ([`CutLoad`]), not in the screw |
    /// | S_e2 (rated), R_s2, J_m2 | 220 V, 0.15 Ω, 0.0063 kg·m² | Table 1 |
    /// | r_x | 1.2 N·m/A | chosen: a 12 N·m-class AC servo (Table 1's 0.0561 is a 25 W motor's) |
    /// | L_q2 | 5 mH | chosen, as L_q1 |
    /// | m_x | 10 mm / 2π | chosen: a 10 mm-lead ball screw, direct (Table 1's 0.014 m is 88 mm a turn) |
    /// | K_L, M, C_z | 37 MN/m, 1100 kg, 18 kN·s/m | Table 1 |
    ///
    /// ```
    /// use cutlab::plant::bond_graph::{BondGraphParams, CutLoad};
    /// let p = BondGraphParams::machining_centre();
    /// let idle = p.steady_state(p.spindle_voltage_v, 0.0, CutLoad::NONE).unwrap();
    /// assert!((idle.spindle_current_a - 1.98).abs() < 0.01); // the drag alone
    /// assert!(idle.table_velocity_m_s.abs() < 1e-12); // m_s = 0: the spindle does not move the table
    /// ```
    pub fn machining_centre() -> Self {
        Self {
            spindle_armature_coefficient: 2.4,
            spindle_inductance_h: 0.005,
            spindle_inertia_kg_m2: 0.1,
            spindle_drag_n_m_s_per_rad: 0.03,
            spindle_conversion_m: 0.0,
            feed_armature_coefficient: 1.2,
            feed_inductance_h: 0.005,
            feed_conversion_m: 0.01 / TAU,
            ..Self::default()
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        super::finite("spindle_voltage_v", self.spindle_voltage_v)?;
        super::finite("feed_voltage_v", self.feed_voltage_v)?;
        positive("spindle_resistance_ohm", self.spindle_resistance_ohm)?;
        positive("feed_resistance_ohm", self.feed_resistance_ohm)?;
        positive("spindle_inductance_h", self.spindle_inductance_h)?;
        positive("feed_inductance_h", self.feed_inductance_h)?;
        positive(
            "spindle_armature_coefficient",
            self.spindle_armature_coefficient,
        )?;
        positive("feed_armature_coefficient", self.feed_armature_coefficient)?;
        positive("spindle_inertia_kg_m2", self.spindle_inertia_kg_m2)?;
        positive("feed_inertia_kg_m2", self.feed_inertia_kg_m2)?;
        non_negative("spindle_conversion_m", self.spindle_conversion_m)?;
        positive("feed_conversion_m", self.feed_conversion_m)?;
        positive("stiffness_n_per_m", self.stiffness_n_per_m)?;
        positive("mass_kg", self.mass_kg)?;
        non_negative("damping_n_s_per_m", self.damping_n_s_per_m)?;
        non_negative(
            "spindle_drag_n_m_s_per_rad",
            self.spindle_drag_n_m_s_per_rad,
        )?;
        Ok(())
    }

    /// Eq 5 as ẋ = A·x + B·[S_e1, S_e2] for state [p₃, p₆, p₁₁, p₁₄, q₁₇, p₂₀], with the cut's
    /// load `cut`.
    pub fn state_space(&self, cut: CutLoad) -> (Mat<6>, [[f64; 2]; 6]) {
        let p = self;
        let kl = p.stiffness_n_per_m;
        let a = [
            [
                -p.spindle_resistance_ohm / p.spindle_inductance_h,
                -p.spindle_armature_coefficient / p.spindle_inertia_kg_m2,
                0.0,
                0.0,
                0.0,
                0.0,
            ],
            [
                p.spindle_armature_coefficient / p.spindle_inductance_h,
                -p.spindle_drag_n_m_s_per_rad / p.spindle_inertia_kg_m2,
                0.0,
                0.0,
                -p.spindle_conversion_m * kl,
                -cut.torque_n_m_s_per_m / p.mass_kg,
            ],
            [
                0.0,
                0.0,
                -p.feed_resistance_ohm / p.feed_inductance_h,
                -p.feed_armature_coefficient / p.feed_inertia_kg_m2,
                0.0,
                0.0,
            ],
            [
                0.0,
                0.0,
                p.feed_armature_coefficient / p.feed_inductance_h,
                0.0,
                -p.feed_conversion_m * kl,
                0.0,
            ],
            [
                0.0,
                p.spindle_conversion_m / p.spindle_inertia_kg_m2,
                0.0,
                p.feed_conversion_m / p.feed_inertia_kg_m2,
                0.0,
                -1.0 / p.mass_kg,
            ],
            [
                0.0,
                0.0,
                0.0,
                0.0,
                kl,
                -(p.damping_n_s_per_m + cut.feed_n_s_per_m) / p.mass_kg,
            ],
        ];
        let b = [
            [1.0, 0.0],
            [0.0, 0.0],
            [0.0, 1.0],
            [0.0, 0.0],
            [0.0, 0.0],
            [0.0, 0.0],
        ];
        (a, b)
    }

    /// The physical quantities of a state vector.
    pub fn outputs(&self, x: &[f64; 6]) -> BondGraphOutputs {
        BondGraphOutputs {
            spindle_current_a: x[0] / self.spindle_inductance_h,
            spindle_speed_rad_s: x[1] / self.spindle_inertia_kg_m2,
            feed_current_a: x[2] / self.feed_inductance_h,
            feed_motor_speed_rad_s: x[3] / self.feed_inertia_kg_m2,
            contact_force_n: self.stiffness_n_per_m * x[4],
            table_velocity_m_s: x[5] / self.mass_kg,
        }
    }

    /// The steady state for constant voltages and cut (`None` if eq 5 has no unique one, which
    /// neither Table 1's values nor the machining centre's cause).
    ///
    /// ```
    /// use cutlab::plant::bond_graph::{BondGraphParams, CutLoad};
    /// let p = BondGraphParams::default();
    /// let s = p.steady_state(380.0, 220.0, CutLoad::NONE).unwrap();
    /// assert!((s.spindle_current_a - 12.86).abs() < 0.01); // paper 002: "12 A"
    /// ```
    pub fn steady_state(
        &self,
        spindle_voltage_v: f64,
        feed_voltage_v: f64,
        cut: CutLoad,
    ) -> Option<BondGraphOutputs> {
        self.steady_state_vector(spindle_voltage_v, feed_voltage_v, cut)
            .map(|x| self.outputs(&x))
    }

    /// The state vector [p₃, p₆, p₁₁, p₁₄, q₁₇, p₂₀] of [`BondGraphParams::steady_state`]:
    /// x = −A⁻¹·B·[S_e1, S_e2].
    pub fn steady_state_vector(
        &self,
        spindle_voltage_v: f64,
        feed_voltage_v: f64,
        cut: CutLoad,
    ) -> Option<[f64; 6]> {
        let (a, b) = self.state_space(cut);
        let mut rhs = [0.0; 6];
        for (r, row) in rhs.iter_mut().zip(&b) {
            *r = -(row[0] * spindle_voltage_v + row[1] * feed_voltage_v);
        }
        linalg::solve(&a, &rhs)
    }

    /// The spindle's steady speed while it draws `current_a` from S_e1 (ṗ₃ = 0:
    /// S_e1 = R_s1·i + r_s·ω, whatever loads it).
    ///
    /// ```
    /// use cutlab::plant::bond_graph::BondGraphParams;
    /// let p = BondGraphParams::machining_centre();
    /// assert!((p.spindle_speed_at_rad_s(25.0) - (380.0 - 0.132 * 25.0) / 2.4).abs() < 1e-12);
    /// ```
    pub fn spindle_speed_at_rad_s(&self, current_a: f64) -> f64 {
        (self.spindle_voltage_v - self.spindle_resistance_ohm * current_a)
            / self.spindle_armature_coefficient
    }
}

/// What eq 5's state means.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct BondGraphOutputs {
    /// Spindle armature current p₃/L_q1.
    pub spindle_current_a: f64,
    /// Spindle motor speed p₆/J_m1.
    pub spindle_speed_rad_s: f64,
    /// x-axis armature current p₁₁/L_q2.
    pub feed_current_a: f64,
    /// x-axis motor speed p₁₄/J_m2.
    pub feed_motor_speed_rad_s: f64,
    /// The screw's force K_L·q₁₇.
    pub contact_force_n: f64,
    /// Table velocity p₂₀/M.
    pub table_velocity_m_s: f64,
}

/// Eq 5 stepped exactly with voltages held over each sample.
///
/// ```
/// use cutlab::plant::bond_graph::{BondGraphModel, BondGraphParams, CutLoad};
/// let mut m = BondGraphModel::new(BondGraphParams::default(), CutLoad::NONE, 1e-3).unwrap();
/// let mut out = m.step(380.0, 220.0);
/// for _ in 0..8000 { out = m.step(380.0, 220.0); }
/// assert!((out.spindle_current_a - 12.86).abs() < 0.1);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BondGraphModel {
    params: BondGraphParams,
    phi: Mat<6>,
    gamma: [[f64; 2]; 6],
    x: [f64; 6],
}

impl BondGraphModel {
    /// The model at rest under the cut's load `cut`, sampled every `dt_s`.
    pub fn new(params: BondGraphParams, cut: CutLoad, dt_s: f64) -> Result<Self, PlantError> {
        params.validate()?;
        non_negative("cut.feed_n_s_per_m", cut.feed_n_s_per_m)?;
        non_negative("cut.torque_n_m_s_per_m", cut.torque_n_m_s_per_m)?;
        positive("dt_s", dt_s)?;
        let (a, b) = params.state_space(cut);
        let (phi, gamma) = linalg::zoh::<6, 2, 8>(&a, &b, dt_s);
        Ok(Self {
            params,
            phi,
            gamma,
            x: [0.0; 6],
        })
    }

    /// Advances one sample with the voltages held.
    pub fn step(&mut self, spindle_voltage_v: f64, feed_voltage_v: f64) -> BondGraphOutputs {
        let mut x = linalg::mul_vec(&self.phi, &self.x);
        for (xi, g) in x.iter_mut().zip(&self.gamma) {
            *xi += g[0] * spindle_voltage_v + g[1] * feed_voltage_v;
        }
        self.x = x;
        self.params.outputs(&self.x)
    }

    /// The state vector [p₃, p₆, p₁₁, p₁₄, q₁₇, p₂₀].
    pub fn state(&self) -> [f64; 6] {
        self.x
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        self.x = [0.0; 6];
    }
}

/// The cut behind paper 002's load: a milling cutter in a material at a radial width, whose
/// depth the load schedule sets ([`DepthStep`]).
///
/// Its mean chip forces are Altintas' closed form ([`mean_forces`]) with the material's shearing
/// coefficients and no edge forces (which would add a force independent of the feed, and make
/// the bond graph affine rather than linear), evaluated at `spindle_rpm`: the spindle droops by
/// under 1 % between idle and the reference cut, and the feed per tooth with it.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BondGraphCut {
    /// The cutter.
    pub cutter: Cutter,
    /// Up, down or slot.
    pub mode: MillingMode,
    /// Radial width of cut a_e.
    pub width_mm: f64,
    /// Work material.
    pub material: Material,
    /// Spindle speed the chip's force is evaluated at.
    pub spindle_rpm: f64,
}

impl BondGraphCut {
    /// Paper 002 names no cut; cutlab's (chosen): a Ø50 mm face mill with 5 inserts climb
    /// milling SM45C steel 40 mm wide, at 1500 mm/min 0.2 mm per tooth, with the spindle at the
    /// speed `spindle_rpm` it turns at under the reference cut.
    pub fn paper_002(spindle_rpm: f64) -> Self {
        Self {
            cutter: Cutter {
                diameter_mm: 50.0,
                teeth: 5,
                helix_deg: 0.0,
                runout_mm: 0.0,
                runout_angle_deg: 0.0,
            },
            mode: MillingMode::Down,
            width_mm: 40.0,
            material: Material::Sm45c,
            spindle_rpm,
        }
    }

    /// The material's shearing coefficients without its edge coefficients.
    fn chip_coefficients(&self) -> CuttingCoefficients {
        CuttingCoefficients {
            kte_n_mm: 0.0,
            kre_n_mm: 0.0,
            kae_n_mm: 0.0,
            ..self.material.coefficients()
        }
    }

    /// Feed per tooth at table speed `feed_mm_min` and spindle speed `spindle_rpm`.
    ///
    /// ```
    /// use cutlab::plant::bond_graph::BondGraphCut;
    /// let cut = BondGraphCut::paper_002(1500.0);
    /// assert!((cut.feed_per_tooth_mm(1500.0, 1500.0) - 0.2).abs() < 1e-12);
    /// ```
    pub fn feed_per_tooth_mm(&self, feed_mm_min: f64, spindle_rpm: f64) -> f64 {
        feed_mm_min / (f64::from(self.cutter.teeth) * spindle_rpm)
    }

    /// The mean chip forces and torque at `depth_mm` and table speed `feed_mm_min`, at the
    /// cut's spindle speed.
    pub fn mean_forces(&self, depth_mm: f64, feed_mm_min: f64) -> ToolForces {
        mean_forces(
            &self.cutter,
            &self.chip_coefficients(),
            &Immersion::new(self.mode, self.width_mm, self.cutter.diameter_mm),
            depth_mm,
            self.feed_per_tooth_mm(feed_mm_min, self.spindle_rpm),
        )
    }

    /// The load per table speed at `depth_mm`: the mean forces at 1 m/s (they are proportional
    /// to the speed).
    pub fn load(&self, depth_mm: f64) -> CutLoad {
        let f = self.mean_forces(depth_mm, S_PER_MIN * 1e3);
        CutLoad {
            // On the tool F̄_x points against the feed: the table pushes against −F̄_x.
            feed_n_s_per_m: -f.fx_n,
            torque_n_m_s_per_m: f.torque_nm,
        }
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        self.cutter.validate().map_err(|e| e.within("cutter"))?;
        positive("width_mm", self.width_mm)?;
        if self.width_mm > self.cutter.diameter_mm {
            return Err(PlantError::new(
                "width_mm",
                format!(
                    "{} mm is wider than the Ø{} mm cutter",
                    self.width_mm, self.cutter.diameter_mm
                ),
            ));
        }
        positive("spindle_rpm", self.spindle_rpm)?;
        Ok(())
    }
}

/// A step of the cutting load: the depth of cut from a time on.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DepthStep {
    /// From this time on…
    pub time_s: f64,
    /// …the axial depth of cut is this.
    pub depth_mm: f64,
}

/// Paper 002's plant as a machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BondGraphRun {
    /// Eq 5's parameters.
    pub params: BondGraphParams,
    /// The cut behind the load.
    pub cut: BondGraphCut,
    /// Programmed feed. Paper 002: 1500 mm/min.
    pub programmed_feed_mm_min: f64,
    /// The load schedule, in time order; the first applies from t = 0 whatever its time.
    pub load_steps: Vec<DepthStep>,
    /// The control's exponential acceleration/deceleration of the cutting feed: the feed the
    /// x axis is driven at follows the commanded feed through a first-order lag of this time
    /// constant (0 follows it at once).
    pub feed_time_constant_s: f64,
    /// Length of the run.
    pub duration_s: f64,
    /// The feed waits this long after the start (the spindle is at speed from t = 0).
    pub spindle_start_dwell_s: f64,
    /// Sample rate.
    pub sample_rate_hz: f64,
    /// Seed of the sensor noise.
    pub seed: u64,
    /// The control.
    pub cnc: CncConfig,
    /// Spindle current channel.
    pub spindle_sensor: CurrentSensorConfig,
    /// x-axis current channel.
    pub feed_sensor: CurrentSensorConfig,
}

impl BondGraphRun {
    /// When the load steps in paper 002's run.
    pub const PAPER_002_LOAD_STEP_TIME_S: f64 = 15.0;

    /// The load step's size when none is chosen: +40 % of the depth (the lab's choice; paper 002
    /// does not give its step's size).
    pub const DEFAULT_LOAD_STEP_PCT: f64 = 40.0;

    /// Paper 002's Fig. 7 setting as cutlab reads it on the machining centre
    /// ([`BondGraphParams::machining_centre`]): 1500 mm/min; the depth at which the spindle draws
    /// the reference 25 A ([`BondGraphRun::depth_for_current`]), stepping by `load_step_pct`
    /// percent at 15 s; the feed smoothed with Table 1's x-axis time constant L_q2/R_s2; 40 s.
    ///
    /// ```
    /// use cutlab::plant::bond_graph::BondGraphRun;
    /// let run = BondGraphRun::paper_002(40.0);
    /// let depths: Vec<f64> = run.load_steps.iter().map(|s| s.depth_mm).collect();
    /// assert!((depths[0] - 3.945).abs() < 1e-3 && (depths[1] - 1.4 * depths[0]).abs() < 1e-12);
    /// assert!((run.feed_time_constant_s - 0.085 / 0.15).abs() < 1e-12);
    /// ```
    pub fn paper_002(load_step_pct: f64) -> Self {
        let params = BondGraphParams::machining_centre();
        let reference_rpm =
            rpm_from_rad_s(params.spindle_speed_at_rad_s(PAPER_002_REFERENCE_CURRENT_A));
        let cut = BondGraphCut::paper_002(reference_rpm);
        let depth_mm = Self::depth_for_current(
            &params,
            &cut,
            PAPER_002_REFERENCE_CURRENT_A,
            PAPER_002_FEED_MM_MIN,
        );
        let table_1 = BondGraphParams::default();
        // A spindle channel for a 30 A motor with room for twice its current: 100 A → 25 mA
        // into 250 Ω (6.25 V at 100 A, ±160 A before the ±10 V ADC saturates), 0.1 A noise.
        let spindle_hall = HallSensorConfig {
            rated_input_a: 100.0,
            rated_output_ma: 25.0,
            burden_ohm: 250.0,
            bandwidth_hz: 1000.0,
            gain_error: 0.0,
            offsets_a: [0.06, -0.04, 0.02],
            noise_a: 0.1,
        };
        Self {
            params,
            cut,
            programmed_feed_mm_min: PAPER_002_FEED_MM_MIN,
            load_steps: vec![
                DepthStep {
                    time_s: 0.0,
                    depth_mm,
                },
                DepthStep {
                    time_s: Self::PAPER_002_LOAD_STEP_TIME_S,
                    depth_mm: depth_mm * (1.0 + load_step_pct / 100.0),
                },
            ],
            feed_time_constant_s: table_1.feed_inductance_h / table_1.feed_resistance_ohm,
            duration_s: 40.0,
            spindle_start_dwell_s: 3.0,
            sample_rate_hz: 10_000.0,
            seed: 0,
            cnc: CncConfig::default(),
            spindle_sensor: CurrentSensorConfig {
                hall: spindle_hall,
                adc: AdcConfig::default(),
                wiring: PhaseWiring::TwoPhases,
            },
            // The x axis carries a few amperes: paper 000's feed-motor channel.
            feed_sensor: CurrentSensorConfig::feed(),
        }
    }

    /// The depth of cut at which the spindle draws `current_a` at `feed_mm_min` in steady state:
    /// r_s·i = b_s·ω + c_T·v with ω the speed at that current, and c_T proportional to the depth.
    ///
    /// ```
    /// use cutlab::plant::bond_graph::{BondGraphCut, BondGraphParams, BondGraphRun};
    /// let p = BondGraphParams::machining_centre();
    /// let cut = BondGraphCut::paper_002(1498.8);
    /// let depth = BondGraphRun::depth_for_current(&p, &cut, 25.0, 1500.0);
    /// assert!((depth - 3.945).abs() < 1e-3); // mm
    /// ```
    pub fn depth_for_current(
        params: &BondGraphParams,
        cut: &BondGraphCut,
        current_a: f64,
        feed_mm_min: f64,
    ) -> f64 {
        let drag_nm = params.spindle_drag_n_m_s_per_rad * params.spindle_speed_at_rad_s(current_a);
        let cutting_nm = params.spindle_armature_coefficient * current_a - drag_nm;
        let torque_per_mm = cut.mean_forces(1.0, feed_mm_min).torque_nm;
        (cutting_nm / torque_per_mm).max(0.0)
    }

    /// The run with the load step at `load_step_pct` percent of the depth.
    pub fn with_load_step_pct(mut self, load_step_pct: f64) -> Self {
        if let [first, rest @ ..] = self.load_steps.as_mut_slice() {
            for step in rest {
                step.depth_mm = first.depth_mm * (1.0 + load_step_pct / 100.0);
            }
        }
        self
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        self.params.validate().map_err(|e| e.within("params"))?;
        self.cut.validate().map_err(|e| e.within("cut"))?;
        positive("programmed_feed_mm_min", self.programmed_feed_mm_min)?;
        if self.load_steps.is_empty() {
            return Err(PlantError::new("load_steps", "needs at least one step"));
        }
        let mut last = f64::NEG_INFINITY;
        for (i, s) in self.load_steps.iter().enumerate() {
            super::finite(&format!("load_steps[{i}].time_s"), s.time_s)?;
            if s.time_s < last {
                return Err(PlantError::new(
                    format!("load_steps[{i}].time_s"),
                    "steps must be in time order",
                ));
            }
            last = s.time_s;
            non_negative(&format!("load_steps[{i}].depth_mm"), s.depth_mm)?;
            let load = self.cut.load(s.depth_mm);
            if load.feed_n_s_per_m < 0.0 {
                // Climb milling at a light radial width pulls the table into the cut.
                return Err(PlantError::new(
                    "cut",
                    "the cut's feed force pulls the table instead of resisting it",
                ));
            }
        }
        non_negative("feed_time_constant_s", self.feed_time_constant_s)?;
        positive("duration_s", self.duration_s)?;
        non_negative("spindle_start_dwell_s", self.spindle_start_dwell_s)?;
        positive("sample_rate_hz", self.sample_rate_hz)?;
        self.cnc.validate().map_err(|e| e.within("cnc"))?;
        self.spindle_sensor
            .validate()
            .map_err(|e| e.within("spindle_sensor"))?;
        self.feed_sensor
            .validate()
            .map_err(|e| e.within("feed_sensor"))?;
        Ok(())
    }
}

/// One load level, discretised: Φ, Γ and the steady-state gains from (S_e1, S_e2) to v.
#[derive(Debug, Clone, Copy, PartialEq)]
struct LoadLevel {
    start_s: f64,
    depth_mm: f64,
    load: CutLoad,
    /// Mean chip forces and torque per table speed (m/s), for the truth.
    forces_per_m_s: ToolForces,
    phi: Mat<6>,
    gamma: [[f64; 2]; 6],
    /// Steady table speed (m/s) per volt of S_e1 and of S_e2.
    speed_per_volt: [f64; 2],
}

impl LoadLevel {
    /// S_e2 that gives `feed_mm_min` in steady state with the spindle at `spindle_voltage_v`
    /// (exact: eq 5 is linear).
    fn feed_voltage_v(&self, spindle_voltage_v: f64, feed_mm_min: f64) -> f64 {
        let v_m_s = feed_mm_min / S_PER_MIN * 1e-3;
        (v_m_s - self.speed_per_volt[0] * spindle_voltage_v) / self.speed_per_volt[1]
    }
}

/// Paper 002's bond-graph plant as a machine: the CNC's feed, smoothed, sets S_e2, the spindle
/// runs at its S_e1, and the sensors read the spindle and x-axis currents.
///
/// ```
/// use cutlab::machine::{Machine, OverrideCommand};
/// use cutlab::plant::bond_graph::{BondGraphMachine, BondGraphRun};
/// let run = BondGraphRun { sample_rate_hz: 1000.0, ..BondGraphRun::paper_002(40.0) };
/// let mut m = BondGraphMachine::new(run).unwrap();
/// let mut s = m.step(OverrideCommand::default());
/// for _ in 0..14_000 { s = m.step(OverrideCommand::default()); }
/// let t = s.truth.unwrap();
/// assert!((t.spindle_current_rms_a - 25.0).abs() < 0.1);  // the reference current at 1500 mm/min
/// assert!((s.sensors.feed_mm_min - 1500.0).abs() < 1.0);
/// assert!(t.feed_current_rms_a < 2.0); // a servo's few amperes
/// ```
#[derive(Debug, Clone)]
pub struct BondGraphMachine {
    run: BondGraphRun,
    levels: Vec<LoadLevel>,
    level: usize,
    sampling: Sampling,
    control: Control,
    /// Per sample, the fraction of the way the smoothed feed moves to the commanded one.
    feed_smoothing: f64,
    smoothed_feed_mm_min: f64,
    x: [f64; 6],
    /// Where `x` starts and restarts: the spindle at speed, the table still.
    initial_state: [f64; 6],
    feed_voltage_v: f64,
    initial_feed_voltage_v: f64,
    position_mm: f64,
    spindle_angle_rad: f64,
    feed_angle_rad: f64,
    waveform: ThreePhaseWaveform,
    spindle_sensor: CurrentSensor,
    feed_sensor: CurrentSensor,
}

/// Pole pairs used to turn the bond graph's motor speeds into phase-current frequencies (the
/// paper's motors are DC-like gyrators; chosen: 2 for the spindle, 50 Hz at 1500 rpm, and 4 for
/// the x axis).
const SPINDLE_POLE_PAIRS: f64 = 2.0;
const FEED_POLE_PAIRS: f64 = 4.0;

impl BondGraphMachine {
    /// A machine with its spindle running at S_e1 and the table still: eq 5's steady state for
    /// S_e1 and the S_e2 of zero feed at the first load level.
    ///
    /// Starting from rest instead would switch both voltages on at once: a spindle run-up the
    /// paper's experiment does not show.
    pub fn new(run: BondGraphRun) -> Result<Self, PlantError> {
        run.validate()?;
        let sampling = Sampling::new(run.sample_rate_hz);
        let dt_s = sampling.dt_s();
        let mut levels = Vec::with_capacity(run.load_steps.len());
        for (i, step) in run.load_steps.iter().enumerate() {
            let load = run.cut.load(step.depth_mm);
            let (a, b) = run.params.state_space(load);
            let (phi, gamma) = linalg::zoh::<6, 2, 8>(&a, &b, dt_s);
            let speed = |se1: f64, se2: f64| {
                run.params
                    .steady_state(se1, se2, load)
                    .map(|o| o.table_velocity_m_s)
            };
            let (Some(v1), Some(v2)) = (speed(1.0, 0.0), speed(0.0, 1.0)) else {
                return Err(PlantError::new(
                    format!("load_steps[{i}]"),
                    "eq 5 has no steady state with this load",
                ));
            };
            if v2.abs() < 1e-15 {
                return Err(PlantError::new(
                    format!("load_steps[{i}]"),
                    "the x-axis voltage does not move the table",
                ));
            }
            levels.push(LoadLevel {
                start_s: step.time_s,
                depth_mm: step.depth_mm,
                load,
                forces_per_m_s: run.cut.mean_forces(step.depth_mm, S_PER_MIN * 1e3),
                phi,
                gamma,
                speed_per_volt: [v1, v2],
            });
        }
        let spindle_voltage_v = run.params.spindle_voltage_v;
        let (initial_feed_voltage_v, initial_state) = match levels.first() {
            Some(first) => {
                let se2 = first.feed_voltage_v(spindle_voltage_v, 0.0);
                let x = run
                    .params
                    .steady_state_vector(spindle_voltage_v, se2, first.load);
                (se2, x)
            }
            None => (0.0, None),
        };
        let initial_state = initial_state.ok_or_else(|| {
            PlantError::new("load_steps[0]", "eq 5 has no steady state with this load")
        })?;
        let length_mm = run.programmed_feed_mm_min * 2.56 * run.duration_s / S_PER_MIN + 1.0;
        let block = PlanBlock::straight(length_mm, run.programmed_feed_mm_min);
        let feed_smoothing = if run.feed_time_constant_s > 0.0 {
            -(-dt_s / run.feed_time_constant_s).exp_m1()
        } else {
            1.0
        };
        Ok(Self {
            levels,
            level: 0,
            sampling,
            control: Control::new(&run.cnc, vec![block], dt_s).map_err(|e| e.within("cnc"))?,
            feed_smoothing,
            smoothed_feed_mm_min: 0.0,
            x: initial_state,
            initial_state,
            feed_voltage_v: initial_feed_voltage_v,
            initial_feed_voltage_v,
            position_mm: 0.0,
            spindle_angle_rad: 0.0,
            feed_angle_rad: 0.0,
            waveform: ThreePhaseWaveform::new(0.0, 0.0),
            spindle_sensor: CurrentSensor::new(run.spindle_sensor, dt_s, run.seed, 3)
                .map_err(|e| e.within("spindle_sensor"))?,
            feed_sensor: CurrentSensor::new(run.feed_sensor, dt_s, run.seed, 0)
                .map_err(|e| e.within("feed_sensor"))?,
            run,
        })
    }

    /// The run's settings.
    pub fn run(&self) -> &BondGraphRun {
        &self.run
    }

    /// The eq-5 state vector.
    pub fn state(&self) -> [f64; 6] {
        self.x
    }
}

impl PlantModel for BondGraphMachine {
    fn sampling(&self) -> &Sampling {
        &self.sampling
    }

    fn sampling_mut(&mut self) -> &mut Sampling {
        &mut self.sampling
    }

    fn advance(&mut self, tick: Tick, command: OverrideCommand) -> PlantSample {
        let (time_s, dt_s) = (tick.time_s, tick.dt_s);
        while self.level + 1 < self.levels.len() && time_s >= self.levels[self.level + 1].start_s {
            self.level += 1;
        }
        let ready = time_s >= self.run.spindle_start_dwell_s;
        let control = self.control.step(command, ready);
        let applied = control.applied;
        self.smoothed_feed_mm_min +=
            self.feed_smoothing * (control.cnc.commanded_feed_mm_min - self.smoothed_feed_mm_min);
        let level = self.levels[self.level];
        let se1 = self.run.params.spindle_voltage_v;
        self.feed_voltage_v = level.feed_voltage_v(se1, self.smoothed_feed_mm_min);
        let mut x = linalg::mul_vec(&level.phi, &self.x);
        for (xi, g) in x.iter_mut().zip(&level.gamma) {
            *xi += g[0] * se1 + g[1] * self.feed_voltage_v;
        }
        self.x = x;
        let params = &self.run.params;
        let out = params.outputs(&self.x);
        let v_m_s = out.table_velocity_m_s;
        let feed_mm_min = v_m_s * 1e3 * S_PER_MIN;
        self.position_mm += feed_mm_min / S_PER_MIN * dt_s;
        self.spindle_angle_rad = (self.spindle_angle_rad
            + SPINDLE_POLE_PAIRS * out.spindle_speed_rad_s * dt_s)
            .rem_euclid(TAU);
        self.feed_angle_rad = (self.feed_angle_rad
            + FEED_POLE_PAIRS * out.feed_motor_speed_rad_s * dt_s)
            .rem_euclid(TAU);
        // The gyrator currents are taken as RMS values of balanced three-phase sets.
        let spindle_currents = self
            .waveform
            .currents(out.spindle_current_a * SQRT_2, self.spindle_angle_rad);
        let feed_currents = self
            .waveform
            .currents(out.feed_current_a * SQRT_2, self.feed_angle_rad);
        let spindle_read = self.spindle_sensor.read(spindle_currents);
        let feed_read = self.feed_sensor.read(feed_currents);
        let spindle_rpm = rpm_from_rad_s(out.spindle_speed_rad_s);
        let spindle_command_rpm = rpm_from_rad_s(se1 / params.spindle_armature_coefficient);
        // The cut's mean forces at this table speed (proportional to it, see `CutLoad`).
        let f = level.forces_per_m_s;
        let (fx_n, fy_n, torque_nm) = (f.fx_n * v_m_s, f.fy_n * v_m_s, f.torque_nm * v_m_s);
        let cut = &self.run.cut;
        let cutting = level.depth_mm > 0.0;
        let fv = SpindleDriveConfig::default().fv_volts_per_krpm * spindle_rpm.abs() * 1e-3;
        let sensors = SensorSample {
            time_s,
            feed_phase_currents_a: feed_read,
            spindle_phase_currents_a: spindle_read,
            spindle_fv_voltage_v: fv,
            spindle_speed_rpm: spindle_rpm,
            spindle_command_rpm,
            programmed_feed_mm_min: self.run.programmed_feed_mm_min,
            feed_mm_min,
            applied_override_pct: applied.pct,
            spindle_running: true,
            time_since_spindle_start_s: time_s,
        };
        let truth = PlantTruth {
            force_x_n: fx_n,
            force_y_n: fy_n,
            force_resultant_n: fx_n.hypot(fy_n),
            feed_force_n: -fx_n,
            spindle_torque_nm: torque_nm,
            cutting_power_w: torque_nm * out.spindle_speed_rad_s,
            depth_mm: level.depth_mm,
            width_mm: if cutting { cut.width_mm } else { 0.0 },
            feed_per_tooth_mm: cut.feed_per_tooth_mm(feed_mm_min, spindle_rpm),
            path_position_mm: self.position_mm,
            material_removal_mm3_s: level.depth_mm * cut.width_mm * feed_mm_min.max(0.0)
                / S_PER_MIN,
            tool_x_mm: self.position_mm,
            // Eq 7 over the three phases, as the field promises and the other plants do.
            feed_current_rms_a: three_phase_rms_a(feed_currents),
            spindle_current_rms_a: out.spindle_current_a.abs(),
            ..PlantTruth::default()
        };
        let immersion = Immersion::new(cut.mode, cut.width_mm, cut.cutter.diameter_mm);
        let mut signals = PlantSignals {
            feed_mm_min,
            spindle_command_rpm,
            spindle_speed_rpm: spindle_rpm,
            material: cutting.then_some(cut.material),
            entry_deg: immersion.entry_rad.to_degrees(),
            exit_deg: immersion.exit_rad.to_degrees(),
            power_law_force_n: f64::NAN,
            axis_x: AxisSignals {
                velocity_mm_min: feed_mm_min,
                load_force_n: out.contact_force_n,
                torque_nm: params.feed_armature_coefficient * out.feed_current_a,
                iq_a: out.feed_current_a,
                phase_currents_a: feed_currents,
            },
            spindle_motor_torque_nm: params.spindle_armature_coefficient * out.spindle_current_a,
            spindle_phase_currents_a: spindle_currents,
            fv_voltage_v: fv,
            feed_currents_read_a: feed_read,
            spindle_currents_read_a: spindle_read,
            brake_excitation_a: f64::NAN,
            brake_torque_nm: f64::NAN,
            ..PlantSignals::from_control(time_s, truth, &control)
        };
        // The feed the axis is driven at is the control's, after its smoothing.
        signals.commanded_feed_mm_min = self.smoothed_feed_mm_min;
        PlantSample {
            sensors,
            signals,
            finished: time_s >= self.run.duration_s - 0.5 * dt_s,
        }
    }

    fn restart(&mut self) -> PlantSignals {
        self.level = 0;
        self.control.reset();
        self.smoothed_feed_mm_min = 0.0;
        self.x = self.initial_state;
        self.feed_voltage_v = self.initial_feed_voltage_v;
        self.position_mm = 0.0;
        self.spindle_angle_rad = 0.0;
        self.feed_angle_rad = 0.0;
        self.spindle_sensor.reset(self.run.seed, 3);
        self.feed_sensor.reset(self.run.seed, 0);
        PlantSignals::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bond_graph_steady_state_balances_eq_5() {
        let p = BondGraphParams::default();
        let s = p.steady_state(380.0, 220.0, CutLoad::NONE).unwrap();
        // ṗ₆ = 0: r_s·i_s = m_s·F;  ṗ₂₀ = 0: F = C_z·v.
        assert!(
            (p.spindle_armature_coefficient * s.spindle_current_a
                - p.spindle_conversion_m * s.contact_force_n)
                .abs()
                < 1e-6
        );
        assert!((s.contact_force_n - p.damping_n_s_per_m * s.table_velocity_m_s).abs() < 1e-6);
    }

    #[test]
    fn the_machining_centres_steady_state_balances_the_cut() {
        let p = BondGraphParams::machining_centre();
        let cut = BondGraphCut::paper_002(1500.0);
        let load = cut.load(4.0);
        let s = p.steady_state(380.0, 19.0, load).unwrap();
        let v = s.table_velocity_m_s;
        // ṗ₆ = 0: r_s·i_s = b_s·ω + c_T·v (m_s = 0);  ṗ₂₀ = 0: F = (C_z + c_f)·v;
        // ṗ₁₄ = 0: r_x·i_x = m_x·F.
        let spindle =
            p.spindle_drag_n_m_s_per_rad * s.spindle_speed_rad_s + load.torque_n_m_s_per_m * v;
        assert!((p.spindle_armature_coefficient * s.spindle_current_a - spindle).abs() < 1e-9);
        let screw = (p.damping_n_s_per_m + load.feed_n_s_per_m) * v;
        assert!((s.contact_force_n - screw).abs() < 1e-6);
        assert!(
            (p.feed_armature_coefficient * s.feed_current_a - p.feed_conversion_m * screw).abs()
                < 1e-9
        );
    }

    #[test]
    fn the_depth_for_a_current_gives_that_current() {
        let p = BondGraphParams::machining_centre();
        let cut = BondGraphCut::paper_002(rpm_from_rad_s(p.spindle_speed_at_rad_s(25.0)));
        let depth = BondGraphRun::depth_for_current(&p, &cut, 25.0, 1500.0);
        let load = cut.load(depth);
        let v = 1500.0 / S_PER_MIN * 1e-3;
        let omega = p.spindle_speed_at_rad_s(25.0);
        let torque = p.spindle_drag_n_m_s_per_rad * omega + load.torque_n_m_s_per_m * v;
        assert!((torque / p.spindle_armature_coefficient - 25.0).abs() < 1e-9);
    }

    #[test]
    fn load_steps_out_of_order_are_refused() {
        let mut run = BondGraphRun::paper_002(40.0);
        run.load_steps.reverse();
        assert_eq!(
            BondGraphMachine::new(run).unwrap_err().field,
            "load_steps[1].time_s"
        );
    }

    #[test]
    fn a_cut_that_pulls_the_table_is_refused() {
        // Climb milling a tenth of the diameter: F̄_x on the tool points along the feed.
        let mut run = BondGraphRun::paper_002(40.0);
        run.cut.width_mm = 5.0;
        assert_eq!(BondGraphMachine::new(run).unwrap_err().field, "cut");
    }
}
