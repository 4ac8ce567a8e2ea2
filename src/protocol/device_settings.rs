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
use crate::input::table::{Kind, Problem, Row, RowError, Shown, Table, Value};
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
        let (key, cli_option, label, unit, kind, default, noun, help) = match self {
            D::Program => (
                "program",
                "scenario",
                "Program (preset)",
                "",
                Kind::Choice,
                Shown::Blank,
                "preset",
                "the preset whose machine and program the device emulates (see cutlab scenarios)",
            ),
            D::Seed => (
                "seed",
                "seed",
                "Seed",
                "",
                Kind::Seed,
                Shown::Seed(1),
                "seed",
                "seed of the machines (as cutlab sim --seed) and of the injected faults",
            ),
            D::TimeScale => (
                "time_scale",
                "time-scale",
                "Time scale",
                "× real time",
                range(TIME_SCALE_RANGE),
                Shown::Number(1.0),
                "time scale",
                "device seconds per wall second (1: real time); the device's watchdog, in device \
                 time, is that much shorter in wall time. In the browser the virtual device runs \
                 at most 400 frames per 10 ms tick (40× real time); faster, it lags its clock",
            ),
            D::DropRate => (
                "drop_rate",
                "drop-rate",
                "Drop rate",
                "per frame",
                range(FAULT_RATE_RANGE),
                Shown::Number(0.0),
                "drop rate",
                "probability that a frame, either way, is lost",
            ),
            D::NoiseRate => (
                "noise_rate",
                "noise-rate",
                "Noise rate",
                "per frame",
                range(FAULT_RATE_RANGE),
                Shown::Number(0.0),
                "noise rate",
                "probability that a frame, either way, is corrupted",
            ),
            D::StallAt => (
                "stall_at",
                "stall-at-s",
                "Receiver stall at (blank: none)",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "stall the device's receiver at this device time (with its length)",
            ),
            D::StallFor => (
                "stall_for",
                "stall-s",
                "Receiver stall for",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "length of the receiver stall, device seconds",
            ),
            D::UnplugAt => (
                "unplug_at",
                "unplug-at-s",
                "Cable pulled at (blank: never)",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "pull the cable at this device time: nothing in or out from then on",
            ),
            D::Watchdog => (
                "watchdog",
                "watchdog-s",
                "Device watchdog",
                "s",
                range(WATCHDOG_RANGE_S),
                Shown::Number(DEFAULT_WATCHDOG_S),
                "",
                "the device's watchdog timeout, device seconds",
            ),
            D::Fallback => (
                "fallback",
                "fallback-pct",
                "Device fallback override",
                "%",
                Kind::Number {
                    min: 0.0,
                    max: crate::plant::cnc::MAX_OVERRIDE_PCT,
                },
                Shown::Number(DEFAULT_FALLBACK_PCT),
                "",
                "the override the watchdog applies at most (the fallback is the lower of it and \
                 the override applied when the watchdog fires; at most what the machine applies)",
            ),
            D::FallbackLimit => (
                "fallback_limit",
                "fallback-limit-s",
                "Fallback time limit",
                "s",
                range(FALLBACK_LIMIT_RANGE_S),
                Shown::Number(DEFAULT_FALLBACK_LIMIT_S),
                "",
                "how long the fallback lasts before the device holds the feed, latched until the \
                 operator's reset, device seconds",
            ),
            D::LineBaud => (
                "line_baud",
                "line-baud",
                "Declared line speed (0: none)",
                "bit/s",
                Kind::Count {
                    min: 0,
                    max: u32::MAX as usize,
                },
                Shown::Count(0),
                "",
                "the baud rate the device declares for its line (0: none, as a pipe); the host \
                 refuses a stream that does not fit it",
            ),
            D::OverCurrentAt => (
                "over_current_at",
                "over-current-at-s",
                "Over-current at (blank: none)",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "read an over-current from this device time (with its length) while a part runs",
            ),
            D::OverCurrentFor => (
                "over_current_for",
                "over-current-s",
                "Over-current for",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "length of the over-current, device seconds",
            ),
            D::EstopAt => (
                "estop_at",
                "estop-at-s",
                "E-stop at (blank: never)",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "make the E-stop input active at this device time (it stays active; the device \
                 then declares an E-stop input)",
            ),
            D::SensorOpenAt => (
                "sensor_open_at",
                "sensor-open-at-s",
                "Spindle transducer opens at (blank: never)",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "open the spindle's phase-u transducer at this device time: it reads 0 A from then on",
            ),
            D::StuckOverrideAt => (
                "stuck_override_at",
                "stuck-override-at-s",
                "Override stuck from (blank: never)",
                "s",
                DEVICE_TIME_S,
                Shown::Blank,
                "",
                "make the CNC ignore the bridge's override outputs from this device time on (it \
                 keeps the override it had; the bridge goes on acknowledging what it outputs)",
            ),
        };
        Row {
            key,
            cli_option,
            label,
            unit,
            help,
            kind,
            default,
            noun,
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
    let mut errors = Vec::new();
    let values: Vec<(DeviceSetting, Option<Value>)> = DeviceSetting::ROWS
        .iter()
        .map(|&s| {
            let text = texts
                .iter()
                .rev()
                .find(|(given, _)| *given == s)
                .map(|(_, t)| t.as_ref());
            match s.parse_given(text) {
                Ok(value) => (s, value),
                Err(e) => {
                    errors.push(e);
                    (s, None)
                }
            }
        })
        .collect();
    let value = |s: DeviceSetting| values.iter().find(|(v, _)| *v == s).and_then(|(_, v)| *v);
    let number = |s: DeviceSetting| value(s).and_then(Value::number);
    let preset = value(DeviceSetting::Program)
        .and_then(Value::choice)
        .and_then(Preset::from_name);
    if preset.is_none() && errors.iter().all(|e| e.setting != DeviceSetting::Program) {
        errors.push(RowError::new(
            DeviceSetting::Program,
            Problem::Parse("choose the preset the device emulates".to_string()),
        ));
    }
    for (at, length, what) in [
        (
            DeviceSetting::StallAt,
            DeviceSetting::StallFor,
            "a stall needs both when it starts and how long it lasts (or neither)",
        ),
        (
            DeviceSetting::OverCurrentAt,
            DeviceSetting::OverCurrentFor,
            "an over-current needs both when it starts and how long it lasts (or neither)",
        ),
    ] {
        let failed = |s| errors.iter().any(|e: &RowError<_>| e.setting == s);
        if failed(at) || failed(length) {
            continue;
        }
        match (number(at).is_some(), number(length).is_some()) {
            (true, false) => errors.push(RowError::other(length, what)),
            (false, true) => errors.push(RowError::other(at, what)),
            _ => {}
        }
    }
    if let (Some(p), Some(fallback)) = (preset, number(DeviceSetting::Fallback)) {
        let max = p.override_mode().max_pct();
        if fallback > max {
            errors.push(RowError::other(
                DeviceSetting::Fallback,
                format!(
                    "{} % is more than this machine applies ({} %)",
                    crate::input::readable(fallback),
                    crate::input::readable(max)
                ),
            ));
        }
    }
    let Some(preset) = preset.filter(|_| errors.is_empty()) else {
        return Err(errors);
    };
    let mut config = DeviceConfig::new(preset);
    let set = |s: DeviceSetting, slot: &mut f64| {
        if let Some(v) = number(s) {
            *slot = v;
        }
    };
    set(DeviceSetting::Watchdog, &mut config.watchdog_timeout_s);
    set(DeviceSetting::Fallback, &mut config.fallback_override_pct);
    set(DeviceSetting::FallbackLimit, &mut config.fallback_limit_s);
    if let Some(seed) = value(DeviceSetting::Seed).and_then(Value::seed) {
        config.seed = seed;
    }
    if let Some(baud) = value(DeviceSetting::LineBaud).and_then(Value::count) {
        // The row's range is a u32's.
        config.line_baud = u32::try_from(baud).unwrap_or(u32::MAX);
    }
    config.faults = FaultInjection {
        drop_rate: number(DeviceSetting::DropRate).unwrap_or(0.0),
        noise_rate: number(DeviceSetting::NoiseRate).unwrap_or(0.0),
        stall_at_s: number(DeviceSetting::StallAt),
        stall_s: number(DeviceSetting::StallFor).unwrap_or(0.0),
        unplug_at_s: number(DeviceSetting::UnplugAt),
        estop_at_s: number(DeviceSetting::EstopAt),
        over_current_at_s: number(DeviceSetting::OverCurrentAt),
        over_current_s: number(DeviceSetting::OverCurrentFor).unwrap_or(0.0),
        sensor_open_at_s: number(DeviceSetting::SensorOpenAt),
        stuck_override_at_s: number(DeviceSetting::StuckOverrideAt),
    };
    Ok(VirtualDevice {
        config,
        time_scale: number(DeviceSetting::TimeScale).unwrap_or(1.0),
    })
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
