//! Fuzzy rules: paper 002's membership functions, the 7×7 rule table (editable), the control
//! surface U(E, EC), a rule viewer for a chosen (E, EC) or a moment of a simulated run, and FLL
//! import and export.

use std::sync::Arc;

use leptos::prelude::*;

use crate::charts::{Axis, HeatMap, LineChart, Series, PALETTE};
use crate::closed_loop::definition::preset_controller;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::LabRuns;
use crate::closed_loop::lab::RunResult;
use crate::control::fuzzy::engine::{Defuzzifier, Engine};
use crate::control::fuzzy::fll;
use crate::control::fuzzy::rules::{paper_002_engine, paper_002_table, RuleBase, LEVEL_NAMES};
use crate::control::registry::ControllerKind;
use crate::plant::Preset;
use crate::web::components::chart::ChartCanvas;
use crate::web::components::download::download_text;
use crate::web::components::fields::{parse_number, NumberField, SelectField};
use crate::web::components::heat_map::HeatMapCanvas;
use crate::web::components::later::{from_next_task, Later};
use crate::web::components::run_form::{decode_rule_table, encode_rule_table};
use crate::web::components::runner::{RunProgress, Runner};
use crate::web::js::read_chosen_file;
use crate::web::route::{query_params, replace_query, Page};

/// Grid points per axis of the control surface.
const SURFACE_POINTS: usize = 61;

/// The engine being studied: paper 002's with an editable table, or one imported from FLL with
/// the reason it is not such a table.
#[derive(Clone)]
enum Source {
    Table,
    Imported(Arc<Engine>, String),
}

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

/// The Fuzzy rules page.
#[component]
pub fn FuzzyPage() -> impl IntoView {
    let query = query_params(&window().location().hash().unwrap_or_default());
    let initial = query
        .iter()
        .find(|(k, _)| k == "rules")
        .and_then(|(_, v)| decode_rule_table(v))
        .unwrap_or_else(|| RuleBase::Dynamics.table());
    let table = RwSignal::new(initial);
    let defuzzifier = RwSignal::new(Defuzzifier::WeightedAverage.name().to_string());
    let source = RwSignal::new(Source::Table);
    let e_text = RwSignal::new("2".to_string());
    let ec_text = RwSignal::new("-1".to_string());
    let (fll_error, set_fll_error) = signal(None::<String>);
    let fll_text = RwSignal::new(String::new());

    // The URL is the page's own work, not its mount's: written from the task after the page's.
    let mounted = from_next_task();
    Effect::new(move |_| {
        if !mounted.get() {
            return;
        }
        replace_query(
            Page::Fuzzy,
            &[("rules".to_string(), encode_rule_table(&table.get()))],
        );
    });

    let engine = Memo::new(move |_| -> Result<Arc<Engine>, String> {
        let d = Defuzzifier::from_name(&defuzzifier.get()).unwrap_or(Defuzzifier::Centroid);
        match source.get() {
            Source::Table => paper_002_engine(&table.get(), d)
                .map(Arc::new)
                .map_err(|e| e.to_string()),
            Source::Imported(engine, _) => {
                let mut e = (*engine).clone();
                e.set_defuzzifier(d);
                Ok(Arc::new(e))
            }
        }
        .and_then(|e| {
            if e.inputs().len() == 2 && !e.outputs().is_empty() {
                Ok(e)
            } else {
                Err("the rule viewer and surface need an engine with two inputs".to_string())
            }
        })
    });
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

    // The rule viewer at the chosen (E, EC).
    let point =
        Signal::derive(
            move || match (parse_number(&e_text.get()), parse_number(&ec_text.get())) {
                (Ok(e), Ok(ec)) => Some((e, ec)),
                _ => None,
            },
        );
    let viewer = Memo::new(move |_| {
        let (e, ec) = point.get()?;
        engine.with(|engine| {
            let mut engine = (**engine.as_ref().ok()?).clone();
            let mut out = vec![0.0; engine.outputs().len()];
            engine.evaluate(&[e, ec], &mut out);
            let firing: Vec<(usize, f64)> = engine
                .activations()
                .iter()
                .copied()
                .enumerate()
                .filter(|(_, a)| *a > 0.0)
                .collect();
            Some((out[0], firing))
        })
    });
    let rule_text = move |index: usize| {
        engine.with(|engine| {
            let Ok(engine) = engine else {
                return String::new();
            };
            engine.rule_text(index)
        })
    };
    let is_firing = move |e: usize, ec: usize| {
        matches!(source.get(), Source::Table)
            && viewer.with(|v| {
                v.as_ref()
                    .is_some_and(|(_, f)| f.iter().any(|(r, _)| *r == e * 7 + ec))
            })
    };

    // A simulated run with this table, to pick a moment from.
    let runner = Runner::<Vec<Arc<RunResult>>>::new();
    let run_preset = RwSignal::new(Preset::LiuCurrentStep.name().to_string());
    let done = runner.finished();
    let run_result = Memo::new(move |_| done.get().and_then(|mut runs| runs.pop()));
    let moment = RwSignal::new(0usize);
    let runner_for_button = runner.clone();
    let start_run = move |_| {
        let Some(preset) = Preset::from_name(&run_preset.get_untracked()) else {
            return;
        };
        let mut controller = preset_controller(preset, ControllerKind::FuzzyDynamics);
        if controller.set_rule_table(table.get_untracked()).is_err() {
            return;
        }
        runner_for_button.start(LabRuns::new(vec![RunSpec {
            preset,
            controller,
            seed: 1,
            settings: Default::default(),
            plant: Default::default(),
        }]));
    };
    Effect::new(move |_| {
        let index = moment.get();
        run_result.with(|r| {
            if let Some(r) = r {
                let width = r.trace.term_names.len();
                let e = r.trace.terms.get(index * width).copied();
                let ec = r.trace.terms.get(index * width + 1).copied();
                // A held period (no force) has no inputs to show: the viewer keeps its point.
                if let (Some(e), Some(ec)) =
                    (e.filter(|v| v.is_finite()), ec.filter(|v| v.is_finite()))
                {
                    e_text.set(format!("{e:.3}"));
                    ec_text.set(format!("{ec:.3}"));
                }
            }
        });
    });

    // The run's E and EC over time, with the picked moment marked: the moment is picked on the
    // trace, not on a bare slider.
    // The traces are built once per run; moving the slider only moves the marker.
    let trace_chart = Memo::new(move |_| {
        let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear("scaled input"));
        run_result.with(|r| {
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
    let moment_chart = Signal::derive(move || {
        let mut chart = trace_chart.get();
        let time = run_result.with(|r| {
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

    let export = move |_| {
        let text = engine.with(|e| e.as_ref().ok().map(|e| fll::write(e)));
        if let Some(text) = text {
            set_fll_error.set(download_text("cutlab-fuzzy.fll", "text/plain", &text).err());
        }
    };
    let import = move |_| match fll::parse(&fll_text.get_untracked()) {
        Ok(engine) => {
            set_fll_error.set(None);
            // The page shows the file's own defuzzifier; changing it afterwards is a choice.
            if let Some(output) = engine.outputs().first() {
                defuzzifier.set(output.defuzzifier.name().to_string());
            }
            // Into the editable table only if the file is paper 002's engine with some table:
            // anything else is kept whole.
            match paper_002_table(&engine) {
                Ok(t) => {
                    table.set(t);
                    source.set(Source::Table);
                }
                Err(why) => source.set(Source::Imported(Arc::new(engine), why.to_string())),
            }
        }
        Err(e) => set_fll_error.set(Some(format!("The FLL could not be read: {e}"))),
    };
    let on_file = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |_, text| match text {
            Ok(text) => fll_text.set(text),
            Err(e) => set_fll_error.set(Some(e)),
        });
    };

    let cell = move |e: usize, ec: usize| {
        let label = format!(
            "Output when E is {} and EC is {}",
            LEVEL_NAMES[e], LEVEL_NAMES[ec]
        );
        let value = Signal::derive(move || {
            let level = table.with(|t| t[e][ec]);
            LEVEL_NAMES[(level + 3).clamp(0, 6) as usize].to_string()
        });
        let class = move || {
            let level = table.with(|t| t[e][ec]);
            let mut c = match level {
                -3 => "level-n3",
                -2 => "level-n2",
                -1 => "level-n1",
                0 => "level-0",
                1 => "level-1",
                2 => "level-2",
                _ => "level-3",
            }
            .to_string();
            if is_firing(e, ec) {
                c.push_str(" firing");
            }
            c
        };
        // The options are marked once, as the cell mounts (`prop:value` cannot choose an option
        // before the options exist); later changes of the table go through `prop:value` alone,
        // which saves a reactive `selected` per option: 343 of them in the table.
        let chosen_at_mount = value.get_untracked();
        view! {
            <td class=class>
                <select
                    aria-label=label
                    on:change=move |ev| {
                        let chosen = event_target_value(&ev);
                        if let Some(level) = LEVEL_NAMES.iter().position(|n| *n == chosen) {
                            table.update(|t| t[e][ec] = level as i8 - 3);
                        }
                    }
                    prop:value=move || value.get()
                >
                    {LEVEL_NAMES
                        .iter()
                        .map(|n| view! { <option value=*n selected=*n == chosen_at_mount>{*n}</option> })
                        .collect_view()}
                </select>
            </td>
        }
    };

    view! {
        <section class="page" aria-labelledby="fuzzy-title">
            <h1 id="fuzzy-title">"Fuzzy rules"</h1>
            <p class="lede">
                "Paper 002's controller sorts the force error E and its change EC into seven sets each "
                "and looks up the feed change U in a 7×7 table. Edit the table cell by cell, see the "
                "control surface change, and watch which rules fire for an (E, EC) you choose or for "
                "a moment of a simulated run."
            </p>
            <div class="layout-fuzzy">
                <div class="panel">
                    <fieldset>
                        <legend>"Rule table"</legend>
                        <div class="button-row">
                            {RuleBase::ALL
                                .iter()
                                .map(|b| {
                                    let b = *b;
                                    view! {
                                        <button type="button" on:click=move |_| {
                                            table.set(b.table());
                                            source.set(Source::Table);
                                        }>
                                            {b.label()}
                                        </button>
                                    }
                                })
                                .collect_view()}
                        </div>
                        // The 49 cells of seven choices each a task after the page's own.
                        <Later>
                        {move || match source.get() {
                            Source::Imported(e, why) => view! {
                                <p class="hint">
                                    {format!("Showing the imported engine \"{}\"; it is not a 7×7 table ({why}). ", e.name)}
                                    <button type="button" on:click=move |_| source.set(Source::Table)>"Back to the table"</button>
                                </p>
                            }
                            .into_any(),
                            Source::Table => view! {
                                <div class="rule-table-wrap">
                                <table class="rule-table" aria-label="Rule table: output U for each E (rows) and EC (columns)">
                                    <thead>
                                        <tr>
                                            <th scope="col">"E \\ EC"</th>
                                            {LEVEL_NAMES.iter().map(|n| view! { <th scope="col">{*n}</th> }).collect_view()}
                                        </tr>
                                    </thead>
                                    <tbody>
                                        {(0..7)
                                            .map(|e| {
                                                view! {
                                                    <tr>
                                                        <th scope="row">{LEVEL_NAMES[e]}</th>
                                                        {(0..7).map(|ec| cell(e, ec)).collect_view()}
                                                    </tr>
                                                }
                                            })
                                            .collect_view()}
                                    </tbody>
                                </table>
                                </div>
                            }
                            .into_any(),
                        }}
                        </Later>
                        <SelectField
                            id="defuzzifier"
                            label="Defuzzifier"
                            options=Defuzzifier::ALL.iter().map(|d| (d.name(), d.label())).collect()
                            value=defuzzifier
                        />
                        <p class="hint">
                            <a href=move || format!(
                                "#/simulate?preset=liu-current-step&controller=fuzzy-dynamics&rules={}",
                                encode_rule_table(&table.get())
                            )>"Simulate with this table"</a>
                        </p>
                    </fieldset>
                    // The viewer (which builds the engine and evaluates it), the run and the FLL
                    // each mount in a task of their own: in the page's, V8's first compile of all
                    // they call took its task past 50 ms.
                    <Later>
                        <fieldset>
                            <legend>"Rule viewer"</legend>
                            <NumberField
                                id="viewer-e"
                                label="E (scaled)"
                                value=e_text
                                error=Signal::derive(move || parse_number(&e_text.get()).err())
                            />
                            <NumberField
                                id="viewer-ec"
                                label="EC (scaled)"
                                value=ec_text
                                error=Signal::derive(move || parse_number(&ec_text.get()).err())
                            />
                            <p class="hint">"Or click a point of the control surface."</p>
                            {move || {
                                viewer
                                    .get()
                                    .map(|(u, firing)| {
                                        let mut firing = firing;
                                        firing.sort_by(|a, b| b.1.total_cmp(&a.1));
                                        view! {
                                            <p role="status">
                                                <strong>{format!("U = {u:.3}")}</strong>
                                                {format!(" — {} rule(s) fire", firing.len())}
                                            </p>
                                            <ol class="firing-list" aria-label="Firing rules">
                                                {firing
                                                    .into_iter()
                                                    .map(|(r, a)| {
                                                        view! {
                                                            <li>
                                                                <span class="bar" style=format!("width: {:.1}rem", 4.0 * a)></span>
                                                                {format!("{:.2}: {}", a, rule_text(r))}
                                                            </li>
                                                        }
                                                    })
                                                    .collect_view()}
                                            </ol>
                                        }
                                    })
                            }}
                        </fieldset>
                    </Later>
                    <Later>
                        <fieldset>
                            <legend>"A moment of a simulated run"</legend>
                            <SelectField
                                id="fuzzy-run-preset"
                                label="Preset"
                                options=Preset::ALL.iter().map(|p| (p.name(), p.label())).collect()
                                value=run_preset
                            />
                            <p class="hint">
                                "The run uses the fuzzy controller with this table and paper 002's "
                                "weighted-average defuzzification, whatever the viewer's choice."
                            </p>
                            <div class="button-row">
                                <button type="button" on:click=start_run.clone()>"Run with this table"</button>
                            </div>
                            <RunProgress runner=runner.clone() />
                            {move || {
                                run_result
                                    .get()
                                    .map(|r| {
                                        let last = r.trace.rows.len().saturating_sub(1);
                                        view! {
                                            <div class="field">
                                                <label for="moment">
                                                    {move || {
                                                        let t = run_result
                                                            .with(|r| r.as_ref().and_then(|r| r.trace.rows.get(moment.get()).map(|row| row.time_s)))
                                                            .unwrap_or(0.0);
                                                        format!("Moment: {t:.2} s")
                                                    }}
                                                </label>
                                                <input
                                                    id="moment"
                                                    type="range"
                                                    min="0"
                                                    max=last.to_string()
                                                    prop:value=move || moment.get().to_string()
                                                    on:input=move |ev| {
                                                        if let Ok(i) = event_target_value(&ev).parse::<usize>() {
                                                            moment.set(i.min(last));
                                                        }
                                                    }
                                                />
                                            </div>
                                        }
                                    })
                            }}
                        </fieldset>
                    </Later>
                    <Later>
                        <fieldset>
                            <legend>"FLL (fuzzylite)"</legend>
                            <div class="button-row">
                                <button type="button" on:click=export>"Export FLL"</button>
                            </div>
                            <div class="field">
                                <label for="fll-file">"FLL file to import"</label>
                                <input id="fll-file" type="file" accept=".fll,text/plain" on:change=on_file />
                            </div>
                            <div class="field">
                                <label for="fll-text">"FLL text"</label>
                                <textarea
                                    id="fll-text"
                                    class="fll"
                                    prop:value=move || fll_text.get()
                                    on:input=move |ev| fll_text.set(event_target_value(&ev))
                                ></textarea>
                            </div>
                            <div class="button-row">
                                <button type="button" on:click=import>"Import FLL"</button>
                            </div>
                            {move || fll_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
                        </fieldset>
                    </Later>
                </div>
                // The surface (the engine over a grid) and the charts in the task after the
                // form's: together they took the page's first task past 50 ms.
                <div class="charts">
                  <Later>
                    {move || engine.with(|e| e.as_ref().err().map(|m| view! { <p class="run-error" role="alert">{m.clone()}</p> }))}
                    <HeatMapCanvas
                        label="Control surface U(E, EC)"
                        map=map_signal
                        on_pick=Callback::new(move |(x, y): (f64, f64)| {
                            e_text.set(format!("{x:.2}"));
                            ec_text.set(format!("{y:.2}"));
                        })
                    />
                    {move || {
                        run_result
                            .with(|r| r.is_some())
                            .then(|| view! { <ChartCanvas label="E and EC of the run" chart=moment_chart height_px=180 /> })
                    }}
                    <ChartCanvas label="Membership functions of E" chart=chart_of(Some(0)) height_px=180 />
                    <ChartCanvas label="Membership functions of EC" chart=chart_of(Some(1)) height_px=180 />
                    <ChartCanvas label="Membership functions of U" chart=chart_of(None) height_px=180 />
                  </Later>
                </div>
            </div>
        </section>
    }
}
