//! The student's progress ([`StudentProgress`]) in this browser's `localStorage`, as one signal every
//! part of the lessons reads, saved on every change.

use leptos::prelude::*;

use crate::lessons::progress::{StudentProgress, STORAGE_KEY};

thread_local! {
    static PROGRESS: ArcRwSignal<StudentProgress> = ArcRwSignal::new(load());
}

fn storage() -> Option<web_sys::Storage> {
    window().local_storage().ok().flatten()
}

fn load() -> StudentProgress {
    storage()
        .and_then(|s| s.get_item(STORAGE_KEY).ok().flatten())
        .map(|text| StudentProgress::from_json(&text))
        .unwrap_or_default()
}

/// The progress (tracked where read).
pub fn progress() -> ArcRwSignal<StudentProgress> {
    PROGRESS.with(Clone::clone)
}

/// Changes the progress and saves it; a browser that keeps nothing keeps it for the session.
pub fn update(change: impl FnOnce(&mut StudentProgress)) {
    let progress = progress();
    progress.update(change);
    if let Some(storage) = storage() {
        let _ = storage.set_item(
            STORAGE_KEY,
            &progress.with_untracked(StudentProgress::to_json),
        );
    }
}
