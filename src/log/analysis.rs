//! The signal chain on a log's columns: statistics (whole and per label), an optional zero-phase
//! low-pass, and the spectrum's peaks.
//!
//! A slow log (10 Hz of RMS or "current feedback" values) cannot take a low-pass above its Nyquist
//! frequency: that stage is skipped, and the analysis says so, instead of failing.

use serde::{Deserialize, Serialize};

use super::{ColumnKind, Log};
use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};
use crate::signal::filtfilt::filtfilt;
use crate::signal::spectrum::{find_peaks, welch};

/// Statistics of some values; NaN and ±∞ (gaps, damaged cells) are left out and counted.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Stats {
    /// Values counted: the finite ones.
    pub count: usize,
    /// Values left out: gaps and numbers that are not finite.
    pub left_out: usize,
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
    /// The statistics of `values` (the rows of one column, or of one label's rows); the
    /// duration is their number × `period_s`.
    ///
    /// The sums are taken over the values divided by a power of two near the largest magnitude
    /// (an exact scaling), with compensation: no partial sum overflows, so a column of finite
    /// 1e308 has the mean 1e308, not ∞, and the RMS of 1e200 is 1e200.
    ///
    /// ```
    /// use cutlab::log::analysis::Stats;
    /// let s = Stats::of(&[1e308, 1e308, f64::NAN, f64::INFINITY], Some(0.5));
    /// assert_eq!((s.count, s.left_out, s.mean, s.rms), (2, 2, Some(1e308), Some(1e308)));
    /// assert_eq!(s.duration_s, Some(2.0));
    /// ```
    pub fn of(values: &[f64], period_s: Option<f64>) -> Self {
        let (mut n, mut lo, mut hi) = (0usize, f64::INFINITY, f64::NEG_INFINITY);
        for &v in values.iter().filter(|v| v.is_finite()) {
            n += 1;
            lo = lo.min(v);
            hi = hi.max(v);
        }
        let (mean, rms) = if n == 0 {
            (None, None)
        } else {
            // The largest power of two not above the largest magnitude: every scaled value lies
            // in (−2, 2), so n of them sum to at most 2n.
            let largest = lo.abs().max(hi.abs());
            let biased_exponent = (largest.to_bits() >> 52) & 0x7ff;
            let scale = if biased_exponent == 0 {
                1.0
            } else {
                f64::from_bits(biased_exponent << 52)
            };
            // Neumaier's compensated sum, and the squares (each below 4).
            let (mut sum, mut compensation, mut squares) = (0.0f64, 0.0f64, 0.0f64);
            for &v in values.iter().filter(|v| v.is_finite()) {
                let x = v / scale;
                let t = sum + x;
                compensation += if sum.abs() >= x.abs() {
                    (sum - t) + x
                } else {
                    (x - t) + sum
                };
                sum = t;
                squares += x * x;
            }
            let count = n as f64;
            (
                Some((sum + compensation) / count * scale),
                Some((squares / count).sqrt() * scale),
            )
        };
        Self {
            count: n,
            left_out: values.len() - n,
            mean,
            rms,
            min: (n > 0).then_some(lo),
            max: (n > 0).then_some(hi),
            duration_s: period_s.map(|p| values.len() as f64 * p),
        }
    }
}

/// The statistics of `values` per label of the text column `labels`, in the order of the
/// labels' first appearance: one pass over the rows, whatever the number of labels.
fn by_label(labels: &super::Column, values: &[f64], period_s: Option<f64>) -> Vec<LabelStats> {
    let mut per_label: Vec<Vec<f64>> = vec![Vec::new(); labels.label_names.len()];
    for (l, v) in labels.labels.iter().zip(values) {
        if let Some(list) = per_label.get_mut(*l as usize) {
            list.push(*v);
        }
    }
    labels
        .label_names
        .iter()
        .zip(&per_label)
        .map(|(label, rows)| LabelStats {
            label: label.clone(),
            stats: Stats::of(rows, period_s),
        })
        .collect()
}

/// One label's rows of a column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
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
                "the low-pass needs the sample period (a time column, or give it): skipped"
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
    let whole = Stats::of(&values, period);
    let by_label = match &request.by {
        None => Vec::new(),
        Some(by) => {
            let labels = log
                .columns
                .iter()
                .find(|c| &c.name == by)
                .ok_or_else(|| format!("no column {by:?} to group by; columns: {}", names()))?;
            if labels.kind != ColumnKind::Text {
                return Err(format!("column {by:?} holds no labels to group by"));
            }
            by_label(labels, &values, period)
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

/// What the signal chain of the Logs page does to one column.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ChainRequest {
    /// The column.
    pub column: String,
    /// A zero-phase Butterworth low-pass (cut-off Hz, order); skipped (and said) above the log's
    /// Nyquist frequency.
    pub lowpass: Option<(f64, usize)>,
    /// The moving RMS window, s (rounded to whole samples, at least one).
    pub rms_window_s: f64,
    /// A label column to group the statistics by.
    pub by: Option<String>,
    /// The sample period of a log without a time column (overrides the log's).
    pub sample_period_s: Option<f64>,
}

impl ChainRequest {
    /// The column of `log` the chain analyses; an unknown or text column is an error naming it.
    pub fn check<'a>(&self, log: &'a Log) -> Result<&'a super::Column, String> {
        let column = log
            .columns
            .iter()
            .find(|c| c.name == self.column)
            .ok_or_else(|| format!("no column {:?}", self.column))?;
        if !matches!(column.kind, ColumnKind::Number | ColumnKind::Time) {
            return Err(format!("column {:?} holds no numbers", self.column));
        }
        Ok(column)
    }
}

/// The chain's output for one column: the filtered values, their moving RMS, the spectrum and the
/// statistics ([`analyse`]'s).
#[derive(Debug, Clone, PartialEq)]
pub struct ChainOutput {
    /// The column after the low-pass (the raw values where it was skipped), gaps bridged.
    pub filtered: Vec<f64>,
    /// Whether a low-pass was applied.
    pub lowpass_applied: bool,
    /// The moving RMS of `filtered` over the window, at each row (the window ending there).
    pub rms: Vec<f64>,
    /// The window in samples.
    pub rms_window_samples: usize,
    /// Welch's power spectral density of `filtered` (bins, PSD); empty without a sample period.
    pub spectrum: (Vec<f64>, Vec<f64>),
    /// Statistics, per label, peaks and notes.
    pub analysis: ColumnAnalysis,
}

/// The chain on one column done a stage at a time (a million rows take a moment per stage in
/// a browser): low-pass, moving RMS, spectrum, statistics.
pub struct ChainWork {
    log: std::sync::Arc<Log>,
    request: ChainRequest,
    stage: usize,
    filtered: Vec<f64>,
    lowpass_applied: bool,
    notes: Vec<String>,
    rms: Vec<f64>,
    window: usize,
    spectrum: (Vec<f64>, Vec<f64>),
    spectrum_cursor: usize,
    spectrum_weight: f64,
    whole: Stats,
    output: Option<ChainOutput>,
}

/// Samples of the column one call of the spectrum stage takes (64 segments of 1024).
const SPECTRUM_BLOCK: usize = 1 << 16;

impl ChainWork {
    /// The chain of `request` on `log`; an unknown or text column is an error naming it.
    pub fn new(log: std::sync::Arc<Log>, request: ChainRequest) -> Result<Self, String> {
        let filtered = request.check(&log)?.values.clone();
        Ok(Self {
            log,
            request,
            stage: 0,
            filtered,
            lowpass_applied: false,
            notes: Vec::new(),
            rms: Vec::new(),
            window: 1,
            spectrum: (Vec::new(), Vec::new()),
            spectrum_cursor: 0,
            spectrum_weight: 0.0,
            whole: Stats::of(&[], None),
            output: None,
        })
    }

    fn step(&mut self) -> Result<(), String> {
        let period = self
            .request
            .sample_period_s
            .filter(|p| p.is_finite() && *p > 0.0)
            .or(self.log.sample_period_s);
        match self.stage {
            0 => {
                let bridged = bridge_gaps(&mut self.filtered);
                if bridged > 0 {
                    self.notes.push(format!(
                        "{bridged} gaps bridged with the last value to filter"
                    ));
                }
                if let Some((cutoff_hz, order)) = self.request.lowpass {
                    match period {
                        None => self.notes.push(
                            "the low-pass needs the sample period (a time column, or give it): \
                             skipped"
                                .into(),
                        ),
                        Some(p) if cutoff_hz >= 0.5 / p => self.notes.push(format!(
                            "the log samples at {} Hz: a low-pass at {} Hz is above its Nyquist \
                             frequency ({} Hz), so the stage is skipped",
                            crate::input::readable(1.0 / p),
                            crate::input::readable(cutoff_hz),
                            crate::input::readable(0.5 / p)
                        )),
                        Some(p) => {
                            let sos = butter(&ButterworthSpec {
                                kind: FilterKind::Lowpass,
                                order,
                                cutoff_hz: Cutoff::Single(cutoff_hz),
                                sample_rate_hz: 1.0 / p,
                            })
                            .map_err(|e| format!("low-pass: {e}"))?;
                            if self.filtered.len() > sos.filtfilt_padlen() {
                                self.filtered = filtfilt(&sos, &self.filtered)
                                    .map_err(|e| format!("low-pass: {e}"))?;
                                self.lowpass_applied = true;
                            } else {
                                self.notes.push(
                                    "too few rows for the zero-phase low-pass: skipped".into(),
                                );
                            }
                        }
                    }
                }
            }
            1 => {
                let samples = period.map_or(1.0, |p| (self.request.rms_window_s / p).round());
                self.window = if samples.is_finite() {
                    samples.clamp(1.0, 1e7) as usize
                } else {
                    1
                };
                // A running sum of squares; rows before a full window use what they have.
                let mut sum = 0.0;
                self.rms = Vec::with_capacity(self.filtered.len());
                for (i, v) in self.filtered.iter().enumerate() {
                    let v = if v.is_finite() { *v } else { 0.0 };
                    sum += v * v;
                    if i >= self.window {
                        let old = self.filtered[i - self.window];
                        if old.is_finite() {
                            sum -= old * old;
                        }
                    }
                    let n = (i + 1).min(self.window) as f64;
                    self.rms.push((sum.max(0.0) / n).sqrt());
                }
            }
            2 => {
                // Welch's average over the column, a block of segments per call: each block's
                // PSD weighted by its segments (segments across a block's edge are left out).
                let Some(p) = period else {
                    self.notes
                        .push("the spectrum needs the sample period: skipped".into());
                    self.stage += 1;
                    return Ok(());
                };
                let start = self.spectrum_cursor;
                let end = (start + SPECTRUM_BLOCK).min(self.filtered.len());
                // A short last block joins the one before it.
                let end = if self.filtered.len() - end < SEGMENT {
                    self.filtered.len()
                } else {
                    end
                };
                if end > start {
                    let psd = welch(&self.filtered[start..end], 1.0 / p, SEGMENT)
                        .map_err(|e| format!("spectrum: {e}"))?;
                    let weight = psd.segments as f64;
                    if self.spectrum.0.is_empty() || self.spectrum.0.len() != psd.freq_hz.len() {
                        if self.spectrum.0.is_empty() {
                            self.spectrum =
                                (psd.freq_hz, psd.psd.iter().map(|v| v * weight).collect());
                            self.spectrum_weight = weight;
                        }
                    } else {
                        for (sum, v) in self.spectrum.1.iter_mut().zip(&psd.psd) {
                            *sum += v * weight;
                        }
                        self.spectrum_weight += weight;
                    }
                }
                self.spectrum_cursor = end;
                if end < self.filtered.len() {
                    // More blocks: stay in this stage.
                    return Ok(());
                }
                if self.spectrum_weight > 0.0 {
                    let w = self.spectrum_weight;
                    for v in &mut self.spectrum.1 {
                        *v /= w;
                    }
                }
            }
            3 => {
                // The statistics of what the chain made (filtered); per label in the next stage.
                self.whole = Stats::of(&self.filtered, period);
            }
            _ => {
                let values = &self.filtered;
                let mut by_label = Vec::new();
                if let Some(by) = &self.request.by {
                    let labels = self
                        .log
                        .columns
                        .iter()
                        .find(|c| &c.name == by)
                        .ok_or_else(|| format!("no label column {by:?}"))?;
                    if labels.kind != ColumnKind::Text {
                        return Err(format!("column {by:?} holds no labels"));
                    }
                    by_label = self::by_label(labels, values, period);
                }
                let (freq, psd) = &self.spectrum;
                let lowest = freq.get(1).copied().unwrap_or(0.0);
                let peaks = find_peaks(freq, psd, lowest, PEAKS)
                    .into_iter()
                    .map(|peak| SpectrumPeak {
                        freq_hz: peak.interpolated_freq_hz,
                        psd: peak.value,
                    })
                    .collect();
                let column = self
                    .log
                    .columns
                    .iter()
                    .find(|c| c.name == self.request.column);
                let analysis = ColumnAnalysis {
                    column: self.request.column.clone(),
                    unit: column.and_then(|c| c.unit.clone()),
                    lowpass: self.request.lowpass.filter(|_| self.lowpass_applied),
                    notes: std::mem::take(&mut self.notes),
                    whole: self.whole,
                    by_label,
                    peaks,
                };
                self.output = Some(ChainOutput {
                    filtered: std::mem::take(&mut self.filtered),
                    lowpass_applied: self.lowpass_applied,
                    rms: std::mem::take(&mut self.rms),
                    rms_window_samples: self.window,
                    spectrum: std::mem::take(&mut self.spectrum),
                    analysis,
                });
            }
        }
        self.stage += 1;
        Ok(())
    }
}

impl crate::work::Work for ChainWork {
    type Output = ChainOutput;
    type Error = String;

    /// One stage per call, whatever the budget: each is one pass over the column.
    fn advance(&mut self, _budget: usize) -> Result<bool, String> {
        if self.output.is_none() {
            self.step()?;
        }
        Ok(self.output.is_some())
    }

    fn progress(&self) -> crate::work::Progress {
        let stage = [
            "Low-pass",
            "Moving RMS",
            "Spectrum",
            "Statistics",
            "Statistics per label",
        ];
        crate::work::Progress::new(
            format!(
                "Signal chain: {}",
                stage.get(self.stage).copied().unwrap_or("done")
            ),
            self.stage as f64 / 5.0,
        )
    }

    fn finish(&mut self) -> Result<ChainOutput, String> {
        self.output
            .take()
            .ok_or_else(|| "the signal chain has not finished".to_string())
    }
}

/// The time of each row of `log`, s: its time column, else the row times `sample_period_s` (the
/// given one, or the log's), else the row number.
pub fn row_times(log: &Log, sample_period_s: Option<f64>) -> Vec<f64> {
    if let Some(t) = log.time_column.and_then(|t| log.columns.get(t)) {
        return t.values.clone();
    }
    let period = sample_period_s.or(log.sample_period_s).unwrap_or(1.0);
    (0..log.rows).map(|i| i as f64 * period).collect()
}

/// Writes the channels a mapping names (numbers only, in mapping order) with the time, and the
/// chain's output on one column (`<column> filtered`, `<column> RMS`), as CSV: the Logs page's
/// "analysed channels" export.
///
/// ```
/// use cutlab::log::{load, mapping::Mapping, analysis::write_channels_csv};
/// let log = load(b"t [s],I [A]\n0,1\n0.1,2\n", None).unwrap();
/// let mut out = Vec::new();
/// write_channels_csv(&log, &Mapping::guess(&log), None, None, &mut out).unwrap();
/// assert_eq!(String::from_utf8(out).unwrap(), "time_s,I [A]\n0,1\n0.1,2\n");
/// ```
pub fn write_channels_csv(
    log: &Log,
    mapping: &super::mapping::Mapping,
    chain: Option<(&str, &ChainOutput)>,
    sample_period_s: Option<f64>,
    out: &mut dyn std::io::Write,
) -> std::io::Result<()> {
    use crate::closed_loop::trace::csv_field;
    let time = row_times(log, sample_period_s);
    let columns: Vec<&super::Column> = mapping
        .columns
        .iter()
        .filter_map(|(name, _)| log.columns.iter().find(|c| &c.name == name))
        .filter(|c| {
            matches!(c.kind, ColumnKind::Number)
                && Some(c.name.as_str())
                    != log
                        .time_column
                        .and_then(|t| log.columns.get(t))
                        .map(|t| t.name.as_str())
        })
        .collect();
    let mut header = vec!["time_s".to_string()];
    header.extend(columns.iter().map(|c| csv_field(&c.name)));
    if let Some((name, _)) = chain {
        header.push(csv_field(&format!("{name} filtered")));
        header.push(csv_field(&format!("{name} RMS")));
    }
    writeln!(out, "{}", header.join(","))?;
    for (row, t) in time.iter().enumerate() {
        let mut line = vec![t.to_string()];
        for c in &columns {
            line.push(c.values.get(row).copied().unwrap_or(f64::NAN).to_string());
        }
        if let Some((_, chain)) = chain {
            line.push(
                chain
                    .filtered
                    .get(row)
                    .copied()
                    .unwrap_or(f64::NAN)
                    .to_string(),
            );
            line.push(chain.rms.get(row).copied().unwrap_or(f64::NAN).to_string());
        }
        writeln!(out, "{}", line.join(","))?;
    }
    Ok(())
}
