//! The chain's statistics per label, notes and peaks; each replay's numbers and the envelope's
//! events.

use std::sync::Arc;

use leptos::prelude::*;

use crate::input::three_significant;
use crate::log::analysis::ChainOutput;
use crate::log::replay::{events, ReplayResult};
use crate::web::components::page::TableScroll;

/// Statistics per label and the chain's notes and peaks.
#[component]
pub fn ChainReport(out: Arc<ChainOutput>, column: String) -> impl IntoView {
    let a = &out.analysis;
    let number = |v: Option<f64>| v.map_or("—".to_string(), three_significant);
    let mut rows = vec![("All rows".to_string(), a.whole)];
    rows.extend(a.by_label.iter().map(|l| (l.label.clone(), l.stats)));
    view! {
        <section aria-labelledby="chain-report-title">
            <h2 id="chain-report-title">{format!("Statistics of {column}")}</h2>
            <ul class="hint">{a.notes.iter().map(|n| view! { <li>{n.clone()}</li> }).collect_view()}</ul>
            <TableScroll label=format!("Statistics of {column} per label segment")>
            <table class="metrics">
                <caption>"Per label segment (after the low-pass, if any)"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Segment"</th>
                        <th scope="col">"Rows"</th>
                        <th scope="col">"Duration (s)"</th>
                        <th scope="col">"Mean"</th>
                        <th scope="col">"RMS"</th>
                        <th scope="col">"Min"</th>
                        <th scope="col">"Max"</th>
                    </tr>
                </thead>
                <tbody>
                    {rows
                        .into_iter()
                        .map(|(label, s)| view! {
                            <tr>
                                <th scope="row">{label}</th>
                                <td>{s.count}</td>
                                <td>{number(s.duration_s)}</td>
                                <td>{number(s.mean)}</td>
                                <td>{number(s.rms)}</td>
                                <td>{number(s.min)}</td>
                                <td>{number(s.max)}</td>
                            </tr>
                        })
                        .collect_view()}
                </tbody>
            </table>
            </TableScroll>
            <p class="hint" role="status">
                {if a.peaks.is_empty() {
                    "No spectral peaks.".to_string()
                } else {
                    format!(
                        "Spectral peaks: {}.",
                        a.peaks.iter().map(|p| format!("{} Hz", three_significant(p.freq_hz))).collect::<Vec<_>>().join(", ")
                    )
                }}
            </p>
        </section>
    }
}

/// Each replay's numbers and events.
#[component]
pub fn ReplayReport(results: Vec<Arc<ReplayResult>>) -> impl IntoView {
    let number = |v: Option<f64>| v.map_or("—".to_string(), three_significant);
    let metric_rows: Vec<(&'static str, Vec<String>)> = vec![
        (
            "Armed at (s)",
            results
                .iter()
                .map(|r| number(r.summary.armed_at_s))
                .collect(),
        ),
        (
            "Override min (%)",
            results
                .iter()
                .map(|r| number(r.summary.override_min_pct))
                .collect(),
        ),
        (
            "Override mean (%)",
            results
                .iter()
                .map(|r| number(r.summary.override_mean_pct))
                .collect(),
        ),
        (
            "Override max (%)",
            results
                .iter()
                .map(|r| number(r.summary.override_max_pct))
                .collect(),
        ),
        (
            "Logged override mean (%)",
            results
                .iter()
                .map(|r| number(r.summary.logged_override_mean_pct))
                .collect(),
        ),
        (
            "Periods limited by the envelope",
            results
                .iter()
                .map(|r| r.summary.periods_limited.to_string())
                .collect(),
        ),
        (
            "Sensor faults",
            results
                .iter()
                .map(|r| r.summary.sensor_faults.to_string())
                .collect(),
        ),
        (
            "Overload (feed hold) at (s)",
            results
                .iter()
                .map(|r| number(r.summary.overload_at_s))
                .collect(),
        ),
        (
            "Force estimate mean (N)",
            results
                .iter()
                .map(|r| number(r.summary.force_est_mean_n))
                .collect(),
        ),
    ];
    let notes = results.first().map(|r| r.notes.clone()).unwrap_or_default();
    let event_logs = results.clone();
    view! {
        <section aria-labelledby="replay-report-title">
            <h2 id="replay-report-title">"Replayed controllers"</h2>
            <ul class="hint">{notes.into_iter().map(|n| view! { <li>{n}</li> }).collect_view()}</ul>
            <TableScroll label="Replayed controllers".to_string()>
            <table class="metrics">
                <caption>"What each controller would have done on this log"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Measure"</th>
                        {results.iter().map(|r| view! { <th scope="col">{r.controller.kind().label()}</th> }).collect_view()}
                    </tr>
                </thead>
                <tbody>
                    {metric_rows
                        .into_iter()
                        .map(|(name, values)| view! {
                            <tr>
                                <th scope="row">{name}</th>
                                {values.into_iter().map(|v| view! { <td>{v}</td> }).collect_view()}
                            </tr>
                        })
                        .collect_view()}
                </tbody>
            </table>
            </TableScroll>
            {event_logs
                .iter()
                .map(|r| {
                    let list = events(&r.trace);
                    view! {
                        <section class="event-log" aria-label=format!("Envelope events of {}", r.controller.kind().label())>
                            <h3>{format!("Envelope events: {}", r.controller.kind().label())}</h3>
                            {if list.is_empty() {
                                view! { <p class="hint">"No events."</p> }.into_any()
                            } else {
                                view! {
                                    <ol>
                                        {list.into_iter().take(50).map(|e| view! {
                                            <li><span class="event-time">{format!("{:.2} s", e.time_s)}</span>" "{e.message}</li>
                                        }).collect_view()}
                                    </ol>
                                }.into_any()
                            }}
                        </section>
                    }
                })
                .collect_view()}
        </section>
    }
}
