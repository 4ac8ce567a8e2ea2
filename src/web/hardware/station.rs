//! The Hardware page's state outside the reactive system: the core session, the port, the
//! recording under way and the live window of rows. Port events and the page's timer call in
//! here; the page reads a [`Snapshot`] of it a few times a second.

use std::collections::VecDeque;
use std::sync::Arc;

use crate::charts::{Axis, LineChart, Series, PALETTE};
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::RunResult;
use crate::hardware::recording::{LiveRow, Recorder, RecordingMeta};
use crate::hardware::session::{
    describe_ack, ArmLimits, HardwareSession, LinkState, SessionOptions, Stage, TaughtCalibration,
};
use crate::protocol::host::{DeviceSummary, LinkStats};

use super::port::{now_s, Port};
use super::store::Store;

/// Device seconds the live charts show.
pub const LIVE_WINDOW_S: f64 = 30.0;
/// The recording's text goes to the store at least this often: a reload or crash loses less.
pub const FLUSH_INTERVAL_S: f64 = 0.5;
/// Events the page lists (the latest).
const EVENTS_SHOWN: usize = 200;

/// What the page shows, copied out of the station.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Snapshot {
    /// Link state; `None` before the first connection.
    pub state: Option<LinkState>,
    /// Why it last changed.
    pub reason: String,
    /// What the host does.
    pub stage: Option<Stage>,
    /// The device, after the handshake.
    pub device: Option<DeviceSummary>,
    /// The device's channels and features in words.
    pub device_details: Vec<(String, String)>,
    /// What crossed the link.
    pub stats: LinkStats,
    /// The latest acknowledgement.
    pub last_ack: Option<String>,
    /// The override the host commands now, and the one applied (latest sample).
    pub commanded_pct: f64,
    /// The override the machine applies.
    pub applied_pct: f64,
    /// Whether the device is in its watchdog fallback.
    pub fallback: bool,
    /// The calibration in use, described.
    pub calibration: Option<String>,
    /// What the calibration in use warns of ([`TaughtCalibration::warnings`]).
    pub calibration_warnings: Vec<String>,
    /// The override Disarm, Escape and alarms command.
    pub safe_override_pct: f64,
    /// The latest events, oldest first.
    pub events: Vec<(f64, String)>,
    /// The recording under way, described.
    pub recording: Option<String>,
    /// Which port: "virtual device", "serial port", or nothing.
    pub port: Option<&'static str>,
    /// The feed hold the device latched, as the machine sees it (until the operator's reset).
    pub hold: Option<String>,
    /// What the machine gets if the link is lost now, while the host holds the device.
    pub if_link_lost: Option<String>,
}

/// The station.
#[derive(Default)]
pub struct Station {
    session: Option<HardwareSession>,
    port: Option<Port>,
    /// Bumped at every connection, so a closed port's late events are ignored.
    generation: u64,
    options: SessionOptions,
    recorder: Option<Recorder>,
    /// The latest recording closed, so a run's summary that comes after its last row lands.
    last_closed: Option<RecordingMeta>,
    last_flush_s: f64,
    last_id: u64,
    live: VecDeque<LiveRow>,
    /// The calibration outlives a connection: the machine is the same after a reconnect.
    calibration: Option<TaughtCalibration>,
    /// The IndexedDB store, once open.
    pub store: Option<Store>,
    /// Recordings kept in memory when there is no store (IndexedDB unavailable): their chunks,
    /// so they can still be exported before the page is left.
    memory: std::collections::BTreeMap<u64, (RecordingMeta, Vec<String>)>,
    /// The latest run's result, when it changes.
    result: Option<Arc<RunResult>>,
    result_changed: bool,
    /// The state at the last snapshot, to publish at once when it changes.
    published_state: Option<LinkState>,
}

/// What the station asks the page to do after a call.
#[derive(Debug, Default)]
pub struct Effects {
    /// Store writes: a recording's description and, maybe, a chunk of its text.
    pub writes: Vec<(RecordingMeta, Option<(u32, String)>)>,
    /// The link state changed: show it now.
    pub state_changed: bool,
    /// A recording was closed: refresh the list.
    pub recording_closed: bool,
}

impl Station {
    /// The generation of the current connection.
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// Whether a port is open.
    pub fn connected(&self) -> bool {
        self.port.is_some()
    }

    /// Uses `options` now and for later connections.
    pub fn set_options(&mut self, options: SessionOptions) -> Result<(), String> {
        if let Some(s) = &mut self.session {
            s.set_options(options)?;
        }
        self.options = options;
        Ok(())
    }

    /// A new connection on `port`: a fresh session says Hello.
    pub fn connect(&mut self, port: Port, generation: u64) {
        self.generation = generation;
        let mut session = HardwareSession::new(self.options, now_s());
        if let Some(c) = &self.calibration {
            session.set_calibration(c.clone());
        }
        port.write(&session.take_output());
        self.session = Some(session);
        self.port = Some(port);
    }

    /// The next connection's generation (the current one's callbacks go quiet).
    pub fn next_generation(&mut self) -> u64 {
        self.generation += 1;
        self.generation
    }

    fn send_output(&mut self) {
        if let (Some(session), Some(port)) = (&mut self.session, &self.port) {
            let out = session.take_output();
            if !out.is_empty() {
                port.write(&out);
            }
        }
    }

    /// Bytes arrived on connection `generation`.
    pub fn on_bytes(&mut self, generation: u64, bytes: &[u8]) -> Effects {
        let mut effects = Effects::default();
        if generation != self.generation {
            return effects;
        }
        let now = now_s();
        if let Some(s) = &mut self.session {
            s.receive(bytes, now);
        }
        self.after_session(now, &mut effects);
        effects
    }

    /// Connection `generation`'s port closed under it.
    pub fn on_closed(&mut self, generation: u64, why: &str) -> Effects {
        let mut effects = Effects::default();
        if generation != self.generation {
            return effects;
        }
        let now = now_s();
        if let Some(s) = &mut self.session {
            s.link_lost(why, now);
        }
        if let Some(mut port) = self.port.take() {
            port.close();
        }
        self.after_session(now, &mut effects);
        self.close_recording(&format!("the link was lost: {why}"), &mut effects);
        effects
    }

    /// Time passes: the session's watchdogs and heartbeats, and the store's flush.
    pub fn tick(&mut self) -> Effects {
        let mut effects = Effects::default();
        let now = now_s();
        if let Some(s) = &mut self.session {
            s.tick(now);
        }
        self.after_session(now, &mut effects);
        if self.session.as_ref().map(HardwareSession::state) == Some(LinkState::Closed) {
            // A failed handshake: the port is of no more use.
            if let Some(mut port) = self.port.take() {
                port.close();
            }
        }
        if now - self.last_flush_s >= FLUSH_INTERVAL_S {
            self.flush(now, &mut effects);
        }
        effects
    }

    /// Rows, output, results and state after the session moved.
    fn after_session(&mut self, now: f64, effects: &mut Effects) {
        self.send_output();
        let Some(session) = &mut self.session else {
            return;
        };
        let rows = session.take_rows();
        let finished = session.take_finished();
        let state = session.state();
        if let Some(c) = session.calibration() {
            if self.calibration.as_ref() != Some(c) {
                self.calibration = Some(c.clone());
            }
        }
        let result = finished
            .then(|| session.result().cloned())
            .flatten()
            .map(Arc::new);
        let device = session.device();
        for row in rows {
            if self.recorder.is_none() {
                self.start_recording(&row, device.as_ref());
                // Listed at once, before its first chunk.
                if let Some(r) = &self.recorder {
                    effects.writes.push((r.meta().clone(), None));
                }
            }
            if let Some(r) = &mut self.recorder {
                r.push(&row);
            }
            let end = row.program_end;
            self.live.push_back(row);
            if end {
                self.close_recording("the part ended", effects);
            }
        }
        let latest_s = self.live.back().map_or(0.0, |r| r.time_s);
        while self
            .live
            .front()
            .is_some_and(|r| r.time_s < latest_s - LIVE_WINDOW_S)
        {
            self.live.pop_front();
        }
        if let Some(r) = result {
            let summary = summary_of(&r);
            if let Some(rec) = &mut self.recorder {
                rec.set_summary(&summary);
            } else if let Some(meta) = &mut self.last_closed {
                meta.summary = summary;
                effects.writes.push((meta.clone(), None));
                effects.recording_closed = true;
            }
            self.result = Some(r);
            self.result_changed = true;
        }
        if self.published_state != Some(state) {
            effects.state_changed = true;
        }
        if self
            .recorder
            .as_ref()
            .is_some_and(|r| r.pending_bytes() > 1 << 20)
        {
            self.flush(now, effects);
        }
    }

    fn start_recording(&mut self, row: &LiveRow, device: Option<&DeviceSummary>) {
        let now_ms = js_sys::Date::now();
        let id = (now_ms as u64).max(self.last_id + 1);
        self.last_id = id;
        let (device_name, rate, truth) = device.map_or(("a device".to_string(), 0.0, false), |d| {
            (
                format!("{} ({})", d.device_id, d.program),
                d.sample_rate_hz,
                d.sim_truth,
            )
        });
        let program = device.map_or("?", |d| d.program.as_str());
        self.recorder = Some(Recorder::new(RecordingMeta {
            id,
            name: format!("{} · {program} · {}", local_time(now_ms), row.phase),
            started_ms: now_ms,
            device: device_name,
            sample_rate_hz: rate,
            sim_truth: truth,
            rows: 0,
            chunks: 0,
            duration_s: 0.0,
            finished: false,
            end: String::new(),
            summary: String::new(),
        }));
    }

    /// Writes what the recording holds to the store.
    fn flush(&mut self, now: f64, effects: &mut Effects) {
        self.last_flush_s = now;
        if let Some(r) = &mut self.recorder {
            if let Some(chunk) = r.take_chunk() {
                effects.writes.push((r.meta().clone(), Some(chunk)));
            }
        }
    }

    fn close_recording(&mut self, end: &str, effects: &mut Effects) {
        if let Some(mut r) = self.recorder.take() {
            r.finish(end, None);
            let chunk = r.take_chunk();
            let meta = r.meta().clone();
            effects.writes.push((meta.clone(), chunk));
            effects.recording_closed = true;
            self.last_closed = Some(meta);
        }
    }

    /// Uses `calibration` from now on, in this connection and the next.
    pub fn set_calibration(&mut self, calibration: TaughtCalibration) {
        if let Some(s) = &mut self.session {
            s.set_calibration(calibration.clone());
        }
        self.calibration = Some(calibration);
    }

    /// The calibration at hand, as a file.
    pub fn calibration_file(&self) -> Option<CalibrationFile> {
        self.calibration
            .as_ref()
            .map(|c| CalibrationFile::new(c.calibration.clone(), c.source.clone()))
    }

    /// The calibration at hand, described (also before any connection).
    pub fn calibration_text(&self) -> Option<String> {
        self.calibration.as_ref().map(|c| {
            format!(
                "{}: {} periods fitted over {:.1} s, {} feedback",
                c.source,
                c.calibration.periods,
                c.calibration.duration_s,
                c.calibration.estimator.feedback().name()
            )
        })
    }

    /// Keeps a recording's write in memory (no store).
    pub fn keep_in_memory(&mut self, meta: RecordingMeta, chunk: Option<(u32, String)>) {
        let entry = self
            .memory
            .entry(meta.id)
            .or_insert_with(|| (meta.clone(), Vec::new()));
        entry.0 = meta;
        if let Some((_, text)) = chunk {
            entry.1.push(text);
        }
    }

    /// The recordings kept in memory.
    pub fn memory_list(&self) -> Vec<RecordingMeta> {
        self.memory.values().map(|(m, _)| m.clone()).collect()
    }

    /// The chunks of a recording kept in memory.
    pub fn memory_chunks(&self, id: u64) -> Option<Vec<String>> {
        self.memory.get(&id).map(|(_, chunks)| chunks.clone())
    }

    /// Forgets a recording kept in memory.
    pub fn memory_delete(&mut self, id: u64) {
        self.memory.remove(&id);
    }

    /// The recording under way, if any.
    pub fn recording(&self) -> Option<&RecordingMeta> {
        self.recorder.as_ref().map(Recorder::meta)
    }

    /// Flushes the recording under way (before an export of it).
    pub fn flush_now(&mut self) -> Effects {
        let mut effects = Effects::default();
        self.flush(now_s(), &mut effects);
        effects
    }

    /// The operator disconnects: a held device is handed back, the port closes.
    pub fn disconnect(&mut self) -> Effects {
        let mut effects = Effects::default();
        let now = now_s();
        if let Some(s) = &mut self.session {
            s.disconnect(now);
        }
        self.send_output();
        self.after_session(now, &mut effects);
        self.close_recording("disconnected by the operator", &mut effects);
        if let Some(mut port) = self.port.take() {
            port.close();
        }
        self.generation += 1;
        effects.state_changed = true;
        effects
    }

    /// Pulls the virtual cable (the virtual device only).
    pub fn unplug_virtual(&self) -> bool {
        match &self.port {
            Some(Port::Virtual(v)) => {
                v.unplug();
                true
            }
            _ => false,
        }
    }

    /// The limits of a teach cut or run, for the confirmation.
    pub fn limits(&self, teach: bool, spec: &RunSpec) -> Result<ArmLimits, String> {
        let s = self
            .session
            .as_ref()
            .ok_or_else(|| "no device: connect first".to_string())?;
        if teach {
            s.teach_limits(spec)
        } else {
            s.arm_limits(spec)
        }
    }

    /// Starts a teach cut or arms the closed loop (the operator confirmed).
    pub fn start(&mut self, teach: bool, spec: &RunSpec) -> Result<Effects, String> {
        let now = now_s();
        let s = self
            .session
            .as_mut()
            .ok_or_else(|| "no device: connect first".to_string())?;
        if teach {
            s.start_teach_cut(spec, now)?;
        } else {
            s.arm(spec, now)?;
        }
        let mut effects = Effects::default();
        self.after_session(now, &mut effects);
        effects.state_changed = true;
        Ok(effects)
    }

    /// Disarm or Escape: the safe override at once.
    pub fn disarm(&mut self, why: &str) -> Effects {
        let now = now_s();
        if let Some(s) = &mut self.session {
            s.disarm(why, now);
        }
        let mut effects = Effects::default();
        self.after_session(now, &mut effects);
        effects.state_changed = true;
        effects
    }

    /// The operator acknowledges the alarm.
    pub fn acknowledge(&mut self) -> Result<Effects, String> {
        let now = now_s();
        if let Some(s) = &mut self.session {
            s.acknowledge_alarm(now)?;
        }
        let mut effects = Effects::default();
        self.after_session(now, &mut effects);
        effects.state_changed = true;
        Ok(effects)
    }

    /// The operator resets the feed hold the device latched (its cause cleared).
    pub fn reset_hold(&mut self) -> Result<Effects, String> {
        let now = now_s();
        let s = self
            .session
            .as_mut()
            .ok_or_else(|| "no device: connect first".to_string())?;
        s.reset_hold()?;
        let mut effects = Effects::default();
        self.after_session(now, &mut effects);
        effects.state_changed = true;
        Ok(effects)
    }

    /// Whether the port is a real serial port (not the virtual device).
    pub fn on_serial_port(&self) -> bool {
        self.port.as_ref().is_some_and(|p| !p.is_virtual())
    }

    /// Whether the host is running a teach cut or the loop (Escape has something to stop).
    pub fn running(&self) -> bool {
        self.session
            .as_ref()
            .is_some_and(|s| matches!(s.stage(), Stage::TeachCut | Stage::ClosedLoop))
    }

    /// The latest run's result, if it changed since the last call.
    pub fn take_result(&mut self) -> Option<Arc<RunResult>> {
        if std::mem::take(&mut self.result_changed) {
            self.result.clone()
        } else {
            None
        }
    }

    /// What the page shows now.
    pub fn snapshot(&mut self) -> Snapshot {
        let port = self.port.as_ref().map(|p| {
            if p.is_virtual() {
                "the virtual device"
            } else {
                "a serial port"
            }
        });
        let recording = self.recorder.as_ref().map(|r| {
            let m = r.meta();
            format!(
                "recording “{}”: {} rows, {:.1} s",
                m.name, m.rows, m.duration_s
            )
        });
        let calibration = self.calibration_text();
        let calibration_warnings = self
            .calibration
            .as_ref()
            .map(TaughtCalibration::warnings)
            .unwrap_or_default();
        let Some(s) = &self.session else {
            return Snapshot {
                recording,
                port,
                calibration,
                calibration_warnings,
                ..Snapshot::default()
            };
        };
        self.published_state = Some(s.state());
        let latest = self.live.back();
        let events = s.events();
        let skip = events.len().saturating_sub(EVENTS_SHOWN);
        Snapshot {
            state: Some(s.state()),
            reason: s.reason().to_string(),
            stage: Some(s.stage()),
            device: s.device(),
            device_details: s.capabilities().map(details).unwrap_or_default(),
            stats: s.stats(),
            last_ack: s.last_ack().map(|a| describe_ack(&a)),
            commanded_pct: latest.map_or(f64::NAN, |r| r.commanded_override_pct),
            applied_pct: latest.map_or(f64::NAN, |r| r.applied_override_pct),
            fallback: s.in_fallback(),
            calibration,
            calibration_warnings,
            safe_override_pct: s.safe_override_pct(),
            events: events
                .iter()
                .skip(skip)
                .map(|e| (e.time_s, e.text.clone()))
                .collect(),
            recording,
            port,
            hold: s.hold_state(),
            if_link_lost: s.if_link_lost(),
        }
    }

    /// The live charts: currents, force, override, feed over the last [`LIVE_WINDOW_S`].
    pub fn live_charts(&self) -> [LineChart; 4] {
        live_charts(&self.live)
    }
}

/// A run's result in a line.
fn summary_of(r: &RunResult) -> String {
    let m = &r.metrics;
    format!(
        "{}: {}, cycle time {:.1} s, mean |error| {:.1} %, peak force {:.0} N",
        r.spec.controller.kind().label(),
        if r.trace.completed {
            "completed"
        } else {
            "stopped before the program's end"
        },
        m.cycle_time_s,
        m.force_mean_abs_error_pct,
        m.peak_force_n
    )
}

/// Local date and time, `2026-11-24 10:31:02`.
fn local_time(ms: f64) -> String {
    let d = js_sys::Date::new(&wasm_bindgen::JsValue::from_f64(ms));
    format!(
        "{:04}-{:02}-{:02} {:02}:{:02}:{:02}",
        d.get_full_year(),
        d.get_month() + 1,
        d.get_date(),
        d.get_hours(),
        d.get_minutes(),
        d.get_seconds()
    )
}

/// The capabilities in words, for the identity list.
fn details(c: &crate::protocol::frame::Capabilities) -> Vec<(String, String)> {
    use crate::protocol::frame::{channel, feature, OverrideModeCode};
    let channels: Vec<&str> = [
        (channel::SPINDLE_U, "spindle u"),
        (channel::SPINDLE_V, "spindle v"),
        (channel::SPINDLE_W, "spindle w"),
        (channel::FEED_U, "feed u"),
        (channel::FEED_V, "feed v"),
        (channel::FEED_W, "feed w"),
        (channel::SPINDLE_FV, "spindle F/V"),
    ]
    .into_iter()
    .filter(|(bit, _)| c.channel_mask & bit != 0)
    .map(|(_, name)| name)
    .collect();
    let mode = match c.override_mode {
        OverrideModeCode::Dial16 => format!(
            "16-grade dial: {} %",
            c.dial_cpct
                .iter()
                .map(|v| format!("{}", f64::from(*v) / 100.0))
                .collect::<Vec<_>>()
                .join(", ")
        ),
        OverrideModeCode::WholePercent => "whole percent".to_string(),
        OverrideModeCode::Continuous => "continuous".to_string(),
        OverrideModeCode::Other(code) => format!("mode {code} (unknown to this host)"),
    };
    let mut features = Vec::new();
    if c.features & feature::SIM_TRUTH != 0 {
        features.push("sends simulation truth");
    }
    if c.features & feature::ESTOP_INPUT != 0 {
        features.push("E-stop input");
    }
    vec![
        ("Channels".into(), channels.join(", ")),
        (
            "Current scale".into(),
            format!(
                "{} A per count (spindle), {} A per count (feed)",
                c.spindle_current_a_per_count, c.feed_current_a_per_count
            ),
        ),
        (
            "Override".into(),
            format!(
                "{mode}; {}–{} %",
                f64::from(c.min_override_cpct) / 100.0,
                f64::from(c.max_override_cpct) / 100.0
            ),
        ),
        (
            "Device watchdog".into(),
            format!(
                "{} s, then at most {} % (the lower of it and the override applied) for {} s, \
                 then a latched feed hold",
                f64::from(c.watchdog_timeout_ms) / 1000.0,
                f64::from(c.fallback_override_cpct) / 100.0,
                f64::from(c.fallback_limit_ms) / 1000.0
            ),
        ),
        ("Measures".into(), {
            let d = crate::protocol::host::DeviceSummary::of(c);
            if d.not_measured.is_empty() {
                d.measured.join(", ")
            } else {
                format!(
                    "{}; not: {}",
                    d.measured.join(", "),
                    d.not_measured.join(", ")
                )
            }
        }),
        (
            "Line".into(),
            if c.line_baud == 0 {
                "no baud rate declared (USB CDC-ACM or a pipe)".to_string()
            } else {
                format!("{} baud", c.line_baud)
            },
        ),
        (
            "Over-current fault".into(),
            format!("beyond ±{} A", c.over_current_a),
        ),
        (
            "Features".into(),
            if features.is_empty() {
                "none".to_string()
            } else {
                features.join(", ")
            },
        ),
    ]
}

fn time_chart(y_label: &str) -> LineChart {
    LineChart::new(Axis::linear("time (s)"), Axis::linear(y_label))
}

fn series(rows: &VecDeque<LiveRow>, value: impl Fn(&LiveRow) -> f64) -> Vec<(f64, f64)> {
    rows.iter().map(|r| (r.time_s, value(r))).collect()
}

/// The live charts of `rows`.
pub fn live_charts(rows: &VecDeque<LiveRow>) -> [LineChart; 4] {
    let mut current = time_chart("current (A)");
    current.series = vec![
        Series::new(
            "spindle i_u",
            PALETTE[0],
            series(rows, |r| r.spindle_currents_a[0]),
        ),
        Series::new(
            "feed i_u",
            PALETTE[2],
            series(rows, |r| r.feed_currents_a[0]),
        ),
        Series::new(
            "spindle RMS (period)",
            PALETTE[1],
            series(rows, |r| r.spindle_current_rms_a),
        ),
        Series::new(
            "feed RMS (period)",
            PALETTE[3],
            series(rows, |r| r.feed_current_rms_a),
        ),
    ];
    let mut force = time_chart("force (N)");
    force.series = vec![
        Series::new(
            "estimated from current",
            PALETTE[1],
            series(rows, |r| {
                if r.envelope_armed {
                    r.force_est_n
                } else {
                    f64::NAN
                }
            }),
        ),
        Series::new("target", PALETTE[7], series(rows, |r| r.target_force_n)).dashed(),
    ];
    if rows.iter().any(|r| r.force_n.is_finite()) {
        force.series.push(Series::new(
            "simulated (device truth)",
            PALETTE[0],
            series(rows, |r| r.force_n),
        ));
    }
    let mut override_pct = time_chart("feed override (%)");
    override_pct.series = vec![
        Series::new(
            "commanded",
            PALETTE[0],
            series(rows, |r| r.commanded_override_pct),
        ),
        Series::new(
            "applied",
            PALETTE[5],
            series(rows, |r| r.applied_override_pct),
        ),
    ];
    let mut feed = time_chart("feed (mm/min)");
    feed.series = vec![
        Series::new("actual", PALETTE[0], series(rows, |r| r.feed_mm_min)),
        Series::new(
            "programmed",
            PALETTE[7],
            series(rows, |r| r.programmed_feed_mm_min),
        )
        .dashed(),
    ];
    let mut charts = [current, force, override_pct, feed];
    let range = match (rows.front(), rows.back()) {
        (Some(a), Some(b)) if b.time_s > a.time_s => Some(a.time_s..b.time_s),
        _ => None,
    };
    for c in &mut charts {
        c.fit();
        if let Some(r) = &range {
            c.x.range = r.clone();
        }
    }
    charts
}
