//! Runs sent to another thread and back: what the browser's page asks a computation worker to run
//! ([`RunRequest`]) and the finished runs it receives ([`RunParts`]).
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
use super::lab::{metrics_config, preset_plan, LabRuns, RunResult, TeachKey};
use super::metrics::compute;
use super::trace::{Trace, TraceRow};
use crate::estimation::estimator::Calibration;
use crate::safety::SafetyEvent;

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

    /// The request as JSON.
    pub fn to_json(&self) -> Result<String, String> {
        serde_json::to_string(self).map_err(|e| format!("the run could not be sent: {e}"))
    }

    /// A request read from JSON.
    pub fn from_json(json: &str) -> Result<Self, String> {
        serde_json::from_str(json).map_err(|e| format!("the worker received a bad request: {e}"))
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

/// Numbers per trace row in [`RunParts::rows`]: its 21 quantities and 5 flags (as 0 or 1).
pub const ROW_VALUES: usize = 29;

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
        let mut rows = Vec::with_capacity(result.trace.rows.len() * ROW_VALUES);
        for row in &result.trace.rows {
            rows.extend_from_slice(&row_values(row));
        }
        Ok(Self {
            header_json,
            rows,
            terms: result.trace.terms.clone(),
        })
    }

    /// The run of `spec` these parts came from, as the run itself made it: the settings settled
    /// from the calibration, the term names of the spec's controller, the metrics of the trace.
    pub fn into_result(self, spec: RunSpec) -> Result<RunResult, String> {
        let header: Header = serde_json::from_str(&self.header_json)
            .map_err(|e| format!("the worker's result could not be read: {e}"))?;
        if !self.rows.len().is_multiple_of(ROW_VALUES) {
            return Err(format!(
                "the worker's trace holds {} numbers, not a whole number of rows of {ROW_VALUES}",
                self.rows.len()
            ));
        }
        let result = |e: LoopError| e.to_string();
        let plan = preset_plan(&spec).map_err(result)?;
        let settings = plan.settle(&header.calibration).map_err(result)?;
        let controller = controller_for(
            &spec.controller,
            &settings,
            &header.calibration,
            plan.operating_point,
        )
        .map_err(result)?;
        let trace = Trace {
            rows: self.rows.chunks_exact(ROW_VALUES).map(row_from).collect(),
            events: header.events,
            term_names: controller
                .terms()
                .iter()
                .map(|t| (t.name, t.unit))
                .collect(),
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

/// A row's numbers, in [`row_from`]'s order.
fn row_values(row: &TraceRow) -> [f64; ROW_VALUES] {
    // Destructured whole, so a field added to the row fails to compile here until it travels.
    let TraceRow {
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
        armed,
        sensor_fault,
        feed_hold,
        estimate_in_range,
        cross_check_disagrees,
    } = *row;
    let flag = |b: bool| if b { 1.0 } else { 0.0 };
    [
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
        flag(armed),
        flag(sensor_fault),
        flag(feed_hold),
        flag(estimate_in_range),
        flag(cross_check_disagrees),
    ]
}

/// The row whose [`row_values`] are `v` (exactly [`ROW_VALUES`] long).
fn row_from(v: &[f64]) -> TraceRow {
    let at = |i: usize| v.get(i).copied().unwrap_or(f64::NAN);
    let flag = |i: usize| at(i) != 0.0;
    TraceRow {
        time_s: at(0),
        depth_mm: at(1),
        width_mm: at(2),
        path_position_mm: at(3),
        programmed_feed_mm_min: at(4),
        feed_mm_min: at(5),
        requested_override_pct: at(6),
        override_pct: at(7),
        applied_override_pct: at(8),
        force_n: at(9),
        force_est_n: at(10),
        force_power_law_n: at(11),
        target_force_n: at(12),
        force_min_n: at(13),
        force_max_n: at(14),
        spindle_current_rms_a: at(15),
        feed_current_rms_a: at(16),
        feed_current_u_min_a: at(17),
        feed_current_u_max_a: at(18),
        spindle_speed_rpm: at(19),
        material_removal_mm3_s: at(20),
        surface_error_um: at(21),
        compensated_error_power_law_um: at(22),
        compensated_error_current_um: at(23),
        armed: flag(24),
        sensor_fault: flag(25),
        feed_hold: flag(26),
        estimate_in_range: flag(27),
        cross_check_disagrees: flag(28),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
        let json = RunRequest::new(vec![spec.clone()], &known)
            .to_json()
            .unwrap();
        let request = RunRequest::from_json(&json).unwrap();
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
        assert!(RunRequest::from_json("{\"specs\": 3}").is_err());
    }

    #[test]
    fn rows_travel_bit_for_bit_and_a_ragged_trace_is_refused() {
        let row = TraceRow {
            time_s: 0.1 + 0.2,
            depth_mm: f64::NAN,
            force_min_n: -0.0,
            spindle_speed_rpm: f64::INFINITY,
            armed: true,
            cross_check_disagrees: true,
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
