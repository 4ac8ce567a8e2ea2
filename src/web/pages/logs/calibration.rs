//! The calibration from the active log: the current-to-force fit of the spindle or feed current
//! against the log's measured force or the force modelled from the cut (the cut table's rows, as
//! `cutlab calibrate --material`), saved in this browser or downloaded. The fit computes in a
//! worker ([`FitJobRequest`]: the log's mapped columns go with the request as numbers).

use std::sync::Arc;

use leptos::prelude::*;

use super::LogsState;
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::SettingsOverrides;
use crate::estimation::cut_settings::{parse_cut, CutSetting};
use crate::estimation::estimator::Feedback;
use crate::input::table::{form_errors, Table};
use crate::log::calibration::{ForceSource, LogFit, LogFitWork};
use crate::log::replay::ReplaySettings;
use crate::log::transfer::FitJobRequest;
use crate::web::components::download::download_text;
use crate::web::components::fields::SelectField;
use crate::web::components::pool::Answer;
use crate::web::components::runner::{RunProgress, Runner};
use crate::web::components::saved_calibrations::{save_calibration, stored_calibrations};
use crate::web::components::table_form::{SettingField, TableForm};

/// The calibrations saved in this browser, and what could not be read of them.
pub type Stored = (Vec<CalibrationFile>, Vec<String>);

/// The fit's feedback path, its run and the calibrations saved in this browser.
#[derive(Clone, Copy)]
pub struct FitForm {
    feedback_text: RwSignal<String>,
    /// Which current the fit (and a replay) measures the force from.
    pub feedback: Memo<Feedback>,
    runner: StoredValue<Runner<Arc<LogFit>>>,
    /// The last fit.
    pub done: ReadSignal<Option<Arc<LogFit>>>,
    /// The calibrations saved in this browser.
    pub stored: RwSignal<Stored>,
}

impl FitForm {
    /// No fit yet, the spindle's current.
    pub fn new() -> Self {
        let feedback_text = RwSignal::new("spindle".to_string());
        let feedback = Memo::new(move |_| {
            if feedback_text.get() == "feed" {
                Feedback::FeedCurrent
            } else {
                Feedback::SpindleCurrent
            }
        });
        let runner = Runner::<Arc<LogFit>>::new();
        let done = runner.finished();
        Self {
            feedback_text,
            feedback,
            runner: StoredValue::new(runner),
            done,
            stored: RwSignal::new(stored_calibrations()),
        }
    }
}

/// The calibration's fieldset.
#[component]
pub fn CalibrationPanel(shared: LogsState, fit: FitForm) -> impl IntoView {
    let force_from = RwSignal::new("measured".to_string());
    let cut = TableForm::<CutSetting>::new(&[]);
    let parsed_cut = Memo::new(move |_| parse_cut(&cut.texts()).map_err(|e| form_errors(&e)));
    let cut_errors = Signal::derive(move || parsed_cut.get().err().unwrap_or_default());
    let fit_error = RwSignal::new(None::<String>);
    let FitForm {
        feedback_text,
        feedback,
        runner,
        done,
        stored,
    } = fit;
    let runner = runner.get_value();
    let runner_for_click = runner.clone();
    let calibrate = move |_| {
        fit_error.set(None);
        let Some(l) = shared.active.get_untracked() else {
            fit_error.set(Some("open a log first".into()));
            return;
        };
        let force = if force_from.get_untracked() == "measured" {
            ForceSource::Measured
        } else {
            match parsed_cut.get_untracked() {
                Ok(cut) => ForceSource::CutModel {
                    geometry: cut.geometry,
                    depth_mm: cut.depth_mm,
                    width_mm: cut.width_mm,
                },
                Err(errors) => {
                    let labels: Vec<&str> = errors
                        .keys()
                        .filter_map(|key| CutSetting::from_key(key))
                        .map(|s| s.row().label)
                        .collect();
                    fit_error.set(Some(format!(
                        "Fix the cut's fields marked above: {}.",
                        labels.join(", ")
                    )));
                    return;
                }
            }
        };
        let settings = ReplaySettings {
            run: SettingsOverrides {
                feedback: Some(feedback.get_untracked()),
                ..SettingsOverrides::default()
            },
            sample_period_s: shared.period_s_untracked(),
            ..ReplaySettings::default()
        };
        // Checked here, so what the fit lacks shows at once, beside the button.
        if let Err(e) = LogFitWork::new(&l.log, &l.mapping, &settings, &force) {
            fit_error.set(Some(e.to_string()));
            return;
        }
        let (job, numbers) = FitJobRequest::job(&l.log, l.mapping.clone(), settings, force);
        runner_for_click.start_log_job(&job, &numbers, |answer| match answer {
            Answer::LogFit(fit) => Some(fit),
            _ => None,
        });
    };
    let saved_message = RwSignal::new(None::<Result<String, String>>);
    let fit_file = move || {
        let fit = done.get()?;
        let name = shared
            .active
            .with_untracked(|l| l.as_ref().map(|l| l.name.clone()))?;
        Some(CalibrationFile::new(
            fit.calibration.clone(),
            format!(
                "log {name}, {} feedback, force from {}",
                feedback.get_untracked().name(),
                fit.force_source
            ),
        ))
    };
    let save_in_browser = move |_| {
        let Some(file) = fit_file() else {
            saved_message.set(Some(Err("calibrate first".into())));
            return;
        };
        saved_message
            .set(Some(save_calibration(&file).map(|()| {
                format!("Saved in this browser as “{}”.", file.source)
            })));
        stored.set(stored_calibrations());
    };
    let download_calibration = move |_| {
        let Some(file) = fit_file() else {
            saved_message.set(Some(Err("calibrate first".into())));
            return;
        };
        if let Err(e) = download_text(
            "cutlab-calibration.json",
            "application/json",
            &file.to_json(),
        ) {
            saved_message.set(Some(Err(e)));
        }
    };
    let cut_field = move |setting: CutSetting| {
        view! { <SettingField form=cut setting=setting errors=cut_errors id_prefix="fit-" /> }
    };
    view! {
        <fieldset>
            <legend>"Calibration"</legend>
            <SelectField id="log-feedback" label="Force measured from the current of the"
                options=vec![("spindle", "Spindle"), ("feed", "Feed drive")] value=feedback_text />
            <SelectField id="fit-force" label="Force for the fit"
                options=vec![("measured", "The log's measured force"), ("model", "Modelled from the cut")] value=force_from />
            <div hidden=move || force_from.get() != "model">
                {CutSetting::ROWS.iter().map(|s| cut_field(*s)).collect_view()}
            </div>
            <div class="button-row">
                <button type="button" on:click=calibrate>"Calibrate"</button>
                <button type="button" on:click=save_in_browser disabled=move || done.with(Option::is_none)>"Save calibration in this browser"</button>
                <button type="button" on:click=download_calibration disabled=move || done.with(Option::is_none)>"Calibration (JSON)"</button>
            </div>
            {move || fit_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
            {move || saved_message.get().map(|m| match m {
                Ok(m) => view! { <p class="hint" role="status">{m}</p> }.into_any(),
                Err(e) => view! { <p class="run-error" role="alert">{e}</p> }.into_any(),
            })}
            <RunProgress runner=runner id="fit-progress" failure="The calibration failed" />
        </fieldset>
    }
}
