//! Runs sent to another thread and back: what the browser's page asks a computation worker to run
//! ([`RunRequest`]), the pieces of a run's trace streamed while it runs ([`TraceChunk`], made by
//! [`TraceStream`], gathered by [`StreamedRun`]) and the finished runs it receives ([`RunParts`]).
//!
//! The worker (`src/bin/cutlab-worker.rs`) is a second wasm module, built without the UI, that
//! runs [`LabRuns`] and posts each result back. A result must read on the page exactly as if the
//! page had run it (the parity checks compare digests of the traces), so nothing is rounded on
//! the way: the trace's numbers travel as raw `f64`s (a `Float64Array` in the browser, moved
//! rather than copied), the calibration and events as JSON (whose numbers read back exactly with
//! serde_json's `float_roundtrip`), and the rest — the settled settings, the controller's term
//! names, the metrics — is derived again on the page from those by the same code the run used.

use serde::{Deserialize, Serialize};

use super::definition::RunSpec;
use super::error::LoopError;
use super::feedback_loop::controller_for;
use super::flat_row::flat_row;
use super::lab::{metrics_config, preset_plan, LabRuns, RunResult, TeachKey};
use super::metrics::compute;
use super::recording_jobs::{BenchRequest, OpenLoopRequest, TeachCutsRequest};
use super::references::{ReferenceSearch, References};
use super::settings::LoopSettings;
use super::trace::{Trace, TraceRow};
use super::trial_cuts::{learn_on_preset, PresetLearning};
use crate::estimation::estimator::Calibration;
use crate::plant::Preset;
use crate::safety::SafetyEvent;

/// What a page asks a worker to do: one variant per kind of job, each with its own answer.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum JobRequest {
    /// Closed-loop runs (Simulate's run, Compare's variants), streamed as [`TraceChunk`]s and
    /// answered by one [`RunParts`] per run.
    Runs(RunRequest),
    /// The fixed-feed reference runs of a scenario's savings, answered by their [`References`]
    /// ([`references_to_json`]).
    References(Box<ReferenceRequest>),
    /// Paper 004's network learned on a preset's trial cuts, answered by its
    /// [`PresetLearning`] ([`learning_to_json`]).
    Learning(LearningRequest),
    /// Paper 000's bench recording (the Signal chain page), answered by its
    /// [`crate::plant::recording::PhaseRecording`] packed ([`super::recording_jobs`]).
    Bench(BenchRequest),
    /// An open-loop recording of a preset's machine (the Machine page), answered by its
    /// [`crate::plant::recording::OpenLoopRecording`] packed ([`super::recording_jobs`]).
    OpenLoop(OpenLoopRequest),
    /// The teach cuts of Tune's teach-in, answered by their calibrations
    /// ([`super::recording_jobs`]).
    TeachCuts(TeachCutsRequest),
}

/// The trial cuts to learn paper 004's network on: a preset's program at fixed feeds
/// ([`learn_on_preset`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LearningRequest {
    /// The preset whose program makes the cuts.
    pub preset: Preset,
    /// The feeds, percent of the programmed feed.
    pub feeds_pct: Vec<f64>,
}

impl LearningRequest {
    /// Learns the network, as `cutlab learn` does.
    pub fn learn(&self) -> Result<PresetLearning, String> {
        learn_on_preset(self.preset, &self.feeds_pct).map_err(|e| e.to_string())
    }
}

/// A learning as JSON, for the worker's answer (every number in it is finite).
pub fn learning_to_json(learning: &PresetLearning) -> Result<String, String> {
    serde_json::to_string(learning).map_err(|e| format!("the learning could not be sent: {e}"))
}

/// A learning read from a worker's answer.
pub fn learning_from_json(json: &str) -> Result<PresetLearning, String> {
    serde_json::from_str(json).map_err(|e| format!("the worker's learning could not be read: {e}"))
}

impl JobRequest {
    /// The request as JSON.
    pub fn to_json(&self) -> Result<String, String> {
        serde_json::to_string(self).map_err(|e| format!("the job could not be sent: {e}"))
    }

    /// A request read from JSON.
    pub fn from_json(json: &str) -> Result<Self, String> {
        serde_json::from_str(json).map_err(|e| format!("the worker received a bad request: {e}"))
    }
}

/// The reference runs of a scenario (a spec at the fixed 100 % feed), on the calibration of its
/// teach cut when the page knows it: the same search, and answer, as the page's own
/// [`ReferenceSearch`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReferenceRequest {
    /// The scenario.
    pub scenario: RunSpec,
    /// The calibration of its teach cut, if known.
    pub calibration: Option<Calibration>,
}

impl ReferenceRequest {
    /// The search.
    pub fn into_work(self) -> Result<ReferenceSearch, String> {
        match self.calibration {
            Some(c) => ReferenceSearch::calibrated(&self.scenario, c),
            None => ReferenceSearch::new(&self.scenario),
        }
        .map_err(|e| e.to_string())
    }
}

/// Found references as a worker sends them (a NaN, where no fixed feed keeps the force, travels
/// as `null` and reads back as NaN; every other number reads back exactly).
pub fn references_to_json(found: &References) -> Result<String, String> {
    serde_json::to_string(found).map_err(|e| format!("the references could not be sent: {e}"))
}

/// References read from a worker's answer.
pub fn references_from_json(json: &str) -> Result<References, String> {
    serde_json::from_str(json)
        .map_err(|e| format!("the worker's references could not be read: {e}"))
}

/// What a page asks a worker to run: closed-loop runs on their presets' simulations, with the
/// teach cuts the page already knows.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RunRequest {
    /// The runs, in order.
    pub specs: Vec<RunSpec>,
    /// Calibrations of teach cuts the runs would make, each with the index of a run it serves
    /// (the worker skips the teach cut of every run with that run's [`TeachKey`]).
    pub calibrations: Vec<(usize, Calibration)>,
}

impl RunRequest {
    /// `specs`, with those of the `known` calibrations that one of them would teach.
    pub fn new(specs: Vec<RunSpec>, known: &[(TeachKey, Calibration)]) -> Self {
        let keys: Vec<Option<TeachKey>> = specs.iter().map(|s| TeachKey::of(s).ok()).collect();
        let calibrations = known
            .iter()
            .filter_map(|(key, c)| {
                let index = keys.iter().position(|k| k.as_ref() == Some(key))?;
                Some((index, c.clone()))
            })
            .collect();
        Self {
            specs,
            calibrations,
        }
    }

    /// The work: [`LabRuns`] starting from the known calibrations (the same runs, and results,
    /// as the page's own `LabRuns::with_calibrations`).
    pub fn into_work(self) -> LabRuns {
        let known = self
            .calibrations
            .into_iter()
            .filter_map(|(index, c)| Some((TeachKey::of(self.specs.get(index)?).ok()?, c)))
            .collect();
        LabRuns::with_calibrations(self.specs, known)
    }
}

/// A finished run as a worker sends it: the parts the page cannot derive again.
#[derive(Debug, Clone, PartialEq)]
pub struct RunParts {
    /// The calibration, events and completion, as JSON.
    pub header_json: String,
    /// The trace's rows, [`ROW_VALUES`] numbers each.
    pub rows: Vec<f64>,
    /// The controller's terms, as in [`Trace::terms`].
    pub terms: Vec<f64>,
}

/// What of a run travels as JSON.
#[derive(Serialize, Deserialize)]
struct Header {
    calibration: Calibration,
    events: Vec<SafetyEvent>,
    completed: bool,
}

flat_row! {
    TraceRow;
    /// Numbers per trace row in [`RunParts::rows`]: its quantities, then its flags.
    ROW_VALUES,
    row_values,
    row_from;
    numbers:
    time_s,
    depth_mm,
    width_mm,
    path_position_mm,
    programmed_feed_mm_min,
    feed_mm_min,
    requested_override_pct,
    override_pct,
    applied_override_pct,
    force_n,
    force_est_n,
    force_power_law_n,
    target_force_n,
    force_min_n,
    force_max_n,
    spindle_current_rms_a,
    feed_current_rms_a,
    feed_current_u_min_a,
    feed_current_u_max_a,
    spindle_speed_rpm,
    material_removal_mm3_s,
    surface_error_um,
    compensated_error_power_law_um,
    compensated_error_current_um,
    ;
    flags:
    armed,
    sensor_fault,
    feed_hold,
    estimate_in_range,
    sensor_failure_predicted,
}

impl RunParts {
    /// The parts of `result` to send.
    pub fn of(result: &RunResult) -> Result<Self, String> {
        let header = Header {
            calibration: result.calibration.clone(),
            events: result.trace.events.clone(),
            completed: result.trace.completed,
        };
        let header_json = serde_json::to_string(&header)
            .map_err(|e| format!("the run's result could not be sent: {e}"))?;
        Ok(Self {
            header_json,
            rows: flat_rows(&result.trace.rows),
            terms: result.trace.terms.clone(),
        })
    }

    /// The run of `spec` these parts came from, as the run itself made it: the settings settled
    /// from the calibration, the term names of the spec's controller, the metrics of the trace.
    pub fn into_result(self, spec: RunSpec) -> Result<RunResult, String> {
        let header: Header = serde_json::from_str(&self.header_json)
            .map_err(|e| format!("the worker's result could not be read: {e}"))?;
        let rows = rows_from_flat(&self.rows, "trace")?;
        let (settings, term_names) = settled(&spec, &header.calibration)?;
        let trace = Trace {
            rows,
            events: header.events,
            term_names,
            terms: self.terms,
            completed: header.completed,
        };
        let metrics = compute(&trace, &metrics_config(spec.preset, &settings));
        Ok(RunResult {
            spec,
            settings,
            calibration: header.calibration,
            trace,
            metrics,
        })
    }
}

/// What a run of `spec` on `calibration` derives again on the page, as the run itself derived
/// it: the settings settled from the calibration, and the names and units of its controller's
/// terms.
fn settled(spec: &RunSpec, calibration: &Calibration) -> Result<(LoopSettings, TermNames), String> {
    let message = |e: LoopError| e.to_string();
    let plan = preset_plan(spec).map_err(message)?;
    let settings = plan.settle(calibration).map_err(message)?;
    let controller = controller_for(
        &spec.controller,
        &settings,
        calibration,
        plan.operating_point,
    )
    .map_err(message)?;
    let names = controller
        .terms()
        .iter()
        .map(|t| (t.name, t.unit))
        .collect();
    Ok((settings, names))
}

/// Names and units of a controller's terms, as in [`Trace::term_names`].
type TermNames = Vec<(&'static str, &'static str)>;

/// A piece of a run's trace sent while the run goes on, so the page can draw the start of a cut
/// long before its end: the rows and terms added since the run's last piece.
#[derive(Debug, Clone, PartialEq)]
pub struct TraceChunk {
    /// Which run of the request it belongs to (its index in [`RunRequest::specs`]).
    pub run: usize,
    /// The run's calibration as JSON, with the run's first piece only (the page derives the
    /// settings and the controller's term names from it).
    pub calibration_json: Option<String>,
    /// The new rows, [`ROW_VALUES`] numbers each.
    pub rows: Vec<f64>,
    /// The new rows' controller terms, as in [`Trace::terms`].
    pub terms: Vec<f64>,
}

/// What of the run under way a worker has streamed so far.
#[derive(Debug, Default)]
pub struct TraceStream {
    /// The run being streamed, and how many of its rows and term values have been sent.
    sent: Option<(usize, usize, usize)>,
}

impl TraceStream {
    /// The rows of `work`'s run under way that have not been sent yet, or `None` if there are
    /// none (the run is still in its teach cut, or nothing new was traced).
    pub fn next_chunk(&mut self, work: &LabRuns) -> Result<Option<TraceChunk>, String> {
        let Some((run, trace, calibration)) = work.under_way() else {
            return Ok(None);
        };
        let (rows_sent, terms_sent, calibration_json) = match self.sent {
            Some((streamed, rows, terms)) if streamed == run => (rows, terms, None),
            _ => (0, 0, Some(to_json(calibration)?)),
        };
        let (Some(new_rows), Some(new_terms)) =
            (trace.rows.get(rows_sent..), trace.terms.get(terms_sent..))
        else {
            return Err("the run's trace shrank while it was sent".into());
        };
        if new_rows.is_empty() {
            return Ok(None);
        }
        let rows = flat_rows(new_rows);
        self.sent = Some((run, trace.rows.len(), trace.terms.len()));
        Ok(Some(TraceChunk {
            run,
            calibration_json,
            rows,
            terms: new_terms.to_vec(),
        }))
    }
}

fn to_json(calibration: &Calibration) -> Result<String, String> {
    serde_json::to_string(calibration)
        .map_err(|e| format!("the run's calibration could not be sent: {e}"))
}

/// A run received piece by piece ([`TraceChunk`]s): the part of it that has arrived, for the page
/// to draw while the worker goes on. The finished run still comes whole ([`RunParts`]).
#[derive(Debug, Clone)]
pub struct StreamedRun {
    spec: RunSpec,
    settings: LoopSettings,
    calibration: Calibration,
    term_names: TermNames,
    rows: Vec<TraceRow>,
    terms: Vec<f64>,
}

impl StreamedRun {
    /// The calibration the run started from (its teach cut's, or one given).
    pub fn calibration(&self) -> &Calibration {
        &self.calibration
    }

    /// The run of `spec` whose first piece is `first` (which carries the calibration).
    pub fn start(spec: RunSpec, first: TraceChunk) -> Result<Self, String> {
        let json = first
            .calibration_json
            .as_deref()
            .ok_or("the worker's first piece of a run lacks its calibration")?;
        let calibration: Calibration = serde_json::from_str(json)
            .map_err(|e| format!("the worker's calibration could not be read: {e}"))?;
        let (settings, term_names) = settled(&spec, &calibration)?;
        let mut run = Self {
            spec,
            settings,
            calibration,
            term_names,
            rows: Vec::new(),
            terms: Vec::new(),
        };
        run.append(first)?;
        Ok(run)
    }

    /// Adds the next piece.
    pub fn append(&mut self, chunk: TraceChunk) -> Result<(), String> {
        if !chunk.rows.len().is_multiple_of(ROW_VALUES) {
            return Err(format!(
                "a piece of the worker's trace holds {} numbers, not a whole number of rows of {ROW_VALUES}",
                chunk.rows.len()
            ));
        }
        self.rows
            .extend(chunk.rows.chunks_exact(ROW_VALUES).map(row_from));
        self.terms.extend_from_slice(&chunk.terms);
        Ok(())
    }

    /// The rows received so far.
    pub fn rows(&self) -> usize {
        self.rows.len()
    }

    /// The run so far as a result: the trace received, not completed, without the safety events
    /// (which come with the finished run), and the metrics of that part.
    pub fn so_far(&self) -> RunResult {
        let trace = Trace {
            rows: self.rows.clone(),
            events: Vec::new(),
            term_names: self.term_names.clone(),
            terms: self.terms.clone(),
            completed: false,
        };
        let metrics = compute(&trace, &metrics_config(self.spec.preset, &self.settings));
        RunResult {
            spec: self.spec.clone(),
            settings: self.settings.clone(),
            calibration: self.calibration.clone(),
            trace,
            metrics,
        }
    }
}

/// Rows' numbers, [`ROW_VALUES`] per row, in the order the row's fields are listed above (a
/// trace as it travels; the Logs page's replays too, [`crate::log::transfer`]).
pub fn flat_rows(rows: &[TraceRow]) -> Vec<f64> {
    let mut flat = Vec::with_capacity(rows.len() * ROW_VALUES);
    for row in rows {
        flat.extend_from_slice(&row_values(row));
    }
    flat
}

/// The rows whose numbers a worker sent for its `what` ([`flat_rows`]'s), refused unless they
/// are a whole number of rows.
pub fn rows_from_flat(flat: &[f64], what: &str) -> Result<Vec<TraceRow>, String> {
    if !flat.len().is_multiple_of(ROW_VALUES) {
        return Err(format!(
            "the worker's {what} holds {} numbers, not a whole number of rows of {ROW_VALUES}",
            flat.len()
        ));
    }
    Ok(flat.chunks_exact(ROW_VALUES).map(row_from).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_row_travels_as_its_numbers_and_flags_and_reads_back() {
        let mut values: Vec<f64> = (0..ROW_VALUES).map(|i| i as f64 + 0.25).collect();
        // The flags, last: alternately set and clear.
        let flags = ROW_VALUES - 5;
        for (i, v) in values[flags..].iter_mut().enumerate() {
            *v = if i % 2 == 0 { 1.0 } else { 0.0 };
        }
        let row = row_from(&values);
        assert_eq!(row.time_s, 0.25);
        assert_eq!(row.compensated_error_current_um, (flags - 1) as f64 + 0.25);
        assert!(row.armed && !row.sensor_fault && row.feed_hold);
        assert_eq!(row_values(&row).to_vec(), values);
        // A short row reads its missing numbers as NaN.
        assert!(row_from(&values[..3]).path_position_mm.is_nan());
    }

    #[test]
    fn a_learning_crosses_to_the_page_unchanged() {
        let request = LearningRequest {
            preset: crate::plant::Preset::KimStepDoc,
            feeds_pct: vec![80.0, 100.0],
        };
        let request_json = JobRequest::Learning(request.clone()).to_json().unwrap();
        assert_eq!(
            JobRequest::from_json(&request_json).unwrap(),
            JobRequest::Learning(request.clone())
        );
        let learning = request.learn().unwrap();
        assert_eq!(learning.cuts.len(), 10);
        let back = learning_from_json(&learning_to_json(&learning).unwrap()).unwrap();
        assert_eq!(back, learning);
        assert!(learning_from_json("{\"preset\": 3}").is_err());
    }
    use crate::closed_loop::lab::simulate;
    use crate::control::registry::ControllerKind;
    use crate::plant::Preset;
    use crate::work::Work;

    fn short_spec(kind: ControllerKind) -> RunSpec {
        RunSpec::new(Preset::ManeeratDoc1, kind)
    }

    #[test]
    fn a_run_sent_and_received_reads_as_the_run_itself() {
        // Debug prints every number at full precision, NaN as NaN (which `==` would not match).
        for kind in [ControllerKind::Threshold, ControllerKind::Pi] {
            let spec = short_spec(kind);
            let direct = simulate(&spec).unwrap();
            let parts = RunParts::of(&direct).unwrap();
            let received = parts.into_result(spec).unwrap();
            assert_eq!(format!("{received:?}"), format!("{direct:?}"));
            assert!(!direct.trace.term_names.is_empty());
        }
    }

    #[test]
    fn a_request_read_back_runs_what_the_page_would_run() {
        let spec = short_spec(ControllerKind::Pi);
        let first = simulate(&spec).unwrap();
        let known = vec![(TeachKey::of(&spec).unwrap(), first.calibration.clone())];
        let json = JobRequest::Runs(RunRequest::new(vec![spec.clone()], &known))
            .to_json()
            .unwrap();
        let Ok(JobRequest::Runs(request)) = JobRequest::from_json(&json) else {
            panic!("{json} read back as another job");
        };
        assert_eq!(
            request.calibrations.len(),
            1,
            "the matching calibration travels"
        );
        let in_worker = request.into_work().run_to_end().unwrap();
        let on_page = LabRuns::with_calibrations(vec![spec], known)
            .run_to_end()
            .unwrap();
        assert_eq!(format!("{in_worker:?}"), format!("{on_page:?}"));
        assert!(JobRequest::from_json("{\"kind\": \"runs\", \"specs\": 3}").is_err());
    }

    #[test]
    fn references_found_in_a_worker_read_as_the_page_would_find_them() {
        let spec = short_spec(ControllerKind::Threshold);
        let scenario = crate::closed_loop::references::fixed_feed_spec(&spec, 100.0).unwrap();
        let calibration = simulate(&spec).unwrap().calibration;
        let on_page = ReferenceSearch::calibrated(&scenario, calibration.clone())
            .unwrap()
            .run_to_end()
            .unwrap();
        let json = JobRequest::References(Box::new(ReferenceRequest {
            scenario,
            calibration: Some(calibration),
        }))
        .to_json()
        .unwrap();
        let Ok(JobRequest::References(request)) = JobRequest::from_json(&json) else {
            panic!("{json} read back as another job");
        };
        let found = request.into_work().unwrap().run_to_end().unwrap();
        let received = references_from_json(&references_to_json(&found).unwrap()).unwrap();
        assert_eq!(format!("{received:?}"), format!("{on_page:?}"));
        assert!(received.programmed_cycle_time_s > 0.0);
        // A search that found no safe fixed feed sends NaN as null and reads it back as NaN.
        let none = References {
            safe_fixed_override_pct: f64::NAN,
            safe_fixed_cycle_time_s: f64::NAN,
            ..received
        };
        let back = references_from_json(&references_to_json(&none).unwrap()).unwrap();
        assert!(back.safe_fixed_override_pct.is_nan() && back.safe_fixed_cycle_time_s.is_nan());
    }

    #[test]
    fn a_streamed_run_arrives_in_pieces_before_its_end_and_adds_up_to_the_run() {
        let spec = short_spec(ControllerKind::Pi);
        let direct = simulate(&spec).unwrap();
        let mut work = LabRuns::new(vec![spec.clone()]);
        let mut stream = TraceStream::default();
        let mut streamed: Option<StreamedRun> = None;
        // Rows seen while the run was still going, at each piece.
        let mut seen_before_end = Vec::new();
        while !work.advance(50).unwrap() {
            if let Some(chunk) = stream.next_chunk(&work).unwrap() {
                assert_eq!(chunk.run, 0);
                assert_eq!(chunk.calibration_json.is_some(), streamed.is_none());
                match &mut streamed {
                    Some(run) => run.append(chunk).unwrap(),
                    None => streamed = Some(StreamedRun::start(spec.clone(), chunk).unwrap()),
                }
                seen_before_end.push(streamed.as_ref().unwrap().rows());
            }
            assert!(
                stream.next_chunk(&work).unwrap().is_none(),
                "nothing new twice"
            );
        }
        let streamed = streamed.expect("the loop streamed");
        assert!(seen_before_end.len() > 2, "{seen_before_end:?}");
        let so_far = streamed.so_far();
        let bits = |rows: &[TraceRow]| -> Vec<[u64; ROW_VALUES]> {
            rows.iter()
                .map(|r| row_values(r).map(f64::to_bits))
                .collect()
        };
        // Everything streamed is the start of the finished run, bit for bit.
        let n = so_far.trace.rows.len();
        assert!(n > 0 && n <= direct.trace.rows.len());
        assert_eq!(bits(&so_far.trace.rows), bits(&direct.trace.rows[..n]));
        let width = direct.trace.term_names.len();
        assert_eq!(so_far.trace.term_names, direct.trace.term_names);
        assert_eq!(
            so_far
                .trace
                .terms
                .iter()
                .map(|t| t.to_bits())
                .collect::<Vec<_>>(),
            direct.trace.terms[..n * width]
                .iter()
                .map(|t| t.to_bits())
                .collect::<Vec<_>>()
        );
        // Debug: NaN (an unused speed range) prints as NaN, which `==` would not match.
        let derived = |r: &RunResult| format!("{:?}", (&r.settings, &r.calibration));
        assert_eq!(derived(&so_far), derived(&direct));
        assert!(!so_far.trace.completed);
        // The finished work equals the direct run whatever was streamed from it.
        let finished = work.finish().unwrap();
        assert_eq!(format!("{:?}", finished[0]), format!("{direct:?}"));
    }

    #[test]
    fn a_first_piece_without_its_calibration_or_a_ragged_piece_is_refused() {
        let spec = short_spec(ControllerKind::Threshold);
        let piece = TraceChunk {
            run: 0,
            calibration_json: None,
            rows: vec![0.0; ROW_VALUES],
            terms: Vec::new(),
        };
        assert!(StreamedRun::start(spec.clone(), piece.clone())
            .unwrap_err()
            .contains("calibration"));
        let calibration = simulate(&spec).unwrap().calibration;
        let first = TraceChunk {
            calibration_json: Some(serde_json::to_string(&calibration).unwrap()),
            ..piece.clone()
        };
        let mut run = StreamedRun::start(spec, first).unwrap();
        let ragged = TraceChunk {
            rows: vec![0.0; ROW_VALUES + 1],
            ..piece
        };
        assert!(run.append(ragged).unwrap_err().contains("whole number"));
        assert_eq!(run.rows(), 1);
    }

    #[test]
    fn rows_travel_bit_for_bit_and_a_ragged_trace_is_refused() {
        let row = TraceRow {
            time_s: 0.1 + 0.2,
            depth_mm: f64::NAN,
            force_min_n: -0.0,
            spindle_speed_rpm: f64::INFINITY,
            armed: true,
            sensor_failure_predicted: true,
            ..TraceRow::default()
        };
        let back = row_from(&row_values(&row));
        let bits = |r: &TraceRow| row_values(r).map(f64::to_bits);
        assert_eq!(bits(&back), bits(&row));
        let spec = short_spec(ControllerKind::Threshold);
        let mut parts = RunParts::of(&simulate(&spec).unwrap()).unwrap();
        parts.rows.pop();
        assert!(parts
            .into_result(spec)
            .unwrap_err()
            .contains("whole number"));
    }
}
