//! Home: what the lab is for, the loop it studies as a picture whose blocks open the pages that
//! show them, three ways to start, and the five papers every "paper 00x" refers to.

use leptos::prelude::*;

use crate::web::components::page::PageShell;
use crate::web::route::{sub_path, Page};

/// One block of the loop: what it is, what it does, and the page (with its query) showing it.
struct LoopBlock {
    name: &'static str,
    does: &'static str,
    href: &'static str,
}

/// The force-control loop, in the order a signal travels it.
const LOOP: [LoopBlock; 6] = [
    LoopBlock {
        name: "Motor currents",
        does: "Hall sensors on the spindle and feed motors",
        href: "#/plant",
    },
    LoopBlock {
        name: "Signal chain",
        does: "low-pass, three-phase RMS, one value per control period",
        href: "#/signal",
    },
    LoopBlock {
        name: "Force estimate",
        does: "the teach cut's calibrated line from current to force",
        href: "#/logs",
    },
    LoopBlock {
        name: "Controller",
        does: "threshold, fuzzy, PI or adaptive law: the override it asks for",
        href: "#/compare",
    },
    LoopBlock {
        name: "Safety envelope",
        does: "override limits, rate limit, watchdogs and arming after every controller",
        href: "#/simulate?preset=kim-step-doc",
    },
    LoopBlock {
        name: "Feed override",
        does: "sent to the machine: simulated, or a real one over the serial line",
        href: "#/hardware",
    },
];

/// One of the five source papers.
struct Paper {
    /// "000" … "004": how the lab names it ("paper 002").
    number: &'static str,
    authors: &'static str,
    title: &'static str,
    /// Where the authors worked, and the year where the paper prints one.
    origin: &'static str,
    /// What the lab takes from it.
    takes: &'static str,
}

/// The five papers, in the lab's numbering.
const PAPERS: [Paper; 5] = [
    Paper {
        number: "000",
        authors: "Na Wang, Changsheng Ai, Xiangbo Ze, Guangwei He",
        title: "Adaptive Cutting Force Control for NC Machine Based on the Current Restriction",
        origin: "University of Jinan, China",
        takes: "the feed drive's current as a force sensor, the brake bench, the 10th-order \
                Butterworth low-pass and RMS, the current-restriction controller, FANUC's \
                16-grade feed override",
    },
    Paper {
        number: "001",
        authors: "Noppadol Maneerat, Adisak Khaengsarigid, Bundit Pasaya",
        title: "Adaptive Cutting Force Control for CNC Milling Machine",
        origin: "King Mongkut's Institute of Technology Ladkrabang, Thailand",
        takes: "the second-order force process and the Lyapunov model-reference adaptive law; \
                the experiments at 1, 2 and 4 mm depth",
    },
    Paper {
        number: "002",
        authors: "Hengli Liu, Taiyong Wang, Dong Wang",
        title: "Constant Cutting Force Control for CNC Machining Using Dynamic \
                Characteristic-Based Fuzzy Controller",
        origin: "Tianjin University, China, 2015",
        takes: "the spindle current as feedback, the bond-graph machine model, the fuzzy \
                controller and its experience- and dynamics-based rule tables",
    },
    Paper {
        number: "003",
        authors: "Gi D. Kim, Won T. Kwon, Chong N. Chu",
        title: "Indirect Cutting Force Measurement and Cutting Force Regulation Using Spindle \
                Motor Current",
        origin: "Seoul National University and University of Seoul, Korea",
        takes: "the Martelotti force model, the spindle current's RMS as force, the gear \
                change, threshold-proportional control, the depth-step and taper experiments",
    },
    Paper {
        number: "004",
        authors: "Xiaolong Shen, Meilin Li, Nanlin Yu",
        title: "Research of Absolute Sensorless Cutting Force Induced Error Compensation System",
        origin: "Hunan Industry Polytechnic and Hunan Urban Construction College, China",
        takes: "the power-law force model learned as a network, its sensor failure prediction, \
                the cutting-force-induced error and its compensation",
    },
];

/// Scrolls to the entry the hash's sub-path names (`#/home/paper-003`: every "paper 00x" in the
/// lab links there, [`crate::web::components::paper_link`]).
fn show_linked_entry() {
    let hash = window().location().hash().unwrap_or_default();
    if let Some(entry) = sub_path(&hash).and_then(|id| document().get_element_by_id(id)) {
        entry.scroll_into_view();
    }
}

/// The home page.
#[component]
pub fn HomePage() -> impl IntoView {
    Effect::new(move |_| show_linked_entry());
    let handle = window_event_listener(leptos::ev::hashchange, move |_| show_linked_entry());
    on_cleanup(move || handle.remove());
    let loop_blocks = LOOP
        .iter()
        .map(|block| {
            view! {
                <li class="loop-block">
                    <a href=block.href>
                        <strong>{block.name}</strong>
                        <span class="loop-does">{block.does}</span>
                    </a>
                </li>
            }
        })
        .collect_view();
    let papers = PAPERS
        .iter()
        .map(|p| {
            view! {
                <li id=format!("paper-{}", p.number)>
                    <strong>{format!("Paper {}. ", p.number)}</strong>
                    {format!("{}: ", p.authors)}
                    <cite>{p.title}</cite>
                    {format!(". {}.", p.origin)}
                    <span class="paper-takes">{format!(" The lab takes {}.", p.takes)}</span>
                </li>
            }
        })
        .collect_view();
    view! {
        <PageShell id="home" title="cutlab: adaptive cutting-force control of CNC milling" class="home">
            <p class="lede">
                "The force on a milling cutter decides how fast a part can be cut and whether the \
                 tool breaks. cutlab measures that force without a dynamometer, from the motor \
                 currents the machine already has, and lets a controller adjust the feed override \
                 to hold it at a target: on a simulated machine, on your own logs, or on a real \
                 machine connected to this browser."
            </p>
            <section aria-labelledby="home-loop">
                <h2 id="home-loop">"The loop"</h2>
                <p class="hint">"Each block opens the page that shows it."</p>
                <ol class="loop-picture" aria-label="The force-control loop">
                    {loop_blocks}
                </ol>
            </section>
            <section aria-labelledby="home-start">
                <h2 id="home-start">"Where to start"</h2>
                <ul class="start-points">
                    <li>
                        <a href=Page::Learn.href()>"Learn the ideas"</a>
                        " — current as a force sensor, filtering, calibration and the controllers, \
                         step by step with the papers' equations; then "
                        <a href=Page::Lessons.href()>"take a guided lesson"</a>
                        ", whose tasks on the lab are checked as your runs finish."
                    </li>
                    <li>
                        <a href="#/simulate?preset=kim-step-doc">"Simulate a paper's experiment"</a>
                        " — paper 003's depth steps on a simulated FANUC mill: the force, the \
                         override and what the controller saved."
                    </li>
                    <li>
                        <a href=Page::Logs.href()>"Bring your own log"</a>
                        " or "
                        <a href=Page::Hardware.href()>"connect your machine"</a>
                        " — analyse and replay a CSV log, or run the loop on a real machine over \
                         WebSerial behind the same safety envelope."
                    </li>
                </ul>
            </section>
            <section aria-labelledby="home-papers">
                <h2 id="home-papers">"The papers"</h2>
                <p class="hint">"Where the lab says \"paper 00x\", it means:"</p>
                <ol class="papers">{papers}</ol>
            </section>
        </PageShell>
    }
}
