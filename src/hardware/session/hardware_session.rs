//! The session itself ([`HardwareSession`]): its state, the work under way, the constructor,
//! what the page reads, and the bookkeeping every part uses (state changes, events, the device's
//! clock).

use super::{LinkState, SessionEvent, SessionOptions, Stage, TaughtCalibration};
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::feedback_loop::FeedbackLoop;
use crate::closed_loop::lab::RunResult;
use crate::closed_loop::settings::ChainSettings;
use crate::closed_loop::teach_cut::TeachCut;
use crate::estimation::estimator::Calibration;
use crate::hardware::recording::LiveRow;
use crate::machine::OverrideCommand;
use crate::protocol::frame::{Ack, Capabilities};
use crate::protocol::host::{DeviceSummary, HostSession, LinkStats};
use crate::protocol::keep_up::KeepUp;

pub(super) struct Teaching {
    pub(super) teach: TeachCut,
    pub(super) settings: ChainSettings,
}

pub(super) struct Running {
    pub(super) run: FeedbackLoop,
    pub(super) spec: RunSpec,
    pub(super) calibration: Calibration,
    pub(super) events_copied: usize,
    pub(super) rows_seen: usize,
}

pub(super) enum Activity {
    Idle,
    Teach(Box<Teaching>),
    Loop(Box<Running>),
    Hold,
}

/// The latest control period's values, held on every row until the next period ends.
#[derive(Debug, Clone, Copy)]
pub(super) struct PeriodValues {
    pub(super) force_est_n: f64,
    /// The envelope had armed (the controller in charge) at the period's end.
    pub(super) armed: bool,
    pub(super) spindle_current_rms_a: f64,
    pub(super) feed_current_rms_a: f64,
    pub(super) target_force_n: f64,
}

pub(super) const NO_PERIOD: PeriodValues = PeriodValues {
    force_est_n: f64::NAN,
    armed: false,
    spindle_current_rms_a: f64::NAN,
    feed_current_rms_a: f64::NAN,
    target_force_n: f64::NAN,
};

/// Event text waiting for the next row is cut off beyond this length.
const MAX_PENDING_EVENT_TEXT: usize = 2048;

/// The host's end of a link. See the [module docs](super).
///
/// ```
/// use cutlab::hardware::session::{HardwareSession, LinkState, SessionOptions};
/// use cutlab::plant::Preset;
/// use cutlab::protocol::device::{DeviceConfig, DeviceEmulator};
/// let mut device = DeviceEmulator::new(DeviceConfig::new(Preset::ManeeratDoc1)).unwrap();
/// let mut host = HardwareSession::new(SessionOptions::default(), 0.0);
/// let mut answer = Vec::new();
/// device.receive(&host.take_output(), &mut answer); // the Hello, answered with Capabilities
/// host.receive(&answer, 0.01);
/// assert_eq!(host.state(), LinkState::Streaming);
/// assert_eq!(host.device().unwrap().sample_rate_hz, 1000.0);
/// assert_eq!(host.safe_override_pct(), 50.0); // the device's fallback, by default
/// ```
pub struct HardwareSession {
    pub(super) host: HostSession,
    pub(super) options: SessionOptions,
    pub(super) state: LinkState,
    pub(super) reason: String,
    pub(super) capabilities: Option<Capabilities>,
    pub(super) keep_up: Option<KeepUp>,
    pub(super) connected_s: f64,
    pub(super) last_hello_s: f64,
    pub(super) last_frame_s: f64,
    /// Wall time of the latest sample, or of the Arm while the part's first is awaited.
    pub(super) last_sample_s: f64,
    pub(super) activity: Activity,
    /// The host holds the device: it sent Arm and no Disarm since (and the link was not lost).
    pub(super) holding: bool,
    /// The port is gone: nothing is sent any more.
    pub(super) port_gone: bool,
    /// The command held while [`Stage::HoldingSafe`].
    pub(super) held: OverrideCommand,
    pub(super) device_time_s: f64,
    pub(super) wall_at_device_time_s: f64,
    pub(super) first_device_time_s: Option<f64>,
    pub(super) out: Vec<u8>,
    pub(super) rows: Vec<LiveRow>,
    pub(super) pending_row_event: String,
    pub(super) events: Vec<SessionEvent>,
    pub(super) host_events_copied: usize,
    pub(super) calibration: Option<TaughtCalibration>,
    pub(super) result: Option<Box<RunResult>>,
    pub(super) period: PeriodValues,
    /// Set when a teach cut or a run ended since the page last asked.
    pub(super) finished_work: bool,
}

impl HardwareSession {
    /// A session starting its handshake at `now_s` (the Hello is in [`Self::take_output`]).
    pub fn new(options: SessionOptions, now_s: f64) -> Self {
        let mut s = Self {
            host: HostSession::new(),
            options,
            state: LinkState::Handshaking,
            reason: "port open: saying Hello".to_string(),
            capabilities: None,
            keep_up: None,
            connected_s: now_s,
            last_hello_s: now_s,
            last_frame_s: now_s,
            last_sample_s: now_s,
            activity: Activity::Idle,
            holding: false,
            port_gone: false,
            held: OverrideCommand::default(),
            device_time_s: 0.0,
            wall_at_device_time_s: now_s,
            first_device_time_s: None,
            out: Vec::with_capacity(1024),
            rows: Vec::with_capacity(4096),
            pending_row_event: String::new(),
            events: Vec::new(),
            host_events_copied: 0,
            calibration: None,
            result: None,
            period: NO_PERIOD,
            finished_work: false,
        };
        s.host.hello(&mut s.out);
        s
    }

    /// The link state.
    pub fn state(&self) -> LinkState {
        self.state
    }

    /// Why the state last changed.
    pub fn reason(&self) -> &str {
        &self.reason
    }

    /// What the host does with the device.
    pub fn stage(&self) -> Stage {
        match self.activity {
            Activity::Idle => Stage::Idle,
            Activity::Teach(_) => Stage::TeachCut,
            Activity::Loop(_) => Stage::ClosedLoop,
            Activity::Hold => Stage::HoldingSafe,
        }
    }

    /// The device's capabilities, after the handshake.
    pub fn capabilities(&self) -> Option<&Capabilities> {
        self.capabilities.as_ref()
    }

    /// The device in a few words, after the handshake.
    pub fn device(&self) -> Option<DeviceSummary> {
        self.capabilities.as_ref().map(DeviceSummary::of)
    }

    /// What crossed the link.
    pub fn stats(&self) -> LinkStats {
        self.host.stats()
    }

    /// The device's latest acknowledgement.
    pub fn last_ack(&self) -> Option<Ack> {
        self.host.last_ack()
    }

    /// Whether the device reports its watchdog fallback.
    pub fn in_fallback(&self) -> bool {
        self.host.in_fallback()
    }

    /// Whether the host holds the device (it sent Arm, no Disarm since, and the link lives).
    pub fn holding(&self) -> bool {
        self.holding
    }

    /// The override the host commands on Disarm, Escape and alarms (NaN before the handshake).
    pub fn safe_override_pct(&self) -> f64 {
        self.options.safe_override_pct.unwrap_or_else(|| {
            self.capabilities
                .map_or(f64::NAN, |c| f64::from(c.fallback_override_cpct) / 100.0)
        })
    }

    /// The host's settings.
    pub fn options(&self) -> SessionOptions {
        self.options
    }

    /// Changes the host's settings (the watchdog and the safe override), unless the host is in
    /// control, when a change would alter the limits the operator confirmed.
    pub fn set_options(&mut self, options: SessionOptions) -> Result<(), String> {
        if self.state == LinkState::Armed {
            return Err(
                "disarm first: the limits in force are the ones confirmed at arming".into(),
            );
        }
        self.options = options;
        Ok(())
    }

    /// The events so far.
    pub fn events(&self) -> &[SessionEvent] {
        &self.events
    }

    /// The calibration the closed loop will use.
    pub fn calibration(&self) -> Option<&TaughtCalibration> {
        self.calibration.as_ref()
    }

    /// Uses `calibration` for the next runs (a saved one, or one taught elsewhere).
    pub fn set_calibration(&mut self, calibration: TaughtCalibration) {
        self.event(format!("calibration loaded: {}", calibration.source));
        self.use_calibration(calibration);
    }

    /// Uses `calibration` from now on and warns of what it rests on
    /// ([`TaughtCalibration::warnings`]): after a teach cut over the link and when a saved one
    /// is loaded alike.
    pub(super) fn use_calibration(&mut self, calibration: TaughtCalibration) {
        for warning in calibration.warnings() {
            self.event(format!("calibration warning: {warning}"));
        }
        self.calibration = Some(calibration);
    }

    /// The latest run, once it ended (completed or not).
    pub fn result(&self) -> Option<&RunResult> {
        self.result.as_deref()
    }

    /// The trace of the run under way, if one is.
    pub fn running_trace(&self) -> Option<&crate::closed_loop::trace::Trace> {
        match &self.activity {
            Activity::Loop(r) => Some(r.run.trace()),
            _ => None,
        }
    }

    /// Whether a teach cut or a run ended since the last call.
    pub fn take_finished(&mut self) -> bool {
        std::mem::take(&mut self.finished_work)
    }

    /// The bytes to send to the device.
    pub fn take_output(&mut self) -> Vec<u8> {
        std::mem::take(&mut self.out)
    }

    /// The rows of the samples received since the last call.
    pub fn take_rows(&mut self) -> Vec<LiveRow> {
        std::mem::take(&mut self.rows)
    }

    pub(super) fn set_state(&mut self, state: LinkState, reason: String) {
        self.event(format!("{}: {reason}", state.name()));
        self.state = state;
        self.reason = reason;
    }

    pub(super) fn close(&mut self, reason: String) {
        self.set_state(LinkState::Closed, reason);
    }

    /// Records an event at the latest sample's time; the next row carries it too.
    pub(super) fn event(&mut self, text: String) {
        self.event_at(None, text);
    }

    /// Records an event at device time `device_time_s` (`None`: the latest sample's); the next
    /// row carries it too.
    pub(super) fn event_at(&mut self, device_time_s: Option<f64>, text: String) {
        let time_s = match (device_time_s, self.first_device_time_s) {
            (Some(t), Some(first)) => t - first,
            _ => self.session_time_s(),
        };
        // Events while no samples come (a silent device) wait for the next row; a few are
        // enough to say what happened.
        if self.pending_row_event.len() < MAX_PENDING_EVENT_TEXT {
            if !self.pending_row_event.is_empty() {
                self.pending_row_event.push_str("; ");
            }
            self.pending_row_event.push_str(&text);
        }
        self.events.push(SessionEvent { time_s, text });
    }

    fn session_time_s(&self) -> f64 {
        self.first_device_time_s
            .map_or(0.0, |first| self.device_time_s - first)
    }

    /// Device time now: the latest sample's, moved on by the wall clock since it arrived.
    pub(super) fn clock_s(&self, now_s: f64) -> f64 {
        self.device_time_s + (now_s - self.wall_at_device_time_s).max(0.0)
    }

    pub(super) fn sent(&mut self, clock_s: f64) {
        if let Some(k) = &mut self.keep_up {
            k.sent(clock_s);
        }
    }
}
