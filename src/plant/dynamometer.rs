//! A dynamometer under the part: the cutting force as a force sensor reads it.
//!
//! Paper 001 (Maneerat et al.) closes its loop on a measured force, not on a motor current: its
//! PC reads the force through a multi-channel acquisition card. A piezoelectric table
//! dynamometer is a stiff, lightly damped sensor whose usable bandwidth is set by its mounted
//! natural frequency (a few hundred hertz to a few kilohertz once the part is clamped on it), and
//! its charge amplifier adds noise and a slow drift. cutlab models it as what the controller can
//! see of it:
//!
//! ```text
//! F_read = lowpass_bandwidth(F_true) + n,   n ~ N(0, σ²) white, per sample and axis
//! ```
//!
//! [`WithDynamometer`] mounts one on any simulated [`Machine`]: it reads the machine's true
//! force each sample and answers [`Machine::dynamometer_force_n`]. Defaults (chosen; the paper
//! gives no sensor data): 500 Hz bandwidth, σ = 2 N.

use serde::{Deserialize, Serialize};

use super::dynamics::FirstOrderLag;
use super::{positive, PlantError};
use crate::machine::{
    BlockStep, DynamometerReading, Machine, MachineStep, OverrideCommand, SensorlessEstimate,
};
use crate::rng::Rng;

/// The sensor's settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct DynamometerConfig {
    /// Corner frequency of the sensor and its amplifier. Default 500 Hz.
    pub bandwidth_hz: f64,
    /// Standard deviation of the white noise on each axis. Default 2 N.
    pub noise_n: f64,
}

impl Default for DynamometerConfig {
    fn default() -> Self {
        Self {
            bandwidth_hz: 500.0,
            noise_n: 2.0,
        }
    }
}

impl DynamometerConfig {
    /// Checks every field.
    ///
    /// ```
    /// use cutlab::plant::dynamometer::DynamometerConfig;
    /// assert!(DynamometerConfig::default().validate().is_ok());
    /// let bad = DynamometerConfig { bandwidth_hz: 0.0, ..DynamometerConfig::default() };
    /// assert_eq!(bad.validate().unwrap_err().field, "bandwidth_hz");
    /// ```
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("bandwidth_hz", self.bandwidth_hz)?;
        if !(self.noise_n.is_finite() && self.noise_n >= 0.0) {
            return Err(PlantError::new(
                "noise_n",
                format!("must be a finite number ≥ 0, got {}", self.noise_n),
            ));
        }
        Ok(())
    }
}

/// The seed stream of the dynamometer's noise, apart from every other sensor's.
const NOISE_STREAM: u64 = 0xD1A0;

/// `machine` with a dynamometer under its part.
///
/// ```
/// use cutlab::machine::{Machine, OverrideCommand};
/// use cutlab::plant::dynamometer::{DynamometerConfig, WithDynamometer};
/// use cutlab::plant::Preset;
/// let quiet = DynamometerConfig { noise_n: 0.0, ..DynamometerConfig::default() };
/// let mut m = WithDynamometer::new(Box::new(Preset::ManeeratDoc2.machine(1).unwrap()), quiet, 1)
///     .unwrap();
/// let mut step = m.step(OverrideCommand::default());
/// while !m.finished() && step.truth.unwrap().force_resultant_n < 100.0 {
///     step = m.step(OverrideCommand::default());
/// }
/// for _ in 0..2000 { step = m.step(OverrideCommand::default()); } // 0.2 s into the cut
/// let read = m.dynamometer_force_n().unwrap();
/// let truth = step.truth.unwrap();
/// // The sensor lags the tooth-passing ripple, so compare magnitudes loosely.
/// assert!((read.force_x_n.hypot(read.force_y_n) / truth.force_resultant_n - 1.0).abs() < 0.5);
/// ```
pub struct WithDynamometer {
    machine: Box<dyn Machine>,
    lag_x: FirstOrderLag,
    lag_y: FirstOrderLag,
    lag_feed: FirstOrderLag,
    noise_n: f64,
    rng: Rng,
    reading: Option<DynamometerReading>,
}

impl WithDynamometer {
    /// Mounts a dynamometer configured by `config` (noise seeded by `seed`) under `machine`.
    pub fn new(
        machine: Box<dyn Machine>,
        config: DynamometerConfig,
        seed: u64,
    ) -> Result<Self, PlantError> {
        config.validate()?;
        let dt_s = 1.0 / machine.sample_rate_hz();
        let lag = FirstOrderLag::new(config.bandwidth_hz, dt_s);
        Ok(Self {
            machine,
            lag_x: lag,
            lag_y: lag,
            lag_feed: lag,
            noise_n: config.noise_n,
            rng: Rng::fork(seed, NOISE_STREAM),
            reading: None,
        })
    }
}

impl WithDynamometer {
    /// The sensor's reading of the force in `step`.
    fn read(&mut self, step: &MachineStep) {
        self.reading = step.truth.map(|truth| {
            let noise = self.noise_n;
            DynamometerReading {
                force_x_n: self.lag_x.step(truth.force_x_n) + noise * self.rng.normal(),
                force_y_n: self.lag_y.step(truth.force_y_n) + noise * self.rng.normal(),
                feed_force_n: self.lag_feed.step(truth.feed_force_n) + noise * self.rng.normal(),
            }
        });
    }
}

impl Machine for WithDynamometer {
    fn sample_rate_hz(&self) -> f64 {
        self.machine.sample_rate_hz()
    }

    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        let step = self.machine.step(command);
        self.read(&step);
        step
    }

    fn step_block(&mut self, command: OverrideCommand, out: &mut [BlockStep]) -> usize {
        // The machine's block, then the sensor's reading of each sample in turn.
        let n = self.machine.step_block(command, out);
        for slot in &mut out[..n] {
            self.read(&slot.step);
            slot.dynamometer = self.reading;
        }
        n
    }

    fn finished(&self) -> bool {
        self.machine.finished()
    }

    fn sensorless_force(&self) -> Option<SensorlessEstimate> {
        self.machine.sensorless_force()
    }

    fn dynamometer_force_n(&self) -> Option<DynamometerReading> {
        self.reading
    }
}
