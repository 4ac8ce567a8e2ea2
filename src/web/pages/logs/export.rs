//! The analysed channels (with the chain's output) and the replays' overrides as CSV.

use leptos::prelude::*;

use super::chain::Chain;
use super::replay::Replay;
use super::LogsState;
use crate::log::analysis::write_channels_csv;
use crate::log::replay::{write_replay_csv, ReplayResult};
use crate::web::components::download::download_written;

/// The export's fieldset.
#[component]
pub fn ExportPanel(shared: LogsState, chain: Chain, replay: Replay) -> impl IntoView {
    let export_error = RwSignal::new(None::<String>);
    let (chain_done, column) = (chain.done, chain.column);
    let export_channels = move |_| {
        let Some(l) = shared.active.get_untracked() else {
            export_error.set(Some("open a log first".into()));
            return;
        };
        let chain = chain_done.get_untracked();
        let column = column.get_untracked();
        let result = download_written("cutlab-log-channels.csv", "text/csv", |out| {
            write_channels_csv(
                &l.log,
                &l.mapping,
                chain.as_deref().map(|c| (column.as_str(), c)),
                shared.period_s_untracked(),
                out,
            )
        });
        export_error.set(result.err());
    };
    let replay_done = replay.done;
    let export_replays = move |_| {
        let Some(results) = replay_done.get_untracked() else {
            export_error.set(Some("replay first".into()));
            return;
        };
        let runs: Vec<&ReplayResult> = results.iter().map(|r| r.as_ref()).collect();
        let result = download_written("cutlab-log-replay.csv", "text/csv", |out| {
            write_replay_csv(&runs, out)
        });
        export_error.set(result.err());
    };
    view! {
        <fieldset>
            <legend>"Export"</legend>
            <div class="button-row">
                <button type="button" on:click=export_channels disabled=move || shared.active.with(Option::is_none)>"Analysed channels (CSV)"</button>
                <button type="button" on:click=export_replays disabled=move || replay_done.with(Option::is_none)>"Replayed overrides (CSV)"</button>
            </div>
            {move || export_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
        </fieldset>
    }
}
