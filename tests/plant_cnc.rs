//! The simulated FANUC control: override modes (paper 000's 16-position dial on X20.7, X20.4,
//! X20.3, X20.2; paper 003's 0–255 % in 1 % steps; continuous), the PMC scan, feed × override
//! with acceleration limits, feed hold, and the corner stop behind paper 003 Fig. 13's dip.
// Helpers outside #[test] functions unwrap too: a failed parse is a failed test.
#![allow(clippy::unwrap_used)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::machine::{Machine, OverrideCommand};
use cutlab::plant::cnc::{CncConfig, DialTable, OverrideMode, PmcInputs};
use cutlab::plant::materials::Material;
use cutlab::plant::mechanics::{mean_forces, Cutter, Immersion, MillingMode};
use cutlab::plant::scenario::{MaterialRegion, Move, Scenario, ScenarioSpec};
use cutlab::plant::simulator::{SimConfig, Simulator};
use cutlab::plant::{Plant, Preset};

const RATE_HZ: f64 = 2000.0;

fn slot_scenario(feed_mm_min: f64, rpm: f64) -> Scenario {
    Scenario::new(ScenarioSpec {
        name: "slot".into(),
        start_mm: [0.0, 0.0],
        moves: vec![Move::line([200.0, 0.0], feed_mm_min, rpm)],
        cutter: Cutter::new(20.0, 2, 30.0).unwrap(),
        mode: MillingMode::Slot,
        depth_mm: vec![(0.0, 3.0)],
        width_mm: vec![(0.0, 20.0)],
        materials: vec![MaterialRegion {
            from_mm: 1.0,
            to_mm: 200.0,
            material: Material::Sm45c,
        }],
        spindle_start_dwell_s: 0.0,
    })
    .unwrap()
}

fn machine(mode: OverrideMode) -> Simulator {
    let config = SimConfig {
        sample_rate_hz: RATE_HZ,
        cnc: CncConfig {
            override_mode: mode,
            ..CncConfig::default()
        },
        ..SimConfig::with_seed(3)
    };
    Simulator::new(slot_scenario(600.0, 1000.0), config).unwrap()
}

fn command(pct: f64) -> OverrideCommand {
    OverrideCommand {
        override_pct: pct,
        feed_hold: false,
    }
}

#[test]
fn dial_mode_applies_the_nearest_position_through_the_four_pmc_inputs() {
    let mut m = machine(OverrideMode::default());
    let mut s = m.step(command(64.0));
    for _ in 0..100 {
        s = m.step(command(64.0));
    }
    assert_eq!(s.sensors.applied_override_pct, 60.0);
    let code = m.signals().dial_code.unwrap();
    assert_eq!(code, 6);
    let inputs = PmcInputs::from_code(code);
    assert!(!inputs.x20_7 && inputs.x20_4 && inputs.x20_3 && !inputs.x20_2);
    // A machine builder's table: code 6 may mean anything.
    let mut table = DialTable::default().percent_by_code;
    table[6] = 65.0;
    let mut m = machine(OverrideMode::Dial(DialTable::new(table).unwrap()));
    for _ in 0..100 {
        s = m.step(command(64.0));
    }
    assert_eq!(s.sensors.applied_override_pct, 65.0);
}

#[test]
fn whole_percent_mode_rounds_and_stops_at_255() {
    let mut m = machine(OverrideMode::WholePercent);
    for (asked, applied) in [(87.4, 87.0), (87.6, 88.0), (300.0, 255.0), (-5.0, 0.0)] {
        let mut s = m.step(command(asked));
        for _ in 0..40 {
            s = m.step(command(asked));
        }
        assert_eq!(s.sensors.applied_override_pct, applied, "asked {asked}");
        assert_eq!(m.signals().dial_code, None);
    }
}

#[test]
fn continuous_mode_takes_any_value_and_nan_keeps_the_last() {
    let mut m = machine(OverrideMode::Continuous);
    let mut s = m.step(command(73.25));
    for _ in 0..40 {
        s = m.step(command(73.25));
    }
    assert_eq!(s.sensors.applied_override_pct, 73.25);
    for _ in 0..40 {
        s = m.step(command(f64::NAN));
    }
    assert_eq!(s.sensors.applied_override_pct, 73.25);
    for _ in 0..40 {
        s = m.step(command(f64::INFINITY));
    }
    assert_eq!(s.sensors.applied_override_pct, 255.0);
}

#[test]
fn the_pmc_reads_the_override_once_per_scan() {
    let mut m = machine(OverrideMode::Continuous);
    let scan = (CncConfig::default().pmc_scan_s * RATE_HZ).round() as usize; // 16 samples
    m.step(command(100.0)); // read at the first scan
    let mut changes = Vec::new();
    let mut last = 100.0;
    for k in 1..(4 * scan) {
        let pct = 50.0 + k as f64; // a new request every sample
        let applied = m.step(command(pct)).sensors.applied_override_pct;
        if applied != last {
            changes.push(k);
            last = applied;
        }
    }
    assert_eq!(changes, vec![scan, 2 * scan, 3 * scan]);
}

#[test]
fn feed_is_programmed_feed_times_override_reached_at_the_acceleration_limit() {
    let mut m = machine(OverrideMode::Continuous);
    let cfg = CncConfig::default();
    let per_period = cfg.cutting_accel_mm_s2 * cfg.interpolation_period_s * 60.0;
    let mut last = 0.0;
    let mut largest_change = 0.0f64;
    for k in 0..(6.0 * RATE_HZ) as usize {
        let pct = if k < (3.0 * RATE_HZ) as usize {
            50.0
        } else {
            150.0
        };
        m.step(command(pct));
        let v = m.signals().commanded_feed_mm_min;
        largest_change = largest_change.max((v - last).abs());
        last = v;
        if k == (3.0 * RATE_HZ) as usize - 1 {
            assert!((v - 300.0).abs() < 1e-9, "50 % of 600 mm/min: {v}");
        }
    }
    assert!((last - 900.0).abs() < 1e-9, "150 %: {last}");
    assert!(
        largest_change <= per_period + 1e-9,
        "{largest_change} > {per_period}"
    );
    // The axes follow through the position loop: actual feed within 1 % after 0.5 s.
    assert!((m.signals().feed_mm_min - 900.0).abs() < 9.0);
}

#[test]
fn feed_hold_stops_the_axes_and_leaves_the_edges_rubbing() {
    let mut m = machine(OverrideMode::Continuous);
    let run = |m: &mut Simulator, hold: bool, seconds: f64| {
        let n = (seconds * RATE_HZ) as usize;
        let mut force = 0.0;
        for _ in 0..n {
            let s = m.step(OverrideCommand {
                override_pct: 100.0,
                feed_hold: hold,
            });
            force += s.truth.unwrap().feed_force_n;
        }
        force / n as f64
    };
    run(&mut m, false, 3.0); // into the cut
    let cutting = run(&mut m, false, 0.6); // 10 revolutions at 1000 rpm
    run(&mut m, true, 0.5);
    assert!(m.signals().feed_mm_min.abs() < 1e-3);
    let held_at = m.signals().truth.path_position_mm;
    let rubbing = run(&mut m, true, 0.6);
    // The position loop has long since converged: the axes stand.
    assert!((m.signals().truth.path_position_mm - held_at).abs() < 1e-6);
    let cutter = Cutter::new(20.0, 2, 30.0).unwrap();
    let slot = Immersion::new(MillingMode::Slot, 20.0, 20.0);
    let edges_only = -mean_forces(&cutter, &Material::Sm45c.coefficients(), &slot, 3.0, 0.0).fx_n;
    assert!(
        (rubbing - edges_only).abs() < 0.02 * edges_only,
        "{rubbing} vs {edges_only}"
    );
    assert!(cutting > 1.5 * rubbing);
}

#[test]
fn the_right_angle_at_b_dips_the_spindle_current_as_in_paper_003_fig_13() {
    let preset = Preset::KimCircularTaper;
    let config = SimConfig {
        sample_rate_hz: RATE_HZ,
        ..preset.sim_config(1)
    };
    let mut m = Simulator::new(preset.scenario().unwrap(), config).unwrap();
    let b = 45.0; // path position of B
    let (mut before_sum, mut before_n) = (0.0, 0);
    let mut dip = f64::INFINITY;
    let mut slowest = f64::INFINITY;
    while m.signals().truth.path_position_mm < b + 1.0 {
        m.step(command(100.0));
        let s = m.signals();
        if (b - 3.0..b - 1.0).contains(&s.truth.path_position_mm) {
            before_sum += s.truth.spindle_current_rms_a;
            before_n += 1;
        }
        if (b - 0.2..b + 0.5).contains(&s.truth.path_position_mm) {
            dip = dip.min(s.truth.spindle_current_rms_a);
            slowest = slowest.min(s.feed_mm_min);
        }
    }
    let before = before_sum / f64::from(before_n);
    assert!(
        slowest < 0.2 * 170.0,
        "the axes stop at B: {slowest} mm/min"
    );
    assert!(
        dip < 0.97 * before,
        "spindle current {dip} A vs {before} A before B"
    );
}
