//! The Logs page's computations sent to a computation worker and back: what the page asks
//! ([`LogJobRequest`]: a replay, the signal chain on a column, or the calibration fit, each with
//! the log's needed columns as numbers beside its JSON) and what the worker answers
//! ([`ReplayParts`] for a replay; the chain's output and the fit [`Packed`]). The rest of the
//! job protocol — closed-loop runs, references, learning — is [`crate::closed_loop::transfer`],
//! a layer below the logs; a replay's trace travels as a run's does ([`flat_rows`],
//! [`rows_from_flat`]), bit for bit.

use std::borrow::Cow;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::analysis::{
    ChainOutput, ChainRequest, ChainWork, ColumnAnalysis, LabelStats, SpectrumPeak, Stats,
};
use super::calibration::{ForceSource, LogFit, LogFitWork};
use super::csv::Dialect;
use super::mapping::Mapping;
use super::replay::{ReplayResult, ReplayRun, ReplayRuns, ReplaySettings};
use super::{Column, ColumnKind, Log, ReadAccount};
use crate::closed_loop::recording_jobs::Packed;
use crate::closed_loop::trace::Trace;
use crate::closed_loop::transfer::{flat_rows, rows_from_flat};
use crate::control::registry::ControllerConfig;
use crate::estimation::estimator::Calibration;
use crate::estimation::teach_fit::FitPoint;
use crate::safety::SafetyEvent;

/// A job on a log for a computation worker, posted as `{ job, log_job, numbers }`
/// (`src/bin/cutlab-worker.rs`): the request as JSON in `log_job`, the log's numbers beside it in
/// `numbers`, one raw `f64` array per column of the request's [`LogShape`] (a `Float64Array` in
/// the browser, moved rather than copied). A log may be 100 MB of text, whose numbers as JSON
/// would be as big again and take a parse; only the columns the job reads travel.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub enum LogJobRequest {
    /// Controllers replayed on the log; answered by their traces ([`ReplayParts`]).
    Replay(ReplayRequest),
    /// The Logs page's signal chain on one column; answered packed ([`pack_chain_output`]).
    Chain(ChainJobRequest),
    /// The calibration fitted to the log; answered packed ([`pack_log_fit`]).
    Fit(FitJobRequest),
}

impl LogJobRequest {
    /// The request as JSON (the log's numbers apart).
    pub fn to_json(&self) -> Result<String, String> {
        serde_json::to_string(self).map_err(|e| format!("the log's job could not be sent: {e}"))
    }

    /// A request read from JSON.
    pub fn from_json(json: &str) -> Result<Self, String> {
        serde_json::from_str(json)
            .map_err(|e| format!("the worker received a bad request on a log: {e}"))
    }
}

/// The numbers sent beside a [`LogJobRequest`]: one list per column of its [`LogShape`], in
/// order. A number column's values are borrowed from the log (the page copies each once, into
/// the array it moves to the worker); a text column's label ids are made as numbers.
pub type LogNumbers<'a> = Vec<Cow<'a, [f64]>>;

/// What the Logs page asks a worker to replay: controllers on a log, each through the loop
/// every run uses ([`ReplayRuns`]), with the page's settings. Only the columns the mapping
/// names travel (and the time column): a replay reads no other.
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

/// What of a log a job reads, but its numbers ([`LogJobRequest`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LogShape {
    /// Rows of the log.
    pub rows: usize,
    /// Its sample period, s, if known.
    pub sample_period_s: Option<f64>,
    /// Which of `columns` is its time column, if one is.
    pub time_column: Option<usize>,
    /// The columns sent, each with its numbers beside the JSON.
    pub columns: Vec<ColumnShape>,
}

/// A column sent with a job on a log.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ColumnShape {
    /// Its name, as the mapping names it.
    pub name: String,
    /// Its unit, if the name had one.
    #[serde(default)]
    pub unit: Option<String>,
    /// What it holds.
    pub kind: ColumnKind,
    /// A text column's distinct labels, by id (its numbers are the rows' ids).
    #[serde(default)]
    pub label_names: Vec<String>,
}

/// The id a text column's empty cell has, as a number.
const NO_LABEL: f64 = u32::MAX as f64;

impl LogShape {
    /// The shape of `log`'s columns `sent` (indices, in order) and their numbers: a number
    /// column's values, a text column's label ids.
    fn of<'a>(log: &'a Log, sent: &[usize]) -> (Self, LogNumbers<'a>) {
        let shape = Self {
            rows: log.rows,
            sample_period_s: log.sample_period_s,
            time_column: log
                .time_column
                .and_then(|t| sent.iter().position(|&i| i == t)),
            columns: sent
                .iter()
                .map(|&i| ColumnShape {
                    name: log.columns[i].name.clone(),
                    unit: log.columns[i].unit.clone(),
                    kind: log.columns[i].kind,
                    label_names: log.columns[i].label_names.clone(),
                })
                .collect(),
        };
        let numbers = sent
            .iter()
            .map(|&i| {
                let column = &log.columns[i];
                if column.kind == ColumnKind::Text {
                    Cow::Owned(column.labels.iter().map(|&l| f64::from(l)).collect())
                } else {
                    Cow::Borrowed(column.values.as_slice())
                }
            })
            .collect();
        (shape, numbers)
    }

    /// The log rebuilt from its shape and `numbers` (one list per column, in order): the columns
    /// sent, with the same numbers and labels as on the page.
    pub fn into_log(self, numbers: Vec<Vec<f64>>) -> Result<Log, String> {
        if numbers.len() != self.columns.len() {
            return Err(format!(
                "the worker received {} columns of numbers for the log's {}",
                numbers.len(),
                self.columns.len()
            ));
        }
        let rows = self.rows;
        let columns = self
            .columns
            .into_iter()
            .zip(numbers)
            .map(|(c, numbers)| {
                if numbers.len() != rows {
                    return Err(format!(
                        "the worker received {} numbers of column {:?} for the log's {rows} rows",
                        numbers.len(),
                        c.name,
                    ));
                }
                let (values, labels) = if c.kind == ColumnKind::Text {
                    let count = c.label_names.len() as f64;
                    let labels = numbers
                        .iter()
                        .map(|&id| {
                            if id == NO_LABEL || (id >= 0.0 && id < count && id.fract() == 0.0) {
                                Ok(id as u32)
                            } else {
                                Err(format!("column {:?} has no label {id}", c.name))
                            }
                        })
                        .collect::<Result<Vec<u32>, String>>()?;
                    (Vec::new(), labels)
                } else {
                    (numbers, Vec::new())
                };
                Ok(Column {
                    name: c.name,
                    unit: c.unit,
                    kind: c.kind,
                    role: None,
                    role_reason: None,
                    values,
                    labels,
                    label_names: c.label_names,
                    numeric_share: 1.0,
                    missing: 0,
                    not_finite: 0,
                })
            })
            .collect::<Result<Vec<_>, String>>()?;
        Ok(Log {
            dialect: Dialect {
                delimiter: b',',
                decimal_comma: false,
            },
            header: true,
            columns,
            rows,
            time_column: self.time_column,
            sample_period_s: self.sample_period_s,
            problems: Vec::new(),
            problems_not_listed: 0,
            row_lines: Vec::new(),
            account: ReadAccount::default(),
        })
    }

    /// The shape of `log`'s time column and the columns `mapping` names, and their numbers: what
    /// a replay or a fit reads.
    fn mapped<'a>(log: &'a Log, mapping: &Mapping) -> (Self, LogNumbers<'a>) {
        let sent: Vec<usize> = (0..log.columns.len())
            .filter(|&i| {
                log.time_column == Some(i)
                    || mapping
                        .columns
                        .iter()
                        .any(|(name, _)| *name == log.columns[i].name)
            })
            .collect();
        Self::of(log, &sent)
    }
}

impl ReplayRequest {
    /// `controllers` replayed on `log` read through `mapping`, and the numbers to send beside
    /// the request ([`LogNumbers`]).
    pub fn job(
        log: &Log,
        mapping: Mapping,
        settings: ReplaySettings,
        controllers: Vec<ControllerConfig>,
    ) -> (LogJobRequest, LogNumbers<'_>) {
        let (shape, numbers) = LogShape::mapped(log, &mapping);
        let request = Self {
            log: shape,
            mapping,
            settings,
            controllers,
        };
        (LogJobRequest::Replay(request), numbers)
    }

    /// The replays, on the log rebuilt from its shape and `numbers` (one per column, in
    /// order): the same replays, and results, as the page's own [`ReplayRuns`] on the whole log.
    pub fn into_work(self, numbers: Vec<Vec<f64>>) -> Result<ReplayRuns, String> {
        let log = self.log.into_log(numbers)?;
        Ok(ReplayRuns::new(
            Arc::new(log),
            self.mapping,
            self.settings,
            self.controllers,
        ))
    }
}

/// What the Logs page asks a worker to analyse: the signal chain ([`ChainWork`]) on one column,
/// which travels with the label column the statistics are grouped by, and nothing else.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainJobRequest {
    /// The log, but its numbers.
    pub log: LogShape,
    /// The chain's column and settings.
    pub chain: ChainRequest,
}

impl ChainJobRequest {
    /// The chain of `chain` on `log`, and the numbers to send beside it; an unknown or text
    /// column is an error naming it (as the chain's own).
    pub fn job(log: &Log, chain: ChainRequest) -> Result<(LogJobRequest, LogNumbers<'_>), String> {
        chain.check(log)?;
        let sent: Vec<usize> = (0..log.columns.len())
            .filter(|&i| {
                let name = &log.columns[i].name;
                *name == chain.column || chain.by.as_ref() == Some(name)
            })
            .collect();
        let (shape, numbers) = LogShape::of(log, &sent);
        let request = Self { log: shape, chain };
        Ok((LogJobRequest::Chain(request), numbers))
    }

    /// The chain on the log rebuilt from its shape and `numbers`: the same output as the page's
    /// own [`ChainWork`] on the whole log.
    pub fn into_work(self, numbers: Vec<Vec<f64>>) -> Result<ChainWork, String> {
        ChainWork::new(Arc::new(self.log.into_log(numbers)?), self.chain)
    }
}

/// What the Logs page asks a worker to fit: the calibration ([`LogFitWork`]) of the log's
/// mapped columns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FitJobRequest {
    /// The log, but its numbers.
    pub log: LogShape,
    /// Which column is which channel.
    pub mapping: Mapping,
    /// The feedback path and sample period the fit reads with.
    pub settings: ReplaySettings,
    /// Where the force comes from.
    pub force: ForceSource,
}

impl FitJobRequest {
    /// The fit of `log` read through `mapping`, and the numbers to send beside it.
    pub fn job(
        log: &Log,
        mapping: Mapping,
        settings: ReplaySettings,
        force: ForceSource,
    ) -> (LogJobRequest, LogNumbers<'_>) {
        let (shape, numbers) = LogShape::mapped(log, &mapping);
        let request = Self {
            log: shape,
            mapping,
            settings,
            force,
        };
        (LogJobRequest::Fit(request), numbers)
    }

    /// The fit on the log rebuilt from its shape and `numbers`: the same fit as the page's own
    /// [`LogFitWork`] on the whole log.
    pub fn into_work(self, numbers: Vec<Vec<f64>>) -> Result<LogFitWork, String> {
        let log = Arc::new(self.log.into_log(numbers)?);
        LogFitWork::new(&log, &self.mapping, &self.settings, &self.force).map_err(|e| e.to_string())
    }
}

/// What of the chain's output travels as JSON; its long lists travel as numbers.
#[derive(Serialize, Deserialize)]
struct ChainHeader {
    lowpass_applied: bool,
    rms_window_samples: usize,
    column: String,
    unit: Option<String>,
    lowpass: Option<(f64, usize)>,
    notes: Vec<String>,
    whole: Stats,
    by_label: Vec<LabelStats>,
}

/// The chain's output as a worker sends it: the filtered column, its moving RMS, the spectrum's
/// bins and densities, and the peaks (frequency and density in turn) as numbers; the rest JSON.
pub fn pack_chain_output(output: ChainOutput) -> Result<Packed, String> {
    let ChainOutput {
        filtered,
        lowpass_applied,
        rms,
        rms_window_samples,
        spectrum: (freq_hz, psd),
        analysis,
    } = output;
    let peaks = analysis
        .peaks
        .iter()
        .flat_map(|p| [p.freq_hz, p.psd])
        .collect();
    let header = ChainHeader {
        lowpass_applied,
        rms_window_samples,
        column: analysis.column,
        unit: analysis.unit,
        lowpass: analysis.lowpass,
        notes: analysis.notes,
        whole: analysis.whole,
        by_label: analysis.by_label,
    };
    Ok(Packed {
        json: serde_json::to_string(&header)
            .map_err(|e| format!("the signal chain's output could not be sent: {e}"))?,
        arrays: vec![filtered, rms, freq_hz, psd, peaks],
    })
}

/// The chain's output a worker sent ([`pack_chain_output`]).
pub fn unpack_chain_output(packed: Packed) -> Result<ChainOutput, String> {
    let header: ChainHeader = serde_json::from_str(&packed.json)
        .map_err(|e| format!("the worker's signal chain could not be read: {e}"))?;
    let Ok([filtered, rms, freq_hz, psd, peaks]) = <[Vec<f64>; 5]>::try_from(packed.arrays) else {
        return Err("the worker's signal chain lacks some of its numbers".into());
    };
    if peaks.len() % 2 != 0 {
        return Err("the worker's signal chain sent half a peak".into());
    }
    Ok(ChainOutput {
        filtered,
        lowpass_applied: header.lowpass_applied,
        rms,
        rms_window_samples: header.rms_window_samples,
        spectrum: (freq_hz, psd),
        analysis: ColumnAnalysis {
            column: header.column,
            unit: header.unit,
            lowpass: header.lowpass,
            notes: header.notes,
            whole: header.whole,
            by_label: header.by_label,
            peaks: peaks
                .chunks_exact(2)
                .map(|p| SpectrumPeak {
                    freq_hz: p[0],
                    psd: p[1],
                })
                .collect(),
        },
    })
}

/// What of a fit travels as JSON; its points travel as numbers.
#[derive(Serialize, Deserialize)]
struct FitHeader {
    calibration: Calibration,
    notes: Vec<String>,
    force_source: String,
}

/// Numbers per fitted point ([`FitPoint`]'s fields in order).
const POINT_VALUES: usize = 5;

/// A fit as a worker sends it: its points as numbers, the rest (the calibration) JSON.
pub fn pack_log_fit(fit: LogFit) -> Result<Packed, String> {
    let points = fit
        .points
        .iter()
        .flat_map(|p| [p.time_s, p.current_a, p.force_n, p.speed_rpm, p.feed_mm_min])
        .collect();
    let header = FitHeader {
        calibration: fit.calibration,
        notes: fit.notes,
        force_source: fit.force_source,
    };
    Ok(Packed {
        json: serde_json::to_string(&header)
            .map_err(|e| format!("the calibration could not be sent: {e}"))?,
        arrays: vec![points],
    })
}

/// The fit a worker sent ([`pack_log_fit`]).
pub fn unpack_log_fit(packed: Packed) -> Result<LogFit, String> {
    let header: FitHeader = serde_json::from_str(&packed.json)
        .map_err(|e| format!("the worker's calibration could not be read: {e}"))?;
    let Ok([points]) = <[Vec<f64>; 1]>::try_from(packed.arrays) else {
        return Err("the worker's calibration lacks its points".into());
    };
    if points.len() % POINT_VALUES != 0 {
        return Err("the worker's calibration sent part of a point".into());
    }
    Ok(LogFit {
        calibration: header.calibration,
        points: points
            .chunks_exact(POINT_VALUES)
            .map(|p| FitPoint {
                time_s: p[0],
                current_a: p[1],
                force_n: p[2],
                speed_rpm: p[3],
                feed_mm_min: p[4],
            })
            .collect(),
        notes: header.notes,
        force_source: header.force_source,
    })
}

/// A finished replay as a worker sends it: its trace, the rest being derived again on the page
/// by the replay prepared there ([`ReplayRun::with_trace`]: the settings, notes, target and
/// summary, by the same code).
#[derive(Debug, Clone, PartialEq)]
pub struct ReplayParts {
    /// The envelope's events and the completion, as JSON.
    pub header_json: String,
    /// The trace's rows, [`crate::closed_loop::transfer::ROW_VALUES`] numbers each.
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
            let (job, numbers) =
                ReplayRequest::job(&log, mapping.clone(), settings.clone(), controllers.clone());
            let LogJobRequest::Replay(request) = job.clone() else {
                panic!("a replay's request")
            };
            // Only the mapped columns travel (the override column does not), their numbers
            // beside the JSON, which stays small.
            assert_eq!(numbers.len(), mapping.columns.len());
            assert_eq!((log.columns.len(), numbers.len()), (9, 8));
            assert!(request.log.columns.iter().all(|c| c.name != "Override [%]"));
            let json = job.to_json().unwrap();
            assert!(json.len() < 20_000, "{} bytes of JSON", json.len());
            let LogJobRequest::Replay(received) = LogJobRequest::from_json(&json).unwrap() else {
                panic!("a replay's request read back as another job")
            };
            // Debug: the calibration's unused speed range is NaN, which `==` would not match.
            assert_eq!(format!("{received:?}"), format!("{request:?}"));
            let numbers = numbers.into_iter().map(Cow::into_owned).collect();
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
        let (job, numbers) =
            ReplayRequest::job(&log, mapping, ReplaySettings::default(), controllers);
        let LogJobRequest::Replay(request) = job else {
            panic!("a replay's request")
        };
        assert!(request
            .clone()
            .into_work(Vec::new())
            .err()
            .unwrap()
            .contains("columns of numbers"));
        let mut short: Vec<Vec<f64>> = numbers.into_iter().map(Cow::into_owned).collect();
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
        assert!(LogJobRequest::from_json("{\"Replay\": {\"log\": 3}}")
            .unwrap_err()
            .contains("bad request on a log"));
    }

    /// The numbers as the worker receives them.
    fn received(numbers: LogNumbers<'_>) -> Vec<Vec<f64>> {
        numbers.into_iter().map(Cow::into_owned).collect()
    }

    #[test]
    fn the_chain_made_in_a_worker_equals_the_pages_bit_for_bit() {
        let (log, _) = sample_log();
        let log = Arc::new(log);
        let chains = [
            // Low-passed, grouped by the phase label.
            ChainRequest {
                column: "F [N]".into(),
                lowpass: Some((20.0, 4)),
                rms_window_s: 0.05,
                by: Some("Phase".into()),
                sample_period_s: None,
            },
            // Above the log's Nyquist frequency (skipped and said), no grouping, a given period.
            ChainRequest {
                column: "S_speed [rpm]".into(),
                lowpass: Some((900.0, 2)),
                rms_window_s: 0.01,
                by: None,
                sample_period_s: Some(0.001),
            },
        ];
        for chain in chains {
            let on_page = ChainWork::new(log.clone(), chain.clone())
                .unwrap()
                .run_to_end()
                .unwrap();
            let (job, numbers) = ChainJobRequest::job(&log, chain.clone()).unwrap();
            // Only the chain's column and its label column travel.
            let LogJobRequest::Chain(request) = &job else {
                panic!("a chain's request")
            };
            let sent: Vec<&str> = request
                .log
                .columns
                .iter()
                .map(|c| c.name.as_str())
                .collect();
            let expected: Vec<&str> = std::iter::once(chain.column.as_str())
                .chain(chain.by.as_deref())
                .collect();
            let mut sorted = sent.clone();
            sorted.sort_unstable();
            let mut expected_sorted = expected.clone();
            expected_sorted.sort_unstable();
            assert_eq!(sorted, expected_sorted);
            let json = job.to_json().unwrap();
            assert!(json.len() < 2_000, "{} bytes of JSON", json.len());
            let LogJobRequest::Chain(back) = LogJobRequest::from_json(&json).unwrap() else {
                panic!("a chain's request read back as another job")
            };
            assert_eq!(&back, request);
            let in_worker = back
                .into_work(received(numbers))
                .unwrap()
                .run_to_end()
                .unwrap();
            let arrived = unpack_chain_output(pack_chain_output(in_worker).unwrap()).unwrap();
            // Debug prints every number at full precision, NaN as NaN.
            assert_eq!(format!("{arrived:?}"), format!("{on_page:?}"));
            assert_eq!(on_page.filtered.len(), 12_000);
            assert!(!on_page.analysis.peaks.is_empty());
        }
        let grouped = ChainWork::new(
            log.clone(),
            ChainRequest {
                column: "F [N]".into(),
                lowpass: None,
                rms_window_s: 0.05,
                by: Some("Phase".into()),
                sample_period_s: None,
            },
        )
        .unwrap()
        .run_to_end()
        .unwrap();
        assert!(grouped.analysis.by_label.len() > 1);
    }

    #[test]
    fn the_fit_made_in_a_worker_equals_the_pages_bit_for_bit() {
        use crate::estimation::cut_settings::parse_cut;
        let (log, mapping) = sample_log();
        let log = Arc::new(log);
        let cut = parse_cut::<&str>(&[]).unwrap();
        let forces = [
            ForceSource::Measured,
            ForceSource::CutModel {
                geometry: cut.geometry,
                depth_mm: Some(2.0),
                width_mm: 5.0,
            },
        ];
        for force in forces {
            let settings = ReplaySettings::default();
            let on_page = LogFitWork::new(&log, &mapping, &settings, &force)
                .unwrap()
                .run_to_end()
                .unwrap();
            let (job, numbers) =
                FitJobRequest::job(&log, mapping.clone(), settings.clone(), force.clone());
            let json = job.to_json().unwrap();
            let LogJobRequest::Fit(back) = LogJobRequest::from_json(&json).unwrap() else {
                panic!("a fit's request read back as another job")
            };
            assert_eq!(LogJobRequest::Fit(back.clone()), job);
            let in_worker = back
                .into_work(received(numbers))
                .unwrap()
                .run_to_end()
                .unwrap();
            let arrived = unpack_log_fit(pack_log_fit(in_worker).unwrap()).unwrap();
            assert_eq!(format!("{arrived:?}"), format!("{on_page:?}"));
            assert!(on_page.points.len() > 10);
        }
    }

    #[test]
    fn a_text_column_travels_with_its_labels_and_a_bad_label_is_refused() {
        let (log, _) = sample_log();
        let phase = log.columns.iter().position(|c| c.name == "Phase").unwrap();
        let (shape, numbers) = LogShape::of(&log, &[phase]);
        let mut numbers = received(numbers);
        let rebuilt = shape.clone().into_log(numbers.clone()).unwrap();
        assert_eq!(rebuilt.columns[0].labels, log.columns[phase].labels);
        assert_eq!(
            rebuilt.columns[0].label_names,
            log.columns[phase].label_names
        );
        numbers[0][7] = 0.5;
        assert!(shape
            .into_log(numbers)
            .unwrap_err()
            .contains("column \"Phase\" has no label 0.5"));
        let packed = Packed {
            json: "{}".into(),
            arrays: Vec::new(),
        };
        assert!(unpack_chain_output(packed.clone()).is_err());
        assert!(unpack_log_fit(packed).is_err());
    }
}
