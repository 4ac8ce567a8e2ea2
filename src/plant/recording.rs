//! Open-loop recordings of a plant, as [`Work`] done in pieces so the browser can run them across
//! frames and the command line and the tests at once.
//!
//! [`OpenLoopRun`] runs a preset's machine at a fixed override and summarises every signal a
//! person wants to see per block of samples (means, and minimum and maximum where a signal swings
//! within the block), so an hour at 10 kHz still fits in a browser and every peak stays visible.
//! On paper 000's brake bench it also keeps the phase current of each load step at full rate and
//! summarises each step once it has ended: its brake torque, its mean RMS current and the
//! spectrum of its phase current, for paper 000's spectra and RMS-versus-load line (Fig. 9 and
//! Fig. 11).
//!
//! [`BenchRecording`] keeps a stretch of the bench's three feed phase currents at full rate, with
//! the spectrum of the raw i_u, for the signal-chain page to filter.
//!
//! Both give the same output whatever budgets they are advanced by (a test checks it): a budget
//! only says where the work may pause. Each takes the plant's samples as its units.

use serde::{Deserialize, Serialize};
use std::fmt;

use super::cnc::MAX_OVERRIDE_PCT;
use super::signals::PlantSignals;
use super::{Plant, PlantError, Preset, PresetMachine};
use crate::input::table::{Kind, Row, Shown, Table};
use crate::machine::{Machine, OverrideCommand};
use crate::math::least_squares::{fit, FitError};
use crate::signal::spectrum::{amplitude_spectrum, AmplitudeSpectrum, SpectrumError, Window};
use crate::signal::stats::MinMeanMax;
use crate::work::{Progress, Work};

/// One block of samples, summarised.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct BlockRow {
    /// Time of the block's last sample.
    pub time_s: f64,
    /// Mean cutting force, x.
    pub force_x_n: f64,
    /// Mean cutting force, y.
    pub force_y_n: f64,
    /// Mean cutting force, z.
    pub force_z_n: f64,
    /// Smallest instantaneous resultant in the block.
    pub resultant_min_n: f64,
    /// Largest instantaneous resultant in the block.
    pub resultant_max_n: f64,
    /// Mean spindle cutting torque.
    pub spindle_torque_nm: f64,
    /// Mean cutting power.
    pub cutting_power_w: f64,
    /// Smallest feed phase current i_u as read.
    pub feed_iu_min_a: f64,
    /// Largest feed phase current i_u as read.
    pub feed_iu_max_a: f64,
    /// Smallest spindle phase current i_u as read.
    pub spindle_iu_min_a: f64,
    /// Largest spindle phase current i_u as read.
    pub spindle_iu_max_a: f64,
    /// Mean true RMS current of the feed axis.
    pub feed_rms_a: f64,
    /// Mean true RMS spindle current.
    pub spindle_rms_a: f64,
    /// Mean axial depth of cut.
    pub depth_mm: f64,
    /// Mean path feed.
    pub feed_mm_min: f64,
    /// Mean spindle speed.
    pub spindle_rpm: f64,
    /// Mean brake torque (brake bench only).
    pub brake_torque_nm: f64,
}

/// The feed phase current of one brake-bench load step, at full rate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadStep {
    /// Start of the step.
    pub start_s: f64,
    /// Brake torque during the step.
    pub brake_torque_nm: f64,
    /// Phase current i_u as read, over the settled part of the step.
    pub feed_iu_a: Vec<f64>,
    /// Mean true three-phase RMS current over the same part.
    pub feed_rms_a: f64,
}

/// One brake-bench load step, summarised once it has ended.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepSummary {
    /// Brake torque during the step.
    pub brake_torque_nm: f64,
    /// Loading: the torque is at least the previous step's (the first step is loading).
    /// Unloading steps draw more current at the same excitation (the brake's hysteresis).
    pub loading: bool,
    /// Mean true RMS feed current over its settled part.
    pub feed_rms_a: f64,
    /// Amplitude spectrum of the phase current i_u over the settled part, up to
    /// [`STEP_SPECTRUM_MAX_HZ`]: (Hz, A).
    pub spectrum: Vec<(f64, f64)>,
}

/// Spectra of the load steps are kept up to this frequency: the bench's 4 Hz electrical
/// frequency and its first harmonics (paper 000 Fig. 9).
pub const STEP_SPECTRUM_MAX_HZ: f64 = 20.0;

/// A load step needs at least this many settled samples (0.1 s at 10 kHz) to be summarised;
/// shorter "steps" are the brake's torque following the feed as it starts or stops.
pub const MIN_STEP_SAMPLES: usize = 1000;

/// The part of each load step left out of its summary while the drive settles.
pub const STEP_SETTLE_S: f64 = 1.0;

/// A finished open-loop recording.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct OpenLoopRecording {
    /// The preset recorded.
    pub preset: Preset,
    /// One row per block of samples.
    pub rows: Vec<BlockRow>,
    /// The brake bench's load steps (empty for other plants).
    pub load_steps: Vec<StepSummary>,
}

/// Paper 000's line through the load steps (eq 9, Fig. 11): RMS current = idle + slope × torque.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LoadLine {
    /// The current at no load, which is not zero (friction, preload).
    pub idle_current_a: f64,
    /// RMS current per newton-metre of brake torque.
    pub slope_a_per_nm: f64,
    /// How well the line fits, 1 for exactly.
    pub r_squared: f64,
    /// Load steps fitted, loading and unloading.
    pub steps: usize,
}

impl OpenLoopRecording {
    /// The least-squares line of RMS current against brake torque over every load step.
    ///
    /// ```
    /// use cutlab::plant::recording::OpenLoopRun;
    /// use cutlab::plant::Preset;
    /// use cutlab::work::Work;
    /// let rec = OpenLoopRun::new(Preset::WangBrakeBench, 1, 100.0, 50, 12.0)
    ///     .unwrap()
    ///     .run_to_end()
    ///     .unwrap();
    /// let line = rec.load_line().unwrap();
    /// assert!((line.slope_a_per_nm - 0.59).abs() < 0.01); // √(1 + h₅² + h₇²)/(√2·K_t)
    /// assert!(line.idle_current_a > 0.5 && line.r_squared > 0.99);
    /// ```
    pub fn load_line(&self) -> Result<LoadLine, FitError> {
        let torque: Vec<f64> = self.load_steps.iter().map(|s| s.brake_torque_nm).collect();
        let rms: Vec<f64> = self.load_steps.iter().map(|s| s.feed_rms_a).collect();
        let ones = vec![1.0; torque.len()];
        let f = fit(&[("idle current", &ones), ("torque", &torque)], &rms)?;
        Ok(LoadLine {
            idle_current_a: f.coefficients[0],
            slope_a_per_nm: f.coefficients[1],
            r_squared: f.r_squared,
            steps: f.samples,
        })
    }
}

/// Why a recording could not be made or handed over.
#[derive(Debug, Clone, PartialEq)]
pub enum RecordingError {
    /// The preset's machine could not be built.
    Plant(PlantError),
    /// The recording is too short for a spectrum.
    Spectrum(SpectrumError),
    /// [`Work::finish`] before the recording was done.
    NotDone,
    /// [`Work::finish`] a second time.
    AlreadyTaken,
}

impl fmt::Display for RecordingError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            RecordingError::Plant(e) => write!(f, "the machine: {e}"),
            RecordingError::Spectrum(e) => write!(f, "the spectrum of the recording: {e}"),
            RecordingError::NotDone => write!(f, "the recording is not done yet"),
            RecordingError::AlreadyTaken => write!(f, "the recording was already handed over"),
        }
    }
}

impl std::error::Error for RecordingError {}

impl From<PlantError> for RecordingError {
    fn from(e: PlantError) -> Self {
        RecordingError::Plant(e)
    }
}

/// The block being summarised: one accumulator per plotted signal.
#[derive(Debug, Clone, Copy, Default)]
struct Block {
    end_time_s: f64,
    force_x_n: MinMeanMax,
    force_y_n: MinMeanMax,
    force_z_n: MinMeanMax,
    resultant_n: MinMeanMax,
    spindle_torque_nm: MinMeanMax,
    cutting_power_w: MinMeanMax,
    feed_iu_a: MinMeanMax,
    spindle_iu_a: MinMeanMax,
    feed_rms_a: MinMeanMax,
    spindle_rms_a: MinMeanMax,
    depth_mm: MinMeanMax,
    feed_mm_min: MinMeanMax,
    spindle_rpm: MinMeanMax,
    brake_torque_nm: MinMeanMax,
}

impl Block {
    fn push(&mut self, s: &PlantSignals) {
        let t = &s.truth;
        self.end_time_s = s.time_s;
        self.force_x_n.push(t.force_x_n);
        self.force_y_n.push(t.force_y_n);
        self.force_z_n.push(t.force_z_n);
        self.resultant_n.push(t.force_resultant_n);
        self.spindle_torque_nm.push(t.spindle_torque_nm);
        self.cutting_power_w.push(t.cutting_power_w);
        self.feed_iu_a.push(s.feed_currents_read_a[0]);
        self.spindle_iu_a.push(s.spindle_currents_read_a[0]);
        self.feed_rms_a.push(t.feed_current_rms_a);
        self.spindle_rms_a.push(t.spindle_current_rms_a);
        // A plant without a depth (the bond graph) plots as no depth rather than a gap.
        self.depth_mm.push(if t.depth_mm.is_finite() {
            t.depth_mm
        } else {
            0.0
        });
        self.feed_mm_min.push(s.feed_mm_min);
        self.spindle_rpm.push(s.spindle_speed_rpm);
        self.brake_torque_nm.push(s.brake_torque_nm);
    }

    fn samples(&self) -> usize {
        self.force_x_n.count()
    }

    fn row(&self) -> BlockRow {
        BlockRow {
            time_s: self.end_time_s,
            force_x_n: self.force_x_n.mean(),
            force_y_n: self.force_y_n.mean(),
            force_z_n: self.force_z_n.mean(),
            resultant_min_n: self.resultant_n.min(),
            resultant_max_n: self.resultant_n.max(),
            spindle_torque_nm: self.spindle_torque_nm.mean(),
            cutting_power_w: self.cutting_power_w.mean(),
            feed_iu_min_a: self.feed_iu_a.min(),
            feed_iu_max_a: self.feed_iu_a.max(),
            spindle_iu_min_a: self.spindle_iu_a.min(),
            spindle_iu_max_a: self.spindle_iu_a.max(),
            feed_rms_a: self.feed_rms_a.mean(),
            spindle_rms_a: self.spindle_rms_a.mean(),
            depth_mm: self.depth_mm.mean(),
            feed_mm_min: self.feed_mm_min.mean(),
            spindle_rpm: self.spindle_rpm.mean(),
            brake_torque_nm: self.brake_torque_nm.mean(),
        }
    }
}

/// The open-loop run's one setting as a table: the override held for the whole run, which the
/// Machine page's field and `cutlab scenarios --run --override` parse alike.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum OpenLoopSetting {
    /// The feed override held for the whole run.
    Override,
}

impl Table for OpenLoopSetting {
    const ROWS: &'static [Self] = &[OpenLoopSetting::Override];

    fn row(self) -> Row {
        Row {
            key: "override",
            cli_option: "override",
            label: "Feed override",
            unit: "%",
            help: "override held for the whole run (a dial's machine applies its nearest grade)",
            kind: Kind::Number {
                min: 0.0,
                max: MAX_OVERRIDE_PCT,
            },
            default: Shown::Number(100.0),
            noun: "",
        }
    }
}

/// A preset's machine run at a fixed override, recorded block by block.
///
/// ```
/// use cutlab::plant::recording::OpenLoopRun;
/// use cutlab::plant::Preset;
/// use cutlab::work::Work;
/// let run = OpenLoopRun::new(Preset::WangBrakeBench, 1, 100.0, 50, 8.0).unwrap();
/// let recording = run.run_to_end().unwrap();
/// assert_eq!(recording.rows.len(), 1600); // 8 s at 10 kHz, 50 samples a row
/// // The steps at 0 and 0.1 A ended; the one at 0.2 A was cut at 8 s, 1 s after settling.
/// assert_eq!(recording.load_steps.len(), 3);
/// assert!((recording.load_steps[1].brake_torque_nm - 0.14).abs() < 1e-9); // 2 N·m/A × (0.1 − 0.03) A
/// ```
pub struct OpenLoopRun {
    preset: Preset,
    machine: PresetMachine,
    command: OverrideCommand,
    block: usize,
    max_samples: usize,
    samples: usize,
    block_sums: Block,
    rows: Vec<BlockRow>,
    steps: Vec<LoadStep>,
    /// Summaries of the load steps that have ended. Each is made as soon as the next step
    /// begins, so the spectra are spread over the run instead of all made at its end.
    step_summaries: Vec<StepSummary>,
    /// How many of `steps` have been summarised (or skipped as too short).
    steps_summarised: usize,
    taken: bool,
}

impl OpenLoopRun {
    /// Records `preset`'s machine with `seed` at `override_pct`, one row per `block_samples`
    /// samples, until the machine finishes or `max_duration_s` of machine time have passed.
    pub fn new(
        preset: Preset,
        seed: u64,
        override_pct: f64,
        block_samples: usize,
        max_duration_s: f64,
    ) -> Result<Self, PlantError> {
        let machine = preset.machine(seed)?;
        let rate = machine.sample_rate_hz();
        Ok(Self {
            preset,
            machine,
            command: OverrideCommand {
                override_pct,
                feed_hold: false,
            },
            block: block_samples.max(1),
            max_samples: (max_duration_s.max(0.0) * rate).min(1e9) as usize,
            samples: 0,
            block_sums: Block::default(),
            rows: Vec::new(),
            steps: Vec::new(),
            step_summaries: Vec::new(),
            steps_summarised: 0,
            taken: false,
        })
    }

    /// A time limit that lets `preset` run to its end at any override the lab offers down to
    /// about a third of 100 %, and stops a run at 0 % after 10 s.
    pub fn time_limit_s(preset: Preset) -> f64 {
        preset.summary().nominal_duration_s * 3.0 + 10.0
    }

    /// The rows so far.
    pub fn rows(&self) -> &[BlockRow] {
        &self.rows
    }

    /// The brake bench's load steps so far, at full rate (empty for other plants).
    pub fn load_steps(&self) -> &[LoadStep] {
        &self.steps
    }

    fn recorded_all(&self) -> bool {
        self.machine.finished() || self.samples >= self.max_samples
    }

    fn keep_load_step(&mut self, s: &PlantSignals) {
        if !matches!(self.machine, PresetMachine::BrakeBench(_)) {
            return;
        }
        let torque = s.brake_torque_nm;
        // A new torque level is a new step (the brake's torque changes in one sample).
        let new_step = self
            .steps
            .last()
            .is_none_or(|last| (last.brake_torque_nm - torque).abs() > 1e-9);
        if new_step {
            self.steps.push(LoadStep {
                start_s: s.time_s,
                brake_torque_nm: torque,
                feed_iu_a: Vec::new(),
                feed_rms_a: 0.0,
            });
            // The step before has ended.
            self.summarise_steps(self.steps.len() - 1);
        }
        if let Some(step) = self.steps.last_mut() {
            if s.time_s - step.start_s >= STEP_SETTLE_S {
                let n = step.feed_iu_a.len() as f64;
                step.feed_rms_a = (step.feed_rms_a * n + s.truth.feed_current_rms_a) / (n + 1.0);
                step.feed_iu_a.push(s.feed_currents_read_a[0]);
            }
        }
    }

    /// Summarises the load steps before `ended` not summarised yet.
    fn summarise_steps(&mut self, ended: usize) {
        let rate_hz = self.machine.sample_rate_hz();
        let ended = ended.min(self.steps.len());
        for step in &self.steps[self.steps_summarised.min(ended)..ended] {
            if step.feed_iu_a.len() < MIN_STEP_SAMPLES {
                continue;
            }
            // Cannot fail: the step has more than one sample and the rate is the plant's.
            let spectrum = amplitude_spectrum(&step.feed_iu_a, rate_hz, Window::Hann)
                .map(|sp| {
                    sp.freq_hz
                        .iter()
                        .zip(&sp.amplitude)
                        .take_while(|(f, _)| **f <= STEP_SPECTRUM_MAX_HZ)
                        .map(|(f, a)| (*f, *a))
                        .collect()
                })
                .unwrap_or_default();
            let loading = self
                .step_summaries
                .last()
                .is_none_or(|previous| step.brake_torque_nm >= previous.brake_torque_nm);
            self.step_summaries.push(StepSummary {
                brake_torque_nm: step.brake_torque_nm,
                loading,
                feed_rms_a: step.feed_rms_a,
                spectrum,
            });
        }
        self.steps_summarised = self.steps_summarised.max(ended);
    }

    fn push(&mut self, s: &PlantSignals) {
        let block_ends = self.block_sums.samples() + 1 >= self.block || self.recorded_all();
        self.block_sums.push(s);
        if block_ends {
            self.rows.push(self.block_sums.row());
            self.block_sums = Block::default();
        }
    }
}

impl Work for OpenLoopRun {
    type Output = OpenLoopRecording;
    type Error = RecordingError;

    /// Records at most `budget` samples.
    fn advance(&mut self, budget: usize) -> Result<bool, RecordingError> {
        for _ in 0..budget {
            if self.recorded_all() {
                break;
            }
            self.machine.step(self.command);
            self.samples += 1;
            let s = *self.machine.signals();
            self.keep_load_step(&s);
            self.push(&s);
        }
        let done = self.recorded_all();
        if done {
            // The last step ends with the run.
            self.summarise_steps(self.steps.len());
        }
        Ok(done)
    }

    fn progress(&self) -> Progress {
        let fraction = if self.max_samples == 0 {
            1.0
        } else {
            self.samples as f64 / self.max_samples as f64
        };
        Progress::new("Simulating the machine", fraction)
    }

    fn finish(&mut self) -> Result<OpenLoopRecording, RecordingError> {
        if self.taken {
            return Err(RecordingError::AlreadyTaken);
        }
        if !self.recorded_all() || self.steps_summarised < self.steps.len() {
            return Err(RecordingError::NotDone);
        }
        self.taken = true;
        Ok(OpenLoopRecording {
            preset: self.preset,
            rows: std::mem::take(&mut self.rows),
            load_steps: std::mem::take(&mut self.step_summaries),
        })
    }
}

/// A stretch of the brake bench's three feed phase currents at full rate.
#[derive(Debug, Clone, PartialEq)]
pub struct PhaseRecording {
    /// The plant's sample rate.
    pub sample_rate_hz: f64,
    /// Time of each sample.
    pub time_s: Vec<f64>,
    /// i_u, i_v, i_w as read, interleaved: three values per sample.
    pub phases_a: Vec<f64>,
    /// The spectrum of the raw i_u, which no filter changes: made once, with the recording.
    pub raw_spectrum: AmplitudeSpectrum,
}

/// Records paper 000's brake bench at 100 % override and keeps its feed phase currents over a
/// window of machine time, then takes the spectrum of the raw i_u.
///
/// ```
/// use cutlab::plant::recording::BenchRecording;
/// use cutlab::work::Work;
/// let r = BenchRecording::new(1, 2.0, 0.5).unwrap().run_to_end().unwrap();
/// assert_eq!((r.time_s.len(), r.phases_a.len()), (5000, 15_000)); // 0.5 s at 10 kHz
/// assert!((r.time_s[0] - 2.0001).abs() < 1e-9);
/// assert_eq!(r.raw_spectrum.freq_hz[1], 2.0); // 1/(0.5 s)
/// ```
pub struct BenchRecording {
    machine: PresetMachine,
    skip: usize,
    total: usize,
    done: usize,
    time_s: Vec<f64>,
    phases_a: Vec<f64>,
    raw_spectrum: Option<AmplitudeSpectrum>,
    taken: bool,
}

impl BenchRecording {
    /// A loaded step of the default schedule after the drive has settled (from 9 s, at 0.3 A),
    /// for 4 s: long enough to resolve paper 000's 4 Hz peak to 0.25 Hz.
    pub const LOADED_STEP_FROM_S: f64 = 9.0;
    /// See [`BenchRecording::LOADED_STEP_FROM_S`].
    pub const LOADED_STEP_FOR_S: f64 = 4.0;

    /// The bench with `seed`, kept from `from_s` for `duration_s` of machine time.
    pub fn new(seed: u64, from_s: f64, duration_s: f64) -> Result<Self, PlantError> {
        let from_s = super::non_negative("from_s", from_s)?;
        let duration_s = super::positive("duration_s", duration_s)?;
        let machine = Preset::WangBrakeBench.machine(seed)?;
        let rate = machine.sample_rate_hz();
        let skip = (from_s * rate) as usize;
        let keep = (duration_s * rate) as usize;
        Ok(Self {
            machine,
            skip,
            total: skip + keep,
            done: 0,
            time_s: Vec::with_capacity(keep),
            phases_a: Vec::with_capacity(3 * keep),
            raw_spectrum: None,
            taken: false,
        })
    }

    /// [`BenchRecording::new`] over the loaded step the signal-chain page shows.
    pub fn loaded_step(seed: u64) -> Result<Self, PlantError> {
        Self::new(seed, Self::LOADED_STEP_FROM_S, Self::LOADED_STEP_FOR_S)
    }
}

impl Work for BenchRecording {
    type Output = PhaseRecording;
    type Error = RecordingError;

    /// Records at most `budget` samples; the spectrum, once they are all in, is one unit of its
    /// own, apart from the last samples.
    fn advance(&mut self, budget: usize) -> Result<bool, RecordingError> {
        if self.raw_spectrum.is_some() {
            return Ok(true);
        }
        if budget == 0 {
            return Ok(false);
        }
        if self.done >= self.total {
            let u: Vec<f64> = self.phases_a.iter().step_by(3).copied().collect();
            let spectrum = amplitude_spectrum(&u, self.machine.sample_rate_hz(), Window::Hann)
                .map_err(RecordingError::Spectrum)?;
            self.raw_spectrum = Some(spectrum);
            return Ok(true);
        }
        let end = (self.done + budget).min(self.total);
        for i in self.done..end {
            let step = self.machine.step(OverrideCommand::default());
            if i >= self.skip {
                self.time_s.push(step.sensors.time_s);
                self.phases_a
                    .extend_from_slice(&step.sensors.feed_phase_currents_a);
            }
        }
        self.done = end;
        Ok(false)
    }

    fn progress(&self) -> Progress {
        let stage = if self.done >= self.total {
            "Computing the spectrum"
        } else {
            "Simulating the brake bench"
        };
        Progress::new(stage, self.done as f64 / self.total.max(1) as f64)
    }

    fn finish(&mut self) -> Result<PhaseRecording, RecordingError> {
        if self.taken {
            return Err(RecordingError::AlreadyTaken);
        }
        let raw_spectrum = self.raw_spectrum.take().ok_or(RecordingError::NotDone)?;
        self.taken = true;
        Ok(PhaseRecording {
            sample_rate_hz: self.machine.sample_rate_hz(),
            time_s: std::mem::take(&mut self.time_s),
            phases_a: std::mem::take(&mut self.phases_a),
            raw_spectrum,
        })
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn the_open_loop_override_is_one_row_of_a_table() {
        assert_eq!(
            crate::input::table::check_table::<OpenLoopSetting>(),
            Ok(())
        );
        let e = OpenLoopSetting::Override.parse("300").unwrap_err();
        assert_eq!(e.problem.to_string(), "300 % is outside 0–255 %");
        assert_eq!(e.for_cli(), "--override: 300 % is outside 0–255 %");
    }

    use super::*;

    #[test]
    fn blocks_summarise_means_and_extremes() {
        let mut run = OpenLoopRun::new(Preset::ManeeratDoc1, 1, 100.0, 100, 5.0).unwrap();
        while !run.advance(10_000).unwrap() {}
        let rows = run.rows();
        assert_eq!(rows.len(), 500);
        assert!((rows[499].time_s - 5.0).abs() < 1e-9);
        for r in rows {
            assert!(r.resultant_min_n <= r.resultant_max_n);
            assert!(r.feed_iu_min_a <= r.feed_iu_max_a);
        }
        assert!(
            rows.iter().any(|r| r.resultant_max_n > 0.0),
            "the tool never cut"
        );
    }

    #[test]
    fn the_brake_bench_keeps_each_load_step_at_full_rate() {
        let mut run = OpenLoopRun::new(Preset::WangBrakeBench, 1, 100.0, 100, 12.0).unwrap();
        while !run.advance(50_000).unwrap() {}
        let steps = run.load_steps();
        assert!(steps.len() >= 3, "{} steps", steps.len());
        // Each complete step keeps its settled part at 10 kHz.
        assert!(steps[1].feed_iu_a.len() > 10_000);
        assert!(steps[2].brake_torque_nm > steps[0].brake_torque_nm);
        assert!(steps[2].feed_rms_a > steps[0].feed_rms_a);
    }

    /// The recording's bits, NaN included, for comparing runs.
    fn bits(rec: &OpenLoopRecording) -> String {
        format!("{rec:?}")
    }

    #[test]
    fn bench_load_steps_summarise_to_their_torque_rms_current_and_4_hz_peak() {
        // Four steps of 3 s: 0, 0.1, 0.2, 0.3 A of excitation; the last is cut at 12 s.
        let rec = OpenLoopRun::new(Preset::WangBrakeBench, 1, 100.0, 50, 12.0)
            .unwrap()
            .run_to_end()
            .unwrap();
        let bench = crate::plant::bench::BrakeBenchConfig::default();
        let (brake, fd) = (bench.brake, bench.feed_drive);
        let torques: Vec<f64> = rec.load_steps.iter().map(|s| s.brake_torque_nm).collect();
        // Loading from a demagnetised brake: T = k_b·(I − h) once I > h.
        let expected = [0.0, 0.1, 0.2, 0.3]
            .map(|i: f64| brake.torque_per_amp_nm_per_a * (i - brake.hysteresis_a).max(0.0));
        assert_eq!(torques.len(), 4, "{torques:?}");
        assert!(rec.load_steps.iter().all(|s| s.loading));
        for (got, want) in torques.iter().zip(expected) {
            assert!((got - want).abs() < 1e-12, "{torques:?} vs {expected:?}");
        }
        // Paper 000 eq 9: I_rms = (T_idle + T_load)/K_t · √(1 + h5² + h7²)/√2.
        let per_amp =
            crate::plant::feed_drive::ThreePhaseWaveform::new(fd.harmonic_5th, fd.harmonic_7th)
                .rms_per_amplitude();
        for s in &rec.load_steps {
            let want = fd.idle_rms_current_a(bench.feed_mm_min)
                + per_amp / fd.torque_constant_nm_per_a() * s.brake_torque_nm;
            // Within the friction's wander (σ 0.03 N·m ≈ 0.018 A, 3 % of the idle current).
            assert!(
                (s.feed_rms_a - want).abs() < 0.06 * want,
                "{} N·m: {} A vs {want} A",
                s.brake_torque_nm,
                s.feed_rms_a
            );
            // About 2 s of settled current: 0.5 Hz bins up to 20 Hz, the strongest line at the
            // 4 Hz electrical frequency of 600 mm/min (paper 000 Fig. 9).
            assert!(s.spectrum.len() >= 40);
            assert!(s.spectrum.iter().all(|(f, _)| *f <= STEP_SPECTRUM_MAX_HZ));
            let peak =
                s.spectrum.iter().skip(1).fold(
                    (0.0, 0.0),
                    |best, &(f, a)| if a > best.1 { (f, a) } else { best },
                );
            assert!((peak.0 - 4.0).abs() < 0.01, "{:?}", s.spectrum);
        }
    }

    #[test]
    fn the_whole_bench_loads_then_unloads_along_paper_000s_line() {
        let rec = OpenLoopRun::new(Preset::WangBrakeBench, 3, 100.0, 500, 70.0)
            .unwrap()
            .run_to_end()
            .unwrap();
        let loading: Vec<bool> = rec.load_steps.iter().map(|s| s.loading).collect();
        let mut expected = vec![true; 11];
        expected.extend([false; 10]);
        assert_eq!(loading, expected);
        let fd = crate::plant::bench::BrakeBenchConfig::default().feed_drive;
        let per_amp =
            crate::plant::feed_drive::ThreePhaseWaveform::new(fd.harmonic_5th, fd.harmonic_7th)
                .rms_per_amplitude();
        let line = rec.load_line().unwrap();
        let slope = per_amp / fd.torque_constant_nm_per_a();
        let idle = fd.idle_rms_current_a(600.0);
        assert_eq!(line.steps, 21);
        // The bench's friction wanders and drifts (BenchFrictionConfig): the line is the
        // model's within a few percent, and its points scatter about it as a real bench's do.
        assert!(
            (line.slope_a_per_nm - slope).abs() < 0.03 * slope,
            "{line:?}"
        );
        assert!((line.idle_current_a - idle).abs() < 0.03 * idle, "{line:?}");
        assert!(line.r_squared > 0.99 && line.r_squared < 0.9995, "{line:?}");
        // A mill has no load steps to fit a line to.
        let mill = OpenLoopRecording {
            preset: Preset::KimStepDoc,
            rows: Vec::new(),
            load_steps: Vec::new(),
        };
        assert!(mill.load_line().is_err());
    }

    #[test]
    fn other_plants_have_no_load_steps() {
        let rec = OpenLoopRun::new(Preset::LiuCurrentStep, 1, 100.0, 50, 0.5)
            .unwrap()
            .run_to_end()
            .unwrap();
        assert_eq!(rec.rows.len(), 100);
        assert!(rec.load_steps.is_empty());
    }

    #[test]
    fn an_open_loop_recording_does_not_depend_on_the_budgets() {
        let run = || OpenLoopRun::new(Preset::WangBrakeBench, 2, 100.0, 37, 7.5).unwrap();
        let whole = run().run_to_end().unwrap();
        let mut by_one = run();
        while !by_one.advance(1).unwrap() {}
        let mut by_many = run();
        while !by_many.advance(10_000).unwrap() {}
        let (one, many) = (by_one.finish().unwrap(), by_many.finish().unwrap());
        assert_eq!(bits(&one), bits(&whole));
        assert_eq!(bits(&many), bits(&whole));
        assert_eq!(whole.load_steps.len(), 3);
    }

    #[test]
    fn a_bench_recording_does_not_depend_on_the_budgets() {
        let run = || BenchRecording::new(4, 3.5, 0.7).unwrap();
        let whole = run().run_to_end().unwrap();
        let mut by_one = run();
        while !by_one.advance(1).unwrap() {}
        let mut by_many = run();
        while !by_many.advance(10_000).unwrap() {}
        assert_eq!(by_one.finish().unwrap(), whole);
        assert_eq!(by_many.finish().unwrap(), whole);
        assert_eq!(whole.time_s.len(), 7000);
        // The raw current's strongest line is the 4 Hz electrical frequency (1/0.7 s bins).
        let s = &whole.raw_spectrum;
        let peak = (1..s.amplitude.len())
            .max_by(|&a, &b| s.amplitude[a].total_cmp(&s.amplitude[b]))
            .unwrap();
        assert!(
            (s.freq_hz[peak] - 4.0).abs() < 1.0 / 0.7,
            "{}",
            s.freq_hz[peak]
        );
    }

    #[test]
    fn finish_refuses_before_the_end_and_a_second_time() {
        let mut run = OpenLoopRun::new(Preset::ManeeratDoc2, 1, 100.0, 10, 0.01).unwrap();
        assert_eq!(run.finish(), Err(RecordingError::NotDone));
        assert!(run.advance(100).unwrap());
        assert_eq!(run.progress().fraction, 1.0);
        assert_eq!(run.finish().unwrap().rows.len(), 10);
        assert_eq!(run.finish(), Err(RecordingError::AlreadyTaken));
        let mut bench = BenchRecording::new(1, 0.0, 0.01).unwrap();
        assert_eq!(bench.finish(), Err(RecordingError::NotDone));
        while !bench.advance(7).unwrap() {}
        assert!(bench.finish().is_ok());
        assert_eq!(bench.finish(), Err(RecordingError::AlreadyTaken));
    }

    #[test]
    fn the_spectrum_is_a_stage_of_its_own() {
        // The browser's runner starts a new stage in a chunk of its own: the spectrum must not
        // be reported as more of the simulation.
        let mut bench = BenchRecording::new(1, 0.0, 0.01).unwrap();
        assert_eq!(bench.progress().stage, "Simulating the brake bench");
        assert!(!bench.advance(99).unwrap());
        assert_eq!(bench.progress().stage, "Simulating the brake bench");
        assert!(
            !bench.advance(1).unwrap(),
            "the last sample, not yet the spectrum"
        );
        assert_eq!(bench.progress().stage, "Computing the spectrum");
        assert!(bench.advance(1).unwrap());
    }

    #[test]
    fn a_bench_window_with_one_sample_has_no_spectrum_and_says_so() {
        let mut bench = BenchRecording::new(1, 0.0, 1e-4).unwrap();
        let e = loop {
            match bench.advance(10) {
                Ok(true) => unreachable!("one sample has no spectrum"),
                Ok(false) => {}
                Err(e) => break e,
            }
        };
        assert!(matches!(e, RecordingError::Spectrum(_)), "{e}");
        assert!(e.to_string().starts_with("the spectrum of the recording"));
        assert_eq!(
            BenchRecording::new(1, -1.0, 1.0).err().map(|e| e.field),
            Some("from_s".to_string())
        );
    }
}
