//! Closed-loop runs on the papers' presets: the teach cut, the run and its metrics, a piece at a
//! time ([`LabRun`]) or several in turn ([`LabRuns`]). The CLI, the browser and the tuner all call
//! this, so a run is the same wherever it is made; its settings come from the one resolution
//! ([`super::settings`]).

use super::definition::RunSpec;
use super::error::LoopError;
use super::feedback_loop::{ClosedLoop, FeedbackLoop};
use super::metrics::{compute, Metrics, MetricsConfig};
use super::sample_loop::OnMachine;
use super::settings::{default_feedback, plan, ChainSettings, LoopSettings, MachineContext, Plan};
use super::teach_cut::{TeachCut, TeachForce};
use super::trace::Trace;
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::estimator::{Calibration, Feedback};
use crate::machine::Machine;
use crate::plant::presets::{PlantEdits, PlantKind, TEACH_SEED_OFFSET};
use crate::plant::Preset;
use crate::work::{Progress, Work};

/// A finished run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunResult {
    /// What was run.
    pub spec: RunSpec,
    /// The settings the run used.
    pub settings: LoopSettings,
    /// The teach cut's calibration.
    pub calibration: Calibration,
    /// The trace.
    pub trace: Trace,
    /// The metrics (savings filled when reference runs were made).
    pub metrics: Metrics,
}

/// The settings of `spec` on its preset's machine before the teach cut, for samples at
/// `sample_rate_hz` (the simulation's, or a device's on the serial line).
pub fn plan_on(spec: &RunSpec, sample_rate_hz: f64) -> Result<Plan, LoopError> {
    plan(
        &spec.settings,
        &spec.controller,
        &MachineContext::of_preset(spec, sample_rate_hz),
    )
}

/// The settings of `spec` on its preset's simulated machine before the teach cut.
pub fn preset_plan(spec: &RunSpec) -> Result<Plan, LoopError> {
    plan_on(spec, spec.preset.sample_rate_hz())
}

/// The teach force a machine without simulation truth or dynamometer can use: the model of the
/// preset's cut, when the whole program cuts one depth, one width and one material (the model
/// takes each period's feed and speed from the machine, but not where on the part the tool is).
/// `None` for a program whose cut changes along the path: such a machine needs a saved
/// calibration ([`super::calibration_file`]).
pub fn cut_model_teach_force(preset: Preset) -> Option<TeachForce> {
    let scenario = preset.scenario_spec()?;
    let single = |points: &[(f64, f64)]| -> Option<f64> {
        let first = points.first()?.1;
        points.iter().all(|p| p.1 == first).then_some(first)
    };
    let [material] = scenario.materials.as_slice() else {
        return None;
    };
    Some(TeachForce::CutModel {
        geometry: CutGeometry {
            cutter: scenario.cutter,
            mode: scenario.mode,
            coefficients: material.material.coefficients(),
        },
        depth_mm: Some(single(&scenario.depth_mm)?),
        width_mm: single(&scenario.width_mm)?,
    })
}

/// The machines a run uses: a simulation makes a fresh pass for the teach cut and another for the
/// run (differently seeded, like two parts); a real machine or a replayed log does both in turn.
pub enum RunMachines {
    /// One machine for the teach cut, another for the closed loop.
    Separate {
        /// Runs the teach cut.
        teach: Box<dyn Machine>,
        /// Runs the closed loop.
        run: Box<dyn Machine>,
    },
    /// One machine that does the teach cut and then the closed loop.
    Shared(Box<dyn Machine>),
}

impl RunMachines {
    /// The preset's machines for `spec`: the teach cut seeded apart from the run.
    pub fn for_preset(spec: &RunSpec) -> Result<Self, LoopError> {
        let [teach, run] = spec
            .preset
            .teach_and_run_machines(spec.seed, &spec.plant, with_dynamometer(spec))
            .map_err(LoopError::Machine)?;
        Ok(RunMachines::Separate { teach, run })
    }
}

/// Whether `spec`'s machines carry a dynamometer: when the run feeds back the measured force.
fn with_dynamometer(spec: &RunSpec) -> bool {
    let feedback = spec
        .settings
        .feedback
        .unwrap_or_else(|| default_feedback(spec.preset));
    feedback == Feedback::Dynamometer
}

/// `spec`'s simulated machine seeded with `seed` (one of [`RunMachines::for_preset`]'s).
fn preset_machine(spec: &RunSpec, seed: u64) -> Result<Box<dyn Machine>, LoopError> {
    spec.preset
        .seeded_machine(seed, &spec.plant, with_dynamometer(spec))
        .map_err(LoopError::Machine)
}

/// A run in progress: first the teach cut, then the closed loop. Advancing in chunks lets a
/// browser show progress and cancel between frames; [`simulate`] runs it to the end at once.
pub struct LabRun {
    spec: RunSpec,
    plan: Plan,
    nominal_duration_s: f64,
    /// True when the run was given a calibration and has no teach cut of its own.
    calibrated: bool,
    stage: RunStage,
}

enum RunStage {
    Teaching {
        teach: Box<OnMachine<TeachCut>>,
        /// The closed loop's machine, when it is not the teach cut's.
        run_machine: Option<Box<dyn Machine>>,
    },
    Running {
        run: Box<ClosedLoop>,
        calibration: Calibration,
    },
    Done(Box<RunResult>),
    /// Between stages, or after the result was taken.
    Empty,
}

impl LabRun {
    /// Starts a run of `spec` on its preset's simulated machine, calibrated by a teach cut that
    /// takes its force from the simulation's truth.
    pub fn new(spec: &RunSpec) -> Result<Self, LoopError> {
        let machines = RunMachines::for_preset(spec)?;
        Self::on_machines(spec, machines, TeachForce::SimulationTruth)
    }

    /// Starts a run of `spec`'s controller and settings on any machine: the teach cut runs on
    /// `machines` with its force from `teach_force`, then the closed loop. The preset gives the
    /// defaults of every setting the spec leaves out.
    pub fn on_machines(
        spec: &RunSpec,
        machines: RunMachines,
        teach_force: TeachForce,
    ) -> Result<Self, LoopError> {
        let (teach_machine, run_machine) = match machines {
            RunMachines::Separate { teach, run } => (teach, Some(run)),
            RunMachines::Shared(machine) => (machine, None),
        };
        let plan = plan_on(spec, teach_machine.sample_rate_hz())?;
        Ok(Self {
            nominal_duration_s: spec.preset.summary().nominal_duration_s.max(1.0),
            calibrated: false,
            stage: RunStage::Teaching {
                teach: Box::new(OnMachine::teach_cut(teach_machine, &plan, teach_force)?),
                run_machine,
            },
            plan,
            spec: spec.clone(),
        })
    }

    /// Starts a run that skips the teach cut and uses `calibration`, made by an earlier run of a
    /// spec with the same preset, seed, machine and signal chain (the teach cut depends on those
    /// alone, so the result is the same as [`LabRun::new`]'s, for less work).
    pub fn calibrated(spec: &RunSpec, calibration: Calibration) -> Result<Self, LoopError> {
        Self::calibrated_on(spec, preset_machine(spec, spec.seed)?, calibration)
    }

    /// Starts the closed loop on any machine from a calibration made elsewhere (a saved
    /// calibration file, a logged cut): no teach cut. Refused when the calibration reads another
    /// feedback path than the run's settings.
    pub fn calibrated_on(
        spec: &RunSpec,
        machine: Box<dyn Machine>,
        calibration: Calibration,
    ) -> Result<Self, LoopError> {
        let plan = plan_on(spec, machine.sample_rate_hz())?;
        let mut run = Self {
            nominal_duration_s: spec.preset.summary().nominal_duration_s.max(1.0),
            calibrated: true,
            stage: RunStage::Empty,
            plan,
            spec: spec.clone(),
        };
        let closed_loop = run.start_loop(machine, &calibration)?;
        run.stage = RunStage::Running {
            run: Box::new(closed_loop),
            calibration,
        };
        Ok(run)
    }

    fn start_loop(
        &mut self,
        machine: Box<dyn Machine>,
        calibration: &Calibration,
    ) -> Result<ClosedLoop, LoopError> {
        let feedback_loop = closed_loop_of(
            &self.spec,
            &self.plan,
            calibration,
            machine.sample_rate_hz(),
        )?;
        Ok(OnMachine::new_with(machine, feedback_loop))
    }

    /// Stops the closed loop after `duration_s` of machine time if that comes before the
    /// preset's own limit (a host's `--duration-s`); the teach cut is not affected.
    pub fn limit_duration_s(&mut self, duration_s: f64) {
        if duration_s < self.plan.max_duration_s || duration_s.is_nan() {
            self.plan.max_duration_s = duration_s;
        }
    }

    /// The trace so far, once the closed loop has started.
    pub fn trace(&self) -> Option<&Trace> {
        match &self.stage {
            RunStage::Running { run, .. } => Some(run.trace()),
            RunStage::Done(r) => Some(&r.trace),
            _ => None,
        }
    }

    /// The trace so far and the calibration it runs on, once the closed loop has started
    /// (`None` during the teach cut): what a computation worker streams to the page.
    pub fn loop_so_far(&self) -> Option<(&Trace, &Calibration)> {
        match &self.stage {
            RunStage::Running { run, calibration } => Some((run.trace(), calibration)),
            RunStage::Done(r) => Some((&r.trace, &r.calibration)),
            _ => None,
        }
    }

    /// The run so far as a result: the trace up to now and its metrics, once the closed loop has
    /// started (`None` during the teach cut).
    pub fn partial_result(&self) -> Option<RunResult> {
        match &self.stage {
            RunStage::Running { run, calibration } => {
                let settings = run.settings().clone();
                let trace = run.trace().clone();
                let metrics = compute(&trace, &metrics_config(self.spec.preset, &settings));
                Some(RunResult {
                    spec: self.spec.clone(),
                    settings,
                    calibration: calibration.clone(),
                    trace,
                    metrics,
                })
            }
            RunStage::Done(r) => Some((**r).clone()),
            _ => None,
        }
    }

    /// The result, once complete.
    pub fn into_result(self) -> Option<RunResult> {
        match self.stage {
            RunStage::Done(r) => Some(*r),
            _ => None,
        }
    }
}

impl Work for LabRun {
    type Output = RunResult;
    type Error = LoopError;

    /// Runs at most `periods` control periods of whichever stage is under way.
    fn advance(&mut self, periods: usize) -> Result<bool, LoopError> {
        match std::mem::replace(&mut self.stage, RunStage::Empty) {
            RunStage::Teaching {
                mut teach,
                run_machine,
            } => {
                if teach.advance(periods)? {
                    let calibration = teach.calibration()?;
                    let (teach_machine, _) = teach.into_parts();
                    let machine = run_machine.unwrap_or(teach_machine);
                    let run = self.start_loop(machine, &calibration)?;
                    self.stage = RunStage::Running {
                        run: Box::new(run),
                        calibration,
                    };
                } else {
                    self.stage = RunStage::Teaching { teach, run_machine };
                }
                Ok(false)
            }
            RunStage::Running {
                mut run,
                calibration,
            } => {
                if run.advance(periods)? {
                    let settings = run.settings().clone();
                    let trace = run.into_trace();
                    let metrics = compute(&trace, &metrics_config(self.spec.preset, &settings));
                    self.stage = RunStage::Done(Box::new(RunResult {
                        spec: self.spec.clone(),
                        settings,
                        calibration,
                        trace,
                        metrics,
                    }));
                    Ok(true)
                } else {
                    self.stage = RunStage::Running { run, calibration };
                    Ok(false)
                }
            }
            done @ RunStage::Done(_) => {
                self.stage = done;
                Ok(true)
            }
            RunStage::Empty => Ok(true),
        }
    }

    /// "teach cut", "closed loop" or "done", with the teach cut counted as the first half.
    fn progress(&self) -> Progress {
        let fraction = |elapsed_s: f64| (elapsed_s / self.nominal_duration_s).clamp(0.0, 1.0);
        match &self.stage {
            RunStage::Teaching { teach, .. } => {
                Progress::new("teach cut", 0.5 * fraction(teach.elapsed_s()))
            }
            RunStage::Running { run, .. } if self.calibrated => {
                Progress::new("closed loop", fraction(run.elapsed_s()))
            }
            RunStage::Running { run, .. } => {
                Progress::new("closed loop", 0.5 + 0.5 * fraction(run.elapsed_s()))
            }
            RunStage::Done(_) | RunStage::Empty => Progress::new("done", 1.0),
        }
    }

    fn finish(&mut self) -> Result<RunResult, LoopError> {
        match std::mem::replace(&mut self.stage, RunStage::Empty) {
            RunStage::Done(result) => Ok(*result),
            other => {
                self.stage = other;
                Err(LoopError::NotFinished)
            }
        }
    }
}

/// The closed loop of `spec` as `plan` resolved it, once `calibration` is known, for samples at
/// `sample_rate_hz`, without a machine: the settings settled, the controller built. Refused when
/// the calibration reads another feedback path than the run's. [`LabRun`] runs it on its machine;
/// a host that gets samples as they arrive (the browser's Hardware page) pushes them into it.
pub fn closed_loop_of(
    spec: &RunSpec,
    plan: &Plan,
    calibration: &Calibration,
    sample_rate_hz: f64,
) -> Result<FeedbackLoop, LoopError> {
    FeedbackLoop::wire(
        &spec.controller,
        plan.settle(calibration)?,
        calibration,
        plan.operating_point,
        sample_rate_hz,
    )
}

/// The metrics settings for a run of `preset` with `settings`.
pub fn metrics_config(preset: Preset, settings: &LoopSettings) -> MetricsConfig {
    MetricsConfig {
        force_limit_n: settings.force_limit_n,
        // Paper 002 judges its load step by how soon the current stays near I_ref (Fig. 7): ±2 %.
        // The mills' depth steps are judged at ±10 %, their force's tooth-passing and noise
        // spread alone being a few percent.
        settling_band_pct: if preset.plant_kind() == PlantKind::BondGraph {
            2.0
        } else {
            10.0
        },
        depth_step_mm: 0.2,
        load_step_times_s: preset.load_step_times_s(),
    }
}

/// `spec`'s teach cut (on the machine a run would teach on) as work done in pieces; its
/// calibration is the one [`LabRun::new`] would use.
pub fn teach_cut_work(spec: &RunSpec) -> Result<OnMachine<TeachCut>, LoopError> {
    let teach = preset_machine(spec, spec.seed.wrapping_add(TEACH_SEED_OFFSET))?;
    let plan = plan_on(spec, teach.sample_rate_hz())?;
    OnMachine::teach_cut(teach, &plan, TeachForce::SimulationTruth)
}

/// The settings a run of `spec` uses once its teach cut gave `calibration` (the target settled).
pub fn settled_settings(
    spec: &RunSpec,
    calibration: &Calibration,
) -> Result<LoopSettings, LoopError> {
    preset_plan(spec)?.settle(calibration)
}

/// What a simulated teach cut depends on: two specs with equal keys make the same teach cut, so
/// one calibration serves both ([`LabRun::calibrated`]). A teach cut runs the preset's machine
/// (with its edits, seeded from the run's seed) through the fixed override schedule, summarised
/// by the signal chain at the control period, for the feedback path: the controller, the target
/// and the safety envelope play no part in it.
#[derive(Debug, Clone, PartialEq)]
pub struct TeachKey {
    preset: Preset,
    seed: u64,
    plant: PlantEdits,
    chain: ChainSettings,
    max_duration_s: f64,
}

impl TeachKey {
    /// The key of `spec`'s teach cut.
    pub fn of(spec: &RunSpec) -> Result<Self, LoopError> {
        let plan = preset_plan(spec)?;
        Ok(Self {
            preset: spec.preset,
            seed: spec.seed,
            // A teach cut's machine: the tool's mount changes only the error's model.
            plant: spec.plant.of_the_machine(),
            chain: plan.chain,
            max_duration_s: plan.max_duration_s,
        })
    }
}

/// Runs only `spec`'s teach cut (on the machine a run would teach on) and returns the run's
/// settings with the target it settles to, and the calibration: what a teach-in learns.
pub fn teach_cut_only(spec: &RunSpec) -> Result<(LoopSettings, Calibration), LoopError> {
    let teach = preset_machine(spec, spec.seed.wrapping_add(TEACH_SEED_OFFSET))?;
    let plan = plan_on(spec, teach.sample_rate_hz())?;
    let calibration =
        OnMachine::teach_cut(teach, &plan, TeachForce::SimulationTruth)?.run_to_end()?;
    Ok((plan.settle(&calibration)?, calibration))
}

/// Runs `spec` to the end, without reference runs.
pub fn simulate(spec: &RunSpec) -> Result<RunResult, LoopError> {
    LabRun::new(spec)?.run_to_end()
}

/// Makes the machines of each run of a batch.
pub type MachineFactory = Box<dyn Fn(&RunSpec) -> Result<RunMachines, LoopError>>;

/// Closed-loop runs one after another: the Simulate page's run, the Compare page's variants.
/// Each run gets its machines from a factory (the preset's simulation unless told otherwise), so
/// a comparison can run on any machine that can be made more than once, such as a replayed log.
pub struct LabRuns {
    specs: Vec<RunSpec>,
    machines: MachineFactory,
    teach_force: TeachForce,
    /// The teach cuts made so far, when runs on the preset's simulation share them: a run whose
    /// [`TeachKey`] is here starts from its calibration instead of cutting again.
    calibrations: Option<Vec<(TeachKey, Calibration)>>,
    current: Option<LabRun>,
    results: Vec<std::sync::Arc<RunResult>>,
}

impl LabRuns {
    /// The runs of `specs`, in order, on their presets' simulated machines.
    ///
    /// Runs on the same scenario share one teach cut (their results are the same as with a teach
    /// cut each: the simulation repeats it exactly).
    pub fn new(specs: Vec<RunSpec>) -> Self {
        Self {
            calibrations: Some(Vec::new()),
            ..Self::on_machines(
                specs,
                Box::new(RunMachines::for_preset),
                TeachForce::SimulationTruth,
            )
        }
    }

    /// Runs that start from a known calibration when their teach cut would be the one of its
    /// key (the Simulate page keeps the calibrations of its last runs, so an edit that leaves
    /// the teach cut alone re-runs only the loop); [`LabRuns::new`] otherwise.
    pub fn with_calibrations(specs: Vec<RunSpec>, known: Vec<(TeachKey, Calibration)>) -> Self {
        let mut runs = Self::new(specs);
        runs.calibrations = Some(known);
        runs
    }

    /// The runs finished so far and, once the run under way has started its closed loop, that
    /// run up to now (its trace so far, with the metrics of that part): what a page draws while
    /// the work goes on.
    pub fn partial(&self) -> Vec<std::sync::Arc<RunResult>> {
        let mut runs = self.results.clone();
        if let Some(run) = self.current.as_ref().and_then(LabRun::partial_result) {
            runs.push(std::sync::Arc::new(run));
        }
        runs
    }

    /// The run under way, by its index in the specs, with [`LabRun::loop_so_far`]'s trace and
    /// calibration once its closed loop has started.
    pub fn under_way(&self) -> Option<(usize, &Trace, &Calibration)> {
        let (trace, calibration) = self.current.as_ref()?.loop_so_far()?;
        Some((self.results.len(), trace, calibration))
    }

    /// The teach cuts made or given so far, by key (empty on other machines than the preset's).
    pub fn calibrations(&self) -> &[(TeachKey, Calibration)] {
        self.calibrations.as_deref().unwrap_or(&[])
    }

    /// The runs of `specs`, in order, each on machines made by `machines` and calibrated with
    /// the teach-cut force from `teach_force`.
    pub fn on_machines(
        specs: Vec<RunSpec>,
        machines: MachineFactory,
        teach_force: TeachForce,
    ) -> Self {
        Self {
            results: Vec::with_capacity(specs.len()),
            specs,
            machines,
            teach_force,
            calibrations: None,
            current: None,
        }
    }
}

impl Work for LabRuns {
    type Output = Vec<std::sync::Arc<RunResult>>;
    type Error = LoopError;

    fn advance(&mut self, budget: usize) -> Result<bool, LoopError> {
        let Some(spec) = self.specs.get(self.results.len()) else {
            return Ok(true);
        };
        let run = match &mut self.current {
            Some(run) => run,
            None => {
                let known = match &self.calibrations {
                    Some(known) => {
                        let key = TeachKey::of(spec)?;
                        known
                            .iter()
                            .find(|(k, _)| *k == key)
                            .map(|(_, c)| c.clone())
                    }
                    None => None,
                };
                let run = match known {
                    Some(calibration) => LabRun::calibrated(spec, calibration)?,
                    None => {
                        let machines = (self.machines)(spec)?;
                        LabRun::on_machines(spec, machines, self.teach_force.clone())?
                    }
                };
                self.current.insert(run)
            }
        };
        if run.advance(budget)? {
            let result = run.finish()?;
            if let Some(known) = &mut self.calibrations {
                let key = TeachKey::of(spec)?;
                if !known.iter().any(|(k, _)| *k == key) {
                    known.push((key, result.calibration.clone()));
                }
            }
            self.results.push(std::sync::Arc::new(result));
            self.current = None;
        }
        Ok(self.results.len() >= self.specs.len())
    }

    fn progress(&self) -> Progress {
        let total = self.specs.len().max(1);
        let index = self.results.len();
        let (stage, part) = match &self.current {
            Some(r) => {
                let p = r.progress();
                (p.stage, p.fraction)
            }
            // Between runs nothing has been done yet for the next one (which may need no teach
            // cut); after the last, the output is being handed over.
            None if index >= self.specs.len() => ("done".to_string(), 0.0),
            None => ("starting".to_string(), 0.0),
        };
        let label = if total > 1 {
            format!("Run {} of {total}: {stage}", (index + 1).min(total))
        } else {
            format!("Running: {stage}")
        };
        Progress::new(label, (index as f64 + part) / total as f64)
    }

    fn finish(&mut self) -> Result<Self::Output, LoopError> {
        if self.results.len() < self.specs.len() {
            return Err(LoopError::NotFinished);
        }
        Ok(std::mem::take(&mut self.results))
    }
}
