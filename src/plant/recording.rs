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
use crate::signal::stats::MinMeanMax;

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

/// The block being summarised: one accumulator per plotted signal.
#[derive(Debug, Clone, Copy, Default)]
struct Block {
    end_time_s: f64,
    force_x_n: MinMeanMax,
    force_y_n: MinMeanMax,
    force_z_n: MinMeanMax,
    resultant_n: MinMeanMax,
    spindle_torque_nm: MinMeanMax,
    cutting_power_w: MinMeanMax,
    feed_iu_a: MinMeanMax,
    spindle_iu_a: MinMeanMax,
    feed_rms_a: MinMeanMax,
    spindle_rms_a: MinMeanMax,
    depth_mm: MinMeanMax,
    feed_mm_min: MinMeanMax,
    spindle_rpm: MinMeanMax,
    brake_torque_nm: MinMeanMax,
}

impl Block {
    fn push(&mut self, s: &PlantSignals) {
        let t = &s.truth;
        self.end_time_s = s.time_s;
        self.force_x_n.push(t.force_x_n);
        self.force_y_n.push(t.force_y_n);
        self.force_z_n.push(t.force_z_n);
        self.resultant_n.push(t.force_resultant_n);
        self.spindle_torque_nm.push(t.spindle_torque_nm);
        self.cutting_power_w.push(t.cutting_power_w);
        self.feed_iu_a.push(s.feed_currents_read_a[0]);
        self.spindle_iu_a.push(s.spindle_currents_read_a[0]);
        self.feed_rms_a.push(t.feed_current_rms_a);
        self.spindle_rms_a.push(t.spindle_current_rms_a);
        // A plant without a depth (the bond graph) plots as no depth rather than a gap.
        self.depth_mm.push(if t.depth_mm.is_finite() {
            t.depth_mm
        } else {
            0.0
        });
        self.feed_mm_min.push(s.feed_mm_min);
        self.spindle_rpm.push(s.spindle_speed_rpm);
        self.brake_torque_nm.push(s.brake_torque_nm);
    }

    fn samples(&self) -> usize {
        self.force_x_n.count()
    }

    fn row(&self) -> BlockRow {
        BlockRow {
            time_s: self.end_time_s,
            force_x_n: self.force_x_n.mean(),
            force_y_n: self.force_y_n.mean(),
            force_z_n: self.force_z_n.mean(),
            resultant_min_n: self.resultant_n.min(),
            resultant_max_n: self.resultant_n.max(),
            spindle_torque_nm: self.spindle_torque_nm.mean(),
            cutting_power_w: self.cutting_power_w.mean(),
            feed_iu_min_a: self.feed_iu_a.min(),
            feed_iu_max_a: self.feed_iu_a.max(),
            spindle_iu_min_a: self.spindle_iu_a.min(),
            spindle_iu_max_a: self.spindle_iu_a.max(),
            feed_rms_a: self.feed_rms_a.mean(),
            spindle_rms_a: self.spindle_rms_a.mean(),
            depth_mm: self.depth_mm.mean(),
            feed_mm_min: self.feed_mm_min.mean(),
            spindle_rpm: self.spindle_rpm.mean(),
            brake_torque_nm: self.brake_torque_nm.mean(),
        }
    }
}

/// A plant run at a fixed override, recorded block by block.
pub struct OpenLoopRun {
    machine: PresetMachine,
    command: OverrideCommand,
    block: usize,
    max_samples: usize,
    samples: usize,
    block_sums: Block,
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
            block_sums: Block::default(),
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
        let block_ends = self.block_sums.samples() + 1 >= self.block || self.finished();
        self.block_sums.push(s);
        if block_ends {
            self.rows.push(self.block_sums.row());
            self.block_sums = Block::default();
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
