//! What the emulator emulates ([`DeviceConfig`]) and the faults it injects ([`FaultInjection`]):
//! the settings' ranges and defaults, and why an emulator cannot be made ([`DeviceError`]).

use crate::plant::Preset;
use crate::protocol::frame::measured;

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
    ///
    /// [`DeviceTraceRow`]: super::DeviceTraceRow
    /// [`DeviceEmulator::take_trace`]: super::DeviceEmulator::take_trace
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
