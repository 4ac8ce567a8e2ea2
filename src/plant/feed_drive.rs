//! One feed axis: ball screw, guides, table and permanent-magnet synchronous motor (paper 000).
//!
//! ## Torque balance (paper 000 eq 1–3, with the table's dynamics of paper 001 eq 2.1)
//!
//! ```text
//! T_m = T_f + T_0 + T_c                                                        (eq 1)
//! T_f = F_0·L_0/(2πη),  T_0 = F_p0·L_0·(1 − η_0²)/(2πη),  T_c = F_c·L_0/(2πη)   (eq 2)
//! T_m = L_0/(2πη)·[ (F_0 + F_p0·(1 − η_0²))·σ(v) + F_c + m·a + c·v ] + J_m·α    (eq 3 + inertia, damping)
//! ```
//!
//! with L_0 the screw pitch (paper 000 prints L_v in eq 3; eq 2 makes it L_0), η the efficiency of
//! the whole chain, η_0 that of the screw without preload, F_0 the guide friction, F_p0 the
//! preload, F_c the cutting force along the axis, m the table (and work) mass, c its viscous
//! damping (paper 001's d), J_m the rotor inertia, a and α the table's and rotor's accelerations.
//! Friction and preload act against the motion: σ(v) = clamp(v / v_band, −1, 1) smooths the sign
//! over a small velocity band so that a standing axis carries no friction torque. The viscous term
//! makes the idle current grow with feed speed, as paper 000's Fig. 12 shows.
//!
//! ## Current (paper 000 eq 4–8)
//!
//! With i_d = 0 the torque is T_m = (3/2)·p·λ_m·i_q (eq 8, amplitude-invariant Park transform, so
//! i_q equals the phase-current amplitude I). The servo does not follow the load instantly: i_q
//! is the demanded current through a second-order lag at the feed drive's bandwidth, ~40 Hz
//! (paper 003, citing Matsushima et al.), damping 0.7. The phase currents are eq 4 at the
//! electrical angle θ of the current vector, which lies on the q axis, 90° ahead of the rotor:
//! θ = p·2π·x/L_0 + π/2, x the axis position. Real drives add 5th and 7th harmonics:
//!
//! ```text
//! i_u = I·[cos θ + h_5·cos 5θ + h_7·cos 7θ]
//! i_v = the same at θ + 2π/3,   i_w = the same at θ − 2π/3
//! ```
//!
//! The three sum to zero (eq 5), and their RMS is I/√2·√(1 + h_5² + h_7²) — I/√2 for a clean set.
//! θ advances with the axis, by p·2π·Δx/L_0 per sample, as a [`crate::math::Phasor`]: its cosine
//! and sine come by rotation, and the harmonics by complex powers, so a sample needs no
//! trigonometric call.
//!
//! NaN in a velocity or load propagates to the currents; the axis position stays finite only if
//! the velocity does.

use serde::{Deserialize, Serialize};
use std::f64::consts::{FRAC_PI_2, TAU};

use super::dynamics::SecondOrderLag;
use super::{in_range, non_negative, positive, PlantError, S_PER_MIN};
use crate::math::{self, Phasor};

/// Parameters of one feed axis. The defaults describe a mid-size vertical machining centre with a
/// FANUC-class AC servo motor; paper 000 gives the equations, not the numbers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct FeedDriveConfig {
    /// Ball screw pitch L_0. Default 10 mm (chosen).
    pub screw_pitch_mm: f64,
    /// Overall efficiency η of the transmission chain. Default 0.9 (chosen).
    pub efficiency: f64,
    /// Efficiency η_0 of the ball screw without preload. Default 0.9 (chosen; ball screws run
    /// 0.9–0.95).
    pub screw_efficiency: f64,
    /// Guide friction F_0. Default 245 N: μ = 0.05 on 500 kg (chosen).
    pub guide_friction_n: f64,
    /// Ball screw preload F_p0. Default 1000 N (chosen).
    pub preload_n: f64,
    /// Table plus work mass m. Default 500 kg (chosen).
    pub table_mass_kg: f64,
    /// Viscous damping c of table and guides. Default 15 N per mm/s (chosen so the idle current
    /// rises by a few percent between 50 and 200 mm/min, paper 000 Fig. 12).
    pub damping_n_s_per_mm: f64,
    /// Rotor (plus screw) inertia J_m. Default 0.0063 kg·m², paper 002's Table 1 J_m2.
    pub rotor_inertia_kg_m2: f64,
    /// Motor pole pairs p. Default 4 (chosen; an 8-pole AC servo).
    pub pole_pairs: u32,
    /// Rotor flux linkage amplitude λ_m. Default 0.2 Wb (chosen: K_t = 1.2 N·m/A).
    pub flux_linkage_wb: f64,
    /// Servo (current-follows-load) bandwidth. Default 40 Hz (paper 003).
    pub servo_bandwidth_hz: f64,
    /// Damping ratio of that response. Default 0.7 (chosen).
    pub servo_damping_ratio: f64,
    /// Velocity band over which friction changes sign. Default 1 mm/min (chosen).
    pub friction_band_mm_min: f64,
    /// 5th harmonic of the phase current, relative to the fundamental. Default 0.03 (chosen).
    pub harmonic_5th: f64,
    /// 7th harmonic, relative. Default 0.02 (chosen).
    pub harmonic_7th: f64,
}

impl Default for FeedDriveConfig {
    fn default() -> Self {
        Self {
            screw_pitch_mm: 10.0,
            efficiency: 0.9,
            screw_efficiency: 0.9,
            guide_friction_n: 245.0,
            preload_n: 1000.0,
            table_mass_kg: 500.0,
            damping_n_s_per_mm: 15.0,
            rotor_inertia_kg_m2: 0.0063,
            pole_pairs: 4,
            flux_linkage_wb: 0.2,
            servo_bandwidth_hz: 40.0,
            servo_damping_ratio: 0.7,
            friction_band_mm_min: 1.0,
            harmonic_5th: 0.03,
            harmonic_7th: 0.02,
        }
    }
}

impl FeedDriveConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("screw_pitch_mm", self.screw_pitch_mm)?;
        in_range("efficiency", self.efficiency, 0.05, 1.0)?;
        in_range("screw_efficiency", self.screw_efficiency, 0.05, 1.0)?;
        non_negative("guide_friction_n", self.guide_friction_n)?;
        non_negative("preload_n", self.preload_n)?;
        non_negative("table_mass_kg", self.table_mass_kg)?;
        non_negative("damping_n_s_per_mm", self.damping_n_s_per_mm)?;
        non_negative("rotor_inertia_kg_m2", self.rotor_inertia_kg_m2)?;
        if self.pole_pairs == 0 || self.pole_pairs > 64 {
            return Err(PlantError::new(
                "pole_pairs",
                format!("must lie in 1..=64, got {}", self.pole_pairs),
            ));
        }
        positive("flux_linkage_wb", self.flux_linkage_wb)?;
        positive("servo_bandwidth_hz", self.servo_bandwidth_hz)?;
        in_range("servo_damping_ratio", self.servo_damping_ratio, 0.05, 5.0)?;
        positive("friction_band_mm_min", self.friction_band_mm_min)?;
        in_range("harmonic_5th", self.harmonic_5th, 0.0, 0.5)?;
        in_range("harmonic_7th", self.harmonic_7th, 0.0, 0.5)?;
        Ok(())
    }

    /// Torque constant K_t = (3/2)·p·λ_m (eq 8), N·m per ampere of phase-current amplitude.
    ///
    /// ```
    /// use cutlab::plant::feed_drive::FeedDriveConfig;
    /// assert!((FeedDriveConfig::default().torque_constant_nm_per_a() - 1.2).abs() < 1e-12);
    /// ```
    pub fn torque_constant_nm_per_a(&self) -> f64 {
        1.5 * f64::from(self.pole_pairs) * self.flux_linkage_wb
    }

    /// L_0/(2πη): motor torque per newton at the nut.
    pub fn torque_per_force_nm_per_n(&self) -> f64 {
        self.screw_pitch_mm * 1e-3 / (TAU * self.efficiency)
    }

    /// F_0 + F_p0·(1 − η_0²): the force-equivalent of friction and preload (eq 3's idle part).
    pub fn friction_force_n(&self) -> f64 {
        self.guide_friction_n
            + self.preload_n * (1.0 - self.screw_efficiency * self.screw_efficiency)
    }

    /// The steady motor torque (eq 3 at constant speed) for a cutting force `load_force_n`
    /// resisting a motion at `speed_mm_min`.
    ///
    /// ```
    /// use cutlab::plant::feed_drive::FeedDriveConfig;
    /// let c = FeedDriveConfig::default();
    /// let t = c.steady_torque_nm(1000.0, 600.0);
    /// let expected = 0.01 / (std::f64::consts::TAU * 0.9) * (245.0 + 1000.0 * 0.19 + 1000.0 + 15.0 * 10.0);
    /// assert!((t - expected).abs() < 1e-9);
    /// ```
    pub fn steady_torque_nm(&self, load_force_n: f64, speed_mm_min: f64) -> f64 {
        let sigma = (speed_mm_min / self.friction_band_mm_min).clamp(-1.0, 1.0);
        self.torque_per_force_nm_per_n()
            * (self.friction_force_n() * sigma
                + load_force_n
                + self.damping_n_s_per_mm * speed_mm_min / S_PER_MIN)
    }

    /// The steady RMS phase current for a load at a speed: |T_m|/K_t/√2·√(1 + h_5² + h_7²), the
    /// straight line with an idle offset of paper 000 eq 9 and Fig. 11.
    pub fn steady_rms_current_a(&self, load_force_n: f64, speed_mm_min: f64) -> f64 {
        self.steady_torque_nm(load_force_n, speed_mm_min).abs() / self.torque_constant_nm_per_a()
            * self.waveform().rms_per_amplitude()
    }

    /// The idle (no-load) RMS current at a feed speed (paper 000 Fig. 12).
    ///
    /// ```
    /// use cutlab::plant::feed_drive::FeedDriveConfig;
    /// let c = FeedDriveConfig::default();
    /// assert!(c.idle_rms_current_a(200.0) > c.idle_rms_current_a(50.0));
    /// let slope = c.steady_rms_current_a(1000.0, 600.0) - c.idle_rms_current_a(600.0);
    /// assert!((slope - 1000.0 * c.torque_per_force_nm_per_n() / 1.2 * 0.7073).abs() < 1e-3);
    /// ```
    pub fn idle_rms_current_a(&self, speed_mm_min: f64) -> f64 {
        self.steady_rms_current_a(0.0, speed_mm_min)
    }

    fn waveform(&self) -> ThreePhaseWaveform {
        ThreePhaseWaveform::new(self.harmonic_5th, self.harmonic_7th)
    }
}

/// A balanced three-phase current shape (paper 000 eq 4) with 5th and 7th harmonics.
///
/// ```
/// use cutlab::plant::feed_drive::{three_phase_rms_a, ThreePhaseWaveform};
/// let w = ThreePhaseWaveform::new(0.0, 0.0);
/// let i = w.currents(10.0, 0.3);
/// assert!((i[0] + i[1] + i[2]).abs() < 1e-12);                    // eq 5
/// assert!((three_phase_rms_a(i) - 10.0 / 2f64.sqrt()).abs() < 1e-12); // eq 7: I/√2
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ThreePhaseWaveform {
    harmonic_5th: f64,
    harmonic_7th: f64,
}

impl ThreePhaseWaveform {
    /// A waveform with relative 5th and 7th harmonics.
    pub fn new(harmonic_5th: f64, harmonic_7th: f64) -> Self {
        Self {
            harmonic_5th,
            harmonic_7th,
        }
    }

    /// i_u, i_v, i_w for amplitude `amplitude_a` at electrical angle `theta_rad`.
    pub fn currents(&self, amplitude_a: f64, theta_rad: f64) -> [f64; 3] {
        self.currents_from_trig(amplitude_a, math::cos(theta_rad), math::sin(theta_rad))
    }

    /// The same from cos θ and sin θ, with no further trigonometry: the harmonics by complex
    /// powers z⁵, z⁷ of z = e^(iθ), and the phases in closed form. Phase k is
    /// Σ_n h_n·cos(n·(θ + ψ_k)) for n ∈ {1, 5, 7}, ψ = 0, +2π/3, −2π/3; n·2π/3 is +2π/3 for
    /// n = 1 and 7 and −2π/3 for n = 5 (mod 2π), so with
    /// P = cos θ + h_5·cos 5θ + h_7·cos 7θ and Q = sin θ − h_5·sin 5θ + h_7·sin 7θ:
    ///
    /// ```text
    /// i_u = I·P,   i_v = I·(−P/2 − (√3/2)·Q),   i_w = I·(−P/2 + (√3/2)·Q)
    /// ```
    #[inline(always)]
    pub fn currents_from_trig(&self, amplitude_a: f64, cos_theta: f64, sin_theta: f64) -> [f64; 3] {
        const HALF_SQRT_3: f64 = 0.866_025_403_784_438_6;
        let mul = |a: (f64, f64), b: (f64, f64)| (a.0 * b.0 - a.1 * b.1, a.0 * b.1 + a.1 * b.0);
        let z1 = (cos_theta, sin_theta);
        let z2 = mul(z1, z1);
        let z4 = mul(z2, z2);
        let z5 = mul(z4, z1);
        let z7 = mul(z5, z2);
        let p = z1.0 + self.harmonic_5th * z5.0 + self.harmonic_7th * z7.0;
        let q = z1.1 - self.harmonic_5th * z5.1 + self.harmonic_7th * z7.1;
        let (half_p, root_q) = (0.5 * p, HALF_SQRT_3 * q);
        [
            amplitude_a * p,
            amplitude_a * (-half_p - root_q),
            amplitude_a * (root_q - half_p),
        ]
    }

    /// [`ThreePhaseWaveform::currents_from_trig`] at `point`.
    #[inline(always)]
    pub fn currents_at(&self, point: PhasePoint) -> [f64; 3] {
        self.currents_from_trig(point.amplitude_a, point.cos_theta, point.sin_theta)
    }

    /// Time-RMS of one phase per unit amplitude, √(1 + h_5² + h_7²)/√2.
    pub fn rms_per_amplitude(&self) -> f64 {
        ((1.0 + self.harmonic_5th * self.harmonic_5th + self.harmonic_7th * self.harmonic_7th)
            / 2.0)
            .sqrt()
    }
}

/// What a drive's phase currents at one sample are made from: their amplitude and the cosine
/// and sine of the current vector's angle. A simulation keeps a block's points and works out
/// their currents together ([`ThreePhaseWaveform::currents_at`]) after the block's physics:
/// nothing in a drive depends on its phase currents.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PhasePoint {
    /// Phase-current amplitude.
    pub amplitude_a: f64,
    /// cos θ.
    pub cos_theta: f64,
    /// sin θ.
    pub sin_theta: f64,
}

/// Paper 003 eq 7: √((i_u² + i_v² + i_w²)/3).
///
/// ```
/// use cutlab::plant::feed_drive::three_phase_rms_a;
/// assert!((three_phase_rms_a([1.0, -0.5, -0.5]) - 0.5f64.sqrt()).abs() < 1e-15);
/// ```
#[inline(always)]
pub fn three_phase_rms_a(currents_a: [f64; 3]) -> f64 {
    ((currents_a[0] * currents_a[0]
        + currents_a[1] * currents_a[1]
        + currents_a[2] * currents_a[2])
        / 3.0)
        .sqrt()
}

/// One sample of a feed axis.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct FeedDriveOutput {
    /// Axis position (integrated velocity).
    pub position_mm: f64,
    /// Axis velocity.
    pub velocity_mm_min: f64,
    /// Axis acceleration.
    pub acceleration_mm_s2: f64,
    /// Torque the motor must give now (eq 3 with inertia).
    pub torque_demand_nm: f64,
    /// Torque it gives, after the servo's lag.
    pub torque_nm: f64,
    /// Torque-producing current i_q (= phase amplitude).
    pub iq_a: f64,
    /// Phase currents i_u, i_v, i_w.
    pub phase_currents_a: [f64; 3],
    /// Electrical angle θ of the current vector, in [0, 2π).
    pub electrical_angle_rad: f64,
}

/// The running state of one feed axis.
///
/// ```
/// use cutlab::plant::feed_drive::{FeedDrive, FeedDriveConfig};
/// let cfg = FeedDriveConfig::default();
/// let mut axis = FeedDrive::new(cfg, 1e-4).unwrap();
/// let mut out = axis.step(600.0, 500.0, 0.0);
/// for _ in 0..5000 { out = axis.step(600.0, 500.0, 0.0); }
/// assert!((out.torque_nm - cfg.steady_torque_nm(500.0, 600.0)).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeedDrive {
    config: FeedDriveConfig,
    k: FeedStepConstants,
    lag: SecondOrderLag,
    waveform: ThreePhaseWaveform,
    position_mm: f64,
    /// θ, π/2 at position 0.
    electrical: Phasor,
    previous_velocity_mm_min: f64,
}

/// What a step multiplies by, worked out once from the configuration and Δt (divisions are the
/// slowest arithmetic in a 10 kHz loop).
#[derive(Debug, Clone, Copy, PartialEq)]
struct FeedStepConstants {
    /// mm of travel per mm/min of velocity in one step, Δt/60.
    mm_per_mm_min: f64,
    /// mm/s² per mm/min of velocity change in one step, 1/(60·Δt).
    mm_s2_per_mm_min: f64,
    /// Friction and preload force at full sign, F_0 + F_p0·(1 − η_0²).
    friction_n: f64,
    /// 1/v_band.
    per_friction_band: f64,
    /// Table inertia, N per mm/s² (kg·mm/s² = 10⁻³ N).
    mass_n_per_mm_s2: f64,
    /// Viscous damping, N per mm/min.
    damping_n_per_mm_min: f64,
    /// Motor torque per newton at the nut, L_0/(2πη).
    torque_per_force_nm_per_n: f64,
    /// Rotor inertia torque per mm/s² of table acceleration, J_m·2π/L_0.
    rotor_nm_per_mm_s2: f64,
    /// 1/K_t.
    amps_per_nm: f64,
    /// Electrical radians per millimetre of travel, p·2π/L_0.
    electrical_rad_per_mm: f64,
}

impl FeedStepConstants {
    fn new(c: &FeedDriveConfig, dt_s: f64) -> Self {
        Self {
            mm_per_mm_min: dt_s / S_PER_MIN,
            mm_s2_per_mm_min: 1.0 / (S_PER_MIN * dt_s),
            friction_n: c.friction_force_n(),
            per_friction_band: 1.0 / c.friction_band_mm_min,
            mass_n_per_mm_s2: c.table_mass_kg * 1e-3,
            damping_n_per_mm_min: c.damping_n_s_per_mm / S_PER_MIN,
            torque_per_force_nm_per_n: c.torque_per_force_nm_per_n(),
            rotor_nm_per_mm_s2: c.rotor_inertia_kg_m2 * TAU / c.screw_pitch_mm,
            amps_per_nm: 1.0 / c.torque_constant_nm_per_a(),
            electrical_rad_per_mm: f64::from(c.pole_pairs) * TAU / c.screw_pitch_mm,
        }
    }
}

impl FeedDrive {
    /// An axis at rest at position 0, sampled every `dt_s`.
    pub fn new(config: FeedDriveConfig, dt_s: f64) -> Result<Self, PlantError> {
        config.validate()?;
        positive("dt_s", dt_s)?;
        Ok(Self {
            config,
            k: FeedStepConstants::new(&config, dt_s),
            lag: SecondOrderLag::new(config.servo_bandwidth_hz, config.servo_damping_ratio, dt_s),
            waveform: config.waveform(),
            position_mm: 0.0,
            electrical: Phasor::new(FRAC_PI_2),
            previous_velocity_mm_min: 0.0,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &FeedDriveConfig {
        &self.config
    }

    /// Back to rest at position 0.
    pub fn reset(&mut self) {
        self.lag.reset(0.0);
        self.position_mm = 0.0;
        self.electrical = Phasor::new(FRAC_PI_2);
        self.previous_velocity_mm_min = 0.0;
    }

    /// Advances one sample: the axis moves at `velocity_mm_min` against a cutting force
    /// `load_force_n` along its direction of positive motion (positive resists positive motion)
    /// plus an external torque `shaft_torque_nm` on the motor shaft (the brake bench's load).
    #[inline(always)]
    pub fn step(
        &mut self,
        velocity_mm_min: f64,
        load_force_n: f64,
        shaft_torque_nm: f64,
    ) -> FeedDriveOutput {
        let mut out = self.step_without_currents(velocity_mm_min, load_force_n, shaft_torque_nm);
        out.phase_currents_a = self.phase_currents_a(out.iq_a);
        out
    }

    /// [`FeedDrive::step`] without the phase currents (left NaN), for an axis whose currents
    /// nobody reads at this sample; [`FeedDrive::phase_currents_a`] right after gives them, the
    /// same bits as `step`'s.
    #[inline(always)]
    pub fn step_without_currents(
        &mut self,
        velocity_mm_min: f64,
        load_force_n: f64,
        shaft_torque_nm: f64,
    ) -> FeedDriveOutput {
        let k = &self.k;
        let accel_mm_s2 = (velocity_mm_min - self.previous_velocity_mm_min) * k.mm_s2_per_mm_min;
        self.previous_velocity_mm_min = velocity_mm_min;
        let step_mm = velocity_mm_min * k.mm_per_mm_min;
        self.position_mm += step_mm;
        self.electrical.advance(k.electrical_rad_per_mm * step_mm);
        // Friction, preload, cut, inertia of the table and damping.
        let force_n = k.friction_n * math::clamp(velocity_mm_min * k.per_friction_band, -1.0, 1.0)
            + load_force_n
            + k.mass_n_per_mm_s2 * accel_mm_s2
            + k.damping_n_per_mm_min * velocity_mm_min;
        let torque_demand_nm = k.torque_per_force_nm_per_n * force_n
            + k.rotor_nm_per_mm_s2 * accel_mm_s2
            + shaft_torque_nm;
        let torque_nm = self.lag.step(torque_demand_nm);
        let iq_a = torque_nm * k.amps_per_nm;
        let theta = &self.electrical;
        FeedDriveOutput {
            position_mm: self.position_mm,
            velocity_mm_min,
            acceleration_mm_s2: accel_mm_s2,
            torque_demand_nm,
            torque_nm,
            iq_a,
            phase_currents_a: [f64::NAN; 3],
            electrical_angle_rad: theta.angle_rad(),
        }
    }

    /// The phase currents for q-current `iq_a` at the axis's present electrical angle (the one
    /// its latest step left).
    #[inline(always)]
    pub fn phase_currents_a(&self, iq_a: f64) -> [f64; 3] {
        self.waveform.currents_at(self.phase_point(iq_a))
    }

    /// What [`FeedDrive::phase_currents_a`] makes the currents from: the amplitude `iq_a` and
    /// the electrical angle's cosine and sine now.
    #[inline(always)]
    pub fn phase_point(&self, iq_a: f64) -> PhasePoint {
        PhasePoint {
            amplitude_a: iq_a,
            cos_theta: self.electrical.cos(),
            sin_theta: self.electrical.sin(),
        }
    }

    /// The shape of its phase currents.
    pub fn waveform(&self) -> &ThreePhaseWaveform {
        &self.waveform
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn balanced_set_rms_is_amplitude_over_root_two_at_every_instant() {
        let w = ThreePhaseWaveform::new(0.0, 0.0);
        for k in 0..100 {
            let i = w.currents(3.0, 0.0628 * f64::from(k));
            assert!((three_phase_rms_a(i) - 3.0 / 2f64.sqrt()).abs() < 1e-12);
            assert!((i[0] + i[1] + i[2]).abs() < 1e-12);
        }
    }

    #[test]
    fn harmonics_keep_the_set_balanced_and_raise_the_time_rms() {
        let w = ThreePhaseWaveform::new(0.03, 0.02);
        let n = 3600;
        let mut sum_sq = 0.0;
        for k in 0..n {
            let theta = TAU * f64::from(k) / f64::from(n);
            let i = w.currents(2.0, theta);
            assert!((i[0] + i[1] + i[2]).abs() < 1e-12);
            sum_sq += i[0] * i[0];
        }
        let rms = (sum_sq / f64::from(n)).sqrt();
        assert!((rms - 2.0 * w.rms_per_amplitude()).abs() < 1e-12);
    }

    #[test]
    fn fifth_harmonic_is_negative_sequence() {
        // With only the 5th, phase v's harmonic equals phase u's shifted by −2π/3·… : check
        // cos 5(θ + 2π/3) = cos(5θ − 2π/3).
        let w = ThreePhaseWaveform::new(1.0, 0.0);
        let theta = 0.37;
        let clean = ThreePhaseWaveform::new(0.0, 0.0);
        let h = w.currents(1.0, theta)[1] - clean.currents(1.0, theta)[1];
        assert!((h - (5.0 * theta - TAU / 3.0).cos()).abs() < 1e-12);
    }

    #[test]
    fn the_electrical_angle_follows_the_axis_position() {
        // θ = p·2π·x/L_0 + π/2 (mod 2π), kept by rotation over a long run with varying speed.
        let cfg = FeedDriveConfig::default();
        let mut axis = FeedDrive::new(cfg, 1e-4).unwrap();
        for k in 0..100_000 {
            let speed = 600.0 + 400.0 * math::sin(f64::from(k) * 1e-4);
            let out = axis.step(speed, 0.0, 0.0);
            let turns = (out.position_mm / cfg.screw_pitch_mm).rem_euclid(1.0);
            let exact = (4.0 * TAU * turns + FRAC_PI_2).rem_euclid(TAU);
            let gap = (out.electrical_angle_rad - exact).abs();
            assert!(gap.min(TAU - gap) < 1e-9, "sample {k}: {gap}");
            let clean = ThreePhaseWaveform::new(cfg.harmonic_5th, cfg.harmonic_7th);
            let want = clean.currents(out.iq_a, exact);
            for (got, want) in out.phase_currents_a.iter().zip(want) {
                assert!((got - want).abs() < 1e-9 * out.iq_a.abs().max(1.0));
            }
        }
    }

    #[test]
    fn current_lags_a_load_step_with_the_servo_bandwidth() {
        let cfg = FeedDriveConfig {
            harmonic_5th: 0.0,
            harmonic_7th: 0.0,
            ..FeedDriveConfig::default()
        };
        let mut axis = FeedDrive::new(cfg, 1e-4).unwrap();
        for _ in 0..2000 {
            axis.step(300.0, 0.0, 0.0);
        }
        let before = axis.step(300.0, 0.0, 0.0).iq_a;
        let after_1ms = axis.step(300.0, 1000.0, 0.0).iq_a;
        let mut last = after_1ms;
        for _ in 0..3000 {
            last = axis.step(300.0, 1000.0, 0.0).iq_a;
        }
        let jump = cfg.torque_per_force_nm_per_n() * 1000.0 / cfg.torque_constant_nm_per_a();
        assert!((last - before - jump).abs() < 1e-9);
        assert!(
            after_1ms - before < 0.05 * jump,
            "a 40 Hz servo barely moves in 0.1 ms"
        );
    }

    #[test]
    fn idle_current_rises_with_feed_speed() {
        let c = FeedDriveConfig::default();
        let speeds = [50.0, 100.0, 150.0, 200.0];
        let idle: Vec<f64> = speeds.iter().map(|&v| c.idle_rms_current_a(v)).collect();
        assert!(idle.windows(2).all(|w| w[1] > w[0]));
        assert!(idle[0] > 0.0);
    }

    #[test]
    fn a_standing_axis_carries_no_friction() {
        let c = FeedDriveConfig::default();
        assert_eq!(c.steady_torque_nm(0.0, 0.0), 0.0);
        assert!(c.steady_torque_nm(0.0, -100.0) < 0.0);
    }

    #[test]
    fn bad_configs_name_the_field() {
        let e = FeedDriveConfig {
            efficiency: 1.5,
            ..FeedDriveConfig::default()
        }
        .validate()
        .unwrap_err();
        assert_eq!(e.field, "efficiency");
    }
}
