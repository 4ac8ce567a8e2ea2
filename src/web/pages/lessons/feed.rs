//! The runs the lab's pages finish, for the lesson panel to check: the computation workers'
//! runner publishes each finished set of runs here ([`publish`]), and the Logs page each
//! finished set of replays ([`publish_replays`]), with the page they ran on and a serial number,
//! so the panel checks only work newer than the step it opened.

use std::sync::Arc;

use leptos::prelude::*;

use crate::closed_loop::lab::RunResult;
use crate::log::replay::ReplayResult;

/// A set of runs a page finished.
#[derive(Debug, Clone)]
pub struct FinishedRuns {
    /// Counts the sets published, from 1.
    pub serial: u64,
    /// The page's slug in the URL hash (`simulate`) when they finished.
    pub page: String,
    /// The runs, in the page's order (variant A first).
    pub runs: Vec<Arc<RunResult>>,
    /// The Logs page's replays, one per controller (empty for runs).
    pub replays: Vec<Arc<ReplayResult>>,
}

thread_local! {
    static FINISHED: ArcRwSignal<Option<FinishedRuns>> = ArcRwSignal::new(None);
}

/// The last finished runs (tracked where read).
pub fn finished() -> ArcRwSignal<Option<FinishedRuns>> {
    FINISHED.with(Clone::clone)
}

/// The serial of the last runs published (untracked): a step opened now checks only later ones.
pub fn last_serial() -> u64 {
    FINISHED.with(|f| f.with_untracked(|r| r.as_ref().map_or(0, |r| r.serial)))
}

/// Publishes `runs`, just finished on the page the URL shows.
pub fn publish(runs: &[Arc<RunResult>]) {
    publish_work(runs.to_vec(), Vec::new());
}

/// Publishes `replays`, just finished on the Logs page.
pub fn publish_replays(replays: &[Arc<ReplayResult>]) {
    publish_work(Vec::new(), replays.to_vec());
}

fn publish_work(runs: Vec<Arc<RunResult>>, replays: Vec<Arc<ReplayResult>>) {
    let hash = window().location().hash().unwrap_or_default();
    let page = hash
        .trim_start_matches('#')
        .trim_start_matches('/')
        .split(['?', '/'])
        .next()
        .unwrap_or_default()
        .to_string();
    let serial = last_serial() + 1;
    FINISHED.with(|f| {
        f.set(Some(FinishedRuns {
            serial,
            page,
            runs,
            replays,
        }))
    });
}
