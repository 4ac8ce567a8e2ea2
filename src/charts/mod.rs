//! Charts: what to draw ([`LineChart`]) apart from where to draw it.
//!
//! The drawing functions take any plotters [`DrawingArea`], so the browser draws them on a canvas
//! (plotters-canvas) and the tests draw them into an SVG string natively. A chart returns the
//! [`PlotGeometry`] it used, which lets the UI turn a mouse position back into data coordinates for
//! hover readouts, zoom and pan without asking plotters again.
//!
//! Non-finite points are gaps: a series is split into separate polylines around them, so one bad
//! sample never draws a line to infinity. On a logarithmic axis, points at or below zero are gaps
//! too.
//!
//! | file | what |
//! |---|---|
//! | this file | line charts: series, axes, drawing on any `DrawingArea`, the geometry for the pointer |
//! | [`pareto`] | a trade-off chart: every result as a dot, the Pareto front highlighted |
//! | [`view`] | what part of a chart is shown: zoom, pan, hidden series, the hover readout |

pub mod pareto;
pub mod view;

use std::ops::Range;

use plotters::coord::Shift;
use plotters::prelude::*;

/// An sRGB colour.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Rgb(pub u8, pub u8, pub u8);

impl Rgb {
    /// The colour as a CSS string, for legends drawn in HTML.
    pub fn css(self) -> String {
        format!("rgb({}, {}, {})", self.0, self.1, self.2)
    }

    fn plotters(self) -> RGBColor {
        RGBColor(self.0, self.1, self.2)
    }
}

/// A palette that stays distinguishable for colour-blind readers (Okabe & Ito, 2008), its yellow
/// darkened so a line in it reads on white.
pub const PALETTE: [Rgb; 8] = [
    Rgb(0, 114, 178),
    Rgb(230, 159, 0),
    Rgb(0, 158, 115),
    Rgb(204, 121, 167),
    Rgb(86, 180, 233),
    Rgb(213, 94, 0),
    // Okabe–Ito's yellow darkened to an olive (3.8:1 on white): the original vanishes on white.
    Rgb(150, 130, 0),
    Rgb(0, 0, 0),
];

/// How a series' line is drawn.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stroke {
    /// A continuous line.
    Solid,
    /// A dashed line, for targets and limits.
    Dashed,
    /// A dot at each point and no line, for a scatter of results.
    Points,
    /// A continuous line with a dot at each point, for a few results that form a curve.
    LinePoints,
}

/// One named line.
#[derive(Debug, Clone, PartialEq)]
pub struct Series {
    /// Legend text.
    pub label: String,
    /// Line colour.
    pub color: Rgb,
    /// Line style.
    pub stroke: Stroke,
    /// The points, in data coordinates, in drawing order.
    pub points: Vec<(f64, f64)>,
}

impl Series {
    /// A solid series.
    pub fn new(label: impl Into<String>, color: Rgb, points: Vec<(f64, f64)>) -> Self {
        Self {
            label: label.into(),
            color,
            stroke: Stroke::Solid,
            points,
        }
    }

    /// The same series drawn dashed.
    pub fn dashed(mut self) -> Self {
        self.stroke = Stroke::Dashed;
        self
    }

    /// The same series drawn with another stroke.
    pub fn with_stroke(mut self, stroke: Stroke) -> Self {
        self.stroke = stroke;
        self
    }

    /// The same series as the faint trace of an earlier run beside the current one: its colour
    /// faded toward the white of the plot ([`BEFORE_FADE`]), dashed, and labelled "before: …" in
    /// the legend, so the current run stays the one that reads first.
    pub fn before(mut self) -> Self {
        self.label = format!("before: {}", self.label);
        self.color = self.color.faded(BEFORE_FADE);
        self.stroke = Stroke::Dashed;
        self
    }
}

/// How far an earlier run's trace is faded toward white (0: its own colour, 1: white): light
/// enough to sit behind the current run, dark enough to follow on a white plot.
pub const BEFORE_FADE: f64 = 0.55;

impl Rgb {
    /// This colour mixed with white, `fraction` of the way (0: unchanged, 1: white).
    pub fn faded(self, fraction: f64) -> Rgb {
        let f = fraction.clamp(0.0, 1.0);
        let mix = |c: u8| (f64::from(c) + (255.0 - f64::from(c)) * f).round() as u8;
        Rgb(mix(self.0), mix(self.1), mix(self.2))
    }
}

/// Linear or logarithmic axis.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Scale {
    /// Evenly spaced values.
    Linear,
    /// Evenly spaced decades; only positive values are shown.
    Log,
}

impl Scale {
    /// A data value in the space where the axis is linear (its decade for a log axis).
    pub fn to_linear(self, value: f64) -> f64 {
        match self {
            Scale::Linear => value,
            Scale::Log => value.log10(),
        }
    }

    /// The data value of a point in the axis's linear space.
    pub fn from_linear(self, position: f64) -> f64 {
        match self {
            Scale::Linear => position,
            Scale::Log => 10f64.powf(position),
        }
    }

    /// Where `value` lies along `range`, 0 at its start and 1 at its end.
    ///
    /// ```
    /// use cutlab::charts::Scale;
    /// assert_eq!(Scale::Linear.fraction(&(0.0..10.0), 2.5), 0.25);
    /// assert!((Scale::Log.fraction(&(1.0..100.0), 10.0) - 0.5).abs() < 1e-12);
    /// ```
    pub fn fraction(self, range: &Range<f64>, value: f64) -> f64 {
        let (a, b) = (self.to_linear(range.start), self.to_linear(range.end));
        (self.to_linear(value) - a) / (b - a)
    }

    /// The value at `fraction` along `range` (the inverse of [`Scale::fraction`]).
    pub fn at_fraction(self, range: &Range<f64>, fraction: f64) -> f64 {
        let (a, b) = (self.to_linear(range.start), self.to_linear(range.end));
        self.from_linear(a + fraction * (b - a))
    }
}

/// One axis: its label (with unit) and the shown range.
#[derive(Debug, Clone, PartialEq)]
pub struct Axis {
    /// Label with unit, e.g. `"frequency (Hz)"`.
    pub label: String,
    /// The shown range; [`LineChart::fit`] fills it from the data.
    pub range: Range<f64>,
    /// Linear or logarithmic.
    pub scale: Scale,
}

impl Axis {
    /// A linear axis with an empty range, to be fitted to the data.
    pub fn linear(label: impl Into<String>) -> Self {
        Self {
            label: label.into(),
            range: 0.0..1.0,
            scale: Scale::Linear,
        }
    }

    /// A logarithmic axis with an empty range, to be fitted to the data.
    pub fn log(label: impl Into<String>) -> Self {
        Self {
            scale: Scale::Log,
            ..Self::linear(label)
        }
    }
}

/// A line chart: axes and series.
#[derive(Debug, Clone, PartialEq)]
pub struct LineChart {
    /// Caption above the plot, if any.
    pub caption: Option<String>,
    /// Horizontal axis.
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// The lines, drawn in order.
    pub series: Vec<Series>,
}

/// Where the plotting area landed on the drawing area, in backend pixels, and what it shows.
#[derive(Debug, Clone, PartialEq)]
pub struct PlotGeometry {
    /// Pixel columns of the plotting area.
    pub x_px: Range<i32>,
    /// Pixel rows of the plotting area (top to bottom).
    pub y_px: Range<i32>,
    /// The data range shown horizontally.
    pub x_range: Range<f64>,
    /// The data range shown vertically.
    pub y_range: Range<f64>,
    /// Horizontal scale.
    pub x_scale: Scale,
    /// Vertical scale.
    pub y_scale: Scale,
}

impl PlotGeometry {
    /// The data x at pixel column `px` (outside the plotting area it extrapolates).
    ///
    /// ```
    /// use cutlab::charts::{PlotGeometry, Scale};
    /// let g = PlotGeometry { x_px: 100..300, y_px: 0..100, x_range: 1.0..100.0,
    ///     y_range: 0.0..1.0, x_scale: Scale::Log, y_scale: Scale::Linear };
    /// assert!((g.x_at(200.0) - 10.0).abs() < 1e-12);
    /// assert!((g.y_at(25.0) - 0.75).abs() < 1e-12);
    /// ```
    pub fn x_at(&self, px: f64) -> f64 {
        let t =
            (px - f64::from(self.x_px.start)) / f64::from((self.x_px.end - self.x_px.start).max(1));
        self.x_scale.at_fraction(&self.x_range, t)
    }

    /// The data y at pixel row `py`.
    pub fn y_at(&self, py: f64) -> f64 {
        let t =
            (f64::from(self.y_px.end) - py) / f64::from((self.y_px.end - self.y_px.start).max(1));
        self.y_scale.at_fraction(&self.y_range, t)
    }

    /// True if the pixel lies inside the plotting area.
    pub fn contains(&self, px: f64, py: f64) -> bool {
        px >= f64::from(self.x_px.start)
            && px <= f64::from(self.x_px.end)
            && py >= f64::from(self.y_px.start)
            && py <= f64::from(self.y_px.end)
    }
}

impl LineChart {
    /// A chart with the given axes and no series.
    pub fn new(x: Axis, y: Axis) -> Self {
        Self {
            caption: None,
            x,
            y,
            series: Vec::new(),
        }
    }

    /// Sets both axis ranges to the data's extent (with a small margin vertically).
    pub fn fit(&mut self) {
        self.x.range = data_extent(&self.series, |p| p.0, self.x.scale, 0.0);
        self.y.range = data_extent(&self.series, |p| p.1, self.y.scale, 0.05);
    }
}

/// The extent of one coordinate over every finite point, widened by `margin` of its span; a
/// degenerate or empty extent becomes a unit-wide range so an axis can always be drawn.
fn data_extent(
    series: &[Series],
    coordinate: impl Fn(&(f64, f64)) -> f64,
    scale: Scale,
    margin: f64,
) -> Range<f64> {
    let values = series
        .iter()
        .flat_map(|s| s.points.iter())
        .filter(|p| p.0.is_finite() && p.1.is_finite())
        .map(coordinate)
        .filter(|v| scale == Scale::Linear || *v > 0.0);
    let (lo, hi) = values.fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    match scale {
        _ if !(lo.is_finite() && hi.is_finite()) => match scale {
            Scale::Linear => 0.0..1.0,
            Scale::Log => 1.0..10.0,
        },
        Scale::Linear if hi - lo <= f64::EPSILON * hi.abs().max(1.0) => (lo - 0.5)..(hi + 0.5),
        Scale::Linear => {
            let pad = margin * (hi - lo);
            (lo - pad)..(hi + pad)
        }
        Scale::Log if hi / lo < 1.0 + 1e-9 => (lo / 2.0)..(hi * 2.0),
        Scale::Log => lo..hi,
    }
}

/// Splits a series into runs of drawable points (finite, and positive where an axis is
/// logarithmic), so gaps stay gaps.
fn drawable_runs(
    points: &[(f64, f64)],
    x_scale: Scale,
    y_scale: Scale,
) -> impl Iterator<Item = &[(f64, f64)]> {
    let drawable = move |p: &(f64, f64)| {
        p.0.is_finite()
            && p.1.is_finite()
            && (x_scale == Scale::Linear || p.0 > 0.0)
            && (y_scale == Scale::Linear || p.1 > 0.0)
    };
    points
        .split(move |p| !drawable(p))
        .filter(|run| !run.is_empty())
}

/// A short axis label: plain decimals for ordinary magnitudes, `1e-7` style for very small or
/// large ones (plotters' default prints every digit of a logarithmic axis's ticks).
///
/// ```
/// use cutlab::charts::tick_label;
/// assert_eq!(tick_label(&0.5), "0.5");
/// assert_eq!(tick_label(&1500.0), "1500");
/// assert_eq!(tick_label(&1e-7), "1e-7");
/// assert_eq!(tick_label(&2.5e6), "2.5e6");
/// ```
pub fn tick_label(v: &f64) -> String {
    let v = *v;
    let magnitude = v.abs();
    if v == 0.0 {
        "0".to_string()
    } else if !(1e-3..1e5).contains(&magnitude) {
        let text = format!("{v:.1e}");
        text.replace(".0e", "e")
    } else {
        let text = format!("{v:.4}");
        let text = text.trim_end_matches('0').trim_end_matches('.');
        text.to_string()
    }
}

impl Axis {
    /// The label of a tick at `v` on this axis: [`tick_label`], except that on a linear axis a
    /// tick within a billionth of the shown span of zero reads "0" — plotters steps its ticks in
    /// floating point, so the tick at zero of a range such as −0.3..0.5 arrives as −5.6e-17.
    ///
    /// ```
    /// use cutlab::charts::Axis;
    /// let mut y = Axis::linear("y (mm)");
    /// y.range = -0.3..0.5;
    /// assert_eq!(y.tick_label(-5.551115123125783e-17), "0");
    /// assert_eq!(y.tick_label(0.1), "0.1");
    /// ```
    pub fn tick_label(&self, v: f64) -> String {
        let span = (self.range.end - self.range.start).abs();
        if self.scale == Scale::Linear && span.is_finite() && v.abs() <= span * 1e-9 {
            "0".to_string()
        } else {
            tick_label(&v)
        }
    }
}

/// Visual settings that depend on the output device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChartStyle {
    /// Device pixels per CSS pixel (2 on most high-DPI screens): fonts and lines scale with it so
    /// the chart is crisp without looking tiny.
    pub pixel_ratio: f64,
}

impl Default for ChartStyle {
    fn default() -> Self {
        Self { pixel_ratio: 1.0 }
    }
}

impl ChartStyle {
    fn px(&self, css_px: f64) -> u32 {
        (css_px * self.pixel_ratio).round().max(1.0) as u32
    }
}

/// The error type of drawing on backend `DB`.
pub type DrawResult<DB> =
    Result<PlotGeometry, DrawingAreaErrorKind<<DB as DrawingBackend>::ErrorType>>;

/// Draws `chart` on `area`, filling it, and returns where the plotting area landed.
pub fn draw_line_chart<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    chart: &LineChart,
    style: ChartStyle,
) -> DrawResult<DB> {
    area.fill(&WHITE)?;
    let x = sanitized(&chart.x);
    let y = sanitized(&chart.y);
    match (x.scale, y.scale) {
        (Scale::Linear, Scale::Linear) => {
            draw_in(area, chart, style, x.range.clone(), y.range.clone(), &x, &y)
        }
        (Scale::Log, Scale::Linear) => draw_in(
            area,
            chart,
            style,
            x.range.clone().log_scale(),
            y.range.clone(),
            &x,
            &y,
        ),
        (Scale::Linear, Scale::Log) => draw_in(
            area,
            chart,
            style,
            x.range.clone(),
            y.range.clone().log_scale(),
            &x,
            &y,
        ),
        (Scale::Log, Scale::Log) => draw_in(
            area,
            chart,
            style,
            x.range.clone().log_scale(),
            y.range.clone().log_scale(),
            &x,
            &y,
        ),
    }
}

/// An axis whose range plotters can draw: finite, increasing, positive on a log scale.
fn sanitized(axis: &Axis) -> Axis {
    let Range { start, end } = axis.range;
    let usable = start.is_finite()
        && end.is_finite()
        && end > start
        && (axis.scale == Scale::Linear || start > 0.0);
    Axis {
        label: axis.label.clone(),
        scale: axis.scale,
        range: if usable {
            start..end
        } else if axis.scale == Scale::Log {
            1.0..10.0
        } else {
            0.0..1.0
        },
    }
}

fn draw_in<DB, XR, YR>(
    area: &DrawingArea<DB, Shift>,
    chart: &LineChart,
    style: ChartStyle,
    x_spec: XR,
    y_spec: YR,
    x_axis: &Axis,
    y_axis: &Axis,
) -> DrawResult<DB>
where
    DB: DrawingBackend,
    XR: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    YR: plotters::coord::ranged1d::AsRangedCoord<Value = f64>,
    XR::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
    YR::CoordDescType: plotters::coord::ranged1d::ValueFormatter<f64>,
{
    let font = ("sans-serif", f64::from(style.px(13.0)));
    let small_font = ("sans-serif", f64::from(style.px(12.0)));
    let mut builder = ChartBuilder::on(area);
    builder
        .margin(style.px(8.0))
        .x_label_area_size(style.px(40.0))
        .y_label_area_size(style.px(64.0));
    if let Some(caption) = &chart.caption {
        builder.caption(caption, font);
    }
    let mut ctx = builder.build_cartesian_2d(x_spec, y_spec)?;
    ctx.configure_mesh()
        .x_desc(x_axis.label.as_str())
        .y_desc(y_axis.label.as_str())
        .label_style(small_font)
        .axis_desc_style(font)
        .light_line_style(RGBColor(236, 239, 243))
        .bold_line_style(RGBColor(214, 220, 228))
        .x_labels(8)
        .y_labels(6)
        .x_label_formatter(&|v| x_axis.tick_label(*v))
        .y_label_formatter(&|v| y_axis.tick_label(*v))
        .draw()?;

    let width = style.px(1.6);
    for series in &chart.series {
        let color = series.color.plotters();
        let line_style = color.stroke_width(width);
        let dot = style.px(3.5);
        for run in drawable_runs(&series.points, x_axis.scale, y_axis.scale) {
            if matches!(series.stroke, Stroke::Points | Stroke::LinePoints) {
                ctx.draw_series(run.iter().map(|&p| Circle::new(p, dot, color.filled())))?;
            }
            match series.stroke {
                Stroke::Points => {}
                Stroke::Solid | Stroke::LinePoints => {
                    ctx.draw_series(LineSeries::new(run.iter().copied(), line_style))?;
                }
                Stroke::Dashed => {
                    ctx.draw_series(DashedLineSeries::new(
                        run.iter().copied(),
                        style.px(6.0),
                        style.px(4.0),
                        line_style,
                    ))?;
                }
            }
        }
    }
    let (x_px, y_px) = ctx.plotting_area().get_pixel_range();
    Ok(PlotGeometry {
        x_px,
        y_px,
        x_range: x_axis.range.clone(),
        y_range: y_axis.range.clone(),
        x_scale: x_axis.scale,
        y_scale: y_axis.scale,
    })
}

/// Values on a regular grid, drawn as coloured cells: a control surface U(E, EC).
#[derive(Debug, Clone, PartialEq)]
pub struct HeatMap {
    /// Horizontal axis (label and range of the grid).
    pub x: Axis,
    /// Vertical axis.
    pub y: Axis,
    /// Columns of the grid.
    pub nx: usize,
    /// Rows of the grid.
    pub ny: usize,
    /// `values[j * nx + i]` at column i, row j (row 0 at the bottom).
    pub values: Vec<f64>,
    /// The value range the colours span.
    pub value_range: Range<f64>,
}

/// A diverging blue–white–orange colour for `t` in [0, 1] (readable by colour-blind people).
pub fn diverging_color(t: f64) -> Rgb {
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.5
    };
    let (lo, mid, hi) = (
        (33.0, 102.0, 172.0),
        (247.0, 247.0, 247.0),
        (230.0, 97.0, 1.0),
    );
    let (a, b, u) = if t < 0.5 {
        (lo, mid, t / 0.5)
    } else {
        (mid, hi, (t - 0.5) / 0.5)
    };
    let mix = |p: f64, q: f64| (p + (q - p) * u).round() as u8;
    Rgb(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// Draws `map` on `area`; cells outside the value range take the end colours.
pub fn draw_heat_map<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    map: &HeatMap,
    style: ChartStyle,
) -> DrawResult<DB> {
    area.fill(&WHITE)?;
    let x = sanitized(&map.x);
    let y = sanitized(&map.y);
    let font = ("sans-serif", f64::from(style.px(13.0)));
    let small_font = ("sans-serif", f64::from(style.px(12.0)));
    let mut ctx = ChartBuilder::on(area)
        .margin(style.px(8.0))
        .x_label_area_size(style.px(40.0))
        .y_label_area_size(style.px(52.0))
        .build_cartesian_2d(x.range.clone(), y.range.clone())?;
    ctx.configure_mesh()
        .disable_mesh()
        .x_desc(x.label.as_str())
        .y_desc(y.label.as_str())
        .label_style(small_font)
        .axis_desc_style(font)
        .x_label_formatter(&|v| x.tick_label(*v))
        .y_label_formatter(&|v| y.tick_label(*v))
        .draw()?;
    let (nx, ny) = (map.nx.max(1), map.ny.max(1));
    let dx = (x.range.end - x.range.start) / nx as f64;
    let dy = (y.range.end - y.range.start) / ny as f64;
    let span = map.value_range.end - map.value_range.start;
    ctx.draw_series((0..ny).flat_map(|j| {
        (0..nx).map(move |i| {
            let v = map.values.get(j * nx + i).copied().unwrap_or(f64::NAN);
            let t = if span > 0.0 {
                (v - map.value_range.start) / span
            } else {
                0.5
            };
            let x0 = x.range.start + i as f64 * dx;
            let y0 = y.range.start + j as f64 * dy;
            Rectangle::new(
                [(x0, y0), (x0 + dx, y0 + dy)],
                diverging_color(t).plotters().filled(),
            )
        })
    }))?;
    let (x_px, y_px) = ctx.plotting_area().get_pixel_range();
    Ok(PlotGeometry {
        x_px,
        y_px,
        x_range: x.range,
        y_range: y.range,
        x_scale: Scale::Linear,
        y_scale: Scale::Linear,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn render(chart: &LineChart) -> (String, PlotGeometry) {
        let mut svg = String::new();
        let geometry = {
            let area = SVGBackend::with_string(&mut svg, (640, 360)).into_drawing_area();
            let g = draw_line_chart(&area, chart, ChartStyle::default()).unwrap();
            area.present().unwrap();
            g
        };
        (svg, geometry)
    }

    fn sine_chart() -> LineChart {
        let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear("current (A)"));
        chart.series.push(Series::new(
            "i_u",
            PALETTE[0],
            (0..200)
                .map(|i| {
                    let t = f64::from(i) / 100.0;
                    (t, (std::f64::consts::TAU * t).sin())
                })
                .collect(),
        ));
        chart.fit();
        chart
    }

    #[test]
    fn fit_covers_the_data_with_a_vertical_margin() {
        let chart = sine_chart();
        assert_eq!(chart.x.range, 0.0..1.99);
        assert!(chart.y.range.start < -0.99 && chart.y.range.start > -1.2);
        assert!(chart.y.range.end > 0.99 && chart.y.range.end < 1.2);
    }

    #[test]
    fn a_dotted_series_is_one_circle_per_point_and_no_line() {
        let mut chart = LineChart::new(Axis::linear("force (N)"), Axis::linear("current (A)"));
        chart.series.push(
            Series::new(
                "periods",
                PALETTE[0],
                vec![(100.0, 5.0), (200.0, 6.0), (f64::NAN, 1.0), (300.0, 7.0)],
            )
            .with_stroke(Stroke::Points),
        );
        chart.fit();
        let (svg, _) = render(&chart);
        assert_eq!(svg.matches("<circle").count(), 3, "{svg}");
    }

    #[test]
    fn draws_axes_labels_and_lines() {
        let (svg, geometry) = render(&sine_chart());
        assert!(svg.contains("time (s)"));
        assert!(svg.contains("current (A)"));
        assert!(svg.contains("<polyline"), "no line drawn");
        assert!(geometry.x_px.start > 0 && geometry.x_px.end < 640);
        // The pixel mapping returns the axis ends.
        assert!((geometry.x_at(f64::from(geometry.x_px.start)) - 0.0).abs() < 1e-12);
        assert!((geometry.x_at(f64::from(geometry.x_px.end)) - 1.99).abs() < 1e-12);
    }

    #[test]
    fn non_finite_points_split_the_line_instead_of_breaking_the_chart() {
        let mut chart = LineChart::new(Axis::linear("x"), Axis::linear("y"));
        chart.series.push(Series::new(
            "gappy",
            PALETTE[1],
            vec![
                (0.0, 0.0),
                (1.0, 1.0),
                (2.0, f64::NAN),
                (3.0, 1.0),
                (4.0, 0.0),
            ],
        ));
        chart.fit();
        assert_eq!(chart.y.range.start, -0.05);
        let (svg, _) = render(&chart);
        let series_lines = svg
            .lines()
            .filter(|l| l.contains("<polyline") && l.contains("#E69F00"))
            .count();
        assert_eq!(series_lines, 2, "{svg}");
    }

    #[test]
    fn points_draw_dots_without_a_line_and_line_points_both() {
        let mut chart = LineChart::new(Axis::linear("x"), Axis::linear("y"));
        let points = vec![(0.0, 1.0), (1.0, 3.0), (2.0, f64::NAN), (3.0, 2.0)];
        chart
            .series
            .push(Series::new("dots", PALETTE[1], points.clone()).with_stroke(Stroke::Points));
        chart.fit();
        let (svg, _) = render(&chart);
        let count = |svg: &str, tag: &str| {
            svg.lines()
                .filter(|l| l.contains(tag) && l.contains("#E69F00"))
                .count()
        };
        assert_eq!(
            (count(&svg, "<circle"), count(&svg, "<polyline")),
            (3, 0),
            "{svg}"
        );
        chart.series[0].stroke = Stroke::LinePoints;
        let (svg, _) = render(&chart);
        // The gap splits the line in two and leaves its point out.
        assert_eq!(
            (count(&svg, "<circle"), count(&svg, "<polyline")),
            (3, 2),
            "{svg}"
        );
    }

    #[test]
    fn an_earlier_run_is_drawn_faint_dashed_and_labelled_before() {
        let mut chart = sine_chart();
        let now = chart.series[0].clone();
        let earlier = now.clone().before();
        assert_eq!(earlier.label, format!("before: {}", now.label));
        assert_eq!(earlier.stroke, Stroke::Dashed);
        // Lighter in every channel than the current run's colour, not white.
        let (a, b) = (now.color, earlier.color);
        assert!(
            b.0 >= a.0 && b.1 >= a.1 && b.2 >= a.2 && b != a,
            "{b:?} vs {a:?}"
        );
        assert_ne!(b, Rgb(255, 255, 255));
        chart.series.push(earlier);
        let (svg, _) = render(&chart);
        let hex = format!("#{:02X}{:02X}{:02X}", b.0, b.1, b.2);
        assert!(svg.contains(&hex), "the faint colour {hex} is not drawn");
    }

    #[test]
    fn empty_and_degenerate_charts_still_draw() {
        let mut chart = LineChart::new(Axis::log("f (Hz)"), Axis::linear("y"));
        chart.fit();
        assert_eq!(chart.x.range, 1.0..10.0);
        render(&chart);
        chart.series.push(Series::new(
            "flat",
            PALETTE[2],
            vec![(5.0, 3.0), (50.0, 3.0)],
        ));
        chart.fit();
        assert_eq!(chart.y.range, 2.5..3.5);
        chart.x.range = f64::NAN..1.0;
        render(&chart);
    }

    #[test]
    fn heat_maps_draw_one_cell_per_value_in_diverging_colours() {
        let map = HeatMap {
            x: Axis {
                label: "E".into(),
                range: -6.0..6.0,
                scale: Scale::Linear,
            },
            y: Axis {
                label: "EC".into(),
                range: -6.0..6.0,
                scale: Scale::Linear,
            },
            nx: 3,
            ny: 2,
            values: vec![-6.0, 0.0, 6.0, -3.0, 3.0, f64::NAN],
            value_range: -6.0..6.0,
        };
        let mut svg = String::new();
        {
            let area = SVGBackend::with_string(&mut svg, (300, 300)).into_drawing_area();
            draw_heat_map(&area, &map, ChartStyle::default()).unwrap();
            area.present().unwrap();
        }
        assert_eq!(diverging_color(0.0), Rgb(33, 102, 172));
        assert_eq!(diverging_color(0.5), Rgb(247, 247, 247));
        assert_eq!(diverging_color(1.0), Rgb(230, 97, 1));
        assert!(svg.contains("#2166AC"), "lowest value's colour missing");
        assert!(svg.contains("#E66101"), "highest value's colour missing");
    }

    #[test]
    fn log_axis_hides_non_positive_points() {
        let runs: Vec<_> = drawable_runs(
            &[
                (0.0, 1.0),
                (1.0, 1.0),
                (10.0, 2.0),
                (-1.0, 3.0),
                (100.0, 4.0),
            ],
            Scale::Log,
            Scale::Linear,
        )
        .collect();
        assert_eq!(runs.len(), 2);
        assert_eq!(runs[0], &[(1.0, 1.0), (10.0, 2.0)]);
    }

    #[test]
    fn a_tick_at_zero_reads_0_not_a_rounding_residue() {
        // Ranges whose zero tick plotters reaches by adding steps in floating point.
        for (start, end) in [(-0.3, 0.5), (-0.7, 0.35), (-0.03, 0.06), (-3.3, 1.1)] {
            let mut chart = sine_chart();
            chart.x.range = 0.5..2.0;
            chart.y.range = start..end;
            let (svg, _) = render(&chart);
            assert!(
                !svg.contains("e-1"),
                "a residue tick on {start}..{end}: {svg}"
            );
            assert!(
                svg.contains(">\n0\n</text>"),
                "no tick reads 0 on {start}..{end}: {svg}"
            );
        }
    }

    /// WCAG's contrast ratio of a colour against white.
    fn contrast_on_white(c: Rgb) -> f64 {
        let channel = |v: u8| {
            let v = f64::from(v) / 255.0;
            if v <= 0.039_28 {
                v / 12.92
            } else {
                ((v + 0.055) / 1.055).powf(2.4)
            }
        };
        let luminance = 0.2126 * channel(c.0) + 0.7152 * channel(c.1) + 0.0722 * channel(c.2);
        1.05 / (luminance + 0.05)
    }

    #[test]
    fn no_palette_colour_is_pale_on_white() {
        // Okabe–Ito's yellow (240, 228, 66) is 1.3:1 on white and vanished as a fuzzy set's line;
        // its orange and sky blue, the palest kept, are 2.3:1.
        for colour in PALETTE {
            let ratio = contrast_on_white(colour);
            assert!(ratio >= 2.2, "{colour:?} is {ratio:.2}:1 on white");
        }
    }
}
