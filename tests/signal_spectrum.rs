//! Spectra: Welch's PSD against `scipy.signal.welch` (defaults: periodic Hann, 50 % overlap,
//! constant detrend, density, one-sided, mean) for even, odd and too-long segments; amplitude
//! scaling of the windowed amplitude spectrum; peaks and milling markers; uneven time steps.
//!
//! Reference: `tests/reference/signal/welch.json`, written by
//! `scripts/reference/signal_reference.py`. Tolerance: each PSD bin within a relative 1e-9 of
//! scipy's; frequencies within 1e-12 relative.

// Helpers outside #[test] functions are test code too: a failed unwrap is a failed test.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::signal::spectrum::{
    amplitude_spectrum, amplitude_spectrum_of_log, find_peaks, milling_markers, welch,
    welch_of_log, MarkerKind, SpectrumError, Window,
};
use serde_json::Value;

const WELCH: &str = include_str!("reference/signal/welch.json");

/// The reference script's test signal (see tests/signal_filtering.rs).
fn test_signal(n: usize) -> Vec<f64> {
    let mut state: u64 = 12345;
    (0..n)
        .map(|i| {
            state = (1_664_525 * state + 1_013_904_223) % (1 << 32);
            let noise = (state >> 8) as f64 / (1u64 << 24) as f64 - 0.5;
            let p = i % 250;
            let tri = (if p < 125 { p } else { 250 - p }) as f64 / 32.0 - 2.0;
            let step = if i >= 600 { 3.0 } else { 0.0 };
            tri + noise + step
        })
        .collect()
}

fn numbers(v: &Value) -> Vec<f64> {
    v.as_array()
        .expect("an array")
        .iter()
        .map(|x| x.as_f64().expect("a number"))
        .collect()
}

#[test]
fn welch_matches_scipy_for_even_odd_and_too_long_segments() {
    let data: Value = serde_json::from_str(WELCH).unwrap();
    let rate = data["sample_rate_hz"].as_f64().unwrap();
    let x = test_signal(3000);
    let mut worst = 0.0f64;
    for case in data["cases"].as_array().unwrap() {
        let nperseg = case["nperseg"].as_u64().unwrap() as usize;
        let length = case["length"].as_u64().unwrap() as usize;
        let psd = welch(&x[..length], rate, nperseg).unwrap();
        let freq = numbers(&case["freq_hz"]);
        let expected = numbers(&case["psd"]);
        assert_eq!(psd.freq_hz.len(), freq.len(), "nperseg {nperseg}");
        assert_eq!(psd.segment_len, nperseg.min(length));
        for (a, b) in psd.freq_hz.iter().zip(&freq) {
            assert!(
                (a - b).abs() <= 1e-12 * b.abs(),
                "nperseg {nperseg}: {a} Hz vs {b} Hz"
            );
        }
        for (k, (a, b)) in psd.psd.iter().zip(&expected).enumerate() {
            let relative = (a - b).abs() / b.abs();
            worst = worst.max(relative);
            assert!(
                relative <= 1e-9,
                "nperseg {nperseg}, bin {k}: {a} vs scipy {b}"
            );
        }
    }
    eprintln!("welch: worst relative difference from scipy {worst:.1e}");
}

#[test]
fn amplitude_spectrum_reads_amplitudes_with_every_window() {
    let rate = 2000.0;
    let n = 4000; // 0.5 Hz bins
    for window in Window::ALL {
        // 4 Hz (paper 000's load peak) at 1.5 A, 50 Hz at 0.25 A, 0.2 A DC.
        let x: Vec<f64> = (0..n)
            .map(|i| {
                let t = i as f64 / rate;
                0.2 + 1.5 * (2.0 * std::f64::consts::PI * 4.0 * t).cos()
                    + 0.25 * (2.0 * std::f64::consts::PI * 50.0 * t).sin()
            })
            .collect();
        let s = amplitude_spectrum(&x, rate, window).unwrap();
        assert_eq!(s.freq_hz.len(), n / 2 + 1);
        assert_eq!(*s.freq_hz.last().unwrap(), 1000.0);
        let at = |f: f64| s.amplitude[(f / 0.5) as usize];
        assert!((at(4.0) - 1.5).abs() < 1e-9, "{window:?}: {}", at(4.0));
        assert!((at(50.0) - 0.25).abs() < 1e-9);
        assert!((s.amplitude[0] - 0.2).abs() < 1e-9);
        let peaks = find_peaks(&s.freq_hz, &s.amplitude, 2.0, 2);
        assert_eq!(peaks[0].freq_hz, 4.0, "{window:?}");
        assert_eq!(peaks[1].freq_hz, 50.0);
    }
}

#[test]
fn nyquist_bin_is_not_doubled() {
    // Alternating ±1 is a cosine at Nyquist with amplitude 1.
    let x: Vec<f64> = (0..64)
        .map(|i| if i % 2 == 0 { 1.0 } else { -1.0 })
        .collect();
    let s = amplitude_spectrum(&x, 100.0, Window::Rectangular).unwrap();
    assert!((s.amplitude[32] - 1.0).abs() < 1e-12);
    assert_eq!(s.freq_hz[32], 50.0);
}

#[test]
fn uneven_time_steps_are_reported_not_assumed_even() {
    let mut t: Vec<f64> = (0..1000).map(|i| i as f64 * 1e-4).collect();
    let x: Vec<f64> = t.iter().map(|t| (t * 300.0).sin()).collect();
    assert!(amplitude_spectrum_of_log(&t, &x, Window::Hann).is_ok());
    assert!(welch_of_log(&t, &x, 128).is_ok());
    // A logging pause of 3 samples at index 400.
    for v in t.iter_mut().skip(400) {
        *v += 3e-4;
    }
    let e = welch_of_log(&t, &x, 128).unwrap_err();
    assert!(
        matches!(e, SpectrumError::UnevenTimeSteps { index: 400, .. }),
        "{e:?}"
    );
    assert!(e.to_string().contains("time stamp 400"), "{e}");
}

#[test]
fn markers_follow_spindle_speed_and_teeth() {
    // Paper 001: Ø10 mm end mill at 3000 rpm; a 4-tooth cutter passes teeth at 200 Hz.
    let markers = milling_markers(3000.0, 4, 1000.0, 20);
    let teeth: Vec<f64> = markers
        .iter()
        .filter(|m| m.kind == MarkerKind::ToothPassing)
        .map(|m| m.freq_hz)
        .collect();
    assert_eq!(teeth, [200.0, 400.0, 600.0, 800.0, 1000.0]);
    assert_eq!(markers[0].freq_hz, 50.0);
    assert_eq!(markers[0].label, "spindle 1×");
    assert!(markers.windows(2).all(|w| w[0].freq_hz < w[1].freq_hz));
}

#[test]
fn bad_spectrum_arguments_are_errors() {
    assert!(amplitude_spectrum(&[1.0], 100.0, Window::Hann).is_err());
    assert!(amplitude_spectrum(&[1.0, 2.0], f64::NAN, Window::Hann).is_err());
    assert!(welch(&[1.0; 10], 100.0, 0).is_err());
    assert!("kaiser".parse::<Window>().is_err());
    for w in Window::ALL {
        assert_eq!(w.label().parse::<Window>().unwrap(), w);
    }
}
