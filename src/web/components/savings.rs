//! The savings rows of the metrics tables. A saving compares a run's cycle time with reference
//! runs at a fixed feed (the programmed feed, and the fastest fixed feed that keeps the peak force
//! at or below the target), which take three to five runs (on the teach cut of the run that asked). They depend on the scenario, not on the
//! controller, so they run in the background once per scenario, from the moment a run's teach
//! cut is known, and the answers of the last few scenarios are kept: retuning a controller never
//! waits for them. The search runs in a computation worker ([`super::pool`]), beside the run's
//! own.

use std::sync::{Arc, OnceLock};

use leptos::prelude::*;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::lab::preset_plan;
use crate::closed_loop::lab::{RunResult, TeachKey};
use crate::closed_loop::precomputed::shipped_references;
use crate::closed_loop::references::{apply_references, fixed_feed_spec, References, ScenarioKey};
use crate::closed_loop::transfer::{JobRequest, ReferenceRequest};
use crate::estimation::estimator::Calibration;
use crate::web::components::pool::Answer;
use crate::web::components::recent;
use crate::web::components::run_view::NamedRun;
use crate::web::components::runner::{RunProgress, RunStatus, Runner};

/// Scenarios whose references are kept.
const KEPT: usize = 8;

/// The scenario of `spec`: everything the reference runs depend on, i.e. all but the controller.
fn scenario_of(spec: &RunSpec) -> Option<RunSpec> {
    fixed_feed_spec(spec, 100.0).ok()
}

/// What the references of `spec`'s scenario depend on (the same for the scenario itself: the key
/// is taken at the fixed 100 % feed).
fn key_of(spec: &RunSpec) -> Option<ScenarioKey> {
    ScenarioKey::of(spec).ok()
}

/// The default scenario's references, shipped with the code ([`shipped_references`]); read on
/// first use, when a run asks for its savings, not while a page mounts (whose first task should
/// stay short).
fn shipped() -> &'static [(ScenarioKey, References)] {
    static SHIPPED: OnceLock<Vec<(ScenarioKey, References)>> = OnceLock::new();
    SHIPPED.get_or_init(shipped_references)
}

/// The references under `key` among those `known`, else among the shipped ones.
fn known_or_shipped(known: &[(ScenarioKey, References)], key: &ScenarioKey) -> Option<References> {
    recent::find(known, key)
        .or_else(|| recent::find(shipped(), key))
        .copied()
}

/// Reference runs for the savings, made on request and remembered per scenario.
#[derive(Clone)]
pub struct Savings {
    runner: Runner<References>,
    /// The scenario of the search under way or last started.
    started: StoredValue<Option<ScenarioKey>>,
    /// Known references, newest last.
    known: RwSignal<Vec<(ScenarioKey, References)>>,
}

impl Savings {
    /// Only the shipped references known; a search under way stops when the page is left.
    pub fn new() -> Self {
        let runner = Runner::<References>::new();
        let started = StoredValue::new(None::<ScenarioKey>);
        let known = RwSignal::new(Vec::new());
        let status = runner.status;
        Effect::new(move |_| {
            if let RunStatus::Done(found) = status.get() {
                if let Some(key) = started.get_value() {
                    known.update(|k| recent::remember(k, key, found, KEPT));
                }
            }
        });
        Self {
            runner,
            started,
            known,
        }
    }

    /// The known references of `spec`'s scenario: found by a search, or shipped.
    fn lookup(&self, spec: &RunSpec) -> Option<References> {
        let key = key_of(spec)?;
        self.known.with(|k| known_or_shipped(k, &key))
    }

    /// Starts the reference runs for the scenario of `spec`, unless they are known or under way;
    /// `calibration`, the teach cut of a run of `spec`, spares the search its own when it is the
    /// same teach cut ([`TeachKey`]).
    pub fn request(&self, spec: &RunSpec, calibration: Option<&Calibration>) {
        let Some(scenario) = scenario_of(spec) else {
            return;
        };
        let Some(key) = key_of(&scenario) else {
            return;
        };
        let known = self
            .known
            .with_untracked(|k| known_or_shipped(k, &key).is_some());
        if known {
            return;
        }
        let running = matches!(
            self.runner.status.get_untracked(),
            RunStatus::Running { .. }
        );
        if running && self.started.get_value().as_ref() == Some(&key) {
            return;
        }
        let same_teach_cut = match (TeachKey::of(spec), TeachKey::of(&scenario)) {
            (Ok(a), Ok(b)) => a == b,
            _ => false,
        };
        // The run itself reports what is wrong with the spec.
        if preset_plan(&scenario).is_err() {
            self.runner.cancel();
            return;
        }
        let request = ReferenceRequest {
            scenario,
            calibration: calibration.filter(|_| same_teach_cut).cloned(),
        };
        self.started.set_value(Some(key));
        self.runner.start_in_worker(
            JobRequest::References(Box::new(request)),
            |answer| match answer {
                Answer::References(found) => Some(found),
                _ => None,
            },
        );
    }

    /// Starts the reference runs as soon as the first run `runner` makes in the workers has its
    /// calibration (its teach cut made), which its first streamed piece carries: on another
    /// worker, beside the runs, instead of after them (the search needs only the scenario and
    /// that teach cut). The finished run's own request then finds them under way or known.
    pub fn request_while_running<T: Send + Sync + 'static>(&self, runner: &Runner<T>) {
        let taught = runner.taught;
        let savings = self.clone();
        Effect::new(move |_| {
            // Set once per start (a calibration holding a NaN never equals itself, so the signal
            // is not compared; it is only set when the first run is taught).
            taught.with(|taught| {
                if let Some((spec, calibration)) = taught {
                    savings.request(spec, Some(calibration));
                }
            });
        });
    }

    /// Stops a search for another scenario than `spec`'s, so it does not slow the new run.
    pub fn keep_only(&self, spec: &RunSpec) {
        let started = self.started.get_value();
        if started.is_none() || started != key_of(spec) {
            self.runner.cancel();
        }
    }

    /// `run` with its savings filled if the references of its scenario are known.
    pub fn apply(&self, run: Arc<RunResult>) -> Arc<RunResult> {
        let known = self.lookup(&run.spec);
        match known {
            Some(references) => {
                let mut with: RunResult = (*run).clone();
                apply_references(&mut with, &references);
                Arc::new(with)
            }
            None => run,
        }
    }

    /// [`apply`](Self::apply) to each of `runs`.
    pub fn apply_all(&self, runs: Vec<NamedRun>) -> Vec<NamedRun> {
        runs.into_iter()
            .map(|(name, run)| (name, self.apply(run)))
            .collect()
    }

    /// The search's progress bar (with Cancel) while it runs.
    pub fn progress(&self) -> impl IntoView {
        view! { <RunProgress runner=self.runner.clone() id="savings-progress" quiet_cancel=true
        failure="The savings could not be computed" /> }
    }
}

impl Default for Savings {
    fn default() -> Self {
        Self::new()
    }
}
