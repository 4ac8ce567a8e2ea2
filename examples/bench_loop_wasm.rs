//! The closed-loop benchmark's workload in wasm: the same run as `examples/bench_loop.rs`
//! (kim-step-doc, fuzzy-dynamics, teach cut and loop), exported to JavaScript so that
//! `scripts/bench/closed_loop.py` can time it under node:
//!
//! ```text
//! cargo build --release --target wasm32-unknown-unknown --example bench_loop_wasm
//! wasm-bindgen --target nodejs --out-dir target/bench-wasm \
//!     target/wasm32-unknown-unknown/release/examples/bench_loop_wasm.wasm
//! node scripts/bench/wasm_loop.mjs target/bench-wasm
//! ```
//!
//! It also exports the batched loop's workload (`examples/common/batch_workload.rs`), which
//! `scripts/bench/wasm_batch.mjs` times one run after another and as one batch.
//!
//! Natively the example is empty (it exists for the wasm build).

#[cfg(target_arch = "wasm32")]
#[path = "common/trace_digest.rs"]
mod trace_digest;

#[cfg(target_arch = "wasm32")]
#[path = "common/batch_workload.rs"]
mod batch_workload;

#[cfg(target_arch = "wasm32")]
mod wasm {
    use wasm_bindgen::prelude::wasm_bindgen;

    use cutlab::closed_loop::definition::RunSpec;
    use cutlab::closed_loop::lab::simulate;
    use cutlab::control::registry::ControllerKind;
    use cutlab::plant::Preset;

    /// Runs the workload once; returns the simulated seconds (teach cut + run), or NaN if the
    /// run failed (the caller reports it).
    #[wasm_bindgen]
    pub fn run_kim_step_doc_fuzzy_dynamics() -> f64 {
        simulate(&RunSpec::new(
            Preset::KimStepDoc,
            ControllerKind::FuzzyDynamics,
        ))
        .map_or(f64::NAN, |r| {
            r.metrics.cycle_time_s + r.calibration.duration_s
        })
    }

    /// The same run's trace digest (`examples/common/trace_digest.rs`), to compare with the
    /// native `bench_loop`'s: a faster wasm build must compute the same run bit for bit.
    #[wasm_bindgen]
    pub fn trace_digest_kim_step_doc_fuzzy_dynamics() -> String {
        simulate(&RunSpec::new(
            Preset::KimStepDoc,
            ControllerKind::FuzzyDynamics,
        ))
        .map_or_else(|e| e.to_string(), |r| super::trace_digest::trace_digest(&r))
    }

    /// The batched loop's workload (`examples/common/batch_workload.rs`) one run after another
    /// (`batched` false) or as one batch; returns the seconds simulated, or NaN if a run failed.
    /// Timed by `scripts/bench/wasm_batch.mjs`.
    #[wasm_bindgen]
    pub fn run_batch_workload(batched: bool) -> f64 {
        super::batch_workload::run(batched).map_or(f64::NAN, |(simulated_s, _)| simulated_s)
    }

    /// The same workload's run digests, joined by commas (or the error).
    #[wasm_bindgen]
    pub fn batch_workload_digests(batched: bool) -> String {
        super::batch_workload::run(batched)
            .unwrap_or_else(|e| (f64::NAN, e))
            .1
    }
}
