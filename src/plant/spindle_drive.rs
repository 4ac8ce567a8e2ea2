//! The spindle drive: squirrel-cage induction motor, two-range gearbox, F/V converter (paper 003).
//!
//! ## What paper 003 reports, and how cutlab produces it
//!
//! * **RMS current linear in cutting torque** (Fig. 6–7, eq 7): I_rms = I_idle(n) + S(n)·T_c.
//! * **Sensitivity rises with speed** (Fig. 3b) and **jumps at the gear change** at 900 rpm from
//!   the high ratio 1:4.81 to the low ratio 1:1.157. cutlab derives both from the motor: the
//!   gearbox divides the spindle torque by its ratio r (and efficiency η_g), and above its base
//!   speed n_b the motor runs field-weakened at constant power, so the current per unit torque
//!   grows as n_m/n_b:
//!
//!   ```text
//!   n_m  = r·n                                   motor speed; r = 4.81 below 900 rpm, 1.157 from 900 rpm
//!   S(n) = max(1, n_m/n_b) / (k_T·r·η_g)          A per N·m of spindle torque
//!   I_idle(n) = I_mag·min(1, n_b/n_m) + S(n)·T_drag(n),   T_drag = T_0 + b·n
//!   ```
//!
//!   With n_b = 1500 rpm the motor is field-weakened above n_b/r: above 312 rpm in the high
//!   range and above 1296 rpm in the low range, so S rises with speed in each range. At 900 rpm
//!   the low range brings the motor back below base speed (1041 rpm), so S jumps up by
//!   n_b/(900·1.157) ≈ 1.44. (Were both sides field-weakened, S = n/(n_b·k_T·η_g) would not
//!   depend on the ratio at all: at constant power the current follows the power, not the
//!   torque.)
//! * **Bandwidth below 5 Hz** (paper 003, citing Matsushima et al.): the motor torque follows the
//!   load torque through a second-order lag at the speed loop's bandwidth, 3 Hz by default.
//! * **A large current while the spindle starts or accelerates**: the speed loop accelerates the
//!   motor at up to its torque limit (constant below n_b, falling as n_b/n_m above), and the
//!   acceleration torque J·α adds to the current without lag. Paper 003 ignores the current for
//!   3 s after a start for this reason.
//! * **F/V converter** (Fig. 4): a voltage proportional to the motor's frequency, hence to the
//!   spindle speed with a different slope in each gear: V = k_FV·n_m.
//!
//! The phase currents are a balanced set of RMS I_rms at the stator frequency p·n_m/60 plus a
//! slip proportional to torque, with small 5th and 7th harmonics. Changing gear stops the
//! spindle, shifts, and restarts it. The stator angle and the tool's angle advance as
//! [`crate::math::Phasor`]s, so a sample needs no trigonometric call.
//!
//! A NaN torque or speed command propagates to the currents.

use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

use super::dynamics::SecondOrderLag;
use super::feed_drive::{PhasePoint, ThreePhaseWaveform};
use super::{in_range, non_negative, positive, rad_s_from_rpm, rpm_from_rad_s, PlantError};
use crate::math::{self, Phasor};

/// The gearbox range in use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum SpindleGear {
    /// The high reduction (paper 003: 1:4.81), below the gear-change speed.
    High,
    /// The low reduction (paper 003: 1:1.157), from the gear-change speed up.
    Low,
}

impl SpindleGear {
    /// Both gears.
    pub const ALL: [SpindleGear; 2] = [SpindleGear::High, SpindleGear::Low];

    /// Label for plots.
    pub fn label(self) -> &'static str {
        match self {
            SpindleGear::High => "high gear ratio (1:4.81)",
            SpindleGear::Low => "low gear ratio (1:1.157)",
        }
    }
}

/// Parameters of the spindle drive. Paper 003's machine gives the gear change and ratios; the
/// motor's numbers are chosen for an 11 kW, 4-pole spindle motor and say so.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SpindleDriveConfig {
    /// Spindle speed at and above which the low reduction is used. Default 900 rpm (paper 003).
    pub gear_change_rpm: f64,
    /// Motor turns per spindle turn in the high reduction. Default 4.81 (paper 003).
    pub high_gear_ratio: f64,
    /// Motor turns per spindle turn in the low reduction. Default 1.157 (paper 003).
    pub low_gear_ratio: f64,
    /// Gearbox efficiency. Default 0.95 (chosen).
    pub gear_efficiency: f64,
    /// Motor pole pairs. Default 2 (chosen: 4-pole).
    pub pole_pairs: u32,
    /// Motor base speed n_b, above which it is field-weakened. Default 1500 rpm (chosen; a
    /// 4-pole 50 Hz motor's, and it puts the gear-change speed's low range below base speed, so
    /// the sensitivity jumps there as in paper 003 Fig. 3b).
    pub base_speed_rpm: f64,
    /// Highest motor speed. Default 8000 rpm (chosen).
    pub max_motor_speed_rpm: f64,
    /// Magnetising (no-load) RMS current below base speed. Default 8 A (chosen).
    pub magnetizing_current_a: f64,
    /// Motor torque per RMS ampere of torque-producing current below base speed, k_T.
    /// Default 2.2 N·m/A (chosen: 70 N·m rated at ≈ 40 A).
    pub torque_per_amp_nm_per_a: f64,
    /// Rated motor torque, for the slip. Default 70 N·m (chosen: 11 kW at 1500 rpm).
    pub rated_torque_nm: f64,
    /// Motor torque limit below base speed (the drive's current limit). Default 90 N·m (chosen).
    pub torque_limit_nm: f64,
    /// Slip frequency at rated torque. Default 1.5 Hz (chosen).
    pub rated_slip_hz: f64,
    /// Constant drag torque of bearings and seals at the spindle, T_0. Default 0.8 N·m (chosen).
    pub drag_torque_nm: f64,
    /// Drag growing with speed, b. Default 0.6 N·m per 1000 rpm (chosen).
    pub drag_nm_per_krpm: f64,
    /// Inertia of motor, gearbox, spindle and tool seen at the motor. Default 0.25 kg·m²
    /// (chosen: a start to 1000 rpm takes ≈ 0.35 s, to 3000 rpm ≈ 1.4 s).
    pub inertia_kg_m2: f64,
    /// Bandwidth of the speed loop: the motor torque follows the load through it, and the speed
    /// approaches its command with this rate. Default 3 Hz (paper 003: below 5 Hz).
    pub bandwidth_hz: f64,
    /// Damping ratio of the torque response. Default 0.7 (chosen).
    pub damping_ratio: f64,
    /// F/V converter gain per 1000 motor rpm. Default 1.2 V (chosen: 9.6 V at 8000 rpm).
    pub fv_volts_per_krpm: f64,
    /// 5th harmonic of the phase current, relative. Default 0.02 (chosen).
    pub harmonic_5th: f64,
    /// 7th harmonic, relative. Default 0.01 (chosen).
    pub harmonic_7th: f64,
}

impl Default for SpindleDriveConfig {
    fn default() -> Self {
        Self {
            gear_change_rpm: 900.0,
            high_gear_ratio: 4.81,
            low_gear_ratio: 1.157,
            gear_efficiency: 0.95,
            pole_pairs: 2,
            base_speed_rpm: 1500.0,
            max_motor_speed_rpm: 8000.0,
            magnetizing_current_a: 8.0,
            torque_per_amp_nm_per_a: 2.2,
            rated_torque_nm: 70.0,
            torque_limit_nm: 90.0,
            rated_slip_hz: 1.5,
            drag_torque_nm: 0.8,
            drag_nm_per_krpm: 0.6,
            inertia_kg_m2: 0.25,
            bandwidth_hz: 3.0,
            damping_ratio: 0.7,
            fv_volts_per_krpm: 1.2,
            harmonic_5th: 0.02,
            harmonic_7th: 0.01,
        }
    }
}

impl SpindleDriveConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("gear_change_rpm", self.gear_change_rpm)?;
        positive("high_gear_ratio", self.high_gear_ratio)?;
        positive("low_gear_ratio", self.low_gear_ratio)?;
        in_range("gear_efficiency", self.gear_efficiency, 0.05, 1.0)?;
        if self.pole_pairs == 0 || self.pole_pairs > 16 {
            return Err(PlantError::new(
                "pole_pairs",
                format!("must lie in 1..=16, got {}", self.pole_pairs),
            ));
        }
        positive("base_speed_rpm", self.base_speed_rpm)?;
        positive("max_motor_speed_rpm", self.max_motor_speed_rpm)?;
        non_negative("magnetizing_current_a", self.magnetizing_current_a)?;
        positive("torque_per_amp_nm_per_a", self.torque_per_amp_nm_per_a)?;
        positive("rated_torque_nm", self.rated_torque_nm)?;
        positive("torque_limit_nm", self.torque_limit_nm)?;
        non_negative("rated_slip_hz", self.rated_slip_hz)?;
        non_negative("drag_torque_nm", self.drag_torque_nm)?;
        non_negative("drag_nm_per_krpm", self.drag_nm_per_krpm)?;
        positive("inertia_kg_m2", self.inertia_kg_m2)?;
        positive("bandwidth_hz", self.bandwidth_hz)?;
        in_range("damping_ratio", self.damping_ratio, 0.05, 5.0)?;
        non_negative("fv_volts_per_krpm", self.fv_volts_per_krpm)?;
        in_range("harmonic_5th", self.harmonic_5th, 0.0, 0.5)?;
        in_range("harmonic_7th", self.harmonic_7th, 0.0, 0.5)?;
        Ok(())
    }

    /// The gear used at spindle speed `spindle_rpm`.
    ///
    /// ```
    /// use cutlab::plant::spindle_drive::{SpindleDriveConfig, SpindleGear};
    /// let c = SpindleDriveConfig::default();
    /// assert_eq!(c.gear_for(899.9), SpindleGear::High);
    /// assert_eq!(c.gear_for(900.0), SpindleGear::Low);
    /// ```
    pub fn gear_for(&self, spindle_rpm: f64) -> SpindleGear {
        if spindle_rpm.abs() < self.gear_change_rpm {
            SpindleGear::High
        } else {
            SpindleGear::Low
        }
    }

    /// Motor turns per spindle turn in `gear`.
    pub fn ratio(&self, gear: SpindleGear) -> f64 {
        match gear {
            SpindleGear::High => self.high_gear_ratio,
            SpindleGear::Low => self.low_gear_ratio,
        }
    }

    /// The highest spindle speed (low reduction at the motor's top speed).
    pub fn max_spindle_rpm(&self) -> f64 {
        self.max_motor_speed_rpm / self.low_gear_ratio
    }

    /// Field-weakening factor max(1, n_m/n_b) at motor speed `motor_rpm`.
    fn weakening(&self, motor_rpm: f64) -> f64 {
        (motor_rpm.abs() / self.base_speed_rpm).max(1.0)
    }

    /// RMS current per motor torque at a motor speed.
    fn amps_per_motor_nm(&self, motor_rpm: f64) -> f64 {
        self.weakening(motor_rpm) / self.torque_per_amp_nm_per_a
    }

    /// Magnetising current at a motor speed.
    fn magnetizing_a(&self, motor_rpm: f64) -> f64 {
        self.magnetizing_current_a / self.weakening(motor_rpm)
    }

    /// Drag torque at the spindle at `spindle_rpm` (zero at rest).
    pub fn drag_torque_at_nm(&self, spindle_rpm: f64) -> f64 {
        if spindle_rpm == 0.0 {
            0.0
        } else {
            (self.drag_torque_nm + self.drag_nm_per_krpm * spindle_rpm.abs() * 1e-3)
                * spindle_rpm.signum()
        }
    }

    /// Quasi-static sensitivity S(n): RMS amperes per N·m of cutting torque at the spindle,
    /// in the gear used at `spindle_rpm`.
    ///
    /// ```
    /// use cutlab::plant::spindle_drive::SpindleDriveConfig;
    /// let c = SpindleDriveConfig::default();
    /// // Below 900 rpm: 4.81 reduction, motor at 4324 rpm, field-weakened by 4324/1500.
    /// let s = c.sensitivity_a_per_nm(899.0);
    /// assert!((s - (899.0 * 4.81 / 1500.0) / (2.2 * 4.81 * 0.95)).abs() < 1e-12);
    /// assert!(c.sensitivity_a_per_nm(900.0) > 1.4 * s); // the gear-change jump
    /// ```
    pub fn sensitivity_a_per_nm(&self, spindle_rpm: f64) -> f64 {
        let r = self.ratio(self.gear_for(spindle_rpm));
        self.amps_per_motor_nm(spindle_rpm * r) / (r * self.gear_efficiency)
    }

    /// Idle (air-cut) RMS current at `spindle_rpm`: magnetising current plus the drag's share.
    pub fn idle_current_a(&self, spindle_rpm: f64) -> f64 {
        if spindle_rpm == 0.0 {
            return 0.0;
        }
        let r = self.ratio(self.gear_for(spindle_rpm));
        self.magnetizing_a(spindle_rpm * r)
            + self.sensitivity_a_per_nm(spindle_rpm) * self.drag_torque_at_nm(spindle_rpm).abs()
    }

    /// Steady RMS current at `spindle_rpm` with cutting torque `cutting_torque_nm` ≥ 0:
    /// I_idle(n) + S(n)·T_c.
    ///
    /// ```
    /// use cutlab::plant::spindle_drive::SpindleDriveConfig;
    /// let c = SpindleDriveConfig::default();
    /// let idle = c.idle_current_a(1000.0); // 8 A magnetising + drag
    /// assert!((c.steady_rms_current_a(1000.0, 5.0) - idle - 5.0 * c.sensitivity_a_per_nm(1000.0)).abs() < 1e-12);
    /// assert!(idle > 8.0 && idle < 9.0);
    /// ```
    pub fn steady_rms_current_a(&self, spindle_rpm: f64, cutting_torque_nm: f64) -> f64 {
        self.idle_current_a(spindle_rpm)
            + self.sensitivity_a_per_nm(spindle_rpm) * cutting_torque_nm
    }

    /// F/V converter voltage at `spindle_rpm` in its gear: k_FV·r·n/1000.
    ///
    /// ```
    /// use cutlab::plant::spindle_drive::SpindleDriveConfig;
    /// let c = SpindleDriveConfig::default();
    /// assert!((c.fv_voltage_v(1000.0) - 1.2 * 1.157).abs() < 1e-12);
    /// assert!((c.fv_voltage_v(500.0) - 1.2 * 0.5 * 4.81).abs() < 1e-12);
    /// ```
    pub fn fv_voltage_v(&self, spindle_rpm: f64) -> f64 {
        self.fv_volts_per_krpm * spindle_rpm.abs() * self.ratio(self.gear_for(spindle_rpm)) * 1e-3
    }
}

/// One sample of the spindle drive.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct SpindleDriveOutput {
    /// Spindle speed.
    pub speed_rpm: f64,
    /// Motor speed.
    pub motor_speed_rpm: f64,
    /// Spindle angle, [0, 2π), turning clockwise (the tool's angle in the machine frame).
    pub angle_rad: f64,
    /// Gear in use.
    pub gear: Option<SpindleGear>,
    /// Torque at the spindle the load asks for (cut plus drag).
    pub load_torque_nm: f64,
    /// Motor torque (lagged load share plus acceleration torque).
    pub motor_torque_nm: f64,
    /// RMS motor current.
    pub rms_current_a: f64,
    /// Phase currents.
    pub phase_currents_a: [f64; 3],
    /// F/V converter output.
    pub fv_voltage_v: f64,
    /// Whether the spindle turns (or is commanded to).
    pub running: bool,
}

/// The running spindle drive.
///
/// ```
/// use cutlab::plant::spindle_drive::{SpindleDrive, SpindleDriveConfig};
/// let mut s = SpindleDrive::new(SpindleDriveConfig::default(), 1e-3).unwrap();
/// let mut out = s.step(1000.0, 0.0);
/// for _ in 0..3000 { out = s.step(1000.0, 0.0); }
/// assert!((out.speed_rpm - 1000.0).abs() < 0.5);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpindleDrive {
    config: SpindleDriveConfig,
    dt_s: f64,
    k: SpindleStepConstants,
    lag: SecondOrderLag,
    waveform: ThreePhaseWaveform,
    /// Motor speed, rad/s (signed).
    motor_rad_s: f64,
    gear: SpindleGear,
    /// The tool's angle, clockwise, with its cosine and sine (the cutting forces need both).
    spindle_angle: Phasor,
    /// The stator current's angle.
    electrical_angle: Phasor,
}

/// Below this motor speed (rad/s) a stopped spindle counts as at rest (gear shifts happen here).
const REST_RAD_S: f64 = 0.05;

impl SpindleDrive {
    /// A drive at rest in the high reduction, sampled every `dt_s`.
    pub fn new(config: SpindleDriveConfig, dt_s: f64) -> Result<Self, PlantError> {
        config.validate()?;
        positive("dt_s", dt_s)?;
        Ok(Self {
            config,
            dt_s,
            k: SpindleStepConstants::new(&config, dt_s),
            lag: SecondOrderLag::new(config.bandwidth_hz, config.damping_ratio, dt_s),
            waveform: ThreePhaseWaveform::new(config.harmonic_5th, config.harmonic_7th),
            motor_rad_s: 0.0,
            gear: SpindleGear::High,
            spindle_angle: Phasor::new(0.0),
            electrical_angle: Phasor::new(0.0),
        })
    }

    /// The configuration.
    pub fn config(&self) -> &SpindleDriveConfig {
        &self.config
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        self.lag.reset(0.0);
        self.motor_rad_s = 0.0;
        self.gear = SpindleGear::High;
        self.spindle_angle = Phasor::new(0.0);
        self.electrical_angle = Phasor::new(0.0);
    }

    /// The spindle speed now.
    #[inline(always)]
    pub fn speed_rpm(&self) -> f64 {
        rpm_from_rad_s(self.motor_rad_s) / self.config.ratio(self.gear)
    }

    /// The spindle angle now, [0, 2π).
    pub fn angle_rad(&self) -> f64 {
        self.spindle_angle.angle_rad()
    }

    /// The spindle angle now with its cosine and sine.
    #[inline(always)]
    pub fn angle(&self) -> &Phasor {
        &self.spindle_angle
    }

    /// Advances one sample with the speed command `command_rpm` (0 stops the spindle, clamped to
    /// the top speed) and the cutting torque `cutting_torque_nm` at the spindle.
    #[inline(always)]
    pub fn step(&mut self, command_rpm: f64, cutting_torque_nm: f64) -> SpindleDriveOutput {
        let mut out = self.step_without_currents(command_rpm, cutting_torque_nm);
        out.phase_currents_a = self.phase_currents_a(out.rms_current_a);
        out
    }

    /// [`SpindleDrive::step`] without the phase currents (left NaN): a simulation that works
    /// out a block's phase currents together (they feed nothing back) asks
    /// [`SpindleDrive::phase_point`] for what they are made of right after, the same bits as
    /// `step`'s.
    #[inline(always)]
    pub fn step_without_currents(
        &mut self,
        command_rpm: f64,
        cutting_torque_nm: f64,
    ) -> SpindleDriveOutput {
        let c = &self.config;
        let k = &self.k;
        let command_rpm = math::clamp(command_rpm, -k.max_spindle_rpm, k.max_spindle_rpm);
        let wanted_gear = c.gear_for(command_rpm);
        let shifting = wanted_gear != self.gear && command_rpm != 0.0;
        if shifting && self.motor_rad_s.abs() < REST_RAD_S {
            self.gear = wanted_gear;
            self.motor_rad_s = 0.0;
        }
        let gear = &k.gears[self.gear as usize];
        let target_rad_s = if wanted_gear != self.gear {
            0.0 // stop before shifting
        } else {
            command_rpm * gear.motor_rad_s_per_spindle_rpm
        };
        let spindle_rpm = self.motor_rad_s * gear.spindle_rpm_per_motor_rad_s;
        let load_torque_nm = cutting_torque_nm + c.drag_torque_at_nm(spindle_rpm);
        let lagged_load_motor_nm = self.lag.step(load_torque_nm * gear.motor_nm_per_spindle_nm);
        // Speed loop: approach the target at the loop's rate, within the torque left over. Above
        // base speed the torque limit falls and the magnetising current with it, as n_b/n_m.
        let per_weakened_rad_s = 1.0 / math::max(self.motor_rad_s.abs(), k.base_rad_s);
        let limit_nm = k.torque_limit_base_nm * per_weakened_rad_s;
        let headroom_nm = math::max(limit_nm - lagged_load_motor_nm.abs(), 0.0);
        let accel_torque_nm = math::clamp(
            k.loop_nm_per_rad_s * (target_rad_s - self.motor_rad_s),
            -headroom_nm,
            headroom_nm,
        );
        self.motor_rad_s += accel_torque_nm * k.rad_s_per_nm_step;
        let stopped = command_rpm == 0.0 && self.motor_rad_s.abs() < REST_RAD_S;
        if stopped {
            self.motor_rad_s = 0.0;
        }
        let motor_rpm = rpm_from_rad_s(self.motor_rad_s);
        let speed_rpm = self.motor_rad_s * gear.spindle_rpm_per_motor_rad_s;
        let motor_torque_nm = lagged_load_motor_nm + accel_torque_nm;
        let rms_current_a = if stopped {
            0.0
        } else {
            // I_mag·min(1, n_b/n_m) + max(1, n_m/n_b)/k_T·|T_m|
            let weakening = math::max(self.motor_rad_s.abs() * k.per_base_rad_s, 1.0);
            k.magnetizing_base_a * per_weakened_rad_s
                + weakening * k.amps_per_nm * motor_torque_nm.abs()
        };
        // Clockwise seen from the spindle: the tool angle grows with positive speed.
        self.spindle_angle
            .advance(self.motor_rad_s * gear.spindle_step_rad_per_motor_rad_s);
        let stator_hz =
            k.stator_hz_per_rad_s * self.motor_rad_s + k.slip_hz_per_nm * motor_torque_nm;
        self.electrical_angle.advance(k.step_rad_per_hz * stator_hz);
        SpindleDriveOutput {
            speed_rpm,
            motor_speed_rpm: motor_rpm,
            angle_rad: self.spindle_angle.angle_rad(),
            gear: (!stopped).then_some(self.gear),
            load_torque_nm,
            motor_torque_nm,
            rms_current_a,
            phase_currents_a: [f64::NAN; 3],
            fv_voltage_v: k.fv_volts_per_rpm * motor_rpm.abs(),
            running: !stopped,
        }
    }

    /// The phase currents for the RMS current `rms_current_a` at the stator's present angle
    /// (the one its latest step left).
    #[inline(always)]
    pub fn phase_currents_a(&self, rms_current_a: f64) -> [f64; 3] {
        self.waveform.currents_at(self.phase_point(rms_current_a))
    }

    /// What [`SpindleDrive::phase_currents_a`] makes the currents from: the amplitude √2·RMS
    /// and the stator angle's cosine and sine now.
    #[inline(always)]
    pub fn phase_point(&self, rms_current_a: f64) -> PhasePoint {
        PhasePoint {
            amplitude_a: rms_current_a * std::f64::consts::SQRT_2,
            cos_theta: self.electrical_angle.cos(),
            sin_theta: self.electrical_angle.sin(),
        }
    }

    /// The shape of its phase currents.
    pub fn waveform(&self) -> &ThreePhaseWaveform {
        &self.waveform
    }
}

/// What a step multiplies by, worked out once from the configuration and Δt (divisions are the
/// slowest arithmetic in a 10 kHz loop).
#[derive(Debug, Clone, Copy, PartialEq)]
struct SpindleStepConstants {
    max_spindle_rpm: f64,
    /// Per gear, indexed by `SpindleGear as usize`.
    gears: [GearConstants; 2],
    /// Base speed n_b in rad/s, and its reciprocal.
    base_rad_s: f64,
    per_base_rad_s: f64,
    /// Torque limit × base speed: the limit at ω is this / max(ω, ω_b).
    torque_limit_base_nm: f64,
    /// Magnetising current × base speed: the current at ω is this / max(ω, ω_b).
    magnetizing_base_a: f64,
    /// 1/k_T.
    amps_per_nm: f64,
    /// Speed loop: J·2π·bandwidth, N·m per rad/s of speed error.
    loop_nm_per_rad_s: f64,
    /// Δt/J: the speed change per N·m of accelerating torque in one step.
    rad_s_per_nm_step: f64,
    /// Stator frequency per motor rad/s, p/2π, and slip frequency per N·m.
    stator_hz_per_rad_s: f64,
    slip_hz_per_nm: f64,
    /// 2π·Δt: the angle step of one hertz.
    step_rad_per_hz: f64,
    /// F/V volts per motor rpm.
    fv_volts_per_rpm: f64,
}

/// [`SpindleStepConstants`] of one gear with ratio r.
#[derive(Debug, Clone, Copy, PartialEq)]
struct GearConstants {
    /// r·2π/60.
    motor_rad_s_per_spindle_rpm: f64,
    /// 60/(2π·r).
    spindle_rpm_per_motor_rad_s: f64,
    /// 1/(r·η_g).
    motor_nm_per_spindle_nm: f64,
    /// Δt/r: the tool's angle step per motor rad/s.
    spindle_step_rad_per_motor_rad_s: f64,
}

impl SpindleStepConstants {
    fn new(c: &SpindleDriveConfig, dt_s: f64) -> Self {
        let gear = |g: SpindleGear| {
            let r = c.ratio(g);
            GearConstants {
                motor_rad_s_per_spindle_rpm: rad_s_from_rpm(r),
                spindle_rpm_per_motor_rad_s: rpm_from_rad_s(1.0) / r,
                motor_nm_per_spindle_nm: 1.0 / (r * c.gear_efficiency),
                spindle_step_rad_per_motor_rad_s: dt_s / r,
            }
        };
        let base_rad_s = rad_s_from_rpm(c.base_speed_rpm);
        Self {
            max_spindle_rpm: c.max_spindle_rpm(),
            gears: [gear(SpindleGear::High), gear(SpindleGear::Low)],
            base_rad_s,
            per_base_rad_s: 1.0 / base_rad_s,
            torque_limit_base_nm: c.torque_limit_nm * base_rad_s,
            magnetizing_base_a: c.magnetizing_current_a * base_rad_s,
            amps_per_nm: 1.0 / c.torque_per_amp_nm_per_a,
            loop_nm_per_rad_s: c.inertia_kg_m2 * TAU * c.bandwidth_hz,
            rad_s_per_nm_step: dt_s / c.inertia_kg_m2,
            stator_hz_per_rad_s: f64::from(c.pole_pairs) / TAU,
            slip_hz_per_nm: c.rated_slip_hz / c.rated_torque_nm,
            step_rad_per_hz: TAU * dt_s,
            fv_volts_per_rpm: c.fv_volts_per_krpm * 1e-3,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run(drive: &mut SpindleDrive, rpm: f64, torque: f64, seconds: f64) -> SpindleDriveOutput {
        let n = (seconds / drive.dt_s).round() as usize;
        let mut out = SpindleDriveOutput::default();
        for _ in 0..n {
            out = drive.step(rpm, torque);
        }
        out
    }

    #[test]
    fn steady_current_is_idle_plus_sensitivity_times_torque() {
        let cfg = SpindleDriveConfig::default();
        let mut d = SpindleDrive::new(cfg, 1e-3).unwrap();
        let out = run(&mut d, 1000.0, 8.0, 5.0);
        let expected = cfg.steady_rms_current_a(1000.0, 8.0);
        assert!(
            (out.rms_current_a - expected).abs() < 1e-3 * expected,
            "{out:?}"
        );
    }

    #[test]
    fn starting_draws_far_more_than_the_running_current() {
        let cfg = SpindleDriveConfig::default();
        let mut d = SpindleDrive::new(cfg, 1e-3).unwrap();
        let start = run(&mut d, 3000.0, 0.0, 0.2);
        let running = run(&mut d, 3000.0, 0.0, 6.0);
        assert!(
            start.rms_current_a > 3.0 * running.rms_current_a,
            "{start:?} {running:?}"
        );
        assert!((running.speed_rpm - 3000.0).abs() < 1.0);
    }

    #[test]
    fn changing_gear_stops_and_restarts_the_spindle() {
        let cfg = SpindleDriveConfig::default();
        let mut d = SpindleDrive::new(cfg, 1e-3).unwrap();
        let low = run(&mut d, 600.0, 0.0, 3.0);
        assert_eq!(low.gear, Some(SpindleGear::High));
        let mut min_speed = f64::INFINITY;
        for _ in 0..6000 {
            min_speed = min_speed.min(d.step(1200.0, 0.0).speed_rpm);
        }
        assert!(min_speed < 1.0);
        assert_eq!(d.step(1200.0, 0.0).gear, Some(SpindleGear::Low));
        assert!((d.speed_rpm() - 1200.0).abs() < 1.0);
    }

    #[test]
    fn fv_voltage_is_proportional_to_speed_within_each_gear() {
        let c = SpindleDriveConfig::default();
        let slope = |a: f64, b: f64| (c.fv_voltage_v(b) - c.fv_voltage_v(a)) / (b - a);
        assert!((slope(300.0, 800.0) - c.fv_voltage_v(300.0) / 300.0).abs() < 1e-12);
        assert!((slope(1000.0, 3000.0) - c.fv_voltage_v(1000.0) / 1000.0).abs() < 1e-12);
        assert!(c.fv_voltage_v(899.0) > c.fv_voltage_v(900.0));
    }

    #[test]
    fn stopped_spindle_draws_nothing() {
        let mut d = SpindleDrive::new(SpindleDriveConfig::default(), 1e-3).unwrap();
        let out = d.step(0.0, 0.0);
        assert_eq!(out.rms_current_a, 0.0);
        assert!(!out.running);
    }
}
