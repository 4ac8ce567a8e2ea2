//! The run's calibration: a teach cut over the link makes one; or load a saved one (a file from
//! `cutlab sim/host --save-calibration` or `cutlab calibrate`, or one the Logs page saved in this
//! browser); save the one in use.

use leptos::prelude::*;

use super::ui::{StationRef, Ui};
use crate::closed_loop::calibration_file::CalibrationFile;
use crate::hardware::session::TaughtCalibration;
use crate::web::components::download::download_text;
use crate::web::components::saved_calibrations::stored_calibrations;
use crate::web::hardware::station::Station;
use crate::web::js::read_chosen_file;

/// The calibration's fieldset.
#[component]
pub fn CalibrationFieldset(station: StationRef, ui: Ui) -> impl IntoView {
    // Calibrations: loaded from a file (cutlab sim/host --save-calibration, cutlab calibrate),
    // saved after a teach cut over the link.
    let calibration_error = RwSignal::new(None::<String>);
    let use_calibration = move |file: CalibrationFile, source: String| {
        station.try_update_value(|s| {
            s.set_calibration(TaughtCalibration {
                calibration: file.calibration,
                settings: None,
                source,
            })
        });
        calibration_error.set(None);
        ui.publish(station, true);
    };
    let load_calibration = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |name, text| {
            match text
                .and_then(|t| CalibrationFile::from_json(&t).map_err(|e| format!("{name}: {e}")))
            {
                Ok(file) => {
                    let source = if file.source.is_empty() {
                        format!("file {name}")
                    } else {
                        format!("file {name} ({})", file.source)
                    };
                    use_calibration(file, source);
                }
                Err(e) => calibration_error.set(Some(e)),
            }
        });
    };
    // The calibrations saved in this browser (the Logs page saves them), read again whenever
    // the list is opened so one saved in another tab shows up.
    let saved = RwSignal::new(stored_calibrations());
    let refresh_saved = move |_| saved.set(stored_calibrations());
    let use_saved = move |ev: leptos::ev::Event| {
        let chosen = event_target_value(&ev);
        let Ok(index) = chosen.parse::<usize>() else {
            return;
        };
        match saved.with_untracked(|(files, _)| files.get(index).cloned()) {
            Some(file) => {
                let source = format!("saved in this browser: {}", file.source);
                use_calibration(file, source);
            }
            None => calibration_error.set(Some(
                "that saved calibration is gone (deleted in another tab?)".into(),
            )),
        }
    };
    let save_calibration = move |_| {
        let Some(file) = station.try_with_value(Station::calibration_file).flatten() else {
            return;
        };
        calibration_error.set(
            download_text(
                "cutlab-calibration.json",
                "application/json",
                &file.to_json(),
            )
            .err(),
        );
    };

    view! {
        <fieldset>
            <legend>"Calibration"</legend>
            <p class="calibration">
                {move || ui.snapshot.with(|s| s.calibration.clone()).map_or_else(
                    || "None yet: make a teach cut over the link, or load a saved calibration.".to_string(),
                    |c| format!("In use: {c}"),
                )}
            </p>
            // The fit's own words, as the Logs page and `cutlab calibrate` show them.
            <ul class="hint" aria-label="Calibration warnings">
                {move || ui.snapshot.with(|s| s.calibration_warnings.clone()).into_iter().map(|w| {
                    view! { <li>{format!("Warning: {w}")}</li> }
                }).collect_view()}
            </ul>
            <div class="field">
                <label for="hw-calibration-file">"Load a calibration file (cutlab-calibration JSON)"</label>
                <input
                    id="hw-calibration-file"
                    type="file"
                    accept=".json,application/json"
                    on:change=load_calibration
                    aria-describedby="hw-calibration-error"
                />
            </div>
            <div class="field">
                <label for="hw-saved-calibration">"Or one saved in this browser (Logs page)"</label>
                <select
                    id="hw-saved-calibration"
                    on:focus=refresh_saved
                    on:change=use_saved
                    aria-describedby="hw-calibration-error hw-saved-problems"
                >
                    <option value="" selected=true>
                        {move || if saved.with(|(files, _)| files.is_empty()) {
                            "None saved yet"
                        } else {
                            "Choose a saved calibration…"
                        }}
                    </option>
                    {move || saved.with(|(files, _)| files.iter().enumerate().map(|(i, f)| {
                        view! { <option value=i.to_string()>{f.source.clone()}</option> }
                    }).collect_view())}
                </select>
                <p class="hint" id="hw-saved-problems">
                    {move || saved.with(|(_, problems)| problems.join("; "))}
                </p>
                <p class="field-error" id="hw-calibration-error" aria-live="polite">
                    {move || calibration_error.get().unwrap_or_default()}
                </p>
            </div>
            <div class="button-row">
                <button
                    type="button"
                    on:click=save_calibration
                    disabled=move || ui.snapshot.with(|s| s.calibration.is_none())
                >
                    "Save the calibration (JSON)"
                </button>
            </div>
        </fieldset>
    }
}
