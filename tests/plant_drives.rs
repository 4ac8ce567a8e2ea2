//! Drives and sensors against closed forms and the papers: the balanced three-phase RMS, paper
//! 000's brake bench (RMS current linear in load with an idle offset, 4 Hz, hysteresis, idle
//! current rising with feed), the feed servo's 40 Hz response, paper 003's spindle (gear-change
//! discontinuity at 900 rpm, sensitivity rising with speed, F/V converter, start current), and
//! paper 000's Hall sensor scale.
// Helpers outside #[test] functions unwrap too: a failed parse is a failed test.
#![allow(clippy::unwrap_used)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::machine::{Machine, OverrideCommand};
use cutlab::plant::bench::{BenchFrictionConfig, BrakeBench, BrakeBenchConfig};
use cutlab::plant::feed_drive::{
    three_phase_rms_a, FeedDrive, FeedDriveConfig, ThreePhaseWaveform,
};
use cutlab::plant::sensors::{CurrentSensor, CurrentSensorConfig, HallSensorConfig};
use cutlab::plant::spindle_drive::{SpindleDrive, SpindleDriveConfig, SpindleGear};
use cutlab::plant::Plant;

fn assert_close(what: &str, got: f64, want: f64, tol: f64) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: got {got}, want {want} (tolerance {tol})"
    );
}

/// Least-squares line y = a + b·x; returns (a, b, r²).
fn fit_line(x: &[f64], y: &[f64]) -> (f64, f64, f64) {
    let n = x.len() as f64;
    let mx = x.iter().sum::<f64>() / n;
    let my = y.iter().sum::<f64>() / n;
    let sxy: f64 = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: f64 = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let syy: f64 = y.iter().map(|b| (b - my) * (b - my)).sum();
    let b = sxy / sxx;
    (my - b * mx, b, sxy * sxy / (sxx * syy))
}

#[test]
fn balanced_three_phase_rms_is_amplitude_over_root_two() {
    let clean = ThreePhaseWaveform::new(0.0, 0.0);
    for k in 0..360 {
        let i = clean.currents(4.0, f64::from(k).to_radians());
        assert_close("eq 5", i[0] + i[1] + i[2], 0.0, 1e-12);
        assert_close("eq 7", three_phase_rms_a(i), 4.0 / 2f64.sqrt(), 1e-12);
    }
    // The feed drive's own currents at a steady load, harmonics off.
    let cfg = FeedDriveConfig {
        harmonic_5th: 0.0,
        harmonic_7th: 0.0,
        ..FeedDriveConfig::default()
    };
    let mut axis = FeedDrive::new(cfg, 1e-3).unwrap();
    let mut out = axis.step(600.0, 800.0, 0.0);
    for _ in 0..2000 {
        out = axis.step(600.0, 800.0, 0.0);
    }
    let amplitude = cfg.steady_torque_nm(800.0, 600.0) / cfg.torque_constant_nm_per_a();
    assert_close("i_q", out.iq_a, amplitude, 1e-9);
    assert_close(
        "drive eq 7",
        three_phase_rms_a(out.phase_currents_a),
        amplitude / 2f64.sqrt(),
        1e-9,
    );
}

/// The bench at 2 kHz with 1.5 s steps (4 Hz: the last second of each step is four periods).
/// A short schedule on an ideal bench (no friction wander or drift), where paper 000's closed
/// form holds exactly.
fn short_bench() -> BrakeBenchConfig {
    BrakeBenchConfig {
        sample_rate_hz: 2000.0,
        step_duration_s: 1.5,
        seed: 11,
        friction: BenchFrictionConfig::IDEAL,
        ..BrakeBenchConfig::default()
    }
}

/// (brake torque, RMS of the sensed phase currents over the last second) for every step.
fn bench_steps(cfg: &BrakeBenchConfig) -> Vec<(f64, f64)> {
    let mut bench = BrakeBench::new(cfg.clone()).unwrap();
    let per_step = (cfg.step_duration_s * cfg.sample_rate_hz).round() as usize;
    let window = cfg.sample_rate_hz as usize; // 1 s
    let mut out = Vec::new();
    for _ in &cfg.excitation_steps_a {
        let mut sum_sq = 0.0;
        let mut torque = 0.0;
        for k in 0..per_step {
            let s = bench.step(OverrideCommand::default());
            if k >= per_step - window {
                let i = s.sensors.feed_phase_currents_a;
                sum_sq += (i[0] * i[0] + i[1] * i[1] + i[2] * i[2]) / 3.0;
            }
            // (The step's last sample lands at its end, t = (k + 1)·T, already on the next level.)
            if k == per_step - window {
                torque = bench.signals().brake_torque_nm;
            }
        }
        out.push((torque, (sum_sq / window as f64).sqrt()));
    }
    out
}

#[test]
fn brake_bench_rms_current_is_linear_in_load_with_the_idle_offset() {
    let cfg = short_bench();
    let steps = bench_steps(&cfg);
    let rising = &steps[..11];
    let x: Vec<f64> = rising.iter().map(|s| s.0).collect();
    let y: Vec<f64> = rising.iter().map(|s| s.1).collect();
    let (idle, slope, r2) = fit_line(&x, &y);
    let fd = &cfg.feed_drive;
    let per_amp = ThreePhaseWaveform::new(fd.harmonic_5th, fd.harmonic_7th).rms_per_amplitude();
    // Paper 000 eq 9 / Fig. 11: I_rms = (T_idle + T_load)/K_t · √(1 + h5² + h7²)/√2.
    assert_close(
        "slope A per N·m",
        slope,
        per_amp / fd.torque_constant_nm_per_a(),
        0.005 * slope,
    );
    assert_close(
        "idle offset A",
        idle,
        fd.idle_rms_current_a(cfg.feed_mm_min),
        0.01 * idle,
    );
    assert!(
        idle > 0.2,
        "the idle current is not zero (paper 000): {idle}"
    );
    assert!(r2 > 0.9999, "r² {r2}");
    // Hysteresis (Fig. 5): unloading carries more torque, hence more current, than loading.
    for k in 1..10 {
        let (up, down) = (steps[k], steps[20 - k]);
        assert!(
            down.0 > up.0 && down.1 > up.1,
            "step {k}: {up:?} vs {down:?}"
        );
    }
}

/// A real bench's points scatter about the line (paper 000 Fig. 11): with the default friction
/// wander and warm-up drift the fit is good but not perfect, the ideal bench's is exact.
#[test]
fn a_real_benchs_friction_scatters_the_points_about_the_line() {
    let r2 = |friction| {
        let cfg = BrakeBenchConfig {
            friction,
            step_duration_s: 3.0,
            ..short_bench()
        };
        let steps = bench_steps(&cfg);
        let x: Vec<f64> = steps.iter().map(|s| s.0).collect();
        let y: Vec<f64> = steps.iter().map(|s| s.1).collect();
        fit_line(&x, &y).2
    };
    let ideal = r2(BenchFrictionConfig::IDEAL);
    let real = r2(BenchFrictionConfig::default());
    // Loading and unloading differ by the brake's hysteresis alone on the ideal bench.
    assert!(ideal > 0.9999, "ideal r² {ideal}");
    assert!(real > 0.98 && real < 0.9995, "real r² {real}");
}

#[test]
fn bench_phase_current_has_the_4_hz_fundamental_of_paper_000_fig_9() {
    let cfg = BrakeBenchConfig {
        sample_rate_hz: 2000.0,
        excitation_steps_a: vec![0.5],
        step_duration_s: 4.0,
        ..BrakeBenchConfig::default()
    };
    let mut bench = BrakeBench::new(cfg).unwrap();
    let mut crossings = 0;
    let mut last = 0.0;
    for k in 0..8000 {
        bench.step(OverrideCommand::default());
        let i = bench.signals().axis_x.phase_currents_a[0];
        if k >= 4000 && (i > 0.0) != (last > 0.0) {
            crossings += 1;
        }
        last = i;
    }
    // 2 s at 4 Hz: 16 zero crossings of the fundamental (the 5th and 7th are too small to add).
    assert_eq!(crossings, 16);
}

#[test]
fn idle_current_rises_with_feed_speed_as_in_paper_000_fig_12() {
    let cfg = FeedDriveConfig::default();
    let dt = 1e-3;
    let mut last = 0.0;
    for speed in [50.0, 100.0, 150.0, 200.0] {
        let mut axis = FeedDrive::new(cfg, dt).unwrap();
        // One electrical period: p·v/(60·L₀) Hz.
        let period_s = 60.0 * cfg.screw_pitch_mm / (f64::from(cfg.pole_pairs) * speed);
        for _ in 0..500 {
            axis.step(speed, 0.0, 0.0);
        }
        let n = (period_s / dt).round() as usize;
        let mut sum_sq = 0.0;
        for _ in 0..n {
            let i = axis.step(speed, 0.0, 0.0).phase_currents_a;
            sum_sq += (i[0] * i[0] + i[1] * i[1] + i[2] * i[2]) / 3.0;
        }
        let rms = (sum_sq / n as f64).sqrt();
        assert_close("idle", rms, cfg.idle_rms_current_a(speed), 1e-3 * rms);
        assert!(rms > last);
        last = rms;
    }
}

#[test]
fn feed_current_follows_a_40_hz_load_with_the_servo_gain() {
    // At its natural frequency a second-order lag passes 1/(2ζ) of the input.
    let cfg = FeedDriveConfig::default();
    let dt = 1e-4;
    let mut axis = FeedDrive::new(cfg, dt).unwrap();
    let (mut demand_max, mut torque_max) = (f64::MIN, f64::MIN);
    let (mut demand_min, mut torque_min) = (f64::MAX, f64::MAX);
    for k in 0..20_000 {
        let t = k as f64 * dt;
        let load = 500.0 * (std::f64::consts::TAU * 40.0 * t).sin();
        let out = axis.step(300.0, load, 0.0);
        if t > 1.0 {
            demand_max = demand_max.max(out.torque_demand_nm);
            demand_min = demand_min.min(out.torque_demand_nm);
            torque_max = torque_max.max(out.torque_nm);
            torque_min = torque_min.min(out.torque_nm);
        }
    }
    let gain = (torque_max - torque_min) / (demand_max - demand_min);
    assert_close(
        "gain at 40 Hz",
        gain,
        1.0 / (2.0 * cfg.servo_damping_ratio),
        0.005,
    );
}

fn steady_spindle_current(
    cfg: SpindleDriveConfig,
    rpm: f64,
    torque: f64,
) -> (f64, Option<SpindleGear>) {
    let mut d = SpindleDrive::new(cfg, 1e-3).unwrap();
    let mut out = d.step(rpm, 0.0);
    for _ in 0..4000 {
        out = d.step(rpm, 0.0);
    }
    for _ in 0..3000 {
        out = d.step(rpm, torque);
    }
    (out.rms_current_a, out.gear)
}

#[test]
fn spindle_sensitivity_jumps_at_the_900_rpm_gear_change() {
    let cfg = SpindleDriveConfig::default();
    let below = cfg.sensitivity_a_per_nm(899.999);
    let above = cfg.sensitivity_a_per_nm(900.0);
    // High gear 1:4.81 field-weakened at 4329 rpm; low gear 1:1.157 at 1041 rpm below base.
    let expected_jump = cfg.base_speed_rpm / (900.0 * cfg.low_gear_ratio);
    assert_close("jump", above / below, expected_jump, 1e-5);
    assert!(above / below > 1.4);
    // The simulated drive shows the same slopes.
    for (rpm, gear) in [(899.0, SpindleGear::High), (900.0, SpindleGear::Low)] {
        let (idle, g0) = steady_spindle_current(cfg, rpm, 0.0);
        let (loaded, g1) = steady_spindle_current(cfg, rpm, 10.0);
        assert_eq!((g0, g1), (Some(gear), Some(gear)));
        let slope = (loaded - idle) / 10.0;
        assert_close(
            "simulated S(n)",
            slope,
            cfg.sensitivity_a_per_nm(rpm),
            2e-3 * slope,
        );
        assert_close("idle", idle, cfg.idle_current_a(rpm), 2e-3 * idle);
    }
}

#[test]
fn spindle_sensitivity_rises_with_speed_within_each_gear() {
    let cfg = SpindleDriveConfig::default();
    let s = |n: f64| cfg.sensitivity_a_per_nm(n);
    for w in [300.0, 500.0, 700.0, 899.0].windows(2) {
        assert!(s(w[1]) > s(w[0]), "high gear {w:?}");
    }
    for w in [1300.0, 2000.0, 3000.0, 5000.0].windows(2) {
        assert!(s(w[1]) > s(w[0]), "low gear {w:?}");
    }
    // Between 900 rpm and n_b/1.157 = 1296 rpm the low gear runs below base speed: flat.
    assert_close("flat", s(1200.0), s(900.0), 1e-12);
}

#[test]
fn fv_voltage_is_proportional_to_speed_within_each_gear() {
    let cfg = SpindleDriveConfig::default();
    let mut d = SpindleDrive::new(cfg, 1e-3).unwrap();
    for rpm in [300.0, 600.0, 1000.0, 3000.0] {
        let mut out = d.step(rpm, 0.0);
        for _ in 0..8000 {
            out = d.step(rpm, 0.0);
        }
        let ratio = cfg.ratio(cfg.gear_for(rpm));
        assert_close(
            "F/V",
            out.fv_voltage_v,
            cfg.fv_volts_per_krpm * ratio * rpm * 1e-3,
            1e-3,
        );
    }
    // Volts per rpm differ by the gear ratio between the ranges (Fig. 4).
    let low = cfg.fv_voltage_v(600.0) / 600.0;
    let high = cfg.fv_voltage_v(3000.0) / 3000.0;
    assert_close("slope ratio", low / high, 4.81 / 1.157, 1e-12);
}

#[test]
fn spindle_start_draws_a_large_current_that_ends_within_paper_003s_3_s() {
    let cfg = SpindleDriveConfig::default();
    let dt = 1e-3;
    let mut d = SpindleDrive::new(cfg, dt).unwrap();
    let idle = cfg.idle_current_a(3000.0);
    let mut peak = 0.0f64;
    let mut settled_at = f64::NAN;
    for k in 1..=5000 {
        let out = d.step(3000.0, 0.0);
        peak = peak.max(out.rms_current_a);
        if settled_at.is_nan() && k > 100 && (out.rms_current_a - idle).abs() < 0.02 * idle {
            settled_at = k as f64 * dt;
        }
    }
    assert!(peak > 5.0 * idle, "start {peak} A vs idle {idle} A");
    assert!(settled_at < 3.0, "settled at {settled_at} s");
}

#[test]
fn paper_000_hall_sensor_reads_through_its_500_ohm_burden() {
    let hall = HallSensorConfig::paper_000_feed();
    // 6 A → 25 mA → 12.5 V across 500 Ω.
    assert_close("V per A", hall.volts_per_amp() * 6.0, 12.5, 1e-12);
    let cfg = CurrentSensorConfig::feed();
    let mut s = CurrentSensor::new(cfg, 1e-4, 5, 0).unwrap();
    let mut r = [0.0; 3];
    for _ in 0..100 {
        r = s.read([3.0, -1.0, -2.0]);
    }
    let lsb_a = cfg.adc.lsb_v() / hall.volts_per_amp();
    // Offset + 4σ noise + half an LSB.
    let tol = hall.offsets_a[0].abs() + 4.0 * hall.noise_a + lsb_a;
    assert_close("u", r[0], 3.0, tol);
    assert_close("w = −(u + v)", r[2], -(r[0] + r[1]), 1e-12);
}

#[test]
fn the_estimator_and_the_drive_agree_on_the_gear_at_the_change_speed() {
    use cutlab::estimation::speed::in_high_speed_range;
    let c = SpindleDriveConfig::default();
    for rpm in [
        c.gear_change_rpm - 0.1,
        c.gear_change_rpm,
        c.gear_change_rpm + 0.1,
    ] {
        let drive_high_speed = c.gear_for(rpm) == SpindleGear::Low;
        assert_eq!(
            in_high_speed_range(rpm, c.gear_change_rpm),
            drive_high_speed,
            "{rpm} rpm"
        );
    }
}
