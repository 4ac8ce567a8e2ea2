//! What part of a chart is shown: zoom, pan, hidden series, and the hover readout.
//!
//! This is the pure half of chart interaction; the web layer only turns wheel, drag, key and
//! pointer events into calls here. Horizontal zoom and pan are shared by every chart of a page
//! (linked time axes); the vertical range follows the data that is visible.

use std::ops::Range;

use super::{LineChart, Scale, Series};
use crate::signal::decimate::min_max;

/// Zooms `range` by `factor` (< 1 zooms in) keeping the data value `anchor` at the same place.
///
/// ```
/// use cutlab::charts::view::zoom;
/// use cutlab::charts::Scale;
/// let r = zoom(&(0.0..10.0), 5.0, 0.5, Scale::Linear);
/// assert_eq!(r, 2.5..7.5);
/// let r = zoom(&(1.0..100.0), 10.0, 0.5, Scale::Log);
/// assert!((r.start - 10f64.powf(0.5)).abs() < 1e-12 && (r.end - 10f64.powf(1.5)).abs() < 1e-12);
/// ```
pub fn zoom(range: &Range<f64>, anchor: f64, factor: f64, scale: Scale) -> Range<f64> {
    let to = |v| scale.to_linear(v);
    let (a, b, c) = (to(range.start), to(range.end), to(anchor));
    let c = if c.is_finite() { c } else { (a + b) / 2.0 };
    scale.from_linear(c + (a - c) * factor)..scale.from_linear(c + (b - c) * factor)
}

/// Moves `range` by `fraction` of its width (positive moves toward larger values).
pub fn pan(range: &Range<f64>, fraction: f64, scale: Scale) -> Range<f64> {
    let (a, b) = (scale.to_linear(range.start), scale.to_linear(range.end));
    let shift = (b - a) * fraction;
    scale.from_linear(a + shift)..scale.from_linear(b + shift)
}

/// The chart as shown: series hidden by the legend removed, points outside `x_range` dropped
/// (keeping one neighbour on each side so lines run to the edge), each series reduced to at most
/// `max_points` by [`min_max`] decimation (every peak stays visible), and the vertical range
/// fitted to what remains.
pub fn visible(
    chart: &LineChart,
    x_range: Option<&Range<f64>>,
    hidden: &[bool],
    max_points: usize,
) -> LineChart {
    let mut shown = LineChart {
        caption: chart.caption.clone(),
        x: chart.x.clone(),
        y: chart.y.clone(),
        series: chart
            .series
            .iter()
            .enumerate()
            .filter(|(i, _)| !hidden.get(*i).copied().unwrap_or(false))
            .map(|(_, s)| Series {
                points: min_max(window(&s.points, x_range), max_points),
                ..s.clone()
            })
            .collect(),
    };
    let x_fixed = chart.x.range.clone();
    let y_fixed = chart.y.range.clone();
    shown.fit();
    match x_range {
        Some(r) => shown.x.range = r.clone(),
        None => shown.x.range = x_fixed,
    }
    if shown.series.iter().all(|s| s.points.is_empty()) {
        shown.y.range = y_fixed;
    } else {
        // A range the chart set on purpose (e.g. a −200 dB floor) bounds the fitted one.
        let start = shown.y.range.start.max(y_fixed.start);
        let end = shown.y.range.end.min(y_fixed.end);
        if start < end {
            shown.y.range = start..end;
        }
    }
    shown
}

/// The points of a series sorted by x that fall within `range`, plus one on each side.
fn window<'a>(points: &'a [(f64, f64)], range: Option<&Range<f64>>) -> &'a [(f64, f64)] {
    let Some(range) = range else {
        return points;
    };
    let sorted = points.windows(2).all(|w| w[1].0 >= w[0].0);
    if !sorted {
        return points;
    }
    let start = points
        .partition_point(|p| p.0 < range.start)
        .saturating_sub(1);
    let end = (points.partition_point(|p| p.0 <= range.end) + 1).min(points.len());
    &points[start.min(end)..end]
}

/// The finite point of `series` whose x is nearest to `x` (series sorted by x), if any; a gap
/// (non-finite y) is never a readout.
///
/// ```
/// use cutlab::charts::{view::nearest, Series, PALETTE};
/// let s = Series::new("s", PALETTE[0], vec![(0.0, 1.0), (1.0, 2.0), (2.0, 3.0)]);
/// assert_eq!(nearest(&s, 1.4), Some((1.0, 2.0)));
/// assert_eq!(nearest(&s, 9.0), Some((2.0, 3.0)));
/// let gappy = Series::new("g", PALETTE[0], vec![(0.0, 1.0), (1.0, f64::NAN), (2.0, 3.0)]);
/// assert_eq!(nearest(&gappy, 1.2), Some((2.0, 3.0)));
/// ```
pub fn nearest(series: &Series, x: f64) -> Option<(f64, f64)> {
    let points = &series.points;
    if points.is_empty() || !x.is_finite() {
        return None;
    }
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let i = points.partition_point(|p| p.0 < x);
    let before = points[..i].iter().rev().find(finite);
    let after = points[i..].iter().find(finite);
    [before, after]
        .into_iter()
        .flatten()
        .copied()
        .min_by(|a, b| (a.0 - x).abs().total_cmp(&(b.0 - x).abs()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::charts::{Axis, PALETTE};

    fn long_series(n: usize) -> Vec<(f64, f64)> {
        (0..n)
            .map(|i| {
                let t = i as f64;
                // A single one-sample spike must survive decimation.
                (t, if i == n / 3 { 100.0 } else { (t * 0.01).sin() })
            })
            .collect()
    }

    #[test]
    fn a_long_series_is_reduced_but_keeps_its_spike() {
        let mut chart = LineChart::new(Axis::linear("t (s)"), Axis::linear("i (A)"));
        chart
            .series
            .push(Series::new("i_u", PALETTE[0], long_series(1_000_000)));
        chart.fit();
        let shown = visible(&chart, None, &[], 2000);
        let points = &shown.series[0].points;
        assert!(points.len() <= 2000, "{}", points.len());
        assert!(points.iter().any(|p| p.1 == 100.0), "the spike was lost");
        assert!(shown.y.range.end > 100.0);
    }

    #[test]
    fn zoom_then_pan_and_back() {
        let r = zoom(&(0.0..100.0), 25.0, 0.5, Scale::Linear);
        assert_eq!(r, 12.5..62.5);
        let r = pan(&r, 0.5, Scale::Linear);
        assert_eq!(r, 37.5..87.5);
        let r = zoom(&r, 62.5, 2.0, Scale::Linear);
        assert_eq!(r, 12.5..112.5);
    }

    #[test]
    fn visible_drops_hidden_series_and_refits_y_to_the_window() {
        let mut chart = LineChart::new(Axis::linear("t (s)"), Axis::linear("F (N)"));
        chart.series.push(Series::new(
            "a",
            PALETTE[0],
            (0..100).map(|i| (f64::from(i), f64::from(i))).collect(),
        ));
        chart.series.push(Series::new(
            "b",
            PALETTE[1],
            vec![(0.0, 1000.0), (99.0, 1000.0)],
        ));
        chart.fit();
        let shown = visible(&chart, Some(&(10.0..20.0)), &[false, true], 1000);
        assert_eq!(shown.series.len(), 1);
        assert_eq!(shown.x.range, 10.0..20.0);
        // Points 9..=21 are kept (one neighbour each side): y fits 9..21 with a 5 % margin.
        assert!(
            (shown.y.range.start - 8.4).abs() < 1e-9,
            "{:?}",
            shown.y.range
        );
        assert!(
            (shown.y.range.end - 21.6).abs() < 1e-9,
            "{:?}",
            shown.y.range
        );
    }
}
