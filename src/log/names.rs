//! What a column's name and unit say: its words, its unit, the time unit of a time axis, and the
//! role it most likely plays (a person confirms or changes the guess on the Logs page or with
//! `cutlab log --map`). docs/logs.md lists the rules; the builder in [`super`] applies them to
//! each column it reads, and checks a guessed RMS current against its values
//! ([`clearly_negative`]).

use serde::Serialize;

use super::ColumnKind;

/// What a column measures, guessed from its name and unit (a person confirms or changes it).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Role {
    /// Time.
    Time,
    /// A phase current of a motor.
    PhaseCurrent,
    /// An RMS or "current feedback" value.
    RmsCurrent,
    /// Spindle speed.
    SpindleSpeed,
    /// Feed rate.
    Feed,
    /// A measured force.
    Force,
    /// Depth of cut.
    Depth,
    /// A label column.
    Label,
}

/// Seconds per unit of a time column, and the unit's symbol: from its unit (`Time [min]`), else
/// from a unit word ending its name (`time_ms`); `Ok(None)` when neither says, `Err(unit)` for a
/// unit that is no time unit.
///
/// ```
/// use cutlab::log::time_scale;
/// assert_eq!(time_scale(Some("min"), "Time [min]"), Ok(Some((60.0, "min"))));
/// assert_eq!(time_scale(None, "t_ns"), Ok(Some((1e-9, "ns"))));
/// assert_eq!(time_scale(None, "Time"), Ok(None));
/// assert_eq!(time_scale(Some("days"), "Zeit [days]"), Err("days".to_string()));
/// ```
pub fn time_scale(unit: Option<&str>, name: &str) -> Result<Option<(f64, &'static str)>, String> {
    const UNITS: [(&[&str], f64, &str); 6] = [
        (&["s", "sec", "secs", "second", "seconds", "sek"], 1.0, "s"),
        (&["ms", "msec", "millisecond", "milliseconds"], 1e-3, "ms"),
        (
            &["us", "µs", "μs", "usec", "microsecond", "microseconds"],
            1e-6,
            "µs",
        ),
        (&["ns", "nsec", "nanosecond", "nanoseconds"], 1e-9, "ns"),
        (&["min", "mins", "minute", "minutes"], 60.0, "min"),
        (&["h", "hr", "hrs", "hour", "hours", "std"], 3600.0, "h"),
    ];
    let find = |word: &str| {
        let word = word.trim().to_lowercase();
        UNITS
            .iter()
            .find(|(names, _, _)| names.contains(&word.as_str()))
            .map(|&(_, seconds, symbol)| (seconds, symbol))
    };
    if let Some(unit) = unit {
        return find(unit).map(Some).ok_or_else(|| unit.trim().to_string());
    }
    let words = name_words(name);
    Ok(match words.as_slice() {
        [_, .., last] => find(last),
        _ => None,
    })
}

/// The words of a column name before its unit, lower case: split at anything but letters and
/// digits and where a lower-case letter meets an upper-case one (`X_CurrentFeedback [A]` →
/// `x`, `current`, `feedback`).
///
/// ```
/// use cutlab::log::name_words;
/// assert_eq!(name_words("X_CurrentFeedback [A]"), ["x", "current", "feedback"]);
/// assert_eq!(name_words("S_I_U"), ["s", "i", "u"]);
/// assert_eq!(name_words("RMSCurrent"), ["rms", "current"]);
/// ```
pub fn name_words(name: &str) -> Vec<String> {
    let base = name.split(['[', '(', '{']).next().unwrap_or_default();
    let base = match base.rsplit_once(" / ") {
        Some((before, _)) if unit_of(name).is_some() => before,
        _ => base,
    };
    let chars: Vec<char> = base.chars().collect();
    let mut words = Vec::new();
    let mut word = String::new();
    for (i, &c) in chars.iter().enumerate() {
        if !c.is_alphanumeric() {
            if !word.is_empty() {
                words.push(std::mem::take(&mut word));
            }
            continue;
        }
        let previous = i.checked_sub(1).and_then(|p| chars.get(p)).copied();
        let next = chars.get(i + 1).copied();
        let boundary = c.is_uppercase()
            && previous.is_some_and(|p| {
                p.is_lowercase()
                    || p.is_ascii_digit()
                    || (p.is_uppercase() && next.is_some_and(char::is_lowercase))
            });
        if boundary && !word.is_empty() {
            words.push(std::mem::take(&mut word));
        }
        word.extend(c.to_lowercase());
    }
    if !word.is_empty() {
        words.push(word);
    }
    words
}

/// The unit in a column name: `Current [A]`, `speed(rpm)`, `F / N`.
///
/// ```
/// use cutlab::log::unit_of;
/// assert_eq!(unit_of("Current [A]").as_deref(), Some("A"));
/// assert_eq!(unit_of("speed(rpm)").as_deref(), Some("rpm"));
/// assert_eq!(unit_of("I_A"), None);
/// ```
pub fn unit_of(name: &str) -> Option<String> {
    let name = name.trim();
    for (open, close) in [('[', ']'), ('(', ')'), ('{', '}')] {
        if let (Some(a), Some(b)) = (name.rfind(open), name.rfind(close)) {
            if a < b && b == name.len() - 1 {
                let unit = name[a + 1..b].trim();
                if !unit.is_empty() {
                    return Some(unit.to_string());
                }
            }
        }
    }
    name.rsplit_once(" / ")
        .map(|(_, u)| u.trim().to_string())
        .filter(|u| !u.is_empty() && !u.contains(' '))
}

/// A role from a column's name and unit (docs/logs.md lists the rules).
///
/// ```
/// use cutlab::log::{guess_role, ColumnKind, Role};
/// assert_eq!(guess_role("Time [s]", Some("s"), ColumnKind::Number), Some(Role::Time));
/// assert_eq!(guess_role("S_speed(rpm)", Some("rpm"), ColumnKind::Number), Some(Role::SpindleSpeed));
/// assert_eq!(guess_role("X_I_U", None, ColumnKind::Number), Some(Role::PhaseCurrent));
/// assert_eq!(guess_role("Z_Current [A]", Some("A"), ColumnKind::Number), Some(Role::RmsCurrent));
/// assert_eq!(guess_role("X_CurrentFeedback", None, ColumnKind::Number), Some(Role::RmsCurrent));
/// assert_eq!(guess_role("Fx [N]", Some("N"), ColumnKind::Number), Some(Role::Force));
/// assert_eq!(guess_role("Phase", None, ColumnKind::Text), Some(Role::Label));
/// ```
pub fn guess_role(name: &str, unit: Option<&str>, kind: ColumnKind) -> Option<Role> {
    guess_role_from(name, unit, kind).map(|(role, _)| role)
}

/// Words that name a quantity, by the role they suggest. A name's word is one of them, or a
/// compound ending in one of five letters or more (`Spindelstrom`, `spindlespeed`); a word that
/// merely contains one names something else (`feedback` is no feed).
const QUANTITY_WORDS: [(Role, &[&str]); 5] = [
    (Role::SpindleSpeed, &["speed", "rpm", "drehzahl"]),
    (Role::Feed, &["feed", "feedrate", "vorschub"]),
    (
        Role::RmsCurrent,
        &[
            "current", "curr", "strom", "i", "irms", "load", "amps", "ampere",
        ],
    ),
    (Role::Force, &["force", "kraft", "fx", "fy", "fz"]),
    (Role::Depth, &["depth", "doc", "ap", "tiefe"]),
];
/// Words that name the time axis.
const TIME_WORDS: [&str; 6] = ["time", "t", "timestamp", "zeit", "zeitstempel", "sec"];
/// Names of one phase current (after an axis prefix).
const PHASE_NAMES: [&str; 12] = [
    "i_u", "i_v", "i_w", "iu", "iv", "iw", "i_a", "i_b", "i_c", "ia", "ib", "ic",
];

/// Whether a name's `word` is the quantity word `q` or a compound ending in it.
fn names_quantity(word: &str, q: &str) -> bool {
    word == q || (q.chars().count() >= 5 && word.ends_with(q))
}

/// [`guess_role`] and what the guess rests on, for people: the unit (`the unit "A"`), a word
/// of the name (`the word "current"`; the last word that names a quantity wins, so
/// `feed_current_rms_a` is a current), a phase name, or text. `None` when nothing fits.
///
/// ```
/// use cutlab::log::{guess_role_from, ColumnKind, Role};
/// assert_eq!(guess_role_from("X_CurrentFeedback", None, ColumnKind::Number),
///     Some((Role::RmsCurrent, "the word \"current\" in its name".to_string())));
/// assert_eq!(guess_role_from("X_Vorschub [mm/min]", Some("mm/min"), ColumnKind::Number),
///     Some((Role::Feed, "its unit \"mm/min\"".to_string())));
/// ```
pub fn guess_role_from(name: &str, unit: Option<&str>, kind: ColumnKind) -> Option<(Role, String)> {
    if kind == ColumnKind::Text {
        return Some((Role::Label, "its cells are text: labels".into()));
    }
    if kind == ColumnKind::Empty {
        return None;
    }
    let words = name_words(name);
    // Axis prefixes: X_, Y_, Z_, S_ (spindle).
    let (axis, stem) = match words.split_first() {
        Some((a, rest))
            if !rest.is_empty() && matches!(a.as_str(), "x" | "y" | "z" | "s" | "sp") =>
        {
            (Some(a.as_str()), rest)
        }
        _ => (None, words.as_slice()),
    };
    let feed_axis = axis.is_some_and(|a| matches!(a, "x" | "y" | "z"));
    let unit_lower = unit.map(|u| u.trim().to_lowercase());
    let unit_lower = unit_lower.as_deref();
    let time_unit = unit.is_some_and(|u| matches!(time_scale(Some(u), name), Ok(Some(_))));
    if let Some(first) = stem.first().filter(|w| TIME_WORDS.contains(&w.as_str())) {
        return Some((Role::Time, format!("the word {first:?} in its name")));
    }
    if let Some(w) = stem
        .iter()
        .find(|w| names_quantity(w, "time") || names_quantity(w, "zeit"))
        .filter(|_| time_unit)
    {
        return Some((
            Role::Time,
            format!("the word {w:?} in its name and its time unit"),
        ));
    }
    let joined = stem.join("_");
    if PHASE_NAMES.contains(&joined.as_str())
        || stem.first().is_some_and(|w| w.starts_with("phase"))
    {
        let written = name.split(['[', '(', '{']).next().unwrap_or(name).trim();
        return Some((
            Role::PhaseCurrent,
            format!("{written:?}, a phase current's name"),
        ));
    }
    let speed = |why: String| {
        Some(if feed_axis {
            (Role::Feed, format!("{why} on a feed axis (a feed)"))
        } else {
            (Role::SpindleSpeed, why)
        })
    };
    if let Some(u) = unit {
        let why = format!("its unit {:?}", u.trim());
        match unit_lower {
            Some("a") => return Some((Role::RmsCurrent, why)),
            Some("rpm" | "1/min" | "u/min" | "min-1" | "min^-1") => return speed(why),
            Some("mm/min" | "m/min" | "mm/s") => return Some((Role::Feed, why)),
            Some("n") => return Some((Role::Force, why)),
            _ => {}
        }
    }
    if axis.is_some_and(|a| a == "s" || a == "sp") && stem.first().is_some_and(|w| w == "n") {
        return Some((
            Role::SpindleSpeed,
            "the spindle's \"n\" (a speed) in its name".into(),
        ));
    }
    // The last word that names a quantity: "feed current" is a current, "spindle speed" a speed.
    let found = stem.iter().rev().find_map(|w| {
        QUANTITY_WORDS.iter().find_map(|(role, list)| {
            list.iter()
                .find(|q| names_quantity(w, q))
                .map(|q| (*role, (*q).to_string()))
        })
    });
    let (role, word) = found?;
    let why = format!("the word {word:?} in its name");
    match role {
        Role::SpindleSpeed => speed(why),
        role => Some((role, why)),
    }
}

/// The lowest value of a column that is clearly signed: at least a tenth of its finite values
/// below zero, and its lowest below −10 % of its largest magnitude (an RMS or a drive's current
/// magnitude with a small offset or noise around zero is not). `None` otherwise.
///
/// ```
/// use cutlab::log::clearly_negative;
/// let sine: Vec<f64> = (0..100).map(|k| 10.0 * (0.2 * k as f64).sin()).collect();
/// assert!(clearly_negative(&sine).unwrap() < -9.9);
/// assert_eq!(clearly_negative(&[5.0, 5.2, -0.01, 4.9, f64::NAN]), None);
/// ```
pub fn clearly_negative(values: &[f64]) -> Option<f64> {
    let finite = || values.iter().copied().filter(|v| v.is_finite());
    let count = finite().count();
    let negative = finite().filter(|v| *v < 0.0).count();
    let lowest = finite().fold(f64::INFINITY, f64::min);
    let largest = finite().fold(0.0_f64, |m, v| m.max(v.abs()));
    (count > 0 && negative * 10 >= count && lowest < -0.1 * largest).then_some(lowest)
}
