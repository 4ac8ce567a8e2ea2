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
//!
//! In the order the data flows (each file adds to [`DeviceEmulator`] what its subject needs):
//!
//! | file | what it holds |
//! |---|---|
//! | `mod.rs` | [`DeviceEmulator`]: its state, and what it shows of it (clock, capabilities, stats, flags, trace) |
//! | `config` | what the emulator emulates ([`DeviceConfig`]), the faults it injects ([`FaultInjection`]), their ranges and defaults, and [`DeviceError`] |
//! | `build` | [`DeviceEmulator::new`]: every check of a configuration, the Capabilities, the machines of the parts |
//! | `injection` | the link through the injected faults: stall and unplug, frames lost or corrupted either way, frames encoded out |
//! | `commands` | the host's frames in ([`DeviceEmulator::receive`]): each command checked, applied and acknowledged; a part started |
//! | `step` | one frame period ([`DeviceEmulator::step_frame`]): the E-stop, the watchdog and its fallback's time limit, the heartbeat |
//! | `samples` | a block of plant samples averaged into a SimTruth and a [`Sample`], in counts ([`cpct`], [`CURRENT_A_PER_COUNT`]) |
//! | `faults` | the currents judged (over-current, the phase check) and the faults reported |
//! | `report` | what the emulator reports: [`DeviceStats`], [`HoldCause`], [`DeviceTraceRow`] |
//! | `tests` | the emulator's tests, driven through its frames as a host would |
//!
//! [`Preset::teach_and_run_machines`]: crate::plant::Preset::teach_and_run_machines
//! [`Sample`]: super::frame::Sample
//! [`SimTruth`]: super::frame::SimTruth
//! [`Fault`]: super::frame::Fault

mod build;
mod commands;
mod config;
mod faults;
mod injection;
mod report;
mod samples;
mod step;
#[cfg(test)]
mod tests;

pub use config::{
    DeviceConfig, DeviceError, FaultInjection, DEFAULT_FALLBACK_LIMIT_S, DEFAULT_FALLBACK_PCT,
    DEFAULT_WATCHDOG_S, DISARMED_OVERRIDE_PCT, FALLBACK_LIMIT_RANGE_S, FAULT_RATE_RANGE,
    TIME_SCALE_RANGE, WATCHDOG_RANGE_S,
};
pub use faults::{PHASE_CHECK_MIN_A, PHASE_CHECK_WINDOW_S, PHASE_SUM_TOLERANCE};
pub use report::{DeviceStats, DeviceTraceRow, HoldCause};
pub use samples::{cpct, CURRENT_A_PER_COUNT, FV_V_PER_COUNT};
pub use step::HEARTBEAT_INTERVAL_S;

use super::codec::Decoder;
use super::frame::{fault_flag, sample_flag, Capabilities};
use crate::machine::{Machine, OverrideCommand};
use crate::plant::cnc::{AppliedOverride, OverrideMode};
use crate::rng::Rng;
use faults::PhaseWindow;

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

    fn log(&mut self, text: String) {
        let line = format!("device {:9.3} s: {text}", self.time_s());
        self.diagnostics.push(line);
    }

    fn time_us(&self) -> u32 {
        (self.time_s() * 1e6).round() as u64 as u32
    }
}
