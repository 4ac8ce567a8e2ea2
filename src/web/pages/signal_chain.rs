//! Signal chain: design the Butterworth low-pass that cleans the motor current, and see what it
//! does to magnitude and phase.
//!
//! The form lives in the URL query (`#/signal?preset=wang-10th-5hz`,
//! `#/signal?kind=bandpass&cutoff=40&upper=400`; defaults are left out), so a link reproduces the
//! design and the Learn page can open a paper's filter.

use std::sync::Arc;

use leptos::prelude::*;

use crate::charts::{Axis, LineChart, Scale, Series, PALETTE};
use crate::plant::recording::{BenchRecording, PhaseRecording};
use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use crate::signal::filter::SosFilterBank;
use crate::signal::rms::three_phase_rms;
use crate::signal::sos::Sos;
use crate::signal::spectrum::{amplitude_spectrum, find_peaks, Window};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::fields::{parse_count, parse_number, NumberField, SelectField};
use crate::web::components::later::{from_next_task, Later};
use crate::web::components::runner::{next_task, RunProgress, RunStatus, Runner};
use crate::web::components::work_job::Shared;
use crate::web::route::{query_params, replace_query, Page};

/// A filter the papers use, one click away.
struct FilterPreset {
    /// The name in the URL: `#/signal?preset=wang-10th-5hz`.
    name: &'static str,
    label: &'static str,
    kind: FilterKind,
    order: usize,
    cutoff_hz: f64,
    sample_rate_hz: f64,
}

static PRESETS: [FilterPreset; 3] = [
    FilterPreset {
        name: "wang-10th-5hz",
        label: "Wang et al.: 10th-order low-pass, 5 Hz",
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: 5.0,
        sample_rate_hz: 10_000.0,
    },
    FilterPreset {
        name: "kim-feed-50hz",
        label: "Kim et al.: feed motor, 50 Hz",
        kind: FilterKind::Lowpass,
        order: 2,
        cutoff_hz: 50.0,
        sample_rate_hz: 10_000.0,
    },
    FilterPreset {
        name: "kim-spindle-260hz",
        label: "Kim et al.: spindle motor, 260 Hz",
        kind: FilterKind::Lowpass,
        order: 2,
        cutoff_hz: 260.0,
        sample_rate_hz: 10_000.0,
    },
];

/// The form as typed, which is also what the URL query holds.
#[derive(Debug, Clone, PartialEq)]
struct FormText {
    /// A [`FilterKind::name`].
    kind: String,
    order: String,
    cutoff: String,
    upper: String,
    rate: String,
}

impl Default for FormText {
    fn default() -> Self {
        Self {
            kind: FilterKind::Lowpass.name().to_string(),
            order: "10".to_string(),
            cutoff: "50".to_string(),
            upper: "200".to_string(),
            rate: "10000".to_string(),
        }
    }
}

impl FormText {
    /// The fields with their query keys, in the order they are written.
    fn fields(&self) -> [(&'static str, &String); 5] {
        [
            ("kind", &self.kind),
            ("order", &self.order),
            ("cutoff", &self.cutoff),
            ("upper", &self.upper),
            ("rate", &self.rate),
        ]
    }

    /// This text with `preset`'s kind, order, cut-off and sample rate; the upper cut-off, which
    /// no preset uses, keeps its text.
    fn with_preset(self, preset: &FilterPreset) -> Self {
        Self {
            kind: preset.kind.name().to_string(),
            order: preset.order.to_string(),
            cutoff: preset.cutoff_hz.to_string(),
            rate: preset.sample_rate_hz.to_string(),
            ..self
        }
    }

    /// The preset whose values the form holds, exactly as that preset's button fills them in.
    fn preset(&self) -> Option<&'static FilterPreset> {
        PRESETS
            .iter()
            .find(|p| self.clone().with_preset(p) == *self)
    }

    /// The form a URL query describes: the defaults, then the named preset, then each field's
    /// own key. An unknown preset and a kind that is not a filter kind are ignored (the select
    /// could not show it); numbers are kept as typed, so their field explains what is wrong.
    fn from_query(query: &[(String, String)]) -> Self {
        let value = |key: &str| query.iter().find(|(k, _)| k == key).map(|(_, v)| v);
        let mut text = Self::default();
        if let Some(preset) = value("preset").and_then(|n| PRESETS.iter().find(|p| p.name == n)) {
            text = text.with_preset(preset);
        }
        if let Some(kind) = value("kind").and_then(|k| k.parse::<FilterKind>().ok()) {
            text.kind = kind.name().to_string();
        }
        for (key, field) in [
            ("order", &mut text.order),
            ("cutoff", &mut text.cutoff),
            ("upper", &mut text.upper),
            ("rate", &mut text.rate),
        ] {
            if let Some(typed) = value(key) {
                field.clone_from(typed);
            }
        }
        text
    }

    /// The URL query of this form: the preset's name when the form holds one, else every field
    /// whose text differs from its default. The upper cut-off, which no preset sets, is written
    /// whenever it differs from its default, also while it is hidden, so its text survives.
    fn query(&self) -> Vec<(String, String)> {
        let defaults = Self::default();
        let preset = self.preset();
        let mut query: Vec<(String, String)> = preset
            .map(|p| ("preset".to_string(), p.name.to_string()))
            .into_iter()
            .collect();
        query.extend(
            self.fields()
                .into_iter()
                .zip(defaults.fields())
                .filter(|((key, _), _)| preset.is_none() || *key == "upper")
                .filter(|((_, text), (_, default))| text.trim() != default.as_str())
                .map(|((key, text), _)| (key.to_string(), text.clone())),
        );
        query
    }
}

/// Number of frequencies at which the response is evaluated, log-spaced.
const RESPONSE_POINTS: usize = 600;

/// What the form's text parses into: the design, or one error per field.
#[derive(Clone, PartialEq)]
struct FilterForm {
    design: Option<(ButterworthSpec, Sos)>,
    order_error: Option<String>,
    cutoff_error: Option<String>,
    upper_error: Option<String>,
    rate_error: Option<String>,
}

fn parse_form(text: &FormText) -> FilterForm {
    let kind = text
        .kind
        .parse::<FilterKind>()
        .unwrap_or(FilterKind::Lowpass);
    let band = kind.is_band();
    let order = parse_count(&text.order);
    let cutoff = parse_number(&text.cutoff);
    let upper = if band {
        parse_number(&text.upper).map(Some)
    } else {
        Ok(None)
    };
    let rate = parse_number(&text.rate);
    let mut form = FilterForm {
        design: None,
        order_error: order.as_ref().err().cloned(),
        cutoff_error: cutoff.as_ref().err().cloned(),
        upper_error: upper.as_ref().err().cloned(),
        rate_error: rate.as_ref().err().cloned(),
    };
    let (Ok(order), Ok(cutoff), Ok(upper), Ok(rate)) = (order, cutoff, upper, rate) else {
        return form;
    };
    let spec = ButterworthSpec {
        kind,
        order,
        cutoff_hz: match upper {
            Some(upper) => Cutoff::Band(cutoff, upper),
            None => Cutoff::Single(cutoff),
        },
        sample_rate_hz: rate,
    };
    match butter(&spec) {
        Ok(sos) => form.design = Some((spec, sos)),
        Err(e) => {
            let message = e.to_string();
            // Put the design error beside the field it is about.
            if message.contains("order") {
                form.order_error = Some(message);
            } else if message.contains("sample rate") || message.contains("sample_rate") {
                form.rate_error = Some(message);
            } else if band && (message.contains("upper") || message.contains("second")) {
                form.upper_error = Some(message);
            } else {
                form.cutoff_error = Some(message);
            }
        }
    }
    form
}

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

/// Phase current before and after the filter, three-phase RMS of both, and both spectra.
fn current_charts(
    recording: &PhaseRecording,
    sos: &Sos,
) -> Option<(LineChart, LineChart, LineChart, String)> {
    let mut bank = SosFilterBank::new(sos, 3).ok()?;
    let first = recording.phases_a.get(..3)?;
    // Start the filter as if the input had always been the first sample: no start-up transient.
    bank.set_steady_state(first);
    let mut filtered = recording.phases_a.clone();
    bank.process_slice(&mut filtered);
    let phase_u = |v: &[f64]| -> Vec<(f64, f64)> {
        recording
            .time_s
            .iter()
            .zip(v.chunks_exact(3))
            .map(|(t, f)| (*t, f[0]))
            .collect()
    };
    let rms = |v: &[f64]| -> Vec<(f64, f64)> {
        recording
            .time_s
            .iter()
            .zip(v.chunks_exact(3))
            .map(|(t, f)| (*t, three_phase_rms(f[0], f[1], f[2])))
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
        .push(Series::new("filtered", PALETTE[0], phase_u(&filtered)));
    phase.fit();
    let mut rms_chart = LineChart::new(
        Axis::linear("time (s)"),
        Axis::linear("three-phase RMS (A)"),
    );
    rms_chart
        .series
        .push(Series::new("raw", PALETTE[4], rms(&recording.phases_a)));
    rms_chart
        .series
        .push(Series::new("filtered", PALETTE[0], rms(&filtered)));
    rms_chart.fit();

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
    Some((phase, rms_chart, spectrum, peak))
}

/// The signal-chain page.
#[component]
pub fn SignalChainPage() -> impl IntoView {
    let initial = FormText::from_query(&query_params(
        &window().location().hash().unwrap_or_default(),
    ));
    let kind = RwSignal::new(initial.kind);
    let order = RwSignal::new(initial.order);
    let cutoff = RwSignal::new(initial.cutoff);
    let upper = RwSignal::new(initial.upper);
    let rate = RwSignal::new(initial.rate);

    let text = Memo::new(move |_| FormText {
        kind: kind.get(),
        order: order.get(),
        cutoff: cutoff.get(),
        upper: upper.get(),
        rate: rate.get(),
    });
    // Keep the URL in step with the form, so a link reproduces the design.
    // Written from the task after the page's: the page's own work, not its mount's.
    let mounted = from_next_task();
    Effect::new(move |_| {
        if mounted.get() {
            replace_query(Page::SignalChain, &text.with(FormText::query));
        }
    });
    let chosen_preset = Memo::new(move |_| text.with(|t| t.preset().map(|p| p.name)));

    let form = Memo::new(move |_| text.with(parse_form));
    let is_band = Signal::derive(move || {
        kind.get()
            .parse::<FilterKind>()
            .is_ok_and(FilterKind::is_band)
    });
    // The last valid design stays on screen while the user types an invalid value.
    let charts = Memo::new(move |previous: Option<&Option<(LineChart, LineChart)>>| {
        match form.with(|f| f.design.clone()) {
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
    // The bench recording is made once, in pieces, starting in the task after the page's (its
    // machine and first compiles are not the mount's work); the filter is re-applied whenever
    // the design changes.
    let bench = Runner::<Arc<PhaseRecording>>::new();
    let bench_to_start = bench.clone();
    next_task(move || match BenchRecording::loaded_step(1) {
        Ok(recording) => bench_to_start.start(Shared(recording)),
        Err(e) => {
            let _ = bench_to_start
                .status
                .try_set(RunStatus::Failed(e.to_string()));
        }
    });
    let recording = bench.finished();
    let currents = Memo::new(
        move |previous: Option<&Option<(LineChart, LineChart, LineChart, String)>>| {
            let design = form.with(|f| f.design.clone());
            match design {
                Some((_, sos)) => {
                    recording.with(|r| r.as_ref().and_then(|r| current_charts(r, &sos)))
                }
                None => previous.cloned().flatten(),
            }
        },
    );
    let current_chart = move |i: usize| {
        Signal::derive(move || {
            currents
                .with(|c| c.as_ref().map(|c| [&c.0, &c.1, &c.2][i].clone()))
                .unwrap_or_else(|| {
                    LineChart::new(Axis::linear("time (s)"), Axis::linear("current (A)"))
                })
        })
    };
    let peak_text = move || currents.with(|c| c.as_ref().map(|c| c.3.clone()).unwrap_or_default());
    let sections = move || {
        form.with(|f| {
            f.design
                .as_ref()
                .map(|(_, sos)| sos.sections().len())
                .unwrap_or_default()
        })
    };

    view! {
        <section class="page" aria-labelledby="signal-title">
            <h1 id="signal-title">"Signal chain: filter design"</h1>
            <p class="lede">
                "Motor current carries the cutting load, buried under the supply frequency, its harmonics "
                "and switching noise. Wang et al. clean it with a 10th-order Butterworth low-pass before "
                "taking the RMS; Kim et al. use analog 50 Hz and 260 Hz filters. Design one here: the "
                "filter is computed as second-order sections, the form that stays stable at high order "
                "and low cut-off."
            </p>
            <div class="layout-two">
                <form class="panel" aria-label="Filter design" on:submit=|ev| ev.prevent_default()>
                    <fieldset>
                        <legend>"Presets from the papers"</legend>
                        <div class="preset-row">
                            {PRESETS
                                .iter()
                                .map(|p| {
                                    let name = p.name;
                                    view! {
                                        <button
                                            type="button"
                                            class="preset"
                                            aria-pressed=move || {
                                                if chosen_preset.get() == Some(name) { "true" } else { "false" }
                                            }
                                            on:click=move |_| {
                                                let filled = text.get_untracked().with_preset(p);
                                                kind.set(filled.kind);
                                                order.set(filled.order);
                                                cutoff.set(filled.cutoff);
                                                rate.set(filled.rate);
                                            }
                                        >
                                            {p.label}
                                        </button>
                                    }
                                })
                                .collect_view()}
                        </div>
                    </fieldset>
                    // The fields and the design they give a task after the presets: with the
                    // page's other work they took its first task past 50 ms.
                    <Later>
                        <SelectField
                            id="filter-kind"
                            label="Filter type"
                            options=FilterKind::ALL.iter().map(|k| (k.name(), k.label())).collect()
                            value=kind
                        />
                        <NumberField
                            id="filter-order"
                            label="Order"
                            value=order
                            step="1"
                            error=Signal::derive(move || form.with(|f| f.order_error.clone()))
                        />
                        <NumberField
                            id="filter-cutoff"
                            label=Signal::derive(move || if is_band.get() { "Lower cut-off" } else { "Cut-off" }.to_string())
                            unit="Hz"
                            value=cutoff
                            error=Signal::derive(move || form.with(|f| f.cutoff_error.clone()))
                        />
                        <NumberField
                            id="filter-upper"
                            label="Upper cut-off"
                            unit="Hz"
                            value=upper
                            hidden=Signal::derive(move || !is_band.get())
                            error=Signal::derive(move || form.with(|f| f.upper_error.clone()))
                        />
                        <NumberField
                            id="filter-rate"
                            label="Sample rate"
                            unit="Hz"
                            value=rate
                            error=Signal::derive(move || form.with(|f| f.rate_error.clone()))
                        />
                        <p class="hint" aria-live="polite">
                            {move || match sections() {
                                0 => "No valid design yet: the charts show the last valid one.".to_string(),
                                1 => "1 second-order section".to_string(),
                                n => format!("{n} second-order sections"),
                            }}
                        </p>
                    </Later>
                </form>
                // The charts in the task after the form's: together they took the page's first
                // task past 50 ms.
                <div class="charts">
                    <Later>
                        <ChartCanvas label="Magnitude response" chart=magnitude />
                        <ChartCanvas label="Phase response" chart=phase />
                    </Later>
                </div>
            </div>
            <h2>"The filter on a motor current"</h2>
            <p class="lede">
                "Four seconds of the feed motor's phase currents on paper 000's brake bench (a "
                "magnetic-particle brake loads the servo; 600 mm/min), through the filter designed "
                "above. The three-phase RMS of a balanced set is steady — the amplitude over √2 — "
                "and the spectrum shows the 4 Hz supply frequency that paper 000 found rising with load."
            </p>
            <RunProgress runner=bench.clone() id="bench-progress" />
            <p class="hint" aria-live="polite">{peak_text}</p>
            <div class="charts">
                <Later>
                    <ChartCanvas label="Phase current before and after filtering" chart=current_chart(0) />
                    <ChartCanvas label="Three-phase RMS current" chart=current_chart(1) height_px=200 />
                    <ChartCanvas label="Amplitude spectrum of i_u" chart=current_chart(2) />
                </Later>
            </div>
        </section>
    }
}
