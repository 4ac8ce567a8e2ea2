//! A tuning's settings as one table: the Tune page's fields and `cutlab tune`'s `--param`,
//! `--sweep`, `--max-evals` and `--objective` are its rows, so both take the same bounds,
//! evaluations and weights and refuse the rest with the same words.
//!
//! | setting | key | option | range | default |
//! |---|---|---|---|---|
//! | a parameter's lowest and highest value tried | `from`, `to` | `--param KEY=FROM:TO` | what the controller's parameter takes, lowest first | |
//! | evaluations of the search at most | `evals` | `--max-evals` | 1–10 000 | 60 |
//! | values per parameter of a sweep | `steps` | `--sweep` | 1–400 | 5 |
//! | the objective's weights ([`Objective`]) | `cycle`, `error`, `above`, `activity` | `--objective TERM=W,…` | 0–10⁶ | 1, 1, 1, 0.1 |

use super::nelder_mead::NelderMead;
use super::{Objective, ParamRange, MAX_SWEEP_POINTS};
use crate::control::registry::ControllerConfig;
use crate::input::table::{self, Kind, Problem, Reader, Row, RowError, Shown, Table};

/// Every setting of a tuning.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum TuneSetting {
    /// A tuned parameter's lowest value tried.
    From,
    /// A tuned parameter's highest value tried.
    To,
    /// The search's evaluations at most.
    Evaluations,
    /// A sweep's values per parameter.
    Steps,
    /// Weight of the cycle time.
    CycleWeight,
    /// Weight of the force error.
    ErrorWeight,
    /// Weight of the time above the force limit.
    AboveWeight,
    /// Weight of the override activity.
    ActivityWeight,
}

/// A parameter's value: any number (the controller's own range checks it).
const PARAMETER: Kind = Kind::Number {
    min: f64::MIN,
    max: f64::MAX,
};

/// The search's evaluations at most.
const EVALUATIONS: Kind = Kind::Count {
    min: 1,
    max: 10_000,
};

/// A sweep's values per parameter: the grid is at most [`MAX_SWEEP_POINTS`] in all.
const STEPS: Kind = Kind::Count {
    min: 1,
    max: MAX_SWEEP_POINTS,
};

/// A weight of the objective.
const WEIGHT: Kind = Kind::Number { min: 0.0, max: 1e6 };

/// The weights in the objective's order, with the term each stands for.
pub const WEIGHTS: [TuneSetting; 4] = [
    TuneSetting::CycleWeight,
    TuneSetting::ErrorWeight,
    TuneSetting::AboveWeight,
    TuneSetting::ActivityWeight,
];

impl Table for TuneSetting {
    const ROWS: &'static [Self] = &[
        TuneSetting::From,
        TuneSetting::To,
        TuneSetting::Evaluations,
        TuneSetting::Steps,
        TuneSetting::CycleWeight,
        TuneSetting::ErrorWeight,
        TuneSetting::AboveWeight,
        TuneSetting::ActivityWeight,
    ];

    fn row(self) -> Row {
        use TuneSetting as T;
        let defaults = Objective::default();
        match self {
            T::From => Row::new("from", "", "From", "")
                .takes(PARAMETER, Shown::Blank)
                .help("the parameter's lowest value tried"),
            T::To => Row::new("to", "", "To", "")
                .takes(PARAMETER, Shown::Blank)
                .help("the parameter's highest value tried"),
            T::Evaluations => Row::new("evals", "max-evals", "Evaluations at most", "")
                .takes(
                    EVALUATIONS,
                    Shown::Count(NelderMead::default().max_evaluations),
                )
                .noun("evaluations")
                .help("largest number of evaluations of the search"),
            T::Steps => Row::new("steps", "sweep", "Values per parameter", "")
                .takes(STEPS, Shown::Count(5))
                .noun("values per parameter")
                .help("run a grid of N values per parameter instead of searching"),
            T::CycleWeight => Row::new("cycle", "", "Weight of the cycle time", "")
                .takes(WEIGHT, Shown::Number(defaults.cycle_time))
                .noun("weight")
                .help("weight of the cycle time, per nominal duration"),
            T::ErrorWeight => Row::new("error", "", "Weight of the force error", "")
                .takes(WEIGHT, Shown::Number(defaults.force_error))
                .noun("weight")
                .help("weight of the mean force error, per 10 % of the target"),
            T::AboveWeight => Row::new("above", "", "Weight of the time above the limit", "")
                .takes(WEIGHT, Shown::Number(defaults.time_above_limit))
                .noun("weight")
                .help("weight of the time above the force limit, per second"),
            T::ActivityWeight => Row::new("activity", "", "Weight of the override activity", "")
                .takes(WEIGHT, Shown::Number(defaults.override_activity))
                .noun("weight")
                .help("weight of the override's total variation, per 100 %"),
        }
    }
}

/// A parameter's range from the text of its bounds: each a number, the lowest first, and — with
/// `controller` — each a value the controller's parameter `key` takes (the message is its own).
///
/// ```
/// use cutlab::control::registry::{ControllerConfig, ControllerKind};
/// use cutlab::tuning::settings::{parse_range, TuneSetting};
/// let pi = ControllerConfig::new(ControllerKind::Pi);
/// let r = parse_range("kp", "0,1", "2", Some(&pi)).unwrap();
/// assert_eq!((r.lo, r.hi), (0.1, 2.0));
/// let e = parse_range("kp", "2", "0.1", Some(&pi)).unwrap_err();
/// assert_eq!(e[0].setting, TuneSetting::To);
/// assert_eq!(e[0].problem.to_string(), "the lower bound 2 is above the upper 0.1");
/// ```
pub fn parse_range(
    key: &str,
    from: &str,
    to: &str,
    controller: Option<&ControllerConfig>,
) -> Result<ParamRange, Vec<RowError<TuneSetting>>> {
    let bound = |s: TuneSetting, text: &str| -> Result<f64, RowError<TuneSetting>> {
        let value = table::number(s, text)?;
        if let Some(controller) = controller {
            controller
                .clone()
                .set(key, value)
                .map_err(|e| RowError::other(s, e.to_string()))?;
        }
        Ok(value)
    };
    match (bound(TuneSetting::From, from), bound(TuneSetting::To, to)) {
        (Ok(lo), Ok(hi)) if lo > hi => Err(vec![RowError::other(
            TuneSetting::To,
            format!(
                "the lower bound {} is above the upper {}",
                crate::input::readable(lo),
                crate::input::readable(hi)
            ),
        )]),
        (Ok(lo), Ok(hi)) => Ok(ParamRange {
            key: key.trim().to_string(),
            lo,
            hi,
        }),
        (from, to) => Err([from.err(), to.err()].into_iter().flatten().collect()),
    }
}

/// The objective from the text of its weights (those not given keep their defaults): each
/// zero or positive, and not all zero.
///
/// ```
/// use cutlab::tuning::settings::{parse_objective, TuneSetting};
/// let o = parse_objective(&[(TuneSetting::ErrorWeight, "2"), (TuneSetting::ActivityWeight, "0")]).unwrap();
/// assert_eq!((o.cycle_time, o.force_error, o.override_activity), (1.0, 2.0, 0.0));
/// let e = parse_objective(&[(TuneSetting::ErrorWeight, "-1")]).unwrap_err();
/// assert_eq!(e[0].problem.to_string(), "must be zero or positive, got -1");
/// ```
pub fn parse_objective<T: AsRef<str>>(
    texts: &[(TuneSetting, T)],
) -> Result<Objective, Vec<RowError<TuneSetting>>> {
    let mut reader = Reader::new(texts);
    let weights = WEIGHTS.map(|s| reader.number(s));
    let [Some(cycle_time), Some(force_error), Some(time_above_limit), Some(override_activity)] =
        weights
    else {
        return Err(reader.finish::<()>(None).err().unwrap_or_default());
    };
    let weights = [cycle_time, force_error, time_above_limit, override_activity];
    // Every run would cost 0 and the "best" would be whichever came first.
    if weights.iter().all(|w| *w == 0.0) {
        return Err(vec![RowError::new(
            TuneSetting::CycleWeight,
            Problem::Other(format!(
                "every weight is 0: nothing is minimised, so no run could be better than \
                 another; give one of {} a positive weight",
                WEIGHTS.map(|s| s.row().key).join(", ")
            )),
        )]);
    }
    Ok(Objective {
        cycle_time,
        force_error,
        time_above_limit,
        override_activity,
    })
}

/// The objective from the command line's `TERM=W,…` (terms by their keys: cycle, error, above,
/// activity): the message names the term.
///
/// ```
/// use cutlab::tuning::settings::objective_from_terms;
/// assert_eq!(objective_from_terms("error=2, activity=0").unwrap().force_error, 2.0);
/// assert!(objective_from_terms("speed=1").unwrap_err().contains("cycle, error, above, activity"));
/// assert_eq!(objective_from_terms("error=-1").unwrap_err(), "error: must be zero or positive, got -1");
/// assert!(objective_from_terms("cycle=0,error=0,above=0,activity=0").unwrap_err().starts_with("every weight is 0"));
/// ```
pub fn objective_from_terms(text: &str) -> Result<Objective, String> {
    let mut texts = Vec::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let (name, value) = part
            .split_once('=')
            .ok_or_else(|| format!("{part:?} is not of the form term=weight"))?;
        let setting = WEIGHTS
            .into_iter()
            .find(|s| s.row().key == name.trim())
            .ok_or_else(|| {
                format!(
                    "unknown objective term {:?}; terms: {}",
                    name.trim(),
                    WEIGHTS.map(|s| s.row().key).join(", ")
                )
            })?;
        texts.push((setting, value));
    }
    parse_objective(&texts).map_err(|errors| match errors.first() {
        Some(e) if matches!(e.problem, Problem::Other(_)) => e.problem.to_string(),
        Some(e) => format!("{}: {}", e.setting.row().key, e.problem),
        None => "the objective was refused".to_string(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::registry::ControllerKind;
    use crate::input::table::check_table;

    #[test]
    fn the_table_holds_and_its_defaults_are_the_cores() {
        assert_eq!(check_table::<TuneSetting>(), Ok(()));
        assert_eq!(parse_objective::<&str>(&[]), Ok(Objective::default()));
        assert_eq!(
            table::count(TuneSetting::Evaluations, ""),
            Ok(NelderMead::default().max_evaluations)
        );
    }

    #[test]
    fn a_bound_the_controller_refuses_is_refused_beside_its_field() {
        let pi = ControllerConfig::new(ControllerKind::Pi);
        let e = parse_range("kp", "-5", "abc", Some(&pi)).unwrap_err();
        let settings: Vec<TuneSetting> = e.iter().map(|e| e.setting).collect();
        assert_eq!(settings, [TuneSetting::From, TuneSetting::To]);
        assert_eq!(e[1].problem.to_string(), "\"abc\" is not a number");
        // Without the controller, only the numbers and their order.
        assert!(parse_range("kp", "-5", "1", None).is_ok());
    }
}
