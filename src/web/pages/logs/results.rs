//! The results column: the active log and its mapping, every open log's current and force on the
//! linked time axis, the chain's output and spectrum with its statistics, the calibration's fit,
//! and the replays' overrides, force estimates and numbers.

use std::sync::Arc;

use leptos::prelude::*;

use super::calibration::FitForm;
use super::chain::Chain;
use super::charts::{
    channel_column, fit_chart, overlay_chart, points, replay_chart, spectrum_chart, CURRENTS,
};
use super::replay::Replay;
use super::reports::{ChainReport, ReplayReport};
use super::summary::LogSummary;
use super::LogsState;
use crate::charts::{Axis, LineChart, Series, PALETTE};
use crate::log::analysis::row_times;
use crate::log::mapping::Channel;
use crate::web::components::chart::ChartCanvas;

/// The whole results column.
#[component]
pub fn LogResults(shared: LogsState, chain: Chain, fit: FitForm, replay: Replay) -> impl IntoView {
    let mapping_error = Memo::new(move |_| {
        shared.active.with(|l| {
            l.as_ref()
                .and_then(|l| l.mapping.resolve(&l.log).err().map(|e| e.0))
        })
    });
    let fit_done = fit.done;
    let calibration_chart = Signal::derive(move || {
        fit_done.get().map(|f| fit_chart(&f)).unwrap_or_else(|| {
            LineChart::new(Axis::linear("force (N)"), Axis::linear("RMS current (A)"))
        })
    });
    view! {
        {move || shared.active.get().map(|l| view! { <LogSummary l=l shared=shared mapping_error=Signal::derive(move || mapping_error.get()) /> })}
        <LogCharts shared=shared chain=chain />
        <h2>"Calibration"</h2>
        {move || fit_done.get().map(|f| view! {
            <p role="status" class="finding">{format!("Fit: {}", f.quality())}</p>
            <ul class="hint">{f.notes.iter().map(|n| view! { <li>{n.clone()}</li> }).collect_view()}</ul>
        })}
        <ChartCanvas label="Calibration fit: current against force" chart=calibration_chart />
        <h2>"Replay"</h2>
        <ReplayCharts shared=shared replay=replay />
    }
}

/// A log's row times, compared by identity: a memo must not compare millions of values.
#[derive(Clone)]
struct RowTimes(Arc<Vec<f64>>);

impl PartialEq for RowTimes {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

/// Every open log's current and force, the chain on the chosen column and its spectrum, and the
/// chain's statistics.
#[component]
fn LogCharts(shared: LogsState, chain: Chain) -> impl IntoView {
    let LogsState {
        logs,
        active,
        time_view,
        ..
    } = shared;
    let Chain { column, done, .. } = chain;
    // Once per log (and period), not once per chain: a big log's times are millions of values,
    // and its speed's median a selection over them; a chain's arrival only draws.
    let times = Memo::new(move |_| {
        active.with(|l| {
            l.as_ref()
                .map(|l| RowTimes(Arc::new(row_times(&l.log, shared.period_s()))))
        })
    });
    let spindle_speed = Memo::new(move |_| {
        active.with(|l| {
            l.as_ref()
                .and_then(|l| channel_column(l, &[Channel::SpindleSpeed, Channel::SpindleCommand]))
                .map(|c| crate::signal::stats::median(c.values.iter().copied()))
        })
    });
    let overlay_current = Signal::derive(move || {
        logs.logs
            .with(|l| overlay_chart(l, &CURRENTS, "current (A)", time_view.get().as_ref()))
    });
    let overlay_force = Signal::derive(move || {
        logs.logs
            .with(|l| overlay_chart(l, &[Channel::Force], "force (N)", time_view.get().as_ref()))
    });
    let chain_chart = Memo::new(move |_| {
        let view = time_view.get();
        let mut chart = LineChart::new(Axis::linear("time (s)"), Axis::linear(column.get()));
        let (Some(l), Some(out)) = (active.get(), done.get()) else {
            return chart;
        };
        let Some(values) = l
            .log
            .columns
            .iter()
            .find(|c| c.name == column.get_untracked())
            .map(|c| &c.values)
        else {
            return chart;
        };
        if out.filtered.len() != values.len() {
            return chart;
        }
        let Some(RowTimes(times)) = times.get() else {
            return chart;
        };
        chart.series.push(Series::new(
            "as logged",
            PALETTE[4],
            points(&times, values, view.as_ref()),
        ));
        if out.lowpass_applied {
            chart.series.push(Series::new(
                "zero-phase low-pass",
                PALETTE[0],
                points(&times, &out.filtered, view.as_ref()),
            ));
        }
        chart.series.push(Series::new(
            format!("moving RMS ({} samples)", out.rms_window_samples),
            PALETTE[5],
            points(&times, &out.rms, view.as_ref()),
        ));
        chart.fit();
        chart
    });
    let spectrum = Signal::derive(move || {
        let Some(out) = done.get() else {
            return LineChart::new(Axis::log("frequency (Hz)"), Axis::log("PSD"));
        };
        spectrum_chart(&out, spindle_speed.get(), shared.teeth.get().ok())
    });
    view! {
        <div class="charts">
            <ChartCanvas label="Current of each open log" chart=overlay_current x_view=time_view />
            <ChartCanvas label="Measured force of each open log" chart=overlay_force x_view=time_view height_px=200 />
            <ChartCanvas label="Signal chain on the chosen column" chart=chain_chart x_view=time_view />
            <ChartCanvas label="Spectrum of the chosen column" chart=spectrum />
        </div>
        {move || done.get().map(|out| view! { <ChainReport out=out column=column.get_untracked() /> })}
    }
}

/// The replays' overrides and force estimates, and their numbers.
#[component]
fn ReplayCharts(shared: LogsState, replay: Replay) -> impl IntoView {
    let (done, time_view) = (replay.done, shared.time_view);
    let replay_override = Signal::derive(move || {
        let results = done.get().unwrap_or_default();
        replay_chart(
            &results,
            |r| r.override_pct,
            Some(("logged override", |r| r.applied_override_pct)),
            "override (%)",
            time_view.get().as_ref(),
        )
    });
    let replay_force = Signal::derive(move || {
        let results = done.get().unwrap_or_default();
        replay_chart(
            &results,
            |r| r.force_est_n,
            Some(("measured force", |r| r.force_n)),
            "force estimate (N, or A uncalibrated)",
            time_view.get().as_ref(),
        )
    });
    view! {
        <div class="charts">
            <ChartCanvas label="Replayed override" chart=replay_override x_view=time_view />
            <ChartCanvas label="Replayed force estimate" chart=replay_force x_view=time_view />
        </div>
        {move || done.get().map(|results| view! { <ReplayReport results=results /> })}
    }
}
