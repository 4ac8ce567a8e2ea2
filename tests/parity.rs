//! Native and wasm give the same numbers.
//!
//! Each check computes something with the core and compares it with the value the *native* test
//! suite stored in `tests/reference/parity/native.json`. Natively this guards against silent
//! changes; compiled to wasm32 and run under node (`cargo test --target wasm32-unknown-unknown`)
//! it proves the browser computes what the terminal computes.
//!
//! Tolerances: everything that feeds a simulation (random numbers, filters, the simulated plant)
//! uses IEEE arithmetic and cutlab's own libm-based transcendental functions (`cutlab::math`),
//! which are the same code on both targets, so those checks demand **bit equality**. The FFT comes
//! from rustfft, whose twiddle factors use the platform's `sin`/`cos` (glibc natively, a Rust libm
//! port in wasm); those may differ in the last bit, so spectra are compared to a relative 1e-12 of
//! their largest value, far below any visible or physical difference.
//!
//! To store new native values after an intended change: `CUTLAB_BLESS=1 cargo test --test parity`.
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::rng::Rng;

const STORED: &str = include_str!("reference/parity/native.json");

/// A stable 64-bit digest of a sequence of numbers' exact bits (FNV-1a).
fn digest(values: &[f64]) -> String {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for v in values {
        for byte in v.to_bits().to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    format!("{hash:016x}")
}

/// What one check produced: a digest of every value (for bit equality) and a few values (for
/// tolerance checks and readable failures).
struct Computed {
    name: &'static str,
    values: Vec<f64>,
}

fn stored(name: &str) -> Option<(String, Vec<f64>)> {
    let json: serde_json::Value = serde_json::from_str(STORED).ok()?;
    let entry = json.get(name)?;
    let digest = entry.get("digest")?.as_str()?.to_string();
    let sample = entry
        .get("sample")?
        .as_array()?
        .iter()
        .filter_map(|v| v.as_f64())
        .collect();
    Some((digest, sample))
}

/// Up to 16 evenly spaced values, stored for tolerance checks.
fn sample(values: &[f64]) -> Vec<f64> {
    let step = (values.len() / 16).max(1);
    values.iter().step_by(step).take(16).copied().collect()
}

#[cfg(not(target_arch = "wasm32"))]
fn bless(computed: &[Computed]) {
    let mut map = serde_json::Map::new();
    for c in computed {
        map.insert(
            c.name.to_string(),
            serde_json::json!({ "digest": digest(&c.values), "sample": sample(&c.values), "count": c.values.len() }),
        );
    }
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/reference/parity/native.json"
    );
    let text = serde_json::to_string_pretty(&serde_json::Value::Object(map)).unwrap();
    std::fs::write(path, text + "\n").unwrap();
}

fn rng_stream() -> Computed {
    let mut rng = Rng::seed_from(20_261_122);
    let mut values: Vec<f64> = (0..1000).map(|_| rng.uniform()).collect();
    values.extend((0..1000).map(|_| rng.normal()));
    Computed {
        name: "rng_uniform_and_normal",
        values,
    }
}

fn math_functions() -> Computed {
    let values = (0..2000)
        .flat_map(|i| {
            let x = -50.0 + 0.05 * f64::from(i);
            [
                cutlab::math::sin(x),
                cutlab::math::cos(x),
                cutlab::math::exp(x / 10.0),
                cutlab::math::ln(1.0 + x.abs()),
                cutlab::math::atan2(x, 3.0),
                cutlab::math::pow(1.0 + x.abs(), 0.37),
            ]
        })
        .collect();
    Computed {
        name: "math_libm_functions",
        values,
    }
}

/// A whole closed loop: teach cut, estimator, PI controller, safety envelope, on the simulated
/// mill with sensor noise.
fn closed_loop_run() -> Computed {
    use cutlab::closed_loop::definition::RunSpec;
    use cutlab::closed_loop::lab::simulate;
    use cutlab::control::registry::ControllerKind;
    use cutlab::plant::Preset;
    let result =
        simulate(&RunSpec::new(Preset::ManeeratDoc1, ControllerKind::Pi)).expect("the preset runs");
    let values = result
        .trace
        .rows
        .iter()
        .flat_map(|r| {
            [
                r.time_s,
                r.override_pct,
                r.force_n,
                r.force_est_n,
                r.spindle_current_rms_a,
                r.feed_current_rms_a,
            ]
        })
        .chain(result.trace.terms.iter().copied())
        .collect();
    Computed {
        name: "closed_loop_maneerat_doc_1_pi",
        values,
    }
}

/// Every check, with its tolerance: `None` demands bit equality.
fn checks() -> Vec<(Computed, Option<f64>)> {
    vec![
        (rng_stream(), None),
        (math_functions(), None),
        (closed_loop_run(), None),
    ]
}

#[test]
fn core_computations_match_the_stored_native_values() {
    let checks = checks();
    #[cfg(not(target_arch = "wasm32"))]
    if std::env::var_os("CUTLAB_BLESS").is_some() {
        let computed: Vec<Computed> = checks.into_iter().map(|(c, _)| c).collect();
        bless(&computed);
        return;
    }
    for (computed, tolerance) in checks {
        let (stored_digest, stored_sample) = stored(computed.name).unwrap_or_else(|| {
            panic!(
                "no stored value for {}: run CUTLAB_BLESS=1 cargo test --test parity natively",
                computed.name
            )
        });
        match tolerance {
            None => assert_eq!(
                digest(&computed.values),
                stored_digest,
                "{}: bits differ from the native run; first values now {:?}, stored {:?}",
                computed.name,
                sample(&computed.values),
                stored_sample
            ),
            Some(relative) => {
                let now = sample(&computed.values);
                let scale = stored_sample.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                assert_eq!(now.len(), stored_sample.len(), "{}", computed.name);
                for (a, b) in now.iter().zip(&stored_sample) {
                    assert!(
                        (a - b).abs() <= relative * scale,
                        "{}: {a} vs stored {b}",
                        computed.name
                    );
                }
            }
        }
    }
}
