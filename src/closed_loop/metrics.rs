//! Metrics of a run, computed from its trace alone, so a run recorded from a real machine or a
//! replayed log is judged by the same code as a simulation.
//!
//! Force metrics count only the rows where the tool is cutting and the controller is armed:
//! before arming the controller is not in charge, and in air there is no force to hold. On a real
//! machine, where the depth of cut is unknown (NaN), every armed row counts.

use serde::Serialize;

use super::trace::{csv_field, Trace, TraceRow};
use crate::plant::presets::ProgramLength;

/// Settings of the metrics.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct MetricsConfig {
    /// The force limit for "time above the limit" (e.g. the tool's safe load).
    pub force_limit_n: f64,
    /// Half-width of the settling band around the target, percent of target.
    pub settling_band_pct: f64,
    /// A depth change larger than this between two control periods is a step (or part of one).
    pub depth_step_mm: f64,
    /// Times of load steps known from the experiment's schedule (paper 002's step in depth at
    /// 15 s), each measured like a depth step, whether or not the trace shows its depth, and
    /// over its whole window: the feed's own lag after the controller's answer is the response
    /// being measured, not the path slowing down.
    pub load_step_times_s: Vec<f64>,
}

/// The response to one depth-of-cut step (or a scheduled load step, whose depths are NaN).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StepResponse {
    /// When the depth changed.
    pub time_s: f64,
    /// Depth before the step.
    pub depth_before_mm: f64,
    /// Depth after the step.
    pub depth_after_mm: f64,
    /// Largest force above the target until the next step, percent of target (0 if none).
    pub overshoot_pct: f64,
    /// Time until the force stays inside the settling band up to the next step; `None` if it
    /// never does.
    pub settling_time_s: Option<f64>,
}

/// What a run achieved.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Metrics {
    /// Time to the end of the program (or of the run, if it did not complete).
    pub cycle_time_s: f64,
    /// Whether the program ran to its end.
    pub completed: bool,
    /// Time spent cutting with the controller armed.
    pub controlled_cutting_time_s: f64,
    /// Integral of |F − F_target| over the controlled cutting time.
    pub force_iae_n_s: f64,
    /// RMS of F − F_target over the controlled cutting time.
    pub force_rms_error_n: f64,
    /// Mean |F − F_target| / F_target over the controlled cutting time.
    pub force_mean_abs_error_pct: f64,
    /// Largest regulated force of the run.
    pub peak_force_n: f64,
    /// Time with the force above the force limit.
    pub time_above_limit_s: f64,
    /// Controlled cutting time with the current or speed outside the range the estimator was
    /// calibrated over: its force estimate is an extrapolation there.
    pub time_outside_calibration_s: f64,
    /// Controlled cutting time where paper 004's sensor failure prediction flags the current
    /// sensor: its estimate and the sensorless network's differ beyond their tolerance.
    pub time_sensor_failure_predicted_s: f64,
    /// Largest overshoot over all depth steps, percent of target.
    pub max_overshoot_pct: f64,
    /// Longest settling time over the depth steps that settled; `None` if none did.
    pub max_settling_time_s: Option<f64>,
    /// Number of depth steps after which the force never stayed inside the settling band.
    pub steps_not_settled: usize,
    /// The settling band the settling times were measured to, ± percent of target.
    pub settling_band_pct: f64,
    /// How much the force still wanders once the controller has had its time: the standard
    /// deviation of force ÷ target over the last [`FLUCTUATION_WINDOW_S`] of controlled cutting,
    /// percent (paper 002's "fluctuates less", Fig. 7). NaN with fewer than two such periods.
    pub late_force_fluctuation_pct: f64,
    /// Each depth step's response.
    pub steps: Vec<StepResponse>,
    /// Total variation of the commanded override, Σ|Δu|.
    pub override_total_variation_pct: f64,
    /// Number of changes of the commanded override.
    pub override_changes: usize,
    /// Volume removed.
    pub removed_volume_mm3: f64,
    /// Mean material removal rate over the cycle.
    pub mean_material_removal_mm3_s: f64,
    /// The spread of the wall's force-induced error along the part once the cutter is engaged,
    /// largest minus smallest, µm: what a CMM would see along the wall after the tool-radius
    /// offset took out its constant part. NaN where the tool's stiffness is not known.
    pub surface_error_range_um: f64,
    /// The same range once paper 004's compensator offsets the tool path by the error the power
    /// law predicts (sensorless), µm. NaN where the stiffness or the power law is not known.
    pub compensated_range_power_law_um: f64,
    /// The same range once the offset is predicted from the current-based estimate, one control
    /// period late, µm. NaN where the stiffness is not known or the feedback path does not
    /// estimate the in-plane resultant.
    pub compensated_range_current_um: f64,
    /// Cycle-time saving against the programmed feed at 100 %, percent (positive = faster).
    /// `None` until reference runs are made, and always for a program whose cycle time does not
    /// depend on the feed ([`with_savings`]).
    pub saving_vs_programmed_pct: Option<f64>,
    /// Cycle-time saving against the highest fixed override that keeps the peak force at or
    /// below the target, percent; `None` as [`Metrics::saving_vs_programmed_pct`], and where no
    /// fixed override does ([`Metrics::no_safe_fixed_feed`]).
    pub saving_vs_safe_fixed_pct: Option<f64>,
}

impl Metrics {
    /// Whether the reference runs were made and found no safe fixed feed: [`with_savings`] set
    /// the saving against the programmed feed, but none against a safe fixed feed (the search
    /// answered NaN: not even the slowest fixed override the envelope applies keeps the peak
    /// force at the target).
    ///
    /// ```
    /// use cutlab::closed_loop::metrics::{compute, with_savings, MetricsConfig};
    /// use cutlab::closed_loop::trace::Trace;
    /// use cutlab::plant::presets::ProgramLength;
    /// let m = compute(&Trace::default(), &MetricsConfig::default());
    /// assert!(!m.no_safe_fixed_feed()); // no references yet
    /// let none_safe = with_savings(m.clone(), ProgramLength::Path, Some(40.0), Some(f64::NAN));
    /// assert!(none_safe.no_safe_fixed_feed());
    /// assert!(!with_savings(m, ProgramLength::Path, Some(40.0), Some(50.0)).no_safe_fixed_feed());
    /// ```
    pub fn no_safe_fixed_feed(&self) -> bool {
        self.saving_vs_programmed_pct.is_some() && self.saving_vs_safe_fixed_pct.is_none()
    }
}

/// The window at the end of the controlled cut over which the force's fluctuation is measured.
pub const FLUCTUATION_WINDOW_S: f64 = 10.0;

/// Whether a row counts for the force metrics.
fn controlled_cut(row: &TraceRow) -> bool {
    let cutting = row.depth_mm.is_nan() || (row.depth_mm > 0.0 && row.width_mm > 0.0);
    row.armed && cutting && row.force_n.is_finite()
}

/// The duration each row stands for: the time since the previous row.
fn durations(rows: &[TraceRow]) -> impl Iterator<Item = (f64, &TraceRow)> {
    let mut previous = rows.first().map_or(0.0, |r| r.time_s);
    rows.iter().enumerate().map(move |(i, r)| {
        let dt = if i == 0 { 0.0 } else { r.time_s - previous };
        previous = r.time_s;
        (dt.max(0.0), r)
    })
}

/// Computes every metric of `trace`. The savings stay `None`; [`with_savings`] fills them from
/// the cycle times of reference runs.
///
/// ```
/// use cutlab::closed_loop::metrics::{compute, MetricsConfig};
/// use cutlab::closed_loop::trace::{Trace, TraceRow};
/// let rows = (0..=10).map(|i| TraceRow { time_s: f64::from(i) * 0.1, depth_mm: 2.0,
///     width_mm: 10.0, force_n: 110.0, target_force_n: 100.0, armed: true, ..TraceRow::default() })
///     .collect();
/// let m = compute(&Trace { rows, completed: true, ..Trace::default() },
///     &MetricsConfig { force_limit_n: 105.0, settling_band_pct: 5.0, depth_step_mm: 0.2, load_step_times_s: vec![] });
/// assert!((m.force_iae_n_s - 10.0).abs() < 1e-9);     // 10 N for 1 s
/// assert!((m.time_above_limit_s - 1.0).abs() < 1e-9);
/// ```
pub fn compute(trace: &Trace, config: &MetricsConfig) -> Metrics {
    let rows = &trace.rows;
    let first_time = rows.first().map_or(0.0, |r| r.time_s);
    let cycle_time_s = rows.last().map_or(0.0, |r| r.time_s - first_time);

    let mut controlled_s = 0.0;
    let mut iae = 0.0;
    let mut squared = 0.0;
    let mut relative = 0.0;
    let mut above_s = 0.0;
    let mut outside_s = 0.0;
    let mut disagree_s = 0.0;
    let mut removed = 0.0;
    for (dt, r) in durations(rows) {
        if r.material_removal_mm3_s.is_finite() {
            removed += r.material_removal_mm3_s * dt;
        }
        if r.force_n.is_finite() && r.force_n > config.force_limit_n {
            above_s += dt;
        }
        if controlled_cut(r) {
            let error = r.force_n - r.target_force_n;
            controlled_s += dt;
            if !r.estimate_in_range {
                outside_s += dt;
            }
            if r.sensor_failure_predicted {
                disagree_s += dt;
            }
            iae += error.abs() * dt;
            squared += error * error * dt;
            relative += (error / r.target_force_n).abs() * dt;
        }
    }
    let peak_force_n = rows
        .iter()
        .map(|r| r.force_n)
        .filter(|f| f.is_finite())
        .fold(0.0, f64::max);

    let steps = step_responses(rows, config);
    let max_overshoot_pct = steps.iter().map(|s| s.overshoot_pct).fold(0.0, f64::max);
    let steps_not_settled = steps.iter().filter(|s| s.settling_time_s.is_none()).count();
    // Over the steps that settled; the ones that did not are counted apart, so a run that never
    // holds the force shows no settling time rather than a flattering one.
    let max_settling_time_s = steps
        .iter()
        .filter_map(|s| s.settling_time_s)
        .reduce(f64::max);

    let late_force_fluctuation_pct = late_fluctuation_pct(rows);

    let (total_variation, changes) = override_moves(rows);

    Metrics {
        cycle_time_s,
        completed: trace.completed,
        controlled_cutting_time_s: controlled_s,
        force_iae_n_s: iae,
        force_rms_error_n: if controlled_s > 0.0 {
            (squared / controlled_s).sqrt()
        } else {
            0.0
        },
        force_mean_abs_error_pct: if controlled_s > 0.0 {
            100.0 * relative / controlled_s
        } else {
            0.0
        },
        peak_force_n,
        time_above_limit_s: above_s,
        time_outside_calibration_s: outside_s,
        time_sensor_failure_predicted_s: disagree_s,
        max_overshoot_pct,
        max_settling_time_s,
        steps_not_settled,
        settling_band_pct: config.settling_band_pct,
        late_force_fluctuation_pct,
        steps,
        override_total_variation_pct: total_variation,
        override_changes: changes,
        removed_volume_mm3: removed,
        surface_error_range_um: wall_range_um(rows, |r| r.surface_error_um),
        compensated_range_power_law_um: wall_range_um(rows, |r| r.compensated_error_power_law_um),
        compensated_range_current_um: wall_range_um(rows, |r| r.compensated_error_current_um),
        mean_material_removal_mm3_s: if cycle_time_s > 0.0 {
            removed / cycle_time_s
        } else {
            0.0
        },
        saving_vs_programmed_pct: None,
        saving_vs_safe_fixed_pct: None,
    }
}

/// The standard deviation of force ÷ target over the last [`FLUCTUATION_WINDOW_S`] of the
/// controlled cut, percent (population form, as a steady signal's spread; NaN with fewer than two
/// periods).
/// Largest minus smallest of a wall error (`error_um`: the surface error, or what compensation
/// leaves of it) along the wall, NaN when none is known: over the periods in work at least the
/// width of cut from each entry into and exit from the part. There the cutter is still engaging
/// or already leaving and the wall it leaves is a ramp, the same for every controller; between
/// them the error follows the force the controller holds. A constant error is taken out by the
/// tool-radius offset; what no offset removes is this spread.
fn wall_range_um(rows: &[TraceRow], error_um: impl Fn(&TraceRow) -> f64) -> f64 {
    let mut lo = f64::INFINITY;
    let mut hi = f64::NEG_INFINITY;
    let in_work = |r: &TraceRow| r.depth_mm > 0.0;
    let mut start = 0;
    while start < rows.len() {
        if !in_work(&rows[start]) {
            start += 1;
            continue;
        }
        let end = rows[start..]
            .iter()
            .position(|r| !in_work(r))
            .map_or(rows.len(), |k| start + k);
        let (first, last) = (&rows[start], &rows[end - 1]);
        for r in &rows[start..end] {
            let engaged = r.path_position_mm - first.path_position_mm >= first.width_mm
                && last.path_position_mm - r.path_position_mm >= last.width_mm;
            let error = error_um(r);
            if engaged && error.is_finite() {
                lo = lo.min(error);
                hi = hi.max(error);
            }
        }
        start = end;
    }
    if hi >= lo {
        hi - lo
    } else {
        f64::NAN
    }
}

fn late_fluctuation_pct(rows: &[TraceRow]) -> f64 {
    let Some(end_s) = rows
        .iter()
        .rev()
        .find(|r| controlled_cut(r))
        .map(|r| r.time_s)
    else {
        return f64::NAN;
    };
    let (mut n, mut sum, mut sum_sq) = (0.0, 0.0, 0.0);
    for r in rows
        .iter()
        .filter(|r| controlled_cut(r) && r.time_s > end_s - FLUCTUATION_WINDOW_S)
    {
        let x = r.force_n / r.target_force_n;
        n += 1.0;
        sum += x;
        sum_sq += x * x;
    }
    if n < 2.0 {
        return f64::NAN;
    }
    let mean = sum / n;
    100.0 * (sum_sq / n - mean * mean).max(0.0).sqrt()
}

/// Fills the savings from the cycle times of the reference runs: the programmed feed at 100 %
/// and the highest fixed override that keeps the peak force at or below the target (NaN where
/// none does: then no saving against it).
///
/// A program whose length is a [`ProgramLength::Time`] ([`crate::plant::Preset::program_length`]) gets none: every run of it, reference or
/// controlled, ends at the same moment, so its "saving" would be 0 % by construction and would
/// read as "this controller saves nothing" when the program cannot show a saving at all.
///
/// ```
/// use cutlab::closed_loop::metrics::{compute, with_savings, MetricsConfig};
/// use cutlab::plant::presets::ProgramLength;
/// use cutlab::closed_loop::trace::Trace;
/// let m = compute(&Trace::default(), &MetricsConfig::default());
/// let timed = with_savings(m, ProgramLength::Time, Some(40.0), Some(40.0));
/// assert_eq!(timed.saving_vs_programmed_pct, None);
/// ```
pub fn with_savings(
    mut metrics: Metrics,
    length: ProgramLength,
    programmed_cycle_time_s: Option<f64>,
    safe_fixed_cycle_time_s: Option<f64>,
) -> Metrics {
    let saving = |reference: f64| 100.0 * (reference - metrics.cycle_time_s) / reference;
    let reference = |t: Option<f64>| t.filter(|t| *t > 0.0 && length == ProgramLength::Path);
    metrics.saving_vs_programmed_pct = reference(programmed_cycle_time_s).map(saving);
    metrics.saving_vs_safe_fixed_pct = reference(safe_fixed_cycle_time_s).map(saving);
    metrics
}

/// The metrics as CSV: a header `metric,value` and one row per scalar metric, units in the names
/// (the per-step responses are summarised by their maxima).
///
/// ```
/// use cutlab::closed_loop::metrics::{compute, metrics_csv, MetricsConfig};
/// use cutlab::closed_loop::trace::Trace;
/// let m = compute(&Trace::default(), &MetricsConfig { force_limit_n: 1.0,
///     settling_band_pct: 5.0, depth_step_mm: 0.2, load_step_times_s: vec![] });
/// let csv = metrics_csv(&m);
/// assert!(csv.starts_with("metric,value\ncycle_time_s,0\n"));
/// ```
pub fn metrics_csv(metrics: &Metrics) -> String {
    metrics_csv_columns(&[("value", metrics)])
}

/// The metrics of several runs as CSV: a `metric` column, then one column per run headed by its
/// name; an empty cell is a metric the run does not have.
///
/// ```
/// use cutlab::closed_loop::metrics::{compute, metrics_csv_columns, MetricsConfig};
/// use cutlab::closed_loop::trace::Trace;
/// let m = compute(&Trace::default(), &MetricsConfig { force_limit_n: 1.0,
///     settling_band_pct: 5.0, depth_step_mm: 0.2, load_step_times_s: vec![] });
/// let csv = metrics_csv_columns(&[("A: fixed", &m), ("B: pi, kp 0.5", &m)]);
/// assert!(csv.starts_with("metric,A: fixed,\"B: pi, kp 0.5\"\ncycle_time_s,0,0\n"));
/// ```
pub fn metrics_csv_columns(runs: &[(&str, &Metrics)]) -> String {
    let value = |v: Option<f64>| v.map_or(String::new(), |v| v.to_string());
    let table: Vec<[(&str, Option<f64>); 25]> =
        runs.iter().map(|(_, m)| metric_values(m)).collect();
    let mut out = String::from("metric");
    for (name, _) in runs {
        out.push(',');
        out.push_str(&csv_field(name));
    }
    out.push('\n');
    let Some(first) = table.first() else {
        return out;
    };
    for (row, (name, _)) in first.iter().enumerate() {
        out.push_str(name);
        for values in &table {
            out.push(',');
            out.push_str(&value(values[row].1));
        }
        out.push('\n');
    }
    out
}

/// How much the commanded override moves over `rows`: its total variation, %, and the number of
/// periods it changed in (the metrics' `override_total_variation_pct` and `override_changes`,
/// and a replay's).
pub fn override_moves(rows: &[TraceRow]) -> (f64, usize) {
    let mut total_variation = 0.0;
    let mut changes = 0;
    for pair in rows.windows(2) {
        let change = pair[1].override_pct - pair[0].override_pct;
        if change.is_finite() && change != 0.0 {
            total_variation += change.abs();
            changes += 1;
        }
    }
    (total_variation, changes)
}

/// Every metric as (CSV name, value), in the CSV's order: the stable names lessons and the
/// CSV share.
pub fn metric_values(metrics: &Metrics) -> [(&'static str, Option<f64>); 25] {
    [
        ("cycle_time_s", Some(metrics.cycle_time_s)),
        ("completed", Some(f64::from(u8::from(metrics.completed)))),
        (
            "controlled_cutting_time_s",
            Some(metrics.controlled_cutting_time_s),
        ),
        ("force_iae_n_s", Some(metrics.force_iae_n_s)),
        ("force_rms_error_n", Some(metrics.force_rms_error_n)),
        (
            "force_mean_abs_error_pct",
            Some(metrics.force_mean_abs_error_pct),
        ),
        ("peak_force_n", Some(metrics.peak_force_n)),
        ("time_above_limit_s", Some(metrics.time_above_limit_s)),
        (
            "time_outside_calibration_s",
            Some(metrics.time_outside_calibration_s),
        ),
        (
            "time_sensor_failure_predicted_s",
            Some(metrics.time_sensor_failure_predicted_s),
        ),
        ("max_overshoot_pct", Some(metrics.max_overshoot_pct)),
        ("max_settling_time_s", metrics.max_settling_time_s),
        ("depth_steps", Some(metrics.steps.len() as f64)),
        (
            "override_total_variation_pct",
            Some(metrics.override_total_variation_pct),
        ),
        ("override_changes", Some(metrics.override_changes as f64)),
        ("removed_volume_mm3", Some(metrics.removed_volume_mm3)),
        (
            "mean_material_removal_mm3_s",
            Some(metrics.mean_material_removal_mm3_s),
        ),
        ("saving_vs_programmed_pct", metrics.saving_vs_programmed_pct),
        ("saving_vs_safe_fixed_pct", metrics.saving_vs_safe_fixed_pct),
        ("steps_not_settled", Some(metrics.steps_not_settled as f64)),
        ("settling_band_pct", Some(metrics.settling_band_pct)),
        (
            "late_force_fluctuation_pct",
            Some(metrics.late_force_fluctuation_pct).filter(|v| v.is_finite()),
        ),
        (
            "surface_error_range_um",
            Some(metrics.surface_error_range_um).filter(|v| v.is_finite()),
        ),
        (
            "compensated_range_power_law_um",
            Some(metrics.compensated_range_power_law_um).filter(|v| v.is_finite()),
        ),
        (
            "compensated_range_current_um",
            Some(metrics.compensated_range_current_um).filter(|v| v.is_finite()),
        ),
    ]
}

/// A feed this share under what the override asks for is the machine slowing the path by itself.
/// (Following an override change lags by a few percent at most: the envelope's rate limit keeps
/// each change small.)
pub const PATH_SLOWDOWN_SHARE: f64 = 0.2;

/// Whether the machine is slowing the path down by itself (a corner, the end of the program): the
/// feed is more than [`PATH_SLOWDOWN_SHARE`] under what the override asks for. NaN fields (a log
/// without them) say no.
fn path_slowdown(row: &TraceRow) -> bool {
    let asked = row.programmed_feed_mm_min * row.applied_override_pct / 100.0;
    asked > 0.0 && row.feed_mm_min < (1.0 - PATH_SLOWDOWN_SHARE) * asked
}

/// Groups the rows where the depth changes by more than the step threshold into steps, as
/// (first row, last row) of each. The depth of a row is its period's, so a step inside a period
/// shows as a partial change on one row and the rest on the next: the neighbours of a large
/// change that move the same way by more than a tenth of the threshold belong to it (less is a
/// taper's slope, or a part too small to matter).
fn depth_step_spans(rows: &[TraceRow], threshold_mm: f64) -> Vec<(usize, usize)> {
    let change = |i: usize| rows[i].depth_mm - rows[i - 1].depth_mm;
    let large = |i: usize| change(i).is_finite() && change(i).abs() > threshold_mm;
    let part_of =
        |i: usize, j: usize| change(i) * change(j) > 0.0 && change(i).abs() > 0.1 * threshold_mm;
    let mut spans: Vec<(usize, usize)> = Vec::new();
    for i in (1..rows.len()).filter(|&i| large(i)) {
        match spans.last_mut() {
            Some((_, last)) if *last + 1 >= i => *last = i,
            _ => {
                let first = if i >= 2 && part_of(i - 1, i) {
                    i - 1
                } else {
                    i
                };
                spans.push((first, i));
            }
        }
        if let Some((_, last)) = spans.last_mut() {
            if i + 1 < rows.len() && !large(i + 1) && part_of(i + 1, i) {
                *last = i + 1;
            }
        }
    }
    spans
}

/// Finds the depth steps into the cut and measures the force's response to each, up to the next
/// step or to the first moment the machine slows the path by itself (a corner, the end of the
/// program), whichever comes first: what follows is a new disturbance, not this step's response.
///
/// Steps out of the cut (to zero depth) are not responses to measure, and neither are steps with
/// no armed cutting row in their window: the controller was not in charge.
fn step_responses(rows: &[TraceRow], config: &MetricsConfig) -> Vec<StepResponse> {
    let mut spans = depth_step_spans(rows, config.depth_step_mm);
    let mut load_step_starts = Vec::new();
    for &t in &config.load_step_times_s {
        // The first row at or after the step: its period saw the new load.
        if let Some(i) = rows.iter().position(|r| r.time_s >= t).filter(|&i| i > 0) {
            // A load step the depth shows too is that depth step, measured as a load step from
            // the period that saw it.
            match spans
                .iter_mut()
                .find(|(first, last)| *first <= i + 1 && i <= *last + 1)
            {
                Some(span) => {
                    span.0 = span.0.min(i);
                    load_step_starts.push(span.0);
                }
                None => {
                    spans.push((i, i));
                    load_step_starts.push(i);
                }
            }
        }
    }
    spans.sort_unstable();
    spans.dedup();
    spans
        .iter()
        .enumerate()
        .filter_map(|(k, &(start, last))| {
            let next_step = spans.get(k + 1).map_or(rows.len(), |next| next.0);
            // A scheduled load step's response is the controller's and the feed's together
            // (paper 002's control smooths the feed over 0.57 s, so the feed lags a large
            // override change by far more than the path-slowdown test allows): only the next
            // step ends its window.
            let end = if load_step_starts.contains(&start) {
                next_step
            } else {
                (last + 1..next_step)
                    .find(|&i| path_slowdown(&rows[i]))
                    .unwrap_or(next_step)
            };
            let depth_after_mm = rows[last].depth_mm;
            // NaN (no depth known) is not a step out of the cut.
            if depth_after_mm <= 0.0 {
                return None;
            }
            let t0 = rows[start].time_s;
            let controlled: Vec<&TraceRow> = rows[start..end]
                .iter()
                .filter(|r| controlled_cut(r))
                .collect();
            if controlled.is_empty() {
                return None;
            }
            let overshoot = controlled
                .iter()
                .map(|r| 100.0 * (r.force_n - r.target_force_n) / r.target_force_n)
                .fold(0.0, f64::max);
            let inside = |r: &TraceRow| {
                (r.force_n - r.target_force_n).abs()
                    <= r.target_force_n * config.settling_band_pct / 100.0
            };
            // Settled from the row after the last one outside the band, if any row remains.
            let settling_time_s = match controlled.iter().rposition(|r| !inside(r)) {
                None => Some(controlled[0].time_s - t0),
                Some(i) => controlled.get(i + 1).map(|r| r.time_s - t0),
            };
            Some(StepResponse {
                time_s: t0,
                depth_before_mm: rows[start - 1].depth_mm,
                depth_after_mm,
                overshoot_pct: overshoot,
                settling_time_s,
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn config() -> MetricsConfig {
        MetricsConfig {
            force_limit_n: 120.0,
            settling_band_pct: 5.0,
            depth_step_mm: 0.2,
            load_step_times_s: Vec::new(),
        }
    }

    /// A run at 0.1 s periods: depth 1 mm, then 2 mm from t = 1 s; the force jumps to 150 N at
    /// the step and decays linearly to the 100 N target by t = 2 s.
    fn step_trace() -> Trace {
        let rows = (0..=30)
            .map(|i| {
                let t = f64::from(i) * 0.1;
                let force = if t < 1.0 - 1e-9 {
                    100.0
                } else {
                    (150.0 - 50.0 * (t - 1.0)).max(100.0)
                };
                TraceRow {
                    time_s: t,
                    depth_mm: if t < 1.0 - 1e-9 { 1.0 } else { 2.0 },
                    width_mm: 10.0,
                    force_n: force,
                    target_force_n: 100.0,
                    override_pct: if t < 1.0 - 1e-9 { 100.0 } else { 80.0 },
                    material_removal_mm3_s: 50.0,
                    armed: true,
                    ..TraceRow::default()
                }
            })
            .collect();
        Trace {
            rows,
            completed: true,
            ..Trace::default()
        }
    }

    #[test]
    fn a_scheduled_load_step_the_depth_shows_is_one_step_from_its_period() {
        // The row at 0.9 s ends with the step's first sample: a sliver of the new depth.
        let mut trace = step_trace();
        trace.rows[9].depth_mm = 1.01;
        let scheduled = MetricsConfig {
            load_step_times_s: vec![0.9],
            ..config()
        };
        let m = compute(&trace, &scheduled);
        assert_eq!(m.steps.len(), 1, "{:?}", m.steps);
        let step = m.steps[0];
        assert!((step.time_s - 0.9).abs() < 1e-9);
        assert_eq!((step.depth_before_mm, step.depth_after_mm), (1.0, 2.0));
        // Without the schedule it is the same depth step, seen from 1 s.
        let unscheduled = compute(&trace, &config());
        assert_eq!(unscheduled.steps.len(), 1);
        assert!((unscheduled.steps[0].time_s - 1.0).abs() < 1e-9);
    }

    #[test]
    fn a_step_is_found_with_its_overshoot_and_settling_time() {
        let m = compute(&step_trace(), &config());
        assert_eq!(m.steps.len(), 1);
        let s = m.steps[0];
        assert!((s.time_s - 1.0).abs() < 1e-9);
        assert_eq!((s.depth_before_mm, s.depth_after_mm), (1.0, 2.0));
        assert!((s.overshoot_pct - 50.0).abs() < 1e-9);
        // Inside ±5 N from 145 − 50·(t − 1) ≤ 105, i.e. t ≥ 1.9 s.
        assert!((s.settling_time_s.unwrap() - 0.9).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn a_step_split_across_two_periods_is_one_step() {
        let mut trace = step_trace();
        // The depth changed half-way through the period that ends at t = 1.0 s.
        trace.rows[10].depth_mm = 1.5;
        let m = compute(&trace, &config());
        assert_eq!(m.steps.len(), 1, "{:?}", m.steps);
        let s = m.steps[0];
        assert_eq!((s.depth_before_mm, s.depth_after_mm), (1.0, 2.0));
        assert!((s.time_s - 1.0).abs() < 1e-9);
        assert!((s.settling_time_s.unwrap() - 0.9).abs() < 1e-9, "{s:?}");
    }

    #[test]
    fn a_step_on_a_taper_starts_where_the_depth_jumps() {
        let mut trace = step_trace();
        for (i, r) in trace.rows.iter_mut().enumerate() {
            r.depth_mm += 0.001 * i as f64;
        }
        let m = compute(&trace, &config());
        assert_eq!(m.steps.len(), 1, "{:?}", m.steps);
        assert!((m.steps[0].time_s - 1.0).abs() < 1e-9, "{:?}", m.steps[0]);
        assert!((m.steps[0].depth_after_mm - 2.010).abs() < 1e-9);
    }

    #[test]
    fn leaving_the_cut_is_not_a_step() {
        let mut trace = step_trace();
        for r in &mut trace.rows[25..] {
            r.depth_mm = 0.0;
            r.force_n = 0.0;
        }
        let m = compute(&trace, &config());
        assert_eq!(m.steps.len(), 1, "{:?}", m.steps);
        assert_eq!(m.steps_not_settled, 0);
    }

    #[test]
    fn a_step_that_never_settles_is_counted_apart() {
        let mut trace = step_trace();
        // A second step at 2.5 s after which the force stays 30 % above the target.
        for r in &mut trace.rows[25..] {
            r.depth_mm = 3.0;
            r.force_n = 130.0;
        }
        let m = compute(&trace, &config());
        assert_eq!(m.steps.len(), 2);
        assert_eq!(m.steps[1].settling_time_s, None);
        assert_eq!(m.steps_not_settled, 1);
        assert!((m.max_settling_time_s.unwrap() - 0.9).abs() < 1e-9);
        assert!((m.max_overshoot_pct - 50.0).abs() < 1e-9);
        // The first step's window ends where the second begins.
        assert!((m.steps[0].settling_time_s.unwrap() - 0.9).abs() < 1e-9);
    }

    #[test]
    fn force_errors_are_integrals_over_the_controlled_cut() {
        let m = compute(&step_trace(), &config());
        // Rectangle rule on 0.1 s rows: the error triangle 50 N × 1 s sampled at its right ends.
        let expected: f64 = (11..=20)
            .map(|i| 50.0 - 5.0 * f64::from(i - 10))
            .sum::<f64>()
            * 0.1
            + 50.0 * 0.1;
        assert!(
            (m.force_iae_n_s - expected).abs() < 1e-9,
            "{}",
            m.force_iae_n_s
        );
        assert!((m.controlled_cutting_time_s - 3.0).abs() < 1e-9);
        assert_eq!(m.peak_force_n, 150.0);
        // Above 120 N while 150 − 50(t − 1) > 120: rows at t = 1.0 … 1.5 (5 periods after the first).
        assert!(
            (m.time_above_limit_s - 0.6).abs() < 1e-9,
            "{}",
            m.time_above_limit_s
        );
        assert_eq!(m.override_changes, 1);
        assert_eq!(m.override_total_variation_pct, 20.0);
        assert!((m.removed_volume_mm3 - 150.0).abs() < 1e-9);
        assert!((m.mean_material_removal_mm3_s - 50.0).abs() < 1e-9);
    }

    #[test]
    fn savings_compare_cycle_times() {
        let m = compute(&step_trace(), &config());
        let path = with_savings(m.clone(), ProgramLength::Path, Some(4.0), Some(6.0));
        assert_eq!(path.saving_vs_programmed_pct, Some(25.0));
        assert_eq!(path.saving_vs_safe_fixed_pct, Some(50.0));
        // The same cycle times on a program that runs for a time show no saving, not 0 %.
        let time = with_savings(m, ProgramLength::Time, Some(3.0), Some(3.0));
        assert_eq!(time.saving_vs_programmed_pct, None);
        assert_eq!(time.saving_vs_safe_fixed_pct, None);
    }

    #[test]
    fn unarmed_and_air_rows_do_not_count() {
        let mut trace = step_trace();
        for r in &mut trace.rows[..5] {
            r.armed = false;
        }
        for r in &mut trace.rows[5..10] {
            r.depth_mm = 0.0;
        }
        let m = compute(&trace, &config());
        // Rows 10–30 remain, each standing for the 0.1 s before it.
        assert!((m.controlled_cutting_time_s - 2.1).abs() < 1e-9);
    }

    #[test]
    fn the_surface_error_range_leaves_out_the_entry_and_exit_ramps() {
        // Air, then 30 mm of work 10 mm wide: the error ramps 0 → 20 µm over the first 10 mm,
        // holds 20–24 µm, and ramps down over the last 10 mm; then air again.
        let mut trace = Trace::default();
        let mut push = |position_mm: f64, depth_mm: f64, error_um: f64| {
            trace.rows.push(TraceRow {
                path_position_mm: position_mm,
                depth_mm,
                width_mm: 10.0,
                surface_error_um: error_um,
                ..TraceRow::default()
            })
        };
        push(0.0, 0.0, 0.0);
        for k in 0..=30 {
            let x = f64::from(k);
            let error = if x < 10.0 {
                2.0 * x
            } else if x > 20.0 {
                2.0 * (30.0 - x)
            } else {
                20.0 + 0.4 * (x - 10.0)
            };
            push(x, 2.0, error);
        }
        push(31.0, 0.0, 0.0);
        let m = compute(&trace, &config());
        assert!(
            (m.surface_error_range_um - 4.0).abs() < 1e-9,
            "{}",
            m.surface_error_range_um
        );
        // Without a known stiffness (NaN errors) there is no range.
        for r in &mut trace.rows {
            r.surface_error_um = f64::NAN;
        }
        assert!(compute(&trace, &config()).surface_error_range_um.is_nan());
    }
}
