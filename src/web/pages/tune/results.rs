//! What a tuning and a teach-in found: the proposals' table; the best evaluation, the chart of
//! cycle time against force error with its Pareto front, a two-parameter sweep's heat map and
//! every evaluation, each one click from Simulate.

use leptos::prelude::*;

use super::Asked;
use crate::charts::pareto::trade_off_chart;
use crate::charts::{Axis, HeatMap, Scale};
use crate::control::fuzzy::fll;
use crate::control::registry::ControllerConfig;
use crate::input::{readable, three_significant};
use crate::plant::Preset;
use crate::tuning::teach_in::TargetBasis;
use crate::tuning::{ParamRange, TeachIn, Tuned};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::heat_map::HeatMapCanvas;
use crate::web::components::page::TableScroll;
use crate::web::route::{hash_with_query, Page};

/// The heat map of a two-parameter sweep's objective (`None` for anything else).
fn sweep_map(tuned: &Tuned, steps: usize, params: &[ParamRange]) -> Option<HeatMap> {
    let [x, y] = params else { return None };
    if tuned.evaluations.len() != steps * steps || steps < 2 {
        return None;
    }
    let half = |r: &ParamRange| 0.5 * (r.hi - r.lo) / (steps - 1) as f64;
    let axis = |r: &ParamRange| Axis {
        label: r.key.clone(),
        range: (r.lo - half(r))..(r.hi + half(r)),
        scale: Scale::Linear,
    };
    // The sweep varies the first parameter slowest: evaluation i·steps + j is (x_i, y_j).
    let mut values = vec![f64::NAN; steps * steps];
    for (index, e) in tuned.evaluations.iter().enumerate() {
        let (i, j) = (index / steps, index % steps);
        values[j * steps + i] = e.cost;
    }
    let finite = values.iter().copied().filter(|v| v.is_finite());
    let lo = finite.clone().fold(f64::INFINITY, f64::min);
    let hi = finite.fold(f64::NEG_INFINITY, f64::max);
    Some(HeatMap {
        x: axis(x),
        y: axis(y),
        nx: steps,
        ny: steps,
        values,
        value_range: if lo < hi { lo..hi } else { lo..lo + 1.0 },
    })
}

/// The Simulate link that runs `preset` with `controller` (its kind, and its engine if it runs
/// one) at `values`.
fn simulate_href(
    preset: Preset,
    controller: &ControllerConfig,
    params: &[ParamRange],
    values: &[f64],
) -> String {
    let mut query = vec![
        ("preset".to_string(), preset.name().to_string()),
        (
            "controller".to_string(),
            controller.kind().name().to_string(),
        ),
    ];
    for (p, v) in params.iter().zip(values) {
        query.push((p.key.clone(), readable(*v)));
    }
    if let Some(engine) = controller.engine_fll() {
        query.push(("engine".to_string(), fll::to_url_text(engine)));
    }
    hash_with_query(Page::Simulate, &query)
}

/// The chart of every evaluation's mean cycle time against its mean force error, the Pareto
/// front joined and the best objective marked.
fn pareto_chart(tuned: &Tuned) -> crate::charts::LineChart {
    let points: Vec<(f64, f64)> = tuned
        .evaluations
        .iter()
        .map(|e| (e.cycle_time_s, e.force_error_pct))
        .collect();
    let best = tuned
        .evaluations
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.cost.total_cmp(&b.1.cost))
        .map(|(i, _)| i);
    trade_off_chart(
        Axis::linear("mean cycle time (s)"),
        Axis::linear("mean force error (%)"),
        &points,
        &tuned.pareto,
        best,
    )
}

/// A short reason for a proposed target, for the teach-in table.
fn basis_text(basis: TargetBasis) -> &'static str {
    match basis {
        TargetBasis::Fraction => "80 % of the force at 100 %",
        TargetBasis::RaisedToCalibratedRange => "raised to the calibrated range",
        TargetBasis::LoweredToCalibratedRange => "lowered to the calibrated range",
    }
}

/// A current for the table: three decimals, or a dash where a dynamometer reads the force.
fn current_text(current_a: f64) -> String {
    if current_a.is_finite() {
        format!("{current_a:.3}")
    } else {
        "— (dynamometer)".to_string()
    }
}

/// The teach-in's proposals, from the scenarios' teach cuts and from a saved calibration.
#[component]
pub fn TeachInTable(
    #[prop(into)] taught: Signal<Option<Vec<TeachIn>>>,
    #[prop(into)] from_file: Signal<Option<TeachIn>>,
) -> impl IntoView {
    view! {
        {move || {
            let list: Vec<TeachIn> = taught
                .get()
                .unwrap_or_default()
                .into_iter()
                .chain(from_file.get())
                .collect();
            // What each calibration rests on, in the fit's words, under the table.
            let warnings: Vec<String> = list
                .iter()
                .flat_map(|t| t.warnings.iter().map(move |w| format!("Warning: {}: {w}", t.source)))
                .collect();
            (!list.is_empty()).then(|| view! {
            <TableScroll label="Teach-in".to_string()>
            <table aria-label="Teach-in">
                <caption>
                    "Proposed from what each teach cut measured; the paper's own target "
                    "beside it for comparison."
                </caption>
                <thead><tr>
                    <th scope="col">"Teach cut"</th>
                    <th scope="col">"Force at 100 % (N)"</th>
                    <th scope="col">"Proposed target (N)"</th>
                    <th scope="col">"Target from"</th>
                    <th scope="col">"Reference current (A)"</th>
                    <th scope="col">"Estimate noise, 1 σ (N)"</th>
                    <th scope="col">"Threshold gap (%)"</th>
                    <th scope="col">"Paper's target"</th>
                </tr></thead>
                <tbody>
                    {list.into_iter().map(|t| {
                        let p = t.proposal;
                        let paper = t.paper.as_ref().map_or("—".to_string(), |paper| {
                            let current = if paper.reference_current_a.is_finite() {
                                format!(" ({:.3} A)", paper.reference_current_a)
                            } else {
                                String::new()
                            };
                            format!("{:.0} N{current}", paper.target_n)
                        });
                        view! {
                            <tr>
                                <th scope="row">{scenario_title(&t)}</th>
                                <td>{format!("{:.0}", t.learned.force_at_full_override_n)}</td>
                                <td>{format!("{:.0}", p.target_n)}</td>
                                <td>{basis_text(p.basis)}</td>
                                <td>{current_text(p.reference_current_a)}</td>
                                <td>{format!("{:.1}", p.estimate_noise_n)}</td>
                                <td>{format!("{:.1}", p.gap_pct)}</td>
                                <td>{paper}</td>
                            </tr>
                        }
                    }).collect_view()}
                </tbody>
            </table>
            </TableScroll>
            <ul class="hint" aria-label="Teach-in warnings">
                {warnings.into_iter().map(|w| view! { <li>{w}</li> }).collect_view()}
            </ul>
            })
        }}
    }
}

/// Where a teach-in came from (a scenario's id, a calibration file), with the scenario's title.
fn scenario_title(t: &TeachIn) -> String {
    match t.preset.and_then(Preset::from_name) {
        Some(p) => format!("{} ({})", t.source, p.label()),
        None => t.source.clone(),
    }
}

/// A tuned parameter as a person reads it: "K_p = 0.439 % per %" (its label, three significant
/// digits, its unit); the key where the controller has no such parameter.
fn param_text(controller: &ControllerConfig, key: &str, value: f64) -> String {
    let spec = controller.kind().params().iter().find(|p| p.key == key);
    let (label, unit) = spec.map_or((key, ""), |p| (p.label, p.unit));
    let value = three_significant(value);
    if unit.is_empty() {
        format!("{label} = {value}")
    } else {
        format!("{label} = {value} {unit}")
    }
}

/// A tuned parameter's column heading: "K_p (% per %)".
fn param_heading(controller: &ControllerConfig, key: &str) -> String {
    match controller.kind().params().iter().find(|p| p.key == key) {
        Some(p) if !p.unit.is_empty() => format!("{} ({})", p.label, p.unit),
        Some(p) => p.label.to_string(),
        None => key.to_string(),
    }
}

/// The tuning's result: the best, the trade-off chart, the heat map, the evaluations.
#[component]
pub fn TuningResults(
    #[prop(into)] tuned: Signal<Option<Tuned>>,
    #[prop(into)] asked: Signal<Option<Asked>>,
) -> impl IntoView {
    view! {
        {move || {
            let (tuned, (params, steps, preset, k)) = (tuned.get()?, asked.get()?);
            let best = tuned.best.clone();
            let map = sweep_map(&tuned, steps, &params);
            let best_href = simulate_href(preset, &k, &params, &best.values);
            let rows: Vec<_> = tuned.evaluations.iter().enumerate().map(|(i, e)| (i, e.clone(), tuned.pareto.contains(&i))).collect();
            let headers = params.iter().map(|p| view! { <th scope="col">{param_heading(&k, &p.key)}</th> }).collect_view();
            Some(view! {
                <p role="status">
                    {format!(
                        "Best of {} evaluations{}: {}; objective {}, cycle {} s, force error {} %. ",
                        tuned.evaluations.len(),
                        if tuned.converged { " (converged)" } else { "" },
                        params
                            .iter()
                            .zip(&best.values)
                            .map(|(p, v)| param_text(&k, &p.key, *v))
                            .collect::<Vec<_>>()
                            .join(", "),
                        three_significant(best.cost),
                        three_significant(best.cycle_time_s),
                        three_significant(best.force_error_pct)
                    )}
                    <a href=best_href>"Open the best in Simulate"</a>
                </p>
                <ChartCanvas
                    label="Cycle time against force error"
                    chart=Signal::derive({
                        let chart = pareto_chart(&tuned);
                        move || chart.clone()
                    })
                />
                {map.map(|m| {
                    // Picking a cell opens the evaluation nearest to it in Simulate.
                    let points: Vec<Vec<f64>> = tuned.evaluations.iter().map(|e| e.values.clone()).collect();
                    let (params, spans) = (params.clone(), params.iter().map(|p| (p.hi - p.lo).max(f64::MIN_POSITIVE)).collect::<Vec<_>>());
                    let k = k.clone();
                    let pick = Callback::new(move |(x, y): (f64, f64)| {
                        let distance = |v: &Vec<f64>| ((v[0] - x) / spans[0]).powi(2) + ((v[1] - y) / spans[1]).powi(2);
                        if let Some(v) = points.iter().min_by(|a, b| distance(a).total_cmp(&distance(b))) {
                            let _ = window().location().set_href(&simulate_href(preset, &k, &params, v));
                        }
                    });
                    view! {
                        <p class="hint">"Pick a cell (click, or Enter on the focused map) to open that point in Simulate."</p>
                        <HeatMapCanvas label="Objective over the two parameters" map=Signal::derive(move || m.clone()) on_pick=pick />
                    }
                })}
                <TableScroll label="Evaluations".to_string()>
                <table aria-label="Evaluations">
                    <caption>"Means over the chosen scenarios."</caption>
                    <thead><tr>
                        {headers}
                        <th scope="col">"Objective"</th>
                        <th scope="col">"Cycle (s)"</th>
                        <th scope="col">"Force error (%)"</th>
                        <th scope="col">"Above limit (s)"</th>
                        <th scope="col">"Override activity (%)"</th>
                        <th scope="col">"Pareto front"</th>
                        <th scope="col">"Simulate"</th>
                    </tr></thead>
                    <tbody>
                        {rows.into_iter().map(|(i, e, front)| view! {
                            <tr>
                                {e.values.iter().map(|v| view! { <td>{three_significant(*v)}</td> }).collect_view()}
                                <td>{three_significant(e.cost)}</td>
                                <td>{three_significant(e.cycle_time_s)}</td>
                                <td>{three_significant(e.force_error_pct)}</td>
                                <td>{three_significant(e.time_above_limit_s)}</td>
                                <td>{three_significant(e.override_activity_pct)}</td>
                                <td>{if front { "yes" } else { "" }}</td>
                                <td><a href=simulate_href(preset, &k, &params, &e.values)>{format!("Open {} in Simulate", i + 1)}</a></td>
                            </tr>
                        }).collect_view()}
                    </tbody>
                </table>
                </TableScroll>
            })
        }}
    }
}
