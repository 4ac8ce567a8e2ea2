//! The shell of the lab: header, navigation and the current page.

use leptos::prelude::*;
use wasm_bindgen::JsCast;

use super::components::chart::ChartHelp;
use super::components::later::Later;
use super::pages;
use super::route::{use_current_page, Page};

/// The whole app.
#[component]
pub fn App() -> impl IntoView {
    let page = use_current_page();
    // The hash holds the page and its settings, so the skip link moves focus itself rather than
    // following `#main` (which would leave the page for Home).
    let skip_to_content = move |ev: leptos::ev::MouseEvent| {
        ev.prevent_default();
        if let Some(main) = document()
            .get_element_by_id("main")
            .and_then(|e| e.dyn_into::<web_sys::HtmlElement>().ok())
        {
            let _ = main.focus();
        }
    };
    view! {
        <a class="skip-link" href="#main" on:click=skip_to_content>"Skip to content"</a>
        <header class="site-header">
            <div class="brand">
                <img src="favicon.svg" alt="" width="28" height="28" />
                <span class="brand-name">"cutlab"</span>
                <span class="brand-tagline">"adaptive cutting-force control lab"</span>
            </div>
            <nav aria-label="Lab sections">
                <ul>
                    {Page::ALL
                        .into_iter()
                        .map(|p| {
                            view! {
                                <li>
                                    <a
                                        href=p.href()
                                        aria-current=move || (page.get() == p).then_some("page")
                                    >
                                        {p.label()}
                                    </a>
                                </li>
                            }
                        })
                        .collect_view()}
                </ul>
            </nav>
        </header>
        <main id="main" tabindex="-1">
            <ChartHelp />
            <Later>
            {move || match page.get() {
                Page::Home => view! { <pages::home::HomePage /> }.into_any(),
                Page::SignalChain => view! { <pages::signal_chain::SignalChainPage /> }.into_any(),
                Page::Learn => view! { <pages::learn::LearnPage /> }.into_any(),
                Page::Simulate => view! { <pages::simulate::SimulatePage /> }.into_any(),
                Page::Compare => view! { <pages::compare::ComparePage /> }.into_any(),
                Page::Fuzzy => view! { <pages::fuzzy::FuzzyPage /> }.into_any(),
                Page::Plant => view! { <pages::plant::PlantPage /> }.into_any(),
                Page::Tune => view! { <pages::tune::TunePage /> }.into_any(),
                Page::Hardware => view! { <pages::hardware::HardwarePage /> }.into_any(),
                Page::Logs => view! { <pages::logs::LogsPage /> }.into_any(),
                Page::Lessons => view! { <pages::lessons::LessonsPage /> }.into_any(),
            }}
            </Later>
        </main>
        <pages::lessons::panel::LessonPanel />
        <footer class="site-footer">
            <p>
                "cutlab "{env!("CARGO_PKG_VERSION")}
                " · models from five research papers on indirect force measurement and feed control"
            </p>
        </footer>
    }
}
