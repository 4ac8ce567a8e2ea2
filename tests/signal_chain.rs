//! The signal chain end to end on synthetic motor currents, checked against closed forms:
//! three phase currents with switching noise → 10th-order low-pass on all three at once → RMS
//! (three-phase, sliding, detector, per revolution) and d-q current → torque.

// Helpers outside #[test] functions are test code too: a failed unwrap is a failed test.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use std::f64::consts::PI;

use cutlab::rng::Rng;
use cutlab::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use cutlab::signal::decimate::min_max;
use cutlab::signal::dq::{abc_to_dq, PmsmParams, Scaling};
use cutlab::signal::filter::SosFilterBank;
use cutlab::signal::rms::{block_rms, three_phase_rms, RevolutionPeak, RmsDetector, SlidingRms};

const RATE_HZ: f64 = 10_000.0;

/// Phase currents of amplitude `amplitude_a` at electrical frequency `freq_hz`, leading the
/// rotor's d axis by 90° (all q current), with white noise.
fn phase_currents(n: usize, amplitude_a: f64, freq_hz: f64, noise_a: f64) -> (Vec<f64>, Vec<f64>) {
    let mut rng = Rng::seed_from(3);
    let mut interleaved = Vec::with_capacity(3 * n);
    let mut rotor_angle = Vec::with_capacity(n);
    for i in 0..n {
        let theta = 2.0 * PI * freq_hz * i as f64 / RATE_HZ;
        let phi = theta + PI / 2.0;
        for shift in [0.0, -2.0 * PI / 3.0, 2.0 * PI / 3.0] {
            interleaved.push(amplitude_a * (phi + shift).cos() + noise_a * rng.normal());
        }
        rotor_angle.push(theta);
    }
    (interleaved, rotor_angle)
}

#[test]
fn filtered_three_phase_currents_give_rms_dq_and_torque() {
    let n = 20_000;
    let (amplitude, freq) = (8.0, 20.0);
    let (mut currents, theta) = phase_currents(n, amplitude, freq, 0.2);
    let lowpass = butter(&ButterworthSpec {
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: Cutoff::Single(200.0),
        sample_rate_hz: RATE_HZ,
    })
    .unwrap();
    let mut bank = SosFilterBank::new(&lowpass, 3).unwrap();
    bank.process_slice(&mut currents);

    // The low-pass delays the 20 Hz fundamental by its group delay; compare after the start-up,
    // with the filter's phase at 20 Hz taken into account.
    let h = lowpass.frequency_response(&[freq], RATE_HZ)[0];
    let motor = PmsmParams::new(4, 0.08, 0.0015, 0.0015).unwrap();
    for i in (5_000..n).step_by(997) {
        let frame = &currents[3 * i..3 * i + 3];
        let rms = three_phase_rms(frame[0], frame[1], frame[2]);
        assert!(
            (rms - amplitude * h.norm() / 2f64.sqrt()).abs() < 0.15,
            "{rms}"
        );
        let dq = abc_to_dq(
            frame[0],
            frame[1],
            frame[2],
            theta[i] + h.arg(),
            Scaling::AmplitudeInvariant,
        );
        assert!(
            dq.d.abs() < 0.2 && (dq.q - amplitude * h.norm()).abs() < 0.2,
            "{dq:?}"
        );
        let torque = motor.torque_nm(dq, Scaling::AmplitudeInvariant);
        assert!((torque - motor.torque_id_zero_nm(dq.q)).abs() < 1e-12);
        let power = abc_to_dq(
            frame[0],
            frame[1],
            frame[2],
            theta[i] + h.arg(),
            Scaling::PowerInvariant,
        );
        assert!((motor.torque_nm(power, Scaling::PowerInvariant) - torque).abs() < 1e-9);
    }
}

#[test]
fn the_rms_measures_agree_on_a_steady_sine() {
    let n = 40_000;
    let amplitude = 5.0;
    let x: Vec<f64> = (0..n)
        .map(|i| amplitude * (2.0 * PI * 50.0 * i as f64 / RATE_HZ).sin())
        .collect();
    let expected = amplitude / 2f64.sqrt();
    // Whole periods: 200 samples per 50 Hz period.
    assert!((block_rms(&x[..20_000]).unwrap() - expected).abs() < 1e-12);
    let mut sliding = SlidingRms::with_duration(0.02, RATE_HZ).unwrap();
    let mut detector = RmsDetector::butterworth(2, 2.0, RATE_HZ).unwrap();
    let mut last = (0.0, 0.0);
    for &v in &x {
        last = (sliding.process(v), detector.process(v));
    }
    assert!((last.0 - expected).abs() < 1e-9, "{}", last.0);
    assert!((last.1 - expected).abs() < 0.01 * expected, "{}", last.1);
}

#[test]
fn per_revolution_peak_tracks_a_load_that_rises_each_revolution() {
    // Spindle at 1920 rpm sampled at 8192 Hz: exactly 256 samples per revolution.
    let rate = 8192.0;
    let mut peak = RevolutionPeak::new(rate).unwrap();
    let mut held = Vec::new();
    for n in 0..(256 * 6) {
        let revolution = n / 256;
        // One tooth hit per revolution, growing by 1 A each revolution.
        let rms_a = if n % 256 == 100 {
            10.0 + revolution as f64
        } else {
            2.0
        };
        held.push(peak.process(rms_a, 1920.0));
    }
    assert!(held[..255].iter().all(|v| v.is_nan()));
    for r in 0..6 {
        assert_eq!(held[256 * r + 255], 10.0 + r as f64);
    }
    let shown = min_max(
        &held
            .iter()
            .enumerate()
            .map(|(i, v)| (i as f64, *v))
            .collect::<Vec<_>>(),
        8,
    );
    // Before the first whole revolution there is no peak: the plot shows a gap there (the
    // decimation keeps it), and every point after it is a finite peak.
    assert!(shown[0].1.is_nan(), "{shown:?}");
    assert!(shown[1..].iter().all(|p| p.1.is_finite()), "{shown:?}");
    assert_eq!(shown.last().map(|p| p.1), Some(15.0));
}
