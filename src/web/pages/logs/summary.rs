//! What the reader found in the active log — its dialect, problems and what it did not read as
//! data — and its column mapping, editable; the sample period of a log without a time column.

use leptos::prelude::*;

use super::loader::LoadedLog;
use super::LogsState;
use crate::input::readable;
use crate::log::mapping::Channel;
use crate::log::settings::LogSetting;
use crate::web::components::page::TableScroll;
use crate::web::components::table_form::SettingField;

/// What the reader found in the active log, and its column mapping.
#[component]
pub fn LogSummary(
    l: LoadedLog,
    shared: LogsState,
    #[prop(into)] mapping_error: Signal<Option<String>>,
) -> impl IntoView {
    let logs = shared.logs;
    let log = l.log.clone();
    let dialect = format!(
        "{}: {} rows, {} columns; {}, {}; time {}; sample period {}; {} read in {:.2} s.",
        l.name,
        log.rows,
        log.columns.len(),
        log.dialect.in_words(),
        if log.header { "a header" } else { "no header" },
        log.time_column
            .and_then(|t| log.columns.get(t))
            .map_or("none".to_string(), |c| c.name.clone()),
        log.sample_period_s
            .map_or("unknown".to_string(), |p| format!("{} s", readable(p))),
        // In the unit that reads best: "6e-6 MB" for a six-byte file said nothing.
        match l.bytes {
            b if b < 1000 => format!("{b} bytes"),
            b if b < 1_000_000 => format!("{} kB", readable(b as f64 / 1e3)),
            b => format!("{} MB", readable(b as f64 / 1e6)),
        },
        l.load_s
    );
    let problems: Vec<String> = log
        .problems
        .iter()
        .take(10)
        .map(|p| {
            format!(
                "line {}{}: {}",
                p.line,
                p.column
                    .as_deref()
                    .map_or(String::new(), |c| format!(", {c}")),
                p.message
            )
        })
        .collect();
    let more = log.problems.len().saturating_sub(10) + log.problems_not_listed;
    let not_read = log.account.unread();
    let needs_period = log.time_column.is_none();
    let options: Vec<(String, String)> = std::iter::once((String::new(), "—".to_string()))
        .chain(
            Channel::ALL
                .iter()
                .map(|c| (c.name().to_string(), c.label().to_string())),
        )
        .collect();
    view! {
        <section aria-labelledby="log-summary-title">
            <h2 id="log-summary-title">"The log"</h2>
            <p role="status">{dialect}</p>
            {(!not_read.is_empty()).then(|| view! {
                <p class="hint">{format!("Not read as data: {}.", not_read.join("; "))}</p>
            })}
            {(!problems.is_empty()).then(|| view! {
                <details>
                    <summary>{format!("{} problems, by line and column", problems.len() + more)}</summary>
                    <ul>{problems.into_iter().map(|p| view! { <li>{p}</li> }).collect_view()}</ul>
                    {(more > 0).then(|| view! { <p class="hint">{format!("… and {more} more")}</p> })}
                </details>
            })}
            {needs_period.then(|| view! {
                <SettingField form=shared.settings setting=LogSetting::SamplePeriod errors=shared.errors id_prefix="log-" />
            })}
            <TableScroll label="Columns and what they carry".to_string()>
            <table class="metrics">
                <caption>"Columns and what they carry (the mapping replay and calibration read)"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Column"</th>
                        <th scope="col">"Kind"</th>
                        <th scope="col">"Unit"</th>
                        <th scope="col">"Missing"</th>
                        <th scope="col">"Not finite"</th>
                        <th scope="col">"Guessed from"</th>
                        <th scope="col">"Channel"</th>
                    </tr>
                </thead>
                <tbody>
                    {log.columns
                        .iter()
                        .enumerate()
                        .map(|(i, c)| {
                            let id = format!("map-{}-{i}", l.id);
                            let name = c.name.clone();
                            let current = l.mapping.channel_of(&c.name).map_or(String::new(), |ch| ch.name().to_string());
                            let options = options.clone();
                            view! {
                                <tr>
                                    <th scope="row"><label for=id.clone()>{c.name.clone()}</label></th>
                                    <td>{format!("{:?}", c.kind).to_lowercase()}</td>
                                    <td>{c.unit.clone().unwrap_or_else(|| "—".into())}</td>
                                    <td>{c.missing}</td>
                                    <td>{c.not_finite}</td>
                                    <td>{c.role_reason.clone().unwrap_or_else(|| "—".into())}</td>
                                    <td>
                                        <select
                                            id=id
                                            on:change=move |ev| logs.set_channel(&name, Channel::from_name(&event_target_value(&ev)))
                                        >
                                            {options
                                                .into_iter()
                                                .map(|(v, text)| {
                                                    let selected = v == current;
                                                    view! { <option value=v selected=selected>{text}</option> }
                                                })
                                                .collect_view()}
                                        </select>
                                    </td>
                                </tr>
                            }
                        })
                        .collect_view()}
                </tbody>
            </table>
            </TableScroll>
            {move || mapping_error.get().map(|e| view! { <p class="run-error" role="alert">{e}</p> })}
        </section>
    }
}
