//! The Logs page's charts, made of what the core computed: each open log's current and force on
//! the linked time axis, the chain's output, its spectrum with the spindle and tooth-passing
//! markers, the calibration's points and line, the replays' overrides and force estimates. Long
//! series are min/max-decimated to what a chart can show.

use std::ops::Range;
use std::sync::Arc;

use super::loader::LoadedLog;
use crate::charts::{Axis, LineChart, Series, Stroke, PALETTE};
use crate::input::readable;
use crate::log::analysis::{row_times, ChainOutput};
use crate::log::calibration::LogFit;
use crate::log::mapping::Channel;
use crate::log::replay::ReplayResult;
use crate::signal::decimate::min_max_indices;

/// Points per series a chart is given (the chart decimates further to its width).
const CHART_POINTS: usize = 4000;

/// `values` against `times` as chart points within `view`, min/max-decimated.
pub fn points(times: &[f64], values: &[f64], view: Option<&Range<f64>>) -> Vec<(f64, f64)> {
    let n = times.len().min(values.len());
    let (start, end) = match view {
        Some(r) => (
            times[..n]
                .partition_point(|t| *t < r.start)
                .saturating_sub(1),
            (times[..n].partition_point(|t| *t <= r.end) + 1).min(n),
        ),
        None => (0, n),
    };
    if start >= end {
        return Vec::new();
    }
    min_max_indices(&values[start..end], CHART_POINTS / 2)
        .into_iter()
        .map(|i| (times[start + i], values[start + i]))
        .collect()
}

/// The column of a log carrying the first of `channels` in its mapping.
pub fn channel_column<'a>(
    l: &'a LoadedLog,
    channels: &[Channel],
) -> Option<&'a crate::log::Column> {
    channels.iter().find_map(|c| {
        let name = l.mapping.columns_of(*c).first().map(|s| s.to_string())?;
        l.log.columns.iter().find(|col| col.name == name)
    })
}

pub const CURRENTS: [Channel; 4] = [
    Channel::SpindlePhase,
    Channel::SpindleCurrent,
    Channel::FeedPhase,
    Channel::FeedCurrent,
];

/// One chart of every open log's column for a channel, on the shared time axis.
pub fn overlay_chart(
    logs: &[LoadedLog],
    channels: &[Channel],
    y_label: &str,
    view: Option<&Range<f64>>,
) -> LineChart {
    let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear(y_label));
    for (k, l) in logs.iter().enumerate() {
        if let Some(column) = channel_column(l, channels) {
            let generated;
            let times: &[f64] = match l.log.time_column.and_then(|t| l.log.columns.get(t)) {
                Some(t) => &t.values,
                None => {
                    generated = row_times(&l.log, None);
                    &generated
                }
            };
            chart.series.push(Series::new(
                format!("{}: {}", l.name, column.name),
                PALETTE[k % PALETTE.len()],
                points(times, &column.values, view),
            ));
        }
    }
    chart.fit();
    chart
}

pub fn spectrum_chart(
    output: &ChainOutput,
    speed_rpm: Option<f64>,
    teeth: Option<usize>,
) -> LineChart {
    let (freq, psd) = &output.spectrum;
    let shown: Vec<(f64, f64)> = freq
        .iter()
        .zip(psd)
        .filter(|(f, p)| **f > 0.0 && **p > 0.0)
        .map(|(f, p)| (*f, *p))
        .collect();
    let mut chart = LineChart::new(Axis::log("frequency (Hz)"), Axis::log("PSD (unit²/Hz)"));
    chart
        .series
        .push(Series::new("Welch PSD", PALETTE[0], shown.clone()));
    let (lo, hi) = shown
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.1), hi.max(p.1))
        });
    let top = freq.last().copied().unwrap_or(0.0);
    if let Some(rpm) = speed_rpm.filter(|r| r.is_finite() && *r > 0.0) {
        let spindle_hz = rpm / 60.0;
        let mut markers = vec![(
            format!("spindle {} Hz", readable(spindle_hz)),
            spindle_hz,
            PALETTE[5],
        )];
        if let Some(z) = teeth.filter(|z| *z > 0) {
            let tooth_hz = spindle_hz * z as f64;
            markers.push((
                format!("tooth passing {} Hz", readable(tooth_hz)),
                tooth_hz,
                PALETTE[2],
            ));
        }
        for (label, f, color) in markers {
            if f < top && lo.is_finite() {
                chart
                    .series
                    .push(Series::new(label, color, vec![(f, lo), (f, hi)]).dashed());
            }
        }
    }
    chart.fit();
    chart
}

pub fn fit_chart(fit: &LogFit) -> LineChart {
    let mut chart = LineChart::new(Axis::linear("force (N)"), Axis::linear("RMS current (A)"));
    let mut dots: Vec<(f64, f64)> = fit
        .points
        .iter()
        .map(|p| (p.force_n, p.current_a))
        .collect();
    dots.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .series
        .push(Series::new("control periods", PALETTE[0], dots.clone()).with_stroke(Stroke::Points));
    let (lo, hi) = dots
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
            (lo.min(p.0), hi.max(p.0))
        });
    if let (Some(point), true) = (fit.points.first(), lo.is_finite()) {
        chart.series.push(Series::new(
            "fitted line",
            PALETTE[5],
            vec![
                (lo, fit.model_current_a(point, lo)),
                (hi, fit.model_current_a(point, hi)),
            ],
        ));
    }
    chart.fit();
    chart
}

/// A value of a replay's trace row.
pub type RowValue = fn(&crate::closed_loop::trace::TraceRow) -> f64;

pub fn replay_chart(
    results: &[Arc<ReplayResult>],
    value: RowValue,
    logged: Option<(&str, RowValue)>,
    y_label: &str,
    view: Option<&Range<f64>>,
) -> LineChart {
    let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear(y_label));
    for (k, r) in results.iter().enumerate() {
        let times: Vec<f64> = r.trace.rows.iter().map(|row| row.time_s).collect();
        let values: Vec<f64> = r.trace.rows.iter().map(value).collect();
        chart.series.push(Series::new(
            r.controller.kind().label(),
            PALETTE[k % PALETTE.len()],
            points(&times, &values, view),
        ));
    }
    if let (Some((label, f)), Some(first)) = (logged, results.first()) {
        let times: Vec<f64> = first.trace.rows.iter().map(|row| row.time_s).collect();
        let values: Vec<f64> = first.trace.rows.iter().map(f).collect();
        if values.iter().any(|v| v.is_finite()) {
            chart
                .series
                .push(Series::new(label, PALETTE[7], points(&times, &values, view)).dashed());
        }
    }
    chart.fit();
    chart
}
