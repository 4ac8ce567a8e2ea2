//! The one page shell: a section named by its heading, the page's panels inside.

use leptos::prelude::*;

/// A page of the lab: `<section class="page …">` labelled by its `<h1>`, then `children` (the
/// lede and the page's panels).
#[component]
pub fn PageShell(
    /// The page's id: its heading is `{id}-title`.
    id: &'static str,
    /// The heading.
    title: &'static str,
    /// A class beside `page`, for the page's own styles (empty: none).
    #[prop(default = "")]
    class: &'static str,
    children: Children,
) -> impl IntoView {
    let (labelled_by, title_id) = (format!("{id}-title"), format!("{id}-title"));
    let class = if class.is_empty() {
        "page".to_string()
    } else {
        format!("page {class}")
    };
    view! {
        <section class=class aria-labelledby=labelled_by>
            <h1 id=title_id>{title}</h1>
            {children()}
        </section>
    }
}

/// A wide table's own scrolling box: on a narrow screen the table scrolls inside it instead of
/// widening the page, and the box takes the keyboard focus so the arrow keys scroll it too.
#[component]
pub fn TableScroll(
    /// What the box holds, for a screen reader ("Statistics per segment").
    label: String,
    children: Children,
) -> impl IntoView {
    view! {
        <div class="table-scroll" tabindex="0" role="region" aria-label=format!("{label}, scrollable")>
            {children()}
        </div>
    }
}
