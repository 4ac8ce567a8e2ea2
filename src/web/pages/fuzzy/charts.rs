//! The fuzzy page's charts: the control surface U(E, EC) (click a point to view it), the run's E
//! and EC with the picked moment, and the membership functions.

use leptos::prelude::*;

use super::{Fuzzy, RunMoment};
use crate::charts::{Axis, HeatMap, LineChart, Series, PALETTE};
use crate::control::fuzzy::engine::Engine;
use crate::web::components::chart::ChartCanvas;
use crate::web::components::heat_map::HeatMapCanvas;
use crate::web::components::run_view::run_charts;

/// Grid points per axis of the control surface.
const SURFACE_POINTS: usize = 61;

fn surface(engine: &Engine) -> HeatMap {
    let mut engine = engine.clone();
    let (x_var, y_var) = (&engine.inputs()[0], &engine.inputs()[1]);
    let (x0, x1, y0, y1) = (x_var.min, x_var.max, y_var.min, y_var.max);
    let (x_name, y_name) = (x_var.name.clone(), y_var.name.clone());
    let (u_min, u_max) = (engine.outputs()[0].min, engine.outputs()[0].max);
    let n = SURFACE_POINTS;
    let mut values = Vec::with_capacity(n * n);
    let mut out = vec![0.0; engine.outputs().len()];
    for j in 0..n {
        let y = y0 + (j as f64 + 0.5) * (y1 - y0) / n as f64;
        for i in 0..n {
            let x = x0 + (i as f64 + 0.5) * (x1 - x0) / n as f64;
            engine.evaluate(&[x, y], &mut out);
            values.push(out[0]);
        }
    }
    HeatMap {
        x: Axis {
            label: x_name,
            range: x0..x1,
            scale: crate::charts::Scale::Linear,
        },
        y: Axis {
            label: y_name,
            range: y0..y1,
            scale: crate::charts::Scale::Linear,
        },
        nx: n,
        ny: n,
        values,
        value_range: u_min..u_max,
    }
}

fn membership_chart(engine: &Engine, input: Option<usize>) -> LineChart {
    let (name, min, max, terms) = match input {
        Some(i) => {
            let v = &engine.inputs()[i];
            (v.name.clone(), v.min, v.max, v.terms.clone())
        }
        None => {
            let v = &engine.outputs()[0];
            (v.name.clone(), v.min, v.max, v.terms.clone())
        }
    };
    let mut chart = LineChart::new(Axis::linear(name), Axis::linear("membership"));
    for (k, t) in terms.iter().enumerate() {
        let points = (0..=240)
            .map(|s| {
                let x = min + (max - min) * f64::from(s) / 240.0;
                (x, t.shape.degree(x))
            })
            .collect();
        chart.series.push(Series::new(
            t.name.clone(),
            PALETTE[k % PALETTE.len()],
            points,
        ));
    }
    chart.fit();
    chart.x.range = min..max;
    chart.y.range = 0.0..1.05;
    chart
}

/// The charts column.
#[component]
pub fn FuzzyCharts(fuzzy: Fuzzy, run: RunMoment) -> impl IntoView {
    let engine = fuzzy.engine;
    // Memo needs PartialEq; engines compare by identity of their Arc.
    let surface_map = Memo::new(move |_| engine.with(|e| e.as_ref().ok().map(|e| surface(e))));
    let map_signal = Signal::derive(move || {
        surface_map.get().unwrap_or(HeatMap {
            x: Axis::linear("E"),
            y: Axis::linear("EC"),
            nx: 1,
            ny: 1,
            values: vec![0.0],
            value_range: -1.0..1.0,
        })
    });
    let chart_of = move |input: Option<usize>| {
        Signal::derive(move || {
            engine
                .with(|e| e.as_ref().ok().map(|e| membership_chart(e, input)))
                .unwrap_or_else(|| LineChart::new(Axis::linear("x"), Axis::linear("membership")))
        })
    };
    let RunMoment { result, moment, .. } = run;
    // The run's E and EC over time, with the picked moment marked: the moment is picked on the
    // trace, not on a bare slider. The traces are built once per run; moving the slider only
    // moves the marker.
    let trace_chart = Memo::new(move |_| {
        let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear("scaled input"));
        result.with(|r| {
            let Some(r) = r else {
                return;
            };
            for (index, colour) in [(0, PALETTE[0]), (1, PALETTE[1])] {
                let Some((name, _)) = r.trace.term_names.get(index) else {
                    continue;
                };
                let points = r
                    .trace
                    .rows
                    .iter()
                    .map(|row| row.time_s)
                    .zip(r.trace.term_series(index))
                    .collect();
                chart.series.push(Series::new(*name, colour, points));
            }
            chart.fit();
        });
        chart
    });
    // The force the table held, against the target and the limit: the same chart Simulate
    // draws, so E and EC (scaled) read beside what they mean in newtons.
    let force_chart = Memo::new(move |_| {
        result.with(|r| {
            r.as_ref().map_or_else(
                || LineChart::new(Axis::linear("time (s)"), Axis::linear("force (N)")),
                |r| {
                    let [force, ..] = run_charts(&[("this table".to_string(), r.clone())], None);
                    force
                },
            )
        })
    });
    let moment_chart = Signal::derive(move || {
        let mut chart = trace_chart.get();
        let time = result.with(|r| {
            r.as_ref()
                .and_then(|r| r.trace.rows.get(moment.get()).map(|row| row.time_s))
        });
        if let Some(t) = time {
            let (lo, hi) = (chart.y.range.start, chart.y.range.end);
            chart.series.push(Series::new(
                "picked moment",
                PALETTE[3],
                vec![(t, lo), (t, hi)],
            ));
        }
        chart
    });
    view! {
        {move || engine.with(|e| e.as_ref().err().map(|m| view! { <p class="run-error" role="alert">{m.clone()}</p> }))}
        <HeatMapCanvas
            label="Control surface U(E, EC)"
            map=map_signal
            on_pick=Callback::new(move |(x, y): (f64, f64)| {
                fuzzy.e_text.set(format!("{x:.2}"));
                fuzzy.ec_text.set(format!("{y:.2}"));
            })
        />
        {move || {
            result
                .with(|r| r.is_some())
                .then(|| view! {
                    <ChartCanvas label="Force of the run" chart=force_chart height_px=200 />
                    <ChartCanvas label="E and EC of the run" chart=moment_chart height_px=180 />
                })
        }}
        <ChartCanvas label="Membership functions of E" chart=chart_of(Some(0)) height_px=180 />
        <ChartCanvas label="Membership functions of EC" chart=chart_of(Some(1)) height_px=180 />
        <ChartCanvas label="Membership functions of U" chart=chart_of(None) height_px=180 />
    }
}
