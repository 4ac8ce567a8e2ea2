//! The frames of the feed-override protocol and their byte layouts (docs/protocol.md is the
//! specification; this file is its implementation, shared by the host and a bridge's firmware).
//!
//! A frame's payload is one type byte followed by its fields, little-endian, packed, in the order
//! the structs below list them. `f32` is IEEE 754 binary32. Overrides travel in hundredths of a
//! percent (`…_cpct`, 10 000 = 100 %), currents and the F/V voltage as signed ADC counts scaled by
//! the device's [`Capabilities`].
//!
//! Versioning: a minor protocol version may append fields to a frame and add frame types. A
//! decoder therefore accepts a payload longer than it knows (and ignores the tail), rejects one
//! shorter ([`FrameError::Short`]), and reports an unknown type ([`FrameError::UnknownType`]) for
//! the caller to skip. Unknown flag bits are ignored.
//!
//! `core` only, no allocation, no panic on any bytes.

use crate::truth_fields::TRUTH_VALUES;

/// The protocol's major version: a host refuses a device of another major version.
pub const VERSION_MAJOR: u8 = 2;
/// The protocol's minor version: additions a host of a lower minor ignores.
pub const VERSION_MINOR: u8 = 0;

/// The largest payload (type byte and fields, without the CRC) a receiver must accept.
pub const MAX_PAYLOAD_LEN: usize = 250;

/// Length of the text fields of [`Capabilities`].
pub const DEVICE_ID_LEN: usize = 16;
/// Length of [`Capabilities::program`].
pub const PROGRAM_LEN: usize = 24;

/// Every frame type and its code (the payload's first byte).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameType {
    /// Host → device: start of a session.
    Hello = 0x01,
    /// Device → host: the answer to Hello.
    Capabilities = 0x02,
    /// Device → host: one sensor sample.
    Sample = 0x10,
    /// Device → host, simulation only: what only a simulated machine knows, for one sample.
    SimTruth = 0x11,
    /// Host → device: the feed override to apply.
    SetOverride = 0x20,
    /// Host → device: take control of the override (and, on the emulator, start a part).
    Arm = 0x21,
    /// Host → device: hand the override back to the machine's own dial.
    Disarm = 0x22,
    /// Host → device: the operator resets a latched feed hold.
    Reset = 0x23,
    /// Device → host: a host command was received, with what the device applied.
    Ack = 0x30,
    /// Device → host: a fault was raised or cleared.
    Fault = 0x31,
    /// Either way: I am alive.
    Heartbeat = 0x40,
}

impl FrameType {
    /// Every frame type, in code order.
    pub const ALL: [FrameType; 11] = [
        FrameType::Hello,
        FrameType::Capabilities,
        FrameType::Sample,
        FrameType::SimTruth,
        FrameType::SetOverride,
        FrameType::Arm,
        FrameType::Disarm,
        FrameType::Reset,
        FrameType::Ack,
        FrameType::Fault,
        FrameType::Heartbeat,
    ];

    /// The type of code `code`.
    pub fn from_code(code: u8) -> Option<Self> {
        Self::ALL.into_iter().find(|t| *t as u8 == code)
    }

    /// The name in docs and in `cutlab protocol` JSON.
    pub fn name(self) -> &'static str {
        match self {
            FrameType::Hello => "hello",
            FrameType::Capabilities => "capabilities",
            FrameType::Sample => "sample",
            FrameType::SimTruth => "sim-truth",
            FrameType::SetOverride => "set-override",
            FrameType::Arm => "arm",
            FrameType::Disarm => "disarm",
            FrameType::Reset => "reset",
            FrameType::Ack => "ack",
            FrameType::Fault => "fault",
            FrameType::Heartbeat => "heartbeat",
        }
    }

    /// The type named `name`.
    pub fn from_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|t| t.name() == name)
    }

    /// The payload length of this version's layout (type byte included).
    pub const fn payload_len(self) -> usize {
        match self {
            FrameType::Hello => 3,
            FrameType::Capabilities => 114,
            FrameType::Sample => 44,
            FrameType::SimTruth => 69,
            FrameType::SetOverride => 12,
            FrameType::Arm | FrameType::Disarm | FrameType::Reset => 5,
            FrameType::Ack => 10,
            FrameType::Fault => 14,
            FrameType::Heartbeat => 15,
        }
    }
}

/// Host → device: the host's protocol version. The device answers with [`Capabilities`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Hello {
    /// The host's major version.
    pub version_major: u8,
    /// The host's minor version.
    pub version_minor: u8,
}

/// How the device sets the CNC's override.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum OverrideModeCode {
    /// A 16-grade dial code on four PMC inputs (FANUC: X20.7, X20.4, X20.3, X20.2), each code's
    /// percentage in [`Capabilities::dial_cpct`].
    Dial16,
    /// Whole percent (an 8-bit 0–255 % override, paper 003).
    WholePercent,
    /// Any value (an analogue or serial override).
    Continuous,
    /// A code this version does not know.
    Other(u8),
}

impl OverrideModeCode {
    /// The wire code.
    pub fn code(self) -> u8 {
        match self {
            OverrideModeCode::Dial16 => 0,
            OverrideModeCode::WholePercent => 1,
            OverrideModeCode::Continuous => 2,
            OverrideModeCode::Other(c) => c,
        }
    }

    /// The mode of wire code `code`.
    pub fn from_code(code: u8) -> Self {
        match code {
            0 => OverrideModeCode::Dial16,
            1 => OverrideModeCode::WholePercent,
            2 => OverrideModeCode::Continuous,
            c => OverrideModeCode::Other(c),
        }
    }
}

/// [`Capabilities::channel_mask`] bits: spindle phases u, v, w; feed phases u, v, w; F/V voltage.
pub mod channel {
    /// Spindle phase u.
    pub const SPINDLE_U: u8 = 1 << 0;
    /// Spindle phase v.
    pub const SPINDLE_V: u8 = 1 << 1;
    /// Spindle phase w.
    pub const SPINDLE_W: u8 = 1 << 2;
    /// Feed-drive phase u.
    pub const FEED_U: u8 = 1 << 3;
    /// Feed-drive phase v.
    pub const FEED_V: u8 = 1 << 4;
    /// Feed-drive phase w.
    pub const FEED_W: u8 = 1 << 5;
    /// The spindle's frequency-to-voltage converter.
    pub const SPINDLE_FV: u8 = 1 << 6;
}

/// [`Capabilities::features`] bits.
pub mod feature {
    /// The device sends a [`super::SimTruth`] frame before each sample (a simulation).
    pub const SIM_TRUTH: u8 = 1 << 0;
    /// The device reads an E-stop input and reports it.
    pub const ESTOP_INPUT: u8 = 1 << 1;
}

/// [`Capabilities::measured`] bits: the [`Sample`] fields the bridge really measures. A field
/// whose bit is clear is not a measurement (0, or what the bridge itself output), and the host
/// refuses a run that needs it.
pub mod measured {
    /// `spindle_speed_rpm`: the control's speed output, or an F/V converter.
    pub const SPINDLE_SPEED: u16 = 1 << 0;
    /// `spindle_command_rpm`: the programmed S word, read from the control.
    pub const SPINDLE_COMMAND: u16 = 1 << 1;
    /// `programmed_feed_mm_min`: the block's F word, read from the control.
    pub const PROGRAMMED_FEED: u16 = 1 << 2;
    /// `feed_mm_min`: the actual path feed (the control's, or encoders).
    pub const ACTUAL_FEED: u16 = 1 << 3;
    /// `applied_override_cpct` read back from the CNC, not only what the bridge output.
    pub const APPLIED_OVERRIDE: u16 = 1 << 4;
    /// The in-cycle flag, from the control's cycle-on output.
    pub const IN_CYCLE: u16 = 1 << 5;
    /// The program-end flag, from the control (M30/M02 reached).
    pub const PROGRAM_END: u16 = 1 << 6;
    /// The feed-hold flag, read back from the control's feed-hold state.
    pub const FEED_HOLD: u16 = 1 << 7;
    /// Every field above.
    pub const ALL: u16 = 0xFF;
    /// Each bit with its field's name, for messages.
    pub const NAMES: [(u16, &str); 8] = [
        (SPINDLE_SPEED, "spindle speed"),
        (SPINDLE_COMMAND, "spindle command"),
        (PROGRAMMED_FEED, "programmed feed"),
        (ACTUAL_FEED, "actual feed"),
        (APPLIED_OVERRIDE, "applied override read back from the CNC"),
        (IN_CYCLE, "in-cycle"),
        (PROGRAM_END, "program end"),
        (FEED_HOLD, "feed hold read back"),
    ];
}

/// Device → host: who the device is and what it can do.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Capabilities {
    /// The device's major version.
    pub version_major: u8,
    /// The device's minor version.
    pub version_minor: u8,
    /// Identity (ASCII, padded with zeros), e.g. `cutlab-emulator`.
    pub device_id: [u8; DEVICE_ID_LEN],
    /// The machine's current program or setup (ASCII, padded with zeros); the emulator sends its
    /// preset's name.
    pub program: [u8; PROGRAM_LEN],
    /// Which channels the samples carry ([`channel`]); an absent channel reads 0.
    pub channel_mask: u8,
    /// Amperes per count of the spindle phase currents.
    pub spindle_current_a_per_count: f32,
    /// Amperes per count of the feed phase currents.
    pub feed_current_a_per_count: f32,
    /// Volts per count of the F/V voltage.
    pub fv_v_per_count: f32,
    /// Samples per second.
    pub sample_rate_hz: f32,
    /// How the override reaches the CNC.
    pub override_mode: OverrideModeCode,
    /// The lowest override the device applies, 0.01 %.
    pub min_override_cpct: u16,
    /// The highest override the device applies, 0.01 %.
    pub max_override_cpct: u16,
    /// Dial mode: the override of each code 0–15, 0.01 % (zeros in the other modes).
    pub dial_cpct: [u16; 16],
    /// The device's watchdog: no valid command or heartbeat for this long → fallback.
    pub watchdog_timeout_ms: u16,
    /// The override the device applies on its own when the watchdog fires, 0.01 %.
    pub fallback_override_cpct: u16,
    /// A phase current beyond ± this raises an over-current fault.
    pub over_current_a: f32,
    /// Optional features ([`feature`]).
    pub features: u8,
    /// The [`Sample`] fields the bridge really measures ([`measured`]).
    pub measured: u16,
    /// How long the device stays in its watchdog fallback before it holds the feed (latched
    /// until an operator reset), ms.
    pub fallback_limit_ms: u16,
    /// The baud rate of the device's UART, which the host checks the line's load against at
    /// the handshake; 0 for a line without one (USB CDC-ACM, a pipe).
    pub line_baud: u32,
}

/// [`Sample::flags`] bits.
pub mod sample_flag {
    /// The spindle is turning.
    pub const SPINDLE_RUNNING: u8 = 1 << 0;
    /// A program (cycle) is running.
    pub const IN_CYCLE: u8 = 1 << 1;
    /// This is the program's last sample (cycle end).
    pub const PROGRAM_END: u8 = 1 << 2;
    /// Feed hold is active.
    pub const FEED_HOLD: u8 = 1 << 3;
    /// The host is in control of the override.
    pub const ARMED: u8 = 1 << 4;
    /// The watchdog fired: the fallback override is applied until the host re-arms.
    pub const FALLBACK: u8 = 1 << 5;
    /// The E-stop input is active.
    pub const ESTOP: u8 = 1 << 6;
    /// The device holds the feed, latched: it stays held through any link state, Disarm and
    /// a host's restart, until the operator resets it ([`super::Reset`]).
    pub const HOLD_LATCHED: u8 = 1 << 7;
}

/// [`Sample::faults`] and [`Heartbeat::faults`] bits: every fault active now, as a level (bit
/// `kind − 1` for [`FaultKind`] `kind`), so a lost Fault report is seen at the next frame.
pub mod fault_flag {
    /// A sensor reads implausibly (an open transducer, three phases that do not sum to zero).
    pub const SENSOR: u8 = 1 << 0;
    /// A phase current beyond the over-current limit.
    pub const OVER_CURRENT: u8 = 1 << 1;
    /// The watchdog's fallback is applied.
    pub const WATCHDOG: u8 = 1 << 2;
    /// The E-stop input is active.
    pub const ESTOP: u8 = 1 << 3;
    /// The fallback lasted its time limit: the device holds the feed.
    pub const FALLBACK_LIMIT: u8 = 1 << 4;
}

/// [`Sample::dial_code`] when no dial code is applied.
pub const NO_DIAL_CODE: u8 = 0xFF;

/// Device → host: one sensor sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sample {
    /// Sample counter: +1 per sample, wrapping (a gap is a lost sample).
    pub seq: u32,
    /// Device clock at the end of the sample, µs, wrapping.
    pub time_us: u32,
    /// State bits ([`sample_flag`]).
    pub flags: u8,
    /// Spindle phase currents u, v, w, counts.
    pub spindle_current_counts: [i16; 3],
    /// Feed-drive phase currents u, v, w, counts.
    pub feed_current_counts: [i16; 3],
    /// Spindle F/V converter voltage, counts.
    pub fv_counts: i16,
    /// Spindle speed as the control reports it.
    pub spindle_speed_rpm: f32,
    /// Programmed spindle speed (the S word).
    pub spindle_command_rpm: f32,
    /// Programmed feed of the current block, before override.
    pub programmed_feed_mm_min: f32,
    /// Actual path feed.
    pub feed_mm_min: f32,
    /// The override the CNC applies now, 0.01 %.
    pub applied_override_cpct: u16,
    /// The dial code on the bridge's four outputs (bit 3 the most significant), or
    /// [`NO_DIAL_CODE`].
    pub dial_code: u8,
    /// Every fault active now ([`fault_flag`]).
    pub faults: u8,
}

/// Device → host, simulation only: the truth of the sample with the same `seq`, sent just before
/// it. A real bridge never sends it; a host uses it for metrics and the teach cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SimTruth {
    /// The [`Sample::seq`] it belongs to.
    pub seq: u32,
    /// Cutting force, x.
    pub force_x_n: f32,
    /// Cutting force, y.
    pub force_y_n: f32,
    /// Cutting force, z.
    pub force_z_n: f32,
    /// Resultant in the x-y plane.
    pub force_resultant_n: f32,
    /// Feed-direction component.
    pub feed_force_n: f32,
    /// Cutting torque on the spindle.
    pub spindle_torque_nm: f32,
    /// Cutting power.
    pub cutting_power_w: f32,
    /// Axial depth of cut.
    pub depth_mm: f32,
    /// Radial width of cut.
    pub width_mm: f32,
    /// Feed per tooth.
    pub feed_per_tooth_mm: f32,
    /// Distance along the programmed path.
    pub path_position_mm: f32,
    /// Material removal rate.
    pub material_removal_mm3_s: f32,
    /// Tool position x.
    pub tool_x_mm: f32,
    /// Tool position y.
    pub tool_y_mm: f32,
    /// True RMS feed current.
    pub feed_current_rms_a: f32,
    /// True RMS spindle current.
    pub spindle_current_rms_a: f32,
}

/// [`SetOverride::flags`] and [`Ack::flags`] bits.
pub mod command_flag {
    /// Feed hold.
    pub const FEED_HOLD: u8 = 1 << 0;
    /// [`super::Ack::flags`] only: the feed hold is latched until the operator resets it.
    pub const HOLD_LATCHED: u8 = 1 << 1;
}

/// Host → device: the override to apply (while armed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SetOverride {
    /// Command counter, shared by SetOverride, Arm and Disarm: +1 per command, wrapping.
    pub seq: u32,
    /// The override asked for, 0.01 %.
    pub override_cpct: u16,
    /// [`command_flag`] bits.
    pub flags: u8,
    /// The `time_us` of the latest sample (or device heartbeat) the host had when it decided:
    /// a device ignores a command decided on a sample older than its watchdog timeout.
    pub sample_time_us: u32,
}

/// Host → device: take control of the override.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Arm {
    /// Command counter.
    pub seq: u32,
}

/// Host → device: hand the override back.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Disarm {
    /// Command counter.
    pub seq: u32,
}

/// Host → device: the operator resets the device's latched feed hold (sent only on the
/// operator's explicit action).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Reset {
    /// Command counter.
    pub seq: u32,
}

/// What the device did with a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum AckResult {
    /// Applied as asked (after quantisation to the machine's positions).
    Applied,
    /// Applied, limited to the device's range.
    Limited,
    /// Ignored: the device is not armed (or in fallback until re-armed).
    NotArmed,
    /// Refused: the E-stop input is active.
    Refused,
    /// Ignored as stale: its sequence number is not newer than the last command's, or it was
    /// decided on a sample older than the device's watchdog timeout.
    Stale,
    /// A Reset refused: what latched the hold is still there (an over-current, the E-stop).
    CauseActive,
    /// A code this version does not know.
    Other(u8),
}

impl AckResult {
    /// The wire code.
    pub fn code(self) -> u8 {
        match self {
            AckResult::Applied => 0,
            AckResult::Limited => 1,
            AckResult::NotArmed => 2,
            AckResult::Refused => 3,
            AckResult::Stale => 4,
            AckResult::CauseActive => 5,
            AckResult::Other(c) => c,
        }
    }

    /// The result of wire code `code`.
    pub fn from_code(code: u8) -> Self {
        match code {
            0 => AckResult::Applied,
            1 => AckResult::Limited,
            2 => AckResult::NotArmed,
            3 => AckResult::Refused,
            4 => AckResult::Stale,
            5 => AckResult::CauseActive,
            c => AckResult::Other(c),
        }
    }
}

/// Device → host: a host command was received.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Ack {
    /// The command's `seq`.
    pub seq: u32,
    /// The command's frame type code.
    pub command: u8,
    /// What the device did.
    pub result: AckResult,
    /// The override applied now, 0.01 %.
    pub applied_override_cpct: u16,
    /// [`command_flag`] bits in force now.
    pub flags: u8,
}

/// The kinds of fault a device reports.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FaultKind {
    /// A sensor reads implausibly (open Hall sensor, ADC out of range).
    Sensor,
    /// A phase current beyond the over-current limit.
    OverCurrent,
    /// No valid command or heartbeat within the watchdog timeout: fallback applied.
    Watchdog,
    /// The E-stop input.
    EStop,
    /// The watchdog's fallback lasted its time limit: the device holds the feed (latched).
    FallbackLimit,
    /// A code this version does not know.
    Other(u8),
}

impl FaultKind {
    /// The wire code.
    pub fn code(self) -> u8 {
        match self {
            FaultKind::Sensor => 1,
            FaultKind::OverCurrent => 2,
            FaultKind::Watchdog => 3,
            FaultKind::EStop => 4,
            FaultKind::FallbackLimit => 5,
            FaultKind::Other(c) => c,
        }
    }

    /// Every kind this version knows, in code order.
    pub const KNOWN: [FaultKind; 5] = [
        FaultKind::Sensor,
        FaultKind::OverCurrent,
        FaultKind::Watchdog,
        FaultKind::EStop,
        FaultKind::FallbackLimit,
    ];

    /// Its bit in the level flags ([`fault_flag`]): bit `code − 1`; 0 for a kind this version
    /// does not know.
    pub fn flag(self) -> u8 {
        match self.code() {
            c @ 1..=8 => 1 << (c - 1),
            _ => 0,
        }
    }

    /// The kind of wire code `code`.
    pub fn from_code(code: u8) -> Self {
        match code {
            1 => FaultKind::Sensor,
            2 => FaultKind::OverCurrent,
            3 => FaultKind::Watchdog,
            4 => FaultKind::EStop,
            5 => FaultKind::FallbackLimit,
            c => FaultKind::Other(c),
        }
    }

    /// The name in docs and JSON.
    pub fn name(self) -> &'static str {
        match self {
            FaultKind::Sensor => "sensor",
            FaultKind::OverCurrent => "over-current",
            FaultKind::Watchdog => "watchdog",
            FaultKind::EStop => "e-stop",
            FaultKind::FallbackLimit => "fallback-limit",
            FaultKind::Other(_) => "other",
        }
    }
}

/// Device → host: a fault was raised or cleared.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fault {
    /// Fault report counter.
    pub seq: u32,
    /// Device clock, µs.
    pub time_us: u32,
    /// What.
    pub kind: FaultKind,
    /// 1 raised, 0 cleared.
    pub active: u8,
    /// The channel concerned ([`channel`] bit number), 0xFF for none.
    pub channel: u8,
    /// The override applied now, 0.01 %.
    pub applied_override_cpct: u16,
}

/// Either way: alive. A host's heartbeat feeds the device's watchdog like a command.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Heartbeat {
    /// The sender's heartbeat counter.
    pub seq: u32,
    /// The sender's clock, µs (a host sends the device time of the latest sample it read).
    pub time_us: u32,
    /// A device's state now ([`sample_flag`] bits; "in cycle" clear once a part ended, so a
    /// host that lost the program-end sample still sees the end); 0 from a host.
    pub flags: u8,
    /// A device's faults active now ([`fault_flag`]); 0 from a host.
    pub faults: u8,
    /// The `seq` of the latest Sample the sender sent (a device) or read (a host).
    pub last_sample_seq: u32,
}

/// One frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Frame {
    /// See [`Hello`].
    Hello(Hello),
    /// See [`Capabilities`].
    Capabilities(Capabilities),
    /// See [`Sample`].
    Sample(Sample),
    /// See [`SimTruth`].
    SimTruth(SimTruth),
    /// See [`SetOverride`].
    SetOverride(SetOverride),
    /// See [`Arm`].
    Arm(Arm),
    /// See [`Disarm`].
    Disarm(Disarm),
    /// See [`Reset`].
    Reset(Reset),
    /// See [`Ack`].
    Ack(Ack),
    /// See [`Fault`].
    Fault(Fault),
    /// See [`Heartbeat`].
    Heartbeat(Heartbeat),
}

/// Why a payload is not a frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum FrameError {
    /// No bytes at all.
    Empty,
    /// A type this version does not know (skip it: a newer minor version may send it).
    UnknownType(u8),
    /// Shorter than its type's layout.
    Short {
        /// The type.
        frame_type: FrameType,
        /// Bytes present.
        len: usize,
    },
    /// The buffer to encode into is too small.
    BufferTooSmall,
}

impl core::fmt::Display for FrameError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            FrameError::Empty => f.write_str("empty payload"),
            FrameError::UnknownType(t) => write!(f, "unknown frame type 0x{t:02x}"),
            FrameError::Short { frame_type, len } => write!(
                f,
                "{} frame of {len} bytes, its layout has {}",
                frame_type.name(),
                frame_type.payload_len()
            ),
            FrameError::BufferTooSmall => f.write_str("buffer too small"),
        }
    }
}

/// Writes little-endian fields into a slice, remembering an overflow instead of panicking.
struct Writer<'a> {
    buf: &'a mut [u8],
    len: usize,
    overflow: bool,
}

impl<'a> Writer<'a> {
    fn new(buf: &'a mut [u8]) -> Self {
        Self {
            buf,
            len: 0,
            overflow: false,
        }
    }

    fn bytes(&mut self, b: &[u8]) {
        let end = self.len.saturating_add(b.len());
        match self.buf.get_mut(self.len..end) {
            Some(dst) => {
                dst.copy_from_slice(b);
                self.len = end;
            }
            None => self.overflow = true,
        }
    }

    fn u8(&mut self, v: u8) {
        self.bytes(&[v]);
    }

    fn u16(&mut self, v: u16) {
        self.bytes(&v.to_le_bytes());
    }

    fn i16(&mut self, v: i16) {
        self.bytes(&v.to_le_bytes());
    }

    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }

    fn f32(&mut self, v: f32) {
        self.bytes(&v.to_le_bytes());
    }

    fn finish(self) -> Result<usize, FrameError> {
        if self.overflow {
            Err(FrameError::BufferTooSmall)
        } else {
            Ok(self.len)
        }
    }
}

/// Reads little-endian fields; the caller has checked the length against the layout, and a
/// read past the end gives zeros rather than a panic.
struct FieldReader<'a> {
    bytes: &'a [u8],
    pos: usize,
}

impl FieldReader<'_> {
    fn array<const N: usize>(&mut self) -> [u8; N] {
        let mut a = [0u8; N];
        let end = self.pos.saturating_add(N);
        if let Some(s) = self.bytes.get(self.pos..end) {
            a.copy_from_slice(s);
        }
        self.pos = end;
        a
    }

    fn u8(&mut self) -> u8 {
        self.array::<1>()[0]
    }

    fn u16(&mut self) -> u16 {
        u16::from_le_bytes(self.array())
    }

    fn i16(&mut self) -> i16 {
        i16::from_le_bytes(self.array())
    }

    fn u32(&mut self) -> u32 {
        u32::from_le_bytes(self.array())
    }

    fn f32(&mut self) -> f32 {
        f32::from_le_bytes(self.array())
    }
}

impl Frame {
    /// The frame's type.
    pub fn frame_type(&self) -> FrameType {
        match self {
            Frame::Hello(_) => FrameType::Hello,
            Frame::Capabilities(_) => FrameType::Capabilities,
            Frame::Sample(_) => FrameType::Sample,
            Frame::SimTruth(_) => FrameType::SimTruth,
            Frame::SetOverride(_) => FrameType::SetOverride,
            Frame::Arm(_) => FrameType::Arm,
            Frame::Disarm(_) => FrameType::Disarm,
            Frame::Reset(_) => FrameType::Reset,
            Frame::Ack(_) => FrameType::Ack,
            Frame::Fault(_) => FrameType::Fault,
            Frame::Heartbeat(_) => FrameType::Heartbeat,
        }
    }

    /// Writes the payload (type byte and fields) into `buf`; returns its length.
    ///
    /// ```
    /// use cutlab::protocol::frame::{Frame, Heartbeat};
    /// let mut buf = [0u8; 16];
    /// let hb = Heartbeat { seq: 1, time_us: 2, flags: 0x12, faults: 0, last_sample_seq: 3 };
    /// let n = Frame::Heartbeat(hb).write_payload(&mut buf).unwrap();
    /// assert_eq!(&buf[..n], &[0x40, 1, 0, 0, 0, 2, 0, 0, 0, 0x12, 0, 3, 0, 0, 0]);
    /// ```
    pub fn write_payload(&self, buf: &mut [u8]) -> Result<usize, FrameError> {
        let mut w = Writer::new(buf);
        w.u8(self.frame_type() as u8);
        match self {
            Frame::Hello(h) => {
                w.u8(h.version_major);
                w.u8(h.version_minor);
            }
            Frame::Capabilities(c) => {
                w.u8(c.version_major);
                w.u8(c.version_minor);
                w.bytes(&c.device_id);
                w.bytes(&c.program);
                w.u8(c.channel_mask);
                w.f32(c.spindle_current_a_per_count);
                w.f32(c.feed_current_a_per_count);
                w.f32(c.fv_v_per_count);
                w.f32(c.sample_rate_hz);
                w.u8(c.override_mode.code());
                w.u16(c.min_override_cpct);
                w.u16(c.max_override_cpct);
                for p in c.dial_cpct {
                    w.u16(p);
                }
                w.u16(c.watchdog_timeout_ms);
                w.u16(c.fallback_override_cpct);
                w.f32(c.over_current_a);
                w.u8(c.features);
                w.u16(c.measured);
                w.u16(c.fallback_limit_ms);
                w.u32(c.line_baud);
            }
            Frame::Sample(s) => {
                w.u32(s.seq);
                w.u32(s.time_us);
                w.u8(s.flags);
                for i in s.spindle_current_counts {
                    w.i16(i);
                }
                for i in s.feed_current_counts {
                    w.i16(i);
                }
                w.i16(s.fv_counts);
                w.f32(s.spindle_speed_rpm);
                w.f32(s.spindle_command_rpm);
                w.f32(s.programmed_feed_mm_min);
                w.f32(s.feed_mm_min);
                w.u16(s.applied_override_cpct);
                w.u8(s.dial_code);
                w.u8(s.faults);
            }
            Frame::SimTruth(t) => {
                w.u32(t.seq);
                for v in t.values() {
                    w.f32(v);
                }
            }
            Frame::SetOverride(c) => {
                w.u32(c.seq);
                w.u16(c.override_cpct);
                w.u8(c.flags);
                w.u32(c.sample_time_us);
            }
            Frame::Arm(Arm { seq })
            | Frame::Disarm(Disarm { seq })
            | Frame::Reset(Reset { seq }) => w.u32(*seq),
            Frame::Ack(a) => {
                w.u32(a.seq);
                w.u8(a.command);
                w.u8(a.result.code());
                w.u16(a.applied_override_cpct);
                w.u8(a.flags);
            }
            Frame::Fault(f) => {
                w.u32(f.seq);
                w.u32(f.time_us);
                w.u8(f.kind.code());
                w.u8(f.active);
                w.u8(f.channel);
                w.u16(f.applied_override_cpct);
            }
            Frame::Heartbeat(h) => {
                w.u32(h.seq);
                w.u32(h.time_us);
                w.u8(h.flags);
                w.u8(h.faults);
                w.u32(h.last_sample_seq);
            }
        }
        w.finish()
    }

    /// Reads a payload (type byte and fields). Bytes beyond the layout are ignored (a newer
    /// minor version's additions).
    ///
    /// ```
    /// use cutlab::protocol::frame::{Frame, FrameError, Heartbeat};
    /// let f = Frame::read_payload(&[0x40, 1, 0, 0, 0, 2, 0, 0, 0, 0, 0, 3, 0, 0, 0, 0xAA]).unwrap();
    /// let hb = Heartbeat { seq: 1, time_us: 2, flags: 0, faults: 0, last_sample_seq: 3 };
    /// assert_eq!(f, Frame::Heartbeat(hb));
    /// assert_eq!(Frame::read_payload(&[0x7E]), Err(FrameError::UnknownType(0x7E)));
    /// ```
    pub fn read_payload(payload: &[u8]) -> Result<Frame, FrameError> {
        let (&code, _) = payload.split_first().ok_or(FrameError::Empty)?;
        let frame_type = FrameType::from_code(code).ok_or(FrameError::UnknownType(code))?;
        if payload.len() < frame_type.payload_len() {
            return Err(FrameError::Short {
                frame_type,
                len: payload.len(),
            });
        }
        let mut r = FieldReader {
            bytes: payload,
            pos: 1,
        };
        Ok(match frame_type {
            FrameType::Hello => Frame::Hello(Hello {
                version_major: r.u8(),
                version_minor: r.u8(),
            }),
            FrameType::Capabilities => Frame::Capabilities(Capabilities {
                version_major: r.u8(),
                version_minor: r.u8(),
                device_id: r.array(),
                program: r.array(),
                channel_mask: r.u8(),
                spindle_current_a_per_count: r.f32(),
                feed_current_a_per_count: r.f32(),
                fv_v_per_count: r.f32(),
                sample_rate_hz: r.f32(),
                override_mode: OverrideModeCode::from_code(r.u8()),
                min_override_cpct: r.u16(),
                max_override_cpct: r.u16(),
                dial_cpct: core::array::from_fn(|_| r.u16()),
                watchdog_timeout_ms: r.u16(),
                fallback_override_cpct: r.u16(),
                over_current_a: r.f32(),
                features: r.u8(),
                measured: r.u16(),
                fallback_limit_ms: r.u16(),
                line_baud: r.u32(),
            }),
            FrameType::Sample => Frame::Sample(Sample {
                seq: r.u32(),
                time_us: r.u32(),
                flags: r.u8(),
                spindle_current_counts: [r.i16(), r.i16(), r.i16()],
                feed_current_counts: [r.i16(), r.i16(), r.i16()],
                fv_counts: r.i16(),
                spindle_speed_rpm: r.f32(),
                spindle_command_rpm: r.f32(),
                programmed_feed_mm_min: r.f32(),
                feed_mm_min: r.f32(),
                applied_override_cpct: r.u16(),
                dial_code: r.u8(),
                faults: r.u8(),
            }),
            FrameType::SimTruth => {
                let seq = r.u32();
                let v: [f32; TRUTH_VALUES] = core::array::from_fn(|_| r.f32());
                Frame::SimTruth(SimTruth::from_values(seq, v))
            }
            FrameType::SetOverride => Frame::SetOverride(SetOverride {
                seq: r.u32(),
                override_cpct: r.u16(),
                flags: r.u8(),
                sample_time_us: r.u32(),
            }),
            FrameType::Arm => Frame::Arm(Arm { seq: r.u32() }),
            FrameType::Disarm => Frame::Disarm(Disarm { seq: r.u32() }),
            FrameType::Reset => Frame::Reset(Reset { seq: r.u32() }),
            FrameType::Ack => Frame::Ack(Ack {
                seq: r.u32(),
                command: r.u8(),
                result: AckResult::from_code(r.u8()),
                applied_override_cpct: r.u16(),
                flags: r.u8(),
            }),
            FrameType::Fault => Frame::Fault(Fault {
                seq: r.u32(),
                time_us: r.u32(),
                kind: FaultKind::from_code(r.u8()),
                active: r.u8(),
                channel: r.u8(),
                applied_override_cpct: r.u16(),
            }),
            FrameType::Heartbeat => Frame::Heartbeat(Heartbeat {
                seq: r.u32(),
                time_us: r.u32(),
                flags: r.u8(),
                faults: r.u8(),
                last_sample_seq: r.u32(),
            }),
        })
    }
}

/// The truth's values in wire order ([`crate::truth_fields::in_wire_order`]), as the codecs
/// (binary and JSON) read and write them.
macro_rules! sim_truth_in_wire_order {
    ($($field:ident,)*) => {
        impl SimTruth {
            /// The names of the values, in wire order.
            pub const NAMES: [&'static str; TRUTH_VALUES] = [$(stringify!($field)),*];

            /// The values in wire order ([`SimTruth::NAMES`]).
            pub fn values(&self) -> [f32; TRUTH_VALUES] {
                [$(self.$field),*]
            }

            /// The truth of sample `seq` from the values in wire order.
            pub fn from_values(seq: u32, values: [f32; TRUTH_VALUES]) -> Self {
                let [$($field),*] = values;
                Self { seq, $($field),* }
            }
        }
    };
}
crate::truth_fields::in_wire_order!(sim_truth_in_wire_order);

/// The text of a zero-padded ASCII field (up to the first zero); `None` if it is not UTF-8.
pub fn text_field(bytes: &[u8]) -> Option<&str> {
    let end = bytes.iter().position(|&b| b == 0).unwrap_or(bytes.len());
    core::str::from_utf8(bytes.get(..end)?).ok()
}

/// A zero-padded field holding as much of `text` as fits (cut at a character boundary).
pub fn padded<const N: usize>(text: &str) -> [u8; N] {
    let mut out = [0u8; N];
    let mut end = text.len().min(N);
    while !text.is_char_boundary(end) {
        end -= 1;
    }
    if let (Some(dst), Some(src)) = (out.get_mut(..end), text.as_bytes().get(..end)) {
        dst.copy_from_slice(src);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_layout_length_is_what_the_writer_writes() {
        let frames = [
            Frame::Hello(Hello {
                version_major: 1,
                version_minor: 0,
            }),
            Frame::Arm(Arm { seq: 3 }),
            Frame::Ack(Ack {
                seq: 1,
                command: 0x20,
                result: AckResult::Limited,
                applied_override_cpct: 15000,
                flags: 0,
            }),
        ];
        for f in frames {
            let mut buf = [0u8; MAX_PAYLOAD_LEN];
            let n = f.write_payload(&mut buf).unwrap();
            assert_eq!(n, f.frame_type().payload_len());
            assert_eq!(Frame::read_payload(&buf[..n]), Ok(f));
            assert!(matches!(
                Frame::read_payload(&buf[..n - 1]),
                Err(FrameError::Short { .. })
            ));
        }
    }

    #[test]
    fn text_fields_pad_and_cut_at_character_boundaries() {
        let f: [u8; 4] = padded("kim-step-doc");
        assert_eq!(&f, b"kim-");
        let g: [u8; 4] = padded("aé");
        assert_eq!(text_field(&g), Some("aé"));
        let h: [u8; 2] = padded("aé");
        assert_eq!(text_field(&h), Some("a"));
        assert_eq!(text_field(&[0xFF, 0]), None);
    }
}
