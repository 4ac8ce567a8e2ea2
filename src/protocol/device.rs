//! The device emulator: the simulated FANUC machine behind the protocol, as a bridge would present
//! a real one, with the device-side watchdog and fault injection.
//!
//! [`DeviceEmulator`] is a state machine without I/O or clock of its own: the driver hands it the
//! bytes that arrived ([`DeviceEmulator::receive`]) and asks it for the next frame period
//! ([`DeviceEmulator::step_frame`]), which appends the bytes to send. `cutlab device --stdio`
//! drives it in (scaled) real time ([`super::link::run_device`]); a test can drive it directly.
//!
//! ## What the emulator does
//!
//! * **Parts.** The machines are made by the code `cutlab sim` uses
//!   ([`Preset::teach_and_run_machines`]):
//!   the first part is seeded like sim's teach cut, the second like its closed-loop run, and
//!   every later part like a run with the seed plus its number. An `Arm` while no program runs
//!   stands for the operator loading the next part and pressing cycle start; the part runs to
//!   its program end whatever the host does (a disarmed part runs at the machine's own dial,
//!   100 %).
//! * **Samples.** The plant samples at 10 kHz; the device sends one [`Sample`] per
//!   [`DeviceConfig::decimation`] plant samples (1 kHz by default), each channel the mean over its
//!   block, as an oversampling ADC would: a sinusoid of frequency f is attenuated by
//!   sin(πfT)/(πfT) (0.2 % at 33 Hz, 1.6 % at 100 Hz for T = 1 ms), which the teach cut, made
//!   over the same link, calibrates away. Currents are sent as counts of 5 mA (±163 A), the F/V
//!   voltage as counts of 0.5 mV. Before each sample it sends a [`SimTruth`] with the block's
//!   truth (a real bridge does not), which the host uses for its metrics and teach cut.
//! * **Commands.** A `SetOverride` while armed is limited to the device's range, quantised to
//!   the machine's positions (the 16-grade dial, whole percent, or continuous) and acknowledged
//!   with the value applied. Every host frame is acknowledged or, for a heartbeat, just noted.
//! * **Watchdog.** While armed, no valid command or heartbeat for
//!   [`DeviceConfig::watchdog_timeout_s`] (device time) → the device applies the fallback override
//!   itself, reports a watchdog [`Fault`], ignores override commands (acknowledged "not armed")
//!   and stays there until the host arms again.
//! * **Faults.** A phase current beyond the over-current limit, or a non-finite one, raises an
//!   over-current or sensor fault, cleared when the currents are back. The device only reports
//!   them; the host decides (docs/protocol.md §5). An active E-stop input (injected) holds the
//!   feed, as the control stops its axes, and refuses every SetOverride and Arm (result 3).
//!
//! ## Fault injection ([`FaultInjection`])
//!
//! * `drop_rate`: each frame, either way, is lost with this probability.
//! * `noise_rate`: each frame, either way, is corrupted with this probability (a bit flipped in a
//!   sent frame; a received frame is discarded as the CRC would discard it).
//! * `stall_at_s`, `stall_s`: for this window of device time the device's receiver is stalled:
//!   every received byte is discarded (its watchdog fires if the window exceeds the timeout).
//! * `unplug_at_s`: from this device time on, the cable is out: nothing is received or sent;
//!   the machine runs on, and the watchdog applies the fallback.
//! * `estop_at_s`: from this device time on, the E-stop input is active (the device then
//!   declares one in its features).
//! * `over_current_at_s`, `over_current_s`: for this window of device time the device reads an
//!   over-current (while a part runs), as a crashed or broken tool would make it.

use super::codec::{encode_frame, Decoder, MAX_FRAME_LEN};
use super::frame::{
    channel, command_flag, fault_flag, feature, measured, padded, sample_flag, Ack, AckResult,
    Capabilities, Fault, FaultKind, Frame, FrameType, Heartbeat, OverrideModeCode, Sample,
    SimTruth, NO_DIAL_CODE, VERSION_MAJOR, VERSION_MINOR,
};
use crate::machine::{Machine, OverrideCommand, PlantTruth, SensorSample};
use crate::plant::cnc::{AppliedOverride, OverrideMode};
use crate::plant::presets::PlantEdits;
use crate::plant::Preset;
use crate::rng::Rng;
use crate::truth_fields::TRUTH_VALUES;

/// [`Fault::channel`] when the fault concerns no channel.
const NO_CHANNEL: u8 = 0xFF;

/// Amperes per count of the emulator's current channels.
pub const CURRENT_A_PER_COUNT: f64 = 0.005;
/// Volts per count of the emulator's F/V channel.
pub const FV_V_PER_COUNT: f64 = 0.0005;
/// The override of a disarmed device: the machine's own dial.
pub const DISARMED_OVERRIDE_PCT: f64 = 100.0;
/// Device seconds per wall second `cutlab device --time-scale` and the Hardware page's virtual
/// device accept: from a hundredth of real time to a thousand times it.
pub const TIME_SCALE_RANGE: (f64, f64) = (0.01, 1000.0);
/// The probability that a frame is lost or corrupted: 0 to 1.
pub const FAULT_RATE_RANGE: (f64, f64) = (0.0, 1.0);
/// The device's watchdog timeout, s: from a millisecond (the Capabilities frame carries it in
/// whole ms) to the 65 s its 16 bits hold.
pub const WATCHDOG_RANGE_S: (f64, f64) = (0.001, 65.0);
/// How long the fallback may last before the device holds the feed, s (whole ms in 16 bits).
pub const FALLBACK_LIMIT_RANGE_S: (f64, f64) = (0.1, 65.0);
/// The device's watchdog timeout unless told, s.
pub const DEFAULT_WATCHDOG_S: f64 = 0.5;
/// The override the watchdog applies at most unless told, %.
pub const DEFAULT_FALLBACK_PCT: f64 = 50.0;
/// How long the fallback lasts before the feed hold unless told, s.
pub const DEFAULT_FALLBACK_LIMIT_S: f64 = 5.0;

/// How often the device sends a heartbeat, device time.
pub const HEARTBEAT_INTERVAL_S: f64 = 0.1;
/// The window, device time, over which the three phases of a drive are checked to sum to zero.
pub const PHASE_CHECK_WINDOW_S: f64 = 0.1;
/// Below this RMS phase current a drive's phase sum says nothing (noise and offsets dominate):
/// its sensors are not judged.
pub const PHASE_CHECK_MIN_A: f64 = 1.0;
/// A drive whose three phases' sum has an RMS above this fraction of the phases' RMS has an open
/// or stuck sensor (a healthy drive's sum is its sensors' noise and offsets: no preset raises
/// the fault, tests/host.rs).
pub const PHASE_SUM_TOLERANCE: f64 = 0.25;

/// Faults the emulator injects.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FaultInjection {
    /// Probability that a frame (either way) is lost.
    pub drop_rate: f64,
    /// Probability that a frame (either way) is corrupted.
    pub noise_rate: f64,
    /// Start of the receiver stall, device time.
    pub stall_at_s: Option<f64>,
    /// Length of the receiver stall.
    pub stall_s: f64,
    /// When the cable is pulled, device time.
    pub unplug_at_s: Option<f64>,
    /// When the E-stop input goes active (and stays so), device time. With it the device
    /// declares an E-stop input (features bit 1).
    pub estop_at_s: Option<f64>,
    /// Start of an over-current, device time: the device reads a phase current beyond its limit
    /// (as a crash or a broken tool would make it) for `over_current_s`.
    pub over_current_at_s: Option<f64>,
    /// Length of the over-current.
    pub over_current_s: f64,
    /// From this device time on, the spindle's phase-u transducer is open: it reads 0 A (a
    /// closed-loop transducer without supply, its burden resistor and the mid-rail shift).
    pub sensor_open_at_s: Option<f64>,
    /// From this device time on, the CNC ignores the bridge's outputs (the selector on the
    /// dial, a dead opto-coupler, a ladder that does not take the code): it keeps the override
    /// it had, while the bridge goes on acknowledging what it outputs.
    pub stuck_override_at_s: Option<f64>,
}

/// What the emulator emulates.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceConfig {
    /// The machine and its program.
    pub preset: Preset,
    /// Seed of the machines (as `cutlab sim --seed`) and of the fault injection.
    pub seed: u64,
    /// Plant samples per sent sample.
    pub decimation: usize,
    /// The device's watchdog.
    pub watchdog_timeout_s: f64,
    /// The override the watchdog applies at most: the fallback is the lower of it and the
    /// override applied when the watchdog fired.
    pub fallback_override_pct: f64,
    /// How long the fallback lasts before the device holds the feed (latched until the
    /// operator's reset).
    pub fallback_limit_s: f64,
    /// The Sample fields the device declares it measures ([`measured`]): all of them, for the
    /// simulation; clear bits to emulate a bridge that lacks an input.
    pub measured: u16,
    /// The baud rate the device declares for its line (0: none, a pipe or USB CDC-ACM).
    pub line_baud: u32,
    /// Keep one [`DeviceTraceRow`] per sample ([`DeviceEmulator::take_trace`]).
    pub trace: bool,
    /// A phase current beyond ± this is an over-current fault.
    pub over_current_a: f64,
    /// Faults to inject.
    pub faults: FaultInjection,
    /// Whether to send the simulation's truth (SimTruth frames, the SIM_TRUTH feature). Off, the
    /// emulator is a real bridge's twin: the host sees currents, speed and feed only, and a
    /// teach cut must take its force from elsewhere.
    pub sim_truth: bool,
}

impl DeviceConfig {
    /// The defaults for `preset`: seed 1, 1 kHz samples, watchdog 0.5 s, fallback at most 50 %
    /// for at most 5 s, over-current at 150 A, every field measured, no baud rate (a pipe), no
    /// injected faults.
    pub fn new(preset: Preset) -> Self {
        Self {
            preset,
            seed: 1,
            decimation: 10,
            watchdog_timeout_s: DEFAULT_WATCHDOG_S,
            fallback_override_pct: DEFAULT_FALLBACK_PCT,
            fallback_limit_s: DEFAULT_FALLBACK_LIMIT_S,
            measured: measured::ALL,
            line_baud: 0,
            trace: false,
            over_current_a: 150.0,
            faults: FaultInjection::default(),
            sim_truth: true,
        }
    }
}

/// Why an emulator cannot be made.
#[derive(Debug, Clone, PartialEq)]
pub struct DeviceError(pub String);

impl std::fmt::Display for DeviceError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for DeviceError {}

/// What the emulator counted, for its diagnostics.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DeviceStats {
    /// Frames sent (before injection).
    pub frames_sent: u64,
    /// Frames dropped by injection, either way.
    pub frames_dropped: u64,
    /// Frames corrupted by injection, either way.
    pub frames_corrupted: u64,
    /// Bytes discarded by a stall or while unplugged.
    pub bytes_discarded: u64,
    /// Valid frames received.
    pub frames_received: u64,
    /// Watchdog firings.
    pub watchdog_fallbacks: u64,
    /// Parts started.
    pub parts: u64,
}

/// Sums of one block of plant samples.
#[derive(Debug, Clone, Copy, Default)]
struct SampleSums {
    n: usize,
    spindle: [f64; 3],
    feed: [f64; 3],
    fv: f64,
    speed: f64,
    feed_mm_min: f64,
    truth: [f64; TRUTH_VALUES],
    last: SensorSample,
    last_truth: PlantTruth,
    truth_seen: bool,
}

/// Counts of `value` at `per_count`, saturating at the ADC's range (NaN reads 0: a real ADC has
/// no NaN; the sensor fault reports it).
fn counts(value: f64, per_count: f64) -> i16 {
    let c = (value / per_count).round();
    if c.is_nan() {
        0
    } else {
        c.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
    }
}

/// An override in hundredths of a percent, saturating.
///
/// ```
/// use cutlab::protocol::device::cpct;
/// assert_eq!((cpct(87.6), cpct(-3.0), cpct(1e9), cpct(f64::NAN)), (8760, 0, 65535, 0));
/// ```
pub fn cpct(pct: f64) -> u16 {
    let c = (pct * 100.0).round();
    if c.is_nan() {
        0
    } else {
        c.clamp(0.0, f64::from(u16::MAX)) as u16
    }
}

/// Why the device holds the feed, latched until the operator resets it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum HoldCause {
    /// The host asked for a feed hold (the safety envelope's overload).
    Host,
    /// The device read an over-current (a crash, a broken tool).
    OverCurrent,
    /// The watchdog's fallback lasted its time limit.
    FallbackLimit,
}

impl HoldCause {
    /// In words, for diagnostics and the trace.
    pub fn name(self) -> &'static str {
        match self {
            HoldCause::Host => "host feed hold",
            HoldCause::OverCurrent => "over-current",
            HoldCause::FallbackLimit => "fallback time limit",
        }
    }
}

/// What the emulated bridge applied at one sample: what `cutlab device --trace` writes, so every
/// fault path can be checked from outside.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DeviceTraceRow {
    /// Device time at the end of the sample.
    pub time_s: f64,
    /// The part (1 = the first).
    pub part: u64,
    /// The sample's sequence number.
    pub seq: u32,
    /// The host holds the override (armed, not in fallback).
    pub armed: bool,
    /// The watchdog's fallback is applied.
    pub fallback: bool,
    /// The feed is held (any cause).
    pub feed_hold: bool,
    /// The latched hold's cause, if the hold is latched.
    pub hold_latched: Option<HoldCause>,
    /// The override the bridge outputs.
    pub bridge_override_pct: f64,
    /// The override the CNC applies (it differs from the bridge's when the override is stuck).
    pub cnc_override_pct: f64,
    /// The block's programmed feed.
    pub programmed_feed_mm_min: f64,
    /// The actual feed.
    pub feed_mm_min: f64,
    /// Faults active ([`fault_flag`] bits).
    pub faults: u8,
}

impl DeviceTraceRow {
    /// The CSV header of [`DeviceTraceRow::csv_line`].
    pub const CSV_HEADER: &'static str = "time_s,part,seq,armed,fallback,feed_hold,hold_latched,\
bridge_override_pct,cnc_override_pct,programmed_feed_mm_min,feed_mm_min,faults";

    /// The row as a CSV line (no newline).
    pub fn csv_line(&self) -> String {
        format!(
            "{:.4},{},{},{},{},{},{},{},{},{},{},{}",
            self.time_s,
            self.part,
            self.seq,
            u8::from(self.armed),
            u8::from(self.fallback),
            u8::from(self.feed_hold),
            self.hold_latched.map_or("", HoldCause::name),
            self.bridge_override_pct,
            self.cnc_override_pct,
            self.programmed_feed_mm_min,
            self.feed_mm_min,
            self.faults
        )
    }
}

/// The running sums of one drive's phase check ([`PHASE_CHECK_WINDOW_S`]).
#[derive(Debug, Clone, Copy, Default)]
struct PhaseWindow {
    sum_sq: f64,
    phase_sq: [f64; 3],
}

impl PhaseWindow {
    fn add(&mut self, i: [f64; 3]) {
        let sum = i[0] + i[1] + i[2];
        if sum.is_finite() {
            self.sum_sq += sum * sum;
            for (sq, x) in self.phase_sq.iter_mut().zip(i) {
                *sq += x * x;
            }
        }
    }

    /// The verdict over `n` samples: `Some(channel offset)` of the sensor that reads least when
    /// the phases do not sum to zero, `None` when they do; `Err(())` when the current is too low
    /// to tell.
    fn verdict(&self, n: f64) -> Result<Option<usize>, ()> {
        let phase_rms = (self.phase_sq.iter().sum::<f64>() / (3.0 * n)).sqrt();
        // NaN (no finite sample in the window) says nothing either.
        if phase_rms.is_nan() || phase_rms <= PHASE_CHECK_MIN_A {
            return Err(());
        }
        let sum_rms = (self.sum_sq / n).sqrt();
        if sum_rms <= PHASE_SUM_TOLERANCE * phase_rms {
            return Ok(None);
        }
        let weakest = (0..3)
            .min_by(|&a, &b| self.phase_sq[a].total_cmp(&self.phase_sq[b]))
            .unwrap_or(0);
        Ok(Some(weakest))
    }
}

/// Ends a phase-check window of `n` samples: each drive with enough current is judged by its
/// three phases' sum (its verdict the channel bit of its open or stuck sensor, or none), a drive
/// with too little keeps its verdict.
fn judge_phases(windows: &mut [PhaseWindow; 2], n: &mut usize, verdicts: &mut [Option<u8>; 2]) {
    for (drive, (window, verdict)) in windows.iter().zip(verdicts.iter_mut()).enumerate() {
        if let Ok(v) = window.verdict(*n as f64) {
            // Channel bits: spindle u, v, w = 0, 1, 2; feed u, v, w = 3, 4, 5.
            *verdict = v.map(|k| (3 * drive + k) as u8);
        }
    }
    *windows = [PhaseWindow::default(); 2];
    *n = 0;
}

/// A part in the machine.
struct Part {
    machine: Box<dyn Machine>,
    ended: bool,
}

/// The simulated machine behind the protocol. See the module docs.
///
/// ```
/// use cutlab::plant::Preset;
/// use cutlab::protocol::codec::{encode_frame, Decoder, MAX_FRAME_LEN};
/// use cutlab::protocol::device::{DeviceConfig, DeviceEmulator};
/// use cutlab::protocol::frame::{Arm, Frame};
/// let mut device = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
/// assert_eq!(device.capabilities().sample_rate_hz, 1000.0);
/// let mut arm = [0u8; MAX_FRAME_LEN];
/// let n = encode_frame(&Frame::Arm(Arm { seq: 1 }), &mut arm).unwrap();
/// let mut out = Vec::new();
/// device.receive(&arm[..n], &mut out); // an Ack; the emulator loads a part
/// for _ in 0..100 {
///     device.step_frame(&mut out); // SimTruth, Sample, and a Heartbeat every 0.1 s
/// }
/// let samples = Decoder::new()
///     .frames(&out)
///     .filter(|f| matches!(f, Ok(Frame::Sample(_))))
///     .count();
/// assert_eq!((samples, device.time_s()), (100, 0.1));
/// ```
pub struct DeviceEmulator {
    config: DeviceConfig,
    capabilities: Capabilities,
    mode: OverrideMode,
    min_pct: f64,
    max_pct: f64,
    plant_dt_s: f64,
    /// Plant samples since power-on: the device clock.
    ticks: u64,
    decoder: Decoder,
    /// Machines for the next parts.
    next_parts: Vec<Box<dyn Machine>>,
    part: Option<Part>,
    armed: bool,
    fallback: bool,
    estop: bool,
    /// The host's latest request.
    requested: OverrideCommand,
    applied: AppliedOverride,
    last_host_frame_s: f64,
    next_heartbeat_s: f64,
    sample_seq: u32,
    fault_seq: u32,
    heartbeat_seq: u32,
    over_current: bool,
    sensor_fault: bool,
    /// The drives' phase checks (spindle, feed), the samples in them, and each drive's verdict:
    /// the channel bit of its open or stuck sensor.
    phase_windows: [PhaseWindow; 2],
    phase_window_n: usize,
    phase_fault: [Option<u8>; 2],
    /// The override the fallback applies, and when it began.
    fallback_pct: f64,
    fallback_since_s: f64,
    hold_latched: Option<HoldCause>,
    /// The latest command accepted since the host's Hello: a command must be newer.
    last_command_seq: Option<u32>,
    /// The override the CNC keeps once it ignores the bridge (injected).
    stuck_override: Option<OverrideCommand>,
    trace: Vec<DeviceTraceRow>,
    rng: Rng,
    stats: DeviceStats,
    stalled: bool,
    unplugged: bool,
    diagnostics: Vec<String>,
}

impl DeviceEmulator {
    /// An emulator of `config.preset`, powered on, waiting for a Hello.
    pub fn new(config: DeviceConfig) -> Result<Self, DeviceError> {
        let bad = |what: &str, v: f64| DeviceError(format!("{what} cannot be {v}"));
        let within = |v: f64, (lo, hi): (f64, f64)| v >= lo && v <= hi;
        let rate = |p: f64| within(p, FAULT_RATE_RANGE);
        let f = &config.faults;
        if !rate(f.drop_rate) {
            return Err(bad("the drop rate (0 to 1)", f.drop_rate));
        }
        if !rate(f.noise_rate) {
            return Err(bad("the noise rate (0 to 1)", f.noise_rate));
        }
        if !(f.stall_s.is_finite() && f.stall_s >= 0.0) {
            return Err(bad("the stall's length", f.stall_s));
        }
        if !(f.over_current_s.is_finite() && f.over_current_s >= 0.0) {
            return Err(bad("the over-current's length", f.over_current_s));
        }
        for t in [
            f.stall_at_s,
            f.unplug_at_s,
            f.estop_at_s,
            f.over_current_at_s,
        ]
        .into_iter()
        .flatten()
        {
            if !(t.is_finite() && t >= 0.0) {
                return Err(bad("a fault's time", t));
            }
        }
        for t in [f.sensor_open_at_s, f.stuck_override_at_s]
            .into_iter()
            .flatten()
        {
            if !(t.is_finite() && t >= 0.0) {
                return Err(bad("a fault's time", t));
            }
        }
        if !within(config.fallback_limit_s, FALLBACK_LIMIT_RANGE_S) {
            return Err(bad(
                "the fallback's time limit (0.1 to 65 s)",
                config.fallback_limit_s,
            ));
        }
        if !within(config.watchdog_timeout_s, WATCHDOG_RANGE_S) {
            return Err(bad(
                "the watchdog timeout (0.001 to 65 s)",
                config.watchdog_timeout_s,
            ));
        }
        if !(1..=1000).contains(&config.decimation) {
            return Err(DeviceError(format!(
                "the decimation must be 1 to 1000 plant samples, not {}",
                config.decimation
            )));
        }
        let mode = config.preset.override_mode();
        let max_pct = mode.max_pct();
        let min_pct = 0.0;
        if !(config.fallback_override_pct >= min_pct && config.fallback_override_pct <= max_pct) {
            return Err(bad("the fallback override", config.fallback_override_pct));
        }
        let mut parts = Self::machines(&config, 0)?;
        parts.reverse();
        let plant_rate_hz = parts.last().map_or(10_000.0, |m| m.sample_rate_hz());
        let (override_mode, dial_cpct) = match mode {
            OverrideMode::Dial(table) => {
                (OverrideModeCode::Dial16, table.percent_by_code.map(cpct))
            }
            OverrideMode::WholePercent => (OverrideModeCode::WholePercent, [0; 16]),
            OverrideMode::Continuous => (OverrideModeCode::Continuous, [0; 16]),
        };
        let capabilities = Capabilities {
            version_major: VERSION_MAJOR,
            version_minor: VERSION_MINOR,
            device_id: padded("cutlab-emulator"),
            program: padded(config.preset.name()),
            channel_mask: channel::SPINDLE_U
                | channel::SPINDLE_V
                | channel::SPINDLE_W
                | channel::FEED_U
                | channel::FEED_V
                | channel::FEED_W
                | channel::SPINDLE_FV,
            spindle_current_a_per_count: CURRENT_A_PER_COUNT as f32,
            feed_current_a_per_count: CURRENT_A_PER_COUNT as f32,
            fv_v_per_count: FV_V_PER_COUNT as f32,
            sample_rate_hz: (plant_rate_hz / config.decimation as f64) as f32,
            override_mode,
            min_override_cpct: cpct(min_pct),
            max_override_cpct: cpct(max_pct),
            dial_cpct,
            watchdog_timeout_ms: (config.watchdog_timeout_s * 1000.0).round() as u16,
            fallback_override_cpct: cpct(config.fallback_override_pct),
            over_current_a: config.over_current_a as f32,
            measured: config.measured,
            fallback_limit_ms: (config.fallback_limit_s * 1000.0).round() as u16,
            line_baud: config.line_baud,
            features: if config.sim_truth {
                feature::SIM_TRUTH
            } else {
                0
            } | if config.faults.estop_at_s.is_some() {
                feature::ESTOP_INPUT
            } else {
                0
            },
        };
        Ok(Self {
            rng: Rng::fork(config.seed, 0xDE71CE),
            capabilities,
            applied: mode.apply(
                DISARMED_OVERRIDE_PCT,
                AppliedOverride {
                    pct: DISARMED_OVERRIDE_PCT,
                    dial_code: None,
                },
            ),
            mode,
            min_pct,
            max_pct,
            plant_dt_s: 1.0 / plant_rate_hz,
            ticks: 0,
            decoder: Decoder::new(),
            next_parts: parts,
            part: None,
            armed: false,
            fallback: false,
            estop: false,
            requested: OverrideCommand::default(),
            last_host_frame_s: 0.0,
            next_heartbeat_s: 0.0,
            sample_seq: 0,
            fault_seq: 0,
            heartbeat_seq: 0,
            over_current: false,
            sensor_fault: false,
            phase_windows: [PhaseWindow::default(); 2],
            phase_window_n: 0,
            phase_fault: [None; 2],
            fallback_pct: config.fallback_override_pct,
            fallback_since_s: 0.0,
            hold_latched: None,
            last_command_seq: None,
            stuck_override: None,
            trace: Vec::new(),
            stats: DeviceStats::default(),
            stalled: false,
            unplugged: false,
            diagnostics: Vec::new(),
            config,
        })
    }

    /// The machines of parts `first` and `first + 1`, seeded as `cutlab sim` seeds its teach cut
    /// and run (for `first` = 0: [`Preset::teach_and_run_machines`]), or as runs with the seed
    /// plus the part's number. A bridge carries no dynamometer.
    fn machines(config: &DeviceConfig, first: u64) -> Result<Vec<Box<dyn Machine>>, DeviceError> {
        let seed = config.seed.wrapping_add(first);
        let edits = PlantEdits::default();
        let machines = if first == 0 {
            config
                .preset
                .teach_and_run_machines(seed, &edits, false)
                .map(Vec::from)
        } else {
            config
                .preset
                .seeded_machine(seed, &edits, false)
                .map(|m| vec![m])
        };
        machines.map_err(|e| DeviceError(format!("machine: {e}")))
    }

    /// What the device tells a host in its Capabilities.
    pub fn capabilities(&self) -> &Capabilities {
        &self.capabilities
    }

    /// The device clock.
    pub fn time_s(&self) -> f64 {
        self.ticks as f64 * self.plant_dt_s
    }

    /// The length of one sent sample.
    pub fn frame_period_s(&self) -> f64 {
        self.plant_dt_s * self.config.decimation as f64
    }

    /// What it counted.
    pub fn stats(&self) -> DeviceStats {
        self.stats
    }

    /// The decoder's counts of what the host sent.
    pub fn decoder_stats(&self) -> super::codec::DecoderStats {
        self.decoder.stats()
    }

    /// Diagnostic lines since the last call (for stderr).
    pub fn drain_diagnostics(&mut self) -> Vec<String> {
        std::mem::take(&mut self.diagnostics)
    }

    /// Whether the host holds the override (armed, and not in the watchdog's fallback).
    pub fn armed(&self) -> bool {
        self.armed && !self.fallback
    }

    /// Whether a part's program is running.
    pub fn in_cycle(&self) -> bool {
        self.part.as_ref().is_some_and(|p| !p.ended)
    }

    /// Whether the watchdog's fallback is applied.
    pub fn in_fallback(&self) -> bool {
        self.fallback
    }

    /// The override the bridge outputs now.
    pub fn applied_override_pct(&self) -> f64 {
        self.applied.pct
    }

    /// Whether the feed is held now (the E-stop, a latched hold, or the host's feed hold).
    pub fn feed_hold(&self) -> bool {
        self.estop
            || self.hold_latched.is_some()
            || (self.armed && !self.fallback && self.requested.feed_hold)
    }

    /// Why the feed is held, latched until the operator's reset, if it is.
    pub fn hold_latched(&self) -> Option<HoldCause> {
        self.hold_latched
    }

    /// The faults active now ([`fault_flag`] bits).
    pub fn fault_flags(&self) -> u8 {
        let mut faults = 0;
        for (on, bit) in [
            (self.sensor_fault, fault_flag::SENSOR),
            (self.over_current, fault_flag::OVER_CURRENT),
            (self.fallback, fault_flag::WATCHDOG),
            (self.estop, fault_flag::ESTOP),
            (
                self.hold_latched == Some(HoldCause::FallbackLimit),
                fault_flag::FALLBACK_LIMIT,
            ),
        ] {
            if on {
                faults |= bit;
            }
        }
        faults
    }

    /// The device's state as a Sample's flags, less the per-sample bits (spindle, program end).
    fn state_flags(&self) -> u8 {
        let mut flags = 0;
        for (on, bit) in [
            (self.in_cycle(), sample_flag::IN_CYCLE),
            (self.feed_hold(), sample_flag::FEED_HOLD),
            (self.armed && !self.fallback, sample_flag::ARMED),
            (self.fallback, sample_flag::FALLBACK),
            (self.estop, sample_flag::ESTOP),
            (self.hold_latched.is_some(), sample_flag::HOLD_LATCHED),
        ] {
            if on {
                flags |= bit;
            }
        }
        flags
    }

    /// The rows traced since the last call (with [`DeviceConfig::trace`]).
    pub fn take_trace(&mut self) -> Vec<DeviceTraceRow> {
        std::mem::take(&mut self.trace)
    }

    /// Latches the feed hold for `cause` (a hold already latched keeps its first cause).
    fn latch_hold(&mut self, cause: HoldCause) {
        if self.hold_latched.is_none() {
            self.hold_latched = Some(cause);
            self.log(format!(
                "feed hold latched ({}): it stays through any link state until the operator \
                 resets it",
                cause.name()
            ));
        }
    }

    /// Whether command `seq` is newer than the last one accepted since the Hello; it is then
    /// the last one.
    fn fresh_command(&mut self, seq: u32) -> bool {
        if let Some(last) = self.last_command_seq {
            let ahead = seq.wrapping_sub(last);
            if ahead == 0 || ahead >= 1 << 31 {
                return false;
            }
        }
        self.last_command_seq = Some(seq);
        true
    }

    fn log(&mut self, text: String) {
        let line = format!("device {:9.3} s: {text}", self.time_s());
        self.diagnostics.push(line);
    }

    fn time_us(&self) -> u32 {
        (self.time_s() * 1e6).round() as u64 as u32
    }

    /// Updates the stall and unplug state for the current time.
    fn update_link_faults(&mut self) {
        let t = self.time_s();
        let f = self.config.faults;
        let stalled = f.stall_at_s.is_some_and(|at| t >= at && t < at + f.stall_s);
        if stalled != self.stalled {
            self.stalled = stalled;
            self.log(if stalled {
                format!("receiver stalled for {} s (injected)", f.stall_s)
            } else {
                "receiver running again".to_string()
            });
        }
        let unplugged = f.unplug_at_s.is_some_and(|at| t >= at);
        if unplugged && !self.unplugged {
            self.unplugged = true;
            self.log("cable unplugged (injected): nothing goes in or out".to_string());
        }
    }

    /// Takes the bytes that arrived from the host; answers go into `out`.
    pub fn receive(&mut self, bytes: &[u8], out: &mut Vec<u8>) {
        self.update_link_faults();
        if self.stalled || self.unplugged {
            self.stats.bytes_discarded += bytes.len() as u64;
            return;
        }
        for &b in bytes {
            let Some(result) = self.decoder.push(b) else {
                continue;
            };
            let Ok(frame) = result else {
                continue;
            };
            if self.injected_loss() {
                continue;
            }
            self.stats.frames_received += 1;
            self.handle(frame, out);
        }
    }

    /// Whether injection loses or corrupts a received frame.
    fn injected_loss(&mut self) -> bool {
        let f = self.config.faults;
        if f.drop_rate > 0.0 && self.rng.uniform() < f.drop_rate {
            self.stats.frames_dropped += 1;
            return true;
        }
        if f.noise_rate > 0.0 && self.rng.uniform() < f.noise_rate {
            self.stats.frames_corrupted += 1;
            return true;
        }
        false
    }

    fn handle(&mut self, frame: Frame, out: &mut Vec<u8>) {
        let now = self.time_s();
        match frame {
            Frame::Hello(h) => {
                self.last_host_frame_s = now;
                // A new session (a host started, or restarted): its commands count from its own
                // first. A latched hold stays.
                self.last_command_seq = None;
                if h.version_major != VERSION_MAJOR {
                    self.log(format!(
                        "host speaks version {}.{}; answering with {VERSION_MAJOR}.{VERSION_MINOR}",
                        h.version_major, h.version_minor
                    ));
                }
                let caps = self.capabilities;
                self.send(&Frame::Capabilities(caps), out);
            }
            Frame::Heartbeat(_) => self.last_host_frame_s = now,
            Frame::Arm(a) => {
                let result = if !self.fresh_command(a.seq) {
                    AckResult::Stale
                } else if self.estop {
                    self.last_host_frame_s = now;
                    AckResult::Refused
                } else {
                    self.last_host_frame_s = now;
                    if self.fallback {
                        self.fallback = false;
                        self.log("re-armed by the host: watchdog fallback cleared".to_string());
                        self.report_fault(FaultKind::Watchdog, false, NO_CHANNEL, out);
                    }
                    self.armed = true;
                    if !self.in_cycle() {
                        self.start_part();
                    }
                    AckResult::Applied
                };
                self.ack(a.seq, FrameType::Arm, result, out);
            }
            Frame::Disarm(d) => {
                let result = if self.fresh_command(d.seq) {
                    self.last_host_frame_s = now;
                    self.armed = false;
                    self.requested = OverrideCommand::default();
                    self.apply_override();
                    AckResult::Applied
                } else {
                    AckResult::Stale
                };
                self.ack(d.seq, FrameType::Disarm, result, out);
            }
            Frame::Reset(r) => {
                let result = if !self.fresh_command(r.seq) {
                    AckResult::Stale
                } else if self.hold_latched.is_some() && (self.over_current || self.estop) {
                    self.last_host_frame_s = now;
                    AckResult::CauseActive
                } else {
                    self.last_host_frame_s = now;
                    if let Some(cause) = self.hold_latched.take() {
                        self.requested.feed_hold = false;
                        // Still without a host, the fallback runs for its time limit again.
                        self.fallback_since_s = now;
                        self.log(format!(
                            "the operator reset the latched feed hold ({})",
                            cause.name()
                        ));
                        if cause == HoldCause::FallbackLimit {
                            self.report_fault(FaultKind::FallbackLimit, false, NO_CHANNEL, out);
                        }
                    }
                    AckResult::Applied
                };
                self.ack(r.seq, FrameType::Reset, result, out);
            }
            Frame::SetOverride(c) => {
                let age_us = self.time_us().wrapping_sub(c.sample_time_us);
                let max_age_us = u32::from(self.capabilities.watchdog_timeout_ms) * 1000;
                let result = if !self.fresh_command(c.seq) || age_us > max_age_us {
                    // A replayed or reordered frame, or a decision on a sample too old to
                    // stand for the machine now: neither applied nor feeding the watchdog.
                    AckResult::Stale
                } else if self.estop {
                    self.last_host_frame_s = now;
                    AckResult::Refused
                } else if !self.armed || self.fallback {
                    self.last_host_frame_s = now;
                    AckResult::NotArmed
                } else {
                    self.last_host_frame_s = now;
                    let pct = f64::from(c.override_cpct) / 100.0;
                    let limited = pct.clamp(self.min_pct, self.max_pct);
                    let feed_hold = c.flags & command_flag::FEED_HOLD != 0;
                    self.requested = OverrideCommand {
                        override_pct: limited,
                        feed_hold,
                    };
                    if feed_hold {
                        self.latch_hold(HoldCause::Host);
                    }
                    self.apply_override();
                    if limited != pct {
                        AckResult::Limited
                    } else {
                        AckResult::Applied
                    }
                };
                self.ack(c.seq, FrameType::SetOverride, result, out);
            }
            // Frames a device sends: a host has no business sending them.
            other => self.log(format!(
                "ignored a {} frame from the host",
                other.frame_type().name()
            )),
        }
    }

    /// The override the machine gets now: the host's while armed, the fallback after the
    /// watchdog, the machine's own dial otherwise.
    fn apply_override(&mut self) {
        let pct = if self.fallback {
            self.fallback_pct
        } else if self.armed {
            self.requested.override_pct
        } else {
            DISARMED_OVERRIDE_PCT
        };
        self.applied = self.mode.apply(pct, self.applied);
    }

    fn start_part(&mut self) {
        if self.next_parts.is_empty() {
            match Self::machines(&self.config, self.stats.parts) {
                Ok(mut m) => self.next_parts.append(&mut m),
                Err(e) => {
                    self.log(format!("cannot load the next part: {e}"));
                    return;
                }
            }
        }
        let Some(machine) = self.next_parts.pop() else {
            return;
        };
        self.stats.parts += 1;
        let n = self.stats.parts;
        self.log(format!("part {n}: cycle start"));
        self.part = Some(Part {
            machine,
            ended: false,
        });
    }

    fn ack(&mut self, seq: u32, command: FrameType, result: AckResult, out: &mut Vec<u8>) {
        let ack = Ack {
            seq,
            command: command as u8,
            result,
            applied_override_cpct: cpct(self.applied.pct),
            flags: if self.feed_hold() {
                command_flag::FEED_HOLD
            } else {
                0
            } | if self.hold_latched.is_some() {
                command_flag::HOLD_LATCHED
            } else {
                0
            },
        };
        self.send(&Frame::Ack(ack), out);
    }

    fn report_fault(&mut self, kind: FaultKind, active: bool, channel: u8, out: &mut Vec<u8>) {
        self.fault_seq = self.fault_seq.wrapping_add(1);
        let fault = Fault {
            seq: self.fault_seq,
            time_us: self.time_us(),
            kind,
            active: u8::from(active),
            channel,
            applied_override_cpct: cpct(self.applied.pct),
        };
        self.send(&Frame::Fault(fault), out);
    }

    /// Encodes `frame` into `out`, through the injected faults.
    fn send(&mut self, frame: &Frame, out: &mut Vec<u8>) {
        if self.unplugged {
            return;
        }
        self.stats.frames_sent += 1;
        let f = self.config.faults;
        if f.drop_rate > 0.0 && self.rng.uniform() < f.drop_rate {
            self.stats.frames_dropped += 1;
            return;
        }
        let mut buf = [0u8; MAX_FRAME_LEN];
        let Ok(n) = encode_frame(frame, &mut buf) else {
            return;
        };
        let bytes = buf.get_mut(..n).unwrap_or_default();
        if f.noise_rate > 0.0 && self.rng.uniform() < f.noise_rate && n > 2 {
            // A bit flipped anywhere between the delimiters.
            let i = 1 + (self.rng.next_u64() % (n as u64 - 2)) as usize;
            let bit = (self.rng.next_u64() % 8) as u8;
            if let Some(b) = bytes.get_mut(i) {
                *b ^= 1 << bit;
            }
            self.stats.frames_corrupted += 1;
        }
        out.extend_from_slice(bytes);
    }

    /// Runs one sample period: the machine (if a part is in), the watchdog, heartbeats; the
    /// frames to send go into `out`.
    pub fn step_frame(&mut self, out: &mut Vec<u8>) {
        self.update_link_faults();
        let start_s = self.time_s();
        if !self.estop
            && self
                .config
                .faults
                .estop_at_s
                .is_some_and(|at| start_s >= at)
        {
            self.estop = true;
            self.apply_override();
            self.log(
                "E-stop input active (injected): the feed stops; commands refused".to_string(),
            );
            self.report_fault(FaultKind::EStop, true, NO_CHANNEL, out);
        }
        if self.armed
            && !self.fallback
            && start_s - self.last_host_frame_s > self.config.watchdog_timeout_s
        {
            // Never faster than the loop left it: the fallback is the lower of the override
            // applied now and the configured one.
            self.fallback_pct = self.applied.pct.min(self.config.fallback_override_pct);
            self.fallback = true;
            self.fallback_since_s = start_s;
            self.stats.watchdog_fallbacks += 1;
            self.apply_override();
            self.log(format!(
                "watchdog: nothing from the host for {} s; fallback override {} % (the lower of \
                 the applied and the configured {} %) until the host re-arms, for at most {} s",
                self.config.watchdog_timeout_s,
                self.applied.pct,
                self.config.fallback_override_pct,
                self.config.fallback_limit_s
            ));
            self.report_fault(FaultKind::Watchdog, true, NO_CHANNEL, out);
        }
        if self.fallback
            && self.hold_latched.is_none()
            && start_s - self.fallback_since_s >= self.config.fallback_limit_s
        {
            self.latch_hold(HoldCause::FallbackLimit);
            self.report_fault(FaultKind::FallbackLimit, true, NO_CHANNEL, out);
        }
        if self.in_cycle() {
            self.run_block(out);
        } else {
            self.ticks += self.config.decimation as u64;
        }
        if self.time_s() >= self.next_heartbeat_s {
            self.next_heartbeat_s = self.time_s() + HEARTBEAT_INTERVAL_S;
            self.heartbeat_seq = self.heartbeat_seq.wrapping_add(1);
            let hb = Heartbeat {
                seq: self.heartbeat_seq,
                time_us: self.time_us(),
                flags: self.state_flags(),
                faults: self.fault_flags(),
                last_sample_seq: self.sample_seq,
            };
            self.send(&Frame::Heartbeat(hb), out);
        }
    }

    /// One block of plant samples, summarised into a SimTruth and a Sample.
    fn run_block(&mut self, out: &mut Vec<u8>) {
        let f = self.config.faults;
        let t0 = self.time_s();
        if self.stuck_override.is_none() && f.stuck_override_at_s.is_some_and(|at| t0 >= at) {
            self.log("the CNC ignores the bridge's outputs from now on (injected)".to_string());
            self.stuck_override = Some(OverrideCommand {
                override_pct: self.applied.pct,
                feed_hold: false,
            });
        }
        let feed_hold = self.feed_hold();
        // What the CNC takes: the bridge's outputs, or what it kept when it stopped listening
        // (a feed hold still reaches it through its own contact in the feed-hold chain).
        let command = OverrideCommand {
            override_pct: self
                .stuck_override
                .map_or(self.applied.pct, |c| c.override_pct),
            feed_hold,
        };
        let sensor_open = f.sensor_open_at_s.is_some_and(|at| t0 >= at);
        let window_n = ((PHASE_CHECK_WINDOW_S / self.plant_dt_s).round() as usize).max(1);
        let mut block = SampleSums::default();
        let mut over_current = false;
        let mut non_finite = false;
        let mut ended = false;
        let limit = self.config.over_current_a;
        if let Some(part) = self.part.as_mut() {
            for _ in 0..self.config.decimation {
                let step = part.machine.step(command);
                self.ticks += 1;
                let s = step.sensors;
                let mut spindle = s.spindle_phase_currents_a;
                if sensor_open {
                    spindle[0] = 0.0;
                }
                for (sum, i) in block.spindle.iter_mut().zip(spindle) {
                    *sum += i;
                }
                for (sum, i) in block.feed.iter_mut().zip(s.feed_phase_currents_a) {
                    *sum += i;
                }
                for i in spindle.iter().chain(&s.feed_phase_currents_a) {
                    non_finite |= !i.is_finite();
                    over_current |= i.abs() > limit;
                }
                self.phase_windows[0].add(spindle);
                self.phase_windows[1].add(s.feed_phase_currents_a);
                self.phase_window_n += 1;
                if self.phase_window_n >= window_n {
                    judge_phases(
                        &mut self.phase_windows,
                        &mut self.phase_window_n,
                        &mut self.phase_fault,
                    );
                }
                block.fv += s.spindle_fv_voltage_v;
                block.speed += s.spindle_speed_rpm;
                block.feed_mm_min += s.feed_mm_min;
                block.last = s;
                if let Some(t) = step.truth {
                    for (sum, v) in block.truth.iter_mut().zip(t.wire_values()) {
                        *sum += v;
                    }
                    block.last_truth = t;
                    block.truth_seen = true;
                }
                block.n += 1;
                if part.machine.finished() {
                    part.ended = true;
                    ended = true;
                    break;
                }
            }
        }
        let t = self.time_s();
        over_current |= f
            .over_current_at_s
            .is_some_and(|at| t > at && t <= at + f.over_current_s);
        self.watch_currents(over_current, non_finite, out);
        let n = block.n.max(1) as f64;
        self.sample_seq = self.sample_seq.wrapping_add(1);
        if block.truth_seen && self.config.sim_truth {
            let mut mean = PlantTruth::from_wire_values(block.truth.map(|sum| sum / n));
            // Positions are where the tool is at the block's end, not on average.
            let last = &block.last_truth;
            mean.path_position_mm = last.path_position_mm;
            mean.tool_x_mm = last.tool_x_mm;
            mean.tool_y_mm = last.tool_y_mm;
            let v = mean.wire_values().map(|value| value as f32);
            self.send(
                &Frame::SimTruth(SimTruth::from_values(self.sample_seq, v)),
                out,
            );
        }
        let last = block.last;
        let mut flags = sample_flag::IN_CYCLE | (self.state_flags() & !sample_flag::IN_CYCLE);
        for (on, bit) in [
            (last.spindle_running, sample_flag::SPINDLE_RUNNING),
            (ended, sample_flag::PROGRAM_END),
        ] {
            if on {
                flags |= bit;
            }
        }
        let faults = self.fault_flags();
        let sample = Sample {
            seq: self.sample_seq,
            time_us: self.time_us(),
            flags,
            spindle_current_counts: block.spindle.map(|i| counts(i / n, CURRENT_A_PER_COUNT)),
            feed_current_counts: block.feed.map(|i| counts(i / n, CURRENT_A_PER_COUNT)),
            fv_counts: counts(block.fv / n, FV_V_PER_COUNT),
            spindle_speed_rpm: (block.speed / n) as f32,
            spindle_command_rpm: last.spindle_command_rpm as f32,
            programmed_feed_mm_min: last.programmed_feed_mm_min as f32,
            feed_mm_min: (block.feed_mm_min / n) as f32,
            applied_override_cpct: cpct(last.applied_override_pct),
            dial_code: self.applied.dial_code.unwrap_or(NO_DIAL_CODE),
            faults,
        };
        self.send(&Frame::Sample(sample), out);
        if self.config.trace {
            self.trace.push(DeviceTraceRow {
                time_s: t,
                part: self.stats.parts,
                seq: self.sample_seq,
                armed: self.armed && !self.fallback,
                fallback: self.fallback,
                feed_hold,
                hold_latched: self.hold_latched,
                bridge_override_pct: self.applied.pct,
                cnc_override_pct: last.applied_override_pct,
                programmed_feed_mm_min: last.programmed_feed_mm_min,
                feed_mm_min: block.feed_mm_min / n,
                faults,
            });
        }
        if ended {
            let n = self.stats.parts;
            self.log(format!("part {n}: program end"));
            self.part = None;
        }
    }

    fn watch_currents(&mut self, over_current: bool, non_finite: bool, out: &mut Vec<u8>) {
        if over_current != self.over_current {
            self.over_current = over_current;
            if over_current {
                self.latch_hold(HoldCause::OverCurrent);
            }
            self.report_fault(FaultKind::OverCurrent, over_current, NO_CHANNEL, out);
        }
        let channel = self.phase_fault.iter().flatten().next().copied();
        let sensor_fault = non_finite || channel.is_some();
        if sensor_fault != self.sensor_fault {
            self.sensor_fault = sensor_fault;
            if let Some(c) = channel {
                self.log(format!(
                    "sensor fault on channel {c}: the drive's three phases do not sum to zero \
                     (an open or stuck transducer)"
                ));
            }
            self.report_fault(
                FaultKind::Sensor,
                sensor_fault,
                channel.unwrap_or(NO_CHANNEL),
                out,
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::frame::{Arm, Hello, SetOverride};

    fn frames(bytes: &[u8]) -> Vec<Frame> {
        Decoder::new()
            .frames(bytes)
            .filter_map(Result::ok)
            .collect()
    }

    fn bytes_of(frame: Frame) -> Vec<u8> {
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&frame, &mut buf).unwrap();
        buf[..n].to_vec()
    }

    #[test]
    fn hello_gets_capabilities_and_arm_starts_a_part_that_streams_samples() {
        let mut d = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
        let mut out = Vec::new();
        d.receive(
            &bytes_of(Frame::Hello(Hello {
                version_major: 1,
                version_minor: 0,
            })),
            &mut out,
        );
        let Some(Frame::Capabilities(c)) = frames(&out).first().copied() else {
            panic!("no capabilities")
        };
        assert_eq!(c.sample_rate_hz, 1000.0);
        assert_eq!(c.override_mode, OverrideModeCode::WholePercent);
        out.clear();
        d.receive(&bytes_of(Frame::Arm(Arm { seq: 1 })), &mut out);
        assert!(d.in_cycle());
        d.receive(
            &bytes_of(Frame::SetOverride(SetOverride {
                seq: 2,
                override_cpct: 8760,
                flags: 0,
                sample_time_us: 0,
            })),
            &mut out,
        );
        let acks: Vec<_> = frames(&out)
            .into_iter()
            .filter_map(|f| match f {
                Frame::Ack(a) => Some(a),
                _ => None,
            })
            .collect();
        // Whole percent: 87.6 % applies as 88 %.
        assert_eq!(acks[1].applied_override_cpct, 8800);
        out.clear();
        for _ in 0..10 {
            d.step_frame(&mut out);
        }
        let samples: Vec<_> = frames(&out)
            .into_iter()
            .filter_map(|f| match f {
                Frame::Sample(s) => Some(s),
                _ => None,
            })
            .collect();
        assert_eq!(samples.len(), 10);
        assert_eq!(samples[9].seq, 10);
        assert_eq!(samples[9].time_us, 10_000);
    }

    #[test]
    fn the_watchdog_falls_back_without_the_host_and_only_an_arm_clears_it() {
        let mut d = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
        let mut out = Vec::new();
        d.receive(&bytes_of(Frame::Arm(Arm { seq: 1 })), &mut out);
        for _ in 0..600 {
            d.step_frame(&mut out);
        }
        assert_eq!(d.stats().watchdog_fallbacks, 1);
        let faults: Vec<_> = frames(&out)
            .into_iter()
            .filter_map(|f| match f {
                Frame::Fault(f) => Some(f),
                _ => None,
            })
            .collect();
        assert_eq!(faults[0].kind, FaultKind::Watchdog);
        assert_eq!(faults[0].applied_override_cpct, 5000);
        out.clear();
        d.receive(
            &bytes_of(Frame::SetOverride(SetOverride {
                seq: 2,
                override_cpct: 12000,
                flags: 0,
                sample_time_us: (d.time_s() * 1e6) as u32,
            })),
            &mut out,
        );
        let Some(Frame::Ack(a)) = frames(&out).first().copied() else {
            panic!()
        };
        assert_eq!(
            (a.result, a.applied_override_cpct),
            (AckResult::NotArmed, 5000)
        );
        out.clear();
        d.receive(&bytes_of(Frame::Arm(Arm { seq: 3 })), &mut out);
        let got = frames(&out);
        assert!(got
            .iter()
            .any(|f| matches!(f, Frame::Fault(x) if x.active == 0)));
    }

    #[test]
    fn an_over_current_is_reported_raised_and_cleared() {
        let mut config = DeviceConfig::new(Preset::KimStepDoc);
        // The spindle's starting current peaks near 70 A; running idle, about 12 A.
        config.over_current_a = 30.0;
        let mut d = DeviceEmulator::new(config).unwrap();
        let mut out = Vec::new();
        d.receive(&bytes_of(Frame::Arm(Arm { seq: 1 })), &mut out);
        let mut faults = Vec::new();
        for _ in 0..3000 {
            // Keep the watchdog fed.
            d.receive(
                &bytes_of(Frame::Heartbeat(
                    crate::protocol::frame::Heartbeat::default(),
                )),
                &mut out,
            );
            d.step_frame(&mut out);
            faults.extend(frames(&out).into_iter().filter_map(|f| match f {
                Frame::Fault(f) => Some((f.kind, f.active)),
                _ => None,
            }));
            out.clear();
        }
        assert_eq!(
            faults.first().copied(),
            Some((FaultKind::OverCurrent, 1)),
            "{faults:?}"
        );
        assert!(faults.contains(&(FaultKind::OverCurrent, 0)), "{faults:?}");
        assert_eq!(d.stats().watchdog_fallbacks, 0);
    }

    #[test]
    fn any_bytes_from_the_host_are_survived() {
        let mut d = DeviceEmulator::new(DeviceConfig::new(Preset::KimStepDoc)).unwrap();
        let mut rng = Rng::seed_from(5);
        let mut out = Vec::new();
        for _ in 0..200 {
            let junk: Vec<u8> = (0..300).map(|_| rng.next_u64() as u8).collect();
            d.receive(&junk, &mut out);
            d.step_frame(&mut out);
        }
        assert!(d.decoder_stats().bytes_dropped > 0);
    }
}
