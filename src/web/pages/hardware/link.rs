//! The link: its state and why, the overrides commanded and applied, the feed hold, the device
//! and the counters; and the session's events.

use leptos::prelude::*;

use super::ui::{pct, Ui};
use crate::hardware::session::LinkState;

/// The link: its state and why, the device, the counters.
#[component]
pub fn LinkPanel(ui: Ui, children: Children) -> impl IntoView {
    let s = ui.snapshot;
    let state_name = move || s.with(|s| s.state.map_or("closed", LinkState::name));
    let counters = move || {
        s.with(|s| {
            let st = &s.stats;
            vec![
                ("Frames received", st.frames_received.to_string()),
                ("Samples lost (sequence gaps)", st.frames_lost.to_string()),
                ("Samples out of order", st.frames_reordered.to_string()),
                (
                    "Frames rejected (CRC, COBS, size)",
                    st.frames_rejected.to_string(),
                ),
                (
                    "Bytes dropped (part of no frame)",
                    st.bytes_dropped.to_string(),
                ),
                ("Frames of unknown type", st.frames_unknown.to_string()),
                ("Commands sent", st.commands_sent.to_string()),
                (
                    "Commands acknowledged",
                    st.commands_acknowledged.to_string(),
                ),
                ("Heartbeats sent", st.heartbeats_sent.to_string()),
                (
                    "Device watchdog fallbacks",
                    st.watchdog_fallbacks.to_string(),
                ),
                (
                    "Link losses (host watchdog, port lost)",
                    st.link_losses.to_string(),
                ),
                ("Device faults", st.device_faults.to_string()),
                (
                    "Command round trip, mean / max (ms)",
                    if st.commands_acknowledged == 0 {
                        "— (no command acknowledged yet)".to_string()
                    } else {
                        format!(
                            "{:.1} / {:.1}",
                            1000.0 * st.command_latency_mean_s,
                            1000.0 * st.command_latency_max_s
                        )
                    },
                ),
            ]
        })
    };
    view! {
        <section class="panel link-panel" aria-labelledby="link-title">
            <h2 id="link-title">"Link"</h2>
            <p class="link-state" role="status">
                "Link state: "
                <strong class=move || format!("state state-{}", state_name())>{state_name}</strong>
                {move || s.with(|s| s.port.map(|p| format!(" — {p}")))}
            </p>
            {move || {
                let (state, reason) = s.with(|s| (s.state, s.reason.clone()));
                if state == Some(LinkState::Alarm) {
                    view! { <p role="alert" class="link-reason run-error">"Alarm: " {reason}</p> }.into_any()
                } else if reason.is_empty() {
                    view! { <p class="link-reason">"Not connected."</p> }.into_any()
                } else {
                    view! { <p class="link-reason">"Why: " {reason}</p> }.into_any()
                }
            }}
            {children()}
            <p class="overrides">
                {move || s.with(|s| if s.state.is_none() {
                    // Nothing is commanded over a link that is not open: 0 % would read as a
                    // feed hold.
                    "Override: no link open.".to_string()
                } else {
                    format!(
                        "Override commanded {}, applied {}{}",
                        pct(s.commanded_pct),
                        pct(s.applied_pct),
                        if s.fallback {
                            " — the device is in its watchdog fallback"
                        } else if !s.commanded_pct.is_finite() {
                            " — no command in force (the machine runs at what it applies itself)"
                        } else {
                            ""
                        },
                    )
                })}
            </p>
            <p class="hold" role="status" aria-label="Feed hold at the machine">
                {move || s.with(|s| s.hold.clone().map_or_else(
                    || "Feed hold: none latched at the device.".to_string(),
                    |h| format!("Feed hold: {h}."),
                ))}
            </p>
            <p class="hint if-link-lost">
                {move || s.with(|s| s.if_link_lost.clone())}
            </p>
            <p class="hint">
                {move || s.with(|s| s.last_ack.clone().map_or_else(
                    || "No acknowledgement yet.".to_string(),
                    |a| format!("Last acknowledgement: {a}"),
                ))}
            </p>
            <p class="hint">{move || s.with(|s| s.recording.clone().unwrap_or_default())}</p>
            <div class="link-details">
                {move || s.with(|s| s.device.clone()).map(|d| view! {
                    <dl class="device" aria-label="Device">
                        <dt>"Device"</dt><dd>{d.device_id.clone()}</dd>
                        <dt>"Program"</dt><dd>{d.program.clone()}</dd>
                        <dt>"Protocol version"</dt><dd>{d.protocol_version.clone()}</dd>
                        <dt>"Sample rate"</dt><dd>{format!("{} Hz", d.sample_rate_hz)}</dd>
                        {s.with(|s| s.device_details.clone())
                            .into_iter()
                            .map(|(k, v)| view! { <dt>{k}</dt><dd>{v}</dd> })
                            .collect_view()}
                    </dl>
                })}
                <table class="metrics counters">
                    <caption>"Link counters"</caption>
                    <tbody>
                        {move || counters()
                            .into_iter()
                            .map(|(name, value)| view! { <tr><th scope="row">{name}</th><td>{value}</td></tr> })
                            .collect_view()}
                    </tbody>
                </table>
            </div>
        </section>
    }
}

/// The session's events, latest last.
#[component]
pub fn EventList(ui: Ui) -> impl IntoView {
    view! {
        <section class="event-log" aria-labelledby="hw-events-title">
            <h2 id="hw-events-title">"Events"</h2>
            {move || {
                let events = ui.snapshot.with(|s| s.events.clone());
                if events.is_empty() {
                    view! { <p class="hint">"No events yet."</p> }.into_any()
                } else {
                    view! {
                        <ol>
                            {events
                                .into_iter()
                                .map(|(t, text)| view! { <li><span class="event-time">{format!("{t:.2} s")}</span>" "{text}</li> })
                                .collect_view()}
                        </ol>
                    }
                    .into_any()
                }
            }}
        </section>
    }
}
