//! A block of plant samples averaged into what the device sends: a SimTruth with the block's
//! truth and a Sample of its currents, speed and feed in counts, as an oversampling ADC would;
//! the trace row of the block.

use super::faults::judge_phases;
use super::{DeviceEmulator, DeviceTraceRow, PHASE_CHECK_WINDOW_S};
use crate::machine::{OverrideCommand, PlantTruth, SensorSample};
use crate::protocol::frame::{sample_flag, Frame, Sample, SimTruth, NO_DIAL_CODE};
use crate::truth_fields::TRUTH_VALUES;

/// Amperes per count of the emulator's current channels.
pub const CURRENT_A_PER_COUNT: f64 = 0.005;
/// Volts per count of the emulator's F/V channel.
pub const FV_V_PER_COUNT: f64 = 0.0005;

/// Sums of one block of plant samples.
#[derive(Debug, Clone, Copy, Default)]
struct SampleSums {
    n: usize,
    spindle: [f64; 3],
    feed: [f64; 3],
    fv: f64,
    speed: f64,
    feed_mm_min: f64,
    truth: [f64; TRUTH_VALUES],
    last: SensorSample,
    last_truth: PlantTruth,
    truth_seen: bool,
}

/// Counts of `value` at `per_count`, saturating at the ADC's range (NaN reads 0: a real ADC has
/// no NaN; the sensor fault reports it).
fn counts(value: f64, per_count: f64) -> i16 {
    let c = (value / per_count).round();
    if c.is_nan() {
        0
    } else {
        c.clamp(f64::from(i16::MIN), f64::from(i16::MAX)) as i16
    }
}

/// An override in hundredths of a percent, saturating.
///
/// ```
/// use cutlab::protocol::device::cpct;
/// assert_eq!((cpct(87.6), cpct(-3.0), cpct(1e9), cpct(f64::NAN)), (8760, 0, 65535, 0));
/// ```
pub fn cpct(pct: f64) -> u16 {
    let c = (pct * 100.0).round();
    if c.is_nan() {
        0
    } else {
        c.clamp(0.0, f64::from(u16::MAX)) as u16
    }
}

impl DeviceEmulator {
    /// One block of plant samples, summarised into a SimTruth and a Sample.
    pub(super) fn run_block(&mut self, out: &mut Vec<u8>) {
        let f = self.config.faults;
        let t0 = self.time_s();
        if self.stuck_override.is_none() && f.stuck_override_at_s.is_some_and(|at| t0 >= at) {
            self.log("the CNC ignores the bridge's outputs from now on (injected)".to_string());
            self.stuck_override = Some(OverrideCommand {
                override_pct: self.applied.pct,
                feed_hold: false,
            });
        }
        let feed_hold = self.feed_hold();
        // What the CNC takes: the bridge's outputs, or what it kept when it stopped listening
        // (a feed hold still reaches it through its own contact in the feed-hold chain).
        let command = OverrideCommand {
            override_pct: self
                .stuck_override
                .map_or(self.applied.pct, |c| c.override_pct),
            feed_hold,
        };
        let sensor_open = f.sensor_open_at_s.is_some_and(|at| t0 >= at);
        let window_n = ((PHASE_CHECK_WINDOW_S / self.plant_dt_s).round() as usize).max(1);
        let mut block = SampleSums::default();
        let mut over_current = false;
        let mut non_finite = false;
        let mut ended = false;
        let limit = self.config.over_current_a;
        if let Some(part) = self.part.as_mut() {
            for _ in 0..self.config.decimation {
                let step = part.machine.step(command);
                self.ticks += 1;
                let s = step.sensors;
                let mut spindle = s.spindle_phase_currents_a;
                if sensor_open {
                    spindle[0] = 0.0;
                }
                for (sum, i) in block.spindle.iter_mut().zip(spindle) {
                    *sum += i;
                }
                for (sum, i) in block.feed.iter_mut().zip(s.feed_phase_currents_a) {
                    *sum += i;
                }
                for i in spindle.iter().chain(&s.feed_phase_currents_a) {
                    non_finite |= !i.is_finite();
                    over_current |= i.abs() > limit;
                }
                self.phase_windows[0].add(spindle);
                self.phase_windows[1].add(s.feed_phase_currents_a);
                self.phase_window_n += 1;
                if self.phase_window_n >= window_n {
                    judge_phases(
                        &mut self.phase_windows,
                        &mut self.phase_window_n,
                        &mut self.phase_fault,
                    );
                }
                block.fv += s.spindle_fv_voltage_v;
                block.speed += s.spindle_speed_rpm;
                block.feed_mm_min += s.feed_mm_min;
                block.last = s;
                if let Some(t) = step.truth {
                    for (sum, v) in block.truth.iter_mut().zip(t.wire_values()) {
                        *sum += v;
                    }
                    block.last_truth = t;
                    block.truth_seen = true;
                }
                block.n += 1;
                if part.machine.finished() {
                    part.ended = true;
                    ended = true;
                    break;
                }
            }
        }
        let t = self.time_s();
        over_current |= f
            .over_current_at_s
            .is_some_and(|at| t > at && t <= at + f.over_current_s);
        self.watch_currents(over_current, non_finite, out);
        let n = block.n.max(1) as f64;
        self.sample_seq = self.sample_seq.wrapping_add(1);
        if block.truth_seen && self.config.sim_truth {
            let mut mean = PlantTruth::from_wire_values(block.truth.map(|sum| sum / n));
            // Positions are where the tool is at the block's end, not on average.
            let last = &block.last_truth;
            mean.path_position_mm = last.path_position_mm;
            mean.tool_x_mm = last.tool_x_mm;
            mean.tool_y_mm = last.tool_y_mm;
            let v = mean.wire_values().map(|value| value as f32);
            self.send(
                &Frame::SimTruth(SimTruth::from_values(self.sample_seq, v)),
                out,
            );
        }
        let last = block.last;
        let mut flags = sample_flag::IN_CYCLE | (self.state_flags() & !sample_flag::IN_CYCLE);
        for (on, bit) in [
            (last.spindle_running, sample_flag::SPINDLE_RUNNING),
            (ended, sample_flag::PROGRAM_END),
        ] {
            if on {
                flags |= bit;
            }
        }
        let faults = self.fault_flags();
        let sample = Sample {
            seq: self.sample_seq,
            time_us: self.time_us(),
            flags,
            spindle_current_counts: block.spindle.map(|i| counts(i / n, CURRENT_A_PER_COUNT)),
            feed_current_counts: block.feed.map(|i| counts(i / n, CURRENT_A_PER_COUNT)),
            fv_counts: counts(block.fv / n, FV_V_PER_COUNT),
            spindle_speed_rpm: (block.speed / n) as f32,
            spindle_command_rpm: last.spindle_command_rpm as f32,
            programmed_feed_mm_min: last.programmed_feed_mm_min as f32,
            feed_mm_min: (block.feed_mm_min / n) as f32,
            applied_override_cpct: cpct(last.applied_override_pct),
            dial_code: self.applied.dial_code.unwrap_or(NO_DIAL_CODE),
            faults,
        };
        self.send(&Frame::Sample(sample), out);
        if self.config.trace {
            self.trace.push(DeviceTraceRow {
                time_s: t,
                part: self.stats.parts,
                seq: self.sample_seq,
                armed: self.armed && !self.fallback,
                fallback: self.fallback,
                feed_hold,
                hold_latched: self.hold_latched,
                bridge_override_pct: self.applied.pct,
                cnc_override_pct: last.applied_override_pct,
                programmed_feed_mm_min: last.programmed_feed_mm_min,
                feed_mm_min: block.feed_mm_min / n,
                faults,
            });
        }
        if ended {
            let n = self.stats.parts;
            self.log(format!("part {n}: program end"));
            self.part = None;
        }
    }
}
