//! The signal chain on a log's columns: statistics (whole and per label), an optional zero-phase
//! low-pass, and the spectrum's peaks.
//!
//! A slow log (10 Hz of RMS or "current feedback" values) cannot take a low-pass above its Nyquist
//! frequency: that stage is skipped, and the analysis says so, instead of failing.

use serde::Serialize;

use super::{ColumnKind, Log};
use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use crate::signal::filtfilt::filtfilt;
use crate::signal::spectrum::{find_peaks, welch};

/// Statistics of some values (NaN gaps left out).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    /// Values counted.
    pub count: usize,
    /// Their mean.
    pub mean: Option<f64>,
    /// Their root mean square.
    pub rms: Option<f64>,
    /// The smallest.
    pub min: Option<f64>,
    /// The largest.
    pub max: Option<f64>,
    /// Rows × sample period, when the period is known.
    pub duration_s: Option<f64>,
}

impl Stats {
    fn of<'a>(values: impl Iterator<Item = &'a f64>, rows: usize, period_s: Option<f64>) -> Self {
        let (mut n, mut sum, mut squares) = (0usize, 0.0, 0.0);
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for &v in values.filter(|v| v.is_finite()) {
            n += 1;
            sum += v;
            squares += v * v;
            lo = lo.min(v);
            hi = hi.max(v);
        }
        let some = |v: f64| (n > 0).then_some(v);
        Self {
            count: n,
            mean: some(sum / n.max(1) as f64),
            rms: some((squares / n.max(1) as f64).sqrt()),
            min: some(lo),
            max: some(hi),
            duration_s: period_s.map(|p| rows as f64 * p),
        }
    }
}

/// One label's rows of a column.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct LabelStats {
    /// The label (a machining phase).
    pub label: String,
    /// Its statistics.
    pub stats: Stats,
}

/// A spectral peak.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SpectrumPeak {
    /// Its frequency, refined between bins, Hz.
    pub freq_hz: f64,
    /// The power spectral density there.
    pub psd: f64,
}

/// The analysis of one column.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ColumnAnalysis {
    /// The column.
    pub column: String,
    /// Its unit, if the name had one.
    pub unit: Option<String>,
    /// The low-pass applied (cut-off Hz, order), if one was.
    pub lowpass: Option<(f64, usize)>,
    /// Why a requested stage was skipped (the low-pass above the log's Nyquist frequency), or
    /// how many gaps were bridged to filter.
    pub notes: Vec<String>,
    /// Statistics of the whole column (after the low-pass, if any).
    pub whole: Stats,
    /// Statistics per label of the `by` column, in order of first appearance.
    pub by_label: Vec<LabelStats>,
    /// The strongest spectral peaks (Welch), when asked.
    pub peaks: Vec<SpectrumPeak>,
}

/// What to do to each column.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct AnalysisRequest {
    /// A label column to group the statistics by.
    pub by: Option<String>,
    /// A zero-phase Butterworth low-pass (cut-off Hz, order).
    pub lowpass: Option<(f64, usize)>,
    /// Whether to find the spectrum's peaks.
    pub spectrum: bool,
}

/// How many spectral peaks are listed.
const PEAKS: usize = 5;
/// The Welch segment length (shorter logs use their length).
const SEGMENT: usize = 1024;

/// Analyses column `name` of `log`. An unknown column, a text column, or a `by` column that is
/// not text is an error naming it.
pub fn analyse(log: &Log, name: &str, request: &AnalysisRequest) -> Result<ColumnAnalysis, String> {
    let names = || {
        log.columns
            .iter()
            .map(|c| c.name.as_str())
            .collect::<Vec<_>>()
            .join(", ")
    };
    let column = log
        .columns
        .iter()
        .find(|c| c.name == name)
        .ok_or_else(|| format!("no column {name:?}; columns: {}", names()))?;
    if !matches!(column.kind, ColumnKind::Number | ColumnKind::Time) {
        return Err(format!("column {name:?} holds no numbers"));
    }
    let period = log.sample_period_s;
    let mut notes = Vec::new();
    let mut values = column.values.clone();
    let mut lowpass = None;
    if let Some((cutoff_hz, order)) = request.lowpass {
        match period {
            None => notes.push(
                "the low-pass needs the sample period (a time column or --sample-period-s): \
                 skipped"
                    .to_string(),
            ),
            Some(p) if cutoff_hz >= 0.5 / p => notes.push(format!(
                "the log samples at {} Hz: a low-pass at {} Hz is above its Nyquist frequency \
                 ({} Hz), so the stage is skipped",
                crate::input::readable(1.0 / p),
                crate::input::readable(cutoff_hz),
                crate::input::readable(0.5 / p)
            )),
            Some(p) => {
                let bridged = bridge_gaps(&mut values);
                if bridged > 0 {
                    notes.push(format!(
                        "{bridged} gaps bridged with the last value to filter"
                    ));
                }
                let sos = butter(&ButterworthSpec {
                    kind: FilterKind::Lowpass,
                    order,
                    cutoff_hz: Cutoff::Single(cutoff_hz),
                    sample_rate_hz: 1.0 / p,
                })
                .map_err(|e| format!("low-pass: {e}"))?;
                values = filtfilt(&sos, &values).map_err(|e| format!("low-pass: {e}"))?;
                lowpass = Some((cutoff_hz, order));
            }
        }
    }
    let whole = Stats::of(values.iter(), log.rows, period);
    let by_label = match &request.by {
        None => Vec::new(),
        Some(by) => {
            let labels = log
                .columns
                .iter()
                .find(|c| &c.name == by)
                .ok_or_else(|| format!("--by: no column {by:?}; columns: {}", names()))?;
            if labels.kind != ColumnKind::Text {
                return Err(format!("--by: column {by:?} holds no labels"));
            }
            labels
                .label_names
                .iter()
                .enumerate()
                .map(|(id, label)| {
                    let rows: Vec<f64> = labels
                        .labels
                        .iter()
                        .zip(&values)
                        .filter(|(l, _)| **l == id as u32)
                        .map(|(_, v)| *v)
                        .collect();
                    LabelStats {
                        label: label.clone(),
                        stats: Stats::of(rows.iter(), rows.len(), period),
                    }
                })
                .collect()
        }
    };
    let mut peaks = Vec::new();
    if request.spectrum {
        match period {
            None => notes.push("the spectrum needs the sample period: skipped".to_string()),
            Some(p) => {
                let mut filled = values.clone();
                bridge_gaps(&mut filled);
                let psd = welch(&filled, 1.0 / p, SEGMENT).map_err(|e| format!("spectrum: {e}"))?;
                // Above the first bin: the mean is not a peak.
                let lowest = psd.freq_hz.get(1).copied().unwrap_or(0.0);
                peaks = find_peaks(&psd.freq_hz, &psd.psd, lowest, PEAKS)
                    .into_iter()
                    .map(|peak| SpectrumPeak {
                        freq_hz: peak.interpolated_freq_hz,
                        psd: peak.value,
                    })
                    .collect();
            }
        }
    }
    Ok(ColumnAnalysis {
        column: column.name.clone(),
        unit: column.unit.clone(),
        lowpass,
        notes,
        whole,
        by_label,
        peaks,
    })
}

/// Replaces each non-finite value by the last finite one (the first finite one at the start);
/// returns how many were replaced. All gaps stay gaps in a column with no number at all.
fn bridge_gaps(values: &mut [f64]) -> usize {
    let Some(first) = values.iter().copied().find(|v| v.is_finite()) else {
        return 0;
    };
    let mut last = first;
    let mut bridged = 0;
    for v in values.iter_mut() {
        if v.is_finite() {
            last = *v;
        } else {
            *v = last;
            bridged += 1;
        }
    }
    bridged
}
