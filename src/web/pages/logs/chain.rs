//! The signal chain on one column of the active log: a zero-phase low-pass, a moving RMS, the
//! spectrum and statistics per label, re-run (debounced) whenever a setting changes. It
//! computes in a worker ([`ChainJobRequest`]: the column and its label column go with the
//! request as numbers, the output comes back as numbers), so the page's thread stays free
//! however long the log; a new setting cancels the computation under way (its worker is
//! terminated) and starts the next.

use std::sync::Arc;
use std::time::Duration;

use leptos::prelude::*;

use super::charts::{channel_column, CURRENTS};
use super::loader::LoadedLog;
use super::LogsState;
use crate::log::analysis::{ChainOutput, ChainRequest};
use crate::log::link::LogsLink;
use crate::log::mapping::Channel;
use crate::log::settings::LogSetting;
use crate::log::transfer::ChainJobRequest;
use crate::log::ColumnKind;
use crate::web::components::fields::ChoiceField;
use crate::web::components::pool::Answer;
use crate::web::components::runner::{Debounce, RunProgress, Runner};
use crate::web::components::table_form::SettingField;

/// The chain's column, its grouping and its run.
#[derive(Clone, Copy)]
pub struct Chain {
    /// The column analysed.
    pub column: RwSignal<String>,
    /// The label column the statistics are grouped by (empty: none).
    pub by: RwSignal<String>,
    runner: StoredValue<Runner<Arc<ChainOutput>>>,
    /// The last chain's output.
    pub done: ReadSignal<Option<Arc<ChainOutput>>>,
    error: RwSignal<Option<String>>,
}

impl Chain {
    /// The chain of `shared`'s active log, run whenever the log or a setting changes; its column
    /// and grouping first those of a shared `link`, if the log has them.
    pub fn new(shared: LogsState, link: &LogsLink) -> Self {
        let column = RwSignal::new(link.column.clone().unwrap_or_default());
        let by = RwSignal::new(link.by.clone().unwrap_or_default());
        // A link's "no grouping" (`by=`) holds for the first log; after it, an empty choice
        // picks the new log's label as before.
        let by_chosen = StoredValue::new(link.by.is_some());
        let runner = Runner::<Arc<ChainOutput>>::new();
        let error = RwSignal::new(None::<String>);
        // A new log: analyse its current (or first numeric) column, grouped by its label.
        Effect::new(move |_| {
            shared.active.with(|l| {
                let Some(l) = l else { return };
                let present = |name: &str| l.log.columns.iter().any(|c| c.name == name);
                if !present(&column.get_untracked()) {
                    column.set(picked_column(l));
                }
                let by_now = by.get_untracked();
                let keep_none = by_now.is_empty() && by_chosen.get_value();
                by_chosen.set_value(false);
                if !keep_none && !present(&by_now) {
                    by.set(picked_by(l));
                }
            })
        });
        let debounce = Debounce::new(Duration::from_millis(250));
        let runner_for_effect = runner.clone();
        Effect::new(move |_| {
            let Some(l) = shared.active.get() else { return };
            let Ok(analysis) = shared.analysis.get() else {
                return;
            };
            let request = ChainRequest {
                column: column.get(),
                lowpass: analysis.lowpass,
                rms_window_s: analysis.rms_window_s,
                by: Some(by.get()).filter(|b| !b.is_empty()),
                sample_period_s: shared.period_s(),
            };
            let runner = runner_for_effect.clone();
            debounce.request(move || match ChainJobRequest::job(&l.log, request) {
                Ok((job, numbers)) => {
                    error.set(None);
                    runner.start_log_job(&job, &numbers, |answer| match answer {
                        Answer::Chain(output) => Some(output),
                        _ => None,
                    });
                }
                Err(e) => error.set(Some(e)),
            });
        });
        let done = runner.finished();
        Self {
            column,
            by,
            runner: StoredValue::new(runner),
            done,
            error,
        }
    }
}

/// The column a log is analysed by unless one is chosen: its current (or first numeric) column.
pub fn picked_column(l: &LoadedLog) -> String {
    channel_column(l, &CURRENTS)
        .or_else(|| l.log.columns.iter().find(|c| c.kind == ColumnKind::Number))
        .map(|c| c.name.clone())
        .unwrap_or_default()
}

/// The label column the statistics are grouped by unless one is chosen: the mapped label.
pub fn picked_by(l: &LoadedLog) -> String {
    l.mapping
        .columns_of(Channel::Label)
        .first()
        .map_or(String::new(), |s| s.to_string())
}

/// The signal chain's fieldset.
#[component]
pub fn ChainPanel(shared: LogsState, chain: Chain) -> impl IntoView {
    let column_options = Signal::derive(move || {
        shared.active.with(|l| {
            l.as_ref()
                .map(|l| {
                    l.log
                        .columns
                        .iter()
                        .filter(|c| matches!(c.kind, ColumnKind::Number))
                        .map(|c| (c.name.clone(), c.name.clone()))
                        .collect()
                })
                .unwrap_or_default()
        })
    });
    let label_options = Signal::derive(move || {
        let mut options = vec![(String::new(), "No grouping".to_string())];
        shared.active.with(|l| {
            if let Some(l) = l {
                options.extend(
                    l.log
                        .columns
                        .iter()
                        .filter(|c| c.kind == ColumnKind::Text)
                        .map(|c| (c.name.clone(), c.name.clone())),
                );
            }
        });
        options
    });
    let error = chain.error;
    let field = move |setting: LogSetting| {
        view! { <SettingField form=shared.settings setting=setting errors=shared.errors id_prefix="chain-" /> }
    };
    view! {
        <fieldset>
            <legend>"Signal chain"</legend>
            <ChoiceField id="chain-column" label="Column" options=column_options value=chain.column error=Some(Signal::derive(move || error.get())) />
            {field(LogSetting::Lowpass)}
            {field(LogSetting::Order)}
            {field(LogSetting::RmsWindow)}
            {field(LogSetting::MarkerTeeth)}
            <ChoiceField id="chain-by" label="Statistics per label of" options=label_options value=chain.by />
            <RunProgress runner=chain.runner.get_value() id="chain-progress" failure="The signal chain failed" />
        </fieldset>
    }
}
