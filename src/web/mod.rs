//! The Leptos browser app: a thin layer that shows and steers the core.
//!
//! Pages hold form state as text (so a half-typed value is never lost) and parse it through the
//! core's tables of settings ([`crate::input::table`]: the run definition, the signal chain's
//! design, the modelled cut, a log's analysis, the virtual device, the serial line, the host,
//! tuning, the open-loop machine); the core's error names the setting it belongs to, and the
//! page shows it beside that field, without reading its text. The computation — filters, runs,
//! fits, replays, tuning, the device and the session — is the core's, run in pieces
//! ([`crate::work::Work`]); what a page does itself is the view: choosing series for a chart,
//! decimating them to its width, laying out tables, and the browser's own work (files, storage,
//! WebSerial, the URL).
//!
//! A page is a short composition of panels: a page with several panels is a directory
//! (`pages/logs/`, `pages/hardware/`, …) whose `mod.rs` composes them, one file per panel
//! (tests/web_layout.rs holds page files to 600 lines and component functions to 200).
//!
//! | module | what it holds |
//! |---|---|
//! | `app` | the shell: header, navigation, the current page |
//! | `route` | the page registry and the URL hash that selects a page |
//! | `components` | the one form for any table of settings, fields, the canvas chart, the page shell, the mount-later helper, the run's forms and views |
//! | `hardware` | the Hardware page's ports (WebSerial, virtual device), station and IndexedDB store |
//! | `pages` | one module per section of the lab |
//! | `js` | what a JavaScript error says, the text of a chosen file |

mod app;
mod components;
mod hardware;
mod js;
mod pages;
mod route;

/// Mounts the lab on the page's `<body>`; called once by the `cutlab-web` binary.
///
/// The mount waits for a task of its own: the binary's `main` runs in the task that finishes
/// instantiating the module (V8 ends its streaming compilation there), and the two together took
/// longer than the 50 ms a task should.
pub fn start() {
    console_error_panic_hook::set_once();
    components::pool::start_workers();
    components::runner::next_task(|| leptos::mount::mount_to_body(app::App));
}
