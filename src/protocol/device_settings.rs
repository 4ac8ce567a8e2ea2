//! The virtual device's settings as one table: `cutlab device`'s options and the Hardware page's
//! virtual-device fields are its rows, parsed by [`parse_device`], so both take the same values
//! (the time scale included) and refuse the rest with the same words.
//!
//! | setting | key | option | unit | range | default |
//! |---|---|---|---|---|---|
//! | see [`DeviceSetting::ROWS`](crate::input::table::Table::ROWS) | | | | | |

use super::device::{
    DeviceConfig, FaultInjection, DEFAULT_FALLBACK_LIMIT_S, DEFAULT_FALLBACK_PCT,
    DEFAULT_WATCHDOG_S, FALLBACK_LIMIT_RANGE_S, FAULT_RATE_RANGE, TIME_SCALE_RANGE,
    WATCHDOG_RANGE_S,
};
use crate::input::table::{Kind, Problem, Reader, Row, RowError, Shown, Table, Value};
use crate::plant::Preset;

/// Every setting of an emulated bridge device.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum DeviceSetting {
    /// The preset whose machine and program the device emulates.
    Program,
    /// Seed of the machines and of the injected faults.
    Seed,
    /// Device seconds per wall second.
    TimeScale,
    /// Probability that a frame, either way, is lost.
    DropRate,
    /// Probability that a frame, either way, is corrupted.
    NoiseRate,
    /// When the device's receiver stalls, device time.
    StallAt,
    /// How long the receiver stall lasts.
    StallFor,
    /// When the cable is pulled, device time.
    UnplugAt,
    /// The device's watchdog timeout.
    Watchdog,
    /// The override the watchdog applies at most.
    Fallback,
    /// How long the fallback lasts before the device holds the feed.
    FallbackLimit,
    /// The baud rate the device declares for its line.
    LineBaud,
    /// When an over-current starts, device time.
    OverCurrentAt,
    /// How long the over-current lasts.
    OverCurrentFor,
    /// When the E-stop input goes active, device time.
    EstopAt,
    /// When the spindle's phase-u transducer opens, device time.
    SensorOpenAt,
    /// When the CNC starts ignoring the bridge's override outputs, device time.
    StuckOverrideAt,
}

/// A device time or a length in device seconds: zero to about 30 years of device time.
const DEVICE_TIME_S: Kind = Kind::Number { min: 0.0, max: 1e9 };

const fn range((min, max): (f64, f64)) -> Kind {
    Kind::Number { min, max }
}

impl Table for DeviceSetting {
    const ROWS: &'static [Self] = &[
        DeviceSetting::Program,
        DeviceSetting::Seed,
        DeviceSetting::TimeScale,
        DeviceSetting::DropRate,
        DeviceSetting::NoiseRate,
        DeviceSetting::StallAt,
        DeviceSetting::StallFor,
        DeviceSetting::UnplugAt,
        DeviceSetting::Watchdog,
        DeviceSetting::Fallback,
        DeviceSetting::FallbackLimit,
        DeviceSetting::LineBaud,
        DeviceSetting::OverCurrentAt,
        DeviceSetting::OverCurrentFor,
        DeviceSetting::EstopAt,
        DeviceSetting::SensorOpenAt,
        DeviceSetting::StuckOverrideAt,
    ];

    fn row(self) -> Row {
        use DeviceSetting as D;
        match self {
            D::Program => Row::new("program", "scenario", "Program (preset)", "")
                .takes(Kind::Choice, Shown::Blank)
                .noun("preset")
                .help("the preset whose machine and program the device emulates (see cutlab scenarios)"),
            D::Seed => Row::new("seed", "seed", "Seed", "")
                .takes(Kind::Seed, Shown::Seed(1))
                .noun("seed")
                .help("seed of the machines (the same seed as a simulated run's) and of the injected faults"),
            D::TimeScale => Row::new("time_scale", "time-scale", "Time scale", "× real time")
                .takes(range(TIME_SCALE_RANGE), Shown::Number(1.0))
                .noun("time scale")
                .help("device seconds per wall second (1: real time); the device's watchdog, in device \
                 time, is that much shorter in wall time. In the browser the virtual device runs \
                 at most 400 frames per 10 ms tick (40× real time; asked for more, 40×) and pauses \
                 while the browser is away"),
            D::DropRate => Row::new("drop_rate", "drop-rate", "Drop rate", "per frame")
                .takes(range(FAULT_RATE_RANGE), Shown::Number(0.0))
                .noun("drop rate")
                .help("probability that a frame, either way, is lost"),
            D::NoiseRate => Row::new("noise_rate", "noise-rate", "Noise rate", "per frame")
                .takes(range(FAULT_RATE_RANGE), Shown::Number(0.0))
                .noun("noise rate")
                .help("probability that a frame, either way, is corrupted"),
            D::StallAt => Row::new("stall_at", "stall-at-s", "Receiver stall at (blank: none)", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("stall the device's receiver at this device time (with its length)"),
            D::StallFor => Row::new("stall_for", "stall-s", "Receiver stall for", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("length of the receiver stall, device seconds"),
            D::UnplugAt => Row::new("unplug_at", "unplug-at-s", "Cable pulled at (blank: never)", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("pull the cable at this device time: nothing in or out from then on"),
            D::Watchdog => Row::new("watchdog", "watchdog-s", "Device watchdog", "s")
                .takes(range(WATCHDOG_RANGE_S), Shown::Number(DEFAULT_WATCHDOG_S))
                .help("the device's watchdog timeout, device seconds"),
            D::Fallback => Row::new("fallback", "fallback-pct", "Device fallback override", "%")
                .takes(Kind::Number {
                    min: 0.0,
                    max: crate::plant::cnc::MAX_OVERRIDE_PCT,
                }, Shown::Number(DEFAULT_FALLBACK_PCT))
                .help("the override the watchdog applies at most (the fallback is the lower of it and \
                 the override applied when the watchdog fires; at most what the machine applies)"),
            D::FallbackLimit => Row::new("fallback_limit", "fallback-limit-s", "Fallback time limit", "s")
                .takes(range(FALLBACK_LIMIT_RANGE_S), Shown::Number(DEFAULT_FALLBACK_LIMIT_S))
                .help("how long the fallback lasts before the device holds the feed, latched until the \
                 operator's reset, device seconds"),
            D::LineBaud => Row::new("line_baud", "line-baud", "Declared line speed (0: none)", "bit/s")
                .takes(Kind::Count {
                    min: 0,
                    max: u32::MAX as usize,
                }, Shown::Count(0))
                .help("the baud rate the device declares for its line (0: none, as a pipe); the host \
                 refuses a stream that does not fit it"),
            D::OverCurrentAt => Row::new("over_current_at", "over-current-at-s", "Over-current at (blank: none)", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("read an over-current from this device time (with its length) while a part runs"),
            D::OverCurrentFor => Row::new("over_current_for", "over-current-s", "Over-current for", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("length of the over-current, device seconds"),
            D::EstopAt => Row::new("estop_at", "estop-at-s", "E-stop at (blank: never)", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("make the E-stop input active at this device time (it stays active; the device \
                 then declares an E-stop input)"),
            D::SensorOpenAt => Row::new("sensor_open_at", "sensor-open-at-s", "Spindle transducer opens at (blank: never)", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("open the spindle's phase-u transducer at this device time: it reads 0 A from then on"),
            D::StuckOverrideAt => Row::new("stuck_override_at", "stuck-override-at-s", "Override stuck from (blank: never)", "s")
                .takes(DEVICE_TIME_S, Shown::Blank)
                .help("make the CNC ignore the bridge's override outputs from this device time on (it \
                 keeps the override it had; the bridge goes on acknowledging what it outputs)"),
        }
    }

    fn choices(self) -> Vec<(&'static str, &'static str)> {
        match self {
            DeviceSetting::Program => Preset::ALL.iter().map(|p| (p.name(), p.label())).collect(),
            _ => Vec::new(),
        }
    }
}

/// An emulated device as asked for: what it emulates and how fast it runs.
#[derive(Debug, Clone, PartialEq)]
pub struct VirtualDevice {
    /// The emulator's configuration (faults, watchdog, fallback, program).
    pub config: DeviceConfig,
    /// Device seconds per wall second.
    pub time_scale: f64,
}

/// Parses the typed text of a device's settings (those not given take their defaults): what
/// `cutlab device` does with its options and the Hardware page with its fields. Every setting
/// that does not parse or is out of range is reported, then the settings that go together (a
/// stall's start and length, an over-current's), and a fallback above what the program's machine
/// applies.
///
/// ```
/// use cutlab::protocol::device_settings::{parse_device, DeviceSetting};
/// let texts = [(DeviceSetting::Program, "kim-step-doc"), (DeviceSetting::TimeScale, "4")];
/// let device = parse_device(&texts).unwrap();
/// assert_eq!((device.time_scale, device.config.watchdog_timeout_s), (4.0, 0.5));
/// let e = parse_device(&[(DeviceSetting::Program, "kim-step-doc"), (DeviceSetting::TimeScale, "5000")])
///     .unwrap_err();
/// assert_eq!(e[0].for_cli(), "--time-scale: time scale 5000 is outside 0.01–1000");
/// ```
pub fn parse_device<T: AsRef<str>>(
    texts: &[(DeviceSetting, T)],
) -> Result<VirtualDevice, Vec<RowError<DeviceSetting>>> {
    use DeviceSetting as D;
    let mut reader = Reader::new(texts);
    let preset = reader.choice(D::Program).and_then(Preset::from_name);
    let seed = reader.value(D::Seed).and_then(Value::seed);
    let time_scale = reader.number(D::TimeScale);
    let drop_rate = reader.number(D::DropRate);
    let noise_rate = reader.number(D::NoiseRate);
    let stall_at_s = reader.number(D::StallAt);
    let stall_s = reader.number(D::StallFor);
    let unplug_at_s = reader.number(D::UnplugAt);
    let watchdog_s = reader.number(D::Watchdog);
    let fallback_pct = reader.number(D::Fallback);
    let fallback_limit_s = reader.number(D::FallbackLimit);
    let line_baud = reader.count(D::LineBaud);
    let over_current_at_s = reader.number(D::OverCurrentAt);
    let over_current_s = reader.number(D::OverCurrentFor);
    let estop_at_s = reader.number(D::EstopAt);
    let sensor_open_at_s = reader.number(D::SensorOpenAt);
    let stuck_override_at_s = reader.number(D::StuckOverrideAt);
    if preset.is_none() && !reader.refused(D::Program) {
        reader.refuse(RowError::new(
            D::Program,
            Problem::Parse("choose the preset the device emulates".to_string()),
        ));
    }
    for ((at, at_s), (length, length_s), what) in [
        (
            (D::StallAt, stall_at_s),
            (D::StallFor, stall_s),
            "a stall needs both when it starts and how long it lasts (or neither)",
        ),
        (
            (D::OverCurrentAt, over_current_at_s),
            (D::OverCurrentFor, over_current_s),
            "an over-current needs both when it starts and how long it lasts (or neither)",
        ),
    ] {
        if reader.refused(at) || reader.refused(length) {
            continue;
        }
        match (at_s.is_some(), length_s.is_some()) {
            (true, false) => reader.refuse(RowError::other(length, what)),
            (false, true) => reader.refuse(RowError::other(at, what)),
            _ => {}
        }
    }
    if let (Some(p), Some(fallback)) = (preset, fallback_pct) {
        let max = p.override_mode().max_pct();
        if fallback > max {
            reader.refuse(RowError::other(
                D::Fallback,
                format!(
                    "{} % is more than this machine applies ({} %)",
                    crate::input::readable(fallback),
                    crate::input::readable(max)
                ),
            ));
        }
    }
    let device = preset.map(|preset| {
        let mut config = DeviceConfig::new(preset);
        config.seed = seed.unwrap_or(config.seed);
        config.watchdog_timeout_s = watchdog_s.unwrap_or(config.watchdog_timeout_s);
        config.fallback_override_pct = fallback_pct.unwrap_or(config.fallback_override_pct);
        config.fallback_limit_s = fallback_limit_s.unwrap_or(config.fallback_limit_s);
        // The row's range is a u32's.
        config.line_baud =
            line_baud.map_or(config.line_baud, |b| u32::try_from(b).unwrap_or(u32::MAX));
        config.faults = FaultInjection {
            drop_rate: drop_rate.unwrap_or(0.0),
            noise_rate: noise_rate.unwrap_or(0.0),
            stall_at_s,
            stall_s: stall_s.unwrap_or(0.0),
            unplug_at_s,
            estop_at_s,
            over_current_at_s,
            over_current_s: over_current_s.unwrap_or(0.0),
            sensor_open_at_s,
            stuck_override_at_s,
        };
        VirtualDevice {
            config,
            time_scale: time_scale.unwrap_or(1.0),
        }
    });
    reader.finish(device)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::table::check_table;
    use crate::protocol::device::DeviceEmulator;

    fn kim(extra: &[(DeviceSetting, &str)]) -> Result<VirtualDevice, Vec<RowError<DeviceSetting>>> {
        let mut texts = vec![(DeviceSetting::Program, "kim-step-doc")];
        texts.extend_from_slice(extra);
        parse_device(&texts)
    }

    #[test]
    fn the_table_holds_and_its_defaults_are_the_emulators() {
        assert_eq!(check_table::<DeviceSetting>(), Ok(()));
        let device = kim(&[]).unwrap();
        assert_eq!(device.config, DeviceConfig::new(Preset::KimStepDoc));
        assert_eq!(device.time_scale, 1.0);
    }

    #[test]
    fn whatever_the_rows_accept_the_emulator_builds() {
        // kim-step-doc is paper 003's machine, whose override input takes up to 255 %: the
        // fallback's whole range.
        for s in DeviceSetting::ROWS {
            let Some((min, max)) = s.row().range() else {
                continue;
            };
            for v in [min, max] {
                let text = match s.row().kind {
                    crate::input::table::Kind::Count { .. } => format!("{v}"),
                    _ => crate::input::readable(v),
                };
                let mut extra = vec![(*s, text.as_str())];
                // The partner of a timed fault, so the pair is complete.
                match s {
                    DeviceSetting::StallAt => extra.push((DeviceSetting::StallFor, "1")),
                    DeviceSetting::StallFor => extra.push((DeviceSetting::StallAt, "1")),
                    DeviceSetting::OverCurrentAt => {
                        extra.push((DeviceSetting::OverCurrentFor, "1"))
                    }
                    DeviceSetting::OverCurrentFor => {
                        extra.push((DeviceSetting::OverCurrentAt, "1"))
                    }
                    _ => {}
                }
                let device = kim(&extra).unwrap_or_else(|e| panic!("{s:?} = {text}: {e:?}"));
                assert!(DeviceEmulator::new(device.config).is_ok(), "{s:?} = {text}");
            }
        }
    }

    #[test]
    fn pairs_and_the_machine_are_checked_with_the_setting_named() {
        let e = kim(&[(DeviceSetting::StallAt, "3")]).unwrap_err();
        assert_eq!(e[0].setting, DeviceSetting::StallFor);
        assert_eq!(
            e[0].for_cli(),
            "--stall-s: a stall needs both when it starts and how long it lasts (or neither)"
        );
        let dial = Preset::ALL
            .into_iter()
            .find(|p| p.override_mode().max_pct() < 200.0)
            .unwrap();
        let e = parse_device(&[
            (DeviceSetting::Program, dial.name()),
            (DeviceSetting::Fallback, "200"),
        ])
        .unwrap_err();
        assert_eq!(e[0].setting, DeviceSetting::Fallback);
        let e = parse_device(&[(DeviceSetting::Program, "nope")]).unwrap_err();
        assert!(
            e[0].for_cli()
                .starts_with("--scenario: unknown preset \"nope\""),
            "{}",
            e[0].for_cli()
        );
        let e = parse_device::<&str>(&[]).unwrap_err();
        assert_eq!(e[0].setting, DeviceSetting::Program);
        // The browser's words name no option.
        let e = kim(&[(DeviceSetting::DropRate, "2")]).unwrap_err();
        assert_eq!(e[0].problem.to_string(), "drop rate 2 is outside 0–1");
    }
}
