//! The Leptos browser app.
pub fn start() {}
