//! Open-loop recordings of a plant for plotting: every signal a person wants to see, summarised
//! per block of samples (means, and minimum and maximum where a signal swings within the block),
//! so an hour at 10 kHz still fits in a browser and every peak stays visible.
//!
//! [`OpenLoopRun`] advances in chunks, so the browser can run it across frames. The brake bench's
//! phase current is also kept at full rate per load step, for paper 000's spectra and its
//! RMS-versus-load line (Fig. 9 and Fig. 11).

use serde::Serialize;

use super::signals::PlantSignals;
use super::{Plant, PresetMachine};
use crate::machine::{Machine, OverrideCommand};

/// One block of samples, summarised.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct BlockRow {
    /// Time of the block's last sample.
    pub time_s: f64,
    /// Mean cutting force, x.
    pub force_x_n: f64,
    /// Mean cutting force, y.
    pub force_y_n: f64,
    /// Mean cutting force, z.
    pub force_z_n: f64,
    /// Smallest instantaneous resultant in the block.
    pub resultant_min_n: f64,
    /// Largest instantaneous resultant in the block.
    pub resultant_max_n: f64,
    /// Mean spindle cutting torque.
    pub spindle_torque_nm: f64,
    /// Mean cutting power.
    pub cutting_power_w: f64,
    /// Smallest feed phase current i_u as read.
    pub feed_iu_min_a: f64,
    /// Largest feed phase current i_u as read.
    pub feed_iu_max_a: f64,
    /// Smallest spindle phase current i_u as read.
    pub spindle_iu_min_a: f64,
    /// Largest spindle phase current i_u as read.
    pub spindle_iu_max_a: f64,
    /// Mean true RMS current of the feed axis.
    pub feed_rms_a: f64,
    /// Mean true RMS spindle current.
    pub spindle_rms_a: f64,
    /// Mean axial depth of cut.
    pub depth_mm: f64,
    /// Mean path feed.
    pub feed_mm_min: f64,
    /// Mean spindle speed.
    pub spindle_rpm: f64,
    /// Mean brake torque (brake bench only).
    pub brake_torque_nm: f64,
}

/// The feed phase current of one brake-bench load step, at full rate.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LoadStep {
    /// Start of the step.
    pub start_s: f64,
    /// Brake torque during the step.
    pub brake_torque_nm: f64,
    /// Phase current i_u as read, over the settled part of the step.
    pub feed_iu_a: Vec<f64>,
    /// Mean true three-phase RMS current over the same part.
    pub feed_rms_a: f64,
}

#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    n: usize,
    last: BlockRow,
    fx: f64,
    fy: f64,
    fz: f64,
    rmin: f64,
    rmax: f64,
    torque: f64,
    power: f64,
    fmin: f64,
    fmax: f64,
    smin: f64,
    smax: f64,
    feed_rms: f64,
    spindle_rms: f64,
    depth: f64,
    feed: f64,
    rpm: f64,
    brake: f64,
}

/// A plant run at a fixed override, recorded block by block.
pub struct OpenLoopRun {
    machine: PresetMachine,
    command: OverrideCommand,
    block: usize,
    max_samples: usize,
    samples: usize,
    sums: Sums,
    rows: Vec<BlockRow>,
    steps: Vec<LoadStep>,
    step_settle_s: f64,
}

impl OpenLoopRun {
    /// Records `machine` at `override_pct`, one row per `block` samples, for at most `max_s`.
    pub fn new(machine: PresetMachine, override_pct: f64, block: usize, max_s: f64) -> Self {
        let rate = machine.sample_rate_hz();
        Self {
            machine,
            command: OverrideCommand {
                override_pct,
                feed_hold: false,
            },
            block: block.max(1),
            max_samples: (max_s.max(0.0) * rate).min(1e9) as usize,
            samples: 0,
            sums: Sums::default(),
            rows: Vec::new(),
            steps: Vec::new(),
            step_settle_s: 1.0,
        }
    }

    /// Whether the run has ended.
    pub fn finished(&self) -> bool {
        self.machine.finished() || self.samples >= self.max_samples
    }

    /// Fraction of the time limit done.
    pub fn fraction(&self) -> f64 {
        if self.max_samples == 0 {
            1.0
        } else {
            self.samples as f64 / self.max_samples as f64
        }
    }

    /// Runs at most `samples` samples; returns true once finished.
    pub fn advance(&mut self, samples: usize) -> bool {
        for _ in 0..samples {
            if self.finished() {
                break;
            }
            self.machine.step(self.command);
            self.samples += 1;
            let s = *self.machine.signals();
            self.keep_load_step(&s);
            self.push(&s);
        }
        self.finished()
    }

    /// The rows so far.
    pub fn rows(&self) -> &[BlockRow] {
        &self.rows
    }

    /// The brake bench's load steps so far (empty for other plants).
    pub fn load_steps(&self) -> &[LoadStep] {
        &self.steps
    }

    fn keep_load_step(&mut self, s: &PlantSignals) {
        if !matches!(self.machine, PresetMachine::BrakeBench(_)) {
            return;
        }
        let torque = s.brake_torque_nm;
        // A new torque level is a new step (the brake's torque changes in one sample).
        let new_step = self
            .steps
            .last()
            .is_none_or(|last| (last.brake_torque_nm - torque).abs() > 1e-9);
        if new_step {
            self.steps.push(LoadStep {
                start_s: s.time_s,
                brake_torque_nm: torque,
                feed_iu_a: Vec::new(),
                feed_rms_a: 0.0,
            });
        }
        if let Some(step) = self.steps.last_mut() {
            if s.time_s - step.start_s >= self.step_settle_s {
                let n = step.feed_iu_a.len() as f64;
                step.feed_rms_a = (step.feed_rms_a * n + s.truth.feed_current_rms_a) / (n + 1.0);
                step.feed_iu_a.push(s.feed_currents_read_a[0]);
            }
        }
    }

    fn push(&mut self, s: &PlantSignals) {
        let block_ends = self.sums.n + 1 >= self.block || self.finished();
        let a = &mut self.sums;
        let first = a.n == 0;
        a.n += 1;
        let r = s.truth.force_resultant_n;
        let (fu, su) = (s.feed_currents_read_a[0], s.spindle_currents_read_a[0]);
        a.fx += s.truth.force_x_n;
        a.fy += s.truth.force_y_n;
        a.fz += s.truth.force_z_n;
        a.rmin = if first { r } else { a.rmin.min(r) };
        a.rmax = if first { r } else { a.rmax.max(r) };
        a.fmin = if first { fu } else { a.fmin.min(fu) };
        a.fmax = if first { fu } else { a.fmax.max(fu) };
        a.smin = if first { su } else { a.smin.min(su) };
        a.smax = if first { su } else { a.smax.max(su) };
        a.torque += s.truth.spindle_torque_nm;
        a.power += s.truth.cutting_power_w;
        a.feed_rms += s.truth.feed_current_rms_a;
        a.spindle_rms += s.truth.spindle_current_rms_a;
        a.depth += if s.truth.depth_mm.is_finite() {
            s.truth.depth_mm
        } else {
            0.0
        };
        a.feed += s.feed_mm_min;
        a.rpm += s.spindle_speed_rpm;
        a.brake += s.brake_torque_nm;
        a.last.time_s = s.time_s;
        if block_ends {
            let n = a.n as f64;
            self.rows.push(BlockRow {
                time_s: a.last.time_s,
                force_x_n: a.fx / n,
                force_y_n: a.fy / n,
                force_z_n: a.fz / n,
                resultant_min_n: a.rmin,
                resultant_max_n: a.rmax,
                spindle_torque_nm: a.torque / n,
                cutting_power_w: a.power / n,
                feed_iu_min_a: a.fmin,
                feed_iu_max_a: a.fmax,
                spindle_iu_min_a: a.smin,
                spindle_iu_max_a: a.smax,
                feed_rms_a: a.feed_rms / n,
                spindle_rms_a: a.spindle_rms / n,
                depth_mm: a.depth / n,
                feed_mm_min: a.feed / n,
                spindle_rpm: a.rpm / n,
                brake_torque_nm: a.brake / n,
            });
            *a = Sums::default();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::Preset;

    #[test]
    fn blocks_summarise_means_and_extremes() {
        let machine = Preset::ManeeratDoc1.machine(1).unwrap();
        let mut run = OpenLoopRun::new(machine, 100.0, 100, 5.0);
        while !run.advance(10_000) {}
        let rows = run.rows();
        assert_eq!(rows.len(), 500);
        assert!((rows[499].time_s - 5.0).abs() < 1e-9);
        for r in rows {
            assert!(r.resultant_min_n <= r.resultant_max_n);
            assert!(r.feed_iu_min_a <= r.feed_iu_max_a);
        }
        assert!(
            rows.iter().any(|r| r.resultant_max_n > 0.0),
            "the tool never cut"
        );
    }

    #[test]
    fn the_brake_bench_keeps_each_load_step_at_full_rate() {
        let machine = Preset::WangBrakeBench.machine(1).unwrap();
        let mut run = OpenLoopRun::new(machine, 100.0, 100, 12.0);
        while !run.advance(50_000) {}
        let steps = run.load_steps();
        assert!(steps.len() >= 3, "{} steps", steps.len());
        // Each complete step keeps its settled part at 10 kHz.
        assert!(steps[1].feed_iu_a.len() > 10_000);
        assert!(steps[2].brake_torque_nm > steps[0].brake_torque_nm);
        assert!(steps[2].feed_rms_a > steps[0].feed_rms_a);
    }
}
