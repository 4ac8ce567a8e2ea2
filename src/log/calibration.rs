//! Calibration from a recorded log: the log as a machine ([`super::machine`]) through the
//! teach cut every other mode makes ([`crate::closed_loop::teach_cut`]), with the override the
//! machine ran at read from the log instead of commanded, and its force from the log's force
//! column or the model of the cut. The same signal chain, the same selection of periods and the
//! same fit ([`crate::estimation::teach_fit`]) as a simulated or a real teach cut.

use std::sync::Arc;

use super::machine::{log_setup, setting, ReplayError};
use super::mapping::{Channel, Mapping};
use super::replay::ReplaySettings;
use super::Log;
use crate::closed_loop::error::LoopError;
use crate::closed_loop::sample_loop::OnMachine;
use crate::closed_loop::settings::plan;
use crate::closed_loop::teach_cut::{TeachCut, TeachForce, TeachSchedule};
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::estimator::{Calibration, Estimator, Feedback};
use crate::estimation::teach_fit::FitPoint;
use crate::work::{Progress, Work};

/// Where a calibration from a log takes its force.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ForceSource {
    /// The log's measured force (the [`Channel::Force`] column).
    Measured,
    /// The mean force of the cut, modelled from each period's feed and speed (as `cutlab
    /// calibrate --material` does): for a log without a dynamometer.
    CutModel {
        /// Cutter, milling mode and material.
        geometry: CutGeometry,
        /// Axial depth; `None` reads the [`Channel::Depth`] column.
        depth_mm: Option<f64>,
        /// Radial width.
        width_mm: f64,
    },
}

/// A calibration made from a log, with the points it was fitted to.
#[derive(Debug, Clone, PartialEq)]
pub struct LogFit {
    /// The calibration (the same kind a teach cut makes, so a replay, a run or a saved file can
    /// use it).
    pub calibration: Calibration,
    /// The periods used, for plotting the fit.
    pub points: Vec<FitPoint>,
    /// What was left out and why.
    pub notes: Vec<String>,
    /// Where the force came from, for people and the saved file.
    pub force_source: String,
}

impl LogFit {
    /// The model's current for `force_n` at a period's speed and feed (to draw the fitted line).
    pub fn model_current_a(&self, point: &FitPoint, force_n: f64) -> f64 {
        self.calibration
            .estimator
            .current_for_force_a(force_n, point.speed_rpm, point.feed_mm_min)
    }

    /// One line for people: the fit's quality.
    pub fn quality(&self) -> String {
        let readable = crate::input::readable;
        match &self.calibration.estimator {
            Estimator::Spindle { model, .. } => model
                .rows
                .iter()
                .map(|r| {
                    format!(
                        "at {} rpm: I = {} A + {} A/N · F, R² {:.4}, residual {} A (≈ {} N), {} \
                         periods",
                        readable(r.speed_rpm),
                        readable(r.idle_current_a),
                        readable(r.sensitivity_a_per_n),
                        r.quality.r_squared,
                        readable(r.quality.residual_std_a),
                        readable(r.quality.residual_std_n),
                        r.quality.samples
                    )
                })
                .collect::<Vec<_>>()
                .join("; "),
            Estimator::Feed { model } => format!(
                "I = {} A + {} A/(mm/min) · |v| + {} A/N · F, R² {:.4}, residual {} A (≈ {} N), \
                 {} periods",
                readable(model.idle_current_a),
                readable(model.idle_current_a_per_mm_min),
                readable(model.sensitivity_a_per_n),
                model.quality.r_squared,
                readable(model.quality.residual_std_a),
                readable(model.quality.residual_std_n),
                model.quality.samples
            ),
            Estimator::Dynamometer => "a dynamometer needs no fit".to_string(),
        }
    }
}

/// Fits the current → force model of `settings`' feedback path to a log: the log runs through
/// the teach cut with the replay's own signal chain (the same low-pass, RMS and control period a
/// replay uses), and each period's current is paired with the force from `force`.
pub fn fit_calibration(
    log: &Arc<Log>,
    mapping: &Mapping,
    settings: &ReplaySettings,
    force: &ForceSource,
) -> Result<LogFit, ReplayError> {
    LogFitWork::new(log, mapping, settings, force)?.run_to_end()
}

/// [`fit_calibration`] done a piece at a time: the teach cut runs a budget of control periods per
/// call, the fit at the end.
pub struct LogFitWork {
    teach: OnMachine<TeachCut>,
    duration_s: f64,
    force_source: String,
    notes: Vec<String>,
    rms_only: bool,
    output: Option<LogFit>,
}

impl LogFitWork {
    /// Sets up the teach cut; a missing column or setting is an error saying what to give.
    pub fn new(
        log: &Arc<Log>,
        mapping: &Mapping,
        settings: &ReplaySettings,
        force: &ForceSource,
    ) -> Result<Self, ReplayError> {
        let feedback = settings.run.feedback.unwrap_or(Feedback::SpindleCurrent);
        if feedback == Feedback::Dynamometer {
            return Err(setting(
                "a dynamometer reads the force itself: there is no current model to fit",
            ));
        }
        let columns = mapping.resolve(log)?;
        let (force_source, teach_force) = match force {
            ForceSource::Measured => {
                let Some(c) = columns.column(Channel::Force) else {
                    return Err(setting(
                        "the log has no measured force mapped: map a force column, or model the \
                         force from the cut",
                    ));
                };
                (
                    format!("the log's measured force ({})", log.columns[c].name),
                    TeachForce::Dynamometer,
                )
            }
            ForceSource::CutModel {
                geometry,
                depth_mm,
                width_mm,
            } => {
                if depth_mm.is_none() && columns.column(Channel::Depth).is_none() {
                    return Err(setting(
                        "the cut model needs the depth: give it, or map a depth column",
                    ));
                }
                if columns.column(Channel::Feed).is_none() {
                    return Err(setting("the cut model needs the feed: map a feed column"));
                }
                let readable = crate::input::readable;
                (
                    format!(
                        "the mechanistic model of the cut (Ø{} mm, {} teeth, {} milling, depth \
                         {}, width {} mm)",
                        readable(geometry.cutter.diameter_mm),
                        geometry.cutter.teeth,
                        geometry.mode.name(),
                        depth_mm.map_or("from the log".to_string(), |d| format!(
                            "{} mm",
                            readable(d)
                        )),
                        readable(*width_mm)
                    ),
                    TeachForce::CutModel {
                        geometry: geometry.clone(),
                        depth_mm: *depth_mm,
                        width_mm: *width_mm,
                    },
                )
            }
        };
        let setup = log_setup(log, mapping, settings.log_options(feedback, None))?;
        // The controller plays no part in a teach cut (a log's end ends it, not a time limit).
        let plan = plan(
            &settings.run,
            &ControllerConfig::new(ControllerKind::Fixed),
            &setup.context,
        )?;
        let mut notes = setup.notes;
        notes.extend(plan.notes.iter().cloned());
        let teach = TeachCut::new(
            setup.context.sample_rate_hz,
            &plan,
            teach_force,
            TeachSchedule::Observed,
        )?;
        Ok(Self {
            teach: OnMachine::new_with(Box::new(setup.machine), teach),
            duration_s: plan.max_duration_s,
            force_source,
            notes,
            rms_only: setup.rms_only,
            output: None,
        })
    }

    /// Fits what the teach cut collected.
    fn fit(&self) -> Result<LogFit, ReplayError> {
        let fit = self.teach.sample_loop().fit().map_err(|e| match e {
            LoopError::Calibration(e) => setting(format!("the fit failed: {e}")),
            e => ReplayError::Loop(e),
        })?;
        let mut notes = self.notes.clone();
        notes.push(fit.selection_note());
        notes.extend(fit.warnings());
        let mut calibration = fit.calibration;
        if self.rms_only {
            // An RMS value stands for three phases of its own value; a phase's peak is √2 of it.
            calibration.max_phase_current_a *= std::f64::consts::SQRT_2;
        }
        Ok(LogFit {
            calibration,
            points: fit.points,
            notes,
            force_source: self.force_source.clone(),
        })
    }
}

impl Work for LogFitWork {
    type Output = LogFit;
    type Error = ReplayError;

    /// Runs the teach cut over at most `budget` control periods; the fit once the log has ended.
    fn advance(&mut self, budget: usize) -> Result<bool, ReplayError> {
        if self.output.is_some() {
            return Ok(true);
        }
        if self.teach.advance(budget.max(1))? {
            self.output = Some(self.fit()?);
            return Ok(true);
        }
        Ok(false)
    }

    fn progress(&self) -> Progress {
        Progress::new(
            "Calibrating",
            (self.teach.elapsed_s() / self.duration_s.max(1e-9)).clamp(0.0, 1.0),
        )
    }

    fn finish(&mut self) -> Result<LogFit, ReplayError> {
        self.output
            .take()
            .ok_or(ReplayError::Loop(LoopError::NotFinished))
    }
}
