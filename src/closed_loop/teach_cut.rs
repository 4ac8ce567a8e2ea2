//! The teach cut: the machine open-loop through a schedule of overrides (so the load varies), each
//! control period summarised by the loop's own signal chain and paired with a force, then fitted
//! ([`crate::estimation::teach_fit`]) into the calibration the closed loop estimates with.
//!
//! ```text
//! samples ─► signal chain ─► one TeachPeriod per control period (with its force from TeachForce)
//!   └ the override: the teach schedule (100, 30, 140, 60 %, each 1.5 s), or a log's own
//! end of the program ─► teach_fit::fit ─► Calibration
//! ```
//!
//! The same teach cut runs on the simulated machine (force from the simulation's truth), on a
//! machine over the serial line (force from a dynamometer or the model of the programmed cut) and
//! over a recorded log (force from its force column or the model of the cut; the override the
//! machine ran at, read from the log).

use super::error::LoopError;
use super::sample_loop::{signal_chain, LoopSample, OnMachine, PeriodClock, SampleLoop};
use super::settings::Plan;
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::estimator::{Calibration, Feedback};
use crate::estimation::speed::GEAR_CHANGE_RPM;
use crate::estimation::teach_fit::{fit, ForceOrigin, TeachFit, TeachFitError, TeachPeriod};
use crate::machine::{Machine, OverrideCommand, SensorSample};
use crate::signal::chain::{PeriodSummary, SignalChain};

/// The overrides a teach cut cycles through, each held for [`TEACH_STEP_S`]: a spread of loads
/// from one pass over the part. None is commanded above the run's highest override.
pub const TEACH_OVERRIDES_PCT: [f64; 4] = [100.0, 30.0, 140.0, 60.0];
/// How long each teach-cut override is held.
pub const TEACH_STEP_S: f64 = 1.5;

/// Where a teach cut takes the force that the current is fitted against.
///
/// A simulation knows the true force; a shop has either a dynamometer under the part or the
/// mechanistic model of the cut it programmed (the same model `cutlab calibrate --material` uses),
/// so a real teach cut calibrates without any simulation truth.
#[derive(Debug, Clone, PartialEq)]
pub enum TeachForce {
    /// The plant's truth (simulation only): each sample's [`crate::machine::PlantTruth`].
    SimulationTruth,
    /// A force sensor: each sample's [`Machine::dynamometer_force_n`] (a log's force column).
    Dynamometer,
    /// The mean force of the programmed cut, modelled from the period's feed and spindle speed.
    CutModel {
        /// Cutter, milling mode and the material's coefficients.
        geometry: CutGeometry,
        /// Axial depth of the teach cut; `None` takes each period's depth from the machine (a
        /// log's depth column).
        depth_mm: Option<f64>,
        /// Radial width of the teach cut.
        width_mm: f64,
    },
}

impl TeachForce {
    /// Name for the command line and URLs.
    pub fn name(&self) -> &'static str {
        match self {
            TeachForce::SimulationTruth => "truth",
            TeachForce::Dynamometer => "dynamometer",
            TeachForce::CutModel { .. } => "cut-model",
        }
    }

    /// How the forces were obtained, for the fit's air rule.
    fn origin(&self) -> ForceOrigin {
        match self {
            TeachForce::CutModel { .. } => ForceOrigin::Modelled,
            TeachForce::SimulationTruth | TeachForce::Dynamometer => ForceOrigin::Measured,
        }
    }

    /// A period's force on `feedback`'s path (NaN when the source has nothing to say).
    fn period_force_n(&self, feedback: Feedback, period: &PeriodSummary) -> f64 {
        match self {
            TeachForce::SimulationTruth => feedback.regulated_truth_n(period),
            TeachForce::Dynamometer => match feedback {
                Feedback::FeedCurrent => period.dynamometer_feed_force_n,
                Feedback::SpindleCurrent | Feedback::Dynamometer => period.dynamometer_resultant_n,
            },
            TeachForce::CutModel {
                geometry,
                depth_mm,
                width_mm,
            } => geometry
                .mean_forces(
                    period.feed_mm_min,
                    period.spindle_speed_rpm,
                    depth_mm.unwrap_or(period.depth_mm),
                    *width_mm,
                )
                .map_or(f64::NAN, |f| match feedback {
                    Feedback::SpindleCurrent | Feedback::Dynamometer => f.resultant_n(),
                    Feedback::FeedCurrent => -f.fx_n,
                }),
        }
    }
}

/// What sets the override during a teach cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TeachSchedule {
    /// The teach cut commands [`TEACH_OVERRIDES_PCT`], each for [`TEACH_STEP_S`].
    Overrides,
    /// The machine ran at its own override, which each sample reports (a recorded log: it cannot
    /// follow a command).
    Observed,
}

/// A teach cut as a [`SampleLoop`]; [`SampleLoop::finish`] fits the estimator.
pub struct TeachCut {
    feedback: Feedback,
    force_source: TeachForce,
    schedule: TeachSchedule,
    /// The run's highest override: the schedule never commands more (reduce-only limits on a
    /// machine's first cuts keep the teach cut at or below 100 %).
    max_override_pct: f64,
    max_duration_s: f64,
    chain: SignalChain,
    clock: PeriodClock,
    last: SensorSample,
    periods: Vec<TeachPeriod>,
    max_phase_current_a: f64,
    time_s: f64,
    command: OverrideCommand,
    /// The observed override: its sum over the period, its latest value and when it last changed.
    override_sum_pct: f64,
    override_pct: f64,
    override_changed_s: f64,
    done: bool,
}

impl TeachCut {
    /// A teach cut at `sample_rate_hz` with the signal chain, feedback path and time limit of
    /// `plan`, taking its force from `force_source` and its override from `schedule`.
    pub fn new(
        sample_rate_hz: f64,
        plan: &Plan,
        force_source: TeachForce,
        schedule: TeachSchedule,
    ) -> Result<Self, LoopError> {
        Ok(Self {
            chain: signal_chain(&plan.chain, sample_rate_hz)?,
            clock: PeriodClock::new(&plan.chain, sample_rate_hz)?,
            feedback: plan.chain.feedback,
            force_source,
            schedule,
            max_override_pct: plan.limits.max_override_pct,
            max_duration_s: plan.max_duration_s,
            last: SensorSample::default(),
            periods: Vec::new(),
            max_phase_current_a: 0.0,
            time_s: 0.0,
            command: Self::command_at(0.0, plan.limits.max_override_pct),
            override_sum_pct: 0.0,
            override_pct: f64::NAN,
            override_changed_s: f64::NEG_INFINITY,
            done: false,
        })
    }

    /// The override the schedule holds at machine time `time_s`, at most `max_override_pct`.
    fn command_at(time_s: f64, max_override_pct: f64) -> OverrideCommand {
        let step_index = (time_s / TEACH_STEP_S) as usize % TEACH_OVERRIDES_PCT.len();
        OverrideCommand {
            override_pct: TEACH_OVERRIDES_PCT[step_index].min(max_override_pct),
            feed_hold: false,
        }
    }

    /// Files one ended period of `samples` samples.
    fn end_period(&mut self, samples: usize) {
        let summary = self.chain.finish_period();
        let samples = samples.max(1) as f64;
        self.time_s = summary.end_time_s;
        let last = self.last;
        let (override_pct, since_override_change_s) = match self.schedule {
            // The schedule changes the override every step.
            TeachSchedule::Overrides => (self.command.override_pct, self.time_s % TEACH_STEP_S),
            TeachSchedule::Observed => (
                self.override_sum_pct / samples,
                summary.end_time_s - self.override_changed_s,
            ),
        };
        self.override_sum_pct = 0.0;
        self.periods.push(TeachPeriod {
            force_n: self.force_source.period_force_n(self.feedback, &summary),
            summary,
            override_pct,
            since_override_change_s,
            since_spindle_start_s: if last.spindle_running {
                last.time_since_spindle_start_s
            } else {
                f64::INFINITY
            },
        });
        if self.time_s >= self.max_duration_s {
            self.done = true;
        }
        self.command = Self::command_at(self.time_s, self.max_override_pct);
    }

    /// Fits the estimator to what was collected, with what the fit rests on.
    pub fn fit(&self) -> Result<TeachFit, LoopError> {
        fit(
            &self.periods,
            self.feedback,
            self.force_source.origin(),
            self.max_phase_current_a,
            GEAR_CHANGE_RPM,
        )
        .map_err(|e| match e {
            TeachFitError::Fit(e) => LoopError::Calibration(e),
            TeachFitError::NoFeedLoad => LoopError::NoFeedLoad,
        })
    }

    /// Fits the estimator to what was collected.
    pub fn calibration(&self) -> Result<Calibration, LoopError> {
        self.fit().map(|f| f.calibration)
    }
}

impl SampleLoop for TeachCut {
    type Output = Calibration;

    #[inline(always)]
    fn push(&mut self, sample: &LoopSample<'_>) -> Option<OverrideCommand> {
        if self.done {
            return None;
        }
        let sensors = &sample.step.sensors;
        self.chain.push(sample.step);
        // The six magnitudes pairwise, then into the running maximum: three comparisons deep
        // instead of six in a row. The maximum of non-negative numbers (a non-finite current
        // counts as 0, which the running maximum, starting at 0, already is) picks the same
        // value whatever the order.
        let magnitude = |i: f64| if i.is_finite() { i.abs() } else { 0.0 };
        let [fu, fv, fw] = sensors.feed_phase_currents_a.map(magnitude);
        let [su, sv, sw] = sensors.spindle_phase_currents_a.map(magnitude);
        let max = crate::math::max;
        let sample_max = max(max(max(fu, fv), max(fw, su)), max(sv, sw));
        self.max_phase_current_a = max(self.max_phase_current_a, sample_max);
        if let Some(d) = &sample.dynamometer {
            self.chain.push_dynamometer(d);
        }
        if self.schedule == TeachSchedule::Observed {
            let pct = sensors.applied_override_pct;
            if self.override_pct.is_finite() && pct != self.override_pct {
                self.override_changed_s = sensors.time_s;
            }
            self.override_pct = pct;
            self.override_sum_pct += pct;
        }
        self.last = *sensors;
        if !self.clock.tick() {
            return None;
        }
        self.end_period(self.clock.samples_per_period());
        Some(self.command)
    }

    fn command(&self) -> OverrideCommand {
        self.command
    }

    fn clock(&self) -> &PeriodClock {
        &self.clock
    }

    fn end_of_program(&mut self) {
        let samples = self.clock.cut_short();
        if samples > 0 && !self.done {
            self.end_period(samples);
        }
        self.done = true;
    }

    fn finished(&self) -> bool {
        self.done
    }

    fn elapsed_s(&self) -> f64 {
        self.time_s
    }

    fn stage(&self) -> &'static str {
        "teach cut"
    }

    fn finish(&mut self) -> Result<Calibration, LoopError> {
        self.calibration()
    }
}

impl OnMachine<TeachCut> {
    /// A teach cut of `machine` with `plan`'s signal chain, feedback path and time limit, through
    /// the teach schedule.
    pub fn teach_cut(
        machine: Box<dyn Machine>,
        plan: &Plan,
        force_source: TeachForce,
    ) -> Result<Self, LoopError> {
        let teach = TeachCut::new(
            machine.sample_rate_hz(),
            plan,
            force_source,
            TeachSchedule::Overrides,
        )?;
        Ok(Self::new_with(machine, teach))
    }

    /// Fits the estimator to what was collected so far.
    pub fn calibration(&self) -> Result<Calibration, LoopError> {
        self.sample_loop.calibration()
    }
}
