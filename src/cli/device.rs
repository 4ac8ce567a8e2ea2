//! `cutlab device`: the simulated machine behind the feed-override protocol, on stdin/stdout.
//!
//! Bytes only on stdout (the protocol's frames), diagnostics on stderr; any bytes on stdin are
//! survived (the decoder resynchronises and counts what it dropped). The device runs until its
//! stdin closes. See [`crate::protocol::device`] for what it emulates and injects.

use super::table_args::{OptionRows, TableArgs};
use super::{CliError, Io};
use crate::input::table::Table;
use crate::protocol::device::DeviceEmulator;
use crate::protocol::device_settings::{parse_device, DeviceSetting, VirtualDevice};
use crate::protocol::link::run_device;

/// Help of `cutlab device`.
pub const ABOUT: &str = "Run a preset's simulated machine behind the feed-override protocol \
(docs/protocol.md), speaking it on stdin/stdout: a bridge device for `cutlab host` and for \
tests. Bytes only on stdout, diagnostics on stderr. The device sends one sample per 10 plant \
samples (1 kHz), each channel the mean of its block, and a sim-truth frame before each. The \
first part armed is seeded like `cutlab sim`'s teach cut, the second like its run.";

/// The device table's rows, every one an option of `cutlab device`.
#[derive(Debug, Clone, Default)]
pub struct DeviceRows;

impl OptionRows for DeviceRows {
    type Setting = DeviceSetting;
    const ROWS: &'static [DeviceSetting] = DeviceSetting::ROWS;
}

/// Options of `cutlab device`.
#[derive(Debug, clap::Args)]
pub struct DeviceArgs {
    /// Speak the protocol on stdin/stdout (the only link the emulator has)
    #[arg(long)]
    stdio: bool,
    /// The emulated device: every row of the device table (the Hardware page's virtual device
    /// takes the same)
    #[command(flatten)]
    settings: TableArgs<DeviceRows>,
    /// Write what the bridge applied at each sample (override, feed hold, latched hold,
    /// fallback, faults) to FILE as CSV
    #[arg(long, value_name = "FILE")]
    trace: Option<String>,
    /// Send no simulation truth, as a real bridge: the host must calibrate from the cut model or
    /// a saved calibration
    #[arg(long = "no-truth")]
    no_truth: bool,
}

/// The device the options describe, through the device table's rows (as the Hardware page's
/// virtual device): the first refused setting names its option.
pub fn device_from(args: &DeviceArgs) -> Result<VirtualDevice, CliError> {
    let mut device =
        parse_device(&args.settings.texts()).map_err(|errors| match errors.first() {
            Some(e) => CliError::new(e.for_cli()),
            None => CliError::new("the device's options were refused"),
        })?;
    device.config.trace = args.trace.is_some();
    device.config.sim_truth = !args.no_truth;
    Ok(device)
}

/// Runs `cutlab device`.
pub fn run(args: DeviceArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    if !args.stdio {
        return Err(CliError::new(
            "--stdio is required: the emulator speaks on stdin/stdout (bridge it to a serial \
             port with socat if a serial line is wanted)",
        ));
    }
    let VirtualDevice { config, time_scale } = device_from(&args)?;
    let mut device = DeviceEmulator::new(config).map_err(|e| CliError::new(e.to_string()))?;
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
