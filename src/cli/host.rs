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

use super::args::{required, value};
use super::sim::{
    check_engine_used, fail_on_controller_faults, metrics_table, EngineFile, EventLine, SimReport,
};
use super::{write_json, CliError, Io};
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::{RunSpec, SettingsOverrides};
use crate::closed_loop::lab::RunResult;
use crate::closed_loop::paper_defaults::preset_controller;
use crate::closed_loop::references::{apply_references, references, References};
use crate::closed_loop::trace::write_csv;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::hardware::host_settings::HostSetting;
use crate::hardware::link_run::run_on_link;
use crate::hardware::serial_settings::SerialSetting;
use crate::input::table;
use crate::plant::Preset;
use crate::protocol::host::{DeviceSummary, LinkEvent, LinkStats};
use crate::protocol::link::{HostLink, HostOptions};

/// Help of `cutlab host`.
pub const ABOUT: &str = "Run the closed loop (teach cut, controller, safety envelope) against a \
device over the feed-override protocol (docs/protocol.md): handshake, arm, stream, command, \
disarm. The device is a command speaking the protocol on stdin/stdout (--device-cmd, e.g. \
\"cutlab device --stdio --scenario kim-step-doc --time-scale 20\") or a serial port (--port). \
Prints the metrics as cutlab sim does and what crossed the link, and the link's events on stderr \
as they happen; --json writes both, whatever happens (a run that never came about gets the \
counts, the events and the error). The savings are measured against cutlab sim's simulated \
fixed-feed references of the preset the device runs (--no-references skips them). A device fault \
(sensor, over-current, E-stop) or a stuck override stops the loop: the host holds the device's \
fallback override until the part ends, or disarms at once after an E-stop or when the device \
holds the feed latched (an overload, an over-current, a fallback that lasted its limit), which \
stays until the operator resets it: --reset-hold. The command fails after a link loss or an \
alarm, with the results up to there printed and written.";

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
    #[arg(long = "fuzzy-engine", value_name = "FILE", help = super::sim::FUZZY_ENGINE_HELP)]
    fuzzy_engine: Option<String>,
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
    /// Write the metrics, calibration, events and link counts as JSON (whatever happens: a run
    /// that never came about gets the link's counts, events and the error)
    #[arg(long, value_name = "FILE")]
    json: Option<String>,
    /// Skip the simulated fixed-feed reference runs (no savings; faster)
    #[arg(long = "no-references")]
    no_references: bool,
    /// Send the operator's reset of a feed hold latched at the device, say what it answered,
    /// and stop (no run): only once the cause (an over-current, a crash) is cleared
    #[arg(long = "reset-hold", conflicts_with = "controller")]
    reset_hold: bool,
}

/// The report `--json` writes: the link's counts, then everything `cutlab sim --json` reports.
/// It is written whatever happened, with what is known: before the handshake there is no
/// device and no counts, and a run that never came about (a teach cut abandoned, a program the
/// host cannot take) has no metrics and no calibration — `error` says why.
#[derive(Serialize)]
struct HostReport<'a> {
    protocol_version: Option<&'a str>,
    device: Option<&'a DeviceSummary>,
    frames_received: Option<u64>,
    frames_lost: Option<u64>,
    frames_rejected: Option<u64>,
    bytes_dropped: Option<u64>,
    commands_sent: Option<u64>,
    commands_acknowledged: Option<u64>,
    watchdog_fallbacks: Option<u64>,
    link_losses: Option<u64>,
    link: Option<&'a LinkStats>,
    /// Whether the host's watchdog (or an I/O error) lost the link.
    link_lost: bool,
    /// The device fault that stopped the loop, if one did.
    alarm: Option<&'a str>,
    /// Why there is no run, if there is none.
    error: Option<&'a str>,
    /// Where the savings' references come from (they are simulated), or why there are none.
    references_source: &'a str,
    #[serde(flatten)]
    run: RunPart<'a>,
}

/// The run's part of the report: `cutlab sim`'s, or what is known without a run.
#[derive(Serialize)]
#[serde(untagged)]
enum RunPart<'a> {
    Done(Box<SimReport<'a>>),
    None(NoRun<'a>),
}

/// The report's run fields when there is no run: the same keys, empty, and the link's events.
#[derive(Serialize)]
struct NoRun<'a> {
    scenario: Option<&'static str>,
    controller: Option<&'a ControllerConfig>,
    metrics: Option<()>,
    references: Option<()>,
    calibration: Option<()>,
    events: Vec<EventLine>,
}

/// What a host run came to, whatever happened.
struct Outcome {
    spec: Option<RunSpec>,
    device: Option<DeviceSummary>,
    stats: Option<LinkStats>,
    events: Vec<LinkEvent>,
    link_lost: bool,
    alarm: Option<String>,
    result: Result<RunResult, String>,
    references: Option<References>,
    references_source: String,
}

impl Outcome {
    /// Nothing but the reason: the link never came up.
    fn failed(error: String) -> Self {
        Self {
            spec: None,
            device: None,
            stats: None,
            events: Vec::new(),
            link_lost: false,
            alarm: None,
            result: Err(error),
            references: None,
            references_source: "none: there is no run".to_string(),
        }
    }
}

fn link_events(events: &[LinkEvent]) -> impl Iterator<Item = EventLine> + '_ {
    events.iter().map(|e| EventLine {
        time_s: e.time_s,
        event: format!("link, part {}: {}", e.part, e.text),
    })
}

fn write_report(
    path: &str,
    outcome: &Outcome,
    controller: Option<&ControllerConfig>,
) -> Result<(), CliError> {
    let s = outcome.stats.as_ref();
    let count = |f: fn(&LinkStats) -> u64| s.map(f);
    let run = match (&outcome.result, &outcome.spec) {
        (Ok(result), Some(spec)) => {
            let mut report = SimReport::new(spec, result, outcome.references);
            report.events.extend(link_events(&outcome.events));
            RunPart::Done(Box::new(report))
        }
        _ => RunPart::None(NoRun {
            scenario: outcome.spec.as_ref().map(|s| s.preset.name()),
            controller: outcome.spec.as_ref().map(|s| &s.controller).or(controller),
            metrics: None,
            references: None,
            calibration: None,
            events: link_events(&outcome.events).collect(),
        }),
    };
    let report = HostReport {
        protocol_version: outcome.device.as_ref().map(|d| d.protocol_version.as_str()),
        device: outcome.device.as_ref(),
        frames_received: count(|s| s.frames_received),
        frames_lost: count(|s| s.frames_lost),
        frames_rejected: count(|s| s.frames_rejected),
        bytes_dropped: count(|s| s.bytes_dropped),
        commands_sent: count(|s| s.commands_sent),
        commands_acknowledged: count(|s| s.commands_acknowledged),
        watchdog_fallbacks: count(|s| s.watchdog_fallbacks),
        link_losses: count(|s| s.link_losses),
        link: s,
        link_lost: outcome.link_lost,
        alarm: outcome.alarm.as_deref(),
        error: outcome.result.as_ref().err().map(String::as_str),
        references_source: &outcome.references_source,
        run,
    };
    let mut file = std::fs::File::create(path)
        .map_err(|e| CliError::new(format!("--json: cannot create {path:?}: {e}")))?;
    write_json(&mut file, &report)
}

/// The device's end of the line, and the child process behind it, if any.
struct Connection {
    link: HostLink,
    child: Option<DeviceChild>,
}

/// The `--device-cmd` child, in a process group of its own so that what its shell started goes
/// with it. Dropping it ends the group and reaps the child — on every way out of `cutlab host`,
/// an early error or a panic's unwinding included — after giving it two seconds to end by
/// itself once its stdin closed (a device should).
struct DeviceChild {
    child: Child,
}

impl DeviceChild {
    /// Starts `cmd` with `sh -c`, its stdin and stdout piped, its stderr passed through.
    fn spawn(cmd: &str) -> std::io::Result<Self> {
        use std::os::unix::process::CommandExt;
        let child = Command::new("sh")
            .arg("-c")
            .arg(cmd)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .process_group(0)
            .spawn()?;
        Ok(Self { child })
    }

    /// Ends the whole group at once (`kill -KILL -- -PGID`: the shell and whatever it started)
    /// and reaps the child.
    fn kill_group(&mut self) {
        let group = format!("-{}", self.child.id());
        let _ = Command::new("kill")
            .args(["-KILL", "--", &group])
            .stderr(Stdio::null())
            .status();
        let _ = self.child.kill();
        let _ = self.child.wait();
    }
}

impl Drop for DeviceChild {
    fn drop(&mut self) {
        // Its stdin is closed by now (the link that held it is gone, or was never made): a
        // well-behaved device ends on its own; whatever is left of the group ends here.
        let until = Instant::now() + Duration::from_secs(2);
        while Instant::now() < until {
            if let Ok(Some(_)) = self.child.try_wait() {
                break;
            }
            std::thread::sleep(Duration::from_millis(20));
        }
        self.kill_group();
    }
}

/// `--link-timeout-s`, through its row of the host's table (the Hardware page's Host watchdog).
fn link_timeout(args: &HostArgs) -> Result<f64, CliError> {
    table::number(
        HostSetting::LinkTimeout,
        args.link_timeout_s.as_deref().unwrap_or_default(),
    )
    .map_err(|e| CliError::new(e.for_cli()))
}

fn connect(args: &HostArgs, options: HostOptions) -> Result<Connection, CliError> {
    match (&args.device_cmd, &args.port) {
        (Some(cmd), None) => {
            let mut child = DeviceChild::spawn(cmd)
                .map_err(|e| CliError::new(format!("--device-cmd: cannot start {cmd:?}: {e}")))?;
            let (Some(stdin), Some(stdout)) = (child.child.stdin.take(), child.child.stdout.take())
            else {
                return Err(CliError::new("--device-cmd: no pipes to the device"));
            };
            // On an error the child is dropped: its group is ended and it is reaped.
            let link = HostLink::connect(stdout, Box::new(stdin), options)
                .map_err(|e| CliError::new(format!("--device-cmd {cmd:?}: {e}")))?;
            Ok(Connection {
                link,
                child: Some(child),
            })
        }
        (None, Some(path)) => {
            // Through its row of the serial table, as the Hardware page's Baud rate.
            let baud = args
                .baud
                .as_deref()
                .map(|text| table::count(SerialSetting::Baud, text))
                .transpose()
                .map_err(|e| CliError::new(e.for_cli()))?;
            if let Some(baud) = baud {
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

/// The run's settings from the options, checked before anything is connected.
struct HostPlan {
    kind: ControllerKind,
    /// The engine a `fuzzy-engine` controller runs (`--fuzzy-engine`).
    engine: Option<EngineFile>,
    target_n: Option<f64>,
    duration_s: Option<f64>,
    calibration: Option<CalibrationFile>,
    options: HostOptions,
}

fn plan(args: &HostArgs) -> Result<HostPlan, CliError> {
    let kind: ControllerKind = required::<String>("controller", &args.controller)?
        .parse()
        .map_err(|e| CliError::new(format!("--controller: {e}")))?;
    let engine = EngineFile::read(args.fuzzy_engine.as_deref())?;
    // Checked now, applied once the preset (and its paper's parameters) is known.
    let controller = controller_for(Preset::ALL[0], kind, &args.set, engine.as_ref())?;
    check_engine_used(&engine, std::iter::once(&controller))?;
    let target_n: Option<f64> = value("target-n", &args.target_n)?;
    let duration_s: Option<f64> = value("duration-s", &args.duration_s)?;
    let link_timeout_s = link_timeout(args)?;
    let options = HostOptions::new(link_timeout_s)
        .map_err(|e| CliError::new(format!("--link-timeout-s: {e}")))?;
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
    Ok(HostPlan {
        kind,
        engine,
        target_n,
        duration_s,
        calibration,
        options,
    })
}

/// `preset`'s controller of `kind` (the paper's parameters where it states them, as `cutlab sim`
/// takes them) running `engine` if it is the fuzzy-engine controller, with the `--set`
/// assignments.
fn controller_for(
    preset: Preset,
    kind: ControllerKind,
    assignments: &[String],
    engine: Option<&EngineFile>,
) -> Result<ControllerConfig, CliError> {
    let mut controller = preset_controller(preset, kind);
    if let Some(engine) = engine {
        engine.give_to(&mut controller)?;
    }
    controller
        .set_texts(assignments.iter().map(String::as_str))
        .map_err(|e| CliError::new(format!("--set: {e}")))?;
    Ok(controller)
}

/// Connects, runs the teach cut and the loop, and makes the references: whatever happens, the
/// outcome says what is known.
fn host_run(args: &HostArgs, plan: HostPlan) -> Outcome {
    let Connection { mut link, child } = match connect(args, plan.options) {
        Ok(c) => c,
        Err(e) => return Outcome::failed(e.0),
    };
    // A run on a machine takes minutes: its events (arming, faults, the program's end) go to
    // stderr as they happen.
    link.log_events_to(Box::new(std::io::stderr()));
    let device = DeviceSummary::of(link.capabilities());
    let program = device.program.clone();
    let preset_name = args.scenario.clone().unwrap_or(program.clone());
    let preset = match Preset::named(&preset_name) {
        Ok(preset) => preset,
        Err(unknown) => {
            let (stats, events) = (link.session().stats(), link.session().events().to_vec());
            drop(link);
            drop(child);
            let error = match &args.scenario {
                Some(_) => format!("--scenario: {unknown}"),
                None => format!(
                    "the device runs {program:?}, which is not a preset: name the preset whose \
                 settings to use with --scenario ({})",
                    Preset::names()
                ),
            };
            return Outcome {
                device: Some(device),
                stats: Some(stats),
                events,
                ..Outcome::failed(error)
            };
        }
    };
    let controller = match controller_for(preset, plan.kind, &args.set, plan.engine.as_ref()) {
        Ok(c) => c,
        Err(e) => {
            drop(link);
            drop(child);
            return Outcome::failed(e.0);
        }
    };
    let spec = RunSpec {
        controller,
        settings: SettingsOverrides {
            target_force_n: plan.target_n,
            ..SettingsOverrides::default()
        },
        ..RunSpec::new(preset, plan.kind)
    };
    let run = run_on_link(
        link,
        &spec,
        plan.duration_s,
        plan.calibration.map(|c| c.calibration),
    );
    drop(child);
    let result = run.result.map_err(|e| {
        let last = run
            .events
            .last()
            .map(|e| format!(" (last on the link: {})", e.text))
            .unwrap_or_default();
        format!("{e}{last}")
    });
    let mut outcome = Outcome {
        spec: Some(spec),
        device: Some(run.device),
        stats: Some(run.stats),
        events: run.events,
        link_lost: run.link_lost,
        alarm: run.alarm.map(|a| a.text),
        result,
        references: None,
        references_source: String::new(),
    };
    fill_references(&mut outcome, &program, args.no_references);
    outcome
}

/// The savings' references: `cutlab sim`'s fixed-feed runs of the preset, simulated — when the
/// device runs that preset's program and the run completed (a cycle time cut short saves
/// nothing), unless `--no-references`.
fn fill_references(outcome: &mut Outcome, program: &str, no_references: bool) {
    let (Some(spec), Ok(result)) = (&outcome.spec, &mut outcome.result) else {
        outcome.references_source = "none: there is no run".to_string();
        return;
    };
    let preset = spec.preset.name();
    outcome.references_source = if no_references {
        "none: --no-references".to_string()
    } else if program != preset {
        format!(
            "none: the device runs {program:?}, not the preset {preset}, so the simulated \
             preset's fixed-feed runs say nothing about its cycle time"
        )
    } else if !result.metrics.completed {
        "none: the run did not complete".to_string()
    } else {
        match references(spec) {
            Ok(r) => {
                apply_references(result, &r);
                outcome.references = Some(r);
                format!(
                    "simulated: cutlab sim's fixed-feed runs of {preset} (seed {}) on the \
                     simulated machine, not runs on this device",
                    spec.seed
                )
            }
            Err(e) => format!("none: the simulated reference runs failed: {e}"),
        }
    };
}

/// `cutlab host --reset-hold`: the operator's reset of a feed hold latched at the device, and
/// nothing more.
fn reset_hold(args: &HostArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let link_timeout_s = link_timeout(args)?;
    let options = HostOptions::new(link_timeout_s)
        .map_err(|e| CliError::new(format!("--link-timeout-s: {e}")))?;
    let Connection { mut link, child } = connect(args, options)?;
    let answer = link.reset_hold().map_err(|e| CliError::new(e.0))?;
    let held = link.session().hold_latched();
    drop(link);
    drop(child);
    writeln!(io.stdout, "reset: {answer}")?;
    if held {
        return Err(CliError::new(
            "the device still holds the feed: clear its cause, then reset again",
        ));
    }
    Ok(())
}

/// Runs `cutlab host`.
pub fn run(args: HostArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    if args.reset_hold {
        return reset_hold(&args, io);
    }
    let plan = match plan(&args) {
        Ok(plan) => plan,
        Err(e) => {
            // The report is written whatever happens, a refused option too.
            if let Some(path) = args.json.as_deref() {
                write_report(path, &Outcome::failed(e.0.clone()), None)?;
            }
            return Err(e);
        }
    };
    let fallback_controller = ControllerConfig::new(plan.kind);
    let from_file = args.calibration.clone();
    let outcome = host_run(&args, plan);
    if let Some(path) = args.json.as_deref() {
        write_report(path, &outcome, Some(&fallback_controller))?;
    }
    if let (Some(path), Ok(result), Some(device), Some(spec)) = (
        args.save_calibration.as_deref(),
        &outcome.result,
        &outcome.device,
        &outcome.spec,
    ) {
        let source = match from_file.as_deref() {
            Some(from) => format!("{from}, used by cutlab host with {}", device.device_id),
            None => format!(
                "teach cut over the link on {} ({}), {} feedback",
                device.device_id,
                spec.preset.name(),
                result.settings.feedback.name()
            ),
        };
        super::save_calibration(path, &result.calibration, source)?;
    }
    if let (Some(path), Ok(result)) = (args.csv.as_deref(), &outcome.result) {
        let mut file = std::fs::File::create(path)
            .map_err(|e| CliError::new(format!("--csv: cannot create {path:?}: {e}")))?;
        write_csv(&result.trace, &mut file)
            .map_err(|e| CliError::new(format!("--csv: cannot write {path:?}: {e}")))?;
    }
    let (result, device, stats, spec) = match (
        &outcome.result,
        &outcome.device,
        &outcome.stats,
        &outcome.spec,
    ) {
        (Ok(r), Some(d), Some(s), Some(spec)) => (r, d, s, spec),
        (Err(e), ..) => return Err(CliError::new(e.clone())),
        _ => return Err(CliError::new("no run")),
    };
    let table = metrics_table(&[(spec.controller.kind().name().to_string(), result)]);
    io.stdout.write_all(table.as_bytes())?;
    let s = stats;
    writeln!(
        io.stdout,
        "link: protocol {}, device {} ({}), {} frames received, {} lost, {} rejected, {} bytes \
         dropped, {}/{} commands acknowledged, {} device watchdog fallbacks, {} link losses",
        device.protocol_version,
        device.device_id,
        device.program,
        s.frames_received,
        s.frames_lost,
        s.frames_rejected,
        s.bytes_dropped,
        s.commands_acknowledged,
        s.commands_sent,
        s.watchdog_fallbacks,
        s.link_losses
    )?;
    writeln!(io.stdout, "references: {}", outcome.references_source)?;
    super::print_calibration_warnings(io.stdout, &result.calibration)?;
    // The results are printed and written; a run the host could not finish under control still
    // fails the command, so a script notices (as `cutlab sim` does on a controller fault).
    if outcome.link_lost {
        let why = outcome
            .events
            .iter()
            .rev()
            .find(|e| e.text.contains("link lost"))
            .map_or("link lost", |e| e.text.as_str());
        return Err(CliError::new(format!(
            "{why}; the program did not finish under control: the results above stop there"
        )));
    }
    if let Some(alarm) = &outcome.alarm {
        return Err(CliError::new(format!(
            "{alarm}; the results above stop at the alarm"
        )));
    }
    fail_on_controller_faults([(spec.controller.kind().name(), result)])
}
