//! The Logs page's replays sent to a computation worker and back: what the page asks
//! ([`ReplayRequest`], the log's numbers beside its JSON) and what the worker answers
//! ([`ReplayParts`]). The rest of the job protocol — closed-loop runs, references, learning — is
//! [`crate::closed_loop::transfer`], a layer below the logs; a replay's trace travels as a run's
//! does ([`flat_rows`], [`rows_from_flat`]), bit for bit.

use serde::{Deserialize, Serialize};

use super::csv::Dialect;
use super::mapping::Mapping;
use super::replay::{ReplayResult, ReplayRun, ReplayRuns, ReplaySettings};
use super::{Column, ColumnKind, Log, ReadAccount};
use crate::closed_loop::trace::Trace;
use crate::closed_loop::transfer::{flat_rows, rows_from_flat};
use crate::control::registry::ControllerConfig;
use crate::safety::SafetyEvent;

/// What the Logs page asks a worker to replay: controllers on a log, each through the loop
/// every run uses ([`ReplayRuns`]), with the page's settings; posted as `{ job, replay, numbers }`
/// (`src/bin/cutlab-worker.rs`). The log travels as its shape here
/// (its columns' names and kinds, rows, sample period) and its numbers beside the JSON, one raw
/// `f64` array per column of the shape (a `Float64Array` in the browser, moved rather than
/// copied): a log may be 100 MB of text, whose numbers as JSON would be as big again and take a
/// parse. Only the columns the mapping names travel (and the time column): a replay reads no
/// other.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ReplayRequest {
    /// The log, but its numbers.
    pub log: LogShape,
    /// Which column is which channel.
    pub mapping: Mapping,
    /// The replay's settings.
    pub settings: ReplaySettings,
    /// The controllers, replayed in turn.
    pub controllers: Vec<ControllerConfig>,
}

/// What of a log a replay reads, but its numbers ([`ReplayRequest`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogShape {
    /// Rows of the log.
    pub rows: usize,
    /// Its sample period, s, if known.
    pub sample_period_s: Option<f64>,
    /// Which of `columns` is its time column, if one is.
    pub time_column: Option<usize>,
    /// The columns sent, each with its numbers beside the JSON (a text column's are none).
    pub columns: Vec<ColumnShape>,
}

/// A column sent with a replay.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColumnShape {
    /// Its name, as the mapping names it.
    pub name: String,
    /// What it holds.
    pub kind: ColumnKind,
}

impl ReplayRequest {
    /// The request as JSON (the log's numbers apart).
    pub fn to_json(&self) -> Result<String, String> {
        serde_json::to_string(self).map_err(|e| format!("the replay could not be sent: {e}"))
    }

    /// A request read from JSON.
    pub fn from_json(json: &str) -> Result<Self, String> {
        serde_json::from_str(json)
            .map_err(|e| format!("the worker received a bad replay request: {e}"))
    }

    /// `controllers` replayed on `log` read through `mapping`, and the numbers to send beside
    /// the request: one slice per column of [`LogShape::columns`], in order (borrowed from the
    /// log, so the page copies each once, into the array it moves to the worker).
    pub fn new(
        log: &Log,
        mapping: Mapping,
        settings: ReplaySettings,
        controllers: Vec<ControllerConfig>,
    ) -> (Self, Vec<&[f64]>) {
        let sent: Vec<usize> = (0..log.columns.len())
            .filter(|&i| {
                log.time_column == Some(i)
                    || mapping
                        .columns
                        .iter()
                        .any(|(name, _)| *name == log.columns[i].name)
            })
            .collect();
        let shape = LogShape {
            rows: log.rows,
            sample_period_s: log.sample_period_s,
            time_column: log
                .time_column
                .and_then(|t| sent.iter().position(|&i| i == t)),
            columns: sent
                .iter()
                .map(|&i| ColumnShape {
                    name: log.columns[i].name.clone(),
                    kind: log.columns[i].kind,
                })
                .collect(),
        };
        let numbers = sent
            .iter()
            .map(|&i| log.columns[i].values.as_slice())
            .collect();
        let request = Self {
            log: shape,
            mapping,
            settings,
            controllers,
        };
        (request, numbers)
    }

    /// The replays, on the log rebuilt from its shape and `numbers` (one per column, in
    /// order): the same replays, and results, as the page's own [`ReplayRuns`] on the whole log.
    pub fn into_work(self, numbers: Vec<Vec<f64>>) -> Result<ReplayRuns, String> {
        let shape = self.log;
        if numbers.len() != shape.columns.len() {
            return Err(format!(
                "the worker received {} columns of numbers for the log's {}",
                numbers.len(),
                shape.columns.len()
            ));
        }
        let numeric = |kind: ColumnKind| matches!(kind, ColumnKind::Number | ColumnKind::Time);
        let columns = shape
            .columns
            .into_iter()
            .zip(numbers)
            .map(|(c, values)| {
                if numeric(c.kind) && values.len() != shape.rows {
                    return Err(format!(
                        "the worker received {} numbers of column {:?} for the log's {} rows",
                        values.len(),
                        c.name,
                        shape.rows
                    ));
                }
                Ok(Column {
                    name: c.name,
                    unit: None,
                    kind: c.kind,
                    role: None,
                    role_reason: None,
                    values,
                    labels: Vec::new(),
                    label_names: Vec::new(),
                    numeric_share: 1.0,
                    missing: 0,
                    not_finite: 0,
                })
            })
            .collect::<Result<Vec<_>, String>>()?;
        let log = Log {
            dialect: Dialect {
                delimiter: b',',
                decimal_comma: false,
            },
            header: true,
            columns,
            rows: shape.rows,
            time_column: shape.time_column,
            sample_period_s: shape.sample_period_s,
            problems: Vec::new(),
            problems_not_listed: 0,
            row_lines: Vec::new(),
            account: ReadAccount::default(),
        };
        Ok(ReplayRuns::new(
            std::sync::Arc::new(log),
            self.mapping,
            self.settings,
            self.controllers,
        ))
    }
}

/// A finished replay as a worker sends it: its trace, the rest being derived again on the page
/// by the replay prepared there ([`ReplayRun::with_trace`]: the settings, notes, target and
/// summary, by the same code).
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayParts {
    /// The envelope's events and the completion, as JSON.
    pub header_json: String,
    /// The trace's rows, [`ROW_VALUES`] numbers each.
    pub rows: Vec<f64>,
    /// The controller's terms, as in [`Trace::terms`].
    pub terms: Vec<f64>,
}

/// What of a replay travels as JSON.
#[derive(Serialize, Deserialize)]
struct ReplayHeader {
    events: Vec<SafetyEvent>,
    completed: bool,
}

impl ReplayParts {
    /// The parts of `result` to send.
    pub fn of(result: &ReplayResult) -> Result<Self, String> {
        let header = ReplayHeader {
            events: result.trace.events.clone(),
            completed: result.trace.completed,
        };
        let header_json = serde_json::to_string(&header)
            .map_err(|e| format!("the replay's result could not be sent: {e}"))?;
        Ok(Self {
            header_json,
            rows: flat_rows(&result.trace.rows),
            terms: result.trace.terms.clone(),
        })
    }

    /// The result of `replay` (prepared on the page, not run) that the worker's replay of the
    /// same controller made.
    pub fn into_result(self, replay: ReplayRun) -> Result<ReplayResult, String> {
        let header: ReplayHeader = serde_json::from_str(&self.header_json)
            .map_err(|e| format!("the worker's replay could not be read: {e}"))?;
        let trace = Trace {
            rows: rows_from_flat(&self.rows, "replay")?,
            events: header.events,
            term_names: replay.term_names(),
            terms: self.terms,
            completed: header.completed,
        };
        replay.with_trace(trace).map_err(|e| e.to_string())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::closed_loop::lab::simulate;
    use crate::closed_loop::transfer::ROW_VALUES;
    use crate::control::registry::ControllerKind;
    use crate::plant::Preset;
    use crate::work::Work;

    fn short_spec(kind: ControllerKind) -> crate::closed_loop::definition::RunSpec {
        crate::closed_loop::definition::RunSpec::new(Preset::ManeeratDoc1, kind)
    }

    /// The DAQ sample log (12,000 rows at 1 kHz, three spindle phases, a force, a label, the
    /// logged override) and its guessed mapping, without the override column.
    fn sample_log() -> (Log, Mapping) {
        let bytes = include_bytes!("../../www/data/synthetic-maneerat-doc-2-daq.csv");
        let log = crate::log::load(bytes, None).unwrap();
        let mut mapping = Mapping::guess(&log);
        mapping.columns.retain(|(name, _)| name != "Override [%]");
        (log, mapping)
    }

    #[test]
    fn replays_made_in_a_worker_read_as_the_page_would_replay_them() {
        use crate::closed_loop::definition::SettingsOverrides;
        let (log, mapping) = sample_log();
        let log = std::sync::Arc::new(log);
        let controllers = vec![
            ControllerConfig::new(ControllerKind::Threshold),
            ControllerConfig::new(ControllerKind::Pi),
        ];
        let calibration = simulate(&short_spec(ControllerKind::Threshold))
            .unwrap()
            .calibration;
        let current = ReplaySettings {
            run: SettingsOverrides {
                target_current_a: Some(30.0),
                ..SettingsOverrides::default()
            },
            ..ReplaySettings::default()
        };
        let calibrated = ReplaySettings {
            calibration: Some(calibration),
            sample_period_s: Some(0.001),
            ..ReplaySettings::default()
        };
        for settings in [current, calibrated] {
            let on_page = ReplayRuns::new(
                log.clone(),
                mapping.clone(),
                settings.clone(),
                controllers.clone(),
            )
            .run_to_end()
            .unwrap();
            let (request, numbers) =
                ReplayRequest::new(&log, mapping.clone(), settings.clone(), controllers.clone());
            // Only the mapped columns travel (the override column does not), their numbers
            // beside the JSON, which stays small.
            assert_eq!(numbers.len(), mapping.columns.len());
            assert_eq!((log.columns.len(), numbers.len()), (9, 8));
            assert!(request.log.columns.iter().all(|c| c.name != "Override [%]"));
            let json = request.to_json().unwrap();
            assert!(json.len() < 20_000, "{} bytes of JSON", json.len());
            let received = ReplayRequest::from_json(&json).unwrap();
            // Debug: the calibration's unused speed range is NaN, which `==` would not match.
            assert_eq!(format!("{received:?}"), format!("{request:?}"));
            let numbers = numbers.into_iter().map(<[f64]>::to_vec).collect();
            let in_worker = received.into_work(numbers).unwrap().run_to_end().unwrap();
            // Back on the page, each rebuilt by the replay prepared there.
            let back: Vec<ReplayResult> = in_worker
                .iter()
                .zip(&controllers)
                .map(|(result, controller)| {
                    let prepared = ReplayRun::new(&log, &mapping, &settings, controller).unwrap();
                    ReplayParts::of(result)
                        .unwrap()
                        .into_result(prepared)
                        .unwrap()
                })
                .collect();
            // Debug prints every number at full precision, NaN as NaN.
            let page: Vec<&ReplayResult> = on_page.iter().map(|r| &**r).collect();
            assert_eq!(format!("{back:?}"), format!("{page:?}"));
            assert!(page.iter().all(|r| r.trace.rows.len() > 100));
            assert!(page.iter().any(|r| !r.trace.events.is_empty()));
        }
    }

    #[test]
    fn a_replay_with_missing_or_short_columns_or_a_ragged_trace_is_refused() {
        let (log, mapping) = sample_log();
        let controllers = vec![ControllerConfig::new(ControllerKind::Threshold)];
        let (request, numbers) =
            ReplayRequest::new(&log, mapping, ReplaySettings::default(), controllers);
        assert!(request
            .clone()
            .into_work(Vec::new())
            .err()
            .unwrap()
            .contains("columns of numbers"));
        let mut short: Vec<Vec<f64>> = numbers.into_iter().map(<[f64]>::to_vec).collect();
        short[0].pop();
        assert!(request
            .into_work(short)
            .err()
            .unwrap()
            .contains("for the log's 12000 rows"));
        let ragged = ReplayParts {
            header_json: "{\"events\": [], \"completed\": true}".into(),
            rows: vec![0.0; ROW_VALUES - 1],
            terms: Vec::new(),
        };
        let (log, mapping) = sample_log();
        let settings = ReplaySettings {
            run: crate::closed_loop::definition::SettingsOverrides {
                target_current_a: Some(30.0),
                ..Default::default()
            },
            ..ReplaySettings::default()
        };
        let prepared = ReplayRun::new(
            &std::sync::Arc::new(log),
            &mapping,
            &settings,
            &ControllerConfig::new(ControllerKind::Threshold),
        )
        .unwrap();
        assert!(ragged
            .into_result(prepared)
            .unwrap_err()
            .contains("whole number"));
    }

    #[test]
    fn a_bad_request_is_refused_with_a_message() {
        assert!(ReplayRequest::from_json("{\"log\": 3}")
            .unwrap_err()
            .contains("bad replay request"));
    }
}
