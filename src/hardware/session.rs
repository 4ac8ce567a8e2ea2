//! The host's end of a link to a machine, driven by the caller's clock: what the Hardware page
//! runs between its serial port (or virtual device) and its controls.
//!
//! A [`HardwareSession`] takes the bytes that arrived ([`HardwareSession::receive`]) and the time
//! now ([`HardwareSession::tick`], a few times a second), and leaves the bytes to send in
//! [`HardwareSession::take_output`]. It owns the protocol session ([`HostSession`]), the run
//! under way, and the link state with the reason of its last change.
//!
//! ## What the host does with the device ([`Stage`])
//!
//! * **Teach cut** ([`HardwareSession::start_teach_cut`]): arms the device (the emulator loads a
//!   part and starts it) and pushes each sample into a [`TeachCut`] — the schedule of overrides
//!   and the fit `cutlab sim` and `cutlab host` make. At the program's end the calibration is
//!   kept and the device disarmed.
//! * **Closed loop** ([`HardwareSession::arm`]): arms the device and pushes each sample into the
//!   [`FeedbackLoop`] [`closed_loop_of`] builds — estimator, controller and safety envelope, the
//!   loop [`crate::closed_loop::lab::LabRun`] runs on a simulated machine. Each period's command
//!   goes out at once; at the program's end the run's metrics are computed as `cutlab sim`
//!   computes them and the device is disarmed.
//! * **Held at the safe override**: Disarm, Escape, an alarm, or a loop that stopped before the
//!   program's end (its time limit, the overload's feed hold) command the configured safe
//!   override at once — keeping a feed hold in force — and hold it until the part ends, when the
//!   device is disarmed (handed back to the machine's own dial). The operator can re-arm.
//!
//! ## Watchdogs and faults
//!
//! * The **host's watchdog** (wall time, [`SessionOptions::link_timeout_s`]): no sample while a
//!   part runs under the host, or no frame at all while connected → alarm (a link loss).
//! * The **device's watchdog** fallback (its Fault, or the fallback flag) is answered by re-arming
//!   it, as docs/protocol.md §5 says, and counted.
//! * A **device fault** raised (sensor, over-current) → alarm; an **E-stop** (its fault, or the
//!   E-stop flag in a sample) → alarm, and the device handed back at once: it refuses commands
//!   and its axes stopped.
//! * The **port closing** (unplugged, read error: [`HardwareSession::link_lost`]) → alarm; nothing
//!   can be sent, and the device falls back on its own watchdog.
//!
//! An alarm ends a teach cut (no calibration) or a run (its trace marked incomplete) and holds
//! the safe override while the device still listens; it stays until the operator acknowledges it.
//!
//! Times: `now_s` is the caller's wall clock (seconds, any origin); a row's time is the device's
//! clock since the session's first sample, so a device that runs faster than real time records
//! in its own time.

use std::fmt::Write as _;

use super::recording::LiveRow;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::error::LoopError;
use crate::closed_loop::feedback_loop::FeedbackLoop;
use crate::closed_loop::lab::{
    closed_loop_of, cut_model_teach_force, metrics_config, plan_on, RunResult,
};
use crate::closed_loop::metrics::compute;
use crate::closed_loop::sample_loop::{LoopSample, SampleLoop};
use crate::closed_loop::settings::ChainSettings;
use crate::closed_loop::teach_cut::{
    TeachCut, TeachForce, TeachSchedule, TEACH_OVERRIDES_PCT, TEACH_STEP_S,
};
use crate::estimation::estimator::{Calibration, Feedback};
use crate::machine::OverrideCommand;
use crate::plant::cnc::MAX_OVERRIDE_PCT;
use crate::protocol::frame::{
    fault_flag, measured, sample_flag, Ack, Capabilities, FaultKind, FrameType, VERSION_MAJOR,
};
use crate::protocol::host::{
    DeviceSummary, HostSession, KeepUp, LineBudget, LinkSample, LinkStats, HELLO_INTERVAL_S,
};
use crate::safety::OverrideResolution;

/// The link's state, as the page shows it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LinkState {
    /// No device (before connecting, after disconnecting, or the handshake failed).
    Closed,
    /// Waiting for the device's Capabilities.
    Handshaking,
    /// The device answers; the host does not control it.
    Streaming,
    /// The host controls the override (a teach cut or the closed loop).
    Armed,
    /// Something went wrong; the override is held at the safe value where the device still
    /// listens. Stays until acknowledged.
    Alarm,
}

impl LinkState {
    /// Every state.
    pub const ALL: [LinkState; 5] = [
        LinkState::Closed,
        LinkState::Handshaking,
        LinkState::Streaming,
        LinkState::Armed,
        LinkState::Alarm,
    ];

    /// The word the page shows.
    pub fn name(self) -> &'static str {
        match self {
            LinkState::Closed => "closed",
            LinkState::Handshaking => "handshaking",
            LinkState::Streaming => "streaming",
            LinkState::Armed => "armed",
            LinkState::Alarm => "alarm",
        }
    }
}

/// What the host does with the device.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stage {
    /// Nothing: the machine runs on its own dial.
    Idle,
    /// A teach cut under way.
    TeachCut,
    /// The closed loop under way.
    ClosedLoop,
    /// The safe override held until the part ends.
    HoldingSafe,
}

impl Stage {
    /// A short label (the recording's phase column).
    pub fn label(self) -> &'static str {
        match self {
            Stage::Idle => "not armed",
            Stage::TeachCut => "teach cut",
            Stage::ClosedLoop => "closed loop",
            Stage::HoldingSafe => "held at the safe override",
        }
    }
}

/// The host's settings.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SessionOptions {
    /// The host's watchdog, wall seconds: no sample for this long while a part runs under the
    /// host, or no frame at all while connected, is an alarm.
    pub link_timeout_s: f64,
    /// How long the device may take to answer the Hello.
    pub handshake_timeout_s: f64,
    /// The override commanded on Disarm, Escape and alarms; `None`: the device's own fallback.
    pub safe_override_pct: Option<f64>,
}

impl Default for SessionOptions {
    fn default() -> Self {
        Self {
            link_timeout_s: 2.0,
            handshake_timeout_s: 10.0,
            safe_override_pct: None,
        }
    }
}

impl SessionOptions {
    /// Options with a host watchdog of `link_timeout_s` and a safe override (`None`: the
    /// device's fallback); the handshake may take five times the watchdog, as `cutlab host`'s.
    ///
    /// ```
    /// use cutlab::hardware::session::SessionOptions;
    /// assert_eq!(SessionOptions::new(2.0, None).unwrap().handshake_timeout_s, 10.0);
    /// assert!(SessionOptions::new(2.0, Some(-5.0)).is_err());
    /// ```
    pub fn new(link_timeout_s: f64, safe_override_pct: Option<f64>) -> Result<Self, String> {
        let link_timeout_s = crate::protocol::host::check_link_timeout_s(link_timeout_s)?;
        if let Some(pct) = safe_override_pct {
            if !(0.0..=MAX_OVERRIDE_PCT).contains(&pct) {
                return Err(format!(
                    "the safe override must be 0 to {MAX_OVERRIDE_PCT} %, not {} %",
                    crate::input::readable(pct)
                ));
            }
        }
        Ok(Self {
            link_timeout_s,
            handshake_timeout_s: 5.0 * link_timeout_s,
            safe_override_pct,
        })
    }
}

/// Something that happened, for the event log and the recording.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionEvent {
    /// Device time since the session's first sample (0 before it).
    pub time_s: f64,
    /// What.
    pub text: String,
}

/// A calibration the closed loop can use, with what it was made with.
#[derive(Debug, Clone, PartialEq)]
pub struct TaughtCalibration {
    /// The fitted model.
    pub calibration: Calibration,
    /// The settings of the teach cut when it was made over this link: a run must measure the
    /// force the same way. `None` for a saved calibration, whose file keeps only the model.
    pub settings: Option<ChainSettings>,
    /// Where it came from.
    pub source: String,
}

impl TaughtCalibration {
    /// Why a run with the signal chain `settings` cannot use this calibration, if it cannot: the
    /// feedback path must be the calibration's, and after a teach cut over this link the signal
    /// chain too (the fitted line holds for those only).
    pub fn mismatch(&self, settings: &ChainSettings) -> Option<String> {
        let feedback = self.calibration.estimator.feedback();
        if feedback != settings.feedback {
            return Some(
                LoopError::CalibrationFeedback {
                    calibration: feedback,
                    run: settings.feedback,
                }
                .to_string(),
            );
        }
        let t = self.settings.as_ref()?;
        let differs = |a: f64, b: f64| (a - b).abs() > 1e-9 * a.abs().max(b.abs()).max(1.0);
        let field = if t.feedback != settings.feedback {
            Some(format!(
                "the feedback ({} in the teach cut, {} now)",
                t.feedback.name(),
                settings.feedback.name()
            ))
        } else if differs(t.control_period_s, settings.control_period_s) {
            Some(format!(
                "the control period ({} s in the teach cut, {} s now)",
                t.control_period_s, settings.control_period_s
            ))
        } else if t.lowpass_order != settings.lowpass_order {
            Some(format!(
                "the filter order ({} in the teach cut, {} now)",
                t.lowpass_order, settings.lowpass_order
            ))
        } else if differs(t.spindle_lowpass_hz, settings.spindle_lowpass_hz) {
            Some(format!(
                "the spindle current cut-off ({} Hz in the teach cut, {} Hz now)",
                t.spindle_lowpass_hz, settings.spindle_lowpass_hz
            ))
        } else if differs(t.feed_lowpass_hz, settings.feed_lowpass_hz) {
            Some(format!(
                "the feed current cut-off ({} Hz in the teach cut, {} Hz now)",
                t.feed_lowpass_hz, settings.feed_lowpass_hz
            ))
        } else {
            None
        };
        field.map(|f| {
            format!(
                "the calibration was made with other settings: {f}; teach again or change it back"
            )
        })
    }
}

/// The limits a run will be held to, for the confirmation the operator reads before arming.
#[derive(Debug, Clone, PartialEq)]
pub struct ArmLimits {
    /// Sentences, one per limit.
    pub lines: Vec<String>,
}

struct Teaching {
    teach: TeachCut,
    settings: ChainSettings,
}

struct Running {
    run: FeedbackLoop,
    spec: RunSpec,
    calibration: Calibration,
    events_copied: usize,
    rows_seen: usize,
}

enum Activity {
    Idle,
    Teach(Box<Teaching>),
    Loop(Box<Running>),
    Hold,
}

/// The latest control period's values, held on every row until the next period ends.
#[derive(Debug, Clone, Copy)]
struct PeriodValues {
    force_est_n: f64,
    /// The envelope had armed (the controller in charge) at the period's end.
    armed: bool,
    spindle_current_rms_a: f64,
    feed_current_rms_a: f64,
    target_force_n: f64,
}

const NO_PERIOD: PeriodValues = PeriodValues {
    force_est_n: f64::NAN,
    armed: false,
    spindle_current_rms_a: f64::NAN,
    feed_current_rms_a: f64::NAN,
    target_force_n: f64::NAN,
};

/// Event text waiting for the next row is cut off beyond this length.
const MAX_PENDING_EVENT_TEXT: usize = 2048;

/// The host's end of a link. See the module docs.
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
    host: HostSession,
    options: SessionOptions,
    state: LinkState,
    reason: String,
    capabilities: Option<Capabilities>,
    keep_up: Option<KeepUp>,
    connected_s: f64,
    last_hello_s: f64,
    last_frame_s: f64,
    /// Wall time of the latest sample, or of the Arm while the part's first is awaited.
    last_sample_s: f64,
    activity: Activity,
    /// The host holds the device: it sent Arm and no Disarm since (and the link was not lost).
    holding: bool,
    /// The port is gone: nothing is sent any more.
    port_gone: bool,
    /// The command held while [`Stage::HoldingSafe`].
    held: OverrideCommand,
    device_time_s: f64,
    wall_at_device_time_s: f64,
    first_device_time_s: Option<f64>,
    out: Vec<u8>,
    rows: Vec<LiveRow>,
    pending_row_event: String,
    events: Vec<SessionEvent>,
    host_events_copied: usize,
    calibration: Option<TaughtCalibration>,
    result: Option<Box<RunResult>>,
    period: PeriodValues,
    /// Set when a teach cut or a run ended since the page last asked.
    finished_work: bool,
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

    // ── What the page reads ────────────────────────────────────────────────────────────────

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

    // ── Input ──────────────────────────────────────────────────────────────────────────────

    /// Takes the bytes that arrived at `now_s`.
    pub fn receive(&mut self, bytes: &[u8], now_s: f64) {
        if self.state == LinkState::Closed || self.port_gone {
            return;
        }
        let frames_before = self.host.stats().frames_received;
        self.host.receive(bytes);
        if self.host.stats().frames_received > frames_before {
            self.last_frame_s = now_s;
        }
        if self.capabilities.is_none() {
            if let Some(c) = self.host.capabilities().copied() {
                self.handshake_done(c, now_s);
            }
        }
        self.copy_host_events();
        while let Some(sample) = self.host.next_sample() {
            self.sample(&sample, now_s);
        }
        self.watch_device_faults(now_s);
    }

    /// Time passes: the handshake's Hello, heartbeats, the host's watchdog.
    pub fn tick(&mut self, now_s: f64) {
        match self.state {
            LinkState::Closed => return,
            LinkState::Handshaking => {
                if now_s - self.connected_s > self.options.handshake_timeout_s {
                    let s = self.host.stats();
                    self.close(format!(
                        "no answer to Hello within {} s ({} bytes received, {} of them dropped): \
                         is the device on, at this baud rate?",
                        self.options.handshake_timeout_s, s.bytes_received, s.bytes_dropped
                    ));
                } else if now_s - self.last_hello_s >= HELLO_INTERVAL_S {
                    self.last_hello_s = now_s;
                    self.host.hello(&mut self.out);
                }
                return;
            }
            LinkState::Streaming | LinkState::Armed | LinkState::Alarm => {}
        }
        let timeout = self.options.link_timeout_s;
        let running = matches!(self.activity, Activity::Teach(_) | Activity::Loop(_));
        if running && now_s - self.last_sample_s > timeout {
            self.host.link_lost(format!(
                "host watchdog: no sample for {timeout} s while the part runs"
            ));
            self.alarm(
                format!("host watchdog: no sample for {timeout} s while the part ran"),
                now_s,
            );
        } else if self.state != LinkState::Alarm && now_s - self.last_frame_s > timeout {
            self.host
                .link_lost(format!("host watchdog: the device silent for {timeout} s"));
            self.alarm(
                format!("host watchdog: the device has been silent for {timeout} s"),
                now_s,
            );
        }
        if !self.port_gone {
            let clock_s = self.clock_s(now_s);
            self.keep_up(clock_s);
        }
        self.copy_host_events();
    }

    /// The port closed under the session (unplugged, a read or write error): nothing more can
    /// be sent or received.
    pub fn link_lost(&mut self, why: &str, now_s: f64) {
        if self.state == LinkState::Closed {
            return;
        }
        let was_holding = self.holding;
        self.holding = false;
        self.port_gone = true;
        self.out.clear();
        self.host.link_lost(format!("link lost: {why}"));
        let fallback = match self.capabilities {
            Some(c) if was_holding => format!(
                "; the device applies its fallback override (at most {} %, never above the \
                 applied) on its own after its watchdog ({} s), then holds the feed",
                f64::from(c.fallback_override_cpct) / 100.0,
                f64::from(c.watchdog_timeout_ms) / 1000.0
            ),
            _ => String::new(),
        };
        self.alarm(format!("link lost: {why}{fallback}"), now_s);
        self.activity = Activity::Idle;
        self.copy_host_events();
    }

    // ── The operator ───────────────────────────────────────────────────────────────────────

    fn ready_to_arm(&self) -> Result<Capabilities, String> {
        let Some(caps) = self.capabilities else {
            return Err("no device: connect first".into());
        };
        if self.host.hold_latched() {
            return Err(
                "the device holds the feed, latched: clear the cause, then reset the \
                        feed hold"
                    .into(),
            );
        }
        match self.state {
            LinkState::Streaming => Ok(caps),
            LinkState::Armed => Err("already armed: disarm first".into()),
            LinkState::Alarm => Err("acknowledge the alarm first".into()),
            LinkState::Closed | LinkState::Handshaking => Err("no device: connect first".into()),
        }
    }

    /// The limits a teach cut will be run with, for the confirmation.
    pub fn teach_limits(&self, spec: &RunSpec) -> Result<ArmLimits, String> {
        let caps = self.ready_to_arm()?;
        let force = teach_force(&caps, spec)?;
        let plan = plan_on(spec, f64::from(caps.sample_rate_hz)).map_err(|e| e.to_string())?;
        let settings = plan.chain;
        // The teach cut never exceeds the run's highest override (reduce-only limits: 100 %).
        let schedule = TEACH_OVERRIDES_PCT
            .iter()
            .map(|p| format!("{:.0} %", p.min(plan.limits.max_override_pct)))
            .collect::<Vec<_>>()
            .join(", ");
        let mut lines = vec![
            format!(
                "The next part runs open loop through the teach-cut overrides {schedule}, each \
                 held {TEACH_STEP_S} s, again and again until the program ends: no controller, \
                 no envelope."
            ),
            match force {
                TeachForce::SimulationTruth => {
                    "The force the current is fitted against: the simulation's truth, which \
                     this device sends."
                        .to_string()
                }
                TeachForce::CutModel {
                    depth_mm, width_mm, ..
                } => format!(
                    "The force the current is fitted against: the model of the preset's cut \
                     ({} deep, {width_mm} mm wide, from each period's feed and speed): the \
                     machine must cut exactly that.",
                    depth_mm.map_or("the machine's depth".to_string(), |d| format!("{d} mm"))
                ),
                TeachForce::Dynamometer => {
                    "The force the current is fitted against: the dynamometer's.".to_string()
                }
            },
            format!(
                "Current measured: {}; control period {} s; low-passes {} Hz (spindle) and {} Hz \
                 (feed), order {}.",
                feedback_name(settings.feedback),
                settings.control_period_s,
                settings.spindle_lowpass_hz,
                settings.feed_lowpass_hz,
                settings.lowpass_order
            ),
        ];
        lines.extend(self.common_limits(&caps));
        Ok(ArmLimits { lines })
    }

    /// The limits the closed loop of `spec` will be held to, for the confirmation.
    pub fn arm_limits(&self, spec: &RunSpec) -> Result<ArmLimits, String> {
        let caps = self.ready_to_arm()?;
        let (run, _) = self.prepare_loop(spec, &caps)?;
        let s = run.settings();
        let e = &s.envelope;
        let resolution = match &e.resolution {
            OverrideResolution::Dial(p) => format!("the {} positions of the dial", p.len()),
            OverrideResolution::WholePercent => "whole percent".to_string(),
            OverrideResolution::Continuous => "continuous".to_string(),
        };
        let mut lines = vec![
            format!(
                "Controller: {}, holding {:.0} N ({}).",
                spec.controller.kind().label(),
                s.target_force_n,
                feedback_name(s.feedback)
            ),
            format!(
                "Override {}–{} % in {resolution}, changing by at most {} %/s; {} % until the \
                 envelope arms, {} s after the spindle starts.",
                e.min_override_pct,
                e.max_override_pct,
                e.max_rate_pct_per_s,
                e.arming_override_pct,
                e.arming_delay_s
            ),
            format!(
                "Overload: feed hold when the force stays above {:.0} N for {} s.",
                e.overload_limit_n, e.overload_time_s
            ),
            format!(
                "A phase current beyond {:.1} A is a sensor fault.",
                e.max_current_a
            ),
        ];
        lines.extend(self.common_limits(&caps));
        Ok(ArmLimits { lines })
    }

    fn common_limits(&self, caps: &Capabilities) -> Vec<String> {
        vec![
            format!(
                "The device applies {}–{} %; its watchdog falls back to {} % after {} s without \
                 the host.",
                f64::from(caps.min_override_cpct) / 100.0,
                f64::from(caps.max_override_cpct) / 100.0,
                f64::from(caps.fallback_override_cpct) / 100.0,
                f64::from(caps.watchdog_timeout_ms) / 1000.0
            ),
            format!(
                "Disarm, Escape and any alarm command {} % (the safe override) at once; the host \
                 alarms after {} s without samples.",
                self.safe_override_pct(),
                self.options.link_timeout_s
            ),
        ]
    }

    fn check_safe_override(&self, caps: &Capabilities) -> Result<(), String> {
        let safe = self.safe_override_pct();
        let (lo, hi) = (
            f64::from(caps.min_override_cpct) / 100.0,
            f64::from(caps.max_override_cpct) / 100.0,
        );
        if !(safe >= lo && safe <= hi) {
            return Err(format!(
                "the safe override {safe} % is outside what the device applies ({lo}–{hi} %)"
            ));
        }
        Ok(())
    }

    /// The closed loop of `spec` on this device with the calibration at hand.
    fn prepare_loop(
        &self,
        spec: &RunSpec,
        caps: &Capabilities,
    ) -> Result<(FeedbackLoop, Calibration), String> {
        let Some(taught) = &self.calibration else {
            return Err("no calibration yet: make a teach cut, or load a saved calibration".into());
        };
        let sample_rate_hz = f64::from(caps.sample_rate_hz);
        let plan = plan_on(spec, sample_rate_hz).map_err(|e| e.to_string())?;
        if let Some(why) = taught.mismatch(&plan.chain) {
            return Err(why);
        }
        check_measured(caps, false)?;
        self.check_safe_override(caps)?;
        let run = closed_loop_of(spec, &plan, &taught.calibration, sample_rate_hz)
            .map_err(|e| e.to_string())?;
        Ok((run, taught.calibration.clone()))
    }

    /// Arms the device for a teach cut of `spec`'s settings (after the page's confirmation).
    pub fn start_teach_cut(&mut self, spec: &RunSpec, now_s: f64) -> Result<(), String> {
        self.teach_limits(spec)?;
        let caps = self.ready_to_arm()?;
        self.check_safe_override(&caps)?;
        let plan = plan_on(spec, f64::from(caps.sample_rate_hz)).map_err(|e| e.to_string())?;
        check_measured(&caps, true)?;
        let teach = TeachCut::new(
            f64::from(caps.sample_rate_hz),
            &plan,
            teach_force(&caps, spec)?,
            TeachSchedule::Overrides,
        )
        .map_err(|e| e.to_string())?;
        let settings = plan.chain;
        self.activity = Activity::Teach(Box::new(Teaching { teach, settings }));
        self.arm_device(
            "teach cut armed: the host runs the teach-cut overrides",
            now_s,
        );
        Ok(())
    }

    /// Arms the device for the closed loop of `spec` (after the page's confirmation).
    pub fn arm(&mut self, spec: &RunSpec, now_s: f64) -> Result<(), String> {
        let caps = self.ready_to_arm()?;
        let (run, calibration) = self.prepare_loop(spec, &caps)?;
        self.period = PeriodValues {
            target_force_n: run.settings().target_force_n,
            ..NO_PERIOD
        };
        self.activity = Activity::Loop(Box::new(Running {
            run,
            spec: spec.clone(),
            calibration,
            events_copied: 0,
            rows_seen: 0,
        }));
        self.arm_device(
            &format!(
                "armed by the operator: {} in control",
                spec.controller.kind().label()
            ),
            now_s,
        );
        Ok(())
    }

    fn arm_device(&mut self, reason: &str, now_s: f64) {
        self.host.start_part();
        self.host.event("arm (cycle start)");
        let clock_s = self.clock_s(now_s);
        if let Some(k) = &mut self.keep_up {
            k.armed(clock_s);
        }
        self.host.arm(&mut self.out);
        self.sent(clock_s);
        self.holding = true;
        self.held = OverrideCommand::default();
        self.last_sample_s = now_s;
        self.set_state(LinkState::Armed, reason.to_string());
    }

    /// The operator resets the device's latched feed hold (after clearing its cause): a Reset
    /// goes out; the device releases the hold unless the cause is still there.
    pub fn reset_hold(&mut self) -> Result<(), String> {
        if self.capabilities.is_none() || self.port_gone || self.state == LinkState::Closed {
            return Err("no device: connect first".into());
        }
        self.host.reset(&mut self.out);
        // The host's own feed hold goes too, or its next command would latch the hold again.
        self.held.feed_hold = false;
        let clock_s = self.device_time_s;
        self.sent(clock_s);
        self.event("the operator resets the device's latched feed hold".to_string());
        Ok(())
    }

    /// The feed hold as the machine sees it: latched at the device (with its cause), or `None`.
    pub fn hold_state(&self) -> Option<String> {
        if !self.host.hold_latched() {
            return None;
        }
        let faults = self.host.active_faults();
        let cause = if faults & fault_flag::OVER_CURRENT != 0 {
            "an over-current, still there: reset once it is cleared"
        } else if faults & fault_flag::FALLBACK_LIMIT != 0 {
            "the fallback lasted its time limit"
        } else {
            "the host's feed hold (the envelope's overload) or an over-current since cleared"
        };
        Some(format!(
            "the device holds the feed, latched ({cause}): it stays through any link state \
             until the operator resets it"
        ))
    }

    /// What the machine gets if the link is lost now (docs/protocol.md §5): the device's
    /// fallback — the lower of the override applied and its configured fallback — for its time
    /// limit, then a latched feed hold; `None` when the host does not hold the device.
    pub fn if_link_lost(&self) -> Option<String> {
        let caps = self.capabilities?;
        if !self.holding {
            return None;
        }
        let applied = self
            .host
            .last_ack()
            .map_or(f64::NAN, |a| f64::from(a.applied_override_cpct) / 100.0);
        let configured = f64::from(caps.fallback_override_cpct) / 100.0;
        let fallback = if applied.is_finite() {
            applied.min(configured)
        } else {
            configured
        };
        Some(format!(
            "If the link is lost now: after {} s the device applies {fallback} % (the lower of \
             {applied} % applied and its {configured} % fallback) for at most {} s, then holds \
             the feed until the operator resets it.",
            f64::from(caps.watchdog_timeout_ms) / 1000.0,
            f64::from(caps.fallback_limit_ms) / 1000.0
        ))
    }

    /// The operator takes the host out of control (Disarm, or Escape): the run ends there and
    /// the safe override is commanded at once and held until the part ends.
    pub fn disarm(&mut self, why: &str, now_s: f64) {
        if !matches!(self.activity, Activity::Teach(_) | Activity::Loop(_)) {
            return;
        }
        self.stop_work(why, false);
        self.hold_safe(now_s);
        let safe = self.safe_override_pct();
        self.set_state(
            LinkState::Streaming,
            format!("{why}: the override held at {safe} % (the safe value) until the part ends"),
        );
    }

    /// The operator acknowledges an alarm; the link must be alive again (a frame within the
    /// host's watchdog) to leave it.
    pub fn acknowledge_alarm(&mut self, now_s: f64) -> Result<(), String> {
        if self.state != LinkState::Alarm {
            return Ok(());
        }
        if self.capabilities.is_none() || now_s - self.last_frame_s > self.options.link_timeout_s {
            return Err(
                "the device is still silent: reconnect it (Disconnect, then Connect)".into(),
            );
        }
        self.set_state(
            LinkState::Streaming,
            "alarm acknowledged by the operator".to_string(),
        );
        Ok(())
    }

    /// Ends the session: a held device is disarmed (handed back to the machine's own dial).
    pub fn disconnect(&mut self, now_s: f64) {
        if self.state == LinkState::Closed {
            return;
        }
        self.stop_work("disconnected", false);
        if self.holding {
            self.host.disarm(&mut self.out);
            let clock_s = self.clock_s(now_s);
            self.sent(clock_s);
            self.holding = false;
        }
        self.activity = Activity::Idle;
        self.close("disconnected by the operator".to_string());
    }

    // ── Inside ─────────────────────────────────────────────────────────────────────────────

    fn set_state(&mut self, state: LinkState, reason: String) {
        self.event(format!("{}: {reason}", state.name()));
        self.state = state;
        self.reason = reason;
    }

    fn close(&mut self, reason: String) {
        self.set_state(LinkState::Closed, reason);
    }

    /// Records an event at the latest sample's time; the next row carries it too.
    fn event(&mut self, text: String) {
        let time_s = self.session_time_s();
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
    fn clock_s(&self, now_s: f64) -> f64 {
        self.device_time_s + (now_s - self.wall_at_device_time_s).max(0.0)
    }

    fn sent(&mut self, clock_s: f64) {
        if let Some(k) = &mut self.keep_up {
            k.sent(clock_s);
        }
    }

    fn copy_host_events(&mut self) {
        let new: Vec<String> = self
            .host
            .events()
            .iter()
            .skip(self.host_events_copied)
            .map(|e| format!("link, part {}: {}", e.part, e.text))
            .collect();
        self.host_events_copied += new.len();
        for text in new {
            self.event(text);
        }
    }

    fn handshake_done(&mut self, caps: Capabilities, now_s: f64) {
        let summary = DeviceSummary::of(&caps);
        if caps.version_major != VERSION_MAJOR {
            self.close(format!(
                "the device speaks protocol {}; this host speaks {VERSION_MAJOR}.x",
                summary.protocol_version
            ));
            return;
        }
        if !(summary.sample_rate_hz.is_finite() && summary.sample_rate_hz > 0.0) {
            self.close(format!(
                "the device declares a sample rate of {} Hz",
                summary.sample_rate_hz
            ));
            return;
        }
        if let Some(why) = LineBudget::of(&caps).refusal() {
            self.close(why);
            return;
        }
        self.capabilities = Some(caps);
        self.keep_up = Some(KeepUp::new(&caps));
        self.last_frame_s = now_s;
        self.set_state(
            LinkState::Streaming,
            format!(
                "handshake complete: {} ({}), protocol {}",
                summary.device_id, summary.program, summary.protocol_version
            ),
        );
    }

    /// A device fault (not the watchdog's, which the host answers by re-arming) raises an alarm
    /// (docs/protocol.md §5): after an over-current or a sensor fault the safe override is held
    /// until the part ends; after an E-stop — commands refused, the axes stopped — the device is
    /// handed back at once, so that after the reset the machine's own dial applies.
    fn watch_device_faults(&mut self, now_s: f64) {
        let running = matches!(self.activity, Activity::Teach(_) | Activity::Loop(_));
        if let Some(stuck) = self.host.take_stuck_override() {
            if self.state != LinkState::Alarm {
                self.alarm(stuck, now_s);
            }
        }
        if running && self.host.hold_latched() {
            self.alarm(
                "the device holds the feed, latched: the operator resets it once the cause is \
                 cleared"
                    .to_string(),
                now_s,
            );
        }
        let Some(kind) = self.host.take_alarm_faults().first().copied() else {
            return;
        };
        let text = self
            .host
            .events()
            .iter()
            .rev()
            .find(|e| e.text.starts_with("device fault") || e.text.contains("fault is active"))
            .map_or_else(
                || format!("device fault {}", kind.name()),
                |e| e.text.clone(),
            );
        if kind == FaultKind::EStop {
            self.stop_work(&text, false);
            self.release("E-stop: commands are refused and the axes stopped");
            self.set_state(
                LinkState::Alarm,
                format!("{text}; the device handed back to the machine's own dial"),
            );
        } else {
            self.alarm(text, now_s);
        }
    }

    /// The command in force while the host holds the device.
    fn command(&self) -> Option<OverrideCommand> {
        if !self.holding {
            return None;
        }
        Some(match &self.activity {
            Activity::Teach(t) => t.teach.command(),
            Activity::Loop(r) => r.run.command(),
            Activity::Hold | Activity::Idle => self.held,
        })
    }

    /// What is due at device time `clock_s`: the command, heartbeats, re-arming.
    fn keep_up(&mut self, clock_s: f64) {
        let command = self.command();
        let Some(k) = &mut self.keep_up else {
            return;
        };
        let before = self.out.len();
        match command {
            Some(c) => k.keep_up(&mut self.host, c, clock_s, &mut self.out),
            None => k.heartbeat_if_due(&mut self.host, clock_s, &mut self.out),
        }
        if self.out.len() > before {
            k.sent(clock_s);
        }
    }

    fn sample(&mut self, s: &LinkSample, now_s: f64) {
        self.device_time_s = s.device_time_s;
        self.wall_at_device_time_s = now_s;
        self.last_sample_s = now_s;
        let first = *self.first_device_time_s.get_or_insert(s.device_time_s);
        let loop_sample = LoopSample {
            step: &s.step,
            sensorless: None,
            dynamometer: None,
        };
        let idle_before = matches!(self.activity, Activity::Hold | Activity::Idle);
        let (mut teach_done, mut run_done) = (false, false);
        match &mut self.activity {
            Activity::Teach(t) => {
                t.teach.push(&loop_sample);
                if s.program_end {
                    t.teach.end_of_program();
                }
                teach_done = t.teach.finished();
            }
            Activity::Loop(r) => {
                if r.run.push(&loop_sample).is_some() && r.run.trace().rows.len() > r.rows_seen {
                    r.rows_seen = r.run.trace().rows.len();
                    if let Some(row) = r.run.trace().rows.last() {
                        self.period = PeriodValues {
                            force_est_n: row.force_est_n,
                            armed: row.armed,
                            spindle_current_rms_a: row.spindle_current_rms_a,
                            feed_current_rms_a: row.feed_current_rms_a,
                            target_force_n: row.target_force_n,
                        };
                    }
                }
                if s.program_end {
                    r.run.end_of_program();
                }
                run_done = r.run.finished();
            }
            Activity::Hold | Activity::Idle => {}
        }
        self.copy_loop_events();
        if teach_done {
            self.finish_teach(s.program_end, now_s);
        }
        if run_done {
            self.finish_run(s.program_end, now_s);
        }
        if idle_before && s.program_end && self.holding {
            self.release("the part ended");
            self.set_state(
                if self.state == LinkState::Alarm {
                    LinkState::Alarm
                } else {
                    LinkState::Streaming
                },
                "the part ended: the device handed back to the machine's own dial".to_string(),
            );
        }
        self.keep_up(s.device_time_s);
        let sensors = &s.step.sensors;
        let truth = s.step.truth;
        let stage = self.stage();
        let row = LiveRow {
            time_s: s.device_time_s - first,
            part: self.host.part(),
            spindle_currents_a: sensors.spindle_phase_currents_a,
            feed_currents_a: sensors.feed_phase_currents_a,
            spindle_fv_v: sensors.spindle_fv_voltage_v,
            spindle_speed_rpm: sensors.spindle_speed_rpm,
            spindle_command_rpm: sensors.spindle_command_rpm,
            programmed_feed_mm_min: sensors.programmed_feed_mm_min,
            feed_mm_min: sensors.feed_mm_min,
            applied_override_pct: sensors.applied_override_pct,
            commanded_override_pct: self.command().map_or(f64::NAN, |c| c.override_pct),
            force_est_n: self.period.force_est_n,
            envelope_armed: self.period.armed,
            spindle_current_rms_a: self.period.spindle_current_rms_a,
            feed_current_rms_a: self.period.feed_current_rms_a,
            target_force_n: self.period.target_force_n,
            force_n: truth.map_or(f64::NAN, |t| t.force_resultant_n),
            depth_mm: truth.map_or(f64::NAN, |t| t.depth_mm),
            phase: if s.flags & sample_flag::FALLBACK != 0 {
                "device watchdog fallback"
            } else {
                stage.label()
            },
            program_end: s.program_end,
            event: std::mem::take(&mut self.pending_row_event),
        };
        self.rows.push(row);
    }

    fn copy_loop_events(&mut self) {
        let Activity::Loop(r) = &mut self.activity else {
            return;
        };
        let events = &r.run.trace().events;
        let new: Vec<String> = events
            .iter()
            .skip(r.events_copied)
            .map(|e| format!("safety envelope: {}", e.describe()))
            .collect();
        r.events_copied = events.len();
        for text in new {
            self.event(text);
        }
    }

    fn finish_teach(&mut self, program_end: bool, now_s: f64) {
        let Activity::Teach(t) = std::mem::replace(&mut self.activity, Activity::Idle) else {
            return;
        };
        self.finished_work = true;
        match t.teach.calibration() {
            Ok(calibration) => {
                let text = format!(
                    "teach cut complete: {} periods fitted over {:.1} s",
                    calibration.periods, calibration.duration_s
                );
                self.calibration = Some(TaughtCalibration {
                    calibration,
                    settings: Some(t.settings),
                    source: format!("teach cut over the link (part {})", self.host.part()),
                });
                self.end_part(program_end, text, now_s);
            }
            Err(e) => self.end_part(program_end, format!("teach cut failed: {e}"), now_s),
        }
    }

    fn finish_run(&mut self, program_end: bool, now_s: f64) {
        self.stop_work("", program_end);
        let text = match (&self.result, program_end) {
            (Some(r), true) => format!(
                "run complete: cycle time {:.1} s, mean |error| {:.1} %",
                r.metrics.cycle_time_s, r.metrics.force_mean_abs_error_pct
            ),
            _ if self.held.feed_hold => "overload: the envelope held the feed".to_string(),
            _ => "the run reached its time limit before the program's end".to_string(),
        };
        if self.held.feed_hold && !program_end {
            self.alarm(text, now_s);
        } else {
            self.end_part(program_end, text, now_s);
        }
    }

    /// After a teach cut or a run: at the program's end the device is handed back; before it,
    /// the safe override is held until the part ends.
    fn end_part(&mut self, program_end: bool, text: String, now_s: f64) {
        if program_end {
            self.release(&text);
            self.set_state(LinkState::Streaming, text);
        } else {
            self.hold_safe(now_s);
            let safe = self.safe_override_pct();
            self.set_state(
                LinkState::Streaming,
                format!("{text}; the override held at {safe} % until the part ends"),
            );
        }
    }

    /// Ends the teach cut or run under way: a run's trace becomes the result (marked incomplete
    /// unless the program ended), a teach cut is dropped.
    fn stop_work(&mut self, why: &str, completed: bool) {
        match std::mem::replace(&mut self.activity, Activity::Idle) {
            Activity::Teach(_) => {
                self.finished_work = true;
                if !why.is_empty() {
                    self.event(format!("teach cut abandoned ({why}): no calibration made"));
                }
            }
            Activity::Loop(mut r) => {
                self.finished_work = true;
                // A feed hold the envelope ordered stays in force whatever comes next.
                self.held.feed_hold |= r.run.command().feed_hold;
                let settings = r.run.settings().clone();
                let mut trace = r.run.finish().unwrap_or_default();
                trace.completed = completed;
                let metrics = compute(&trace, &metrics_config(r.spec.preset, &settings));
                self.result = Some(Box::new(RunResult {
                    spec: r.spec,
                    settings,
                    calibration: r.calibration,
                    trace,
                    metrics,
                }));
                if !why.is_empty() {
                    self.event(format!("run stopped ({why}): its trace ends here"));
                }
            }
            other => self.activity = other,
        }
        self.period = NO_PERIOD;
    }

    /// Commands the safe override at once (keeping a feed hold in force) and holds it.
    fn hold_safe(&mut self, now_s: f64) {
        if !self.holding {
            self.activity = Activity::Idle;
            return;
        }
        self.held.override_pct = self.safe_override_pct();
        self.activity = Activity::Hold;
        let clock_s = self.clock_s(now_s);
        self.keep_up(clock_s);
    }

    /// Hands the device back to the machine's own dial (Disarm).
    fn release(&mut self, why: &str) {
        if self.holding {
            self.host.disarm(&mut self.out);
            let clock_s = self.device_time_s;
            self.sent(clock_s);
            self.holding = false;
            self.held = OverrideCommand::default();
            self.event(format!("disarm: {why}; the machine's own dial applies"));
        }
        self.activity = Activity::Idle;
    }

    fn alarm(&mut self, reason: String, now_s: f64) {
        self.stop_work(&reason, false);
        self.hold_safe(now_s);
        let mut text = reason;
        if self.holding {
            let _ = write!(
                text,
                "; the host commands the safe override ({} %)",
                self.safe_override_pct()
            );
        }
        self.set_state(LinkState::Alarm, text);
    }
}

/// Whether the device measures what a teach cut (`teach`) or a closed loop needs
/// (docs/protocol.md §3, `measured`): program end to end a part, the spindle's speed and command
/// to judge it at speed, the actual feed for the teach cut's periods and the feed-drive model,
/// and for the closed loop the programmed feed too, so that a stuck override is seen.
pub fn check_measured(caps: &Capabilities, teach: bool) -> Result<(), String> {
    let mut needed = measured::PROGRAM_END
        | measured::SPINDLE_SPEED
        | measured::SPINDLE_COMMAND
        | measured::ACTUAL_FEED;
    if !teach {
        needed |= measured::PROGRAMMED_FEED;
    }
    let missing: Vec<&str> = measured::NAMES
        .iter()
        .filter(|(bit, _)| needed & bit != 0 && caps.measured & bit == 0)
        .map(|(_, name)| *name)
        .collect();
    if missing.is_empty() {
        Ok(())
    } else {
        Err(format!(
            "the device does not measure the {} a {} needs: wire {} to the bridge (docs/hardware.md §1)",
            missing.join(", "),
            if teach { "teach cut" } else { "closed loop" },
            if missing.len() == 1 { "it" } else { "them" }
        ))
    }
}

/// Where a teach cut on this device takes its force: the simulation's truth when the device
/// sends it, else the model of the preset's cut when the program cuts one depth, width and
/// material (as `cutlab host` decides).
fn teach_force(caps: &Capabilities, spec: &RunSpec) -> Result<TeachForce, String> {
    if DeviceSummary::of(caps).sim_truth {
        return Ok(TeachForce::SimulationTruth);
    }
    cut_model_teach_force(spec.preset).ok_or_else(|| {
        "this device sends no force and the preset's cut changes along the path, so a teach cut \
         has nothing to fit the current against: load a saved calibration instead"
            .to_string()
    })
}

fn feedback_name(feedback: Feedback) -> &'static str {
    match feedback {
        Feedback::SpindleCurrent => "force from the spindle current",
        Feedback::FeedCurrent => "force from the feed-drive current",
        Feedback::Dynamometer => "force from a dynamometer",
    }
}

/// A short description of an acknowledgement, for the page.
pub fn describe_ack(ack: &Ack) -> String {
    let command = FrameType::from_code(ack.command).map_or("?", FrameType::name);
    let result = match ack.result.code() {
        0 => "applied",
        1 => "applied, limited to the device's range",
        2 => "ignored: not armed",
        3 => "refused: E-stop",
        _ => "unknown result",
    };
    format!(
        "{command} #{}: {result}; override now {} %",
        ack.seq,
        f64::from(ack.applied_override_cpct) / 100.0
    )
}
