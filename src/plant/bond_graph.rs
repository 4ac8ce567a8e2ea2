//! Paper 002's plant: Liu et al.'s bond-graph spindle + x-axis model, usable as the whole machine.
//!
//! Liu et al.'s eq 5 with the evident typesetting errors repaired (ṗ₇ is ṗ₆; the first line's
//! r_s/J_m1 multiplies p₆; q₉ and p₁₇ are q₁₇):
//!
//! ```text
//! ṗ₃  = S_e1 − (R_s1/L_q1)·p₃ − (r_s/J_m1)·p₆                  spindle armature
//! ṗ₆  = (r_s/L_q1)·p₃ − m_s·K_L·q₁₇                             spindle rotor
//! ṗ₁₁ = S_e2 − (R_s2/L_q2)·p₁₁ − (r_x/J_m2)·p₁₄                 x-axis armature
//! ṗ₁₄ = (r_x/L_q2)·p₁₁ − m_x·K_L·q₁₇                             x-axis rotor
//! q̇₁₇ = (m_s/J_m1)·p₆ + (m_x/J_m2)·p₁₄ − p₂₀/M                   compliance
//! ṗ₂₀ = K_L·q₁₇ − ((C_z + C_cut)/M)·p₂₀                          translating mass
//! ```
//!
//! with Table 1's parameters ([`BondGraphParams::default`]). The currents are i = p₃/L_q1 and
//! p₁₁/L_q2, the speeds p₆/J_m1, p₁₄/J_m2, p₂₀/M, the contact force K_L·q₁₇. cutlab adds one
//! term: the cutting resistance C_cut·v (a cutting force proportional to feed speed at constant
//! spindle speed, the mechanistic model without edge forces), whose steps are the "step in load"
//! of paper 002's Fig. 7. The model is linear, so it is discretised exactly (matrix exponential,
//! zero-order hold) for each load level at construction.
//!
//! At rated voltages (380/220 V) and no cutting load it settles in about 3 s to a spindle current
//! of 12.9 A; paper 002 reports "about 3 s" and 12 A. It also settles at a table speed of
//! 19 800 mm/min, where the paper prints 1440 mm/min: that number cannot come from eq 5 with
//! Table 1 (see docs/plant.md). As a [`crate::machine::Machine`] the x-axis voltage S_e2 is
//! set, each interpolation period, to the value that gives the commanded feed in steady state
//! (exact, the model being linear); the transient is the bond graph's own.
//!
//! NaN voltages propagate into the state and stay there.

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

use super::cnc::{CncConfig, Control, PlanBlock};
use super::feed_drive::{three_phase_rms_a, ThreePhaseWaveform};
use super::linalg::{self, Mat};
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

/// Paper 002's Table 1.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BondGraphParams {
    /// Spindle motor rated voltage S_e1: 380 V.
    pub spindle_voltage_v: f64,
    /// x-axis motor rated voltage S_e2: 220 V.
    pub feed_voltage_v: f64,
    /// Spindle motor resistance R_s1: 0.132 Ω.
    pub spindle_resistance_ohm: f64,
    /// x-axis motor resistance R_s2: 0.15 Ω.
    pub feed_resistance_ohm: f64,
    /// Spindle motor inductance L_q1: 88 mH.
    pub spindle_inductance_h: f64,
    /// x-axis motor inductance L_q2: 85 mH.
    pub feed_inductance_h: f64,
    /// Spindle armature (gyrator) coefficient r_s: 9.68 (V·s/rad = N·m/A).
    pub spindle_armature_coefficient: f64,
    /// x-axis armature coefficient r_x: 0.0561.
    pub feed_armature_coefficient: f64,
    /// Spindle drive moment of inertia J_m1: 0.0048 kg·m².
    pub spindle_inertia_kg_m2: f64,
    /// x-axis drive moment of inertia J_m2: 0.0063 kg·m².
    pub feed_inertia_kg_m2: f64,
    /// Spindle conversion coefficient m_s: 0.021 m.
    pub spindle_conversion_m: f64,
    /// x-axis conversion coefficient m_x: 0.014 m.
    pub feed_conversion_m: f64,
    /// Equivalent compressive stiffness K_L: 37 MN/m.
    pub stiffness_n_per_m: f64,
    /// Translational mass M: 1100 kg.
    pub mass_kg: f64,
    /// Viscous damping C_z: 18 kN·s/m.
    pub damping_n_s_per_m: f64,
}

impl Default for BondGraphParams {
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
        }
    }
}

impl BondGraphParams {
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
        positive("spindle_conversion_m", self.spindle_conversion_m)?;
        positive("feed_conversion_m", self.feed_conversion_m)?;
        positive("stiffness_n_per_m", self.stiffness_n_per_m)?;
        positive("mass_kg", self.mass_kg)?;
        non_negative("damping_n_s_per_m", self.damping_n_s_per_m)?;
        Ok(())
    }

    /// Eq 5 as ẋ = A·x + B·[S_e1, S_e2] for state [p₃, p₆, p₁₁, p₁₄, q₁₇, p₂₀], with the cutting
    /// resistance `cutting_damping_n_s_per_m` added to C_z.
    pub fn state_space(&self, cutting_damping_n_s_per_m: f64) -> (Mat<6>, [[f64; 2]; 6]) {
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
                0.0,
                0.0,
                0.0,
                -p.spindle_conversion_m * kl,
                0.0,
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
                -(p.damping_n_s_per_m + cutting_damping_n_s_per_m) / p.mass_kg,
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

    /// The steady state for constant voltages and cutting resistance (`None` if eq 5 has no
    /// unique one, which Table 1's values never cause).
    ///
    /// ```
    /// use cutlab::plant::bond_graph::BondGraphParams;
    /// let p = BondGraphParams::default();
    /// let s = p.steady_state(380.0, 220.0, 0.0).unwrap();
    /// assert!((s.spindle_current_a - 12.86).abs() < 0.01); // paper 002: "12 A"
    /// ```
    pub fn steady_state(
        &self,
        spindle_voltage_v: f64,
        feed_voltage_v: f64,
        cutting_damping_n_s_per_m: f64,
    ) -> Option<BondGraphOutputs> {
        self.steady_state_vector(spindle_voltage_v, feed_voltage_v, cutting_damping_n_s_per_m)
            .map(|x| self.outputs(&x))
    }

    /// The state vector [p₃, p₆, p₁₁, p₁₄, q₁₇, p₂₀] of [`BondGraphParams::steady_state`]:
    /// x = −A⁻¹·B·[S_e1, S_e2].
    pub fn steady_state_vector(
        &self,
        spindle_voltage_v: f64,
        feed_voltage_v: f64,
        cutting_damping_n_s_per_m: f64,
    ) -> Option<[f64; 6]> {
        let (a, b) = self.state_space(cutting_damping_n_s_per_m);
        let mut rhs = [0.0; 6];
        for (r, row) in rhs.iter_mut().zip(&b) {
            *r = -(row[0] * spindle_voltage_v + row[1] * feed_voltage_v);
        }
        linalg::solve(&a, &rhs)
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
    /// Contact force K_L·q₁₇.
    pub contact_force_n: f64,
    /// Table velocity p₂₀/M.
    pub table_velocity_m_s: f64,
}

/// Eq 5 stepped exactly with voltages held over each sample.
///
/// ```
/// use cutlab::plant::bond_graph::{BondGraphModel, BondGraphParams};
/// let mut m = BondGraphModel::new(BondGraphParams::default(), 0.0, 1e-3).unwrap();
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
    /// The model at rest with a cutting resistance, sampled every `dt_s`.
    pub fn new(
        params: BondGraphParams,
        cutting_damping_n_s_per_m: f64,
        dt_s: f64,
    ) -> Result<Self, PlantError> {
        params.validate()?;
        non_negative("cutting_damping_n_s_per_m", cutting_damping_n_s_per_m)?;
        positive("dt_s", dt_s)?;
        let (a, b) = params.state_space(cutting_damping_n_s_per_m);
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

/// A step of the cutting load.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct LoadStep {
    /// From this time on…
    pub time_s: f64,
    /// …the cutting resistance is this (force per table speed).
    pub cutting_damping_n_s_per_m: f64,
}

/// Paper 002's plant as a machine.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BondGraphRun {
    /// Table 1.
    pub params: BondGraphParams,
    /// Programmed feed. Paper 002: 1500 mm/min.
    pub programmed_feed_mm_min: f64,
    /// The load schedule, in time order; the first applies from t = 0 whatever its time.
    pub load_steps: Vec<LoadStep>,
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
    /// Paper 002's Fig. 7 setting as cutlab reads it: 1500 mm/min; a cutting resistance that
    /// draws the reference 25 A at 1500 mm/min, stepping up by 40 % at 15 s (chosen); 40 s.
    pub fn paper_002() -> Self {
        let params = BondGraphParams::default();
        let base = Self::cutting_damping_for(&params, 25.0, 1500.0);
        Self {
            params,
            programmed_feed_mm_min: 1500.0,
            load_steps: vec![
                LoadStep {
                    time_s: 0.0,
                    cutting_damping_n_s_per_m: base,
                },
                LoadStep {
                    time_s: 15.0,
                    cutting_damping_n_s_per_m: 1.4 * (base + params.damping_n_s_per_m)
                        - params.damping_n_s_per_m,
                },
            ],
            duration_s: 40.0,
            spindle_start_dwell_s: 3.0,
            sample_rate_hz: 10_000.0,
            seed: 0,
            cnc: CncConfig::default(),
            spindle_sensor: CurrentSensorConfig::spindle(),
            feed_sensor: CurrentSensorConfig {
                // Table 1's x axis carries thousands of amperes (see the module docs): a
                // 5000 A → 25 mA transducer into 300 Ω reads ±6.7 kA.
                hall: HallSensorConfig {
                    rated_input_a: 5000.0,
                    rated_output_ma: 25.0,
                    burden_ohm: 300.0,
                    bandwidth_hz: 1000.0,
                    gain_error: 0.0,
                    offsets_a: [2.0, -1.5, 1.0],
                    noise_a: 3.0,
                },
                adc: AdcConfig::default(),
                wiring: PhaseWiring::TwoPhases,
            },
        }
    }

    /// The cutting resistance at which the steady spindle current is `current_a` at `feed_mm_min`:
    /// in steady state r_s·i_s = m_s·K_L·q₁₇ and K_L·q₁₇ = (C_z + C_cut)·v.
    ///
    /// ```
    /// use cutlab::plant::bond_graph::{BondGraphParams, BondGraphRun};
    /// let c = BondGraphRun::cutting_damping_for(&BondGraphParams::default(), 25.0, 1500.0);
    /// assert!((c - 442_952.38).abs() < 0.01); // N·s/m
    /// ```
    pub fn cutting_damping_for(params: &BondGraphParams, current_a: f64, feed_mm_min: f64) -> f64 {
        let force_n = current_a * params.spindle_armature_coefficient / params.spindle_conversion_m;
        (force_n / (feed_mm_min / S_PER_MIN * 1e-3) - params.damping_n_s_per_m).max(0.0)
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        self.params.validate().map_err(|e| e.within("params"))?;
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
            non_negative(
                &format!("load_steps[{i}].cutting_damping_n_s_per_m"),
                s.cutting_damping_n_s_per_m,
            )?;
        }
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
    cutting_damping_n_s_per_m: f64,
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

/// Paper 002's bond-graph plant as a machine: the CNC's feed sets S_e2, the spindle runs at its
/// rated S_e1, and the sensors read the spindle and x-axis currents.
///
/// ```
/// use cutlab::machine::{Machine, OverrideCommand};
/// use cutlab::plant::bond_graph::{BondGraphMachine, BondGraphRun};
/// let run = BondGraphRun { sample_rate_hz: 1000.0, ..BondGraphRun::paper_002() };
/// let mut m = BondGraphMachine::new(run).unwrap();
/// let mut s = m.step(OverrideCommand::default());
/// for _ in 0..14_000 { s = m.step(OverrideCommand::default()); }
/// let t = s.truth.unwrap();
/// assert!((t.spindle_current_rms_a - 25.0).abs() < 0.5);  // the reference current at 1500 mm/min
/// assert!((s.sensors.feed_mm_min - 1500.0).abs() < 20.0);
/// ```
#[derive(Debug, Clone)]
pub struct BondGraphMachine {
    run: BondGraphRun,
    levels: Vec<LoadLevel>,
    level: usize,
    sampling: Sampling,
    control: Control,
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
/// paper's motors are DC-like gyrators; chosen: 2 for the spindle, 4 for the x axis).
const SPINDLE_POLE_PAIRS: f64 = 2.0;
const FEED_POLE_PAIRS: f64 = 4.0;

impl BondGraphMachine {
    /// A machine with its spindle running at the rated voltage and the table still: eq 5's
    /// steady state for S_e1 and the S_e2 of zero feed at the first load level.
    ///
    /// Starting from rest instead would switch both voltages on at once, and the spindle's
    /// run-up, which eq 5 couples into the table through m_s·K_L, would shake the table at
    /// ±650 mm/min for the first 0.1 s (and ±3 mm/min after 3 s) with no feed commanded.
    pub fn new(run: BondGraphRun) -> Result<Self, PlantError> {
        run.validate()?;
        let sampling = Sampling::new(run.sample_rate_hz);
        let dt_s = sampling.dt_s();
        let mut levels = Vec::with_capacity(run.load_steps.len());
        for (i, step) in run.load_steps.iter().enumerate() {
            let (a, b) = run.params.state_space(step.cutting_damping_n_s_per_m);
            let (phi, gamma) = linalg::zoh::<6, 2, 8>(&a, &b, dt_s);
            let speed = |se1: f64, se2: f64| {
                run.params
                    .steady_state(se1, se2, step.cutting_damping_n_s_per_m)
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
                cutting_damping_n_s_per_m: step.cutting_damping_n_s_per_m,
                phi,
                gamma,
                speed_per_volt: [v1, v2],
            });
        }
        let spindle_voltage_v = run.params.spindle_voltage_v;
        let (initial_feed_voltage_v, initial_state) = match levels.first() {
            Some(first) => {
                let se2 = first.feed_voltage_v(spindle_voltage_v, 0.0);
                let x = run.params.steady_state_vector(
                    spindle_voltage_v,
                    se2,
                    first.cutting_damping_n_s_per_m,
                );
                (se2, x)
            }
            None => (0.0, None),
        };
        let initial_state = initial_state.ok_or_else(|| {
            PlantError::new("load_steps[0]", "eq 5 has no steady state with this load")
        })?;
        let length_mm = run.programmed_feed_mm_min * 2.56 * run.duration_s / S_PER_MIN + 1.0;
        let block = PlanBlock::straight(length_mm, run.programmed_feed_mm_min);
        Ok(Self {
            levels,
            level: 0,
            sampling,
            control: Control::new(&run.cnc, vec![block], dt_s).map_err(|e| e.within("cnc"))?,
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
        let (applied, cnc) = (control.applied, control.cnc);
        let level = self.levels[self.level];
        let se1 = self.run.params.spindle_voltage_v;
        self.feed_voltage_v = level.feed_voltage_v(se1, cnc.commanded_feed_mm_min);
        let mut x = linalg::mul_vec(&level.phi, &self.x);
        for (xi, g) in x.iter_mut().zip(&level.gamma) {
            *xi += g[0] * se1 + g[1] * self.feed_voltage_v;
        }
        self.x = x;
        let out = self.run.params.outputs(&self.x);
        let feed_mm_min = out.table_velocity_m_s * 1e3 * S_PER_MIN;
        self.position_mm += feed_mm_min / S_PER_MIN * dt_s;
        self.spindle_angle_rad = (self.spindle_angle_rad
            + SPINDLE_POLE_PAIRS * out.spindle_speed_rad_s * dt_s)
            .rem_euclid(TAU);
        self.feed_angle_rad = (self.feed_angle_rad
            + FEED_POLE_PAIRS * out.feed_motor_speed_rad_s * dt_s)
            .rem_euclid(TAU);
        // The gyrator currents are taken as RMS values of balanced three-phase sets.
        let spindle_currents = self.waveform.currents(
            out.spindle_current_a * std::f64::consts::SQRT_2,
            self.spindle_angle_rad,
        );
        let feed_currents = self.waveform.currents(
            out.feed_current_a * std::f64::consts::SQRT_2,
            self.feed_angle_rad,
        );
        let spindle_read = self.spindle_sensor.read(spindle_currents);
        let feed_read = self.feed_sensor.read(feed_currents);
        let spindle_rpm = rpm_from_rad_s(out.spindle_speed_rad_s);
        let torque_nm = self.run.params.spindle_conversion_m * out.contact_force_n;
        let power_w = torque_nm * out.spindle_speed_rad_s;
        let fv = SpindleDriveConfig::default().fv_volts_per_krpm * spindle_rpm.abs() * 1e-3;
        let sensors = SensorSample {
            time_s,
            feed_phase_currents_a: feed_read,
            spindle_phase_currents_a: spindle_read,
            spindle_fv_voltage_v: fv,
            spindle_speed_rpm: spindle_rpm,
            spindle_command_rpm: rpm_from_rad_s(se1 / self.run.params.spindle_armature_coefficient),
            programmed_feed_mm_min: self.run.programmed_feed_mm_min,
            feed_mm_min,
            applied_override_pct: applied.pct,
            spindle_running: true,
            time_since_spindle_start_s: time_s,
        };
        let cutting_force_n = level.cutting_damping_n_s_per_m * out.table_velocity_m_s;
        let truth = PlantTruth {
            force_x_n: -out.contact_force_n,
            force_resultant_n: out.contact_force_n.abs(),
            feed_force_n: cutting_force_n,
            spindle_torque_nm: torque_nm,
            cutting_power_w: power_w,
            depth_mm: f64::NAN,
            width_mm: f64::NAN,
            feed_per_tooth_mm: f64::NAN,
            path_position_mm: self.position_mm,
            tool_x_mm: self.position_mm,
            // Eq 7 over the three phases, as the field promises and the other plants do.
            feed_current_rms_a: three_phase_rms_a(feed_currents),
            spindle_current_rms_a: out.spindle_current_a.abs(),
            ..PlantTruth::default()
        };
        let signals = PlantSignals {
            feed_mm_min,
            spindle_command_rpm: rpm_from_rad_s(se1 / self.run.params.spindle_armature_coefficient),
            spindle_speed_rpm: spindle_rpm,
            entry_deg: f64::NAN,
            exit_deg: f64::NAN,
            power_law_force_n: f64::NAN,
            axis_x: AxisSignals {
                velocity_mm_min: feed_mm_min,
                load_force_n: out.contact_force_n,
                torque_nm: self.run.params.feed_armature_coefficient * out.feed_current_a,
                iq_a: out.feed_current_a,
                phase_currents_a: feed_currents,
            },
            spindle_motor_torque_nm: self.run.params.spindle_armature_coefficient
                * out.spindle_current_a,
            spindle_phase_currents_a: spindle_currents,
            fv_voltage_v: fv,
            feed_currents_read_a: feed_read,
            spindle_currents_read_a: spindle_read,
            brake_excitation_a: f64::NAN,
            brake_torque_nm: f64::NAN,
            ..PlantSignals::from_control(time_s, truth, &control)
        };
        PlantSample {
            sensors,
            signals,
            finished: time_s >= self.run.duration_s - 0.5 * dt_s,
        }
    }

    fn restart(&mut self) -> PlantSignals {
        self.level = 0;
        self.control.reset();
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
        let s = p.steady_state(380.0, 220.0, 0.0).unwrap();
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
    fn cutting_damping_gives_the_asked_current() {
        let p = BondGraphParams::default();
        let c = BondGraphRun::cutting_damping_for(&p, 25.0, 1500.0);
        let v = 1500.0 / 60.0 * 1e-3;
        let force = (p.damping_n_s_per_m + c) * v;
        assert!(
            (force * p.spindle_conversion_m / p.spindle_armature_coefficient - 25.0).abs() < 1e-9
        );
    }

    #[test]
    fn load_steps_out_of_order_are_refused() {
        let mut run = BondGraphRun::paper_002();
        run.load_steps.reverse();
        assert_eq!(
            BondGraphMachine::new(run).unwrap_err().field,
            "load_steps[1].time_s"
        );
    }
}
