//! The closed-loop benchmark's workload, natively: kim-step-doc with fuzzy-dynamics (the full
//! chain: teach cut, then the loop), run through the library exactly as `cutlab sim --scenario
//! kim-step-doc --controller fuzzy-dynamics --no-references` runs it, timed in the process.
//!
//! Driven by `scripts/bench/closed_loop.py` (see docs/benchmarks.md); `examples/bench_loop_wasm.rs`
//! is the same workload compiled to wasm and timed under node. On its own:
//!
//! ```text
//! cargo run --release --example bench_loop -- [--repeats 3]
//! ```
//!
//! Prints the best repeat as one JSON line: `{"simulated_s": …, "wall_s": …, "cpu_s": …}`; the
//! CPU time (Linux: this thread's time on a processor, from /proc) tells on a shared machine how
//! much of the wall time was spent waiting for a core.

use std::time::Instant;

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::simulate;
use cutlab::control::registry::ControllerKind;
use cutlab::plant::Preset;

#[path = "common/trace_digest.rs"]
mod trace_digest;

#[path = "common/timing.rs"]
mod timing;
use timing::{repeats_from_args, thread_cpu_s};

fn main() {
    let repeats = repeats_from_args("bench_loop [--repeats N]");
    let spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::FuzzyDynamics);
    let mut best_s = f64::INFINITY;
    let mut best_cpu_s = f64::INFINITY;
    let mut simulated_s = f64::NAN;
    let mut digest = String::new();
    for _ in 0..repeats {
        let start = Instant::now();
        let cpu_start = thread_cpu_s();
        match simulate(&spec) {
            Ok(result) => {
                best_s = best_s.min(start.elapsed().as_secs_f64());
                best_cpu_s = best_cpu_s.min(thread_cpu_s() - cpu_start);
                simulated_s = result.metrics.cycle_time_s + result.calibration.duration_s;
                digest = trace_digest::trace_digest(&result);
            }
            Err(e) => {
                eprintln!("bench_loop: {e}");
                std::process::exit(1);
            }
        }
    }
    println!(
        "{{\"simulated_s\": {simulated_s}, \"wall_s\": {best_s}, \"cpu_s\": {}, \"digest\": \"{digest}\"}}",
        if best_cpu_s.is_finite() {
            best_cpu_s.to_string()
        } else {
            "null".to_string()
        }
    );
}
