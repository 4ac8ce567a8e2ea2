//! Plant: the simulated machine on its own — a preset's tool path and depth profile, and its
//! forces, torque and motor currents at a fixed override; for paper 000's brake bench, the
//! current spectrum at each load step and the RMS-current-versus-load line (Fig. 9 and 11); and
//! paper 004's network learned on the machine's trial cuts, or on the user's own.
//!
//! | file | what |
//! |---|---|
//! | `mod.rs` | the page: the preset, its open-loop run (recorded in a computation worker, [`crate::web::components::pool`]) and charts |
//! | [`learning`] | paper 004's network learned from trial cuts, with its residuals |
//! | [`own_cuts`] | the same network learned from a table of the user's own trial cuts |
//! | [`learned_tables`] | the two panels' tables: learned exponents, and each cut's residuals, for one force or two |

mod learned_tables;
mod learning;
mod own_cuts;

use std::ops::Range;
use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use crate::charts::{Axis, LineChart, Rgb, Series, PALETTE};
use crate::closed_loop::recording_jobs::OpenLoopRequest;
use crate::closed_loop::transfer::JobRequest;
use crate::input::table::{self, form_errors};
use crate::plant::recording::{BlockRow, OpenLoopRecording, OpenLoopRun, OpenLoopSetting};
use crate::plant::scenario::Profile;
use crate::plant::Preset;
use crate::web::components::chart::ChartCanvas;
use crate::web::components::fields::SelectField;
use crate::web::components::page::PageShell;
use crate::web::components::paper_link::WithPaperLinks;
use crate::web::components::pool::Answer;
use crate::web::components::runner::{Debounce, RunProgress, Runner};
use crate::web::components::table_form::{SettingField, TableForm};
use crate::web::route::{query_params, replace_query, Page};

use learning::LearningPanel;
use own_cuts::OwnCutsPanel;

/// Wait after the last edit before re-running.
const RERUN_DELAY: Duration = Duration::from_millis(300);

/// Samples summarised per plotted row: 5 ms at 10 kHz.
const BLOCK_SAMPLES: usize = 50;

fn time_series(rows: &[BlockRow], f: impl Fn(&BlockRow) -> f64) -> Vec<(f64, f64)> {
    rows.iter().map(|r| (r.time_s, f(r))).collect()
}

fn time_chart(y: &str, series: Vec<Series>) -> LineChart {
    let mut c = LineChart::new(Axis::linear("time (s)"), Axis::linear(y));
    c.series = series;
    c.fit();
    c
}

/// `profile`'s points drawn over the whole path (0 to `length_mm`): a profile is constant beyond
/// its ends ([`Profile::value_at`]), so the first value is drawn back to the start and the last
/// held section to the end — a constant profile (one point) is a line, not a dot.
fn profile_along_path(profile: &Profile, length_mm: f64) -> Vec<(f64, f64)> {
    let mut points: Vec<(f64, f64)> = profile
        .points()
        .iter()
        .map(|p| (p.position_mm, p.value))
        .collect();
    if let Some(&(first_mm, first)) = points.first() {
        if first_mm > 0.0 {
            points.insert(0, (0.0, first));
        }
    }
    if let Some(&(last_mm, last)) = points.last() {
        if last_mm < length_mm {
            points.push((length_mm, last));
        }
    }
    points
}

/// Every chart of a recording, in page order, with its accessible name.
fn recording_charts(rec: &OpenLoopRecording) -> Vec<(&'static str, LineChart)> {
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
            profile_along_path(scenario.depth_profile(), scenario.total_length_mm()),
        ));
        depth.series.push(Series::new(
            "radial width",
            PALETTE[1],
            profile_along_path(scenario.width_profile(), scenario.total_length_mm()),
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
                    PALETTE[4],
                    time_series(r, |b| b.feed_iu_min_a),
                ),
                Series::new(
                    "spindle i_u max",
                    PALETTE[5],
                    time_series(r, |b| b.spindle_iu_max_a),
                ),
                Series::new(
                    "spindle i_u min",
                    PALETTE[3],
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
fn bench_charts(rec: &OpenLoopRecording) -> Option<BenchCharts> {
    let steps = &rec.load_steps;
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
    for s in steps {
        let chart = if s.loading {
            &mut loading
        } else {
            &mut unloading
        };
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
    let mut line = LineChart::new(
        Axis::linear("brake torque (N·m)"),
        Axis::linear("RMS current (A)"),
    );
    line.series.push(Series::new(
        "load steps (loading and unloading)",
        PALETTE[0],
        steps
            .iter()
            .map(|s| (s.brake_torque_nm, s.feed_rms_a))
            .collect(),
    ));
    let text = match rec.load_line() {
        Ok(fitted) => {
            let (a, b) = (fitted.idle_current_a, fitted.slope_a_per_nm);
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
                fitted.steps,
                fitted.r_squared
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
    // The override through its row of the core's table, as `cutlab scenarios --override`.
    let form = TableForm::<OpenLoopSetting>::new(&query);
    let override_text = form.text(OpenLoopSetting::Override);
    let override_pct =
        Memo::new(move |_| table::number(OpenLoopSetting::Override, &override_text.get()));
    let errors = Signal::derive(move || {
        override_pct
            .get()
            .err()
            .map(|e| form_errors(&[e]))
            .unwrap_or_default()
    });
    let runner = Runner::<Arc<OpenLoopRecording>>::new();
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
        let (Some(p), Ok(pct)) = (Preset::from_name(&name), override_pct.get()) else {
            return;
        };
        let runner = runner_for_effect.clone();
        // In a computation worker: the page's thread stays free while the machine runs.
        debounce.request(move || {
            let request = OpenLoopRequest {
                preset: p,
                seed: 1,
                override_pct: pct,
                block_samples: BLOCK_SAMPLES,
                max_duration_s: OpenLoopRun::time_limit_s(p),
            };
            runner.start_in_worker(JobRequest::OpenLoop(request), |answer| match answer {
                Answer::OpenLoopRecording(recording) => Some(recording),
                _ => None,
            });
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
        <PageShell id="plant" title="The simulated machine">
            <p class="lede">
                <WithPaperLinks text="Each preset is one of the papers' experiments run on the simulated \
                    FANUC mill (or, for paper 000, its brake bench). Here it runs open-loop at a fixed \
                    feed override, so you see what the plant does before any controller touches it." />
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
                    <SettingField form=form setting=OpenLoopSetting::Override errors=errors id_prefix="plant-" />
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
            <LearningPanel preset=preset />
            <OwnCutsPanel />
        </PageShell>
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_cut_profiles_are_drawn_over_the_whole_path() {
        let preset = Preset::from_name("kim-step-doc").expect("a preset");
        let scenario = preset.scenario().expect("a mill preset");
        let length_mm = scenario.total_length_mm();
        let depth = profile_along_path(scenario.depth_profile(), length_mm);
        let width = profile_along_path(scenario.width_profile(), length_mm);
        // The depth's last breakpoint is before the end of the path: its section is held there.
        let last_break_mm = scenario
            .depth_profile()
            .points()
            .last()
            .expect("points")
            .position_mm;
        assert!(last_break_mm < length_mm, "{last_break_mm} vs {length_mm}");
        for line in [&depth, &width] {
            assert_eq!(line.first().map(|p| p.0), Some(0.0));
            assert_eq!(line.last().map(|p| p.0), Some(length_mm));
        }
        let held = scenario.depth_profile().value_at(length_mm);
        assert_eq!(depth.last().map(|p| p.1), Some(held));
        // A constant width is a line over the path, not a single point.
        assert_eq!(scenario.width_profile().points().len(), 1);
        assert_eq!(width.len(), 2);
    }
}
