//! Signal chain: design the Butterworth low-pass that cleans the motor current, and see what it
//! does to magnitude and phase.
//!
//! The form is the design table's rows ([`crate::signal::design_settings`]) and lives in the URL
//! query (`#/signal?preset=wang-10th-5hz`, `#/signal?kind=bandpass&cutoff=40&upper=400`; defaults
//! are left out), so a link reproduces the design and the Learn page can open a paper's filter.

use std::sync::Arc;

use leptos::prelude::*;

use crate::charts::{Axis, LineChart, Scale, Series, PALETTE};
use crate::closed_loop::recording_jobs::BenchRequest;
use crate::closed_loop::transfer::JobRequest;
use crate::input::table::{form_errors, Table};
use crate::plant::recording::PhaseRecording;
use crate::plant::Preset;
use crate::signal::butterworth::{ButterworthSpec, FilterKind};
use crate::signal::design_settings::{
    parse_design, query_texts, FilterPreset, FilterSetting, PAPER_FILTERS,
};
use crate::signal::filter::SosFilterBank;
use crate::signal::rms::three_phase_rms;
use crate::signal::sos::Sos;
use crate::signal::spectrum::{amplitude_spectrum, find_peaks, Window};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::later::{effect_after_mount, Later};
use crate::web::components::page::PageShell;
use crate::web::components::paper_link::WithPaperLinks;
use crate::web::components::pool::Answer;
use crate::web::components::runner::{next_task, RunProgress, Runner};
use crate::web::components::table_form::{FieldErrors, SettingField, TableForm};
use crate::web::route::{query_params, replace_query, Page};

/// The paper filter whose values the form holds, exactly as its button fills them in.
fn chosen_preset(texts: &[(FilterSetting, String)]) -> Option<&'static FilterPreset> {
    PAPER_FILTERS.iter().find(|p| {
        p.texts()
            .iter()
            .all(|given| texts.iter().any(|typed| typed == given))
    })
}

/// The form a URL query describes: the defaults, then what the query gives
/// ([`query_texts`], which lessons read too).
fn form_from_query(query: &[(String, String)]) -> TableForm<FilterSetting> {
    let form = TableForm::new(&[]);
    for (setting, text) in query_texts(query) {
        form.text(setting).set(text);
    }
    form
}

/// Fills the form with `preset`'s values; the upper cut-off, which no preset uses, keeps its text.
fn fill(form: TableForm<FilterSetting>, preset: &FilterPreset) {
    for (setting, text) in preset.texts() {
        form.text(setting).set(text);
    }
}

/// The URL query of the form: the preset's name when the form holds one, else every field whose
/// text differs from its default. The upper cut-off, which no preset sets, is written whenever it
/// differs from its default, also while it is hidden, so its text survives.
fn design_query(texts: &[(FilterSetting, String)]) -> Vec<(String, String)> {
    let preset = chosen_preset(texts);
    let mut query: Vec<(String, String)> = preset
        .map(|p| ("preset".to_string(), p.name.to_string()))
        .into_iter()
        .collect();
    query.extend(
        texts
            .iter()
            .filter(|(s, _)| preset.is_none() || *s == FilterSetting::Upper)
            .filter(|(s, text)| text.trim() != s.row().default_text())
            .map(|(s, text)| (s.row().key.to_string(), text.clone())),
    );
    query
}

/// A design, or the message of each field that does not give one.
type Design = Result<(ButterworthSpec, Sos), FieldErrors>;

/// Number of frequencies at which the response is evaluated, log-spaced.
const RESPONSE_POINTS: usize = 600;

/// Magnitude (dB) and phase (degrees, unwrapped) charts of a design.
fn response_charts(spec: &ButterworthSpec, sos: &Sos) -> (LineChart, LineChart) {
    let nyquist = spec.sample_rate_hz / 2.0;
    let low = (nyquist * 1e-4).max(1e-3);
    let high = nyquist * 0.999;
    let freqs: Vec<f64> = (0..RESPONSE_POINTS)
        .map(|i| {
            let t = i as f64 / (RESPONSE_POINTS - 1) as f64;
            low * (high / low).powf(t)
        })
        .collect();
    let response = sos.frequency_response(&freqs, spec.sample_rate_hz);
    let magnitude: Vec<(f64, f64)> = freqs
        .iter()
        .zip(&response)
        .map(|(f, h)| (*f, 20.0 * h.norm().max(1e-300).log10()))
        .collect();
    let mut phase = Vec::with_capacity(freqs.len());
    let mut previous = 0.0;
    let mut offset = 0.0;
    for (f, h) in freqs.iter().zip(&response) {
        let wrapped = h.arg().to_degrees();
        if !phase.is_empty() {
            let jump = wrapped + offset - previous;
            offset -= 360.0 * (jump / 360.0).round();
        }
        previous = wrapped + offset;
        phase.push((*f, previous));
    }

    let mut magnitude_chart =
        LineChart::new(Axis::log("frequency (Hz)"), Axis::linear("magnitude (dB)"));
    magnitude_chart.series.push(Series::new(
        format!("|H(f)|, order {}", spec.order),
        PALETTE[0],
        magnitude,
    ));
    magnitude_chart
        .series
        .push(Series::new("−3 dB", PALETTE[5], vec![(low, -3.0103), (high, -3.0103)]).dashed());
    magnitude_chart.fit();
    // Below −200 dB is numerical floor, not information.
    magnitude_chart.y.range.start = magnitude_chart.y.range.start.max(-200.0);

    let mut phase_chart = LineChart::new(Axis::log("frequency (Hz)"), Axis::linear("phase (°)"));
    phase_chart
        .series
        .push(Series::new("arg H(f), unwrapped", PALETTE[2], phase));
    phase_chart.fit();
    (magnitude_chart, phase_chart)
}

/// The bench's phase currents through `sos` (interleaved as the recording's), the filter started
/// as if the input had always been the first sample: no start-up transient.
fn filtered_phases(recording: &PhaseRecording, sos: &Sos) -> Option<Vec<f64>> {
    let mut bank = SosFilterBank::new(sos, 3).ok()?;
    let first = recording.phases_a.get(..3)?;
    bank.set_steady_state(first);
    let mut filtered = recording.phases_a.clone();
    bank.process_slice(&mut filtered);
    Some(filtered)
}

/// Phase current i_u before and after the filter.
fn phase_chart(recording: &PhaseRecording, filtered: &[f64]) -> LineChart {
    let phase_u = |v: &[f64]| -> Vec<(f64, f64)> {
        recording
            .time_s
            .iter()
            .zip(v.chunks_exact(3))
            .map(|(t, f)| (*t, f[0]))
            .collect()
    };
    let mut phase = LineChart::new(
        Axis::linear("time (s)"),
        Axis::linear("phase current i_u (A)"),
    );
    phase.series.push(Series::new(
        "raw (Hall + ADC)",
        PALETTE[4],
        phase_u(&recording.phases_a),
    ));
    phase
        .series
        .push(Series::new("filtered", PALETTE[0], phase_u(filtered)));
    phase.fit();
    phase
}

/// The three-phase RMS before and after the filter.
fn rms_chart(recording: &PhaseRecording, filtered: &[f64]) -> LineChart {
    let rms = |v: &[f64]| -> Vec<(f64, f64)> {
        recording
            .time_s
            .iter()
            .zip(v.chunks_exact(3))
            .map(|(t, f)| (*t, three_phase_rms(f[0], f[1], f[2])))
            .collect()
    };
    let mut rms_chart = LineChart::new(
        Axis::linear("time (s)"),
        Axis::linear("three-phase RMS (A)"),
    );
    rms_chart
        .series
        .push(Series::new("raw", PALETTE[4], rms(&recording.phases_a)));
    rms_chart
        .series
        .push(Series::new("filtered", PALETTE[0], rms(filtered)));
    rms_chart.fit();
    rms_chart
}

/// The amplitude spectra of i_u before and after the filter, and the raw current's strongest
/// peak in words.
fn spectrum_chart(recording: &PhaseRecording, filtered: &[f64]) -> Option<(LineChart, String)> {
    let u_filtered: Vec<f64> = filtered.iter().step_by(3).copied().collect();
    let raw = &recording.raw_spectrum;
    let after = amplitude_spectrum(&u_filtered, recording.sample_rate_hz, Window::Hann).ok()?;
    let shown = |s: &crate::signal::spectrum::AmplitudeSpectrum| -> Vec<(f64, f64)> {
        s.freq_hz
            .iter()
            .zip(&s.amplitude)
            .filter(|(f, _)| **f > 0.0 && **f <= 1000.0)
            .map(|(f, a)| (*f, *a))
            .collect()
    };
    let mut spectrum = LineChart::new(Axis::log("frequency (Hz)"), Axis::log("amplitude (A)"));
    spectrum
        .series
        .push(Series::new("raw", PALETTE[4], shown(raw)));
    spectrum
        .series
        .push(Series::new("filtered", PALETTE[0], shown(&after)));
    spectrum.fit();
    spectrum.y.scale = Scale::Log;
    let peak = find_peaks(&raw.freq_hz, &raw.amplitude, 1.0, 1)
        .first()
        .map(|p| {
            format!(
                "Strongest peak of the raw current: {:.2} Hz, {:.3} A.",
                p.interpolated_freq_hz, p.value
            )
        })
        .unwrap_or_default();
    Some((spectrum, peak))
}

/// The signal-chain page.
#[component]
pub fn SignalChainPage() -> impl IntoView {
    let form = form_from_query(&query_params(
        &window().location().hash().unwrap_or_default(),
    ));
    let texts = Memo::new(move |_| form.texts());
    // Keep the URL in step with the form, so a link reproduces the design.
    effect_after_mount(move || {
        replace_query(Page::SignalChain, &texts.with(|t| design_query(t)));
    });
    let design: Memo<Design> =
        Memo::new(move |_| texts.with(|t| parse_design(t)).map_err(|e| form_errors(&e)));
    view! {
        <PageShell id="signal" title="Signal chain: filter design">
            <p class="lede">
                "Motor current carries the cutting load, buried under the supply frequency, its harmonics "
                "and switching noise. Wang et al. clean it with a 10th-order Butterworth low-pass before "
                "taking the RMS; Kim et al. use analog 50 Hz and 260 Hz filters. Design one here: the "
                "filter is computed as second-order sections, the form that stays stable at high order "
                "and low cut-off."
            </p>
            <div class="layout-two">
                <DesignForm form=form texts=texts design=design />
                <div class="charts">
                    <Later>
                        <ResponseCharts design=design />
                    </Later>
                </div>
            </div>
            <BenchFiltered design=design />
        </PageShell>
    }
}

/// The papers' filters and the design's fields.
#[component]
fn DesignForm(
    form: TableForm<FilterSetting>,
    texts: Memo<Vec<(FilterSetting, String)>>,
    design: Memo<Design>,
) -> impl IntoView {
    let chosen = Memo::new(move |_| texts.with(|t| chosen_preset(t).map(|p| p.name)));
    let kind = form.text(FilterSetting::Kind);
    let is_band = Signal::derive(move || {
        kind.get()
            .parse::<FilterKind>()
            .is_ok_and(FilterKind::is_band)
    });
    let errors = Signal::derive(move || design.get().err().unwrap_or_default());
    let sections = move || design.with(|d| d.as_ref().map_or(0, |(_, sos)| sos.sections().len()));
    let field = move |setting: FilterSetting| {
        view! { <SettingField form=form setting=setting errors=errors id_prefix="filter-" /> }
    };
    view! {
        <form class="panel" aria-label="Filter design" on:submit=|ev| ev.prevent_default()>
            <fieldset>
                <legend>"Presets from the papers"</legend>
                <div class="preset-row">
                    {PAPER_FILTERS
                        .iter()
                        .map(|p| {
                            let name = p.name;
                            view! {
                                <button
                                    type="button"
                                    class="preset"
                                    aria-pressed=move || {
                                        if chosen.get() == Some(name) { "true" } else { "false" }
                                    }
                                    on:click=move |_| fill(form, p)
                                >
                                    {p.label}
                                </button>
                            }
                        })
                        .collect_view()}
                </div>
            </fieldset>
            <Later>
                {field(FilterSetting::Kind)}
                {field(FilterSetting::Order)}
                <SettingField
                    form=form
                    setting=FilterSetting::Cutoff
                    errors=errors
                    id_prefix="filter-"
                    label=Signal::derive(move || if is_band.get() { "Lower cut-off" } else { "Cut-off" }.to_string())
                />
                <SettingField
                    form=form
                    setting=FilterSetting::Upper
                    errors=errors
                    id_prefix="filter-"
                    hidden=Signal::derive(move || !is_band.get())
                />
                {field(FilterSetting::SampleRate)}
                <p class="hint" aria-live="polite">
                    {move || match sections() {
                        0 => "No valid design yet: the charts show the last valid one.".to_string(),
                        1 => "1 second-order section".to_string(),
                        n => format!("{n} second-order sections"),
                    }}
                </p>
            </Later>
        </form>
    }
}

/// The design's magnitude and phase response; the last valid design stays on screen while the
/// user types an invalid value.
#[component]
fn ResponseCharts(design: Memo<Design>) -> impl IntoView {
    let charts = Memo::new(move |previous: Option<&Option<(LineChart, LineChart)>>| {
        match design.with(|d| d.as_ref().ok().cloned()) {
            Some((spec, sos)) => Some(response_charts(&spec, &sos)),
            None => previous.cloned().flatten(),
        }
    });
    let magnitude = Signal::derive(move || {
        charts
            .with(|c| c.as_ref().map(|c| c.0.clone()))
            .unwrap_or_else(|| {
                LineChart::new(Axis::log("frequency (Hz)"), Axis::linear("magnitude (dB)"))
            })
    });
    let phase = Signal::derive(move || {
        charts
            .with(|c| c.as_ref().map(|c| c.1.clone()))
            .unwrap_or_else(|| {
                LineChart::new(Axis::log("frequency (Hz)"), Axis::linear("phase (°)"))
            })
    });
    view! {
        <ChartCanvas label="Magnitude response" chart=magnitude />
        <ChartCanvas label="Phase response" chart=phase />
    }
}

/// What the bench's currents show: the three-phase RMS of balanced sines is steady, but the feed
/// drive's 5th and 7th harmonics (the bench's own, [`Preset::bench_config`]) beat with the
/// fundamental at six times the supply frequency, a ripple of about ±(h₅ + h₇) on the raw RMS,
/// which a low-pass below the harmonics removes.
fn bench_lede() -> String {
    let (h5, h7) = Preset::WangBrakeBench
        .bench_config(1)
        .map_or((0.0, 0.0), |b| {
            (b.feed_drive.harmonic_5th, b.feed_drive.harmonic_7th)
        });
    // A no-break space: "3 %" never splits across lines.
    let pct = |h: f64| format!("{:.0}\u{a0}%", 100.0 * h);
    format!(
        "Four seconds of the feed motor's phase currents on paper 000's brake bench (a \
         magnetic-particle brake loads the servo; 600 mm/min), through the filter designed above. \
         The three-phase RMS of balanced sines is steady — the amplitude over √2 — but this drive's \
         currents carry {} of 5th and {} of 7th harmonic, which make the raw RMS ripple by about \
         ±{} at six times the supply frequency, on top of the sensors' noise; a low-pass below the \
         harmonics leaves a smooth RMS that follows the load. The spectrum shows the 4 Hz supply \
         frequency that paper 000 found rising with load.",
        pct(h5),
        pct(h7),
        pct(h5 + h7)
    )
}

/// Paper 000's bench current through the design: the recording is made once, in a computation
/// worker (the page's thread stays free while the bench's 13 s at 10 kHz compute); the filter
/// is re-applied on the page whenever the design changes. The filtering and each chart's series
/// are made in tasks of their own (the time charts, then the spectrum), each well under the 50 ms
/// a task should take, where together they took 50–80 ms; a newer design or recording drops the
/// stages of the last one still to come.
#[component]
fn BenchFiltered(design: Memo<Design>) -> impl IntoView {
    let bench = Runner::<Arc<PhaseRecording>>::new();
    bench.start_in_worker(
        JobRequest::Bench(BenchRequest::loaded_step(1)),
        |answer| match answer {
            Answer::BenchRecording(recording) => Some(recording),
            _ => None,
        },
    );
    let recording = bench.finished();
    let charts: [RwSignal<Option<LineChart>>; 3] = std::array::from_fn(|_| RwSignal::new(None));
    let peak_text = RwSignal::new(String::new());
    let latest = StoredValue::new(0u64);
    Effect::new(move |_| {
        // An invalid design keeps the last valid one's charts.
        let Some(sos) = design.with(|d| d.as_ref().ok().map(|(_, sos)| sos.clone())) else {
            return;
        };
        let Some(recording) = recording.get() else {
            return;
        };
        let generation = latest.get_value() + 1;
        latest.set_value(generation);
        let current = move || latest.try_get_value() == Some(generation);
        next_task(move || {
            if !current() {
                return;
            }
            let Some(filtered) = filtered_phases(&recording, &sos) else {
                return;
            };
            charts[0].set(Some(phase_chart(&recording, &filtered)));
            next_task(move || {
                if !current() {
                    return;
                }
                charts[1].set(Some(rms_chart(&recording, &filtered)));
                next_task(move || {
                    if !current() {
                        return;
                    }
                    if let Some((spectrum, peak)) = spectrum_chart(&recording, &filtered) {
                        charts[2].set(Some(spectrum));
                        peak_text.set(peak);
                    }
                });
            });
        });
    });
    let current_chart = move |i: usize| {
        Signal::derive(move || {
            charts[i].get().unwrap_or_else(|| {
                LineChart::new(Axis::linear("time (s)"), Axis::linear("current (A)"))
            })
        })
    };
    view! {
        <h2>"The filter on a motor current"</h2>
        <p class="lede">
            <WithPaperLinks text=bench_lede() />
        </p>
        <RunProgress runner=bench.clone() id="bench-progress" />
        <p class="hint" aria-live="polite">{move || peak_text.get()}</p>
        <div class="charts">
            <Later>
                <ChartCanvas label="Phase current before and after filtering" chart=current_chart(0) />
                <ChartCanvas label="Three-phase RMS current" chart=current_chart(1) height_px=200 />
                <ChartCanvas label="Amplitude spectrum of i_u" chart=current_chart(2) />
            </Later>
        </div>
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::recording::BenchRecording;
    use crate::work::Work;

    /// The strongest bin of `spectrum` above `above_hz`, Hz.
    fn strongest_hz(spectrum: &crate::signal::spectrum::AmplitudeSpectrum, above_hz: f64) -> f64 {
        spectrum
            .freq_hz
            .iter()
            .zip(&spectrum.amplitude)
            .filter(|(f, _)| **f > above_hz)
            .max_by(|a, b| a.1.total_cmp(b.1))
            .map_or(f64::NAN, |(f, _)| *f)
    }

    /// Half the range of `values` over their mean.
    fn relative_ripple(values: &[f64]) -> f64 {
        let (lo, hi) = values
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(*v), hi.max(*v))
            });
        let mean = values.iter().sum::<f64>() / values.len() as f64;
        (hi - lo) / 2.0 / mean
    }

    #[test]
    fn the_bench_text_says_why_the_raw_rms_ripples_and_the_filtered_does_not() {
        let recording = BenchRecording::loaded_step(1)
            .expect("the bench")
            .run_to_end()
            .expect("a recording");
        let wang = PAPER_FILTERS
            .iter()
            .find(|p| p.name == "wang-10th-5hz")
            .expect("paper 003's filter");
        let (_, sos) = parse_design(&wang.texts()).expect("a design");
        let filtered = filtered_phases(&recording, &sos).expect("filtered");
        let rms = |v: &[f64]| -> Vec<f64> {
            v.chunks_exact(3)
                .map(|f| three_phase_rms(f[0], f[1], f[2]))
                .collect()
        };
        let (raw, clean) = (rms(&recording.phases_a), rms(&filtered));
        let bench = Preset::WangBrakeBench.bench_config(1).expect("the bench");
        let harmonics = bench.feed_drive.harmonic_5th + bench.feed_drive.harmonic_7th;
        let mean = raw.iter().sum::<f64>() / raw.len() as f64;
        let centred: Vec<f64> = raw.iter().map(|r| r - mean).collect();
        let ripple =
            amplitude_spectrum(&centred, recording.sample_rate_hz, Window::Hann).expect("spectrum");
        // The raw RMS's strongest ripple is at six times the supply frequency ...
        let supply_hz = strongest_hz(&recording.raw_spectrum, 0.5);
        let ripple_hz = strongest_hz(&ripple, 0.5);
        assert!(
            (ripple_hz - 6.0 * supply_hz).abs() <= 0.5,
            "ripple at {ripple_hz} Hz, supply {supply_hz} Hz"
        );
        // ... and about ±(h5 + h7) of the mean, as the text says.
        let at = |f: f64| {
            ripple
                .freq_hz
                .iter()
                .zip(&ripple.amplitude)
                .find(|(g, _)| **g == f)
                .map_or(0.0, |(_, a)| *a)
        };
        let relative = at(ripple_hz) / mean;
        assert!(
            (0.7 * harmonics..1.3 * harmonics).contains(&relative),
            "ripple {relative} of the mean vs harmonics {harmonics}"
        );
        // The filter, below the harmonics, smooths it: in each half second between its start
        // (the first second) and the load's change near the end, the filtered RMS moves less
        // than a third of the raw.
        let n = raw.len();
        for k in 2..=5 {
            let part = k * n / 8..(k + 1) * n / 8;
            let (r, c) = (
                relative_ripple(&raw[part.clone()]),
                relative_ripple(&clean[part]),
            );
            assert!(c < r / 3.0, "half second {k}: filtered {c}, raw {r}");
        }
        let text = bench_lede();
        assert!(
            text.contains(&format!("±{:.0}\u{a0}%", 100.0 * harmonics)),
            "{text}"
        );
    }
}
