//! A page mounted in pieces, and its own work done after its mount: the one place this is
//! explained.
//!
//! Everything a page builds as it mounts runs in one task, with the effects that follow it and
//! V8's compilation of each function the first time it is called: for a page with a form, five
//! charts and tables, more than the 50 ms a task should take (docs/benchmarks.md holds the first
//! task to 50 ms). So what a person needs first (the header, the navigation, the form) mounts at
//! once, and what waits for a result anyway (charts, tables, the later parts of a long form)
//! mounts after it ([`Later`]), a piece per frame: the browser styles and lays out each piece in
//! a frame of its own, where all of them at once took 66–78 ms of Compare's first layout
//! (docs/benchmarks.md, "The page's longest tasks"). The page's own work — parsing its form,
//! writing its URL, starting its first run — starts in the task after its mount
//! ([`effect_after_mount`]). Each `<Later>` on a page and each such effect needs no comment of its
//! own.

use leptos::prelude::*;

use crate::web::components::runner::next_task;

/// `false` until the task after the one that calls it, then `true`. An effect that returns early
/// while it reads `false` does its work in that task instead of the one that mounts the page.
fn from_next_task() -> ReadSignal<bool> {
    let (ready, set_ready) = signal(false);
    next_task(move || {
        let _ = set_ready.try_set(true);
    });
    ready
}

/// An effect that first runs `work` in the task after the one that mounts the page, then again
/// whenever what `work` reads changes: the page's own work, kept out of its mount's task.
pub fn effect_after_mount(work: impl Fn() + 'static) {
    let mounted = from_next_task();
    Effect::new(move |_| {
        if mounted.get() {
            work();
        }
    });
}

/// Calls `work` with `value` at once, in the task that mounts the page, if it holds one: a page's
/// first run is asked for as the page mounts, so that its worker computes while the page is laid
/// out and painted (asking costs the mount only the request). Then, as [`effect_after_mount`],
/// again whenever `value` changes to another `Some`; the value the page mounted with is not
/// asked for twice.
pub fn now_and_after_mount<T>(value: Memo<Option<T>>, work: impl Fn(T) + 'static)
where
    T: Clone + PartialEq + Send + Sync + 'static,
{
    let mounted_with = value.get_untracked();
    if let Some(first) = mounted_with.clone() {
        work(first);
    }
    let mounted_with = StoredValue::new(mounted_with);
    effect_after_mount(move || {
        let Some(now) = value.get() else {
            return;
        };
        let first = mounted_with.try_update_value(Option::take).flatten();
        if first.as_ref() != Some(&now) {
            work(now);
        }
    });
}

/// The pieces waiting to be shown, in the order they were mounted, and whether a frame is asked
/// for to show the first of them.
struct Pieces {
    waiting: std::collections::VecDeque<WriteSignal<bool>>,
    frame_asked: bool,
}

thread_local! {
    static PIECES: std::cell::RefCell<Pieces> = const {
        std::cell::RefCell::new(Pieces { waiting: std::collections::VecDeque::new(), frame_asked: false })
    };
}

/// `false` until it is this piece's turn: the first piece waiting is shown in the task after the
/// next frame (so after the page mounted so far is laid out and painted), each next one a frame
/// later. A page opened in a background tab, where the browser draws no frames, shows its pieces
/// once it is shown; its own work ([`effect_after_mount`]) starts regardless.
fn in_turn() -> ReadSignal<bool> {
    let (ready, set_ready) = signal(false);
    let ask = PIECES.with_borrow_mut(|pieces| {
        pieces.waiting.push_back(set_ready);
        !std::mem::replace(&mut pieces.frame_asked, true)
    });
    if ask {
        show_next_after_frame();
    }
    ready
}

/// After the next frame, shows the first waiting piece (one that was left meanwhile shows
/// nothing and gives its turn to the next) and asks for another frame while pieces wait.
fn show_next_after_frame() {
    request_animation_frame(|| {
        next_task(|| {
            let more = PIECES.with_borrow_mut(|pieces| {
                while let Some(piece) = pieces.waiting.pop_front() {
                    if piece.try_set(true).is_none() {
                        break;
                    }
                }
                pieces.frame_asked = !pieces.waiting.is_empty();
                pieces.frame_asked
            });
            if more {
                show_next_after_frame();
            }
        });
    });
}

/// Shows `children` in its turn after the page mounted: the browser paints what was mounted
/// before, a piece per frame, and handles input in between. Nothing shows if the page is left
/// meanwhile.
#[component]
pub fn Later(children: ChildrenFn) -> impl IntoView {
    let ready = in_turn();
    move || ready.get().then(|| children())
}
