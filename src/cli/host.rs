//! `cutlab host`: the closed loop against a device over the feed-override protocol.
//!
//! The device is a command speaking the protocol on its stdin/stdout (`--device-cmd`, run with
//! `sh -c`, its stderr passed through) or a serial port opened as a file (`--port`; with
//! `--baud` the port is set up first with `stty -F PATH BAUD raw -echo`, otherwise it is used as
//! the system left it). The run is `cutlab sim`'s, through the same [`LabRun`]: a teach cut on
//! the first part, the closed loop on the second, then the same metrics, plus what crossed the
//! link.
//!
//! [`LabRun`]: crate::closed_loop::lab::LabRun

use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

use serde::Serialize;

use super::args::{required, value, value_or};
use super::sim::{metrics_table, EventLine, SimReport};
use super::{write_json, CliError, Io};
use crate::closed_loop::lab::{RunSpec, SettingsOverrides};
use crate::closed_loop::trace::write_csv;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::plant::Preset;
use crate::protocol::frame::text_field;
use crate::protocol::host::{DeviceSummary, LinkStats};
use crate::protocol::link::{run_on_link, HostLink, HostOptions};

/// Help of `cutlab host`.
pub const ABOUT: &str = "Run the closed loop (teach cut, controller, safety envelope) against a \
device over the feed-override protocol (docs/protocol.md): handshake, arm, stream, command, \
disarm. The device is a command speaking the protocol on stdin/stdout (--device-cmd, e.g. \
\"cutlab device --stdio --scenario kim-step-doc --time-scale 20\") or a serial port (--port). \
Prints the metrics as cutlab sim does and what crossed the link; --json writes both.";

/// Options of `cutlab host`.
#[derive(Debug, clap::Args)]
pub struct HostArgs {
    /// A command that speaks the protocol on its stdin/stdout (run with sh -c)
    #[arg(long = "device-cmd", value_name = "COMMAND", conflicts_with = "port")]
    device_cmd: Option<String>,
    /// A serial port (or any file) to speak the protocol on
    #[arg(long, value_name = "PATH")]
    port: Option<String>,
    /// Set the port's speed first with stty (default: leave the port as it is)
    #[arg(long, value_name = "N", requires = "port")]
    baud: Option<String>,
    /// Controller (see cutlab controllers)
    #[arg(long, value_name = "NAME")]
    controller: Option<String>,
    /// Set a controller parameter (repeatable)
    #[arg(long, value_name = "KEY=VALUE", allow_hyphen_values = true)]
    set: Vec<String>,
    /// The preset whose settings the run takes (default: the program the device names)
    #[arg(long, value_name = "NAME")]
    scenario: Option<String>,
    /// Force to hold, N (default: the preset's)
    #[arg(long = "target-n", value_name = "N", allow_hyphen_values = true)]
    target_n: Option<String>,
    /// Stop the closed loop after this much machine time, s
    #[arg(long = "duration-s", value_name = "T", allow_hyphen_values = true)]
    duration_s: Option<String>,
    /// The host's watchdog: no sample for this long (wall time) → link lost (default 2; the
    /// handshake waits five times as long for a device to answer)
    #[arg(long = "link-timeout-s", value_name = "S", allow_hyphen_values = true)]
    link_timeout_s: Option<String>,
    /// Start from a saved calibration (cutlab-calibration JSON) instead of a teach cut: the
    /// device's first part is then the run
    #[arg(long, value_name = "FILE")]
    calibration: Option<String>,
    /// Write the run's calibration (the teach cut's, or the one given) as a calibration file
    #[arg(long = "save-calibration", value_name = "FILE")]
    save_calibration: Option<String>,
    /// Write the closed loop's trace as CSV
    #[arg(long, value_name = "FILE")]
    csv: Option<String>,
    /// Write the metrics, calibration, events and link counts as JSON
    #[arg(long, value_name = "FILE")]
    json: Option<String>,
}

/// The report `--json` writes: the link's counts, then everything `cutlab sim --json` reports.
#[derive(Serialize)]
struct HostReport<'a> {
    protocol_version: String,
    device: &'a DeviceSummary,
    frames_received: u64,
    frames_lost: u64,
    frames_rejected: u64,
    bytes_dropped: u64,
    commands_sent: u64,
    commands_acknowledged: u64,
    watchdog_fallbacks: u64,
    link_losses: u64,
    link: &'a LinkStats,
    #[serde(flatten)]
    run: SimReport<'a>,
}

/// The device's end of the line, and the child process behind it, if any.
struct Connection {
    link: HostLink,
    child: Option<Child>,
}

fn connect(args: &HostArgs, options: HostOptions) -> Result<Connection, CliError> {
    match (&args.device_cmd, &args.port) {
        (Some(cmd), None) => {
            let mut child = Command::new("sh")
                .arg("-c")
                .arg(cmd)
                .stdin(Stdio::piped())
                .stdout(Stdio::piped())
                .stderr(Stdio::inherit())
                .spawn()
                .map_err(|e| CliError::new(format!("--device-cmd: cannot start {cmd:?}: {e}")))?;
            let (Some(stdin), Some(stdout)) = (child.stdin.take(), child.stdout.take()) else {
                let _ = child.kill();
                return Err(CliError::new("--device-cmd: no pipes to the device"));
            };
            match HostLink::connect(stdout, Box::new(stdin), options) {
                Ok(link) => Ok(Connection {
                    link,
                    child: Some(child),
                }),
                Err(e) => {
                    let _ = child.kill();
                    let _ = child.wait();
                    Err(CliError::new(format!("--device-cmd {cmd:?}: {e}")))
                }
            }
        }
        (None, Some(path)) => {
            if let Some(baud) = value::<u32>("baud", &args.baud)? {
                let status = Command::new("stty")
                    .args(["-F", path, &baud.to_string(), "raw", "-echo"])
                    .status()
                    .map_err(|e| CliError::new(format!("--baud: cannot run stty: {e}")))?;
                if !status.success() {
                    return Err(CliError::new(format!(
                        "--baud: stty could not set {path:?} to {baud} baud"
                    )));
                }
            }
            let file = std::fs::OpenOptions::new()
                .read(true)
                .write(true)
                .open(path)
                .map_err(|e| CliError::new(format!("--port: cannot open {path:?}: {e}")))?;
            let reader = file
                .try_clone()
                .map_err(|e| CliError::new(format!("--port {path:?}: {e}")))?;
            let link = HostLink::connect(reader, Box::new(file), options)
                .map_err(|e| CliError::new(format!("--port {path:?}: {e}")))?;
            Ok(Connection { link, child: None })
        }
        _ => Err(CliError::new(
            "give the device: --device-cmd \"COMMAND\" or --port PATH",
        )),
    }
}

/// Lets the device process end by itself (its stdin is closed), then ends it.
fn reap(child: Option<Child>) {
    let Some(mut child) = child else {
        return;
    };
    let until = Instant::now() + Duration::from_secs(2);
    while Instant::now() < until {
        if let Ok(Some(_)) = child.try_wait() {
            return;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let _ = child.wait();
}

/// Runs `cutlab host`.
pub fn run(args: HostArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let kind: ControllerKind = required::<String>("controller", &args.controller)?
        .parse()
        .map_err(|e| CliError::new(format!("--controller: {e}")))?;
    let mut controller = ControllerConfig::new(kind);
    for assignment in &args.set {
        controller
            .set_text(assignment)
            .map_err(|e| CliError::new(format!("--set: {e}")))?;
    }
    let target_n: Option<f64> = value("target-n", &args.target_n)?;
    let duration_s: Option<f64> = value("duration-s", &args.duration_s)?;
    let link_timeout_s: f64 = value_or("link-timeout-s", &args.link_timeout_s, 2.0)?;
    if !(link_timeout_s.is_finite() && link_timeout_s > 0.0) {
        return Err(CliError::new(format!(
            "--link-timeout-s must be positive, not {link_timeout_s}"
        )));
    }
    if let Some(d) = duration_s {
        if !(d.is_finite() && d > 0.0) {
            return Err(CliError::new(format!(
                "--duration-s must be positive, not {d}"
            )));
        }
    }
    let calibration = args
        .calibration
        .as_deref()
        .map(super::read_calibration)
        .transpose()?;
    let options = HostOptions {
        link_timeout_s,
        handshake_timeout_s: 5.0 * link_timeout_s,
    };
    let Connection { link, child } = connect(&args, options)?;
    let program = text_field(&link.capabilities().program)
        .unwrap_or_default()
        .to_string();
    let preset_name = args.scenario.clone().unwrap_or(program.clone());
    let Some(preset) = Preset::from_name(&preset_name) else {
        drop(link);
        reap(child);
        return Err(CliError::new(match &args.scenario {
            Some(name) => format!(
                "--scenario: unknown preset {name:?}; presets: {}",
                Preset::names()
            ),
            None => format!(
                "the device runs {program:?}, which is not a preset: name the preset whose \
                 settings to use with --scenario ({})",
                Preset::names()
            ),
        }));
    };
    let spec = RunSpec {
        controller,
        settings: SettingsOverrides {
            target_force_n: target_n,
            ..SettingsOverrides::default()
        },
        ..RunSpec::new(preset, kind)
    };
    let run = run_on_link(link, &spec, duration_s, calibration.map(|c| c.calibration));
    reap(child);
    let result = run.result.map_err(|e| {
        let last = run
            .events
            .last()
            .map(|e| format!(" (last on the link: {})", e.text))
            .unwrap_or_default();
        CliError::new(format!("{e}{last}"))
    })?;
    if let Some(path) = args.save_calibration.as_deref() {
        let source = match args.calibration.as_deref() {
            Some(from) => format!("{from}, used by cutlab host with {}", run.device.device_id),
            None => format!(
                "teach cut over the link on {} ({}), {} feedback",
                run.device.device_id,
                spec.preset.name(),
                result.settings.feedback.name()
            ),
        };
        super::save_calibration(path, &result.calibration, source)?;
    }
    if let Some(path) = args.csv.as_deref() {
        let mut file = std::fs::File::create(path)
            .map_err(|e| CliError::new(format!("--csv: cannot create {path:?}: {e}")))?;
        write_csv(&result.trace, &mut file)
            .map_err(|e| CliError::new(format!("--csv: cannot write {path:?}: {e}")))?;
    }
    let s = run.stats;
    if let Some(path) = args.json.as_deref() {
        let mut report = SimReport::new(&spec, &result, None);
        report.events.extend(run.events.iter().map(|e| EventLine {
            time_s: e.time_s,
            event: format!("link, part {}: {}", e.part, e.text),
        }));
        let report = HostReport {
            protocol_version: run.device.protocol_version.clone(),
            device: &run.device,
            frames_received: s.frames_received,
            frames_lost: s.frames_lost,
            frames_rejected: s.frames_rejected,
            bytes_dropped: s.bytes_dropped,
            commands_sent: s.commands_sent,
            commands_acknowledged: s.commands_acknowledged,
            watchdog_fallbacks: s.watchdog_fallbacks,
            link_losses: s.link_losses,
            link: &s,
            run: report,
        };
        let mut file = std::fs::File::create(path)
            .map_err(|e| CliError::new(format!("--json: cannot create {path:?}: {e}")))?;
        write_json(&mut file, &report)?;
    }
    let table = metrics_table(&[(spec.controller.kind().name().to_string(), &result)]);
    io.stdout.write_all(table.as_bytes())?;
    writeln!(
        io.stdout,
        "link: protocol {}, device {} ({}), {} frames received, {} lost, {} rejected, {} bytes \
         dropped, {}/{} commands acknowledged, {} device watchdog fallbacks, {} link losses",
        run.device.protocol_version,
        run.device.device_id,
        run.device.program,
        s.frames_received,
        s.frames_lost,
        s.frames_rejected,
        s.bytes_dropped,
        s.commands_acknowledged,
        s.commands_sent,
        s.watchdog_fallbacks,
        s.link_losses
    )?;
    if run.link_lost {
        writeln!(
            io.stdout,
            "link lost: the host alarmed and disarmed; the program did not finish under control"
        )?;
    }
    Ok(())
}
