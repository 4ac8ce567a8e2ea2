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
//! * **Parts.** The machines are made by the code `cutlab sim` uses ([`RunMachines::for_preset`]):
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
    channel, command_flag, feature, padded, sample_flag, Ack, AckResult, Capabilities, Fault,
    FaultKind, Frame, FrameType, Heartbeat, OverrideModeCode, Sample, SimTruth, NO_DIAL_CODE,
    VERSION_MAJOR, VERSION_MINOR,
};
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::RunMachines;
use crate::control::registry::ControllerKind;
use crate::machine::{Machine, OverrideCommand, PlantTruth, SensorSample};
use crate::plant::cnc::{AppliedOverride, OverrideMode};
use crate::plant::Preset;
use crate::rng::Rng;

/// Amperes per count of the emulator's current channels.
pub const CURRENT_A_PER_COUNT: f64 = 0.005;
/// Volts per count of the emulator's F/V channel.
pub const FV_V_PER_COUNT: f64 = 0.0005;
/// The override of a disarmed device: the machine's own dial.
pub const DISARMED_OVERRIDE_PCT: f64 = 100.0;
/// How often the device sends a heartbeat, device time.
pub const HEARTBEAT_INTERVAL_S: f64 = 0.1;

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
    /// The override the watchdog applies.
    pub fallback_override_pct: f64,
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
    /// The defaults for `preset`: seed 1, 1 kHz samples, watchdog 0.5 s, fallback 50 %,
    /// over-current at 150 A, no injected faults.
    pub fn new(preset: Preset) -> Self {
        Self {
            preset,
            seed: 1,
            decimation: 10,
            watchdog_timeout_s: 0.5,
            fallback_override_pct: 50.0,
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
struct Block {
    n: usize,
    spindle: [f64; 3],
    feed: [f64; 3],
    fv: f64,
    speed: f64,
    feed_mm_min: f64,
    truth: [f64; 16],
    last: SensorSample,
    last_truth: PlantTruth,
    truth_seen: bool,
}

fn truth_values(t: &PlantTruth) -> [f64; 16] {
    [
        t.force_x_n,
        t.force_y_n,
        t.force_z_n,
        t.force_resultant_n,
        t.feed_force_n,
        t.spindle_torque_nm,
        t.cutting_power_w,
        t.depth_mm,
        t.width_mm,
        t.feed_per_tooth_mm,
        t.path_position_mm,
        t.material_removal_mm3_s,
        t.tool_x_mm,
        t.tool_y_mm,
        t.feed_current_rms_a,
        t.spindle_current_rms_a,
    ]
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
        let rate = |p: f64| p.is_finite() && (0.0..=1.0).contains(&p);
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
        if !(config.watchdog_timeout_s > 0.0 && config.watchdog_timeout_s <= 65.0) {
            return Err(bad(
                "the watchdog timeout (0 to 65 s)",
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
            stats: DeviceStats::default(),
            stalled: false,
            unplugged: false,
            diagnostics: Vec::new(),
            config,
        })
    }

    /// The machines of parts `first` and `first + 1`, seeded as `cutlab sim` seeds its teach cut
    /// and run (for `first` = 0), or as runs with the seed plus the part's number.
    fn machines(config: &DeviceConfig, first: u64) -> Result<Vec<Box<dyn Machine>>, DeviceError> {
        let mut spec = RunSpec::new(config.preset, ControllerKind::Fixed);
        spec.seed = config.seed.wrapping_add(first);
        let machines =
            RunMachines::for_preset(&spec).map_err(|e| DeviceError(format!("machine: {e}")))?;
        Ok(match machines {
            RunMachines::Separate { teach, run } if first == 0 => vec![teach, run],
            RunMachines::Separate { run, .. } => vec![run],
            RunMachines::Shared(m) => vec![m],
        })
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
                self.last_host_frame_s = now;
                let result = if self.estop {
                    AckResult::Refused
                } else {
                    if self.fallback {
                        self.fallback = false;
                        self.log("re-armed by the host: watchdog fallback cleared".to_string());
                        self.report_fault(FaultKind::Watchdog, false, out);
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
                self.last_host_frame_s = now;
                self.armed = false;
                self.requested = OverrideCommand::default();
                self.apply_override();
                self.ack(d.seq, FrameType::Disarm, AckResult::Applied, out);
            }
            Frame::SetOverride(c) => {
                self.last_host_frame_s = now;
                let result = if self.estop {
                    AckResult::Refused
                } else if !self.armed || self.fallback {
                    AckResult::NotArmed
                } else {
                    let pct = f64::from(c.override_cpct) / 100.0;
                    let limited = pct.clamp(self.min_pct, self.max_pct);
                    self.requested = OverrideCommand {
                        override_pct: limited,
                        feed_hold: c.flags & command_flag::FEED_HOLD != 0,
                    };
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
            self.config.fallback_override_pct
        } else if self.armed {
            self.requested.override_pct
        } else {
            DISARMED_OVERRIDE_PCT
        };
        self.applied = self.mode.apply(pct, self.applied);
    }

    /// The feed is held while the E-stop input is active (the control stops the axes), and
    /// while the host asks for it.
    fn feed_hold(&self) -> bool {
        self.estop || (self.armed && !self.fallback && self.requested.feed_hold)
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
            },
        };
        self.send(&Frame::Ack(ack), out);
    }

    fn report_fault(&mut self, kind: FaultKind, active: bool, out: &mut Vec<u8>) {
        self.fault_seq = self.fault_seq.wrapping_add(1);
        let fault = Fault {
            seq: self.fault_seq,
            time_us: self.time_us(),
            kind,
            active: u8::from(active),
            channel: 0xFF,
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
            self.report_fault(FaultKind::EStop, true, out);
        }
        if self.armed
            && !self.fallback
            && start_s - self.last_host_frame_s > self.config.watchdog_timeout_s
        {
            self.fallback = true;
            self.stats.watchdog_fallbacks += 1;
            self.apply_override();
            self.log(format!(
                "watchdog: nothing from the host for {} s; fallback override {} % applied until \
                 the host re-arms",
                self.config.watchdog_timeout_s, self.applied.pct
            ));
            self.report_fault(FaultKind::Watchdog, true, out);
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
            };
            self.send(&Frame::Heartbeat(hb), out);
        }
    }

    /// One block of plant samples, summarised into a SimTruth and a Sample.
    fn run_block(&mut self, out: &mut Vec<u8>) {
        let command = OverrideCommand {
            override_pct: self.applied.pct,
            feed_hold: self.feed_hold(),
        };
        let mut block = Block::default();
        let mut over_current = false;
        let mut sensor_fault = false;
        let mut ended = false;
        let limit = self.config.over_current_a;
        if let Some(part) = self.part.as_mut() {
            for _ in 0..self.config.decimation {
                let step = part.machine.step(command);
                self.ticks += 1;
                let s = step.sensors;
                for (sum, i) in block.spindle.iter_mut().zip(s.spindle_phase_currents_a) {
                    *sum += i;
                }
                for (sum, i) in block.feed.iter_mut().zip(s.feed_phase_currents_a) {
                    *sum += i;
                }
                for i in s
                    .spindle_phase_currents_a
                    .iter()
                    .chain(&s.feed_phase_currents_a)
                {
                    sensor_fault |= !i.is_finite();
                    over_current |= i.abs() > limit;
                }
                block.fv += s.spindle_fv_voltage_v;
                block.speed += s.spindle_speed_rpm;
                block.feed_mm_min += s.feed_mm_min;
                block.last = s;
                if let Some(t) = step.truth {
                    for (sum, v) in block.truth.iter_mut().zip(truth_values(&t)) {
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
        let f = self.config.faults;
        let t = self.time_s();
        over_current |= f
            .over_current_at_s
            .is_some_and(|at| t > at && t <= at + f.over_current_s);
        self.watch_currents(over_current, sensor_fault, out);
        let n = block.n.max(1) as f64;
        self.sample_seq = self.sample_seq.wrapping_add(1);
        if block.truth_seen && self.config.sim_truth {
            let mut v: [f32; 16] = core::array::from_fn(|i| (block.truth[i] / n) as f32);
            // Positions are where the tool is at the block's end, not on average.
            let t = &block.last_truth;
            v[10] = t.path_position_mm as f32;
            v[12] = t.tool_x_mm as f32;
            v[13] = t.tool_y_mm as f32;
            self.send(
                &Frame::SimTruth(SimTruth::from_values(self.sample_seq, v)),
                out,
            );
        }
        let last = block.last;
        let mut flags = sample_flag::IN_CYCLE;
        for (on, bit) in [
            (last.spindle_running, sample_flag::SPINDLE_RUNNING),
            (ended, sample_flag::PROGRAM_END),
            (command.feed_hold, sample_flag::FEED_HOLD),
            (self.armed && !self.fallback, sample_flag::ARMED),
            (self.fallback, sample_flag::FALLBACK),
            (self.estop, sample_flag::ESTOP),
        ] {
            if on {
                flags |= bit;
            }
        }
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
        };
        self.send(&Frame::Sample(sample), out);
        if ended {
            let n = self.stats.parts;
            self.log(format!("part {n}: program end"));
            self.part = None;
        }
    }

    fn watch_currents(&mut self, over_current: bool, sensor_fault: bool, out: &mut Vec<u8>) {
        if over_current != self.over_current {
            self.over_current = over_current;
            self.report_fault(FaultKind::OverCurrent, over_current, out);
        }
        if sensor_fault != self.sensor_fault {
            self.sensor_fault = sensor_fault;
            self.report_fault(FaultKind::Sensor, sensor_fault, out);
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
                &bytes_of(Frame::Heartbeat(crate::protocol::frame::Heartbeat {
                    seq: 1,
                    time_us: 0,
                })),
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
