//! Controllers replayed on the active log: the override each would have commanded and what the
//! envelope would have done, through the loop every run uses, computed in the workers
//! ([`super::in_workers`]); the target is the run definition's row (as
//! `cutlab log replay --target-n/--target-a`), checked as typed.

use std::sync::Arc;

use leptos::prelude::*;

use super::calibration::FitForm;
use super::in_workers::{start_replays, ReplayRunner};
use super::LogsState;
use crate::closed_loop::definition::{max_override_pct_of, RunSetting};
use crate::closed_loop::error::LoopError;
use crate::control::registry::ControllerKind;
use crate::estimation::estimator::Calibration;
use crate::log::link::{machine_label, machine_named, machines, LogsLink, TargetKind};
use crate::log::machine::ReplayError;
use crate::log::replay::{ReplayResult, ReplayRun};
use crate::web::components::fields::{ChoiceField, NumberField, SelectField};
use crate::web::components::runner::RunProgress;

/// The replays' form and run.
#[derive(Clone, Copy)]
pub struct Replay {
    runner: StoredValue<ReplayRunner>,
    /// The last replays.
    pub done: ReadSignal<Option<Vec<Arc<ReplayResult>>>>,
    /// Whether each of [`ControllerKind::ALL`] is replayed.
    chosen: [RwSignal<bool>; ControllerKind::ALL.len()],
    /// The target's kind ([`TargetKind::name`]).
    target_kind: RwSignal<String>,
    /// The target as typed.
    target_text: RwSignal<String>,
    /// The machine's override input ([`crate::plant::cnc::OverrideMode::name`]).
    machine: RwSignal<String>,
}

impl Replay {
    /// No replay yet; the form as `link` sets it. Each finished set of replays goes to the
    /// lesson panel.
    pub fn new(link: &LogsLink) -> Self {
        let runner = ReplayRunner::new();
        let done = runner.finished();
        Effect::new(move |_| {
            if let Some(replays) = done.get() {
                crate::web::pages::lessons::feed::publish_replays(&replays);
            }
        });
        Self {
            runner: StoredValue::new(runner),
            done,
            chosen: std::array::from_fn(|i| {
                RwSignal::new(link.replayed.contains(&ControllerKind::ALL[i]))
            }),
            target_kind: RwSignal::new(link.target_kind.name().to_string()),
            target_text: RwSignal::new(link.target_text.clone()),
            machine: RwSignal::new(link.machine.name().to_string()),
        }
    }

    /// The form as a link writes it (tracked): `link` with this form's controllers, target and
    /// machine.
    pub fn form_link(self, link: LogsLink) -> LogsLink {
        LogsLink {
            replayed: ControllerKind::ALL
                .iter()
                .zip(self.chosen)
                .filter(|(_, on)| on.get())
                .map(|(k, _)| *k)
                .collect(),
            machine: machine_named(&self.machine.get()).unwrap_or_default(),
            target_kind: TargetKind::from_name(&self.target_kind.get()),
            target_text: self.target_text.get(),
            ..link
        }
    }
}

/// The replay's fieldset.
#[component]
pub fn ReplayPanel(shared: LogsState, fit: FitForm, replay: Replay) -> impl IntoView {
    let (chosen, target_kind, target_text, machine) = (
        replay.chosen,
        replay.target_kind,
        replay.target_text,
        replay.machine,
    );
    // A log's machine is FANUC's dial unless told.
    let target = Memo::new(move |_| {
        let max_override_pct =
            max_override_pct_of(&machine_named(&machine.get()).unwrap_or_default());
        TargetKind::from_name(&target_kind.get())
            .setting()
            .parse_on(&target_text.get(), max_override_pct)
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
    // A fit just made is what the person calibrated for: the replay uses it until they choose
    // another calibration (each new fit chooses itself again).
    Effect::new(move |_| {
        if fit_done.with(Option::is_some) {
            use_calibration.set("fit".to_string());
        }
    });
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
        let form = untrack(|| replay.form_link(LogsLink::default()));
        let controllers = form.controllers();
        if controllers.is_empty() {
            replay_error.set(Some("choose at least one controller".into()));
            return;
        }
        if target.get_untracked().is_err() {
            return;
        }
        // The settings a lesson's link replays with natively, built by the same code.
        let settings = match form.replay_settings(
            fit.feedback.get_untracked(),
            chosen_calibration(),
            shared.period_s_untracked(),
        ) {
            Ok(settings) => settings,
            Err(e) => {
                refused_target.set(Some(e));
                return;
            }
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
            <SelectField id="replay-machine" label="Machine's override input"
                options=machines().iter().map(|m| (m.name(), machine_label(m))).collect() value=machine />
            <SelectField id="replay-target-kind" label="Target is a"
                options=TargetKind::ALL.iter().map(|k| (k.name(), k.label())).collect() value=target_kind />
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
