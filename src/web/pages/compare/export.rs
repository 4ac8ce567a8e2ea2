//! The comparison as files: the traces and the metrics as CSV, the configuration as the JSON
//! `cutlab compare --config` runs.

use leptos::prelude::*;

use crate::closed_loop::definition::RunSpec;
use crate::closed_loop::metrics::metrics_csv_columns;
use crate::closed_loop::trace::write_csv_runs;
use crate::web::components::download::{download_configuration, download_text, download_written};
use crate::web::components::run_view::NamedRun;

/// The export buttons and what went wrong with the last export.
#[component]
pub fn ExportPanel(
    /// The runs shown.
    #[prop(into)]
    runs: Signal<Vec<NamedRun>>,
    /// The runs the form defines, if it parses.
    specs: Memo<Option<Vec<RunSpec>>>,
) -> impl IntoView {
    let (export_error, set_export_error) = signal(None::<String>);
    let export_traces = move |_| {
        let shown = runs.get_untracked();
        let named: Vec<(&str, &crate::closed_loop::trace::Trace)> =
            shown.iter().map(|(n, r)| (n.as_str(), &r.trace)).collect();
        let outcome = download_written("cutlab-compare-traces.csv", "text/csv", |out| {
            write_csv_runs(&named, out)
        });
        set_export_error.set(outcome.err());
    };
    let export_metrics = move |_| {
        let shown = runs.get_untracked();
        let named: Vec<(&str, &crate::closed_loop::metrics::Metrics)> = shown
            .iter()
            .map(|(n, r)| (n.as_str(), &r.metrics))
            .collect();
        set_export_error.set(
            download_text(
                "cutlab-compare-metrics.csv",
                "text/csv",
                &metrics_csv_columns(&named),
            )
            .err(),
        );
    };
    let export_config = move |_| {
        set_export_error.set(
            specs
                .get_untracked()
                .ok_or_else(|| "fix the settings marked above first".to_string())
                .and_then(download_configuration)
                .err(),
        );
    };
    view! {
        <fieldset>
            <legend>"Export"</legend>
            <div class="button-row">
                <button type="button" on:click=export_traces disabled=move || runs.with(Vec::is_empty)>
                    "Traces (CSV)"
                </button>
                <button type="button" on:click=export_metrics disabled=move || runs.with(Vec::is_empty)>
                    "Metrics (CSV)"
                </button>
                <button type="button" on:click=export_config disabled=move || specs.get().is_none()>
                    "Configuration (JSON)"
                </button>
            </div>
            {move || export_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
        </fieldset>
    }
}
