//! Paper 004's compensation of the cutting-force-induced error (issue 32): each period the error
//! the model predicts from a force offsets the wall, and the trace keeps what is left. Checked
//! row by row against the model, with the power law's offset fed forward and the current's one
//! period late; that compensation narrows the error's range on kim-step-doc and maneerat-doc-4 is
//! asserted where docs/papers.md states the figures (tests/docs.rs).
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

#[cfg(target_arch = "wasm32")]
use wasm_bindgen_test::wasm_bindgen_test as test;

use cutlab::closed_loop::definition::{RunSetting, RunSpec};
use cutlab::closed_loop::lab::simulate;
use cutlab::control::registry::ControllerKind;
use cutlab::estimation::estimator::Feedback;
use cutlab::plant::deflection::{normal_share, ErrorModel, ToolMount};
use cutlab::plant::mechanics::ToolForces;
use cutlab::plant::Preset;

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-9 * a.abs().max(b.abs()).max(1.0)
}

#[test]
fn the_offsets_are_the_models_predictions_fed_forward_from_the_power_law_and_one_period_late_from_the_current(
) {
    let preset = Preset::ManeeratDoc1;
    let run = simulate(&RunSpec::new(preset, ControllerKind::Pi)).unwrap();
    let model =
        ErrorModel::of_program(&preset.scenario_spec().unwrap(), ToolMount::default()).unwrap();
    assert_eq!(run.settings.error_model, Some(model));
    let rows = &run.trace.rows;
    let in_work = rows.iter().filter(|r| r.depth_mm > 0.0).count();
    assert!(in_work > 20, "{in_work} periods in work");
    for pair in rows.windows(2) {
        let (before, r) = (&pair[0], &pair[1]);
        let from_power_law = model.predicted_error_um(r.force_power_law_n);
        assert!(close(
            r.compensated_error_power_law_um,
            r.surface_error_um - from_power_law
        ));
        let offset_um = if before.armed {
            model.predicted_error_um(before.force_est_n.max(0.0))
        } else {
            0.0
        };
        assert!(
            close(
                r.compensated_error_current_um,
                r.surface_error_um - offset_um
            ),
            "at {} s",
            r.time_s
        );
    }
    // In the cut the error is tens of micrometres, and the power law's offset leaves a few.
    let engaged: Vec<_> = rows.iter().filter(|r| r.depth_mm > 0.0).collect();
    let middle = engaged[engaged.len() / 2];
    assert!(
        (5.0..200.0).contains(&middle.surface_error_um),
        "{} µm",
        middle.surface_error_um
    );
    assert!(
        middle.compensated_error_power_law_um.abs() < 0.2 * middle.surface_error_um,
        "{} µm left of {} µm",
        middle.compensated_error_power_law_um,
        middle.surface_error_um
    );
}

#[test]
fn the_feed_path_has_no_current_based_compensation() {
    // The feed current estimates the feed force, which does not say how hard the tool is pushed
    // off the wall.
    let mut spec = RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed);
    spec.settings.feedback = Some(Feedback::FeedCurrent);
    let run = simulate(&spec).unwrap();
    let metrics = &run.metrics;
    assert!(metrics.surface_error_range_um.is_finite());
    assert!(metrics.compensated_range_power_law_um.is_finite());
    assert!(metrics.compensated_range_current_um.is_nan());
}

#[test]
fn plants_without_a_tool_have_no_error_to_compensate() {
    let run = simulate(&RunSpec::new(Preset::LiuCurrentStep, ControllerKind::Fixed)).unwrap();
    assert_eq!(run.settings.error_model, None);
    assert!(run.metrics.compensated_range_power_law_um.is_nan());
    assert!(run.metrics.compensated_range_current_um.is_nan());
}

#[test]
fn the_normal_share_is_the_forces_part_across_the_feed() {
    let forces = ToolForces {
        fx_n: -300.0,
        fy_n: 400.0,
        fz_n: 50.0,
        torque_nm: 0.0,
    };
    assert!(close(normal_share(&forces), 0.8));
    assert!(normal_share(&ToolForces::default()).is_nan());
}

/// kim-step-doc's surface-error range at fixed feed with the mount's `setting` typed as `text`,
/// µm (through the run table's parse, as a form or a flag gives it).
fn error_range_with(setting: RunSetting, text: &str) -> f64 {
    let preset = Preset::KimStepDoc;
    let mut spec = RunSpec::new(preset, ControllerKind::Fixed);
    setting.apply(&mut spec, setting.parse(text, preset).unwrap());
    simulate(&spec).unwrap().metrics.surface_error_range_um
}

/// The tool's stick-out is a run setting: a longer tool bends more under the same forces, so the
/// wall's error range over the part grows, and by the cantilever's L³ — the spindle's part, the
/// same at every stick-out, cancels in the differences.
#[test]
fn a_longer_stick_out_widens_the_error_range_by_the_cantilevers_cube() {
    let ranges_um = ["40", "60", "80"].map(|l| error_range_with(RunSetting::ToolStickOut, l));
    assert!(
        ranges_um.windows(2).all(|w| w[1] > w[0]),
        "{ranges_um:?} µm"
    );
    let cube = |l: f64| l * l * l;
    let measured = (ranges_um[1] - ranges_um[0]) / (ranges_um[2] - ranges_um[0]);
    let closed_form = (cube(60.0) - cube(40.0)) / (cube(80.0) - cube(40.0));
    assert!(
        (measured - closed_form).abs() < 1e-6,
        "{measured} against the cantilever's {closed_form}"
    );
    // Magnitude: a Ø20 mm carbide tool 80 mm out on a 50 N/µm spindle bends tens of µm over
    // kim-step-doc's depth steps.
    assert!((10.0..500.0).contains(&ranges_um[2]), "{} µm", ranges_um[2]);
}

#[test]
fn a_high_speed_steel_tool_bends_further_than_a_carbide_one() {
    let range = |e| error_range_with(RunSetting::ToolModulus, e);
    assert!(range("210") > range("600"));
    let e = RunSetting::ToolModulus
        .parse("50", Preset::KimStepDoc)
        .unwrap_err();
    assert_eq!(e.problem.to_string(), "50 GPa is outside 150–700 GPa");
}

#[test]
fn a_stiffer_spindle_narrows_the_error_range() {
    let range = |k| error_range_with(RunSetting::SpindleStiffness, k);
    assert!(range("200") < range("20"));
}

#[test]
fn bad_stick_outs_and_spindle_stiffnesses_are_refused_with_the_tables_message() {
    let preset = Preset::KimStepDoc;
    let e = RunSetting::ToolStickOut.parse("1000", preset).unwrap_err();
    assert_eq!(e.problem.to_string(), "1000 mm is outside 2–400 mm");
    let e = RunSetting::SpindleStiffness
        .parse("0,5", preset)
        .unwrap_err();
    assert_eq!(e.problem.to_string(), "0.5 N/µm is outside 5–500 N/µm");
    assert!(RunSetting::ToolStickOut.parse("ten", preset).is_err());
    // Within the table's range, but shorter than kim-step-doc's deepest cut (5 mm): the flutes
    // would not reach it.
    let mut spec = RunSpec::new(preset, ControllerKind::Fixed);
    spec.plant.tool_stick_out_mm = Some(3.0);
    let e = simulate(&spec).err().unwrap().to_string();
    assert!(
        e.contains("tool_stick_out_mm") && e.contains("3 mm is outside"),
        "{e}"
    );
}
