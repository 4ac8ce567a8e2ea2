//! The run definition's settings as rows of the generic tables ([`crate::input::table`]), so one
//! form component renders them beside every other table: each row's names, unit, range and help
//! from [`RunSetting::spec`], the text a fresh form shows from the defaults
//! [`super::settings`] resolves with. A run's settings still parse through
//! [`RunSetting::parse`], whose ranges follow the preset's machine.

use super::definition::{RunSetting, SettingKind, DEFAULT_SEED};
use super::settings::{DEFAULT_FEED_LOWPASS_HZ, DEFAULT_LOWPASS_ORDER, DEFAULT_SPINDLE_LOWPASS_HZ};
use crate::estimation::estimator::Feedback;
use crate::input::table::{Kind, Row, Shown, Table};
use crate::plant::materials::Material;

/// What the blank choice of a setting that takes names means.
const PRESETS_OWN: &str = "The preset's";

/// The text a fresh form shows for `setting`: the default a run resolves to where the form
/// shows it, blank where blank keeps the preset's value.
///
/// ```
/// use cutlab::closed_loop::definition::RunSetting;
/// use cutlab::closed_loop::run_table::shown_default;
/// use cutlab::input::table::Shown;
/// assert_eq!(shown_default(RunSetting::SpindleCutoff), Shown::Number(260.0));
/// assert_eq!(shown_default(RunSetting::TargetForce), Shown::Blank);
/// ```
pub fn shown_default(setting: RunSetting) -> Shown {
    match setting {
        RunSetting::Seed => Shown::Seed(DEFAULT_SEED),
        RunSetting::FilterOrder => Shown::Count(DEFAULT_LOWPASS_ORDER),
        RunSetting::SpindleCutoff => Shown::Number(DEFAULT_SPINDLE_LOWPASS_HZ),
        RunSetting::FeedCutoff => Shown::Number(DEFAULT_FEED_LOWPASS_HZ),
        // A factor of 1 is the preset's own depth profile.
        RunSetting::DepthScale => Shown::Number(1.0),
        _ => Shown::Blank,
    }
}

impl Table for RunSetting {
    const ROWS: &'static [Self] = &RunSetting::ALL;

    fn row(self) -> Row {
        let spec = self.spec();
        let kind = match spec.kind {
            SettingKind::Number { min, max } => Kind::Number { min, max },
            SettingKind::Count { min, max } => Kind::Count { min, max },
            SettingKind::Seed => Kind::Seed,
            SettingKind::Feedback | SettingKind::Material => Kind::Choice,
        };
        // The words of the run definition's own messages ("order 0 is outside 1–20").
        let noun = match self {
            RunSetting::FilterOrder => "order",
            RunSetting::Feedback => "feedback path",
            RunSetting::Material => "material",
            _ => "",
        };
        Row {
            key: spec.query_key,
            cli_option: spec.cli_option,
            label: spec.label,
            unit: spec.unit,
            help: spec.help,
            kind,
            default: shown_default(self),
            noun,
        }
    }

    fn choices(self) -> Vec<(&'static str, &'static str)> {
        let named: Vec<(&'static str, &'static str)> = match self.spec().kind {
            SettingKind::Feedback => Feedback::ALL
                .iter()
                .map(|f| (f.name(), f.label()))
                .collect(),
            SettingKind::Material => Material::ALL
                .iter()
                .map(|m| (m.name(), m.label()))
                .collect(),
            _ => return Vec::new(),
        };
        std::iter::once(("", PRESETS_OWN)).chain(named).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::table::Value;
    use crate::plant::Preset;

    #[test]
    fn every_run_setting_is_a_row_whose_defaults_the_run_definition_accepts() {
        assert_eq!(crate::input::table::check_table::<RunSetting>(), Ok(()));
        for s in RunSetting::ALL {
            let row = s.row();
            assert_eq!(row.key, s.spec().query_key);
            let text = row.default_text();
            assert!(s.parse(&text, Preset::KimStepDoc).is_ok(), "{s:?} {text:?}");
        }
        // The form's defaults are the resolution's.
        assert_eq!(
            RunSetting::FilterOrder.row().default_value(),
            Some(Value::Count(DEFAULT_LOWPASS_ORDER))
        );
        assert_eq!(RunSetting::FeedCutoff.row().default_text(), "50");
    }
}
