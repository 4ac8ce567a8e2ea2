//! The shell of the lab: header, navigation and the current page.

use leptos::prelude::*;

use super::components::chart::ChartHelp;
use super::components::later::Later;
use super::pages;
use super::route::{use_current_page, Page};

/// The whole app.
#[component]
pub fn App() -> impl IntoView {
    let page = use_current_page();
    view! {
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
        <ChartHelp />
        <main id="main">
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
