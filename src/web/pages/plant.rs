//! Plant: the simulated machine on its own — a preset's tool path and depth profile, and its
//! forces, torque and motor currents at a fixed override; for paper 000's brake bench, the
//! current spectrum at each load step and the RMS-current-versus-load line (Fig. 9 and 11).

use std::ops::Range;
use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::charts::{Axis, LineChart, Series, PALETTE};
use crate::estimation::least_squares::fit;
use crate::plant::recording::{BlockRow, LoadStep, OpenLoopRun};
use crate::plant::Preset;
use crate::signal::spectrum::{amplitude_spectrum, Window};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::fields::{parse_number, NumberField, SelectField};
use crate::web::components::runner::{Debounce, Job, RunProgress, RunStatus, Runner};
use crate::web::route::{query_params, replace_query, Page};

/// Wait after the last edit before re-running.
const RERUN_DELAY: Duration = Duration::from_millis(300);

/// Samples summarised per plotted row: 5 ms at 10 kHz.
const BLOCK_SAMPLES: usize = 50;

/// A finished open-loop recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    preset: Preset,
    rows: Vec<BlockRow>,
    steps: Vec<LoadStep>,
}

struct PlantJob {
    preset: Preset,
    run: OpenLoopRun,
}

impl Job for PlantJob {
    type Output = Arc<Recording>;

    fn advance(&mut self, budget: usize) -> Result<bool, String> {
        Ok(self.run.advance(budget.max(1000)))
    }

    fn progress(&self) -> (String, f64) {
        ("Simulating the machine".to_string(), self.run.fraction())
    }

    fn finish(&mut self) -> Result<Self::Output, String> {
        Ok(Arc::new(Recording {
            preset: self.preset,
            rows: self.run.rows().to_vec(),
            steps: self.run.load_steps().to_vec(),
        }))
    }
}

fn time_series(rows: &[BlockRow], f: impl Fn(&BlockRow) -> f64) -> Vec<(f64, f64)> {
    rows.iter().map(|r| (r.time_s, f(r))).collect()
}

fn time_chart(y: &str, series: Vec<Series>) -> LineChart {
    let mut c = LineChart::new(Axis::linear("time (s)"), Axis::linear(y));
    c.series = series;
    c.fit();
    c
}

/// Every chart of a recording, in page order, with its accessible name.
fn recording_charts(rec: &Recording) -> Vec<(&'static str, LineChart)> {
    let r = &rec.rows;
    let mut charts = Vec::new();
    if let Some(scenario) = rec.preset.scenario() {
        let mut path = LineChart::new(Axis::linear("x (mm)"), Axis::linear("y (mm)"));
        path.series.push(Series::new(
            "tool path",
            PALETTE[0],
            scenario
                .polyline(0.5)
                .into_iter()
                .map(|[x, y]| (x, y))
                .collect(),
        ));
        path.fit();
        charts.push(("Tool path", path));
        let mut depth = LineChart::new(Axis::linear("path position (mm)"), Axis::linear("mm"));
        depth.series.push(Series::new(
            "axial depth",
            PALETTE[0],
            scenario
                .depth_profile()
                .points()
                .iter()
                .map(|p| (p.position_mm, p.value))
                .collect(),
        ));
        depth.series.push(Series::new(
            "radial width",
            PALETTE[1],
            scenario
                .width_profile()
                .points()
                .iter()
                .map(|p| (p.position_mm, p.value))
                .collect(),
        ));
        depth.fit();
        charts.push(("Depth and width of cut along the path", depth));
    }
    charts.push((
        "Cutting forces",
        time_chart(
            "force (N)",
            vec![
                Series::new("F_x (mean)", PALETTE[0], time_series(r, |b| b.force_x_n)),
                Series::new("F_y (mean)", PALETTE[1], time_series(r, |b| b.force_y_n)),
                Series::new("F_z (mean)", PALETTE[2], time_series(r, |b| b.force_z_n)),
                Series::new("|F| max", PALETTE[5], time_series(r, |b| b.resultant_max_n)),
            ],
        ),
    ));
    charts.push((
        "Spindle torque",
        time_chart(
            "torque (N·m)",
            vec![Series::new(
                "cutting torque",
                PALETTE[0],
                time_series(r, |b| b.spindle_torque_nm),
            )],
        ),
    ));
    charts.push((
        "Phase currents",
        time_chart(
            "current (A)",
            vec![
                Series::new(
                    "feed i_u max",
                    PALETTE[0],
                    time_series(r, |b| b.feed_iu_max_a),
                ),
                Series::new(
                    "feed i_u min",
                    PALETTE[0],
                    time_series(r, |b| b.feed_iu_min_a),
                ),
                Series::new(
                    "spindle i_u max",
                    PALETTE[1],
                    time_series(r, |b| b.spindle_iu_max_a),
                ),
                Series::new(
                    "spindle i_u min",
                    PALETTE[1],
                    time_series(r, |b| b.spindle_iu_min_a),
                ),
            ],
        ),
    ));
    charts.push((
        "RMS currents",
        time_chart(
            "RMS current (A)",
            vec![
                Series::new("feed drive", PALETTE[0], time_series(r, |b| b.feed_rms_a)),
                Series::new("spindle", PALETTE[1], time_series(r, |b| b.spindle_rms_a)),
            ],
        ),
    ));
    charts
}

/// Paper 000's bench: spectra at the load steps, and RMS current against brake torque with the
/// fitted line.
fn bench_charts(rec: &Recording) -> Option<(LineChart, LineChart, String)> {
    let steps: Vec<&LoadStep> = rec
        .steps
        .iter()
        .filter(|s| s.feed_iu_a.len() > 1000)
        .collect();
    if steps.is_empty() {
        return None;
    }
    let mut spectra = LineChart::new(
        Axis::linear("frequency (Hz)"),
        Axis::linear("amplitude of i_u (A)"),
    );
    let shown: Vec<&&LoadStep> = steps.iter().step_by((steps.len() / 5).max(1)).collect();
    for (k, s) in shown.iter().enumerate() {
        if let Ok(sp) = amplitude_spectrum(&s.feed_iu_a, 10_000.0, Window::Hann) {
            spectra.series.push(Series::new(
                format!("{:.2} N·m", s.brake_torque_nm),
                PALETTE[k % PALETTE.len()],
                sp.freq_hz
                    .iter()
                    .zip(&sp.amplitude)
                    .filter(|(f, _)| **f <= 20.0)
                    .map(|(f, a)| (*f, *a))
                    .collect(),
            ));
        }
    }
    spectra.fit();
    let torque: Vec<f64> = steps.iter().map(|s| s.brake_torque_nm).collect();
    let rms: Vec<f64> = steps.iter().map(|s| s.feed_rms_a).collect();
    let mut line = LineChart::new(
        Axis::linear("brake torque (N·m)"),
        Axis::linear("RMS current (A)"),
    );
    line.series.push(Series::new(
        "load steps (loading and unloading)",
        PALETTE[0],
        torque.iter().copied().zip(rms.iter().copied()).collect(),
    ));
    let ones = vec![1.0; torque.len()];
    let text = match fit(&[("idle current", &ones), ("torque", &torque)], &rms) {
        Ok(f) => {
            let (a, b) = (f.coefficients[0], f.coefficients[1]);
            let t_max = torque.iter().cloned().fold(0.0, f64::max);
            line.series.push(
                Series::new(
                    "least-squares line",
                    PALETTE[5],
                    vec![(0.0, a), (t_max, a + b * t_max)],
                )
                .dashed(),
            );
            format!(
                "RMS current = {a:.3} A + {b:.3} A/(N·m) × torque (R² = {:.4}): linear, with an idle \
                 current that is not zero, as paper 000's Fig. 11 shows.",
                f.r_squared
            )
        }
        Err(e) => format!("No line could be fitted: {e}"),
    };
    line.fit();
    Some((spectra, line, text))
}

/// The Plant page.
#[component]
pub fn PlantPage() -> impl IntoView {
    let query = query_params(&window().location().hash().unwrap_or_default());
    let get = |key: &str, default: &str| {
        query
            .iter()
            .find(|(k, _)| k == key)
            .map_or(default.to_string(), |(_, v)| v.clone())
    };
    let preset = RwSignal::new(get("preset", Preset::KimStepDoc.name()));
    let override_text = RwSignal::new(get("override", "100"));
    let override_error = Signal::derive(move || match parse_number(&override_text.get()) {
        Ok(v) if (0.0..=255.0).contains(&v) => None,
        Ok(v) => Some(format!("{v} % is outside 0–255 %")),
        Err(e) => Some(e),
    });
    let runner = Runner::<Arc<Recording>>::new();
    let debounce = Debounce::new(RERUN_DELAY);
    let runner_for_effect = runner.clone();
    Effect::new(move |_| {
        let name = preset.get();
        let text = override_text.get();
        replace_query(
            Page::Plant,
            &[
                ("preset".into(), name.clone()),
                ("override".into(), text.clone()),
            ],
        );
        let (Some(p), Ok(pct)) = (Preset::from_name(&name), parse_number(&text)) else {
            return;
        };
        if !(0.0..=255.0).contains(&pct) {
            return;
        }
        let runner = runner_for_effect.clone();
        debounce.request(move || match p.machine(1) {
            Ok(machine) => {
                let max_s = p.summary().nominal_duration_s * 3.0 + 10.0;
                runner.start(PlantJob {
                    preset: p,
                    run: OpenLoopRun::new(machine, pct, BLOCK_SAMPLES, max_s),
                });
            }
            Err(e) => {
                let _ = runner.status.try_set(RunStatus::Failed(e.to_string()));
            }
        });
    });
    let recording = runner.finished();
    let charts = Memo::new(move |_| {
        recording
            .get()
            .map(|r| recording_charts(&r))
            .unwrap_or_default()
    });
    let bench = Memo::new(move |_| recording.get().and_then(|r| bench_charts(&r)));
    let x_view = RwSignal::new(None::<Range<f64>>);
    let summary = move || {
        Preset::from_name(&preset.get()).map(|p| {
            let s = p.summary();
            let mut parts = vec![format!("{} ({})", p.label(), p.source())];
            parts.extend(s.tool.clone());
            parts.extend(s.material.clone());
            if let Some(rpm) = s.spindle_rpm {
                parts.push(format!("{rpm:.0} rpm"));
            }
            if let Some(f) = s.programmed_feed_mm_min {
                parts.push(format!("{f:.0} mm/min"));
            }
            parts.join(" · ")
        })
    };
    let regions = move || {
        Preset::from_name(&preset.get())
            .and_then(|p| p.scenario())
            .map(|s| {
                s.material_regions()
                    .iter()
                    .map(|r| format!("{:.0}–{:.0} mm: {}", r.from_mm, r.to_mm, r.material.label()))
                    .collect::<Vec<_>>()
                    .join("; ")
            })
    };

    view! {
        <section class="page" aria-labelledby="plant-title">
            <h1 id="plant-title">"The simulated machine"</h1>
            <p class="lede">
                "Each preset is one of the papers' experiments run on the simulated FANUC mill (or, for "
                "paper 000, its brake bench). Here it runs open-loop at a fixed feed override, so you see "
                "what the plant does before any controller touches it."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Plant settings" on:submit=|ev| ev.prevent_default()>
                    <SelectField
                        id="plant-preset"
                        label="Preset"
                        options=Preset::ALL.iter().map(|p| (p.name(), p.label())).collect()
                        value=preset
                    />
                    <p class="hint">{summary}</p>
                    <p class="hint">{move || regions().map(|r| format!("Material: {r}"))}</p>
                    <NumberField id="plant-override" label="Feed override" unit="%" value=override_text error=override_error />
                    <RunProgress runner=runner.clone() />
                </form>
                <div class="charts">
                    {move || {
                        charts
                            .get()
                            .into_iter()
                            .map(|(label, chart)| {
                                let is_time = chart.x.label == "time (s)";
                                let chart = Signal::derive(move || chart.clone());
                                if is_time {
                                    view! { <ChartCanvas label=label chart=chart height_px=200 x_view=x_view /> }.into_any()
                                } else {
                                    view! { <ChartCanvas label=label chart=chart height_px=220 /> }.into_any()
                                }
                            })
                            .collect_view()
                    }}
                    {move || {
                        bench
                            .get()
                            .map(|(spectra, line, text)| {
                                view! {
                                    <h2>"Paper 000's bench: current against load"</h2>
                                    <ChartCanvas label="Spectrum of the phase current at load steps" chart=Signal::derive(move || spectra.clone()) />
                                    <p class="hint" role="status">{text}</p>
                                    <ChartCanvas label="RMS current against brake torque" chart=Signal::derive(move || line.clone()) />
                                }
                            })
                    }}
                </div>
            </div>
        </section>
    }
}
