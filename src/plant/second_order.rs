//! Paper 001's plant: a second-order force process, usable as the whole machine.
//!
//! Maneerat et al. model the feed drive and the milling process as
//!
//! ```text
//! m·ẍ + d·ẋ = f_r            (eq 2.1: the table answers the control signal f_r)
//! k·v = Ḟ_c + c·F_c          (eq 2.2: the force builds up with the table speed v = ẋ)
//! m·F̈_c + (mc + d)·Ḟ_c + dc·F_c = k·f_r     (eq 2.3)
//! ```
//!
//! The paper gives no numbers. cutlab takes the control signal to be the CNC's commanded feed in
//! mm/min with d = 1, so m = τ_f is the feed drive's time constant in seconds, c = 1/τ_c the
//! force's build-up rate, and k/(d·c) = G the static gain in N per mm/min. Writing
//! F_c = G·y with ẏ = c·(v − y) keeps eq 2.3 exactly for a constant G and lets G follow the depth
//! along the path (a depth step then changes the force at once, as it does in a cut).
//! [`SecondOrderConfig::paper_coefficients`] gives m, d, c, k back.
//!
//! [`SecondOrderMachine`] runs the process with the mill's CNC, drives and sensors: the one force
//! acts against the feed and makes the spindle torque R·F/√(1 + r²).

use serde::{Deserialize, Serialize};

use super::cnc::{Control, PlanBlock};
use super::feed_drive::{three_phase_rms_a, FeedDrive};
use super::linalg::{self, Mat};
use super::scenario::Profile;
use super::sensors::CurrentSensor;
use super::signals::{AxisSignals, PlantSignals};
use super::spindle_drive::SpindleDrive;
use super::{
    non_negative, positive, PlantError, PlantModel, PlantSample, Sampling, Tick, S_PER_MIN,
};
use crate::machine::{OverrideCommand, PlantTruth, SensorSample};
use crate::math;

/// Paper 001's process in cutlab's parameters.
///
/// ```
/// use cutlab::plant::second_order::SecondOrderConfig;
/// let c = SecondOrderConfig::new(0.05, 0.02, 0.4).unwrap();
/// let p = c.paper_coefficients();
/// assert_eq!((p.m, p.d, p.c), (0.05, 1.0, 50.0));
/// assert!((p.k - 0.4 * 50.0).abs() < 1e-12);              // k = G·c·d
/// assert!((p.mc_plus_d - (0.05 * 50.0 + 1.0)).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct SecondOrderConfig {
    /// τ_f = m/d: how fast the table follows the feed command.
    pub feed_time_constant_s: f64,
    /// τ_c = 1/c: how fast the force builds up with the feed.
    pub force_time_constant_s: f64,
    /// G = k/(d·c): static force per commanded feed.
    pub force_gain_n_per_mm_min: f64,
}

/// Paper 001's m, d, c, k (eq 2.3) for f_r in mm/min and F in N.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct PaperCoefficients {
    /// m (s, with d = 1).
    pub m: f64,
    /// d (1).
    pub d: f64,
    /// c (1/s).
    pub c: f64,
    /// k (N per mm/min per s).
    pub k: f64,
    /// mc + d, eq 2.3's first-derivative coefficient (α in the adaptive law).
    pub mc_plus_d: f64,
    /// dc, eq 2.3's zeroth-derivative coefficient (β).
    pub dc: f64,
}

impl SecondOrderConfig {
    /// A process with positive time constants and a gain ≥ 0.
    pub fn new(
        feed_time_constant_s: f64,
        force_time_constant_s: f64,
        force_gain_n_per_mm_min: f64,
    ) -> Result<Self, PlantError> {
        let c = Self {
            feed_time_constant_s,
            force_time_constant_s,
            force_gain_n_per_mm_min,
        };
        c.validate()?;
        Ok(c)
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("feed_time_constant_s", self.feed_time_constant_s)?;
        positive("force_time_constant_s", self.force_time_constant_s)?;
        non_negative("force_gain_n_per_mm_min", self.force_gain_n_per_mm_min)?;
        Ok(())
    }

    /// m, d, c, k of eq 2.3.
    pub fn paper_coefficients(&self) -> PaperCoefficients {
        let m = self.feed_time_constant_s;
        let d = 1.0;
        let c = 1.0 / self.force_time_constant_s;
        let k = self.force_gain_n_per_mm_min * c * d;
        PaperCoefficients {
            m,
            d,
            c,
            k,
            mc_plus_d: m * c + d,
            dc: d * c,
        }
    }

    /// The force at `time_s` after a step of the feed command to `feed_mm_min` from rest: the
    /// closed-form solution of eq 2.3.
    ///
    /// ```
    /// use cutlab::plant::second_order::SecondOrderConfig;
    /// let c = SecondOrderConfig::new(0.05, 0.02, 0.4).unwrap();
    /// assert!((c.step_response_n(10.0, 500.0) - 200.0).abs() < 1e-9);
    /// assert_eq!(c.step_response_n(0.0, 500.0), 0.0);
    /// ```
    pub fn step_response_n(&self, time_s: f64, feed_mm_min: f64) -> f64 {
        if time_s <= 0.0 {
            return 0.0;
        }
        let (tf, tc) = (self.feed_time_constant_s, self.force_time_constant_s);
        let shape = if (tf - tc).abs() < 1e-12 * tf {
            1.0 - (1.0 + time_s / tf) * math::exp(-time_s / tf)
        } else {
            1.0 - (tf * math::exp(-time_s / tf) - tc * math::exp(-time_s / tc)) / (tf - tc)
        };
        self.force_gain_n_per_mm_min * feed_mm_min * shape
    }
}

/// The process's state, stepped exactly for a command held over each sample.
///
/// ```
/// use cutlab::plant::second_order::{SecondOrderConfig, SecondOrderProcess};
/// let cfg = SecondOrderConfig::new(0.05, 0.02, 0.4).unwrap();
/// let mut p = SecondOrderProcess::new(cfg, 1e-3).unwrap();
/// let mut f = 0.0;
/// for _ in 0..100 { f = p.step(500.0, cfg.force_gain_n_per_mm_min).1; }
/// assert!((f - cfg.step_response_n(0.1, 500.0)).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondOrderProcess {
    phi: Mat<2>,
    gamma: [f64; 2],
    /// [v (mm/min), y (mm/min)].
    x: [f64; 2],
}

impl SecondOrderProcess {
    /// At rest, sampled every `dt_s`.
    pub fn new(config: SecondOrderConfig, dt_s: f64) -> Result<Self, PlantError> {
        config.validate()?;
        positive("dt_s", dt_s)?;
        let (tf, tc) = (config.feed_time_constant_s, config.force_time_constant_s);
        let a = [[-1.0 / tf, 0.0], [1.0 / tc, -1.0 / tc]];
        let b = [[1.0 / tf], [0.0]];
        let (phi, gamma) = linalg::zoh::<2, 1, 3>(&a, &b, dt_s);
        Ok(Self {
            phi,
            gamma: [gamma[0][0], gamma[1][0]],
            x: [0.0, 0.0],
        })
    }

    /// Advances one sample with command `feed_command_mm_min` and the current gain; returns
    /// (table speed v in mm/min, force F in N).
    pub fn step(&mut self, feed_command_mm_min: f64, gain_n_per_mm_min: f64) -> (f64, f64) {
        let x = linalg::mul_vec(&self.phi, &self.x);
        self.x = [
            x[0] + self.gamma[0] * feed_command_mm_min,
            x[1] + self.gamma[1] * feed_command_mm_min,
        ];
        (self.x[0], gain_n_per_mm_min * self.x[1])
    }

    /// Back to rest.
    pub fn reset(&mut self) {
        self.x = [0.0, 0.0];
    }
}

/// What paper 001's plant cuts: a straight line, one spindle speed, a gain along the path.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SecondOrderRun {
    /// The process dynamics (its gain is overridden by `gain_n_per_mm_min` along the path).
    pub process: SecondOrderConfig,
    /// Length of the cut.
    pub length_mm: f64,
    /// Programmed feed.
    pub programmed_feed_mm_min: f64,
    /// Spindle speed.
    pub spindle_rpm: f64,
    /// Static gain G(s) along the path as (position, N per mm/min) points.
    pub gain_n_per_mm_min: Vec<(f64, f64)>,
    /// Cutter radius R, for the torque T = R·F/√(1 + r²) (paper 003 eq 3, 5).
    pub cutter_radius_mm: f64,
    /// Radial-to-tangential ratio r.
    pub radial_ratio: f64,
    /// Axial depth and radial width of the cut where the gain is not zero (zero in the air), for
    /// the metrics' "in the cut"; NaN when not known (every row then counts as cutting).
    pub cut_depth_width_mm: (f64, f64),
    /// Sample rate, seed, CNC, drives and sensors (the scenario-free parts of a mill).
    pub machine: super::simulator::SimConfig,
}

/// Paper 001's plant as a machine: CNC → eq 2.3 → feed and spindle drives → sensors.
///
/// The reduced model has no geometry: its one force F acts against the feed (the feed axis is X)
/// and makes the spindle torque R·F/√(1 + r²).
#[derive(Debug, Clone)]
pub struct SecondOrderMachine {
    run: SecondOrderRun,
    gain: Profile,
    sampling: Sampling,
    control: Control,
    process: SecondOrderProcess,
    axis: FeedDrive,
    spindle: SpindleDrive,
    feed_sensor: CurrentSensor,
    spindle_sensor: CurrentSensor,
    started_at_s: Option<f64>,
}

impl SecondOrderMachine {
    /// A machine at rest.
    ///
    /// ```
    /// use cutlab::machine::{Machine, OverrideCommand};
    /// use cutlab::plant::second_order::{SecondOrderConfig, SecondOrderMachine, SecondOrderRun};
    /// use cutlab::plant::simulator::SimConfig;
    /// let run = SecondOrderRun {
    ///     process: SecondOrderConfig::new(1.0 / 30.0, 0.02, 0.3).unwrap(),
    ///     length_mm: 50.0, programmed_feed_mm_min: 600.0, spindle_rpm: 3000.0,
    ///     gain_n_per_mm_min: vec![(0.0, 0.3)], cutter_radius_mm: 5.0, radial_ratio: 0.4,
    ///     cut_depth_width_mm: (2.0, 3.0),
    ///     machine: SimConfig { sample_rate_hz: 1000.0, ..SimConfig::default() },
    /// };
    /// let mut m = SecondOrderMachine::new(run).unwrap();
    /// let mut s = m.step(OverrideCommand::default());
    /// for _ in 0..4000 { s = m.step(OverrideCommand::default()); }
    /// assert!((s.truth.unwrap().force_resultant_n - 0.3 * 600.0).abs() < 1.0);
    /// ```
    pub fn new(run: SecondOrderRun) -> Result<Self, PlantError> {
        run.process.validate().map_err(|e| e.within("process"))?;
        run.machine.validate().map_err(|e| e.within("machine"))?;
        positive("length_mm", run.length_mm)?;
        positive("programmed_feed_mm_min", run.programmed_feed_mm_min)?;
        non_negative("spindle_rpm", run.spindle_rpm)?;
        positive("cutter_radius_mm", run.cutter_radius_mm)?;
        non_negative("radial_ratio", run.radial_ratio)?;
        let gain = Profile::new(&run.gain_n_per_mm_min, "gain_n_per_mm_min")?;
        let m = &run.machine;
        let sampling = Sampling::new(m.sample_rate_hz);
        let dt_s = sampling.dt_s();
        let block = PlanBlock::straight(run.length_mm, run.programmed_feed_mm_min);
        Ok(Self {
            gain,
            sampling,
            control: Control::new(&m.cnc, vec![block], dt_s)
                .map_err(|e| e.within("machine.cnc"))?,
            process: SecondOrderProcess::new(run.process, dt_s)?,
            axis: FeedDrive::new(m.feed_drive, dt_s).map_err(|e| e.within("machine.feed_drive"))?,
            spindle: SpindleDrive::new(m.spindle_drive, dt_s)
                .map_err(|e| e.within("machine.spindle_drive"))?,
            feed_sensor: CurrentSensor::new(m.feed_sensor, dt_s, m.seed, 0)?,
            spindle_sensor: CurrentSensor::new(m.spindle_sensor, dt_s, m.seed, 3)?,
            run,
            started_at_s: None,
        })
    }
}

impl PlantModel for SecondOrderMachine {
    fn sampling(&self) -> &Sampling {
        &self.sampling
    }

    fn sampling_mut(&mut self) -> &mut Sampling {
        &mut self.sampling
    }

    fn advance(&mut self, tick: Tick, command: OverrideCommand) -> PlantSample {
        let time_s = tick.time_s;
        let tol = self.run.machine.cnc.spindle_arrival_tolerance * self.run.spindle_rpm;
        let ready = (self.spindle.speed_rpm() - self.run.spindle_rpm).abs() <= tol;
        let control = self.control.step(command, ready);
        let (applied, cnc) = (control.applied, control.cnc);
        let gain = self.gain.value_at(cnc.position_mm);
        // f_r is the commanded feed; the process contains the feed drive's own lag.
        let (v, force_n) = self.process.step(cnc.commanded_feed_mm_min, gain);
        let r = self.run.radial_ratio;
        let torque_nm = self.run.cutter_radius_mm * 1e-3 * force_n / (1.0 + r * r).sqrt();
        let ax = self.axis.step(v, force_n, 0.0);
        let sp = self.spindle.step(self.run.spindle_rpm, torque_nm);
        if sp.running && self.started_at_s.is_none() {
            self.started_at_s = Some(time_s);
        }
        let feed_read = self.feed_sensor.read(ax.phase_currents_a);
        let spindle_read = self.spindle_sensor.read(sp.phase_currents_a);
        let feed_rms = three_phase_rms_a(ax.phase_currents_a);
        // The reduced model has no tool geometry.
        let f_tooth = f64::NAN;
        let power_w = torque_nm * super::rad_s_from_rpm(sp.speed_rpm);
        let sensors = SensorSample {
            time_s,
            feed_phase_currents_a: feed_read,
            spindle_phase_currents_a: spindle_read,
            spindle_fv_voltage_v: sp.fv_voltage_v,
            spindle_speed_rpm: sp.speed_rpm,
            spindle_command_rpm: self.run.spindle_rpm,
            programmed_feed_mm_min: self.run.programmed_feed_mm_min,
            feed_mm_min: v,
            applied_override_pct: applied.pct,
            spindle_running: sp.running,
            time_since_spindle_start_s: self.started_at_s.map_or(0.0, |t| time_s - t),
        };
        let (depth_mm, width_mm) = if gain > 0.0 {
            self.run.cut_depth_width_mm
        } else {
            (0.0, 0.0)
        };
        let truth = PlantTruth {
            force_x_n: -force_n,
            force_resultant_n: force_n,
            feed_force_n: force_n,
            spindle_torque_nm: torque_nm,
            cutting_power_w: power_w,
            depth_mm,
            width_mm,
            feed_per_tooth_mm: f_tooth,
            path_position_mm: cnc.position_mm,
            // The reduced model has no tool, but its cut has a depth and width: the volume swept.
            material_removal_mm3_s: depth_mm * width_mm * v.max(0.0) / S_PER_MIN,
            tool_x_mm: cnc.position_mm,
            feed_current_rms_a: feed_rms,
            spindle_current_rms_a: sp.rms_current_a,
            ..PlantTruth::default()
        };
        let signals = PlantSignals {
            feed_mm_min: v,
            spindle_command_rpm: self.run.spindle_rpm,
            spindle_speed_rpm: sp.speed_rpm,
            spindle_gear: sp.gear,
            entry_deg: f64::NAN,
            exit_deg: f64::NAN,
            power_law_force_n: f64::NAN,
            axis_x: AxisSignals {
                velocity_mm_min: v,
                load_force_n: force_n,
                torque_nm: ax.torque_nm,
                iq_a: ax.iq_a,
                phase_currents_a: ax.phase_currents_a,
            },
            spindle_motor_torque_nm: sp.motor_torque_nm,
            spindle_phase_currents_a: sp.phase_currents_a,
            fv_voltage_v: sp.fv_voltage_v,
            feed_currents_read_a: feed_read,
            spindle_currents_read_a: spindle_read,
            brake_excitation_a: f64::NAN,
            brake_torque_nm: f64::NAN,
            ..PlantSignals::from_control(time_s, truth, &control)
        };
        PlantSample {
            sensors,
            signals,
            finished: cnc.finished || time_s >= self.run.machine.max_duration_s,
        }
    }

    fn restart(&mut self) -> PlantSignals {
        let seed = self.run.machine.seed;
        self.control.reset();
        self.process.reset();
        self.axis.reset();
        self.spindle.reset();
        self.feed_sensor.reset(seed, 0);
        self.spindle_sensor.reset(seed, 3);
        self.started_at_s = None;
        PlantSignals::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn second_order_step_matches_the_closed_form_at_every_sample() {
        let cfg = SecondOrderConfig::new(0.033, 0.02, 0.5).unwrap();
        let dt = 1e-4;
        let mut p = SecondOrderProcess::new(cfg, dt).unwrap();
        for k in 1..=2000 {
            let (_, f) = p.step(300.0, cfg.force_gain_n_per_mm_min);
            let exact = cfg.step_response_n(k as f64 * dt, 300.0);
            assert!((f - exact).abs() < 1e-9 * 150.0, "k {k}: {f} vs {exact}");
        }
    }

    #[test]
    fn equal_time_constants_use_the_critically_damped_form() {
        let cfg = SecondOrderConfig::new(0.02, 0.02, 1.0).unwrap();
        let mut p = SecondOrderProcess::new(cfg, 1e-3).unwrap();
        let mut f = 0.0;
        for _ in 0..50 {
            f = p.step(100.0, 1.0).1;
        }
        assert!((f - cfg.step_response_n(0.05, 100.0)).abs() < 1e-9);
    }
}
