//! Butterworth design against scipy: sections, their order and gain placement, and the frequency
//! response, over every kind, orders 1–20, cut-offs from 5 Hz to 10 Hz below Nyquist at 10 kHz.
//!
//! Reference: `tests/reference/signal/design.json`, written by
//! `scripts/reference/signal_reference.py` (`scipy.signal.butter(..., output='sos')` and
//! `freqz_sos`). Tolerances: each coefficient within a relative 1e-9 of scipy's (exact zeros must
//! be exact); each response value within a relative 1e-9 of scipy's, widened by 1e-13 times the
//! condition number of evaluating the sections only where the response is itself ill-conditioned
//! (next to one of its zeros, e.g. a low-pass just below Nyquist, where scipy's value carries the
//! same rounding). Designs whose poles tie in distance to the unit circle (bands centred on
//! f_s/4) are compared by their denominators and response, since scipy's rounding decides their
//! section order.

// Helpers outside #[test] functions are test code too: a failed unwrap is a failed test.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::signal::butterworth::{
    butter, ButterworthSpec, Cutoff, DesignError, FilterKind, MAX_ORDER,
};
use rustfft::num_complex::Complex64;
use serde_json::Value;

const DESIGN: &str = include_str!("reference/signal/design.json");

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("an array")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

fn spec_of(case: &Value) -> ButterworthSpec {
    let cutoffs = numbers(&case["cutoff_hz"]);
    ButterworthSpec {
        kind: case["kind"].as_str().unwrap().parse().unwrap(),
        order: case["order"].as_u64().unwrap() as usize,
        cutoff_hz: match cutoffs.as_slice() {
            [f] => Cutoff::Single(*f),
            [a, b] => Cutoff::Band(*a, *b),
            _ => panic!("one or two cut-offs"),
        },
        sample_rate_hz: case["sample_rate_hz"].as_f64().unwrap(),
    }
}

fn cases() -> Vec<Value> {
    let data: Value = serde_json::from_str(DESIGN).unwrap();
    data["cases"].as_array().unwrap().clone()
}

#[test]
fn every_design_matches_scipy_section_by_section() {
    let cases = cases();
    assert!(cases.len() > 200, "the reference covers the grid");
    let mut worst = 0.0f64;
    let mut compared = 0;
    for case in cases.iter().filter(|c| c["tied_poles"] == false) {
        let spec = spec_of(case);
        let sos = butter(&spec).unwrap_or_else(|e| panic!("{spec:?}: {e}"));
        let expected: Vec<Vec<f64>> = case["sos"]
            .as_array()
            .unwrap()
            .iter()
            .map(numbers)
            .collect();
        assert_eq!(
            sos.sections().len(),
            expected.len(),
            "{spec:?}: section count"
        );
        for (k, (ours, theirs)) in sos.rows().iter().zip(&expected).enumerate() {
            for (j, (a, b)) in ours.iter().zip(theirs).enumerate() {
                if *b == 0.0 {
                    assert_eq!(*a, 0.0, "{spec:?} section {k} coefficient {j}");
                    continue;
                }
                let relative = (a - b).abs() / b.abs();
                worst = worst.max(relative);
                assert!(
                    relative <= 1e-9,
                    "{spec:?} section {k} coefficient {j}: {a} vs scipy {b} (relative {relative:e})"
                );
            }
        }
        compared += 1;
    }
    assert_eq!(
        compared,
        cases.len() - cases.iter().filter(|c| c["tied_poles"] == true).count()
    );
    assert!(compared > 180);
    eprintln!("worst relative coefficient difference from scipy: {worst:e}");
    // The agreement is far better than the tolerance; a jump here means a changed algorithm.
    assert!(worst < 1e-11, "worst relative difference {worst:e}");
}

/// Bands centred on f_s/4 (edges adding up to f_s/2) have mirror-image poles equally close to
/// the unit circle; scipy's rounding picks which goes last. Those designs must give the same
/// filter: the same denominators (as a set) and the same response.
#[test]
fn designs_with_tied_poles_give_the_same_sections_in_some_order() {
    let tied: Vec<Value> = cases()
        .into_iter()
        .filter(|c| c["tied_poles"] == true)
        .collect();
    assert!(
        tied.len() >= 8,
        "the reference includes bands centred on fs/4"
    );
    for case in &tied {
        let spec = spec_of(case);
        let sos = butter(&spec).unwrap();
        let expected: Vec<Vec<f64>> = case["sos"]
            .as_array()
            .unwrap()
            .iter()
            .map(numbers)
            .collect();
        assert_eq!(sos.sections().len(), expected.len());
        for s in sos.sections() {
            let [_, a1, a2] = s.a();
            let found = expected.iter().any(|row| {
                (row[4] - a1).abs() <= 1e-9 * a1.abs().max(1e-300) + 1e-15
                    && (row[5] - a2).abs() <= 1e-9 * a2.abs().max(1e-300) + 1e-15
            });
            assert!(
                found,
                "{spec:?}: denominator [1, {a1}, {a2}] is not one of scipy's"
            );
        }
        let rows: Vec<[f64; 6]> = expected
            .iter()
            .map(|r| [r[0], r[1], r[2], r[3], r[4], r[5]])
            .collect();
        let theirs = cutlab::signal::sos::Sos::from_rows(&rows).unwrap();
        let nyquist = spec.nyquist_hz();
        let freqs: Vec<f64> = (1..200).map(|i| nyquist * i as f64 / 200.0).collect();
        assert_responses_agree(
            &sos,
            &theirs.frequency_response(&freqs, spec.sample_rate_hz),
            &freqs,
            &spec,
        );
    }
}

/// Relative condition of evaluating one section at `z⁻¹`: Σ|b|/|B(z)| + Σ|a|/|A(z)|. Rounding
/// makes any evaluation (scipy's too) wrong by about ε times this, relative.
fn condition(sos: &cutlab::signal::sos::Sos, freq_hz: f64, sample_rate_hz: f64) -> f64 {
    let omega = 2.0 * std::f64::consts::PI * freq_hz / sample_rate_hz;
    let z1 = Complex64::new(omega.cos(), -omega.sin());
    let z2 = z1 * z1;
    sos.sections()
        .iter()
        .map(|s| {
            let [b0, b1, b2] = s.b();
            let [a0, a1, a2] = s.a();
            let b = (z2 * b2 + z1 * b1 + b0).norm();
            let a = (z2 * a2 + z1 * a1 + a0).norm();
            (b0.abs() + b1.abs() + b2.abs()) / b + (a0.abs() + a1.abs() + a2.abs()) / a
        })
        .sum()
}

fn assert_responses_agree(
    sos: &cutlab::signal::sos::Sos,
    reference: &[Complex64],
    freqs: &[f64],
    spec: &ButterworthSpec,
) {
    let ours = sos.frequency_response(freqs, spec.sample_rate_hz);
    for ((h, theirs), f) in ours.iter().zip(reference).zip(freqs) {
        let error = (h - theirs).norm();
        // 1e-9 relative, widened only where the value itself is ill-conditioned (next to a zero
        // of the response, e.g. a low-pass just below Nyquist).
        let relative = 1e-9 + 1e-13 * condition(sos, *f, spec.sample_rate_hz);
        assert!(
            error == 0.0 || error <= relative * theirs.norm() + 1e-300,
            "{spec:?} at {f} Hz: {h} vs {theirs} (relative error {:e}, allowed {relative:e})",
            error / theirs.norm()
        );
    }
}

#[test]
fn frequency_responses_match_scipy_freqz_sos() {
    let mut checked = 0;
    for case in cases().iter().filter(|c| c.get("response").is_some()) {
        let spec = spec_of(case);
        let sos = butter(&spec).unwrap();
        let response = &case["response"];
        let freqs = numbers(&response["freq_hz"]);
        let re = numbers(&response["re"]);
        let im = numbers(&response["im"]);
        let theirs: Vec<Complex64> = re
            .iter()
            .zip(&im)
            .map(|(r, i)| Complex64::new(*r, *i))
            .collect();
        assert_responses_agree(&sos, &theirs, &freqs, &spec);
        checked += freqs.len();
    }
    assert!(checked > 900, "{checked}");
}

#[test]
fn the_papers_filters_are_among_the_references() {
    // Paper 000: 10th order, 5 Hz at 10 kHz (unstable as one polynomial, fine as sections).
    // Paper 003: 50 Hz feed-motor and 260 Hz spindle-motor filters.
    for (order, cutoff) in [(10, 5.0), (2, 50.0), (2, 260.0)] {
        let found = cases().iter().any(|c| {
            c["kind"] == "lowpass"
                && c["order"] == order
                && numbers(&c["cutoff_hz"]) == [cutoff]
                && c["sample_rate_hz"] == 10_000.0
        });
        assert!(found, "order {order}, {cutoff} Hz");
    }
    let spec = ButterworthSpec {
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: Cutoff::Single(5.0),
        sample_rate_hz: 10_000.0,
    };
    let sos = butter(&spec).unwrap();
    // Every section is stable: |a2| < 1 and |a1| < 1 + a2.
    for s in sos.sections() {
        let [_, a1, a2] = s.a();
        assert!(a2.abs() < 1.0 && a1.abs() < 1.0 + a2, "{a1} {a2}");
    }
}

#[test]
fn every_kind_and_order_designs_without_error() {
    for kind in FilterKind::ALL {
        for order in 1..=MAX_ORDER {
            let cutoff_hz = if kind.is_band() {
                Cutoff::Band(100.0, 900.0)
            } else {
                Cutoff::Single(300.0)
            };
            let spec = ButterworthSpec {
                kind,
                order,
                cutoff_hz,
                sample_rate_hz: 2_000.0,
            };
            let sos = butter(&spec).unwrap();
            let poles = if kind.is_band() { 2 * order } else { order };
            assert_eq!(sos.sections().len(), poles.div_ceil(2), "{kind} {order}");
        }
    }
}

#[test]
fn bad_arguments_are_errors_with_a_message_never_a_panic() {
    let base = ButterworthSpec {
        kind: FilterKind::Lowpass,
        order: 4,
        cutoff_hz: Cutoff::Single(100.0),
        sample_rate_hz: 10_000.0,
    };
    let cases: Vec<(ButterworthSpec, &str)> = vec![
        (ButterworthSpec { order: 0, ..base }, "order"),
        (ButterworthSpec { order: 21, ..base }, "order"),
        (
            ButterworthSpec {
                order: usize::MAX,
                ..base
            },
            "order",
        ),
        (
            ButterworthSpec {
                sample_rate_hz: -1.0,
                ..base
            },
            "sample rate",
        ),
        (
            ButterworthSpec {
                sample_rate_hz: f64::INFINITY,
                ..base
            },
            "sample rate",
        ),
        (
            ButterworthSpec {
                cutoff_hz: Cutoff::Single(5_000.0),
                ..base
            },
            "Nyquist",
        ),
        (
            ButterworthSpec {
                cutoff_hz: Cutoff::Single(7_000.0),
                ..base
            },
            "Nyquist",
        ),
        (
            ButterworthSpec {
                cutoff_hz: Cutoff::Single(0.0),
                ..base
            },
            "cut-off",
        ),
        (
            ButterworthSpec {
                cutoff_hz: Cutoff::Single(f64::NAN),
                ..base
            },
            "cut-off",
        ),
        (
            ButterworthSpec {
                kind: FilterKind::Bandpass,
                cutoff_hz: Cutoff::Band(10.0, 5_000.0),
                ..base
            },
            "upper cut-off",
        ),
        (
            ButterworthSpec {
                kind: FilterKind::Bandstop,
                cutoff_hz: Cutoff::Band(f64::NEG_INFINITY, 50.0),
                ..base
            },
            "lower cut-off",
        ),
        (
            ButterworthSpec {
                kind: FilterKind::Bandpass,
                cutoff_hz: Cutoff::Band(500.0, 400.0),
                ..base
            },
            "upper cut-off",
        ),
        (
            ButterworthSpec {
                kind: FilterKind::Bandpass,
                cutoff_hz: Cutoff::Single(500.0),
                ..base
            },
            "lower and an upper",
        ),
        (
            ButterworthSpec {
                cutoff_hz: Cutoff::Band(1.0, 2.0),
                ..base
            },
            "one cut-off",
        ),
    ];
    for (spec, field) in cases {
        let error: DesignError = butter(&spec).unwrap_err();
        let message = error.to_string();
        assert!(
            message.contains(field),
            "{spec:?}: {message:?} should name {field:?}"
        );
        assert!(!message.contains('\n'));
    }
}

#[test]
fn kind_registry_round_trips() {
    for kind in FilterKind::ALL {
        assert_eq!(kind.name().parse::<FilterKind>().unwrap(), kind);
        assert_eq!(kind.label().parse::<FilterKind>().unwrap(), kind);
        assert_eq!(kind.to_string(), kind.name());
    }
    let labels: Vec<&str> = FilterKind::ALL.iter().map(|k| k.label()).collect();
    assert_eq!(labels, ["Low-pass", "High-pass", "Band-pass", "Band-stop"]);
    let e = "allpass".parse::<FilterKind>().unwrap_err();
    assert!(e
        .to_string()
        .contains("lowpass, highpass, bandpass, bandstop"));
}

/// FNV-1a over the exact bits of a sequence of numbers.
fn digest(values: &[f64]) -> u64 {
    let mut hash: u64 = 0xcbf2_9ce4_8422_2325;
    for v in values {
        for byte in v.to_bits().to_le_bytes() {
            hash ^= u64::from(byte);
            hash = hash.wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    hash
}

/// Designs and filtering use only IEEE arithmetic and cutlab's libm functions, so the bits are
/// the same natively and in wasm. The digests were taken natively; under wasm this proves the
/// browser designs the very same filters.
#[test]
fn design_and_filtering_bits_are_the_same_on_every_target() {
    let designs = [
        (FilterKind::Lowpass, 10, Cutoff::Single(5.0)),
        (FilterKind::Bandpass, 7, Cutoff::Band(40.0, 400.0)),
        (FilterKind::Bandstop, 3, Cutoff::Band(45.0, 55.0)),
        (FilterKind::Highpass, 20, Cutoff::Single(4_990.0)),
    ];
    let mut coefficients = Vec::new();
    let mut outputs = Vec::new();
    for (kind, order, cutoff_hz) in designs {
        let sos = butter(&ButterworthSpec {
            kind,
            order,
            cutoff_hz,
            sample_rate_hz: 10_000.0,
        })
        .unwrap();
        coefficients.extend(sos.rows().iter().flatten());
        let x: Vec<f64> = (0..500)
            .map(|i| ((i * 37) % 101) as f64 / 50.0 - 1.0)
            .collect();
        outputs.extend(cutlab::signal::filter::sosfilt(&sos, &x));
        outputs.extend(cutlab::signal::filtfilt::filtfilt(&sos, &x).unwrap());
    }
    let found = (digest(&coefficients), digest(&outputs));
    eprintln!("digests: {:#018x} {:#018x}", found.0, found.1);
    assert_eq!(found, (0x7397_9079_3586_f686, 0xe665_279a_90a8_91c6));
}
