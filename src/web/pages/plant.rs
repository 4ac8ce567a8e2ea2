//! Plant: the simulated machine on its own — a preset's tool path and depth profile, and its
//! forces, torque and motor currents at a fixed override; for paper 000's brake bench, the
//! current spectrum at each load step and the RMS-current-versus-load line (Fig. 9 and 11).

use std::ops::Range;
use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::charts::{Axis, LineChart, Rgb, Series, PALETTE};
use crate::estimation::least_squares::fit;
use crate::machine::Machine;
use crate::plant::recording::{BlockRow, OpenLoopRun};
use crate::plant::Preset;
use crate::signal::spectrum::{amplitude_spectrum, Window};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::fields::{parse_number, NumberField, SelectField};
use crate::web::components::runner::{Debounce, RunProgress, RunStatus, Runner};
use crate::web::route::{query_params, replace_query, Page};
use crate::work::{Progress, Work};

/// Wait after the last edit before re-running.
const RERUN_DELAY: Duration = Duration::from_millis(300);

/// Samples summarised per plotted row: 5 ms at 10 kHz.
const BLOCK_SAMPLES: usize = 50;

/// Spectra are drawn up to this frequency: the bench's 4 Hz electrical frequency and its first
/// harmonics (paper 000 Fig. 9).
const SPECTRUM_MAX_HZ: f64 = 20.0;

/// A load step needs at least this many settled samples (0.1 s at 10 kHz) to count; shorter
/// "steps" are the brake's torque following the feed as it starts or stops.
const MIN_STEP_SAMPLES: usize = 1000;

/// One brake-bench load step as the page shows it.
#[derive(Debug, Clone, PartialEq)]
pub struct StepSummary {
    /// Brake torque during the step.
    brake_torque_nm: f64,
    /// Mean RMS feed current over its settled part.
    feed_rms_a: f64,
    /// Amplitude spectrum of the phase current i_u up to [`SPECTRUM_MAX_HZ`]: (Hz, A).
    spectrum: Vec<(f64, f64)>,
}

/// A finished open-loop recording.
#[derive(Debug, Clone, PartialEq)]
pub struct Recording {
    preset: Preset,
    rows: Vec<BlockRow>,
    steps: Vec<StepSummary>,
}

struct PlantJob {
    preset: Preset,
    run: OpenLoopRun,
    sample_rate_hz: f64,
    /// The summaries of the load steps that have ended. Each step's spectrum is taken as soon as
    /// the next step begins, so the work is spread over the run's chunks instead of holding the
    /// page for all steps at the end.
    steps: Vec<StepSummary>,
    /// How many of the run's load steps have been summarised (or skipped as too short).
    steps_seen: usize,
}

impl PlantJob {
    /// Summarises the load steps up to (not including) `ended`.
    fn summarise_steps(&mut self, ended: usize) {
        let ended = ended.min(self.run.load_steps().len());
        for step in &self.run.load_steps()[self.steps_seen.min(ended)..ended] {
            if step.feed_iu_a.len() < MIN_STEP_SAMPLES {
                continue;
            }
            // Cannot fail: the step has more than one sample and the rate is the plant's.
            let spectrum = amplitude_spectrum(&step.feed_iu_a, self.sample_rate_hz, Window::Hann)
                .map(|sp| {
                    sp.freq_hz
                        .iter()
                        .zip(&sp.amplitude)
                        .take_while(|(f, _)| **f <= SPECTRUM_MAX_HZ)
                        .map(|(f, a)| (*f, *a))
                        .collect()
                })
                .unwrap_or_default();
            self.steps.push(StepSummary {
                brake_torque_nm: step.brake_torque_nm,
                feed_rms_a: step.feed_rms_a,
                spectrum,
            });
        }
        self.steps_seen = self.steps_seen.max(ended);
    }
}

impl Work for PlantJob {
    type Output = Arc<Recording>;
    type Error = String;

    fn advance(&mut self, budget: usize) -> Result<bool, String> {
        let done = self.run.advance(budget.max(1000));
        // A step has ended once the next one has begun; the last one when the run ends.
        let steps = self.run.load_steps().len();
        self.summarise_steps(if done { steps } else { steps.saturating_sub(1) });
        Ok(done)
    }

    fn progress(&self) -> Progress {
        Progress::new("Simulating the machine", self.run.fraction())
    }

    fn finish(&mut self) -> Result<Self::Output, String> {
        self.summarise_steps(self.run.load_steps().len());
        Ok(Arc::new(Recording {
            preset: self.preset,
            rows: self.run.rows().to_vec(),
            steps: std::mem::take(&mut self.steps),
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

/// A colour for a load, `fraction` = load / largest load: light green at no load to dark violet
/// at the largest (viridis, which stays readable for colour-blind readers, without its pale
/// yellow end that would vanish on white). The same load has the same colour in every chart.
fn load_colour(fraction: f64) -> Rgb {
    const STOPS: [(f64, f64, f64); 4] = [
        (94.0, 201.0, 98.0),
        (33.0, 145.0, 140.0),
        (59.0, 82.0, 139.0),
        (68.0, 1.0, 84.0),
    ];
    let t = if fraction.is_finite() {
        fraction.clamp(0.0, 1.0) * (STOPS.len() - 1) as f64
    } else {
        0.0
    };
    let i = (t.floor() as usize).min(STOPS.len() - 2);
    let u = t - i as f64;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    let mix = |p: f64, q: f64| (p + (q - p) * u).round() as u8;
    Rgb(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

/// The bench's charts: the spectrum of every load step (loading steps in one chart, unloading
/// steps in another, so neither holds more than about ten lines), RMS current against brake
/// torque with the fitted line, and the fit as text.
#[derive(Debug, Clone, PartialEq)]
struct BenchCharts {
    loading: LineChart,
    unloading: LineChart,
    line: LineChart,
    text: String,
}

/// Paper 000's bench: spectra at the load steps, and RMS current against brake torque with the
/// fitted line.
fn bench_charts(rec: &Recording) -> Option<BenchCharts> {
    let steps = &rec.steps;
    if steps.is_empty() {
        return None;
    }
    let spectrum_chart = || {
        LineChart::new(
            Axis::linear("frequency (Hz)"),
            Axis::linear("amplitude of i_u (A)"),
        )
    };
    let (mut loading, mut unloading) = (spectrum_chart(), spectrum_chart());
    let largest_nm = steps.iter().map(|s| s.brake_torque_nm).fold(0.0, f64::max);
    let mut previous_nm = f64::NEG_INFINITY;
    for s in steps {
        // A step is loading when its torque is at least the previous step's.
        let chart = if s.brake_torque_nm >= previous_nm {
            &mut loading
        } else {
            &mut unloading
        };
        previous_nm = s.brake_torque_nm;
        chart.series.push(Series::new(
            format!("{:.2} N·m", s.brake_torque_nm),
            load_colour(s.brake_torque_nm / largest_nm),
            s.spectrum.clone(),
        ));
    }
    // One amplitude scale for both, so loading and unloading at a similar torque compare by eye.
    loading.fit();
    unloading.fit();
    if !unloading.series.is_empty() {
        let (a, b) = (&loading.y.range, &unloading.y.range);
        let shared = a.start.min(b.start)..a.end.max(b.end);
        loading.y.range = shared.clone();
        unloading.y.range = shared;
    }
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
            line.series.push(
                Series::new(
                    "least-squares line",
                    PALETTE[5],
                    vec![(0.0, a), (largest_nm, a + b * largest_nm)],
                )
                .dashed(),
            );
            format!(
                "RMS current = {a:.3} A + {b:.3} A/(N·m) × torque over {} load steps (R² = {:.4}): \
                 linear, with an idle current that is not zero, as paper 000's Fig. 11 shows.",
                steps.len(),
                f.r_squared
            )
        }
        Err(e) => format!("No line could be fitted to {} load steps: {e}", steps.len()),
    };
    line.fit();
    Some(BenchCharts {
        loading,
        unloading,
        line,
        text,
    })
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
                let sample_rate_hz = machine.sample_rate_hz();
                runner.start(PlantJob {
                    preset: p,
                    run: OpenLoopRun::new(machine, pct, BLOCK_SAMPLES, max_s),
                    sample_rate_hz,
                    steps: Vec::new(),
                    steps_seen: 0,
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
                            .map(|BenchCharts { loading, unloading, line, text }| {
                                // A run cut short by its time limit may end before the brake is unloaded.
                                let unloading = (!unloading.series.is_empty()).then(|| {
                                    view! {
                                        <ChartCanvas label="Spectrum of the phase current at each unloading step" chart=Signal::derive(move || unloading.clone()) />
                                    }
                                });
                                view! {
                                    <h2>"Paper 000's bench: current against load"</h2>
                                    <ChartCanvas label="Spectrum of the phase current at each loading step" chart=Signal::derive(move || loading.clone()) />
                                    {unloading}
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
