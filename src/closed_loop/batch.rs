//! Independent runs of one plant stepped together (issue 28's batched loop): [`run_batch`] and
//! [`LabBatch`] give each run's result bit for bit as [`LabRun`] alone gives it.
//!
//! ## Design
//!
//! A batch is N runs of one preset and scenario that differ in controller, settings or seed
//! (Compare's variants, the reference probes, a sweep's points). They advance in lockstep, one
//! control period of every run per round, so a lane layout can replace the per-run stepping
//! without changing the interface. The lane-able stages are the per-sample arithmetic that takes
//! no data-dependent branch: the drives' lag, phasor and three-phase currents with harmonics
//! (`plant/feed_drive.rs`, `spindle_drive.rs`, 30 % of the profile), the structural dynamics
//! (`plant/dynamics.rs`), the sensors' gains apart from their RNG draws, and the signal chain's
//! SOS bank (`signal/sos.rs`). Their state would be `[f64; LANES]` arrays with one kernel that
//! the single run calls with one lane, each lane doing the same operations in the same order (no
//! FMA contraction, no reassociation), so bits do not change. The CNC, path, tooth engagement,
//! ziggurat draws, envelope and controllers stay per run. Built so far: the lockstep stepping and
//! the shared teach cut; the lane kernels are not (docs/benchmarks.md, "The batched loop").

use super::definition::RunSpec;
use super::error::LoopError;
use super::lab::{LabRun, RunResult, TeachKey};
use crate::work::{Progress, Work};

/// One run of a batch: waiting for the teach cut it shares, under way, or finished.
enum Lane {
    /// Its teach cut is the one lane `teacher` makes; it starts from that calibration.
    Waiting {
        teacher: usize,
    },
    Running(Box<LabRun>),
    Done(Box<Result<RunResult, LoopError>>),
}

/// Runs of one plant advanced together, a control period of each per round.
///
/// Runs with the same [`TeachKey`] share the first one's teach cut (the simulation repeats it
/// exactly, so the results are those of a teach cut each, as [`super::lab::LabRuns`] relies on).
pub struct LabBatch {
    specs: Vec<RunSpec>,
    lanes: Vec<Lane>,
}

impl LabBatch {
    /// The runs of `specs` on their presets' simulated machines, none stepped yet. A spec that
    /// cannot start (a bad setting) is finished at once with its error.
    pub fn new(specs: Vec<RunSpec>) -> Self {
        let keys: Vec<Option<TeachKey>> = specs.iter().map(|s| TeachKey::of(s).ok()).collect();
        let lanes = specs
            .iter()
            .enumerate()
            .map(|(i, spec)| {
                let teacher = keys[i]
                    .as_ref()
                    .and_then(|key| keys[..i].iter().position(|k| k.as_ref() == Some(key)));
                match teacher {
                    Some(teacher) => Lane::Waiting { teacher },
                    None => match LabRun::new(spec) {
                        Ok(run) => Lane::Running(Box::new(run)),
                        Err(e) => Lane::Done(Box::new(Err(e))),
                    },
                }
            })
            .collect();
        Self { specs, lanes }
    }

    /// Starts the waiting lanes whose teacher has finished its teach cut (or failed).
    fn start_waiting(&mut self) {
        for i in 0..self.lanes.len() {
            let Lane::Waiting { teacher } = self.lanes[i] else {
                continue;
            };
            let started = match &self.lanes[teacher] {
                Lane::Running(run) => run.loop_so_far().map(|(_, calibration)| {
                    LabRun::calibrated(&self.specs[i], calibration.clone())
                }),
                Lane::Done(outcome) => Some(match outcome.as_ref() {
                    Ok(result) => LabRun::calibrated(&self.specs[i], result.calibration.clone()),
                    // The teacher failed: this run makes its own teach cut, and fails or not
                    // alone.
                    Err(_) => LabRun::new(&self.specs[i]),
                }),
                Lane::Waiting { .. } => None,
            };
            if let Some(started) = started {
                self.lanes[i] = match started {
                    Ok(run) => Lane::Running(Box::new(run)),
                    Err(e) => Lane::Done(Box::new(Err(e))),
                };
            }
        }
    }

    fn all_done(&self) -> bool {
        self.lanes.iter().all(|l| matches!(l, Lane::Done(_)))
    }
}

impl Work for LabBatch {
    type Output = Vec<Result<RunResult, LoopError>>;
    type Error = LoopError;

    /// At most `periods` rounds, each a control period (or a teach-cut period) of every run.
    fn advance(&mut self, periods: usize) -> Result<bool, LoopError> {
        for _ in 0..periods {
            self.start_waiting();
            if self.all_done() {
                break;
            }
            for lane in &mut self.lanes {
                let Lane::Running(run) = lane else { continue };
                match run.advance(1) {
                    Ok(false) => {}
                    Ok(true) => *lane = Lane::Done(Box::new(run.finish())),
                    Err(e) => *lane = Lane::Done(Box::new(Err(e))),
                }
            }
        }
        Ok(self.all_done())
    }

    fn progress(&self) -> Progress {
        let total = self.lanes.len().max(1) as f64;
        let fraction = self
            .lanes
            .iter()
            .map(|lane| match lane {
                Lane::Waiting { .. } => 0.0,
                Lane::Running(run) => run.progress().fraction,
                Lane::Done(_) => 1.0,
            })
            .sum::<f64>()
            / total;
        Progress::new(format!("{} runs together", self.lanes.len()), fraction)
    }

    fn finish(&mut self) -> Result<Self::Output, LoopError> {
        if !self.all_done() {
            return Err(LoopError::NotFinished);
        }
        Ok(std::mem::take(&mut self.lanes)
            .into_iter()
            .filter_map(|lane| match lane {
                Lane::Done(outcome) => Some(*outcome),
                _ => None,
            })
            .collect())
    }
}

/// Runs `specs` together to the end; each outcome is what [`LabRun::new`] and
/// [`Work::run_to_end`] give for that spec alone, in `specs`' order.
///
/// ```
/// use cutlab::closed_loop::batch::run_batch;
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::closed_loop::lab::simulate;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let specs = vec![
///     RunSpec::new(Preset::WangBrakeBench, ControllerKind::Fixed),
///     RunSpec::new(Preset::WangBrakeBench, ControllerKind::Pi),
/// ];
/// let together = run_batch(&specs);
/// let alone = simulate(&specs[1]).unwrap();
/// // Every number, NaN included, by its shortest round-trip text.
/// let exact = |trace| format!("{trace:?}");
/// assert_eq!(exact(&together[1].as_ref().unwrap().trace), exact(&alone.trace));
/// ```
pub fn run_batch(specs: &[RunSpec]) -> Vec<Result<RunResult, LoopError>> {
    let mut batch = LabBatch::new(specs.to_vec());
    // Each round advances every run, so this ends: a run finishes within its time limit.
    while !batch.advance(usize::MAX).unwrap_or(true) {}
    batch.finish().unwrap_or_default()
}
