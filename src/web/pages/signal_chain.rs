//! Signal chain: design the Butterworth low-pass that cleans the motor current, and see what it
//! does to magnitude and phase.

use leptos::prelude::*;

use crate::charts::{Axis, LineChart, Scale, Series, PALETTE};
use crate::machine::{Machine, OverrideCommand};
use crate::plant::Preset;
use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use crate::signal::filter::SosFilterBank;
use crate::signal::rms::three_phase_rms;
use crate::signal::sos::Sos;
use crate::signal::spectrum::{amplitude_spectrum, find_peaks, Window};
use crate::web::components::chart::ChartCanvas;
use crate::web::components::fields::{parse_count, parse_number, NumberField, SelectField};

/// A filter the papers use, one click away.
struct FilterPreset {
    label: &'static str,
    kind: FilterKind,
    order: usize,
    cutoff_hz: f64,
    sample_rate_hz: f64,
}

const PRESETS: [FilterPreset; 3] = [
    FilterPreset {
        label: "Wang et al.: 10th-order low-pass, 5 Hz",
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: 5.0,
        sample_rate_hz: 10_000.0,
    },
    FilterPreset {
        label: "Kim et al.: feed motor, 50 Hz",
        kind: FilterKind::Lowpass,
        order: 2,
        cutoff_hz: 50.0,
        sample_rate_hz: 10_000.0,
    },
    FilterPreset {
        label: "Kim et al.: spindle motor, 260 Hz",
        kind: FilterKind::Lowpass,
        order: 2,
        cutoff_hz: 260.0,
        sample_rate_hz: 10_000.0,
    },
];

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

fn parse_form(kind: &str, order: &str, cutoff: &str, upper: &str, rate: &str) -> FilterForm {
    let kind = kind.parse::<FilterKind>().unwrap_or(FilterKind::Lowpass);
    let band = matches!(kind, FilterKind::Bandpass | FilterKind::Bandstop);
    let order = parse_count(order);
    let cutoff = parse_number(cutoff);
    let upper = if band {
        parse_number(upper).map(Some)
    } else {
        Ok(None)
    };
    let rate = parse_number(rate);
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

/// A stretch of the brake bench's feed-motor phase currents (paper 000's experiment).
struct PhaseRecording {
    sample_rate_hz: f64,
    time_s: Vec<f64>,
    /// Interleaved i_u, i_v, i_w.
    phases_a: Vec<f64>,
}

/// The bench is recorded from this time (a loaded step, after the drive has settled) …
const RECORD_FROM_S: f64 = 9.0;
/// … for this long: long enough to resolve paper 000's 4 Hz peak to 0.25 Hz.
const RECORD_FOR_S: f64 = 4.0;

fn record_bench() -> Option<PhaseRecording> {
    let mut machine = Preset::WangBrakeBench.machine(1).ok()?;
    let rate = machine.sample_rate_hz();
    let skip = (RECORD_FROM_S * rate) as usize;
    let keep = (RECORD_FOR_S * rate) as usize;
    let mut time_s = Vec::with_capacity(keep);
    let mut phases_a = Vec::with_capacity(3 * keep);
    for i in 0..skip + keep {
        let step = machine.step(OverrideCommand::default());
        if i >= skip {
            time_s.push(step.sensors.time_s);
            phases_a.extend_from_slice(&step.sensors.feed_phase_currents_a);
        }
    }
    Some(PhaseRecording {
        sample_rate_hz: rate,
        time_s,
        phases_a,
    })
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

    let u_raw: Vec<f64> = recording.phases_a.iter().step_by(3).copied().collect();
    let u_filtered: Vec<f64> = filtered.iter().step_by(3).copied().collect();
    let raw = amplitude_spectrum(&u_raw, recording.sample_rate_hz, Window::Hann).ok()?;
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
        .push(Series::new("raw", PALETTE[4], shown(&raw)));
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
    let kind = RwSignal::new(FilterKind::Lowpass.name().to_string());
    let order = RwSignal::new("10".to_string());
    let cutoff = RwSignal::new("50".to_string());
    let upper = RwSignal::new("200".to_string());
    let rate = RwSignal::new("10000".to_string());

    let form = Memo::new(move |_| {
        parse_form(
            &kind.get(),
            &order.get(),
            &cutoff.get(),
            &upper.get(),
            &rate.get(),
        )
    });
    let is_band = Signal::derive(move || {
        matches!(
            kind.get().parse::<FilterKind>(),
            Ok(FilterKind::Bandpass | FilterKind::Bandstop)
        )
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
    // The bench recording is made once; the filter is re-applied whenever the design changes.
    let recording = StoredValue::new_local(record_bench());
    let currents = Memo::new(
        move |previous: Option<&Option<(LineChart, LineChart, LineChart, String)>>| {
            let design = form.with(|f| f.design.clone());
            match design {
                Some((_, sos)) => {
                    recording.with_value(|r| r.as_ref().and_then(|r| current_charts(r, &sos)))
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
                                    let (k, o, c, r) = (p.kind, p.order, p.cutoff_hz, p.sample_rate_hz);
                                    view! {
                                        <button
                                            type="button"
                                            class="preset"
                                            on:click=move |_| {
                                                kind.set(k.name().to_string());
                                                order.set(o.to_string());
                                                cutoff.set(c.to_string());
                                                rate.set(r.to_string());
                                            }
                                        >
                                            {p.label}
                                        </button>
                                    }
                                })
                                .collect_view()}
                        </div>
                    </fieldset>
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
                </form>
                <div class="charts">
                    <ChartCanvas label="Magnitude response" chart=magnitude />
                    <ChartCanvas label="Phase response" chart=phase />
                </div>
            </div>
            <h2>"The filter on a motor current"</h2>
            <p class="lede">
                "Four seconds of the feed motor's phase currents on paper 000's brake bench (a "
                "magnetic-particle brake loads the servo; 600 mm/min), through the filter designed "
                "above. The three-phase RMS of a balanced set is steady — the amplitude over √2 — "
                "and the spectrum shows the 4 Hz supply frequency that paper 000 found rising with load."
            </p>
            <p class="hint" aria-live="polite">{peak_text}</p>
            <div class="charts">
                <ChartCanvas label="Phase current before and after filtering" chart=current_chart(0) />
                <ChartCanvas label="Three-phase RMS current" chart=current_chart(1) height_px=200 />
                <ChartCanvas label="Amplitude spectrum of i_u" chart=current_chart(2) />
            </div>
        </section>
    }
}
