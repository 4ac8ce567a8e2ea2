//! The simulated machine: a CNC mill whose motor currents look like the ones in the papers, built
//! from their equations, for the lab to control when there is no machine.
//!
//! ## Data flow of one sample
//!
//! ```text
//! OverrideCommand ─► cnc        override mode (16-position dial on X20.7/X20.4/X20.3/X20.2,
//!                               0–255 % in 1 % steps, or continuous), PMC scan, feed hold,
//!                               programmed feed × override, acceleration limits, corner stops,
//!                               interpolation period, position loop
//!                 ─► scenario   where the tool is: path (lines, arcs), axial depth and radial
//!                               width profiles, material regions, air cuts
//!                 ─► mechanics  feed per tooth, tooth angles at spindle speed, mechanistic forces
//!                               F_x, F_y, F_z, torque, power (paper 003 eq 1–6, Altintas ch. 2)
//!                 ─► feed_drive     axis load → motor torque (paper 000 eq 1–3) → i_q with the
//!                                   servo's ~40 Hz lag → i_u, i_v, i_w (eq 4) at the axis's
//!                                   electrical angle
//!                 ─► spindle_drive  torque → RMS current = idle(n) + S(n, gear)·T with < 5 Hz lag,
//!                                   gear change at 900 rpm, start current, F/V voltage (paper 003)
//!                 ─► sensors    Hall sensor (6 A → 25 mA into 500 Ω, paper 000), ADC
//!                 ─► SensorSample + PlantTruth (crate::machine), inside PlantSignals
//! ```
//!
//! Every plant implements one trait, [`PlantModel`]: advance the physics over one sample period
//! ([`Tick`]) and restart. The blanket implementations here make each a
//! [`crate::machine::Machine`] and a [`Plant`], so the sample clock, the latest sample (repeated
//! once the run has ended) and the reset are written once for all of them. A sample's
//! [`PlantSignals`] holds its [`crate::machine::PlantTruth`], built once.
//!
//! The reduced models stand in for the whole chain when a paper's own plant is wanted:
//! [`second_order::SecondOrderMachine`] (paper 001's m·F̈ + (mc+d)·Ḟ + dc·F = k·f_r) and
//! [`bond_graph::BondGraphMachine`] (paper 002's eq 5, on a machining centre cutting a stated
//! cut; Table 1 as printed is [`bond_graph::BondGraphParams::default`]). [`bench::BrakeBench`] is
//! paper 000's magnetic-particle brake bench. [`power_law`] is paper 004's empirical model and
//! [`sensorless`] the network a preset learns in its form: a sensorless estimate, not a plant.
//!
//! ## Modules
//!
//! | module | what it holds |
//! |---|---|
//! | [`materials`] | work materials and their mechanistic cutting coefficients, with sources |
//! | [`mechanics`] | cutter, immersion, instantaneous and mean milling forces, paper 003's Martelotti relations |
//! | [`power_law`] | paper 004's power-law force model with its published weights |
//! | [`sensorless`] | paper 004's sensorless estimate: the force network learned on the preset's trial cuts, shipped per preset |
//! | [`deflection`] | the cutting-force-induced error: tool and spindle deflecting under the normal force (paper 004's CFIE) |
//! | [`feed_drive`] | ball screw, guides, table and PMSM of one feed axis (paper 000) |
//! | [`spindle_drive`] | induction spindle motor, gearbox and F/V converter (paper 003) |
//! | [`sensors`] | Hall current sensors and the ADC |
//! | [`cnc`] | the FANUC-style control: override modes, dial table, feed planning |
//! | [`scenario`] | tool paths, depth/width profiles, material regions |
//! | [`simulator`] | the full simulated mill, a [`PlantModel`] |
//! | [`bench`](mod@bench) | paper 000's brake test bench, a `PlantModel` |
//! | [`second_order`] | paper 001's second-order force process, a `PlantModel` |
//! | [`bond_graph`] | paper 002's bond-graph spindle + x-axis model, a `PlantModel` |
//! | [`presets`] | the papers' experiments as named, seeded machines: [`Preset`], one [`presets::Definition`] each, and the checked [`presets::PlantEdits`] |
//! | [`recording`] | open-loop runs summarised per block, the brake bench's load-step analysis and its phase currents, each a [`crate::work::Work`] |
//! | [`signals`] | every internal signal of a sample, with units, for plots and CSV |
//! | [`dynamics`] | exactly discretised first- and second-order lags |
//! | `linalg` | small dense matrices on the stack: the matrix exponential that discretises the linear plants |
//! | [`dynamometer`] | a dynamometer under the part: the cutting force as a force sensor reads it |
//!
//! ## Contracts
//!
//! Every configuration is a plain struct with documented defaults; the constructors of the
//! running objects validate it and return [`PlantError`] naming the offending field. Once built,
//! stepping cannot fail and does not allocate. A seed fixes every noise source (each one draws
//! from its own [`crate::rng::Rng::fork`] stream), and all transcendental functions come from
//! [`crate::math`], so a seed gives the same bits natively and in wasm.
//!
//! Non-finite values cannot enter through a validated configuration. The only run-time input is
//! the [`crate::machine::OverrideCommand`]: a NaN override keeps the override the machine applied
//! last, ±∞ clamps to the machine's limits.

pub mod bench;
pub mod bond_graph;
pub mod cnc;
pub mod deflection;
pub mod dynamics;
pub mod dynamometer;
pub mod feed_drive;
pub(crate) mod linalg;
pub mod materials;
pub mod mechanics;
pub mod power_law;
pub mod presets;
pub mod recording;
pub mod scenario;
pub mod second_order;
pub mod sensorless;
pub mod sensors;
pub mod signals;
pub mod simulator;
pub mod spindle_drive;

use std::fmt;

use crate::machine::{
    BlockStep, Machine, MachineStep, OverrideCommand, SensorSample, SensorlessEstimate,
};

pub use presets::{Preset, PresetMachine};
pub use signals::PlantSignals;
pub use simulator::{SimConfig, Simulator};

/// A simulated machine: a [`Machine`] that also shows its insides and can start over.
///
/// Object-safe, so the lab can hold any plant as `Box<dyn Plant>`. Every [`PlantModel`] is one.
pub trait Plant: Machine {
    /// Every internal signal of the last sample.
    fn signals(&self) -> &PlantSignals;

    /// Back to the state right after construction (same seed, same noise).
    fn reset(&mut self);
}

/// The physics of one simulated plant, a sample period at a time.
///
/// A type that implements it is a [`Machine`] and a [`Plant`] (the blanket implementations
/// below), so what every plant shares is written once: the sample clock, the latest sample that
/// [`Machine::step`] returns and keeps returning once the run has ended, and a reset that
/// replays the same run.
pub trait PlantModel {
    /// The clock and the latest sample, kept for the shared implementations.
    fn sampling(&self) -> &Sampling;

    /// The same, to update.
    fn sampling_mut(&mut self) -> &mut Sampling;

    /// Advances the physics over the sample period that ends at `tick` under `command`. Called
    /// only until a sample says the run has finished. It must not read the latest sample back
    /// ([`Sampling::latest`]): [`Machine::step_block`] keeps only a block's last one.
    fn advance(&mut self, tick: Tick, command: OverrideCommand) -> PlantSample;

    /// [`PlantModel::advance`] for a sample whose internal signals nobody will read unless it
    /// ends the run (a sample inside a block, [`advance_sample_by_sample`]): the sensors, the
    /// truth and `finished` are the same; the other signals may be left out, which spares work
    /// a plant does only to show them.
    #[inline(always)]
    fn advance_unkept(&mut self, tick: Tick, command: OverrideCommand) -> PlantSample {
        self.advance(tick, command)
    }

    /// What [`Machine::step_block`] does for this plant: [`Machine::step`] sample after sample,
    /// keeping only the block's last sample (or the one that finished the run) as the latest.
    /// The default advances sample after sample ([`advance_sample_by_sample`]); a plant that
    /// works out part of a block's samples together (the simulator: the phase currents and
    /// sensor readings, which feed nothing back) overrides it, with the same bits.
    #[inline(always)]
    fn advance_block(&mut self, command: OverrideCommand, out: &mut [BlockStep]) -> usize
    where
        Self: Sized,
    {
        advance_sample_by_sample(self, command, out)
    }

    /// Back to the state right after construction; returns the signals to show before the
    /// first sample.
    fn restart(&mut self) -> PlantSignals;

    /// Paper 004's sensorless force estimate at the latest sample, for a plant that knows the
    /// programmed cutting conditions (see [`Machine::sensorless_force`]).
    fn power_law_force(&self) -> Option<SensorlessEstimate> {
        None
    }
}

/// The sample period a [`PlantModel`] advances over.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tick {
    /// 1 for the first sample after the start (or a reset), 2 for the next, …
    pub number: u64,
    /// Time at the end of the period since the start: `number · dt_s`.
    pub time_s: f64,
    /// Length of the period, 1/sample rate.
    pub dt_s: f64,
}

/// One sample of a simulated plant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PlantSample {
    /// What its sensors read.
    pub sensors: SensorSample,
    /// Everything inside, the ground truth included.
    pub signals: PlantSignals,
    /// The run ended with this sample.
    pub finished: bool,
}

/// What every simulated plant keeps besides its physics: the sample clock and the latest sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sampling {
    sample_rate_hz: f64,
    dt_s: f64,
    samples: u64,
    latest: PlantSample,
}

impl Sampling {
    /// A clock at `sample_rate_hz` (validated by the plant's configuration) before its first
    /// sample.
    pub fn new(sample_rate_hz: f64) -> Self {
        Self {
            sample_rate_hz,
            dt_s: 1.0 / sample_rate_hz,
            samples: 0,
            latest: PlantSample::default(),
        }
    }

    /// The sample period.
    pub fn dt_s(&self) -> f64 {
        self.dt_s
    }

    /// The latest sample.
    pub fn latest(&self) -> &PlantSample {
        &self.latest
    }

    #[inline(always)]
    fn tick(&mut self) -> Tick {
        self.samples += 1;
        Tick {
            number: self.samples,
            time_s: self.samples as f64 * self.dt_s,
            dt_s: self.dt_s,
        }
    }

    #[inline(always)]
    fn machine_step(&self) -> MachineStep {
        MachineStep {
            sensors: self.latest.sensors,
            truth: Some(self.latest.signals.truth),
        }
    }
}

impl<P: PlantModel> Machine for P {
    fn sample_rate_hz(&self) -> f64 {
        self.sampling().sample_rate_hz
    }

    #[inline(always)]
    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        if !self.sampling().latest.finished {
            let tick = self.sampling_mut().tick();
            let sample = self.advance(tick, command);
            self.sampling_mut().latest = sample;
        }
        self.sampling().machine_step()
    }

    fn finished(&self) -> bool {
        self.sampling().latest.finished
    }

    /// [`PlantModel::advance_block`].
    #[inline(always)]
    fn step_block(&mut self, command: OverrideCommand, out: &mut [BlockStep]) -> usize {
        self.advance_block(command, out)
    }

    fn sensorless_force(&self) -> Option<SensorlessEstimate> {
        self.power_law_force()
    }
}

/// [`Machine::step`] sample after sample, keeping only the block's last sample as the latest:
/// nothing can look at the latest sample while the block runs (plants do not read it back, see
/// [`PlantModel::advance`]), so the others are only written to `out`, which saves storing every
/// internal signal of every sample.
#[inline(always)]
pub fn advance_sample_by_sample<P: PlantModel>(
    plant: &mut P,
    command: OverrideCommand,
    out: &mut [BlockStep],
) -> usize {
    let n = out.len();
    for (i, slot) in out.iter_mut().enumerate() {
        if plant.sampling().latest.finished {
            slot.step = plant.sampling().machine_step();
            slot.dynamometer = None;
            return i + 1;
        }
        let tick = plant.sampling_mut().tick();
        let sample = if i + 1 == n {
            plant.advance(tick, command)
        } else {
            plant.advance_unkept(tick, command)
        };
        slot.step = MachineStep {
            sensors: sample.sensors,
            truth: Some(sample.signals.truth),
        };
        slot.dynamometer = None;
        if sample.finished || i + 1 == n {
            plant.sampling_mut().latest = sample;
            return i + 1;
        }
    }
    n
}

impl<P: PlantModel> Plant for P {
    fn signals(&self) -> &PlantSignals {
        &self.sampling().latest.signals
    }

    fn reset(&mut self) {
        let signals = self.restart();
        let sampling = self.sampling_mut();
        sampling.samples = 0;
        sampling.latest = PlantSample {
            signals,
            ..PlantSample::default()
        };
    }
}

/// Runs `plant` with a fixed `command` until it finishes or `max_samples` have passed, keeping
/// every `every`-th sample's signals (and the last one). A convenience for tests, the CLI and
/// open-loop plots; the closed loop steps the plant itself.
///
/// ```
/// use cutlab::machine::OverrideCommand;
/// use cutlab::plant::{record, Preset};
/// let mut m = Preset::WangBrakeBench.machine(3).unwrap();
/// let rows = record(&mut m, OverrideCommand::default(), 1000, 20_000);
/// assert_eq!(rows.len(), 20);
/// assert!((rows[19].time_s - 2.0).abs() < 1e-9);
/// ```
pub fn record(
    plant: &mut dyn Plant,
    command: OverrideCommand,
    every: usize,
    max_samples: usize,
) -> Vec<PlantSignals> {
    let every = every.max(1);
    let mut rows = Vec::with_capacity(max_samples / every + 1);
    let mut n = 0;
    while n < max_samples && !plant.finished() {
        plant.step(command);
        n += 1;
        if n % every == 0 {
            rows.push(*plant.signals());
        }
    }
    if n % every != 0 {
        rows.push(*plant.signals());
    }
    rows
}

/// A configuration value the plant cannot be built from.
///
/// ```
/// use cutlab::plant::mechanics::Cutter;
/// let e = Cutter::new(-10.0, 2, 30.0).unwrap_err();
/// assert_eq!(e.field, "diameter_mm");
/// assert_eq!(e.to_string(), "diameter_mm: must be a finite number > 0, got -10");
/// ```
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PlantError {
    /// The field, with its struct path where it helps (`feed_drive.screw_pitch_mm`).
    pub field: String,
    /// What is wrong with it.
    pub message: String,
}

impl fmt::Display for PlantError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}: {}", self.field, self.message)
    }
}

impl std::error::Error for PlantError {}

impl PlantError {
    /// An error about `field`.
    pub fn new(field: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            field: field.into(),
            message: message.into(),
        }
    }

    /// The same error with `prefix.` before the field, for errors found inside a nested config.
    pub fn within(self, prefix: &str) -> Self {
        Self {
            field: format!("{prefix}.{}", self.field),
            message: self.message,
        }
    }
}

/// `value` if it is finite and > 0.
pub(crate) fn positive(field: &str, value: f64) -> Result<f64, PlantError> {
    if value.is_finite() && value > 0.0 {
        Ok(value)
    } else {
        Err(PlantError::new(
            field,
            format!("must be a finite number > 0, got {value}"),
        ))
    }
}

/// `value` if it is finite and ≥ 0.
pub(crate) fn non_negative(field: &str, value: f64) -> Result<f64, PlantError> {
    if value.is_finite() && value >= 0.0 {
        Ok(value)
    } else {
        Err(PlantError::new(
            field,
            format!("must be a finite number ≥ 0, got {value}"),
        ))
    }
}

/// `value` if it is finite.
pub(crate) fn finite(field: &str, value: f64) -> Result<f64, PlantError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(PlantError::new(
            field,
            format!("must be a finite number, got {value}"),
        ))
    }
}

/// `value` if it lies in `[min, max]`.
pub(crate) fn in_range(field: &str, value: f64, min: f64, max: f64) -> Result<f64, PlantError> {
    if value.is_finite() && value >= min && value <= max {
        Ok(value)
    } else {
        Err(PlantError::new(
            field,
            format!("must lie in [{min}, {max}], got {value}"),
        ))
    }
}

/// Seconds per minute, for mm/min ↔ mm/s.
pub(crate) const S_PER_MIN: f64 = 60.0;

/// Revolutions per minute from radians per second.
#[inline]
pub(crate) fn rpm_from_rad_s(rad_s: f64) -> f64 {
    rad_s * S_PER_MIN / std::f64::consts::TAU
}

/// Radians per second from revolutions per minute.
#[inline]
pub(crate) fn rad_s_from_rpm(rpm: f64) -> f64 {
    rpm * std::f64::consts::TAU / S_PER_MIN
}
