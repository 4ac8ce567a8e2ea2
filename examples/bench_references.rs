//! The savings' reference search of one preset, run by run: which fixed overrides it probes and
//! the processor time each run takes (issue 28: why `kim-circular-taper`'s savings took seconds).
//!
//! ```text
//! cargo run --release --example bench_references -- kim-circular-taper [--applied 100,36,14,2]
//! ```
//!
//! Prints one line per reference run (the search's own progress label) with its CPU seconds
//! (Linux: this thread's time on a processor, from /proc), then the total; with `--applied`, runs
//! those fixed overrides whole (with the search's calibration) and prints the override the
//! machine applied (the safety envelope narrows it to the chip-load window), the peak force and
//! the cycle time of each.

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::LabRun;
use cutlab::closed_loop::references::{fixed_feed_spec, ReferenceSearch};
use cutlab::control::registry::ControllerKind;
use cutlab::plant::Preset;
use cutlab::work::Work;

#[path = "common/timing.rs"]
// This bench takes its own arguments, not the shared `--repeats`.
#[allow(dead_code)]
mod timing;
use timing::thread_cpu_s;

fn main() {
    let mut args = std::env::args().skip(1);
    let name = args.next().unwrap_or_else(|| "kim-circular-taper".into());
    // Fixed overrides to run whole afterwards, percent: `--applied 14,2`.
    let applied: Vec<f64> = match (args.next().as_deref(), args.next()) {
        (Some("--applied"), Some(list)) => list.split(',').filter_map(|v| v.parse().ok()).collect(),
        _ => Vec::new(),
    };
    let Some(preset) = Preset::from_name(&name) else {
        eprintln!("bench_references: no preset named {name}");
        std::process::exit(2);
    };
    let spec = RunSpec::new(preset, ControllerKind::FuzzyDynamics);
    let mut search = match ReferenceSearch::new(&spec) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("bench_references: {e}");
            std::process::exit(1);
        }
    };
    let start_s = thread_cpu_s();
    let mut stage = search.progress().stage;
    let mut stage_start_s = start_s;
    loop {
        match search.advance(1) {
            Ok(done) => {
                let now = search.progress().stage;
                if now != stage || done {
                    let t = thread_cpu_s();
                    println!("{:6.3} s CPU  {stage}", t - stage_start_s);
                    (stage, stage_start_s) = (now, t);
                }
                if done {
                    break;
                }
            }
            Err(e) => {
                eprintln!("bench_references: {e}");
                std::process::exit(1);
            }
        }
    }
    println!(
        "{:6.3} s CPU in all: {:?}",
        thread_cpu_s() - start_s,
        search.found()
    );
    // What the machine applied at a few of those overrides, and what each run gave.
    let Some(calibration) = search.calibration().cloned() else {
        return;
    };
    for pct in applied {
        let run = fixed_feed_spec(&spec, pct)
            .and_then(|fixed| LabRun::calibrated(&fixed, calibration.clone())?.run_to_end());
        match run {
            Ok(r) => {
                let mut applied_pct: Vec<f64> =
                    r.trace.rows.iter().map(|row| row.override_pct).collect();
                applied_pct.sort_by(f64::total_cmp);
                println!(
                    "fixed {pct} %: applied override median {} %, peak force {:.3} N, cycle time {} s",
                    applied_pct.get(applied_pct.len() / 2).copied().unwrap_or(f64::NAN),
                    r.metrics.peak_force_n,
                    r.metrics.cycle_time_s
                );
            }
            Err(e) => println!("fixed {pct} %: {e}"),
        }
    }
}
