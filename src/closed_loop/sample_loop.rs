//! The shape every loop shares: sensor samples pushed in one at a time, an override command out
//! at the end of each control period ([`SampleLoop`]), and the adapter that pulls samples from a
//! [`Machine`] and pushes them ([`OnMachine`]).
//!
//! ```text
//! a simulated machine, a replayed log ── OnMachine pulls ─┐
//! a device on the serial line, the browser's port ────────┴─► SampleLoop::push ─► command
//!   (the teach cut: teach_cut::TeachCut; the closed loop: feedback_loop::FeedbackLoop)
//! ```
//!
//! Both loops summarise their periods with the same signal chain, built here from the resolved
//! [`ChainSettings`].

use super::error::LoopError;
use super::settings::ChainSettings;
use crate::machine::{
    BlockStep, DynamometerReading, Machine, MachineStep, OverrideCommand, SensorlessEstimate,
};
use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, DesignError, FilterKind};
use crate::signal::chain::SignalChain;
use crate::signal::sos::Sos;
use crate::work::{Progress, Work};

/// One sensor sample as a loop takes it: the machine's step and what the machine adds beside it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LoopSample<'a> {
    /// What the sensors read (and the truth, if simulated).
    pub step: &'a MachineStep,
    /// The power-law estimate of [`Machine::sensorless_force`], when the machine offers one.
    /// Only a period's last sample needs it ([`SampleLoop::next_sample_ends_period`]).
    pub sensorless: Option<SensorlessEstimate>,
    /// A dynamometer's reading, when the machine has one.
    pub dynamometer: Option<DynamometerReading>,
}

/// A loop that takes sensor samples as they come and answers with an override command at the end
/// of each control period.
///
/// This is the shape a real machine needs: WebSerial delivers samples when they arrive and a log
/// is read in chunks, so the loop is pushed, never pulls. [`OnMachine`] is the thin adapter that
/// pulls samples from a [`Machine`] (the simulation) and pushes them here; replay and hardware
/// push theirs directly. The teach cut and the closed loop are both sample loops.
pub trait SampleLoop {
    /// What the finished loop gives.
    type Output;

    /// Takes one sample. At the end of a control period it returns the command for the samples
    /// that follow; in between, `None` (the command in force is [`SampleLoop::command`]).
    fn push(&mut self, sample: &LoopSample<'_>) -> Option<OverrideCommand>;

    /// The override command in force.
    fn command(&self) -> OverrideCommand;

    /// Where the loop is in its control period.
    fn clock(&self) -> &PeriodClock;

    /// Whether the next pushed sample is the last of its control period.
    fn next_sample_ends_period(&self) -> bool {
        self.clock().next_ends_period()
    }

    /// How many more samples the control period under way takes (at least one): a machine can
    /// step that many under the same command at once.
    fn samples_left_in_period(&self) -> usize {
        self.clock().samples_left()
    }

    /// The machine says its program (or log) has ended with the last sample pushed: a period
    /// under way ends with the samples it has (the machine has nothing more to say, and repeating
    /// its last reading would look like a stuck sensor), and the loop ends.
    fn end_of_program(&mut self);

    /// Whether the loop has ended (program over, time limit, or its own reason).
    fn finished(&self) -> bool;

    /// Machine time of the latest period's end.
    fn elapsed_s(&self) -> f64;

    /// What a person reads on a progress bar.
    fn stage(&self) -> &'static str;

    /// The output, once finished (or early, for what is there so far when the run is stopped).
    fn finish(&mut self) -> Result<Self::Output, LoopError>;
}

/// A low-pass at `cutoff_hz`; an infinite cut-off is no low-pass (one section that passes every
/// sample through unchanged).
fn lowpass(cutoff_hz: f64, order: usize, sample_rate_hz: f64) -> Result<Sos, LoopError> {
    if cutoff_hz == f64::INFINITY {
        return Sos::from_rows(&[[1.0, 0.0, 0.0, 1.0, 0.0, 0.0]])
            .map_err(|_| LoopError::Filter(DesignError::Order { order: 0 }));
    }
    butter(&ButterworthSpec {
        kind: FilterKind::Lowpass,
        order,
        cutoff_hz: Cutoff::Single(cutoff_hz),
        sample_rate_hz,
    })
    .map_err(LoopError::Filter)
}

/// The signal chain of `chain` for samples at `sample_rate_hz`.
pub fn signal_chain(chain: &ChainSettings, sample_rate_hz: f64) -> Result<SignalChain, LoopError> {
    let spindle = lowpass(
        chain.spindle_lowpass_hz,
        chain.lowpass_order,
        sample_rate_hz,
    )?;
    let feed = lowpass(chain.feed_lowpass_hz, chain.lowpass_order, sample_rate_hz)?;
    // Three phases per drive: the bank always has channels.
    SignalChain::new(&spindle, &feed)
        .map_err(|_| LoopError::Filter(DesignError::Order { order: 0 }))
}

/// Where a loop is in its control period: the samples pushed so far against the period's length
/// (the resolved period is a whole number of samples).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PeriodClock {
    per_period: usize,
    in_period: usize,
}

impl PeriodClock {
    /// The clock of `chain`'s control period at `sample_rate_hz`.
    pub fn new(chain: &ChainSettings, sample_rate_hz: f64) -> Result<Self, LoopError> {
        let n = (chain.control_period_s * sample_rate_hz).round();
        if !(1.0..=1e7).contains(&n) {
            return Err(LoopError::ControlPeriod {
                period_s: chain.control_period_s,
                sample_rate_hz,
            });
        }
        Ok(Self {
            per_period: n as usize,
            in_period: 0,
        })
    }

    /// Counts one sample; true when it ends the period (the count starts again).
    #[inline(always)]
    pub fn tick(&mut self) -> bool {
        self.in_period += 1;
        if self.in_period < self.per_period {
            return false;
        }
        self.in_period = 0;
        true
    }

    /// Ends the period under way early (the program ended with it) and says how many samples it
    /// had (0: none, nothing to end).
    pub fn cut_short(&mut self) -> usize {
        std::mem::take(&mut self.in_period)
    }

    /// Whether the next sample ends the period ([`SampleLoop::next_sample_ends_period`]).
    pub fn next_ends_period(&self) -> bool {
        self.in_period + 1 >= self.per_period
    }

    /// Samples still to come in the period under way, at least one
    /// ([`SampleLoop::samples_left_in_period`]).
    pub fn samples_left(&self) -> usize {
        self.per_period.saturating_sub(self.in_period).max(1)
    }

    /// Samples in a whole period.
    pub fn samples_per_period(&self) -> usize {
        self.per_period
    }
}

/// A [`SampleLoop`] pulling its samples from a [`Machine`]: each sample period it steps the
/// machine with the loop's command and pushes what the machine read. This is how a simulation
/// (and a replayed log) drives the same loop a real machine pushes samples into.
pub struct OnMachine<L> {
    machine: Box<dyn Machine>,
    pub(super) sample_loop: L,
    /// The samples of the block being pushed ([`Machine::step_block`]).
    block: Vec<BlockStep>,
}

/// Samples a machine steps at once, at most (a block stays in the first-level cache).
const MACHINE_BLOCK: usize = 64;

impl<L: SampleLoop> OnMachine<L> {
    /// `sample_loop` driven by `machine`.
    pub fn new_with(machine: Box<dyn Machine>, sample_loop: L) -> Self {
        Self {
            machine,
            sample_loop,
            block: vec![BlockStep::default(); MACHINE_BLOCK],
        }
    }

    /// The loop.
    pub fn sample_loop(&self) -> &L {
        &self.sample_loop
    }

    /// Machine time of the latest period's end.
    pub fn elapsed_s(&self) -> f64 {
        self.sample_loop.elapsed_s()
    }

    /// Whether the loop has ended.
    pub fn finished(&self) -> bool {
        self.sample_loop.finished()
    }

    /// The machine back (a real machine does the teach cut and then the run), and the loop.
    pub fn into_parts(self) -> (Box<dyn Machine>, L) {
        (self.machine, self.sample_loop)
    }

    /// Runs one control period: the machine steps the period's samples in blocks under the
    /// period's command, and each sample is pushed into the loop in turn.
    fn period(&mut self) {
        let command = self.sample_loop.command();
        loop {
            let wanted = self.sample_loop.samples_left_in_period().min(MACHINE_BLOCK);
            let stepped = self.machine.step_block(command, &mut self.block[..wanted]);
            let program_over = self.machine.finished();
            for (i, b) in self.block[..stepped].iter().enumerate() {
                let last = i + 1 == stepped;
                // A period ends at the block's last sample (the block never crosses one), or
                // where the program does.
                let ends = (last && program_over) || self.sample_loop.next_sample_ends_period();
                let sample = LoopSample {
                    step: &b.step,
                    // The power law is evaluated once per period, where the loop reads it: at
                    // the machine's latest sample, which is this one.
                    sensorless: if ends && last {
                        self.machine.sensorless_force()
                    } else {
                        None
                    },
                    dynamometer: b.dynamometer,
                };
                let period_ended = self.sample_loop.push(&sample).is_some();
                if last && program_over {
                    self.sample_loop.end_of_program();
                    return;
                }
                if period_ended || self.sample_loop.finished() {
                    return;
                }
            }
            if stepped == 0 {
                // Not reached (a block holds at least one sample); never spin.
                return;
            }
        }
    }
}

impl<L: SampleLoop> Work for OnMachine<L> {
    type Output = L::Output;
    type Error = LoopError;

    /// Runs at most `periods` control periods.
    fn advance(&mut self, periods: usize) -> Result<bool, LoopError> {
        for _ in 0..periods {
            if self.sample_loop.finished() {
                break;
            }
            self.period();
        }
        Ok(self.sample_loop.finished())
    }

    fn progress(&self) -> Progress {
        // The machine's own duration is unknown here; LabRun scales by the program's.
        Progress::new(self.sample_loop.stage(), 0.0)
    }

    fn finish(&mut self) -> Result<L::Output, LoopError> {
        self.sample_loop.finish()
    }
}
