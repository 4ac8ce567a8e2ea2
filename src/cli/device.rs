//! `cutlab device`: the simulated machine behind the feed-override protocol, on stdin/stdout.
//!
//! Bytes only on stdout (the protocol's frames), diagnostics on stderr; any bytes on stdin are
//! survived (the decoder resynchronises and counts what it dropped). The device runs until its
//! stdin closes. See [`crate::protocol::device`] for what it emulates and injects.

use super::args::{value, value_or};
use super::{CliError, Io};
use crate::input::readable;
use crate::plant::Preset;
use crate::protocol::device::{DeviceConfig, DeviceEmulator, FaultInjection, TIME_SCALE_RANGE};
use crate::protocol::link::run_device;

/// Help of `cutlab device`.
pub const ABOUT: &str = "Run a preset's simulated machine behind the feed-override protocol \
(docs/protocol.md), speaking it on stdin/stdout: a bridge device for `cutlab host` and for \
tests. Bytes only on stdout, diagnostics on stderr. The device sends one sample per 10 plant \
samples (1 kHz), each channel the mean of its block, and a sim-truth frame before each. The \
first part armed is seeded like `cutlab sim`'s teach cut, the second like its run.";

/// Options of `cutlab device`.
#[derive(Debug, clap::Args)]
pub struct DeviceArgs {
    /// Speak the protocol on stdin/stdout (the only link the emulator has)
    #[arg(long)]
    stdio: bool,
    /// Preset to emulate (see cutlab scenarios)
    #[arg(long, value_name = "NAME")]
    scenario: Option<String>,
    /// Seed of the machines (as cutlab sim --seed) and of the injected faults (default 1)
    #[arg(long, value_name = "N", allow_hyphen_values = true)]
    seed: Option<String>,
    /// Probability that a frame, either way, is lost (default 0)
    #[arg(long = "drop-rate", value_name = "P", allow_hyphen_values = true)]
    drop_rate: Option<String>,
    /// Probability that a frame, either way, is corrupted (default 0)
    #[arg(long = "noise-rate", value_name = "P", allow_hyphen_values = true)]
    noise_rate: Option<String>,
    /// Stall the device's receiver at this device time (with --stall-s)
    #[arg(long = "stall-at-s", value_name = "T", allow_hyphen_values = true)]
    stall_at_s: Option<String>,
    /// Length of the receiver stall, device seconds
    #[arg(long = "stall-s", value_name = "D", allow_hyphen_values = true)]
    stall_s: Option<String>,
    /// Pull the cable at this device time: nothing in or out from then on
    #[arg(long = "unplug-at-s", value_name = "T", allow_hyphen_values = true)]
    unplug_at_s: Option<String>,
    /// Read an over-current from this device time (with --over-current-s) while a part runs
    #[arg(
        long = "over-current-at-s",
        value_name = "T",
        allow_hyphen_values = true
    )]
    over_current_at_s: Option<String>,
    /// Length of the over-current, device seconds
    #[arg(long = "over-current-s", value_name = "D", allow_hyphen_values = true)]
    over_current_s: Option<String>,
    /// Make the E-stop input active at this device time (it stays active; the device then
    /// declares an E-stop input)
    #[arg(long = "estop-at-s", value_name = "T", allow_hyphen_values = true)]
    estop_at_s: Option<String>,
    /// Device seconds per wall second (default 1: real time; the device's watchdog, in device
    /// time, is then that much shorter in wall time: 0.5 s is 10 ms at 50)
    #[arg(long = "time-scale", value_name = "K", allow_hyphen_values = true)]
    time_scale: Option<String>,
    /// The device's watchdog timeout, device seconds (default 0.5)
    #[arg(long = "watchdog-s", value_name = "S", allow_hyphen_values = true)]
    watchdog_s: Option<String>,
    /// The override the watchdog applies at most, % (default 50; the fallback is the lower of
    /// it and the override applied when the watchdog fires)
    #[arg(long = "fallback-pct", value_name = "PCT", allow_hyphen_values = true)]
    fallback_pct: Option<String>,
    /// How long the fallback lasts before the device holds the feed, latched until the
    /// operator's reset, device seconds (default 5)
    #[arg(
        long = "fallback-limit-s",
        value_name = "S",
        allow_hyphen_values = true
    )]
    fallback_limit_s: Option<String>,
    /// The baud rate the device declares for its line (default 0: none, as a pipe); the host
    /// refuses a stream that does not fit it
    #[arg(long = "line-baud", value_name = "N")]
    line_baud: Option<String>,
    /// Open the spindle's phase-u transducer at this device time: it reads 0 A from then on
    #[arg(
        long = "sensor-open-at-s",
        value_name = "T",
        allow_hyphen_values = true
    )]
    sensor_open_at_s: Option<String>,
    /// Make the CNC ignore the bridge's override outputs from this device time on (it keeps the
    /// override it had; the bridge goes on acknowledging what it outputs)
    #[arg(
        long = "stuck-override-at-s",
        value_name = "T",
        allow_hyphen_values = true
    )]
    stuck_override_at_s: Option<String>,
    /// Write what the bridge applied at each sample (override, feed hold, latched hold,
    /// fallback, faults) to FILE as CSV
    #[arg(long, value_name = "FILE")]
    trace: Option<String>,
    /// Send no simulation truth, as a real bridge: the host must calibrate from the cut model or
    /// a saved calibration
    #[arg(long = "no-truth")]
    no_truth: bool,
}

/// The emulator the options describe.
pub fn emulator_from(args: &DeviceArgs) -> Result<DeviceEmulator, CliError> {
    let name: String = super::args::required("scenario", &args.scenario)?;
    let preset = Preset::from_name(&name).ok_or_else(|| {
        CliError::new(format!(
            "--scenario: unknown preset {name:?}; presets: {}",
            Preset::names()
        ))
    })?;
    let mut config = DeviceConfig::new(preset);
    config.seed = value_or("seed", &args.seed, config.seed)?;
    config.watchdog_timeout_s = value_or("watchdog-s", &args.watchdog_s, 0.5)?;
    config.fallback_override_pct = value_or("fallback-pct", &args.fallback_pct, 50.0)?;
    config.fallback_limit_s = value_or("fallback-limit-s", &args.fallback_limit_s, 5.0)?;
    config.line_baud = value_or("line-baud", &args.line_baud, 0)?;
    config.trace = args.trace.is_some();
    config.sim_truth = !args.no_truth;
    let stall_at_s = value("stall-at-s", &args.stall_at_s)?;
    let stall_s: Option<f64> = value("stall-s", &args.stall_s)?;
    if stall_at_s.is_some() != stall_s.is_some() {
        return Err(CliError::new(
            "--stall-at-s and --stall-s go together: when the stall starts and how long it lasts",
        ));
    }
    let over_current_at_s = value("over-current-at-s", &args.over_current_at_s)?;
    let over_current_s: Option<f64> = value("over-current-s", &args.over_current_s)?;
    if over_current_at_s.is_some() != over_current_s.is_some() {
        return Err(CliError::new(
            "--over-current-at-s and --over-current-s go together: when the over-current starts \
             and how long it lasts",
        ));
    }
    config.faults = FaultInjection {
        drop_rate: value_or("drop-rate", &args.drop_rate, 0.0)?,
        noise_rate: value_or("noise-rate", &args.noise_rate, 0.0)?,
        stall_at_s,
        stall_s: stall_s.unwrap_or(0.0),
        unplug_at_s: value("unplug-at-s", &args.unplug_at_s)?,
        estop_at_s: value("estop-at-s", &args.estop_at_s)?,
        over_current_at_s,
        over_current_s: over_current_s.unwrap_or(0.0),
        sensor_open_at_s: value("sensor-open-at-s", &args.sensor_open_at_s)?,
        stuck_override_at_s: value("stuck-override-at-s", &args.stuck_override_at_s)?,
    };
    DeviceEmulator::new(config).map_err(|e| CliError::new(e.to_string()))
}

/// Runs `cutlab device`.
pub fn run(args: DeviceArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    if !args.stdio {
        return Err(CliError::new(
            "--stdio is required: the emulator speaks on stdin/stdout (bridge it to a serial \
             port with socat if a serial line is wanted)",
        ));
    }
    let time_scale: f64 = value_or("time-scale", &args.time_scale, 1.0)?;
    let (lo, hi) = TIME_SCALE_RANGE;
    if !(time_scale >= lo && time_scale <= hi) {
        return Err(CliError::new(format!(
            "--time-scale must be {lo} to {hi}, not {}",
            readable(time_scale)
        )));
    }
    let mut device = emulator_from(&args)?;
    let mut trace = match args.trace.as_deref() {
        Some(path) => Some(std::io::BufWriter::new(
            std::fs::File::create(path)
                .map_err(|e| CliError::new(format!("--trace: cannot create {path:?}: {e}")))?,
        )),
        None => None,
    };
    // The process's own stdin, read on a thread of its own so the device keeps time while it
    // waits for bytes (io.stdin is a locked handle, which cannot move to that thread).
    let stdin = std::io::stdin();
    let mut stderr = std::io::stderr();
    run_device(
        &mut device,
        stdin,
        io.stdout,
        &mut stderr,
        trace.as_mut().map(|t| t as &mut dyn std::io::Write),
        time_scale,
    );
    if let Some(mut t) = trace {
        std::io::Write::flush(&mut t)
            .map_err(|e| CliError::new(format!("--trace: cannot write: {e}")))?;
    }
    Ok(())
}
