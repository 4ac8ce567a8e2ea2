//! Tune: teach-in (the chosen scenarios' simulated teach cuts, or a saved calibration file), a
//! grid sweep or a Nelder–Mead search over a controller's parameters across scenarios, sliced
//! between frames (`tuning::TuningWork`); the table, the heat map of a two-parameter sweep and
//! the chart of the Pareto front fill in when it is done.

use leptos::prelude::*;

use crate::charts::pareto::trade_off_chart;
use crate::charts::{Axis, HeatMap, Scale};
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::preset_controller;
use crate::closed_loop::definition::RunSpec;
use crate::control::registry::ControllerKind;
use crate::input::{parse_count, parse_number, readable};
use crate::plant::Preset;
use crate::tuning::nelder_mead::NelderMead;
use crate::tuning::teach_in::{teach_in_calibration, TargetBasis};
use crate::tuning::{
    Objective, ParamRange, TeachIn, TeachInWork, Tuned, TuningMode, TuningProblem, TuningWork,
};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::fields::{NumberField, SelectField};
use crate::web::components::heat_map::HeatMapCanvas;
use crate::web::components::page::PageShell;
use crate::web::components::runner::{RunProgress, Runner};
use crate::web::js::read_chosen_file;
use crate::web::route::Page;

/// The controllers worth tuning (a fixed feed has one value, found by the reference search).
const TUNABLE: [ControllerKind; 6] = [
    ControllerKind::Restriction,
    ControllerKind::Threshold,
    ControllerKind::FuzzyExperience,
    ControllerKind::FuzzyDynamics,
    ControllerKind::Pi,
    ControllerKind::Mrac,
];

/// One parameter row of the form: its key and bounds as typed.
#[derive(Clone, Copy)]
struct ParamRow {
    key: RwSignal<String>,
    lo: RwSignal<String>,
    hi: RwSignal<String>,
}

/// A sensible range around a parameter's default: a quarter to twice it, inside its limits.
fn default_range(kind: ControllerKind, key: &str) -> (f64, f64) {
    kind.params()
        .iter()
        .find(|p| p.key == key)
        .map_or((0.0, 1.0), |p| {
            let d = p.default;
            if d > 0.0 {
                ((0.25 * d).max(p.min), (2.0 * d).min(p.max))
            } else {
                (p.min, p.max.min(p.min + 1.0))
            }
        })
}

impl ParamRow {
    fn new(kind: ControllerKind, index: usize) -> Self {
        let key = kind
            .params()
            .get(index)
            .map_or(String::new(), |p| p.key.to_string());
        let (lo, hi) = default_range(kind, &key);
        Self {
            key: RwSignal::new(key),
            lo: RwSignal::new(readable(lo)),
            hi: RwSignal::new(readable(hi)),
        }
    }

    fn reset(&self, kind: ControllerKind, index: usize) {
        let fresh = Self::new(kind, index);
        self.key.set(fresh.key.get_untracked());
        self.lo.set(fresh.lo.get_untracked());
        self.hi.set(fresh.hi.get_untracked());
    }

    fn parse(&self) -> Result<ParamRange, String> {
        let key = self.key.get();
        let lo = parse_number(&self.lo.get()).map_err(|e| format!("{key} from: {e}"))?;
        let hi = parse_number(&self.hi.get()).map_err(|e| format!("{key} to: {e}"))?;
        if lo > hi {
            return Err(format!(
                "{key}: the lower bound {lo} is above the upper {hi}"
            ));
        }
        Ok(ParamRange { key, lo, hi })
    }
}

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

/// The Simulate link that runs `preset` with `kind` at `values`.
fn simulate_href(
    preset: Preset,
    kind: ControllerKind,
    params: &[ParamRange],
    values: &[f64],
) -> String {
    let mut href = format!(
        "{}?preset={}&controller={}",
        Page::Simulate.href(),
        preset.name(),
        kind.name()
    );
    for (p, v) in params.iter().zip(values) {
        href.push_str(&format!("&{}={}", p.key, readable(*v)));
    }
    href
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

/// The Tune page.
#[component]
pub fn TunePage() -> impl IntoView {
    let kind_text = RwSignal::new(ControllerKind::Pi.name().to_string());
    let kind = Memo::new(move |_| {
        kind_text
            .get()
            .parse::<ControllerKind>()
            .unwrap_or(ControllerKind::Pi)
    });
    let chosen: Vec<(Preset, RwSignal<bool>)> = Preset::ALL
        .iter()
        .map(|&p| (p, RwSignal::new(p == Preset::ManeeratDoc1)))
        .collect();
    let chosen = StoredValue::new(chosen);
    let rows = [
        ParamRow::new(ControllerKind::Pi, 0),
        ParamRow::new(ControllerKind::Pi, 1),
    ];
    let second_on = RwSignal::new(true);
    Effect::new(move |previous: Option<ControllerKind>| {
        let k = kind.get();
        if previous.is_some_and(|p| p != k) {
            for (i, row) in rows.iter().enumerate() {
                row.reset(k, i);
            }
        }
        k
    });
    let mode = RwSignal::new("search".to_string());
    let steps = RwSignal::new("5".to_string());
    let max_evals = RwSignal::new("30".to_string());
    let defaults = Objective::default();
    let weights = [
        ("Weight of the cycle time", defaults.cycle_time),
        ("Weight of the force error", defaults.force_error),
        (
            "Weight of the time above the limit",
            defaults.time_above_limit,
        ),
        (
            "Weight of the override activity",
            defaults.override_activity,
        ),
    ]
    .map(|(label, w)| (label, RwSignal::new(readable(w))));

    let runner = Runner::<Tuned>::new();
    let teach_runner = Runner::<Vec<TeachIn>>::new();
    let (form_error, set_form_error) = signal(None::<String>);
    // What the last finished tuning was asked, for the heat map and the links.
    let asked = RwSignal::new(None::<(Vec<ParamRange>, usize, Preset, ControllerKind)>);

    let scenarios = move || -> Vec<Preset> {
        chosen.with_value(|c| {
            c.iter()
                .filter(|(_, on)| on.get())
                .map(|(p, _)| *p)
                .collect()
        })
    };
    let runner_for_start = runner.clone();
    let start = move |_| {
        let presets = scenarios();
        let Some(&first) = presets.first() else {
            set_form_error.set(Some("Choose at least one scenario.".into()));
            return;
        };
        let k = kind.get_untracked();
        let count = if second_on.get_untracked() { 2 } else { 1 };
        let params: Result<Vec<ParamRange>, String> =
            rows[..count].iter().map(ParamRow::parse).collect();
        let params = match params {
            Ok(p) => p,
            Err(e) => {
                set_form_error.set(Some(e));
                return;
            }
        };
        let number = |label: &str, s: RwSignal<String>| {
            parse_number(&s.get_untracked()).map_err(|e| format!("{label}: {e}"))
        };
        let objective = (|| -> Result<Objective, String> {
            let w: Vec<f64> = weights
                .iter()
                .map(|(label, s)| {
                    number(label, *s).and_then(|v| {
                        if v >= 0.0 {
                            Ok(v)
                        } else {
                            Err(format!("{label}: a weight cannot be negative"))
                        }
                    })
                })
                .collect::<Result<_, _>>()?;
            Ok(Objective {
                cycle_time: w[0],
                force_error: w[1],
                time_above_limit: w[2],
                override_activity: w[3],
            })
        })();
        let objective = match objective {
            Ok(o) => o,
            Err(e) => {
                set_form_error.set(Some(e));
                return;
            }
        };
        let tuning_mode = if mode.get_untracked() == "sweep" {
            match parse_count(&steps.get_untracked()) {
                Ok(n) if n >= 1 => TuningMode::Sweep(n),
                _ => {
                    set_form_error.set(Some("Values per parameter: a whole number ≥ 1.".into()));
                    return;
                }
            }
        } else {
            match parse_count(&max_evals.get_untracked()) {
                Ok(n) if n >= 1 => TuningMode::Search(NelderMead {
                    max_evaluations: n,
                    ..NelderMead::default()
                }),
                _ => {
                    set_form_error.set(Some("Evaluations: a whole number ≥ 1.".into()));
                    return;
                }
            }
        };
        let problem = TuningProblem {
            controller: preset_controller(first, k),
            params: params.clone(),
            scenarios: presets.iter().map(|&p| RunSpec::new(p, k)).collect(),
            objective,
        };
        match TuningWork::new(problem, tuning_mode) {
            Ok(work) => {
                set_form_error.set(None);
                let steps = match tuning_mode {
                    TuningMode::Sweep(n) => n,
                    TuningMode::Search(_) => 0,
                };
                asked.set(Some((params, steps, first, k)));
                runner_for_start.start(work);
            }
            Err(e) => set_form_error.set(Some(e.to_string())),
        }
    };
    let teach_for_start = teach_runner.clone();
    let teach_in = move |_| {
        let presets = scenarios();
        if presets.is_empty() {
            set_form_error.set(Some("Choose at least one scenario.".into()));
            return;
        }
        set_form_error.set(None);
        teach_for_start.start(TeachInWork::new(
            presets
                .iter()
                .map(|&p| RunSpec::new(p, ControllerKind::Threshold))
                .collect(),
        ));
    };

    // A teach-in from a saved calibration (what `cutlab host --save-calibration` writes after a
    // teach cut on the machine): the first chosen scenario is the program it was taught on.
    let from_file = RwSignal::new(None::<TeachIn>);
    let (file_error, set_file_error) = signal(None::<String>);
    let on_calibration_file = move |ev: leptos::ev::Event| {
        let program = scenarios()
            .first()
            .map(|&p| RunSpec::new(p, ControllerKind::Threshold));
        read_chosen_file(&ev, move |name, text| {
            let taught = text.and_then(|text| {
                CalibrationFile::from_json(&text)
                    .map_err(|e| format!("{name}: {e}"))
                    .and_then(|file| {
                        teach_in_calibration(&file, &name, program.as_ref())
                            .map_err(|e| e.to_string())
                    })
            });
            match taught {
                Ok(t) => {
                    set_file_error.set(None);
                    from_file.set(Some(t));
                }
                Err(e) => {
                    from_file.set(None);
                    set_file_error.set(Some(e));
                }
            }
        });
    };

    let tuned = runner.finished();
    let taught = teach_runner.finished();
    let param_options = Memo::new(move |_| {
        kind.get()
            .params()
            .iter()
            .map(|p| (p.key, p.label))
            .collect::<Vec<_>>()
    });

    view! {
        <PageShell id="tune" title="Tune a controller">
            <p class="lede">
                "Find settings instead of trying them: a teach-in proposes a target and a threshold "
                "gap from one teach cut; a sweep runs a grid of one or two parameters; a search "
                "(Nelder–Mead) minimises the weighted objective across the scenarios. Every "
                "evaluation runs the same closed loop as Simulate."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Tuning settings" on:submit=|ev| ev.prevent_default()>
                    <fieldset>
                        <legend>"Scenarios"</legend>
                        {chosen
                            .get_value()
                            .into_iter()
                            .map(|(p, on)| {
                                let id = format!("tune-scenario-{}", p.name());
                                view! {
                                    <div class="check">
                                        <input
                                            type="checkbox"
                                            id=id.clone()
                                            prop:checked=move || on.get()
                                            on:change=move |ev| on.set(event_target_checked(&ev))
                                        />
                                        <label for=id>{p.name()}</label>
                                    </div>
                                }
                            })
                            .collect_view()}
                    </fieldset>
                    <fieldset>
                        <legend>"Teach-in"</legend>
                        <p class="hint">
                            "A teach cut on each chosen scenario, or a calibration saved after a "
                            "teach cut on the machine (the first chosen scenario is its program)."
                        </p>
                        <button type="button" on:click=teach_in>"Teach-in"</button>
                        <div class="field">
                            <label for="tune-calibration-file">"Calibration file to teach in from"</label>
                            <input
                                id="tune-calibration-file"
                                type="file"
                                accept=".json,application/json"
                                on:change=on_calibration_file
                            />
                            {move || file_error.get().map(|e| view! { <p class="field-error" role="alert">{e}</p> })}
                        </div>
                    </fieldset>
                    <fieldset>
                        <legend>"Controller and parameters"</legend>
                        <SelectField
                            id="tune-controller"
                            label="Controller"
                            options=TUNABLE.iter().map(|k| (k.name(), k.label())).collect()
                            value=kind_text
                        />
                        {rows
                            .iter()
                            .enumerate()
                            .map(|(i, row)| {
                                let row = *row;
                                let n = i + 1;
                                let hidden = Signal::derive(move || i == 1 && !second_on.get());
                                view! {
                                    <div class="field" hidden=move || hidden.get()>
                                        <label for=format!("tune-param-{n}")>{format!("Parameter {n}")}</label>
                                        <select
                                            id=format!("tune-param-{n}")
                                            on:change=move |ev| {
                                                let key = event_target_value(&ev);
                                                let (lo, hi) = default_range(kind.get_untracked(), &key);
                                                row.key.set(key);
                                                row.lo.set(readable(lo));
                                                row.hi.set(readable(hi));
                                            }
                                            prop:value=move || row.key.get()
                                        >
                                            {move || {
                                                param_options
                                                    .get()
                                                    .into_iter()
                                                    .map(|(key, label)| view! { <option value=key>{format!("{label} ({key})")}</option> })
                                                    .collect_view()
                                            }}
                                        </select>
                                    </div>
                                    <NumberField id=format!("tune-lo-{n}") label=format!("Parameter {n} from") value=row.lo error=no_error() hidden=hidden />
                                    <NumberField id=format!("tune-hi-{n}") label=format!("Parameter {n} to") value=row.hi error=no_error() hidden=hidden />
                                }
                            })
                            .collect_view()}
                        <div class="check">
                            <input
                                type="checkbox"
                                id="tune-second"
                                prop:checked=move || second_on.get()
                                on:change=move |ev| second_on.set(event_target_checked(&ev))
                            />
                            <label for="tune-second">"Tune a second parameter"</label>
                        </div>
                    </fieldset>
                    <fieldset>
                        <legend>"Method"</legend>
                        <SelectField
                            id="tune-mode"
                            label="Method"
                            options=vec![("search", "Search (Nelder–Mead)"), ("sweep", "Sweep a grid")]
                            value=mode
                        />
                        <NumberField id="tune-evals" label="Evaluations at most" value=max_evals error=no_error() hidden=Signal::derive(move || mode.get() == "sweep") />
                        <NumberField id="tune-steps" label="Values per parameter" value=steps error=no_error() hidden=Signal::derive(move || mode.get() != "sweep") />
                    </fieldset>
                    <fieldset>
                        <legend>"Objective"</legend>
                        {weights
                            .iter()
                            .enumerate()
                            .map(|(i, (label, value))| view! {
                                <NumberField id=format!("tune-weight-{i}") label=label.to_string() value=*value error=no_error() />
                            })
                            .collect_view()}
                    </fieldset>
                    <div class="button-row">
                        <button type="button" on:click=start>"Run"</button>
                    </div>
                    {move || form_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                </form>
                <div class="results">
                    <RunProgress runner=teach_runner.clone() id="teach-progress" failure="The teach-in could not be made" />
                    {move || {
                        let list: Vec<TeachIn> = taught
                            .get()
                            .unwrap_or_default()
                            .into_iter()
                            .chain(from_file.get())
                            .collect();
                        (!list.is_empty()).then(|| view! {
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
                                            <th scope="row">{t.source.clone()}</th>
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
                        })
                    }}
                    <RunProgress runner=runner.clone() id="tune-progress" failure="The tuning could not be made" />
                    {move || {
                        let (tuned, (params, steps, preset, k)) = (tuned.get()?, asked.get()?);
                        let best = tuned.best.clone();
                        let map = sweep_map(&tuned, steps, &params);
                        let best_href = simulate_href(preset, k, &params, &best.values);
                        let rows: Vec<_> = tuned.evaluations.iter().enumerate().map(|(i, e)| (i, e.clone(), tuned.pareto.contains(&i))).collect();
                        let headers = params.iter().map(|p| view! { <th scope="col">{p.key.clone()}</th> }).collect_view();
                        Some(view! {
                            <p role="status">
                                {format!(
                                    "Best of {} evaluations{}: {}; objective {:.3}, cycle {:.1} s, force error {:.1} %. ",
                                    tuned.evaluations.len(),
                                    if tuned.converged { " (converged)" } else { "" },
                                    params
                                        .iter()
                                        .zip(&best.values)
                                        .map(|(p, v)| format!("{} = {}", p.key, readable(*v)))
                                        .collect::<Vec<_>>()
                                        .join(", "),
                                    best.cost, best.cycle_time_s, best.force_error_pct
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
                                let pick = Callback::new(move |(x, y): (f64, f64)| {
                                    let distance = |v: &Vec<f64>| ((v[0] - x) / spans[0]).powi(2) + ((v[1] - y) / spans[1]).powi(2);
                                    if let Some(v) = points.iter().min_by(|a, b| distance(a).total_cmp(&distance(b))) {
                                        let _ = window().location().set_href(&simulate_href(preset, k, &params, v));
                                    }
                                });
                                view! {
                                    <p class="hint">"Pick a cell (click, or Enter on the focused map) to open that point in Simulate."</p>
                                    <HeatMapCanvas label="Objective over the two parameters" map=Signal::derive(move || m.clone()) on_pick=pick />
                                }
                            })}
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
                                            {e.values.iter().map(|v| view! { <td>{readable(*v)}</td> }).collect_view()}
                                            <td>{format!("{:.3}", e.cost)}</td>
                                            <td>{format!("{:.1}", e.cycle_time_s)}</td>
                                            <td>{format!("{:.1}", e.force_error_pct)}</td>
                                            <td>{format!("{:.2}", e.time_above_limit_s)}</td>
                                            <td>{format!("{:.0}", e.override_activity_pct)}</td>
                                            <td>{if front { "yes" } else { "" }}</td>
                                            <td><a href=simulate_href(preset, k, &params, &e.values)>{format!("Open {} in Simulate", i + 1)}</a></td>
                                        </tr>
                                    }).collect_view()}
                                </tbody>
                            </table>
                        })
                    }}
                </div>
            </div>
        </PageShell>
    }
}

/// A field whose text is checked only when Run is pressed (the message appears below the form).
fn no_error() -> Signal<Option<String>> {
    Signal::derive(|| None)
}
