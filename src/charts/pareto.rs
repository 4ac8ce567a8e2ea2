//! A trade-off chart: every result as a dot, the Pareto front as a highlighted line through its
//! members, and the chosen (best) result marked — cycle time against force error on the Tune
//! page.

use super::{Axis, LineChart, Series, Stroke, PALETTE};

/// The chart of `points` (x, y), with the points at the indices `front` joined as the front (in
/// increasing x) and the point at `best` marked. Non-finite points are left out; the series are
/// sorted by x, as the hover readout expects.
///
/// ```
/// use cutlab::charts::pareto::trade_off_chart;
/// use cutlab::charts::Axis;
/// let points = [(10.0, 5.0), (12.0, 3.0), (11.0, 6.0), (15.0, 1.0)];
/// let chart = trade_off_chart(Axis::linear("cycle (s)"), Axis::linear("error (%)"),
///     &points, &[0, 1, 3], Some(1));
/// assert_eq!(chart.series[0].points.len(), 4); // every result
/// assert_eq!(chart.series[1].points, vec![(10.0, 5.0), (12.0, 3.0), (15.0, 1.0)]); // the front
/// assert_eq!(chart.series[2].points, vec![(12.0, 3.0)]); // the best
/// ```
pub fn trade_off_chart(
    x: Axis,
    y: Axis,
    points: &[(f64, f64)],
    front: &[usize],
    best: Option<usize>,
) -> LineChart {
    let finite = |p: &&(f64, f64)| p.0.is_finite() && p.1.is_finite();
    let sorted = |mut v: Vec<(f64, f64)>| {
        v.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)));
        v
    };
    let all = sorted(points.iter().filter(finite).copied().collect());
    let on_front = sorted(
        front
            .iter()
            .filter_map(|&i| points.get(i))
            .filter(finite)
            .copied()
            .collect(),
    );
    let chosen: Vec<(f64, f64)> = best
        .and_then(|i| points.get(i))
        .filter(finite)
        .copied()
        .into_iter()
        .collect();
    let mut chart = LineChart::new(x, y);
    chart.series = vec![
        Series::new("every evaluation", PALETTE[4], all).with_stroke(Stroke::Points),
        Series::new("Pareto front", PALETTE[5], on_front).with_stroke(Stroke::LinePoints),
        Series::new("best objective", PALETTE[7], chosen).with_stroke(Stroke::Points),
    ];
    chart.fit();
    // Dots at the ends of the x range would be cut in half by the plot's edge: leave room, as
    // the fit does vertically.
    let (start, end) = (chart.x.range.start, chart.x.range.end);
    let pad = 0.05 * (end - start);
    chart.x.range = (start - pad)..(end + pad);
    chart
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::charts::{draw_line_chart, ChartStyle};
    use plotters::prelude::*;

    #[test]
    fn the_front_is_drawn_over_every_result_and_gaps_are_left_out() {
        let points = [
            (10.0, 5.0),
            (f64::NAN, 1.0),
            (12.0, 3.0),
            (11.0, 6.0),
            (15.0, 1.0),
            (9.0, f64::INFINITY),
        ];
        let chart = trade_off_chart(
            Axis::linear("cycle time (s)"),
            Axis::linear("force error (%)"),
            &points,
            &[0, 2, 4],
            Some(2),
        );
        assert_eq!(chart.series[0].points.len(), 4);
        assert!(chart.series[0].points.windows(2).all(|w| w[0].0 <= w[1].0));
        // The results span 10–15 s; 5 % of that on each side keeps the end dots whole.
        assert_eq!(chart.x.range, 9.75..15.25);
        let mut svg = String::new();
        {
            let area = SVGBackend::with_string(&mut svg, (480, 320)).into_drawing_area();
            draw_line_chart(&area, &chart, ChartStyle::default()).unwrap();
            area.present().unwrap();
        }
        let circles = |color: &str| {
            svg.lines()
                .filter(|l| l.contains("<circle") && l.contains(color))
                .count()
        };
        // Four results, three of them on the front (one line through them), one best.
        assert_eq!(circles("#56B4E9"), 4, "{svg}");
        assert_eq!(circles("#D55E00"), 3, "{svg}");
        assert_eq!(circles("#000000"), 1, "{svg}");
        let front_lines = svg
            .lines()
            .filter(|l| l.contains("<polyline") && l.contains("#D55E00"))
            .count();
        assert_eq!(front_lines, 1, "{svg}");
    }
}
