//! Logs: engineers' own machine logs, loaded as they are, analysed, calibrated from and replayed.
//!
//! ```text
//! File / drop / sample ─► streamed in chunks (Blob.slice + arrayBuffer) ─► LogBuilder::push
//!   ─► Log + guessed Mapping (editable, kept per file name)
//!   ─► signal chain on a column (ChainWork): zero-phase low-pass, moving RMS, spectrum, statistics
//!   ─► calibration (LogFitWork) ─► saved in localStorage (calibration_store::STORAGE_KEY)
//!   ─► replay of controllers (ReplayRuns, in the workers) ─► charts on linked time axes, CSV export
//! ```
//!
//! Replays compute in the workers ([`in_workers`]); every other long job runs in pieces on the
//! page (the file a chunk per task, the chain a stage per task, a fit a budget of periods per
//! task), so the page never freezes. Every field is a row of a
//! core table: the analysis's ([`crate::log::settings`]), the modelled cut's
//! ([`crate::estimation::cut_settings`]) and the run definition's target
//! ([`crate::closed_loop::definition::RunSetting`]), checked as typed.
//!
//! | file | panel |
//! |---|---|
//! | `mod.rs` | the page, and what its panels share: the open logs, the active one, the time axis, the analysis settings; the page's state in its URL ([`crate::log::link`]) |
//! | `loader.rs` | opening a file, a drop or a sample, in chunks |
//! | `open.rs` | the Open a log and Open logs panels |
//! | `chain.rs` | the signal chain on a column |
//! | `calibration.rs` | the calibration from the log, saved or downloaded |
//! | `replay.rs` | controllers replayed on the log |
//! | `in_workers.rs` | the replays computed in the workers |
//! | `export.rs` | the analysed channels and the replays as CSV |
//! | `results.rs`, `summary.rs`, `reports.rs`, `charts.rs` | the results column: the log and its mapping, the charts, the statistics and the replays' numbers |
//! | [`open`] | opening logs: file picker, drop zone, sample logs |
//! | [`loader`] | a log streamed in chunks into the core's reader |
//! | [`summary`] | what the reader found in the active log: dialect, problems, what it did not read |
//! | [`chain`] | the signal chain on one column of the active log |
//! | [`calibration`] | the current-to-force fit from the active log |
//! | [`replay`] | controllers replayed on the active log |
//! | [`in_workers`] | the replays computed in the workers |
//! | [`results`] | the results column: the active log, its mapping, every open log |
//! | [`charts`] | the page's charts, made of what the core computed |
//! | [`reports`] | the chain's statistics, notes and peaks; each replay's numbers |
//! | [`export`] | the analysed channels and the replays' overrides as CSV |

mod calibration;
mod chain;
mod charts;
mod export;
mod in_workers;
mod loader;
mod open;
mod replay;
mod reports;
mod results;
mod summary;

use std::ops::Range;

use leptos::prelude::*;

use crate::input::table::{self, form_errors, RowError};
use crate::log::link::{sample_named, LogsLink};
use crate::log::settings::{parse_analysis, sample_period, AnalysisSettings, LogSetting};
use crate::web::components::later::Later;
use crate::web::components::page::PageShell;
use crate::web::components::run_view::StaleNotice;
use crate::web::components::table_form::{FieldErrors, TableForm};
use crate::web::route::{query_params, replace_query, Page};
use calibration::{CalibrationPanel, FitForm};
use chain::{picked_by, picked_column, Chain, ChainPanel};
use export::ExportPanel;
use loader::{LoadedLog, Logs};
use open::{load_sample, OpenLogsPanel, OpenPanel};
use replay::{Replay, ReplayPanel};
use results::LogResults;

/// What the panels share: the open logs and the active one, the linked time axis, and the
/// analysis settings (the sample period of a log without a time column, the chain's low-pass,
/// RMS window and marker teeth), each parsed through its row.
#[derive(Clone, Copy)]
struct LogsState {
    logs: Logs,
    active: Memo<Option<LoadedLog>>,
    time_view: RwSignal<Option<Range<f64>>>,
    settings: TableForm<LogSetting>,
    period: Memo<Result<Option<f64>, RowError<LogSetting>>>,
    analysis: Memo<Result<AnalysisSettings, Vec<RowError<LogSetting>>>>,
    teeth: Memo<Result<usize, RowError<LogSetting>>>,
    errors: Memo<FieldErrors>,
}

impl LogsState {
    /// The state, its settings from a shared link's `query`.
    fn new(query: &[(String, String)]) -> Self {
        let logs = Logs::new();
        let active = Memo::new(move |_| {
            let id = logs.active.get();
            logs.logs
                .with(|l| l.iter().find(|x| Some(x.id) == id).cloned())
        });
        let settings = TableForm::<LogSetting>::new(query);
        let text = move |s: LogSetting| settings.text(s).get();
        let period = Memo::new(move |_| sample_period(Some(&text(LogSetting::SamplePeriod))));
        // The chain's own rows: the period and the marker's teeth do not stop it.
        let analysis = Memo::new(move |_| {
            let rows = [
                LogSetting::Lowpass,
                LogSetting::Order,
                LogSetting::RmsWindow,
            ];
            parse_analysis(&rows.map(|s| (s, text(s))))
        });
        let teeth = Memo::new(move |_| {
            table::count(LogSetting::MarkerTeeth, &text(LogSetting::MarkerTeeth))
        });
        let errors = Memo::new(move |_| {
            let mut all: Vec<RowError<LogSetting>> = analysis.get().err().unwrap_or_default();
            all.extend(period.get().err());
            all.extend(teeth.get().err());
            form_errors(&all)
        });
        Self {
            logs,
            active,
            time_view: RwSignal::new(None),
            settings,
            period,
            analysis,
            teeth,
            errors,
        }
    }

    /// The sample period given, if it parses (tracked).
    fn period_s(&self) -> Option<f64> {
        self.period.get().ok().flatten()
    }

    /// The sample period given, if it parses (untracked, for an action).
    fn period_s_untracked(&self) -> Option<f64> {
        self.period.get_untracked().ok().flatten()
    }
}

/// The Logs page.
#[component]
pub fn LogsPage() -> impl IntoView {
    let query = query_params(&window().location().hash().unwrap_or_default());
    let shared = LogsState::new(&query);
    // The whole analysis and replay form live in the address bar ([`LogsLink`]), so a reload or
    // a shared link restores them. A person's own file cannot (it is on their disk, not the
    // server): a link's mapping waits for the next log opened, and applies if it has those
    // columns.
    let (link, _) = LogsLink::parse(&query);
    let chain = Chain::new(shared, &link);
    let fit = FitForm::new();
    let replay = Replay::new(&link);
    if let Some(file) = link.sample {
        load_sample(shared.logs, file);
    }
    shared.logs.from_link.set(Some(link));
    Effect::new(move |_| {
        // Until a log opens, the link as it came; then the active log's sample, mapping and
        // analysed column (each left out where it is the page's own pick).
        let state = shared.logs.from_link.with(|waiting| {
            shared.active.with(|active| match (active, waiting) {
                (Some(l), _) => LogsLink {
                    sample: sample_named(&l.name),
                    mapping: LogsLink::mapping_of(&l.log, &l.mapping),
                    column: Some(chain.column.get()).filter(|c| *c != picked_column(l)),
                    by: Some(chain.by.get()).filter(|b| *b != picked_by(l)),
                    ..LogsLink::default()
                },
                (None, Some(waiting)) => LogsLink {
                    sample: waiting.sample,
                    mapping: waiting.mapping.clone(),
                    column: waiting.column.clone(),
                    by: waiting.by.clone(),
                    ..LogsLink::default()
                },
                (None, None) => LogsLink::default(),
            })
        });
        let mut pairs = replay.form_link(state).query();
        pairs.extend(shared.settings.query());
        replace_query(Page::Logs, &pairs);
    });
    let waiting_mapping = move || {
        shared.logs.from_link.with(|l| {
            l.as_ref()
                .filter(|l| l.sample.is_none() && !l.mapping.is_empty())
                .map(|l| l.mapping.len())
        })
    };
    // A setting that no longer validates leaves the chain shown from the last valid settings:
    // marked stale, as Simulate's results are, until it is fixed.
    let chain_done = chain.done;
    let stale = Signal::derive(move || {
        !shared.errors.with(|e| e.is_empty()) && chain_done.with(Option::is_some)
    });
    view! {
        <PageShell id="logs" title="Machine logs">
            <p class="lede">
                "Bring a log from your own machine — a CNC's spindle or servo monitor export, a DAQ, a "
                "logging script — as it is: comma, semicolon or tab, decimal commas, quotes, a header "
                "with units or none. Map its columns, run the signal chain on a current, calibrate the "
                "current-to-force model from it, and replay controllers on it: the override each would "
                "have commanded and when the safety envelope would have acted. Replay is open-loop: the "
                "log cannot react to a command."
            </p>
            {move || waiting_mapping().map(|n| view! {
                <p class="hint" role="note">
                    {format!("This link maps {n} columns to channels: the mapping applies to the next log you open whose columns have those names.")}
                </p>
            })}
            <div class="layout-two">
                <form class="panel" aria-label="Logs" on:submit=|ev| ev.prevent_default()>
                    <OpenPanel logs=shared.logs />
                    <OpenLogsPanel logs=shared.logs />
                    <Later>
                        <ChainPanel shared=shared chain=chain />
                    </Later>
                    <Later>
                        <CalibrationPanel shared=shared fit=fit />
                    </Later>
                    <Later>
                        <ReplayPanel shared=shared fit=fit replay=replay />
                    </Later>
                    <Later>
                        <ExportPanel shared=shared chain=chain replay=replay />
                    </Later>
                </form>
                <div class="results" class:stale=stale>
                    <StaleNotice stale=stale />
                    <Later>
                        <LogResults shared=shared chain=chain fit=fit replay=replay />
                    </Later>
                </div>
            </div>
        </PageShell>
    }
}
