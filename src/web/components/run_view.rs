//! Charts, metrics table and event log of closed-loop runs, shared by Simulate and Compare.

use std::ops::Range;
use std::sync::Arc;

use leptos::prelude::*;

use crate::charts::{Axis, LineChart, Series, PALETTE};
use crate::closed_loop::lab::RunResult;
use crate::closed_loop::metrics::Metrics;
use crate::closed_loop::summary::{
    best_marks, format_metric, missing_notes, negative_saving_notes, not_best_note, MetricRow,
    METRIC_ROWS,
};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::help::HelpToggle;

/// A run with the name it is shown under.
pub type NamedRun = (String, Arc<RunResult>);

fn series_of(
    run: &RunResult,
    value: impl Fn(&crate::closed_loop::trace::TraceRow) -> f64,
) -> Vec<(f64, f64)> {
    run.trace
        .rows
        .iter()
        .map(|r| (r.time_s, value(r)))
        .collect()
}

fn time_chart(y_label: &str) -> LineChart {
    LineChart::new(Axis::linear("time (s)"), Axis::linear(y_label))
}

/// The charts of one or more runs: force, spindle current, feed-axis current, override, feed,
/// depth and the wall's force-induced error. With one run every signal of it is drawn; with
/// several, the main signal of each run is overlaid (the feed axis's current, a single run's
/// detail, is drawn for one run only). The feed axis's current (about 1 A) has a chart of its own:
/// beside the spindle's tens of amperes it would be a flat line. `before`, an earlier run of the same scenario, is drawn faint behind
/// a single run's main signals ([`Series::before`]), so an edit's effect shows at a glance.
pub fn run_charts(runs: &[NamedRun], before: Option<&RunResult>) -> [LineChart; 7] {
    let mut force = time_chart("force (N)");
    let mut current = time_chart("spindle current (A)");
    let mut feed_current = time_chart("feed-axis current (A)");
    let mut override_pct = time_chart("feed override (%)");
    let mut feed = time_chart("feed (mm/min)");
    let mut depth = time_chart("depth of cut (mm)");
    let mut wall = time_chart("wall error (µm)");
    let single = runs.len() == 1;
    for (k, (name, run)) in runs.iter().enumerate() {
        let color = PALETTE[k % PALETTE.len()];
        let label = |what: &str| {
            if single {
                what.to_string()
            } else {
                format!("{name}: {what}")
            }
        };
        force.series.push(Series::new(
            label("true force"),
            color,
            series_of(run, |r| r.force_n),
        ));
        if single {
            // Before arming the estimate reads the spindle's starting current, thousands of
            // newtons of nothing; the chart leaves it out (the CSV keeps it).
            force.series.push(Series::new(
                "estimated from current",
                PALETTE[1],
                series_of(run, |r| if r.armed { r.force_est_n } else { f64::NAN }),
            ));
            if run
                .trace
                .rows
                .iter()
                .any(|r| r.force_power_law_n.is_finite() && r.force_power_law_n > 0.0)
            {
                force.series.push(
                    Series::new(
                        "power law (sensorless)",
                        PALETTE[4],
                        series_of(run, |r| r.force_power_law_n),
                    )
                    .dashed(),
                );
            }
            current.series.push(Series::new(
                "spindle RMS",
                PALETTE[0],
                series_of(run, |r| r.spindle_current_rms_a),
            ));
            feed_current.series.push(Series::new(
                "feed RMS",
                PALETTE[2],
                series_of(run, |r| r.feed_current_rms_a),
            ));
            feed_current.series.push(Series::new(
                "feed i_u max (raw)",
                PALETTE[3],
                series_of(run, |r| r.feed_current_u_max_a),
            ));
            feed_current.series.push(Series::new(
                "feed i_u min (raw)",
                PALETTE[6],
                series_of(run, |r| r.feed_current_u_min_a),
            ));
            override_pct.series.push(
                Series::new(
                    "requested",
                    PALETTE[5],
                    series_of(run, |r| r.requested_override_pct),
                )
                .dashed(),
            );
            override_pct.series.push(Series::new(
                "commanded (after the envelope)",
                PALETTE[0],
                series_of(run, |r| r.override_pct),
            ));
            feed.series.push(
                Series::new(
                    "programmed",
                    PALETTE[7],
                    series_of(run, |r| r.programmed_feed_mm_min),
                )
                .dashed(),
            );
        } else {
            current.series.push(Series::new(
                label("spindle RMS"),
                color,
                series_of(run, |r| r.spindle_current_rms_a),
            ));
            override_pct.series.push(Series::new(
                label("override"),
                color,
                series_of(run, |r| r.override_pct),
            ));
        }
        feed.series.push(Series::new(
            label("actual"),
            color,
            series_of(run, |r| r.feed_mm_min),
        ));
        wall.series.push(Series::new(
            label("uncompensated"),
            color,
            series_of(run, |r| r.surface_error_um),
        ));
        if single {
            wall.series.push(Series::new(
                "compensated from the power law",
                PALETTE[4],
                series_of(run, |r| r.compensated_error_power_law_um),
            ));
            wall.series.push(
                Series::new(
                    "compensated from the current",
                    PALETTE[1],
                    series_of(run, |r| r.compensated_error_current_um),
                )
                .dashed(),
            );
        }
        if single || k == 0 {
            depth.series.push(Series::new(
                "axial depth",
                PALETTE[0],
                series_of(run, |r| r.depth_mm),
            ));
        }
    }
    let end = runs
        .iter()
        .map(|(_, r)| r.as_ref())
        .chain(before.filter(|_| single))
        .filter_map(|r| r.trace.rows.last().map(|row| row.time_s))
        .fold(0.0, f64::max);
    if let Some((_, first)) = runs.first() {
        // Black for the target, vermilion for the limit: told apart without reading the legend.
        let limits = [
            ("target", PALETTE[7], first.settings.target_force_n),
            ("limit", PALETTE[5], first.settings.force_limit_n),
        ];
        for (name, colour, value) in limits {
            force
                .series
                .push(Series::new(name, colour, vec![(0.0, value), (end, value)]).dashed());
        }
    }
    if let (true, Some(earlier)) = (single, before) {
        // One faint line per chart, after the current run's series, so a series hidden in a
        // legend (by index) stays the one hidden when the earlier run comes and goes.
        let faint = [
            (&mut force, "true force", series_of(earlier, |r| r.force_n)),
            (
                &mut current,
                "spindle RMS",
                series_of(earlier, |r| r.spindle_current_rms_a),
            ),
            (
                &mut override_pct,
                "commanded",
                series_of(earlier, |r| r.override_pct),
            ),
            (&mut feed, "actual", series_of(earlier, |r| r.feed_mm_min)),
            (
                &mut wall,
                "uncompensated",
                series_of(earlier, |r| r.surface_error_um),
            ),
        ];
        for (chart, what, points) in faint {
            chart
                .series
                .push(Series::new(what, PALETTE[0], points).before());
        }
    }
    let mut charts = [
        force,
        current,
        feed_current,
        override_pct,
        feed,
        depth,
        wall,
    ];
    for c in &mut charts {
        c.fit();
        // One time axis for every chart, whichever run lasted longest.
        if end > 0.0 {
            c.x.range = 0.0..end;
        }
    }
    charts
}

/// The linked charts of one or more runs; the wall's error only where the tool is known (a mill).
#[component]
pub fn RunCharts(
    /// The runs to draw.
    #[prop(into)]
    runs: Signal<Vec<NamedRun>>,
    /// An earlier run drawn faint behind a single run (Simulate's run before the last edit).
    #[prop(optional, into)]
    before: MaybeProp<Arc<RunResult>>,
) -> impl IntoView {
    let x_view = RwSignal::new(None::<Range<f64>>);
    let charts = Memo::new(move |_| {
        let earlier = before.get();
        runs.with(|r| run_charts(r, earlier.as_deref()))
    });
    let chart = move |i: usize| Signal::derive(move || charts.with(|c| c[i].clone()));
    let single = move || runs.with(|r| r.len() == 1);
    let wall_known = move || {
        runs.with(|r| {
            r.iter().any(|(_, run)| {
                run.trace
                    .rows
                    .iter()
                    .any(|row| row.surface_error_um.is_finite())
            })
        })
    };
    // The trace rows drawn (of the longest run), for a person's devtools and the browser tests:
    // a run streamed from a worker shows a growing count before it is done.
    let rows_drawn = move || {
        runs.with(|r| {
            r.iter()
                .map(|(_, run)| run.trace.rows.len())
                .max()
                .unwrap_or(0)
        })
        .to_string()
    };
    view! {
        <div class="charts" data-trace-rows=rows_drawn>
            <ChartCanvas label="Cutting force" chart=chart(0) height_px=240 x_view=x_view />
            <ChartCanvas label="Spindle current" chart=chart(1) height_px=170 x_view=x_view />
            <Show when=single>
                <ChartCanvas label="Feed-axis current" chart=chart(2) height_px=150 x_view=x_view />
            </Show>
            <ChartCanvas label="Feed override" chart=chart(3) height_px=170 x_view=x_view />
            <ChartCanvas label="Feed rate" chart=chart(4) height_px=170 x_view=x_view />
            <ChartCanvas label="Depth of cut" chart=chart(5) height_px=140 x_view=x_view />
            <Show when=wall_known>
                <ChartCanvas label="Wall error" chart=chart(6) height_px=170 x_view=x_view />
            </Show>
        </div>
    }
}

/// A cell's value, or a "—" that says why on hover and to a screen reader.
fn metric_cell(row: &MetricRow, run: &RunResult) -> impl IntoView {
    let shown = row.show((row.value)(run), format_metric);
    if shown == "—" {
        let why = row.why_missing(run);
        view! {
            <span class="missing" title=why>
                <span aria-hidden="true">"—"</span>
                <span class="visually-hidden">{format!("none: {why}")}</span>
            </span>
        }
        .into_any()
    } else {
        shown.into_any()
    }
}

/// The metrics of the runs as a table; with several runs the best value of each row is marked
/// (only beyond the row's tolerance, which its help states). With one run and `before`, the
/// earlier run's values stand in a "Before" column beside it.
#[component]
pub fn MetricsTable(
    /// The runs.
    #[prop(into)]
    runs: Signal<Vec<NamedRun>>,
    /// An earlier run shown beside a single run (Simulate's run before the last edit).
    #[prop(optional, into)]
    before: MaybeProp<Arc<RunResult>>,
) -> impl IntoView {
    // Which rows' explanations are open, kept while the table is drawn again (the savings
    // arrive after the run, a comparison's runs one by one).
    let help_open: Vec<RwSignal<bool>> = METRIC_ROWS.iter().map(|_| RwSignal::new(false)).collect();
    move || {
        let runs = runs.get();
        if runs.is_empty() {
            return None;
        }
        let several = runs.len() > 1;
        let earlier = before.get().filter(|_| !several);
        let named: Vec<(&str, &RunResult)> =
            runs.iter().map(|(n, r)| (n.as_str(), r.as_ref())).collect();
        Some(view! {
            <table class="metrics">
                <caption>
                    "Metrics of the run"
                    {several.then_some("s (★: best beyond the row's noise; see a row's ?)")}
                </caption>
                <thead>
                    <tr>
                        <th scope="col">"Metric"</th>
                        {runs.iter().map(|(n, _)| view! { <th scope="col">{n.clone()}</th> }).collect_view()}
                        {earlier.is_some().then(|| view! { <th scope="col" class="before">"Before"</th> })}
                    </tr>
                </thead>
                <tbody>
                    {METRIC_ROWS
                        .iter()
                        .zip(help_open.clone())
                        .map(|(row, open)| {
                            let results: Vec<&RunResult> = runs.iter().map(|(_, r)| r.as_ref()).collect();
                            let marks = best_marks(row, &results, format_metric);
                            view! {
                                <tr>
                                    <th scope="row">
                                        {row.heading()}
                                        <HelpToggle subject=row.label.to_string() help=row.help_with_rule() open=open />
                                    </th>
                                    {results
                                        .iter()
                                        .zip(marks)
                                        .map(|(run, is_best)| {
                                            view! {
                                                <td class:best=is_best>
                                                    {metric_cell(row, run)}
                                                    {is_best.then(|| view! { <span class="best-mark" aria-label="best">" ★"</span> })}
                                                </td>
                                            }
                                        })
                                        .collect_view()}
                                    {earlier.clone().map(|e| view! { <td class="before">{metric_cell(row, &e)}</td> })}
                                </tr>
                            }
                        })
                        .collect_view()}
                </tbody>
            </table>
            // Each "—" says why on hover; written out too, for a touch screen.
            {missing_notes(&named)
                .into_iter()
                .map(|note| view! { <p class="note missing-note">{format!("— {note}")}</p> })
                .collect_view()}
            {not_best_note(&named).map(|note| view! { <p class="note">{note}</p> })}
            {negative_saving_notes(&named)
                .into_iter()
                .map(|note| view! { <p class="note saving-note">{note}</p> })
                .collect_view()}
        })
    }
}

/// Marks results computed from settings that no longer validate: a banner says so (announced,
/// `aria-live`), and the page dims the results it wraps with the `stale` class.
#[component]
pub fn StaleNotice(
    /// Whether the results shown are from settings the form no longer holds.
    #[prop(into)]
    stale: Signal<bool>,
) -> impl IntoView {
    // The live region is always in the page, so the banner arriving in it is announced.
    view! {
        <div class="stale-status" role="status" aria-live="polite">
            {move || {
                stale
                    .get()
                    .then(|| {
                        view! {
                            <p class="stale-banner">
                                "These results are from the last valid settings: a field above no "
                                "longer validates. Fix it to run again."
                            </p>
                        }
                    })
            }}
        </div>
    }
}

/// The safety events of a run.
#[component]
pub fn EventLog(
    /// The run.
    #[prop(into)]
    run: Signal<Option<Arc<RunResult>>>,
) -> impl IntoView {
    move || {
        run.get().map(|r| {
            let events = r.trace.events.clone();
            view! {
                <section class="event-log" aria-labelledby="events-title">
                    <h2 id="events-title">"Event log"</h2>
                    {if events.is_empty() {
                        view! { <p class="hint">"No events."</p> }.into_any()
                    } else {
                        view! {
                            <ol>
                                {events
                                    .iter()
                                    .map(|e| view! { <li><span class="event-time">{format!("{:.2} s", e.time_s())}</span>" "{e.describe()}</li> })
                                    .collect_view()}
                            </ol>
                        }
                        .into_any()
                    }}
                </section>
            }
        })
    }
}

/// Metrics as JSON and the trace as CSV, for the export buttons.
pub fn metrics_json(metrics: &Metrics) -> String {
    serde_json::to_string_pretty(metrics).unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"))
}
