//! What the feed-override protocol costs a closed loop: the same preset, controller and seed run
//! three ways, and their metrics side by side (docs/protocol.md §8, "What the protocol costs").
//!
//! ```text
//! cargo run --release --features cli --example protocol_cost -- [--scenario kim-step-doc]
//!     [--controller threshold] [--seeds 1,2,3] [--time-scale 20] [--no-real-time]
//! ```
//!
//! * `sim`: `cutlab sim`'s run — the 10 kHz simulated machine, its signals as they are.
//! * `lockstep`: `cutlab host`'s run against the device emulator over a line with no latency
//!   ([`LockstepLine`]): the 1 kHz block means, the 5 mA counts and the host's handling of
//!   them, deterministic.
//! * `link`: `cutlab host`'s run against the emulator in scaled real time over pipes, as the
//!   tests run it: the lockstep run plus the line's latency and the machine's scheduling.
//!
//! Prints one row per run and metric, then, per seed, each metric's difference from `sim`.

use std::cell::RefCell;
use std::error::Error;
use std::rc::Rc;

use cutlab::closed_loop::definition::RunSpec;
use cutlab::closed_loop::lab::{simulate, RunResult};
use cutlab::control::registry::ControllerKind;
use cutlab::hardware::link_run::{run_on_link, LinkRun};
use cutlab::plant::Preset;
use cutlab::protocol::device::{DeviceConfig, DeviceEmulator};
use cutlab::protocol::link::{run_device, HostLink, HostOptions, LockstepLine};

struct Options {
    preset: Preset,
    controller: ControllerKind,
    seeds: Vec<u64>,
    time_scale: f64,
    real_time: bool,
}

fn options() -> Result<Options, Box<dyn Error>> {
    let mut o = Options {
        preset: Preset::KimStepDoc,
        controller: ControllerKind::Threshold,
        seeds: vec![1],
        time_scale: 20.0,
        real_time: true,
    };
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--scenario" => {
                let name = value()?;
                o.preset = Preset::from_name(&name).ok_or(format!("unknown preset {name}"))?;
            }
            "--controller" => o.controller = value()?.parse()?,
            "--seeds" => {
                o.seeds = value()?
                    .split(',')
                    .map(str::parse)
                    .collect::<Result<_, _>>()?
            }
            "--time-scale" => o.time_scale = value()?.parse()?,
            "--no-real-time" => o.real_time = false,
            other => return Err(format!("unknown option {other}").into()),
        }
    }
    Ok(o)
}

fn device_config(preset: Preset, seed: u64) -> DeviceConfig {
    let mut config = DeviceConfig::new(preset);
    config.seed = seed;
    // Not about the watchdog: a moment of scheduling must not trip it.
    config.watchdog_timeout_s = 5.0;
    config
}

fn lockstep(spec: &RunSpec) -> Result<LinkRun, Box<dyn Error>> {
    let device = Rc::new(RefCell::new(DeviceEmulator::new(device_config(
        spec.preset,
        spec.seed,
    ))?));
    let line = Box::new(LockstepLine::new(Rc::clone(&device)));
    let link = HostLink::connect_line(line, HostOptions::default())?;
    Ok(run_on_link(link, spec, None, None))
}

fn real_time(spec: &RunSpec, time_scale: f64) -> Result<LinkRun, Box<dyn Error>> {
    let (host_to_device_r, host_to_device_w) = std::io::pipe()?;
    let (device_to_host_r, mut device_to_host_w) = std::io::pipe()?;
    let config = device_config(spec.preset, spec.seed);
    let thread = std::thread::spawn(move || {
        let Ok(mut device) = DeviceEmulator::new(config) else {
            return;
        };
        let mut diagnostics = Vec::new();
        run_device(
            &mut device,
            host_to_device_r,
            &mut device_to_host_w,
            &mut diagnostics,
            None,
            time_scale,
        );
    });
    let link = HostLink::connect(
        device_to_host_r,
        Box::new(host_to_device_w),
        HostOptions::default(),
    )?;
    let run = run_on_link(link, spec, None, None);
    thread.join().map_err(|_| "the device thread panicked")?;
    Ok(run)
}

/// How a metric is read from a run.
type Reading = fn(&RunResult) -> f64;

/// The metrics compared, with how each is read.
const METRICS: [(&str, Reading); 8] = [
    ("cycle time [s]", |r| r.metrics.cycle_time_s),
    ("removed volume [mm3]", |r| r.metrics.removed_volume_mm3),
    ("mean removal rate [mm3/s]", |r| {
        r.metrics.mean_material_removal_mm3_s
    }),
    ("peak force [N]", |r| r.metrics.peak_force_n),
    ("force IAE [N s]", |r| r.metrics.force_iae_n_s),
    ("force RMS error [N]", |r| r.metrics.force_rms_error_n),
    ("mean |error| [% of target]", |r| {
        r.metrics.force_mean_abs_error_pct
    }),
    ("controlled cutting [s]", |r| {
        r.metrics.controlled_cutting_time_s
    }),
];

fn main() -> Result<(), Box<dyn Error>> {
    let o = options()?;
    println!(
        "{} / {}, seeds {:?}{}",
        o.preset.name(),
        o.controller.name(),
        o.seeds,
        if o.real_time {
            format!(", real time at {}x", o.time_scale)
        } else {
            String::new()
        }
    );
    for &seed in &o.seeds {
        let spec = RunSpec {
            seed,
            ..RunSpec::new(o.preset, o.controller)
        };
        let sim = simulate(&spec)?;
        let mut runs: Vec<(String, RunResult)> = vec![("sim".into(), sim)];
        let step = lockstep(&spec)?;
        runs.push(("lockstep".into(), step.result?));
        if o.real_time {
            let link = real_time(&spec, o.time_scale)?;
            let s = link.stats;
            println!(
                "seed {seed} link: {} frames, {} lost, command round trip {:.1} ms mean, {:.1} ms \
                 max",
                s.frames_received,
                s.frames_lost,
                s.command_latency_mean_s * 1e3,
                s.command_latency_max_s * 1e3
            );
            runs.push(("link".into(), link.result?));
        }
        println!("\nseed {seed}");
        print!("{:<28}", "metric");
        for (name, _) in &runs {
            print!("{name:>12}");
        }
        for (name, _) in runs.iter().skip(1) {
            print!("{:>14}", format!("{name} vs sim"));
        }
        println!();
        for (label, read) in METRICS {
            print!("{label:<28}");
            let values: Vec<f64> = runs.iter().map(|(_, r)| read(r)).collect();
            for v in &values {
                print!("{v:>12.3}");
            }
            for v in values.iter().skip(1) {
                print!("{:>13.1}%", (v - values[0]) / values[0] * 100.0);
            }
            println!();
        }
        let first = |r: &RunResult| r.trace.rows.len();
        println!(
            "control periods: {}",
            runs.iter()
                .map(|(n, r)| format!("{n} {}", first(r)))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    Ok(())
}
