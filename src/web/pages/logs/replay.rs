//! Controllers replayed on the active log: the override each would have commanded and what the
//! envelope would have done, through the loop every run uses, computed in the workers
//! ([`super::in_workers`]); the target is the run definition's row (as
//! `cutlab log replay --target-n/--target-a`), checked as typed.

use std::sync::Arc;

use leptos::prelude::*;

use super::calibration::FitForm;
use super::in_workers::{start_replays, ReplayRunner};
use super::LogsState;
use crate::closed_loop::definition::{max_override_pct_of, RunSetting, SettingsOverrides};
use crate::closed_loop::error::LoopError;
use crate::control::registry::{ControllerConfig, ControllerKind};
use crate::estimation::estimator::Calibration;
use crate::log::machine::ReplayError;
use crate::log::replay::{ReplayResult, ReplayRun, ReplaySettings};
use crate::web::components::fields::{ChoiceField, NumberField, SelectField};
use crate::web::components::runner::RunProgress;

/// The replays' run.
#[derive(Clone, Copy)]
pub struct Replay {
    runner: StoredValue<ReplayRunner>,
    /// The last replays.
    pub done: ReadSignal<Option<Vec<Arc<ReplayResult>>>>,
}

impl Replay {
    /// No replay yet.
    pub fn new() -> Self {
        let runner = ReplayRunner::new();
        let done = runner.finished();
        Self {
            runner: StoredValue::new(runner),
            done,
        }
    }
}

/// The target's row: a current or a force.
fn target_setting(kind: &str) -> RunSetting {
    if kind == "force" {
        RunSetting::TargetForce
    } else {
        RunSetting::TargetCurrent
    }
}

/// The replay's fieldset.
#[component]
pub fn ReplayPanel(shared: LogsState, fit: FitForm, replay: Replay) -> impl IntoView {
    let chosen: [RwSignal<bool>; ControllerKind::ALL.len()] = std::array::from_fn(|i| {
        RwSignal::new(matches!(
            ControllerKind::ALL[i],
            ControllerKind::Threshold | ControllerKind::Pi
        ))
    });
    let target_kind = RwSignal::new("current".to_string());
    let target_text = RwSignal::new(String::new());
    // A log's machine is FANUC's dial unless told.
    let max_override_pct = max_override_pct_of(&ReplaySettings::default().override_mode);
    let target = Memo::new(move |_| {
        target_setting(&target_kind.get()).parse_on(&target_text.get(), max_override_pct)
    });
    // What the replay itself refused about the target, until the target changes.
    let refused_target = RwSignal::new(None::<String>);
    Effect::new(move |_| {
        target.track();
        refused_target.set(None);
    });
    let target_error = Signal::derive(move || {
        target
            .get()
            .err()
            .map(|e| e.problem.to_string())
            .or_else(|| refused_target.get())
    });
    let use_calibration = RwSignal::new("none".to_string());
    let (fit_done, stored) = (fit.done, fit.stored);
    let calibration_options = Signal::derive(move || {
        let mut options = vec![("none".to_string(), "None: regulate the current".to_string())];
        if fit_done.with(Option::is_some) {
            options.push(("fit".to_string(), "The fit made above".to_string()));
        }
        for (i, f) in stored.with(|s| s.0.clone()).iter().enumerate() {
            options.push((format!("stored-{i}"), format!("Saved: {}", f.source)));
        }
        options
    });
    let chosen_calibration = move || -> Option<Calibration> {
        let choice = use_calibration.get_untracked();
        if choice == "fit" {
            return fit_done.get_untracked().map(|f| f.calibration.clone());
        }
        let index: usize = choice.strip_prefix("stored-")?.parse().ok()?;
        stored.with_untracked(|s| s.0.get(index).map(|f| f.calibration.clone()))
    };
    let replay_error = RwSignal::new(None::<String>);
    let runner = replay.runner.get_value();
    let start = move |_| {
        replay_error.set(None);
        let Some(l) = shared.active.get_untracked() else {
            replay_error.set(Some("open a log first".into()));
            return;
        };
        let controllers: Vec<ControllerConfig> = ControllerKind::ALL
            .iter()
            .zip(chosen)
            .filter(|(_, on)| on.get_untracked())
            .map(|(k, _)| ControllerConfig::new(*k))
            .collect();
        if controllers.is_empty() {
            replay_error.set(Some("choose at least one controller".into()));
            return;
        }
        let Ok(value) = target.get_untracked() else {
            return;
        };
        let mut run = SettingsOverrides {
            feedback: Some(fit.feedback.get_untracked()),
            ..SettingsOverrides::default()
        };
        target_setting(&target_kind.get_untracked()).apply_to_settings(&mut run, value);
        let settings = ReplaySettings {
            run,
            sample_period_s: shared.period_s_untracked(),
            calibration: chosen_calibration(),
            ..ReplaySettings::default()
        };
        // Check what the first replay needs before starting, so the message lands beside the
        // control it is about.
        if let Err(e) = ReplayRun::new(&l.log, &l.mapping, &settings, &controllers[0]) {
            match e {
                ReplayError::Loop(LoopError::Setting(e))
                    if matches!(
                        e.setting,
                        RunSetting::TargetForce | RunSetting::TargetCurrent
                    ) =>
                {
                    refused_target.set(Some(e.problem.to_string()))
                }
                e => replay_error.set(Some(e.to_string())),
            }
            return;
        }
        start_replays(
            &runner,
            l.log.clone(),
            l.mapping.clone(),
            settings,
            controllers,
        );
    };
    view! {
        <fieldset>
            <legend>"Replay controllers"</legend>
            {ControllerKind::ALL
                .iter()
                .zip(chosen)
                .map(|(kind, on)| {
                    let id = format!("replay-{}", kind.name());
                    view! {
                        <div class="check">
                            <input type="checkbox" id=id.clone() prop:checked=move || on.get()
                                on:change=move |ev| on.set(event_target_checked(&ev)) />
                            <label for=id>{format!("Replay {}", kind.label())}</label>
                        </div>
                    }
                })
                .collect_view()}
            <SelectField id="replay-target-kind" label="Target is a"
                options=vec![("current", "Current (A)"), ("force", "Force (N)")] value=target_kind />
            <NumberField id="replay-target" label="Target value (empty: 80 % of the calibrated force at full override)" value=target_text
                error=target_error />
            <ChoiceField id="replay-calibration" label="Calibration for the replay" options=calibration_options value=use_calibration />
            {move || stored.with(|s| s.1.clone()).into_iter().map(|p| view! { <p class="field-error">{p}</p> }).collect_view()}
            <div class="button-row">
                <button type="button" on:click=start>"Replay"</button>
            </div>
            {move || replay_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
            <RunProgress runner=replay.runner.get_value() id="replay-progress" failure="The replay failed" />
        </fieldset>
    }
}
