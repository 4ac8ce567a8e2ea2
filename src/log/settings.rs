//! The settings of a log's analysis as one table: the Logs page's signal-chain fields and the
//! options of `cutlab log inspect`, `analyse` and `replay` are its rows, parsed by
//! [`parse_analysis`], so both take the same sample period, cut-off and order and refuse the rest
//! with the same words. A replay's target and control period are the run definition's rows
//! ([`crate::closed_loop::definition::RunSetting`]).

use crate::closed_loop::settings::DEFAULT_LOWPASS_ORDER;
use crate::input::table::{Kind, Reader, Row, RowError, Shown, Table, Value};
use crate::plant::mechanics::MAX_TEETH;
use crate::signal::butterworth::MAX_ORDER;

/// Every setting of a log's analysis.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum LogSetting {
    /// The sample period of a log without a time column.
    SamplePeriod,
    /// The zero-phase low-pass's cut-off; blank: none.
    Lowpass,
    /// The low-pass's order.
    Order,
    /// The moving RMS's window.
    RmsWindow,
    /// The teeth of the cutter, for the spectrum's tooth-passing marker.
    MarkerTeeth,
}

/// A time step of a log: a microsecond (a fast DAQ) to an hour (a slow export).
const LOG_PERIOD_S: Kind = Kind::Number {
    min: 1e-6,
    max: 3600.0,
};

impl Table for LogSetting {
    const ROWS: &'static [Self] = &[
        LogSetting::SamplePeriod,
        LogSetting::Lowpass,
        LogSetting::Order,
        LogSetting::RmsWindow,
        LogSetting::MarkerTeeth,
    ];

    fn row(self) -> Row {
        use LogSetting as L;
        match self {
            L::SamplePeriod => Row::new(
                "period",
                "sample-period-s",
                "Sample period (the log has no time column)",
                "s",
            )
            .takes(LOG_PERIOD_S, Shown::Blank)
            .help("the sample period of a log without a time column"),
            L::Lowpass => Row::new(
                "lowpass",
                "lowpass-hz",
                "Zero-phase low-pass cut-off (empty: none)",
                "Hz",
            )
            .takes(
                Kind::Number {
                    min: 0.001,
                    max: 1e6,
                },
                Shown::Blank,
            )
            .help(
                "zero-phase Butterworth low-pass cut-off (skipped, and said, above the log's \
                 Nyquist frequency)",
            ),
            L::Order => Row::new("order", "order", "Low-pass order", "")
                .takes(
                    Kind::Count {
                        min: 1,
                        max: MAX_ORDER,
                    },
                    Shown::Count(DEFAULT_LOWPASS_ORDER),
                )
                .noun("order")
                .help("order of the low-pass"),
            L::RmsWindow => Row::new("rms_window", "", "RMS window", "s")
                .takes(LOG_PERIOD_S, Shown::Number(0.1))
                .help("the moving RMS's window (whole samples, at least one)"),
            L::MarkerTeeth => Row::new(
                "marker_teeth",
                "",
                "Cutter teeth (tooth-passing marker)",
                "",
            )
            .takes(
                Kind::Count {
                    min: 1,
                    max: MAX_TEETH as usize,
                },
                Shown::Count(2),
            )
            .noun("teeth")
            .help("teeth of the cutter, for the spectrum's tooth-passing marker"),
        }
    }
}

/// A log's analysis settings, parsed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AnalysisSettings {
    /// The sample period given for a log without a time column.
    pub sample_period_s: Option<f64>,
    /// The zero-phase low-pass: cut-off and order.
    pub lowpass: Option<(f64, usize)>,
    /// The moving RMS's window.
    pub rms_window_s: f64,
    /// The cutter's teeth for the tooth-passing marker.
    pub marker_teeth: usize,
}

/// Parses the typed text of a log's analysis (rows not given, or blank, take their defaults):
/// every setting that does not parse or is out of range is reported.
///
/// ```
/// use cutlab::log::settings::{parse_analysis, LogSetting};
/// let s = parse_analysis(&[(LogSetting::Lowpass, "100")]).unwrap();
/// assert_eq!((s.lowpass, s.rms_window_s, s.sample_period_s), (Some((100.0, 4)), 0.1, None));
/// let e = parse_analysis(&[(LogSetting::SamplePeriod, "-1")]).unwrap_err();
/// assert_eq!(e[0].for_cli(), "--sample-period-s: must be positive, got -1");
/// ```
pub fn parse_analysis<T: AsRef<str>>(
    texts: &[(LogSetting, T)],
) -> Result<AnalysisSettings, Vec<RowError<LogSetting>>> {
    let mut reader = Reader::new(texts);
    let sample_period_s = reader.number(LogSetting::SamplePeriod);
    let cutoff_hz = reader.number(LogSetting::Lowpass);
    let order = reader.count(LogSetting::Order);
    let rms_window_s = reader.number(LogSetting::RmsWindow);
    let marker_teeth = reader.count(LogSetting::MarkerTeeth);
    let settings = match (order, rms_window_s, marker_teeth) {
        (Some(order), Some(rms_window_s), Some(marker_teeth)) => Some(AnalysisSettings {
            sample_period_s,
            lowpass: cutoff_hz.map(|f| (f, order)),
            rms_window_s,
            marker_teeth,
        }),
        _ => None,
    };
    reader.finish(settings)
}

/// The sample period of `cutlab log`'s `--sample-period-s`, if given: through its row.
///
/// ```
/// use cutlab::log::settings::sample_period;
/// assert_eq!(sample_period(Some("0,001")), Ok(Some(0.001)));
/// assert!(sample_period(Some("0")).is_err());
/// ```
pub fn sample_period(text: Option<&str>) -> Result<Option<f64>, RowError<LogSetting>> {
    Ok(LogSetting::SamplePeriod
        .parse_given(text)?
        .and_then(Value::number))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::table::check_table;

    #[test]
    fn the_table_holds_and_reports_each_field() {
        assert_eq!(check_table::<LogSetting>(), Ok(()));
        let e = parse_analysis(&[
            (LogSetting::Lowpass, "0"),
            (LogSetting::Order, "50"),
            (LogSetting::RmsWindow, "x"),
            (LogSetting::MarkerTeeth, "0"),
        ])
        .unwrap_err();
        let settings: Vec<LogSetting> = e.iter().map(|e| e.setting).collect();
        assert_eq!(
            settings,
            [
                LogSetting::Lowpass,
                LogSetting::Order,
                LogSetting::RmsWindow,
                LogSetting::MarkerTeeth
            ]
        );
        assert_eq!(e[1].problem.to_string(), "order 50 is outside 1–20");
        assert_eq!(e[0].for_cli(), "--lowpass-hz: must be positive, got 0");
    }
}
