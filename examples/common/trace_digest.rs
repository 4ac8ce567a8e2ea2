//! A digest of a run's trace, so the benchmarks can show that a faster build (another profile,
//! another target feature) computes the same run bit for bit, natively and in wasm.

use cutlab::closed_loop::lab::RunResult;

/// FNV-1a over the exact bits of every row's time, measured and estimated force, override and
/// feed, and the run's cycle time and calibration (the same hash as tests/parity.rs).
pub fn trace_digest(result: &RunResult) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    let mut eat = |v: f64| {
        for byte in v.to_bits().to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    };
    for r in &result.trace.rows {
        for v in [
            r.time_s,
            r.force_n,
            r.force_est_n,
            r.override_pct,
            r.feed_mm_min,
        ] {
            eat(v);
        }
    }
    eat(result.metrics.cycle_time_s);
    eat(result.calibration.duration_s);
    format!("{hash:016x}")
}
