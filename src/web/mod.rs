//! The Leptos browser app: a thin layer that shows and steers the core.
//!
//! Pages hold form state as text (so a half-typed value is never lost), parse it into the core's
//! validated types with `Result`, show each error beside the field that caused it, and draw what
//! the core computed with [`crate::charts`] on a canvas. No page computes anything itself.
//!
//! | module | what it holds |
//! |---|---|
//! | `app` | the shell: header, navigation, the current page |
//! | `route` | the page registry and the URL hash that selects a page |
//! | `components` | form fields and the canvas chart |
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
    components::runner::next_task(|| leptos::mount::mount_to_body(app::App));
}
