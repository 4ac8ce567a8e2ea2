//! The batched loop's benchmark workload (issue 28): a Compare of four controllers on
//! kim-step-doc (fuzzy-dynamics, fuzzy-experience, PI, restriction; one seed, so one teach cut),
//! stepped one run after another ([`LabRuns`], the single loop, sharing the teach cut as Compare
//! does) or together ([`cutlab::closed_loop::batch::run_batch`]). Both compute the same runs bit
//! for bit; the digests say so.

use cutlab::closed_loop::batch::run_batch;
use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::{LabRuns, RunResult};
use cutlab::control::registry::ControllerKind;
use cutlab::plant::Preset;
use cutlab::work::Work;

use super::trace_digest::trace_digest;

/// The four runs.
pub fn specs() -> Vec<RunSpec> {
    [
        ControllerKind::FuzzyDynamics,
        ControllerKind::FuzzyExperience,
        ControllerKind::Pi,
        ControllerKind::Restriction,
    ]
    .into_iter()
    .map(|kind| RunSpec::new(Preset::KimStepDoc, kind))
    .collect()
}
/// Runs the workload one run at a time (`batched` false) or as one batch; returns the seconds
/// simulated (every run's loop and the one teach cut) and the runs' digests joined by
/// commas, or the first error.
pub fn run(batched: bool) -> Result<(f64, String), String> {
    let specs = specs();
    let results: Vec<RunResult> = if batched {
        run_batch(&specs)
            .into_iter()
            .collect::<Result<_, _>>()
            .map_err(|e| e.to_string())?
    } else {
        LabRuns::new(specs)
            .run_to_end()
            .map_err(|e| e.to_string())?
            .into_iter()
            .map(|r| (*r).clone())
            .collect()
    };
    // Seeds 1 and 7 each make one teach cut; the others share seed 1's.
    let teach_s: f64 = [0, 3]
        .iter()
        .map(|&i| results[i].calibration.duration_s)
        .sum();
    let simulated_s = teach_s + results.iter().map(|r| r.metrics.cycle_time_s).sum::<f64>();
    let digests: Vec<String> = results.iter().map(trace_digest).collect();
    Ok((simulated_s, digests.join(",")))
}
