//! The scenarios tuned, and the teach-in: a teach cut on each (made in a computation worker,
//! [`crate::web::components::pool`]), or a calibration saved after a teach cut on the machine
//! (the first chosen scenario is its program).

use leptos::prelude::*;

use crate::closed_loop::calibration_file::CalibrationFile;
use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::recording_jobs::TeachCutsRequest;
use crate::closed_loop::transfer::JobRequest;
use crate::control::registry::ControllerKind;
use crate::plant::Preset;
use crate::tuning::teach_in::teach_in_calibration;
use crate::tuning::TeachIn;
use crate::web::components::help::HelpToggle;
use crate::web::components::pool::Answer;
use crate::web::components::runner::Runner;
use crate::web::js::read_chosen_file;

/// The scenarios, each with whether it is chosen.
#[derive(Clone, Copy)]
pub struct Scenarios(StoredValue<Vec<(Preset, RwSignal<bool>)>>);

impl Scenarios {
    /// Every preset, paper 001's first depth of cut chosen.
    pub fn new() -> Self {
        Self(StoredValue::new(
            Preset::ALL
                .iter()
                .map(|&p| (p, RwSignal::new(p == Preset::ManeeratDoc1)))
                .collect(),
        ))
    }

    /// Chooses exactly the presets a shared link names (`kim-step-doc,maneerat-doc-1`); unknown
    /// names are passed over, and a list naming none changes nothing.
    pub fn restore(&self, names: &str) {
        let wanted: Vec<Preset> = names
            .split(',')
            .filter_map(|n| Preset::from_name(n.trim()))
            .collect();
        if wanted.is_empty() {
            return;
        }
        self.0.with_value(|c| {
            for (p, on) in c {
                on.set(wanted.contains(p));
            }
        });
    }

    /// The chosen presets (tracked).
    pub fn chosen(&self) -> Vec<Preset> {
        self.0.with_value(|c| {
            c.iter()
                .filter(|(_, on)| on.get())
                .map(|(p, _)| *p)
                .collect()
        })
    }
}

/// The scenarios' checkboxes.
#[component]
pub fn ScenariosPanel(scenarios: Scenarios) -> impl IntoView {
    view! {
        <fieldset>
            <legend>"Scenarios"</legend>
            {scenarios
                .0
                .get_value()
                .into_iter()
                .map(|(p, on)| {
                    let id = format!("tune-scenario-{}", p.name());
                    view! {
                        <div class="check">
                            <input
                                type="checkbox"
                                id=id.clone()
                                prop:checked=move || on.get()
                                on:change=move |ev| on.set(event_target_checked(&ev))
                            />
                            <label for=id>{format!("{} ({})", p.label(), p.name())}</label>
                            <HelpToggle subject=p.label().to_string() help=p.source() />
                        </div>
                    }
                })
                .collect_view()}
        </fieldset>
    }
}

/// The teach-in's fieldset: the scenarios' teach cuts, or a saved calibration's.
#[component]
pub fn TeachInPanel(
    scenarios: Scenarios,
    runner: Runner<Vec<TeachIn>>,
    /// The proposal from a saved calibration.
    from_file: RwSignal<Option<TeachIn>>,
    /// Where a missing scenario is said.
    form_error: WriteSignal<Option<String>>,
) -> impl IntoView {
    let teach_in = move |_| {
        let presets = scenarios.chosen();
        if presets.is_empty() {
            form_error.set(Some("Choose at least one scenario.".into()));
            return;
        }
        form_error.set(None);
        let specs = presets
            .iter()
            .map(|&p| RunSpec::new(p, ControllerKind::Threshold))
            .collect();
        // The teach cuts in a computation worker; the proposals are derived here from them.
        runner.start_in_worker(
            JobRequest::TeachCuts(TeachCutsRequest { specs }),
            |answer| match answer {
                Answer::TeachIns(taught) => Some(taught),
                _ => None,
            },
        );
    };
    let (file_error, set_file_error) = signal(None::<String>);
    let on_calibration_file = move |ev: leptos::ev::Event| {
        let program = scenarios
            .chosen()
            .first()
            .map(|&p| RunSpec::new(p, ControllerKind::Threshold));
        read_chosen_file(&ev, move |name, text| {
            let taught = text.and_then(|text| {
                CalibrationFile::from_json(&text)
                    .map_err(|e| format!("{name}: {e}"))
                    .and_then(|file| {
                        teach_in_calibration(&file, &name, program.as_ref())
                            .map_err(|e| e.to_string())
                    })
            });
            match taught {
                Ok(t) => {
                    set_file_error.set(None);
                    from_file.set(Some(t));
                }
                Err(e) => {
                    from_file.set(None);
                    set_file_error.set(Some(e));
                }
            }
        });
    };
    view! {
        <fieldset>
            <legend>"Teach-in"</legend>
            <p class="hint">
                "A teach cut on each chosen scenario, or a calibration saved after a "
                "teach cut on the machine (the first chosen scenario is its program)."
            </p>
            <button type="button" on:click=teach_in>"Teach-in"</button>
            <div class="field">
                <label for="tune-calibration-file">"Calibration file to teach in from"</label>
                <input
                    id="tune-calibration-file"
                    type="file"
                    accept=".json,application/json"
                    on:change=on_calibration_file
                />
                {move || file_error.get().map(|e| view! { <p class="field-error" role="alert">{e}</p> })}
            </div>
        </fieldset>
    }
}
