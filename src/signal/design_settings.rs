//! A Butterworth design's settings as one table: the Signal chain page's fields and `cutlab
//! filter`'s options are its rows, and [`parse_design`] turns their text into a design. Each
//! row's own range is checked by the design ([`butter`]), which also checks what the values mean
//! together (a cut-off below the Nyquist frequency of the rate, a band's upper edge above its
//! lower); its typed [`DesignError`] names the row it belongs to ([`setting_of`]), so a page puts
//! the message beside that field and the command line names that option.
//!
//! The papers' filters are presets of the same rows ([`PAPER_FILTERS`]).

use super::butterworth::{
    butter, ButterworthSpec, Cutoff, DesignError, Edge, FilterKind, MAX_ORDER,
};
use super::sos::Sos;
use crate::input::table::{
    read_text, unknown_choice, Kind, Problem, Reader, Row, RowError, Shown, Table, Value,
};

/// Every setting of a Butterworth design.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum FilterSetting {
    /// Low-pass, high-pass, band-pass or band-stop.
    Kind,
    /// The prototype's order.
    Order,
    /// The cut-off, or a band's lower edge.
    Cutoff,
    /// A band's upper edge.
    Upper,
    /// The sampling rate.
    SampleRate,
}

/// A frequency: above zero (the design checks it against the Nyquist frequency).
const FREQUENCY_HZ: Kind = Kind::Number {
    min: f64::MIN_POSITIVE,
    max: f64::MAX,
};

impl Table for FilterSetting {
    const ROWS: &'static [Self] = &[
        FilterSetting::Kind,
        FilterSetting::Order,
        FilterSetting::Cutoff,
        FilterSetting::Upper,
        FilterSetting::SampleRate,
    ];

    fn row(self) -> Row {
        use FilterSetting as F;
        match self {
            F::Kind => Row::new("kind", "kind", "Filter type", "")
                .takes(Kind::Choice, Shown::Choice("lowpass"))
                .noun("filter kind")
                .help("lowpass, highpass, bandpass or bandstop"),
            F::Order => Row::new("order", "order", "Order", "")
                .takes(
                    Kind::Count {
                        min: 1,
                        max: MAX_ORDER,
                    },
                    Shown::Count(10),
                )
                .noun("order")
                .help("filter order (band filters have 2N poles)"),
            F::Cutoff => Row::new("cutoff", "cutoff", "Cut-off", "Hz")
                .takes(FREQUENCY_HZ, Shown::Number(50.0))
                .help("cut-off frequency, below the Nyquist frequency; a band's lower edge"),
            // The second value of --cutoff (lower,upper): no option of its own.
            F::Upper => Row::new("upper", "", "Upper cut-off", "Hz")
                .takes(FREQUENCY_HZ, Shown::Number(200.0))
                .help("a band's upper edge, above its lower and below the Nyquist frequency"),
            F::SampleRate => Row::new("rate", "fs", "Sample rate", "Hz")
                .takes(FREQUENCY_HZ, Shown::Number(10_000.0))
                .help("sampling rate"),
        }
    }

    fn choices(self) -> Vec<(&'static str, &'static str)> {
        match self {
            FilterSetting::Kind => FilterKind::ALL
                .iter()
                .map(|k| (k.name(), k.label()))
                .collect(),
            _ => Vec::new(),
        }
    }

    /// A kind is also read by its label or scipy's short forms (`lp`, `band`, …).
    fn read(self, text: &str) -> Result<Option<Value>, RowError<Self>> {
        match self {
            FilterSetting::Kind if !text.trim().is_empty() => text
                .parse::<FilterKind>()
                .map(|kind| Some(Value::Choice(kind.name())))
                .map_err(|_| unknown_choice(self, text)),
            _ => read_text(self, text),
        }
    }
}

/// The setting a design error is about.
///
/// ```
/// use cutlab::signal::butterworth::DesignError;
/// use cutlab::signal::design_settings::{setting_of, FilterSetting};
/// assert_eq!(setting_of(&DesignError::Order { order: 0 }), FilterSetting::Order);
/// ```
pub fn setting_of(error: &DesignError) -> FilterSetting {
    match error {
        DesignError::Order { .. } => FilterSetting::Order,
        DesignError::SampleRate { .. } => FilterSetting::SampleRate,
        // The cut-offs given do not fit the kind: one for a band, two for a low/high-pass.
        DesignError::CutoffCount { .. } => FilterSetting::Cutoff,
        DesignError::CutoffNotFinite { edge, .. }
        | DesignError::CutoffNotPositive { edge, .. }
        | DesignError::CutoffAboveNyquist { edge, .. } => match edge {
            Edge::Upper => FilterSetting::Upper,
            Edge::Single | Edge::Lower => FilterSetting::Cutoff,
        },
        DesignError::BandEdges { .. } => FilterSetting::Upper,
        DesignError::Numerical { .. } => FilterSetting::Cutoff,
    }
}

/// Parses the typed text of a design (rows not given, or blank, take their defaults; the upper
/// edge is read only for a band): every field that does not read is reported, then the
/// design's own refusal with the setting it is about.
///
/// ```
/// use cutlab::signal::design_settings::{parse_design, FilterSetting};
/// let (spec, sos) = parse_design(&[(FilterSetting::Order, "2"), (FilterSetting::Cutoff, "260")]).unwrap();
/// assert_eq!((spec.order, sos.sections().len()), (2, 1));
/// let e = parse_design(&[(FilterSetting::Cutoff, "6000")]).unwrap_err();
/// assert_eq!(e[0].setting, FilterSetting::Cutoff);
/// assert!(e[0].problem.to_string().contains("Nyquist"));
/// ```
pub fn parse_design<T: AsRef<str>>(
    texts: &[(FilterSetting, T)],
) -> Result<(ButterworthSpec, Sos), Vec<RowError<FilterSetting>>> {
    let mut reader = Reader::new(texts);
    let kind = reader
        .read(FilterSetting::Kind)
        .and_then(Value::choice)
        .and_then(|name| name.parse::<FilterKind>().ok());
    let order = reader.read(FilterSetting::Order).and_then(Value::count);
    let cutoff = reader.read(FilterSetting::Cutoff).and_then(Value::number);
    let upper = match kind {
        Some(kind) if kind.is_band() => reader.read(FilterSetting::Upper).and_then(Value::number),
        _ => None,
    };
    let rate = reader
        .read(FilterSetting::SampleRate)
        .and_then(Value::number);
    let spec = match (kind, order, cutoff, rate) {
        (Some(kind), Some(order), Some(cutoff), Some(rate)) => Some(ButterworthSpec {
            kind,
            order,
            cutoff_hz: match upper {
                Some(upper) => Cutoff::Band(cutoff, upper),
                None => Cutoff::Single(cutoff),
            },
            sample_rate_hz: rate,
        }),
        _ => None,
    };
    let spec = reader.finish(spec)?;
    butter(&spec)
        .map(|sos| (spec, sos))
        .map_err(|e| vec![RowError::new(setting_of(&e), Problem::Other(e.to_string()))])
}

/// A filter a paper uses, one click (or one `#/signal?preset=…`) away: values of the design's
/// rows.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FilterPreset {
    /// The name in a URL: `wang-10th-5hz`.
    pub name: &'static str,
    /// For people.
    pub label: &'static str,
    /// The design's kind.
    pub kind: FilterKind,
    /// Its order.
    pub order: usize,
    /// Its cut-off, Hz.
    pub cutoff_hz: f64,
    /// The sampling rate it was designed for, Hz.
    pub sample_rate_hz: f64,
}

impl FilterPreset {
    /// The preset as the text of the rows it sets (the upper edge it leaves alone).
    pub fn texts(&self) -> [(FilterSetting, String); 4] {
        [
            (FilterSetting::Kind, self.kind.name().to_string()),
            (FilterSetting::Order, self.order.to_string()),
            (FilterSetting::Cutoff, self.cutoff_hz.to_string()),
            (FilterSetting::SampleRate, self.sample_rate_hz.to_string()),
        ]
    }
}

/// The papers' filters: paper 000's 10th-order 5 Hz low-pass, paper 003's analog 50 Hz (feed)
/// and 260 Hz (spindle) filters, at the lab's 10 kHz.
pub const PAPER_FILTERS: [FilterPreset; 3] = [
    FilterPreset {
        name: "wang-10th-5hz",
        label: "Wang et al.: 10th-order low-pass, 5 Hz",
        kind: FilterKind::Lowpass,
        order: 10,
        cutoff_hz: 5.0,
        sample_rate_hz: 10_000.0,
    },
    FilterPreset {
        name: "kim-feed-50hz",
        label: "Kim et al.: feed motor, 50 Hz",
        kind: FilterKind::Lowpass,
        order: 2,
        cutoff_hz: 50.0,
        sample_rate_hz: 10_000.0,
    },
    FilterPreset {
        name: "kim-spindle-260hz",
        label: "Kim et al.: spindle motor, 260 Hz",
        kind: FilterKind::Lowpass,
        order: 2,
        cutoff_hz: 260.0,
        sample_rate_hz: 10_000.0,
    },
];

/// The text of each setting a Signal chain link's query gives (`preset=wang-10th-5hz&order=4`):
/// the named paper filter's values, then each setting's own key over them. An unknown preset and
/// a kind that is not a filter kind are left out (a form's select could not show them); numbers
/// are kept as written, so [`parse_design`] says what is wrong with them. Settings the query
/// leaves out are absent: [`parse_design`] takes their defaults.
///
/// ```
/// use cutlab::signal::design_settings::{parse_design, query_texts};
/// let query = [("preset".to_string(), "kim-feed-50hz".to_string()),
///              ("order".to_string(), "4".to_string())];
/// let (spec, _) = parse_design(&query_texts(&query)).unwrap();
/// assert_eq!(spec.order, 4);
/// ```
pub fn query_texts(query: &[(String, String)]) -> Vec<(FilterSetting, String)> {
    let value = |key: &str| query.iter().find(|(k, _)| k == key).map(|(_, v)| v);
    let mut texts: Vec<(FilterSetting, String)> = value("preset")
        .and_then(|name| PAPER_FILTERS.iter().find(|p| p.name == name))
        .map(|p| p.texts().to_vec())
        .unwrap_or_default();
    for (key, text) in query {
        let text = match FilterSetting::from_key(key) {
            Some(FilterSetting::Kind) => match text.parse::<FilterKind>() {
                Ok(kind) => kind.name().to_string(),
                Err(_) => continue,
            },
            Some(_) => text.clone(),
            None => continue,
        };
        if let Some(setting) = FilterSetting::from_key(key) {
            texts.retain(|(s, _)| *s != setting);
            texts.push((setting, text));
        }
    }
    texts
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::table::check_table;

    #[test]
    fn the_table_holds_and_its_defaults_design_a_filter() {
        assert_eq!(check_table::<FilterSetting>(), Ok(()));
        let (spec, sos) = parse_design::<&str>(&[]).unwrap();
        assert_eq!((spec.kind, spec.order), (FilterKind::Lowpass, 10));
        assert_eq!(sos.sections().len(), 5);
        for preset in PAPER_FILTERS {
            let (spec, _) = parse_design(&preset.texts()).unwrap();
            assert_eq!(spec.order, preset.order, "{}", preset.name);
        }
    }

    #[test]
    fn each_refusal_names_the_setting_it_is_about() {
        let setting = |texts: &[(FilterSetting, &str)]| parse_design(texts).unwrap_err()[0].setting;
        assert_eq!(
            setting(&[(FilterSetting::Order, "0")]),
            FilterSetting::Order
        );
        assert_eq!(
            setting(&[(FilterSetting::Order, "x")]),
            FilterSetting::Order
        );
        assert_eq!(
            setting(&[(FilterSetting::SampleRate, "-1")]),
            FilterSetting::SampleRate
        );
        assert_eq!(
            setting(&[(FilterSetting::Cutoff, "0")]),
            FilterSetting::Cutoff
        );
        let band = |upper| {
            setting(&[
                (FilterSetting::Kind, "bandpass"),
                (FilterSetting::Cutoff, "100"),
                (FilterSetting::Upper, upper),
            ])
        };
        assert_eq!(band("50"), FilterSetting::Upper);
        assert_eq!(band("6000"), FilterSetting::Upper);
        assert_eq!(band("abc"), FilterSetting::Upper);
        // Not a band: the upper edge is not read.
        assert!(parse_design(&[(FilterSetting::Upper, "abc")]).is_ok());
        let e = parse_design(&[(FilterSetting::Order, "0")]).unwrap_err();
        assert_eq!(
            e[0].for_cli(),
            "--order: order must be a whole number from 1 to 20, got 0"
        );
        let e = parse_design(&[(FilterSetting::Kind, "comb")]).unwrap_err();
        assert!(e[0]
            .problem
            .to_string()
            .starts_with("unknown filter kind \"comb\""));
    }
}
