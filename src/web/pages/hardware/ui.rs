//! What the page shows of the station, as signals, and how the station's effects (store writes,
//! a list refresh, a redraw) are carried out.

use std::rc::Rc;
use std::sync::Arc;

use leptos::prelude::*;

use crate::charts::{Axis, LineChart};
use crate::closed_loop::lab::RunResult;
use crate::hardware::recording::RecordingMeta;
use crate::web::hardware::port::{now_s, PortEvent, Sink};
use crate::web::hardware::station::{Effects, Snapshot, Station};

/// The page redraws the live view at most this often.
const PUBLISH_INTERVAL_S: f64 = 0.25;

/// Everything the page shows, as signals.
#[derive(Clone, Copy)]
pub struct Ui {
    pub snapshot: RwSignal<Snapshot>,
    pub charts: [RwSignal<LineChart>; 4],
    pub result: RwSignal<Option<Arc<RunResult>>>,
    pub recordings: RwSignal<Vec<RecordingMeta>>,
    pub active_recording: RwSignal<Option<u64>>,
    /// The outcome of the last action (connect, arm, …), shown beside the buttons.
    pub message: RwSignal<Option<String>>,
    /// What went wrong with the recordings store.
    pub store_error: RwSignal<Option<String>>,
    last_publish_s: StoredValue<f64>,
}

pub type StationRef = StoredValue<Station, LocalStorage>;

impl Ui {
    pub fn new() -> Self {
        let empty = || RwSignal::new(LineChart::new(Axis::linear("time (s)"), Axis::linear("")));
        Self {
            snapshot: RwSignal::new(Snapshot::default()),
            charts: [empty(), empty(), empty(), empty()],
            result: RwSignal::new(None),
            recordings: RwSignal::new(Vec::new()),
            active_recording: RwSignal::new(None),
            message: RwSignal::new(None),
            store_error: RwSignal::new(None),
            last_publish_s: StoredValue::new(f64::NEG_INFINITY),
        }
    }

    /// Copies the station into the signals (at most every [`PUBLISH_INTERVAL_S`] unless `now`).
    pub fn publish(self, station: StationRef, now: bool) {
        let t = now_s();
        if !now && t - self.last_publish_s.get_value() < PUBLISH_INTERVAL_S {
            return;
        }
        self.last_publish_s.set_value(t);
        let Some((snapshot, charts, result, active)) = station.try_update_value(|s| {
            (
                s.snapshot(),
                s.live_charts(),
                s.take_result(),
                s.recording().cloned(),
            )
        }) else {
            return;
        };
        self.snapshot.set(snapshot);
        for (signal, chart) in self.charts.iter().zip(charts) {
            signal.set(chart);
        }
        if let Some(r) = result {
            self.result.set(Some(r));
        }
        self.active_recording.set(active.as_ref().map(|m| m.id));
        if let Some(meta) = active {
            self.recordings
                .update(|list| match list.iter_mut().find(|m| m.id == meta.id) {
                    Some(m) => *m = meta,
                    None => list.push(meta),
                });
        }
    }

    /// Carries out what the station asked for: store writes, a list refresh, a redraw.
    pub fn apply(self, station: StationRef, effects: Effects) {
        let store = station.try_with_value(|s| s.store.clone()).flatten();
        for (meta, chunk) in effects.writes {
            match &store {
                Some(store) => {
                    let store = store.clone();
                    let error = self.store_error;
                    leptos::task::spawn_local(async move {
                        if let Err(e) = store.put(&meta, chunk).await {
                            error.set(Some(format!(
                                "The recording “{}” could not be saved in this browser: {e}. \
                                 Export it before leaving the page.",
                                meta.name
                            )));
                        }
                    });
                }
                None => {
                    station.try_update_value(|s| s.keep_in_memory(meta, chunk));
                }
            }
        }
        if effects.recording_closed {
            self.refresh_recordings(station);
        }
        self.publish(station, effects.state_changed);
    }

    /// Reads the list of recordings from the store again.
    pub fn refresh_recordings(self, station: StationRef) {
        let Some(store) = station.try_with_value(|s| s.store.clone()).flatten() else {
            if let Some(list) = station.try_with_value(Station::memory_list) {
                self.recordings.set(list);
            }
            return;
        };
        let ui = self;
        leptos::task::spawn_local(async move {
            match store.list().await {
                Ok((list, unreadable)) => {
                    ui.recordings.set(list);
                    if unreadable > 0 {
                        ui.store_error.set(Some(format!(
                            "{unreadable} stored recording description(s) could not be read and \
                             are not listed."
                        )));
                    }
                    ui.publish(station, true);
                }
                Err(e) => ui
                    .store_error
                    .set(Some(format!("The recordings could not be listed: {e}"))),
            }
        });
    }
}

/// A port's events, into the station (ignored once connection `generation` is over).
pub fn sink(station: StationRef, ui: Ui, generation: u64) -> Sink {
    Rc::new(move |event: PortEvent| {
        if let PortEvent::Refused(why) = &event {
            if station.try_with_value(Station::generation) != Some(generation) {
                return;
            }
            ui.message
                .set(Some(format!("The virtual device cannot start: {why}.")));
        }
        let effects = station.try_update_value(|s| match &event {
            PortEvent::Bytes(bytes) => s.on_bytes(generation, bytes),
            PortEvent::Closed(why) => s.on_closed(generation, why),
            // It never connected: as if the operator had disconnected at once.
            PortEvent::Refused(_) => s.disconnect(),
        });
        if let Some(e) = effects {
            ui.apply(station, e);
        }
    })
}

/// A percentage for people, a dash where it is not known.
pub fn pct(v: f64) -> String {
    if v.is_finite() {
        format!("{v:.1} %")
    } else {
        "—".into()
    }
}
