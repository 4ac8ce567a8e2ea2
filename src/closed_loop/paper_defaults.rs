//! The defaults a preset's paper states for its runs, where they differ from the generic ones:
//! a controller's parameters ([`preset_controller`]: paper 002's output range and the time base
//! of its EC) and paper 002's control period. Every front end that starts a controller on a
//! preset — the forms, the command line, a lesson, a run definition read without a controller's
//! parameters — asks here.

use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::plant::bond_graph::PAPER_002_FEED_MM_MIN;
use crate::plant::presets::PlantKind;
use crate::plant::Preset;

/// One parameter of [`preset_controller`]`(preset, kind)`, without building the controller (the
/// forms show every parameter of every controller as they mount, and a `fuzzy-engine`
/// controller carries its engine's text): the paper's value where it states one, else the
/// parameter's default. `None` for a key `kind` has not.
///
/// ```
/// use cutlab::closed_loop::paper_defaults::{preset_controller, preset_parameter};
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let kind = ControllerKind::FuzzyDynamics;
/// assert_eq!(preset_parameter(Preset::LiuCurrentStep, kind, "output_range_pct"), Some(100.0));
/// assert_eq!(preset_parameter(Preset::KimStepDoc, kind, "output_range_pct"),
///     preset_controller(Preset::KimStepDoc, kind).get("output_range_pct"));
/// assert_eq!(preset_parameter(Preset::KimStepDoc, kind, "no_such_key"), None);
/// ```
pub fn preset_parameter(preset: Preset, kind: ControllerKind, key: &str) -> Option<f64> {
    let spec = kind.params().iter().find(|p| p.key == key)?;
    let stated = paper_parameters(preset, kind)
        .iter()
        .find(|(k, _)| *k == key);
    Some(stated.map_or(spec.default, |&(_, value)| value))
}

/// A controller at the defaults of `preset`: the generic defaults, except where the preset's paper
/// states the controller's own parameters. Paper 002 states k_u = 250 mm/min per unit of U at
/// 1500 mm/min, added to the feed each sampling period (eq 1), and gives the current change EC
/// in A/s (Table 2). So on its preset (`liu-current-step`) the fuzzy controllers' output range is
/// the paper's 100 % per control period (6 × 250 of 1500 mm/min) instead of the 20 % that keeps
/// the fuzzy law from chattering at the mill presets' rate-limited 40 ms periods, and EC is read
/// as a rate over 1 s instead of per period.
///
/// ```
/// use cutlab::closed_loop::paper_defaults::preset_controller;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let liu = preset_controller(Preset::LiuCurrentStep, ControllerKind::FuzzyDynamics);
/// assert_eq!(liu.get("output_range_pct"), Some(100.0));
/// assert_eq!(liu.get("change_time_base_s"), Some(1.0)); // Table 2: EC in A/s
/// assert_eq!(liu.get("output_time_base_s"), Some(0.0)); // eq 1: k_u per period
/// let kim = preset_controller(Preset::KimStepDoc, ControllerKind::FuzzyDynamics);
/// assert_eq!(kim.get("output_range_pct"), Some(20.0));
/// assert_eq!(kim.get("change_time_base_s"), Some(0.0));
/// ```
pub fn preset_controller(preset: Preset, kind: ControllerKind) -> ControllerConfig {
    let mut config = ControllerConfig::new(kind);
    for &(key, value) in paper_parameters(preset, kind) {
        // The table below holds values inside every parameter's range (tested).
        let _ = config.set(key, value);
    }
    config
}

/// The controller parameters `preset`'s paper states, as (key, value).
pub fn paper_parameters(preset: Preset, kind: ControllerKind) -> &'static [(&'static str, f64)] {
    match (preset.plant_kind(), kind) {
        (PlantKind::BondGraph, kind) if kind.is_fuzzy() => &[
            ("output_range_pct", PAPER_002_OUTPUT_RANGE_PCT),
            ("change_time_base_s", PAPER_002_EC_TIME_BASE_S),
        ],
        _ => &[],
    }
}

/// Paper 002's k_u = 250 mm/min per unit of U, at |U| = 6 and 1500 mm/min: 100 % per period.
pub const PAPER_002_OUTPUT_RANGE_PCT: f64 =
    PAPER_002_K_U_MM_MIN * 6.0 / PAPER_002_FEED_MM_MIN * 100.0;
/// Paper 002's output quantification factor k_u, mm/min of feed change per unit of U.
const PAPER_002_K_U_MM_MIN: f64 = 250.0;
/// The time base of paper 002's EC: its Table 2 gives the current change in A/s (−11.5 → 8.5 A
/// in 0.05 s is its 400 A/s), so k_ec = 3/25 saturates at 50 A/s.
pub const PAPER_002_EC_TIME_BASE_S: f64 = 1.0;

/// The control period on paper 002's preset. The paper states no control period; 50 ms is the
/// spacing of its Table 2's rows (the data its rules were drawn from). docs/papers.md shows both
/// rule tables from 40 ms to 1 s, with EC and k_u each per period or per second.
pub const PAPER_002_CONTROL_PERIOD_S: f64 = 0.05;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_preset_parameter_is_the_preset_controller_s() {
        let mut stated = 0;
        for preset in Preset::ALL {
            for kind in ControllerKind::ALL {
                let config = preset_controller(preset, kind);
                for p in kind.params() {
                    let value = preset_parameter(preset, kind, p.key);
                    assert_eq!(value, config.get(p.key), "{preset:?} {kind:?} {}", p.key);
                    stated += usize::from(value != Some(p.default));
                }
            }
        }
        // Paper 002's two values, on its preset, for both fuzzy controllers and the engine.
        assert!(stated >= 4, "{stated}");
    }
}
