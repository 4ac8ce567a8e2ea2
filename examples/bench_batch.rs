//! The batched loop against the single loop, natively (issue 28): the four runs of
//! `examples/common/batch_workload.rs` one after another and as one batch, alternating, each
//! timed by this thread's CPU time (a shared machine's wall time includes waiting for a core).
//!
//! ```text
//! cargo run --release --example bench_batch -- [--repeats 3]
//! ```
//!
//! Prints one JSON line: the simulated seconds, the best CPU and wall seconds of each way, and
//! the runs' digests (the same for both, or it exits with an error).

use std::time::Instant;

#[path = "common/trace_digest.rs"]
mod trace_digest;

#[path = "common/timing.rs"]
mod timing;
use timing::{repeats_from_args, thread_cpu_s};

#[path = "common/batch_workload.rs"]
mod batch_workload;

fn main() {
    let repeats = repeats_from_args("bench_batch [--repeats N]");
    // [single, batched]: best wall s, best CPU s, digests.
    let mut wall_s = [f64::INFINITY; 2];
    let mut cpu_s = [f64::INFINITY; 2];
    let mut digests = [String::new(), String::new()];
    let mut simulated_s = f64::NAN;
    for _ in 0..repeats {
        for (way, batched) in [false, true].into_iter().enumerate() {
            let start = Instant::now();
            let cpu_start = thread_cpu_s();
            match batch_workload::run(batched) {
                Ok((simulated, digest)) => {
                    wall_s[way] = wall_s[way].min(start.elapsed().as_secs_f64());
                    cpu_s[way] = cpu_s[way].min(thread_cpu_s() - cpu_start);
                    simulated_s = simulated;
                    digests[way] = digest;
                }
                Err(e) => {
                    eprintln!("bench_batch: {e}");
                    std::process::exit(1);
                }
            }
        }
    }
    if digests[0] != digests[1] {
        eprintln!(
            "bench_batch: the batch computed other runs: {} vs {}",
            digests[1], digests[0]
        );
        std::process::exit(1);
    }
    println!(
        "{{\"simulated_s\": {simulated_s}, \"single_wall_s\": {}, \"single_cpu_s\": {}, \"batch_wall_s\": {}, \"batch_cpu_s\": {}, \"digests\": \"{}\"}}",
        wall_s[0], json_number(cpu_s[0]), wall_s[1], json_number(cpu_s[1]), digests[0]
    );
}

fn json_number(v: f64) -> String {
    if v.is_finite() {
        v.to_string()
    } else {
        "null".to_string()
    }
}
