//! The emulator made ([`DeviceEmulator::new`]): every check of a configuration, the Capabilities
//! the device declares, and the machines of the parts, seeded as `cutlab sim` seeds its own.

use super::faults::PhaseWindow;
use super::{
    cpct, DeviceConfig, DeviceEmulator, DeviceError, DeviceStats, CURRENT_A_PER_COUNT,
    DISARMED_OVERRIDE_PCT, FALLBACK_LIMIT_RANGE_S, FAULT_RATE_RANGE, FV_V_PER_COUNT,
    WATCHDOG_RANGE_S,
};
use crate::machine::{Machine, OverrideCommand};
use crate::plant::cnc::{AppliedOverride, OverrideMode};
use crate::plant::presets::PlantEdits;
use crate::protocol::codec::Decoder;
use crate::protocol::frame::{
    channel, feature, padded, Capabilities, OverrideModeCode, VERSION_MAJOR, VERSION_MINOR,
};
use crate::rng::Rng;

impl DeviceEmulator {
    /// An emulator of `config.preset`, powered on, waiting for a Hello.
    pub fn new(config: DeviceConfig) -> Result<Self, DeviceError> {
        let bad = |what: &str, v: f64| DeviceError(format!("{what} cannot be {v}"));
        let within = |v: f64, (lo, hi): (f64, f64)| v >= lo && v <= hi;
        let rate = |p: f64| within(p, FAULT_RATE_RANGE);
        let f = &config.faults;
        if !rate(f.drop_rate) {
            return Err(bad("the drop rate (0 to 1)", f.drop_rate));
        }
        if !rate(f.noise_rate) {
            return Err(bad("the noise rate (0 to 1)", f.noise_rate));
        }
        if !(f.stall_s.is_finite() && f.stall_s >= 0.0) {
            return Err(bad("the stall's length", f.stall_s));
        }
        if !(f.over_current_s.is_finite() && f.over_current_s >= 0.0) {
            return Err(bad("the over-current's length", f.over_current_s));
        }
        for t in [
            f.stall_at_s,
            f.unplug_at_s,
            f.estop_at_s,
            f.over_current_at_s,
        ]
        .into_iter()
        .flatten()
        {
            if !(t.is_finite() && t >= 0.0) {
                return Err(bad("a fault's time", t));
            }
        }
        for t in [f.sensor_open_at_s, f.stuck_override_at_s]
            .into_iter()
            .flatten()
        {
            if !(t.is_finite() && t >= 0.0) {
                return Err(bad("a fault's time", t));
            }
        }
        if !within(config.fallback_limit_s, FALLBACK_LIMIT_RANGE_S) {
            return Err(bad(
                "the fallback's time limit (0.1 to 65 s)",
                config.fallback_limit_s,
            ));
        }
        if !within(config.watchdog_timeout_s, WATCHDOG_RANGE_S) {
            return Err(bad(
                "the watchdog timeout (0.001 to 65 s)",
                config.watchdog_timeout_s,
            ));
        }
        if !(1..=1000).contains(&config.decimation) {
            return Err(DeviceError(format!(
                "the decimation must be 1 to 1000 plant samples, not {}",
                config.decimation
            )));
        }
        let mode = config.preset.override_mode();
        let max_pct = mode.max_pct();
        let min_pct = 0.0;
        if !(config.fallback_override_pct >= min_pct && config.fallback_override_pct <= max_pct) {
            return Err(bad("the fallback override", config.fallback_override_pct));
        }
        let mut parts = Self::machines(&config, 0)?;
        parts.reverse();
        let plant_rate_hz = parts.last().map_or(10_000.0, |m| m.sample_rate_hz());
        let (override_mode, dial_cpct) = match mode {
            OverrideMode::Dial(table) => {
                (OverrideModeCode::Dial16, table.percent_by_code.map(cpct))
            }
            OverrideMode::WholePercent => (OverrideModeCode::WholePercent, [0; 16]),
            OverrideMode::Continuous => (OverrideModeCode::Continuous, [0; 16]),
        };
        let capabilities = Capabilities {
            version_major: VERSION_MAJOR,
            version_minor: VERSION_MINOR,
            device_id: padded("cutlab-emulator"),
            program: padded(config.preset.name()),
            channel_mask: channel::SPINDLE_U
                | channel::SPINDLE_V
                | channel::SPINDLE_W
                | channel::FEED_U
                | channel::FEED_V
                | channel::FEED_W
                | channel::SPINDLE_FV,
            spindle_current_a_per_count: CURRENT_A_PER_COUNT as f32,
            feed_current_a_per_count: CURRENT_A_PER_COUNT as f32,
            fv_v_per_count: FV_V_PER_COUNT as f32,
            sample_rate_hz: (plant_rate_hz / config.decimation as f64) as f32,
            override_mode,
            min_override_cpct: cpct(min_pct),
            max_override_cpct: cpct(max_pct),
            dial_cpct,
            watchdog_timeout_ms: (config.watchdog_timeout_s * 1000.0).round() as u16,
            fallback_override_cpct: cpct(config.fallback_override_pct),
            over_current_a: config.over_current_a as f32,
            measured: config.measured,
            fallback_limit_ms: (config.fallback_limit_s * 1000.0).round() as u16,
            line_baud: config.line_baud,
            features: if config.sim_truth {
                feature::SIM_TRUTH
            } else {
                0
            } | if config.faults.estop_at_s.is_some() {
                feature::ESTOP_INPUT
            } else {
                0
            },
        };
        Ok(Self {
            rng: Rng::fork(config.seed, 0xDE71CE),
            capabilities,
            applied: mode.apply(
                DISARMED_OVERRIDE_PCT,
                AppliedOverride {
                    pct: DISARMED_OVERRIDE_PCT,
                    dial_code: None,
                },
            ),
            mode,
            min_pct,
            max_pct,
            plant_dt_s: 1.0 / plant_rate_hz,
            ticks: 0,
            decoder: Decoder::new(),
            next_parts: parts,
            part: None,
            armed: false,
            fallback: false,
            estop: false,
            requested: OverrideCommand::default(),
            last_host_frame_s: 0.0,
            next_heartbeat_s: 0.0,
            sample_seq: 0,
            fault_seq: 0,
            heartbeat_seq: 0,
            over_current: false,
            sensor_fault: false,
            phase_windows: [PhaseWindow::default(); 2],
            phase_window_n: 0,
            phase_fault: [None; 2],
            fallback_pct: config.fallback_override_pct,
            fallback_since_s: 0.0,
            hold_latched: None,
            last_command_seq: None,
            stuck_override: None,
            trace: Vec::new(),
            stats: DeviceStats::default(),
            stalled: false,
            unplugged: false,
            diagnostics: Vec::new(),
            config,
        })
    }

    /// The machines of parts `first` and `first + 1`, seeded as `cutlab sim` seeds its teach cut
    /// and run (for `first` = 0: [`Preset::teach_and_run_machines`]), or as runs with the seed
    /// plus the part's number. A bridge carries no dynamometer.
    ///
    /// [`Preset::teach_and_run_machines`]: crate::plant::Preset::teach_and_run_machines
    pub(super) fn machines(
        config: &DeviceConfig,
        first: u64,
    ) -> Result<Vec<Box<dyn Machine>>, DeviceError> {
        let seed = config.seed.wrapping_add(first);
        let edits = PlantEdits::default();
        let machines = if first == 0 {
            config
                .preset
                .teach_and_run_machines(seed, &edits, false)
                .map(Vec::from)
        } else {
            config
                .preset
                .seeded_machine(seed, &edits, false)
                .map(|m| vec![m])
        };
        machines.map_err(|e| DeviceError(format!("machine: {e}")))
    }
}
