//! Paper 000's test bench: a magnetic-particle brake loads the feed servo motor.
//!
//! Paper 000 (§4.1, Fig. 4–5, 7–12) drives a FANUC AC servo motor through its servo amplifier and
//! loads it with a magnetic-particle brake fed by a steady power supply. The brake's torque is
//! linear in its excitation current, with magnetic hysteresis between loading and unloading
//! (Fig. 5: 0 → 5 A → 0). The motor's RMS phase current is then linear in the load torque with an
//! idle offset (Fig. 11, eq 9), and the idle current changes a little with speed (Fig. 12).
//!
//! cutlab's bench is the feed drive of [`super::feed_drive`] (ball screw and table included, as
//! on a machine axis) turning at a constant feed while the brake's torque acts on the motor shaft:
//!
//! ```text
//! T_brake = k_b · max(m, 0),   m ← clamp(m, I_exc − h, I_exc + h)     (play hysteresis)
//! T_m     = (eq 3 at the bench's feed) + T_brake·σ(v)
//! ```
//!
//! The play operator makes the torque lag by h on the way up and lead by h on the way down, so the
//! unloading curve lies above the loading one (remanence), as in Fig. 5. The brake only resists
//! motion: standing still, it holds no torque.
//!
//! The default schedule steps the excitation 0 → 1 A → 0 in 0.1 A steps of 3 s at 600 mm/min,
//! where a 10 mm screw and a 4-pole-pair motor give a 4 Hz electrical frequency: paper 000's
//! "peak in the 4 Hz frequency area" (Fig. 9) whose height rises with the load.
//!
//! [`PlantTruth::feed_force_n`] carries the brake's torque as the equivalent force at the nut,
//! T_brake·2πη/L_0, so a feed-current model can be calibrated on the bench exactly as paper 000
//! does; there is no cutting and no spindle: depth and width of cut are 0 and the cutting
//! angles NaN. A NaN excitation gives a NaN torque; the schedule's validated values never do.

use serde::{Deserialize, Serialize};

use super::cnc::{CncConfig, Control, PlanBlock};
use super::feed_drive::{three_phase_rms_a, FeedDrive, FeedDriveConfig};
use super::sensors::{CurrentSensor, CurrentSensorConfig};
use super::signals::{AxisSignals, PlantSignals};
use super::{
    non_negative, positive, PlantError, PlantModel, PlantSample, Sampling, Tick, S_PER_MIN,
};
use crate::machine::{OverrideCommand, PlantTruth, SensorSample};
use crate::math;
use crate::rng::Rng;

/// A magnetic-particle brake.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BrakeConfig {
    /// Torque per ampere of excitation. Default 2 N·m/A (chosen: 10 N·m at the 5 A of Fig. 5).
    pub torque_per_amp_nm_per_a: f64,
    /// Half-width h of the hysteresis, in excitation amperes. Default 0.03 A (chosen: 0.6 % of
    /// the 5 A range).
    pub hysteresis_a: f64,
    /// Largest excitation. Default 5 A (paper 000 Fig. 5).
    pub rated_current_a: f64,
}

impl Default for BrakeConfig {
    fn default() -> Self {
        Self {
            torque_per_amp_nm_per_a: 2.0,
            hysteresis_a: 0.03,
            rated_current_a: 5.0,
        }
    }
}

impl BrakeConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("torque_per_amp_nm_per_a", self.torque_per_amp_nm_per_a)?;
        non_negative("hysteresis_a", self.hysteresis_a)?;
        positive("rated_current_a", self.rated_current_a)?;
        Ok(())
    }
}

/// The brake's state: the play operator's output.
///
/// ```
/// use cutlab::plant::bench::{BrakeConfig, MagneticParticleBrake};
/// let mut b = MagneticParticleBrake::new(BrakeConfig::default()).unwrap();
/// let up = b.torque_nm(0.5);   // loading: (0.5 − 0.03)·2
/// b.torque_nm(1.0);
/// let down = b.torque_nm(0.5); // unloading: (0.5 + 0.03)·2
/// assert!((up - 0.94).abs() < 1e-12 && (down - 1.06).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MagneticParticleBrake {
    config: BrakeConfig,
    state_a: f64,
}

impl MagneticParticleBrake {
    /// A demagnetised brake.
    pub fn new(config: BrakeConfig) -> Result<Self, PlantError> {
        config.validate()?;
        Ok(Self {
            config,
            state_a: 0.0,
        })
    }

    /// The torque at excitation `excitation_a` (clamped to 0…rated), updating the hysteresis.
    pub fn torque_nm(&mut self, excitation_a: f64) -> f64 {
        if excitation_a.is_nan() {
            return f64::NAN;
        }
        let i = excitation_a.clamp(0.0, self.config.rated_current_a);
        let h = self.config.hysteresis_a;
        self.state_a = self.state_a.clamp(i - h, i + h);
        self.config.torque_per_amp_nm_per_a * self.state_a.max(0.0)
    }

    /// Demagnetises.
    pub fn reset(&mut self) {
        self.state_a = 0.0;
    }
}

/// What a real bench adds to the brake's torque and the motor's nominal friction: the friction of
/// screw, nut and guides wanders (lubricant film, temperature, position along the screw) and
/// falls slowly as the axis warms up. Paper 000's Fig. 11 shows its points scattered about the
/// line; the figure's data are lost, so the defaults are chosen to give the scatter of such
/// calibrations (R² ≈ 0.998 over the default schedule, 1 without them): a wander of σ = 0.03 N·m (1.5 % of the 2
/// N·m full load) with a 2 s correlation time, and a warm-up drift of −0.02 N·m per minute.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BenchFrictionConfig {
    /// Standard deviation of the wandering friction torque.
    pub scatter_nm: f64,
    /// Its correlation time (an Ornstein–Uhlenbeck process).
    pub correlation_time_s: f64,
    /// Change of the friction torque per minute of running (negative: it falls as it warms).
    pub drift_nm_per_min: f64,
}

impl Default for BenchFrictionConfig {
    fn default() -> Self {
        Self {
            scatter_nm: 0.03,
            correlation_time_s: 2.0,
            drift_nm_per_min: -0.02,
        }
    }
}

impl BenchFrictionConfig {
    /// An ideal bench: the nominal friction only.
    pub const IDEAL: Self = Self {
        scatter_nm: 0.0,
        correlation_time_s: 1.0,
        drift_nm_per_min: 0.0,
    };

    fn validate(&self) -> Result<(), PlantError> {
        non_negative("scatter_nm", self.scatter_nm)?;
        positive("correlation_time_s", self.correlation_time_s)?;
        if !self.drift_nm_per_min.is_finite() {
            return Err(PlantError::new(
                "drift_nm_per_min",
                format!("must be a finite number, got {}", self.drift_nm_per_min),
            ));
        }
        Ok(())
    }
}

/// The wandering friction is updated this often (it changes over seconds).
const FRICTION_UPDATE_S: f64 = 0.01;
/// The seed stream of the friction's wander, apart from the sensors'.
const FRICTION_STREAM: u64 = 0xF41C;

/// The bench's settings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct BrakeBenchConfig {
    /// Feed the servo turns at (at 100 % override). Default 600 mm/min (4 Hz electrical).
    pub feed_mm_min: f64,
    /// Excitation of each step, in order.
    pub excitation_steps_a: Vec<f64>,
    /// Duration of each step. Default 3 s.
    pub step_duration_s: f64,
    /// The brake.
    pub brake: BrakeConfig,
    /// Sensor sample rate. Default 10 kHz.
    pub sample_rate_hz: f64,
    /// Seed of the sensor noise.
    pub seed: u64,
    /// The control (override mode, acceleration).
    pub cnc: CncConfig,
    /// The servo motor and its axis.
    pub feed_drive: FeedDriveConfig,
    /// The Hall sensors and ADC.
    pub feed_sensor: CurrentSensorConfig,
    /// Friction's wander and drift.
    pub friction: BenchFrictionConfig,
}

impl Default for BrakeBenchConfig {
    fn default() -> Self {
        let up = (0..=10).map(|k| 0.1 * f64::from(k));
        let down = (0..10).rev().map(|k| 0.1 * f64::from(k));
        Self {
            feed_mm_min: 600.0,
            excitation_steps_a: up.chain(down).collect(),
            step_duration_s: 3.0,
            brake: BrakeConfig::default(),
            sample_rate_hz: 10_000.0,
            seed: 0,
            cnc: CncConfig::default(),
            feed_drive: FeedDriveConfig::default(),
            feed_sensor: CurrentSensorConfig::feed(),
            friction: BenchFrictionConfig::default(),
        }
    }
}

impl BrakeBenchConfig {
    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("feed_mm_min", self.feed_mm_min)?;
        if self.excitation_steps_a.is_empty() {
            return Err(PlantError::new(
                "excitation_steps_a",
                "needs at least one step",
            ));
        }
        for (i, e) in self.excitation_steps_a.iter().enumerate() {
            non_negative(&format!("excitation_steps_a[{i}]"), *e)?;
        }
        positive("step_duration_s", self.step_duration_s)?;
        self.brake.validate().map_err(|e| e.within("brake"))?;
        positive("sample_rate_hz", self.sample_rate_hz)?;
        self.cnc.validate().map_err(|e| e.within("cnc"))?;
        self.feed_drive
            .validate()
            .map_err(|e| e.within("feed_drive"))?;
        self.feed_sensor
            .validate()
            .map_err(|e| e.within("feed_sensor"))?;
        self.friction.validate().map_err(|e| e.within("friction"))?;
        Ok(())
    }

    /// Total run time.
    pub fn duration_s(&self) -> f64 {
        self.step_duration_s * self.excitation_steps_a.len() as f64
    }

    /// The excitation at `time_s`.
    ///
    /// ```
    /// use cutlab::plant::bench::BrakeBenchConfig;
    /// let c = BrakeBenchConfig::default();
    /// assert!((c.excitation_at(4.0) - 0.1).abs() < 1e-12); // second 3 s step
    /// ```
    pub fn excitation_at(&self, time_s: f64) -> f64 {
        let i = (time_s / self.step_duration_s).floor();
        let i = if i.is_finite() && i > 0.0 {
            i as usize
        } else {
            0
        };
        self.excitation_steps_a[i.min(self.excitation_steps_a.len() - 1)]
    }
}

/// The running bench.
///
/// ```
/// use cutlab::machine::{Machine, OverrideCommand};
/// use cutlab::plant::bench::{BrakeBench, BrakeBenchConfig};
/// let mut bench = BrakeBench::new(BrakeBenchConfig::default()).unwrap();
/// let mut s = bench.step(OverrideCommand::default());
/// for _ in 0..20_000 { s = bench.step(OverrideCommand::default()); }
/// assert!((s.sensors.feed_mm_min - 600.0).abs() < 1.0);
/// assert!(!s.sensors.spindle_running);
/// ```
#[derive(Debug, Clone)]
pub struct BrakeBench {
    config: BrakeBenchConfig,
    sampling: Sampling,
    control: Control,
    drive: FeedDrive,
    brake: MagneticParticleBrake,
    sensor: CurrentSensor,
    friction: WanderingFriction,
}

/// The friction's wander: an Ornstein–Uhlenbeck process sampled every [`FRICTION_UPDATE_S`],
/// plus the warm-up drift.
#[derive(Debug, Clone)]
struct WanderingFriction {
    config: BenchFrictionConfig,
    rng: Rng,
    seed: u64,
    wander_nm: f64,
    next_update_s: f64,
}

impl WanderingFriction {
    fn new(config: BenchFrictionConfig, seed: u64) -> Self {
        let mut rng = Rng::fork(seed, FRICTION_STREAM);
        // Started in its stationary distribution: the bench has been running before.
        let wander_nm = config.scatter_nm * rng.normal();
        Self {
            config,
            rng,
            seed,
            wander_nm,
            next_update_s: FRICTION_UPDATE_S,
        }
    }

    /// The extra friction torque at `time_s`.
    fn torque_nm(&mut self, time_s: f64) -> f64 {
        while time_s >= self.next_update_s {
            let a = math::exp(-FRICTION_UPDATE_S / self.config.correlation_time_s);
            self.wander_nm = a * self.wander_nm
                + self.config.scatter_nm * (1.0 - a * a).sqrt() * self.rng.normal();
            self.next_update_s += FRICTION_UPDATE_S;
        }
        self.wander_nm + self.config.drift_nm_per_min * time_s / S_PER_MIN
    }
}

impl BrakeBench {
    /// A bench at rest.
    pub fn new(config: BrakeBenchConfig) -> Result<Self, PlantError> {
        config.validate()?;
        let sampling = Sampling::new(config.sample_rate_hz);
        let dt_s = sampling.dt_s();
        // One straight "block" long enough for the whole run at the highest override.
        let length_mm = config.feed_mm_min * 2.56 * config.duration_s() / S_PER_MIN + 1.0;
        let block = PlanBlock::straight(length_mm, config.feed_mm_min);
        Ok(Self {
            sampling,
            control: Control::new(&config.cnc, vec![block], dt_s).map_err(|e| e.within("cnc"))?,
            drive: FeedDrive::new(config.feed_drive, dt_s).map_err(|e| e.within("feed_drive"))?,
            brake: MagneticParticleBrake::new(config.brake).map_err(|e| e.within("brake"))?,
            sensor: CurrentSensor::new(config.feed_sensor, dt_s, config.seed, 0)
                .map_err(|e| e.within("feed_sensor"))?,
            friction: WanderingFriction::new(config.friction, config.seed),
            config,
        })
    }

    /// The configuration.
    pub fn config(&self) -> &BrakeBenchConfig {
        &self.config
    }
}

impl PlantModel for BrakeBench {
    fn sampling(&self) -> &Sampling {
        &self.sampling
    }

    fn sampling_mut(&mut self) -> &mut Sampling {
        &mut self.sampling
    }

    fn advance(&mut self, tick: Tick, command: OverrideCommand) -> PlantSample {
        let time_s = tick.time_s;
        let control = self.control.step(command, true);
        let (applied, cnc) = (control.applied, control.cnc);
        let excitation_a = self.config.excitation_at(time_s);
        let brake_nm = self.brake.torque_nm(excitation_a);
        let fd = &self.config.feed_drive;
        let sigma = (cnc.feed_mm_min / fd.friction_band_mm_min).clamp(-1.0, 1.0);
        // The wander and drift act like the brake, against the motion; the "load" the bench
        // reports stays the brake's alone, as a bench's operator knows only the excitation.
        let friction_nm = self.friction.torque_nm(time_s);
        let out = self
            .drive
            .step(cnc.feed_mm_min, 0.0, (brake_nm + friction_nm) * sigma);
        let read = self.sensor.read(out.phase_currents_a);
        let equivalent_force_n = brake_nm / fd.torque_per_force_nm_per_n();
        let rms = three_phase_rms_a(out.phase_currents_a);
        let sensors = SensorSample {
            time_s,
            feed_phase_currents_a: read,
            spindle_phase_currents_a: [0.0; 3],
            spindle_fv_voltage_v: 0.0,
            spindle_speed_rpm: 0.0,
            spindle_command_rpm: 0.0,
            programmed_feed_mm_min: self.config.feed_mm_min,
            feed_mm_min: cnc.feed_mm_min,
            applied_override_pct: applied.pct,
            spindle_running: false,
            time_since_spindle_start_s: 0.0,
        };
        // No cut: depth and width of cut are 0, so the closed loop's metrics count no row as
        // cutting.
        let truth = PlantTruth {
            force_x_n: -equivalent_force_n,
            force_resultant_n: equivalent_force_n,
            feed_force_n: equivalent_force_n,
            path_position_mm: cnc.position_mm,
            tool_x_mm: cnc.position_mm,
            feed_current_rms_a: rms,
            ..PlantTruth::default()
        };
        let signals = PlantSignals {
            entry_deg: f64::NAN,
            exit_deg: f64::NAN,
            power_law_force_n: f64::NAN,
            axis_x: AxisSignals {
                velocity_mm_min: cnc.feed_mm_min,
                load_force_n: equivalent_force_n,
                torque_nm: out.torque_nm,
                iq_a: out.iq_a,
                phase_currents_a: out.phase_currents_a,
            },
            feed_currents_read_a: read,
            brake_excitation_a: excitation_a,
            brake_torque_nm: brake_nm,
            ..PlantSignals::from_control(time_s, truth, &control)
        };
        PlantSample {
            sensors,
            signals,
            finished: time_s >= self.config.duration_s() - 0.5 * tick.dt_s,
        }
    }

    fn restart(&mut self) -> PlantSignals {
        self.control.reset();
        self.drive.reset();
        self.brake.reset();
        self.sensor.reset(self.config.seed, 0);
        self.friction = WanderingFriction::new(self.config.friction, self.friction.seed);
        PlantSignals::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brake_torque_is_linear_between_the_hysteresis_branches() {
        let mut b = MagneticParticleBrake::new(BrakeConfig::default()).unwrap();
        let rising: Vec<f64> = (0..=10).map(|k| b.torque_nm(0.5 * f64::from(k))).collect();
        let slopes: Vec<f64> = rising.windows(2).skip(1).map(|w| w[1] - w[0]).collect();
        assert!(slopes.iter().all(|s| (s - 1.0).abs() < 1e-12), "{slopes:?}");
        let falling = b.torque_nm(2.5);
        assert!(falling > rising[5]);
    }

    #[test]
    fn schedule_steps_up_and_back_down() {
        let c = BrakeBenchConfig::default();
        assert_eq!(c.excitation_at(0.0), 0.0);
        assert!((c.excitation_at(31.0) - 1.0).abs() < 1e-12);
        assert!((c.excitation_at(62.9) - 0.0).abs() < 1e-12);
        assert!((c.duration_s() - 63.0).abs() < 1e-12);
    }

    #[test]
    fn an_empty_schedule_is_refused() {
        let c = BrakeBenchConfig {
            excitation_steps_a: vec![],
            ..BrakeBenchConfig::default()
        };
        assert_eq!(BrakeBench::new(c).unwrap_err().field, "excitation_steps_a");
    }
}
