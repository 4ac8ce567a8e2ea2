//! The metrics table both front ends show: which metrics, in which order, with their units, which
//! way is better, how far apart two values must be to differ ([`Tolerance`]), why a value is
//! missing ([`MetricRow::why_missing`]), and which runs have the best value of a row
//! ([`best_marks`]: only beyond the row's tolerance, never a run that spent a share of its cycle
//! above the force limit, which the table says with [`not_best_note`], nor one that left more
//! depth steps unsettled than another, [`MetricRow::outranked`]).

use super::lab::RunResult;
use crate::input::three_significant;
use crate::plant::presets::ProgramLength;

/// Which way is better for a metric.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Better {
    Lower,
    Higher,
    /// A setting shown for reference (the target), not a result to rank.
    Neither,
}

/// How far apart two values of a metric must be before one is better than the other: beyond
/// the scatter a change of seed alone gives (726 against 727 override changes is the same calm).
/// Two values differ when they are further apart than `relative` of the larger magnitude and
/// than `absolute` (in the row's unit).
///
/// Each row's tolerance ([`METRIC_ROWS`]) is at least the spread seeds 1–5 gave with `cutlab sim
/// --seed` on kim-step-doc (pi), maneerat-doc-1 (threshold), liu-current-step (fuzzy-dynamics)
/// and kim-material-taper (mrac), 2026-11-26: e.g. override changes 124–130 (4.6 %), override
/// total variation 16.9–18.1 % (6.6 %), force fluctuation 2.7–5.6 points of the target, force
/// IAE 21.1–26.4 N·s, time above the limit 1.1–1.3 s; cycle time, peak force, overshoot and
/// removal rate did not move.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerance {
    /// Fraction of the larger value's magnitude.
    pub relative: f64,
    /// In the row's unit: what differences near zero must exceed.
    pub absolute: f64,
}

impl Tolerance {
    /// The tolerance most rows take: 2 % of the value.
    pub const DEFAULT: Tolerance = Tolerance {
        relative: 0.02,
        absolute: 0.0,
    };

    /// Whether `a` and `b` are further apart than this tolerance.
    ///
    /// ```
    /// use cutlab::closed_loop::summary::Tolerance;
    /// let t = Tolerance { relative: 0.05, absolute: 0.0 };
    /// assert!(!t.separates(726.0, 727.0));
    /// assert!(t.separates(88.0, 574.0));
    /// ```
    pub fn separates(self, a: f64, b: f64) -> bool {
        let margin = (self.relative * a.abs().max(b.abs())).max(self.absolute);
        (a - b).abs() > margin
    }

    /// The rule in words, for a row's help: "A ★ only where it beats another run by more than
    /// 5 % (and 0.05 s)."
    pub fn rule(self, unit: &str) -> String {
        let unit = match unit {
            "" => String::new(),
            "%" | "% of target" => " points".to_string(),
            u => format!(" {u}"),
        };
        let absolute = crate::input::readable(self.absolute);
        let by = match (self.relative > 0.0, self.absolute > 0.0) {
            (true, true) => format!(
                "{} % of the value and by more than {absolute}{unit}",
                crate::input::readable(self.relative * 100.0)
            ),
            (true, false) => format!(
                "{} % of the value",
                crate::input::readable(self.relative * 100.0)
            ),
            _ => format!("{absolute}{unit}"),
        };
        format!(
            "A ★ only where the best value beats another run's by more than {by}; values within that of the best share its ★ (closer values are one result within the metric's noise)."
        )
    }
}

/// Why a row may have no value for a run, so the table can say it beside the "—".
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Missing {
    /// Always has a value.
    Never,
    /// Only for a run that finished its program.
    Unfinished,
    /// A saving: needs a finished run, a program of a set path, and the reference runs.
    Saving,
    /// The saving against the safe fixed feed: as [`Missing::Saving`], and a fixed feed that
    /// keeps the peak force at the target ([`super::metrics::Metrics::no_safe_fixed_feed`]).
    SafeFixedSaving,
    /// Only where the controller held a cut.
    Uncontrolled,
    /// Only for a program with depth steps (and, for settling, a step that settled).
    Steps,
    /// Only where the wall's error is modelled (the tool's stiffness and force law known).
    Wall,
    /// Only where material was removed.
    Removal,
}

/// How many of a row's cases a run failed, out of how many it met: the depth steps after which
/// the force never settled, of the steps cut. Among runs that met as many cases, one that failed
/// more is beaten on the row whatever its value ([`best_marks`]): a run that settled two of five
/// depth steps quickly has not done better than one that settled four, and a run that settled
/// none (no value, "—") loses to one that settled any.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shortfall {
    pub failed: usize,
    pub out_of: usize,
}

/// What a row counts as its cases, for [`MetricRow::shortfall`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Cases {
    /// None: the value alone ranks the runs.
    Unranked,
    /// The depth steps, failed where the force never settled after one.
    DepthSteps,
}

/// One row of the metrics table.
#[derive(Clone, Copy)]
pub struct MetricRow {
    /// What the row shows, capitalised, without the unit.
    pub label: &'static str,
    /// The unit, empty for counts.
    pub unit: &'static str,
    /// What the row means, in a sentence or two for someone new to the field: the glossary
    /// entry every front end shows beside it.
    pub help: &'static str,
    pub better: Better,
    /// A yes/no row: 1 is shown as "yes", 0 as "no".
    pub yes_no: bool,
    /// The row's value for a run; `None` where it does not exist (no reference runs yet, no step
    /// that settled).
    pub value: fn(&RunResult) -> Option<f64>,
    /// How far apart two values must be before one is marked better ([`best_marks`]).
    pub tolerance: Tolerance,
    /// Why [`MetricRow::value`] may be `None` ([`MetricRow::why_missing`]).
    pub missing: Missing,
    /// The cases that rank before the value ([`MetricRow::shortfall`]).
    pub cases: Cases,
}

impl MetricRow {
    /// This row with its glossary entry.
    const fn explained(self, help: &'static str) -> MetricRow {
        MetricRow { help, ..self }
    }

    /// This row with another tolerance than [`Tolerance::DEFAULT`].
    const fn within(self, relative: f64, absolute: f64) -> MetricRow {
        MetricRow {
            tolerance: Tolerance { relative, absolute },
            ..self
        }
    }

    /// This row with the reason its value can be missing.
    const fn missing(self, missing: Missing) -> MetricRow {
        MetricRow { missing, ..self }
    }

    /// This row with cases that rank the runs before its value.
    const fn counting(self, cases: Cases) -> MetricRow {
        MetricRow { cases, ..self }
    }

    /// How many of this row's cases `run` failed, out of how many it met; `None` for a row
    /// ranked by its value alone.
    ///
    /// ```
    /// use cutlab::closed_loop::definition::RunSpec;
    /// use cutlab::closed_loop::lab::simulate;
    /// use cutlab::closed_loop::summary::{Shortfall, METRIC_ROWS};
    /// use cutlab::control::registry::ControllerKind;
    /// use cutlab::plant::Preset;
    /// let row = |label| METRIC_ROWS.iter().find(|r| r.label == label).unwrap();
    /// let run = simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold)).unwrap();
    /// // Five depth steps; at the 1 mm one even the envelope's ceiling leaves the force under the band.
    /// assert_eq!(row("Max settling time").shortfall(&run), Some(Shortfall { failed: 1, out_of: 5 }));
    /// assert_eq!(row("Force IAE").shortfall(&run), None);
    /// ```
    pub fn shortfall(&self, run: &RunResult) -> Option<Shortfall> {
        let m = &run.metrics;
        match self.cases {
            Cases::Unranked => None,
            Cases::DepthSteps => Some(Shortfall {
                failed: m.steps_not_settled,
                out_of: m.steps.len(),
            }),
        }
    }

    /// Which of `runs` are beaten on this row before their values are compared: those that failed
    /// more of its cases than another run that met as many ([`Shortfall`]). All `false` for a row
    /// ranked by its value alone.
    pub fn outranked(&self, runs: &[&RunResult]) -> Vec<bool> {
        let shortfalls: Vec<Option<Shortfall>> = runs.iter().map(|r| self.shortfall(r)).collect();
        shortfalls
            .iter()
            .map(|own| {
                own.is_some_and(|own| {
                    shortfalls
                        .iter()
                        .flatten()
                        .any(|other| other.out_of == own.out_of && other.failed < own.failed)
                })
            })
            .collect()
    }

    /// Why this row shows "—" for `run`, in a few words a person reads on hover.
    pub fn why_missing(&self, run: &RunResult) -> &'static str {
        let m = &run.metrics;
        let unfinished = "the program did not finish: a run stopped early is not comparable";
        match self.missing {
            Missing::Unfinished | Missing::Saving | Missing::SafeFixedSaving if !m.completed => {
                unfinished
            }
            Missing::Saving | Missing::SafeFixedSaving
                if run.spec.preset.program_length() == ProgramLength::Time =>
            {
                "this program runs for a set time, so no run of it can be shorter"
            }
            Missing::SafeFixedSaving if m.no_safe_fixed_feed() => {
                "no safe fixed feed: even the slowest fixed override the envelope applies breaks \
                 the target, so there is none to save against"
            }
            Missing::Saving | Missing::SafeFixedSaving => {
                "no reference runs: the fixed-feed runs it is measured against have not been made"
            }
            Missing::Uncontrolled
                if m.controlled_cutting_time_s <= 0.0 && m.removed_volume_mm3 <= 0.0 =>
            {
                "nothing was cut (a brake bench, or a run stopped in air), so there is no cut \
                 whose force error to measure"
            }
            Missing::Uncontrolled if m.controlled_cutting_time_s <= 0.0 => {
                "not controlled: the controller held no cut"
            }
            Missing::Uncontrolled => "the controlled cut is too short to measure it",
            Missing::Steps if m.steps.is_empty() && m.removed_volume_mm3 <= 0.0 => {
                "nothing was cut, so no depth step was measured"
            }
            Missing::Steps if m.steps.is_empty() && !m.completed => {
                "no depth step was cut before the run stopped"
            }
            Missing::Steps if m.steps.is_empty() => "no depth step in this program",
            Missing::Steps => "the force never settled after a depth step",
            Missing::Wall if run.settings.error_model.is_none() => {
                "not modelled: this preset's tool stiffness or force law is not known"
            }
            Missing::Wall if m.removed_volume_mm3 <= 0.0 => "no wall was cut",
            Missing::Wall => {
                "not measured in this run: the estimate it is predicted from was not made here \
                 (a feedback that does not estimate the in-plane force, or no power law)"
            }
            Missing::Removal => "no material was removed",
            Missing::Never | Missing::Unfinished => "not measured in this run",
        }
    }

    /// The row's help with its rule for the best mark (none for a row that ranks nothing).
    pub fn help_with_rule(&self) -> String {
        match self.better {
            _ if self.yes_no => self.help.to_string(),
            Better::Neither => self.help.to_string(),
            _ => {
                let first = match self.cases {
                    Cases::Unranked => "",
                    Cases::DepthSteps => {
                        " A run that left more depth steps unsettled than another is beaten here, whatever its time."
                    }
                };
                format!("{} {}{first}", self.help, self.tolerance.rule(self.unit))
            }
        }
    }

    /// How a front end shows `value` of this row: yes/no rows as words, others through
    /// `number`, a missing value as "—".
    pub fn show(&self, value: Option<f64>, number: impl Fn(f64) -> String) -> String {
        match value {
            Some(v) if self.yes_no => if v > 0.5 { "yes" } else { "no" }.to_string(),
            Some(v) if v.is_finite() => number(v),
            _ => "—".to_string(),
        }
    }

    /// The label with its unit in brackets, as a row heading.
    pub fn heading(&self) -> String {
        if self.unit.is_empty() {
            self.label.to_string()
        } else {
            format!("{} ({})", self.label, self.unit)
        }
    }
}

const fn row(
    label: &'static str,
    unit: &'static str,
    better: Better,
    value: fn(&RunResult) -> Option<f64>,
) -> MetricRow {
    MetricRow {
        label,
        unit,
        help: "",
        better,
        yes_no: false,
        value,
        tolerance: Tolerance::DEFAULT,
        missing: Missing::Never,
        cases: Cases::Unranked,
    }
}

/// A value that exists only for a run that finished its program: a run stopped by the overload
/// alarm is "faster" only because it stopped.
fn if_finished(r: &RunResult, value: Option<f64>) -> Option<f64> {
    value.filter(|_| r.metrics.completed)
}

/// A force-error value, which exists only where the controller held a cut.
fn if_controlled(r: &RunResult, value: f64) -> Option<f64> {
    (r.metrics.controlled_cutting_time_s > 0.0).then_some(value)
}

/// The rows, in the order shown.
pub const METRIC_ROWS: [MetricRow; 22] = [
    row("Target force", "N", Better::Neither, |r| {
        Some(r.settings.target_force_n)
    }).explained("The force the controller holds, on the run's feedback path."),
    MetricRow {
        yes_no: true,
        ..row("Program finished", "", Better::Higher, |r| {
            Some(f64::from(u8::from(r.metrics.completed)))
        }).explained("Whether the part program ran to its end; a run stopped by the overload alarm or the time limit did not, and its other results are not comparable.")
        .within(0.0, 0.5)
    },
    row("Cycle time", "s", Better::Lower, |r| {
        if_finished(r, Some(r.metrics.cycle_time_s))
    }).explained("Time from the spindle start to the program's end: what adaptive control shortens.")
    .within(0.01, 0.0).missing(Missing::Unfinished),
    row("Saving vs programmed feed", "%", Better::Higher, |r| {
        if_finished(r, r.metrics.saving_vs_programmed_pct)
    }).explained("How much shorter the cycle is than the program at 100 % override. Negative where the target asks for less force than the programmed feed makes: the controller then slows the cut to hold it.")
    .within(0.0, 1.0).missing(Missing::Saving),
    row("Saving vs safe fixed feed", "%", Better::Higher, |r| {
        if_finished(r, r.metrics.saving_vs_safe_fixed_pct)
    }).explained("How much shorter the cycle is than at the highest fixed override that keeps the peak force at or below the target: the fair baseline for adaptive control.")
    .within(0.0, 1.0).missing(Missing::SafeFixedSaving),
    row("Force IAE", "N·s", Better::Lower, |r| {
        if_controlled(r, r.metrics.force_iae_n_s)
    }).explained("Integral of |force − target| over the controlled cut: the whole force error, in newton-seconds.")
    .within(0.05, 10.0).missing(Missing::Uncontrolled),
    row("Force RMS error", "N", Better::Lower, |r| {
        if_controlled(r, r.metrics.force_rms_error_n)
    }).explained("Root-mean-square of force − target over the controlled cut.")
    .within(0.05, 2.0).missing(Missing::Uncontrolled),
    row("Mean |error|", "%", Better::Lower, |r| {
        if_controlled(r, r.metrics.force_mean_abs_error_pct)
    }).explained("Mean of |force − target| ÷ target over the controlled cut.")
    .within(0.05, 0.5).missing(Missing::Uncontrolled),
    row("Peak force", "N", Better::Lower, |r| {
        Some(r.metrics.peak_force_n)
    }).explained("The highest regulated force of the run, true value: the largest control-period mean, the quantity the target and the limit are set on (the force on each tooth peaks higher within a period); compare it with the force limit."),
    row("Surface error range", "µm", Better::Lower, |r| {
        Some(r.metrics.surface_error_range_um).filter(|v| v.is_finite())
    }).explained("The wall's error from the tool and spindle bending under the force across the cut, largest minus smallest along the engaged wall (paper 004's cutting-force-induced error); its constant part is taken out by the tool-radius offset, this spread is not.")
    .within(0.05, 0.5).missing(Missing::Wall),
    row(
        "Surface error range, compensated from the power law",
        "µm",
        Better::Lower,
        |r| Some(r.metrics.compensated_range_power_law_um).filter(|v| v.is_finite()),
    ).explained("What is left of that spread when the tool path is offset by the error the power law predicts from what the CNC knows of the cut (paper 004's sensorless compensation).")
    .within(0.05, 0.5).missing(Missing::Wall),
    row(
        "Surface error range, compensated from the current",
        "µm",
        Better::Lower,
        |r| Some(r.metrics.compensated_range_current_um).filter(|v| v.is_finite()),
    ).explained("What is left of it when the offset is predicted from the current-based force estimate of the control period before.")
    .within(0.05, 0.5).missing(Missing::Wall),
    row("Time above limit", "s", Better::Lower, |r| {
        Some(r.metrics.time_above_limit_s)
    }).explained("Time the true force spent above the force limit, where tools break.")
    .within(0.2, 0.1),
    row(
        "Time outside the calibrated range",
        "s",
        Better::Lower,
        |r| if_controlled(r, r.metrics.time_outside_calibration_s),
    ).explained("Time the estimator's inputs lay outside the range its teach cut calibrated: there its force estimate is an extrapolation.")
    .within(0.2, 0.15).missing(Missing::Uncontrolled),
    row(
        "Time a sensor failure is predicted",
        "s",
        Better::Lower,
        |r| if_controlled(r, r.metrics.time_sensor_failure_predicted_s),
    ).explained("Paper 004's sensor failure prediction: controlled cutting time in which the current-based force estimate left the sensorless one (the force network learned on the preset's trial cuts, fed with what the CNC program knows of the cut) by more than the sensor-failure tolerance plus the network's own uncertainty there. A healthy sensor keeps this near zero; a drifting or failing current sensor makes it grow.")
    .within(0.2, 0.15).missing(Missing::Uncontrolled),
    row(
        "Max overshoot after a depth step",
        "%",
        Better::Lower,
        |r| (!r.metrics.steps.is_empty()).then_some(r.metrics.max_overshoot_pct),
    ).explained("The largest overshoot of the force above the target after a step in the depth of cut, percent of the target.")
    .within(0.0, 1.0).missing(Missing::Steps),
    row("Max settling time", "s", Better::Lower, |r| {
        r.metrics.max_settling_time_s
    }).explained("The longest time after a depth step until the force stays within the settling band around the target.")
    .within(0.05, 0.05).missing(Missing::Steps).counting(Cases::DepthSteps),
    row(
        "Force fluctuation, last 10 s",
        "% of target",
        Better::Lower,
        |r| if_controlled(r, r.metrics.late_force_fluctuation_pct),
    ).explained("Standard deviation of force ÷ target over the last 10 s of the controlled cut (paper 002's \"fluctuates less\").")
    .within(0.1, 3.0).missing(Missing::Uncontrolled),
    row("Depth steps never settled", "", Better::Lower, |r| {
        (!r.metrics.steps.is_empty()).then_some(r.metrics.steps_not_settled as f64)
    }).explained("Depth steps after which the force never stayed within the settling band.")
    .within(0.0, 0.5).missing(Missing::Steps),
    row("Override changes", "", Better::Lower, |r| {
        Some(r.metrics.override_changes as f64)
    }).explained("How many times the commanded override changed: a calmer controller changes it less often.")
    .within(0.06, 0.0),
    row("Override total variation", "%", Better::Lower, |r| {
        Some(r.metrics.override_total_variation_pct)
    }).explained("The sum of the commanded override's changes: how hard the controller works the feed.")
    .within(0.08, 0.0),
    row("Mean removal rate", "mm³/s", Better::Higher, |r| {
        (r.metrics.removed_volume_mm3 > 0.0).then_some(r.metrics.mean_material_removal_mm3_s)
    }).explained("Material removed per second, over the whole cycle.")
    .within(0.01, 0.0).missing(Missing::Removal),
];

/// A metric as the browser's table shows it: a whole number (a count, an exact time) as it is,
/// anything else to three significant digits, its meaning (issue 30: "76.04 s" reads as "76 s",
/// and a 0.1 s difference in a 76 s cycle is not one a person acts on). The exports (CSV, JSON)
/// keep every digit for a user who wants more. The papers' findings quote figures in the same
/// form, so a reader finds them in the table.
///
/// ```
/// use cutlab::closed_loop::summary::format_metric;
/// assert_eq!(format_metric(5.0), "5");
/// assert_eq!(format_metric(1234.0), "1234");
/// assert_eq!(format_metric(16.54), "16.5");
/// assert_eq!(format_metric(844.6), "845");
/// assert_eq!(format_metric(2482.49), "2480");
/// assert_eq!(format_metric(-32.42), "-32.4");
/// assert_eq!(format_metric(0.66), "0.66");
/// ```
pub fn format_metric(v: f64) -> String {
    if v.fract() == 0.0 && v.abs() < 1e6 {
        format!("{v:.0}")
    } else {
        three_significant(v)
    }
}

/// Which of `values` are the best, judged beyond `tolerance` and as they are shown (`shown`
/// formats a value): the best value is marked with every value within the tolerance of it or
/// printing alike (a reader never sees two equal numbers of which only one is "best"), and only
/// where some other value lies beyond the tolerance. Nothing is marked with fewer than two runs,
/// for [`Better::Neither`], where no value is finite, or where every value ties within the
/// tolerance (nothing is better than anything).
///
/// ```
/// use cutlab::closed_loop::summary::{best, Better, Tolerance};
/// let shown = |v: f64| format!("{v:.1}");
/// let marks = best(&[Some(2.04), Some(2.0), None, Some(3.0)], Better::Lower, Tolerance::DEFAULT, shown);
/// assert_eq!(marks, [true, true, false, false]);
/// let calm = Tolerance { relative: 0.05, absolute: 0.0 };
/// assert_eq!(best(&[Some(726.0), Some(727.0)], Better::Lower, calm, shown), [false, false]);
/// ```
pub fn best(
    values: &[Option<f64>],
    better: Better,
    tolerance: Tolerance,
    shown: impl Fn(f64) -> String,
) -> Vec<bool> {
    let n = values.len();
    best_among(
        values,
        &vec![true; n],
        &vec![false; n],
        better,
        tolerance,
        shown,
    )
}

/// [`best`] with only the `eligible` runs' values marked. The others' values still count as
/// values to beat: the best eligible value is marked where it beats some other run's value —
/// theirs included — beyond the tolerance, so a lone eligible run beside a run left out is marked
/// where it beats that run, and not where that run did better. An `outranked` run
/// ([`MetricRow::outranked`]: more depth steps left unsettled, its value missing or not) is
/// beaten by every eligible value, so a run that settled is marked beside one that never did;
/// any other missing value is no result and beats nothing.
fn best_among(
    values: &[Option<f64>],
    eligible: &[bool],
    outranked: &[bool],
    better: Better,
    tolerance: Tolerance,
    shown: impl Fn(f64) -> String,
) -> Vec<bool> {
    let finite = |i: usize| values[i].filter(|v| v.is_finite());
    let eligible_values = || {
        (0..values.len())
            .filter(|&i| eligible[i])
            .filter_map(finite)
    };
    let extreme = match better {
        _ if values.len() < 2 => None,
        Better::Neither => None,
        Better::Lower => eligible_values().reduce(f64::min),
        Better::Higher => eligible_values().reduce(f64::max),
    };
    let Some(extreme) = extreme else {
        return vec![false; values.len()];
    };
    let alike = |v: f64| shown(v) == shown(extreme) || !tolerance.separates(v, extreme);
    let worse = |v: f64| match better {
        Better::Lower => v > extreme,
        _ => v < extreme,
    };
    let beaten =
        (0..values.len()).any(|i| outranked[i] || finite(i).is_some_and(|v| !alike(v) && worse(v)));
    (0..values.len())
        .map(|i| beaten && eligible[i] && finite(i).is_some_and(alike))
        .collect()
}

/// A run that spent more than this share of its cycle above the force limit is never marked
/// best: a teaching lab must not crown a run that would break the tool. (A transient at a depth
/// step, a few tenths of a second, is allowed.)
pub const ABOVE_LIMIT_SHARE_NOT_BEST: f64 = 0.01;

/// Whether `run` may be marked best on rows other than the time above the limit itself.
pub fn may_be_best(run: &RunResult) -> bool {
    let m = &run.metrics;
    m.time_above_limit_s <= ABOVE_LIMIT_SHARE_NOT_BEST * m.cycle_time_s
}

/// The best marks of `row` over `runs` ([`best`]), a run above the force limit for more than
/// [`ABOVE_LIMIT_SHARE_NOT_BEST`] of its cycle never marked on any row but the time above the
/// limit (where the least is best whoever it is). Its values still count as values to beat, so
/// the runs within the limit are marked where they beat it: beside one such run, the other is
/// the winner wherever it did better, not a table without a mark ([`not_best_note`] says so).
/// A run [`MetricRow::outranked`] on the row (more depth steps left unsettled than another) is
/// beaten there and never marked.
pub fn best_marks(
    row: &MetricRow,
    runs: &[&RunResult],
    shown: impl Fn(f64) -> String,
) -> Vec<bool> {
    let judges_the_limit = row.label == "Time above limit";
    let values: Vec<Option<f64>> = runs.iter().map(|r| (row.value)(r)).collect();
    let outranked = row.outranked(runs);
    let eligible: Vec<bool> = runs
        .iter()
        .zip(&outranked)
        .map(|(r, &outranked)| !outranked && (judges_the_limit || may_be_best(r)))
        .collect();
    best_among(
        &values,
        &eligible,
        &outranked,
        row.better,
        row.tolerance,
        shown,
    )
}

/// A sentence for each row of a table with a "—", saying why it has no value (what a cell shows
/// on hover, written out for a touch screen and the terminal): `Saving vs safe fixed feed (%):
/// no safe fixed feed: …`, the runs named where their reasons differ or some have a value.
///
/// ```
/// use cutlab::closed_loop::summary::missing_notes;
/// assert!(missing_notes(&[]).is_empty());
/// ```
pub fn missing_notes(runs: &[(&str, &RunResult)]) -> Vec<String> {
    let mut notes = Vec::new();
    for row in &METRIC_ROWS {
        let mut whys: Vec<(&'static str, Vec<&str>)> = Vec::new();
        for (name, run) in runs {
            if (row.value)(run).is_some() {
                continue;
            }
            let why = row.why_missing(run);
            match whys.iter_mut().find(|(w, _)| *w == why) {
                Some((_, names)) => names.push(name),
                None => whys.push((why, vec![name])),
            }
        }
        let all_alike = whys.len() == 1 && whys[0].1.len() == runs.len();
        for (why, names) in whys {
            notes.push(if all_alike {
                format!("{}: {why}", row.heading())
            } else {
                format!("{}, {}: {why}", row.heading(), names.join(", "))
            });
        }
    }
    notes
}

/// The sentence a table shows under its marks when a run was left out of them, naming each with
/// its time above the limit, and against what the others' marks stand: the runs within the limit
/// are marked where they beat any run, those left out included; where none is within it, no run
/// is marked on any other row. `None` when every run could be marked.
pub fn not_best_note(runs: &[(&str, &RunResult)]) -> Option<String> {
    let left_out: Vec<String> = runs
        .iter()
        .filter(|(_, r)| !may_be_best(r))
        .map(|(name, r)| format!("{name} ({:.1} s)", r.metrics.time_above_limit_s))
        .collect();
    if left_out.is_empty() || runs.len() < 2 {
        return None;
    }
    let within: Vec<&str> = runs
        .iter()
        .filter(|(_, r)| may_be_best(r))
        .map(|(name, _)| *name)
        .collect();
    let marks = match within.as_slice() {
        [] => "No run kept within the limit, so none is marked best on any other row.".to_string(),
        [one] => format!(
            "{one} is the only run within the limit, the one to choose of these: it is marked \
             best where it beat the runs left out (their values still count as ones to beat)."
        ),
        several => format!(
            "The runs within the limit ({}) are marked best where one beats another run's \
             value, those left out included.",
            several.join(", ")
        ),
    };
    Some(format!(
        "not marked best on any row but the time above the limit: above the force limit for \
         more than {:.0} % of the cycle — {}. {marks}",
        ABOVE_LIMIT_SHARE_NOT_BEST * 100.0,
        left_out.join(", ")
    ))
}

/// Why a negative "Saving vs programmed feed" is what it is, in words, for each run that has one
/// (named when there are several): the controller cut slower than the program at 100 % feed,
/// and where its mean override under control stayed below 100 % it did so on purpose: the target
/// is below the force the programmed feed gives, so it slows the cut to hold the target.
pub fn negative_saving_notes(runs: &[(&str, &RunResult)]) -> Vec<String> {
    runs.iter()
        .filter_map(|(name, run)| {
            let saving = run.metrics.saving_vs_programmed_pct.filter(|s| *s < 0.0)?;
            let armed: Vec<f64> = run
                .trace
                .rows
                .iter()
                .filter(|r| r.armed && r.override_pct.is_finite())
                .map(|r| r.override_pct)
                .collect();
            let mean_override_pct = armed.iter().sum::<f64>() / armed.len().max(1) as f64;
            let who = if runs.len() > 1 {
                format!("{name}: ")
            } else {
                String::new()
            };
            let slower = format!(
                "{who}the cycle is {} % longer than the program at 100 % feed",
                crate::input::readable((-saving * 10.0).round() / 10.0)
            );
            Some(if !armed.is_empty() && mean_override_pct < 100.0 {
                format!(
                    "{slower}: the target ({:.0} N) is below the force the programmed feed gives, so the controller slows the cut to hold it (mean override {mean_override_pct:.0} % while controlling)."
                    , run.settings.target_force_n
                )
            } else {
                format!("{slower}.")
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_metric_row_is_explained_in_a_sentence_and_named_once() {
        let mut labels = Vec::new();
        for row in &METRIC_ROWS {
            assert!(
                row.help.len() > 30 && row.help.ends_with(['.', ')', '"']),
                "{}: {:?}",
                row.label,
                row.help
            );
            assert!(
                !row.help.contains("--"),
                "{}: a CLI flag in the help",
                row.label
            );
            labels.push(row.label);
        }
        labels.sort_unstable();
        labels.dedup();
        assert_eq!(labels.len(), METRIC_ROWS.len());
    }

    fn shown(v: f64) -> String {
        format!("{v:.0}")
    }

    #[test]
    fn the_best_follows_the_direction_of_the_row() {
        let values = [Some(3.0), Some(1.0), Some(2.0)];
        assert_eq!(
            best(&values, Better::Lower, Tolerance::DEFAULT, shown),
            [false, true, false]
        );
        assert_eq!(
            best(&values, Better::Higher, Tolerance::DEFAULT, shown),
            [true, false, false]
        );
        assert_eq!(
            best(&values, Better::Neither, Tolerance::DEFAULT, shown),
            [false, false, false]
        );
    }

    #[test]
    fn one_run_or_no_finite_value_marks_nothing() {
        assert_eq!(
            best(&[Some(1.0)], Better::Lower, Tolerance::DEFAULT, shown),
            [false]
        );
        assert_eq!(
            best(
                &[None, Some(f64::NAN)],
                Better::Lower,
                Tolerance::DEFAULT,
                shown
            ),
            [false, false]
        );
    }

    #[test]
    fn a_row_where_every_run_ties_marks_nothing() {
        let values = [Some(0.0), Some(0.0), None];
        assert_eq!(
            best(&values, Better::Lower, Tolerance::DEFAULT, shown),
            [false, false, false]
        );
        assert_eq!(
            best(
                &[Some(0.2), Some(0.4)],
                Better::Lower,
                Tolerance::DEFAULT,
                shown
            ),
            [false, false]
        );
    }

    #[test]
    fn a_run_left_out_is_still_a_value_to_beat() {
        // The first run is left out (above the force limit).
        let eligible = [false, true];
        let marks = |values: &[Option<f64>], better| {
            best_among(
                values,
                &eligible,
                &[false; 2],
                better,
                Tolerance::DEFAULT,
                shown,
            )
        };
        // The lone run within the limit beats it: marked.
        assert_eq!(
            marks(&[Some(744.0), Some(561.0)], Better::Lower),
            [false, true]
        );
        // It did better (a shorter cycle): nothing is marked, the better run being left out.
        assert_eq!(
            marks(&[Some(54.0), Some(76.0)], Better::Lower),
            [false, false]
        );
        assert_eq!(
            marks(&[Some(54.0), Some(76.0)], Better::Higher),
            [false, true]
        );
        // Within the row's noise of it: nothing.
        assert_eq!(
            marks(&[Some(100.0), Some(101.0)], Better::Lower),
            [false, false]
        );
        // Two runs within the limit that tie share the mark when they beat the one left out.
        let three = [Some(900.0), Some(500.0), Some(501.0)];
        let marked = best_among(
            &three,
            &[false, true, true],
            &[false; 3],
            Better::Lower,
            Tolerance::DEFAULT,
            shown,
        );
        assert_eq!(marked, [false, true, true]);
        // Nobody within the limit: nothing.
        let none = best_among(
            &three,
            &[false; 3],
            &[false; 3],
            Better::Lower,
            Tolerance::DEFAULT,
            shown,
        );
        assert_eq!(none, [false; 3]);
    }

    #[test]
    fn beside_a_fixed_feed_above_the_limit_the_controller_wins_where_it_beat_it_and_says_so() {
        use crate::closed_loop::definition::RunSpec;
        use crate::closed_loop::lab::simulate;
        use crate::control::registry::ControllerKind;
        use crate::plant::Preset;
        let run = |kind| simulate(&RunSpec::new(Preset::KimStepDoc, kind)).unwrap();
        let (fixed, threshold) = (run(ControllerKind::Fixed), run(ControllerKind::Threshold));
        // The fixed feed spends 18 s of its 54 s above the limit; threshold 0.7 s of 76 s.
        assert!(!may_be_best(&fixed) && may_be_best(&threshold));
        let marked: Vec<&str> = METRIC_ROWS
            .iter()
            .filter(|row| best_marks(row, &[&fixed, &threshold], format_metric)[1])
            .map(|row| row.label)
            .collect();
        // The fixed feed never settled after any depth step ("—"): a loss to threshold's time.
        let settling = METRIC_ROWS.iter().find(|r| r.label == "Max settling time");
        assert_eq!(
            settling.map(|row| row.outranked(&[&fixed, &threshold])),
            Some(vec![true, false])
        );
        for label in [
            "Peak force",
            "Force IAE",
            "Mean |error|",
            "Time above limit",
            "Max settling time",
        ] {
            assert!(marked.contains(&label), "{label} not in {marked:?}");
        }
        // Where the fixed feed did better (its shorter cycle), threshold is no winner.
        for label in ["Cycle time", "Override changes", "Mean removal rate"] {
            assert!(!marked.contains(&label), "{label} in {marked:?}");
        }
        let note = not_best_note(&[("fixed", &fixed), ("threshold", &threshold)]).unwrap();
        assert!(
            note.contains("— fixed (18.0 s). threshold is the only run within the limit"),
            "{note}"
        );
        assert_eq!(not_best_note(&[("threshold", &threshold)]), None);
        let both_out = not_best_note(&[("a", &fixed), ("b", &fixed)]).unwrap();
        assert!(
            both_out.ends_with("so none is marked best on any other row."),
            "{both_out}"
        );
    }

    #[test]
    fn a_run_that_never_settled_loses_the_settling_time_to_one_that_settled() {
        use crate::closed_loop::definition::RunSpec;
        use crate::closed_loop::lab::simulate;
        use crate::control::registry::ControllerKind;
        use crate::plant::Preset;
        let row = |label: &str| METRIC_ROWS.iter().find(|r| r.label == label).unwrap();
        let settling = row("Max settling time");
        let settled =
            simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold)).unwrap();
        assert!(may_be_best(&settled) && !settled.metrics.steps.is_empty());
        assert!((settling.value)(&settled).is_some());
        // The same run, but the force never settled after any of its depth steps.
        let mut unsettled = settled.clone();
        unsettled.metrics.max_settling_time_s = None;
        unsettled.metrics.steps_not_settled = unsettled.metrics.steps.len();
        assert_eq!(
            settling.why_missing(&unsettled),
            "the force never settled after a depth step"
        );
        assert_eq!(settling.outranked(&[&unsettled, &settled]), [true, false]);
        assert_eq!(
            best_marks(settling, &[&unsettled, &settled], format_metric),
            [false, true]
        );
        assert_eq!(
            best_marks(settling, &[&settled, &unsettled], format_metric),
            [true, false]
        );
        // The depth steps the run never settled after are beaten on their own row as before.
        assert_eq!(
            best_marks(
                row("Depth steps never settled"),
                &[&unsettled, &settled],
                format_metric
            ),
            [false, true]
        );
        // A "—" that means the metric does not apply is no loss: a run without depth steps (a
        // program that has none) leaves the settled run unmarked, alone with a value.
        let mut stepless = settled.clone();
        stepless.metrics.steps.clear();
        stepless.metrics.max_settling_time_s = None;
        stepless.metrics.steps_not_settled = 0;
        assert_eq!(settling.outranked(&[&stepless, &settled]), [false, false]);
        assert_eq!(
            best_marks(settling, &[&stepless, &settled], format_metric),
            [false, false]
        );
        // And where the metric failed for every run, nothing is marked.
        assert_eq!(
            best_marks(settling, &[&unsettled, &unsettled], format_metric),
            [false, false]
        );
    }

    #[test]
    fn a_run_that_left_more_depth_steps_unsettled_loses_the_settling_time_however_quick() {
        use crate::closed_loop::definition::RunSpec;
        use crate::closed_loop::lab::simulate;
        use crate::control::registry::ControllerKind;
        use crate::plant::Preset;
        let row = |label: &str| METRIC_ROWS.iter().find(|r| r.label == label).unwrap();
        let settling = row("Max settling time");
        let steady =
            simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold)).unwrap();
        let steps = steady.metrics.steps.len();
        assert!(steps >= 3 && steady.metrics.steps_not_settled < steps - 1);
        // The same run, but one more step never settled, and the ones it settled settled faster:
        // its max is over fewer steps, a flattering number.
        let mut quick = steady.clone();
        quick.metrics.steps_not_settled += 1;
        quick.metrics.max_settling_time_s = steady.metrics.max_settling_time_s.map(|t| t / 4.0);
        assert_eq!(
            best_marks(settling, &[&quick, &steady], format_metric),
            [false, true]
        );
        assert_eq!(
            best_marks(settling, &[&steady, &quick], format_metric),
            [true, false]
        );
        // Among runs that left as many unsettled, the time decides as before.
        let mut also_quick = quick.clone();
        also_quick.metrics.max_settling_time_s = steady.metrics.max_settling_time_s;
        assert_eq!(
            best_marks(settling, &[&quick, &also_quick], format_metric),
            [true, false]
        );
        // A run stopped before its later steps met fewer of them: not compared by its count.
        let mut stopped = quick.clone();
        stopped.metrics.steps.truncate(steps - 1);
        assert_eq!(settling.outranked(&[&stopped, &steady]), [false, false]);
        // The row's help says so.
        assert!(settling
            .help_with_rule()
            .contains("more depth steps unsettled"));
    }

    #[test]
    fn values_that_print_alike_are_marked_alike() {
        let marks = best(
            &[Some(631.4), Some(630.9), Some(700.0)],
            Better::Lower,
            Tolerance::DEFAULT,
            shown,
        );
        assert_eq!(marks, [true, true, false]);
    }

    #[test]
    fn a_difference_within_the_rows_noise_earns_no_star() {
        let changes = METRIC_ROWS
            .iter()
            .find(|r| r.label == "Override changes")
            .copied()
            .unwrap();
        let marks = |a: f64, b: f64| {
            best(
                &[Some(a), Some(b)],
                changes.better,
                changes.tolerance,
                shown,
            )
        };
        assert_eq!(marks(726.0, 727.0), [false, false]);
        assert_eq!(marks(88.0, 574.0), [true, false]);
        // And the help of every ranked row states its rule.
        for row in METRIC_ROWS
            .iter()
            .filter(|r| r.better != Better::Neither && !r.yes_no)
        {
            assert!(row.help_with_rule().contains("★"), "{}", row.label);
        }
    }

    #[test]
    fn a_missing_value_says_why_and_a_negative_saving_is_explained() {
        use crate::closed_loop::definition::RunSpec;
        use crate::closed_loop::lab::simulate;
        use crate::control::registry::ControllerKind;
        use crate::plant::Preset;
        let row = |label: &str| {
            METRIC_ROWS
                .iter()
                .find(|r| r.label == label)
                .copied()
                .unwrap()
        };
        let mut fixed = simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Fixed)).unwrap();
        // A run whose controller never held a cut (it never armed).
        fixed.metrics.controlled_cutting_time_s = 0.0;
        let iae = row("Force IAE");
        assert_eq!((iae.value)(&fixed), None);
        assert!(
            iae.why_missing(&fixed).starts_with("not controlled"),
            "{}",
            iae.why_missing(&fixed)
        );
        let saving = row("Saving vs programmed feed");
        assert_eq!((saving.value)(&fixed), None);
        assert!(saving.why_missing(&fixed).starts_with("no reference run"));
        // References made, and no fixed override keeps the peak at the target: the saving
        // against the programmed feed shows, the one against a safe fixed feed says there is none.
        let safe = row("Saving vs safe fixed feed");
        assert!(safe.why_missing(&fixed).starts_with("no reference run"));
        let mut none_safe = fixed.clone();
        crate::closed_loop::references::apply_references(
            &mut none_safe,
            &crate::closed_loop::references::References {
                programmed_cycle_time_s: 2.0 * fixed.metrics.cycle_time_s,
                safe_fixed_override_pct: f64::NAN,
                safe_fixed_cycle_time_s: f64::NAN,
            },
        );
        assert_eq!((saving.value)(&none_safe), Some(50.0));
        assert_eq!((safe.value)(&none_safe), None);
        assert!(
            safe.why_missing(&none_safe)
                .starts_with("no safe fixed feed"),
            "{}",
            safe.why_missing(&none_safe)
        );
        // A run that cut nothing (a bad filter setting's false overload stops it at once) says
        // so, not that the preset has no depth steps or no wall model.
        let mut uncut = fixed.clone();
        uncut.metrics.removed_volume_mm3 = 0.0;
        uncut.metrics.steps.clear();
        uncut.metrics.surface_error_range_um = f64::NAN;
        assert!(uncut.settings.error_model.is_some());
        let wall = row("Surface error range");
        assert_eq!((wall.value)(&uncut), None);
        assert_eq!(wall.why_missing(&uncut), "no wall was cut");
        let steps = row("Max overshoot after a depth step");
        assert_eq!(
            steps.why_missing(&uncut),
            "nothing was cut, so no depth step was measured"
        );
        uncut.settings.error_model = None;
        assert!(wall.why_missing(&uncut).starts_with("not modelled"));

        let mut held =
            simulate(&RunSpec::new(Preset::KimStepDoc, ControllerKind::Threshold)).unwrap();
        assert!(negative_saving_notes(&[("threshold", &held)]).is_empty());
        held.metrics.saving_vs_programmed_pct = Some(-32.42);
        let notes = negative_saving_notes(&[("threshold", &held)]);
        assert_eq!(notes.len(), 1);
        assert!(notes[0].contains("32.4 % longer"), "{}", notes[0]);
        assert!(
            notes[0].contains("below the force the programmed feed gives"),
            "{}",
            notes[0]
        );
    }
}
