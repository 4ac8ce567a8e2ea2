//! Learn: a short guided path through the idea, with the papers' key equations and "try it"
//! links that open the other pages with the right preset.
//!
//! The equations are static MathML written here (no user input reaches `inner_html`), which
//! every current browser renders natively and screen readers read as mathematics.

use leptos::prelude::*;

/// One step of the guided path.
struct Lesson {
    id: &'static str,
    title: &'static str,
    paragraphs: &'static [&'static str],
    equations: &'static [(&'static str, &'static str)],
    try_it: &'static [(&'static str, &'static str)],
}

const LESSONS: &[Lesson] = &[
    Lesson {
        id: "why-current",
        title: "1. Why measure force through motor current",
        paragraphs: &[
            "Too much force breaks the cutter; too little wastes time. A dynamometer measures the \
             force directly, but it is expensive, limits the workpiece size and gets in the way. \
             The machine already measures something that follows the force: the current of the \
             motors that push the table and turn the spindle.",
            "In steady state the feed motor's torque balances guide friction, ball-screw preload \
             and the cutting force carried through the screw (Wang et al., eq 3). A permanent-magnet \
             servo's torque is proportional to its q-axis current (eq 8). Together: the feed force \
             is a straight line in the current, with an offset for friction — the idle current.",
        ],
        equations: &[
            (
                "Feed-drive torque balance (paper 000, eq 3)",
                r#"<math display="block"><msub><mi>T</mi><mi>m</mi></msub><mo>=</mo><mfrac><msub><mi>L</mi><mn>0</mn></msub><mrow><mn>2</mn><mi>π</mi><mi>η</mi></mrow></mfrac><mrow><mo>[</mo><msub><mi>F</mi><mn>0</mn></msub><mo>+</mo><msub><mi>F</mi><mrow><mi>p</mi><mn>0</mn></mrow></msub><mo>(</mo><mn>1</mn><mo>−</mo><msubsup><mi>η</mi><mn>0</mn><mn>2</mn></msubsup><mo>)</mo><mo>+</mo><msub><mi>F</mi><mi>c</mi></msub><mo>]</mo></mrow></math>"#,
            ),
            (
                "PMSM torque with i_d = 0 (paper 000, eq 8)",
                r#"<math display="block"><msub><mi>T</mi><mi>m</mi></msub><mo>=</mo><mfrac><mn>3</mn><mn>2</mn></mfrac><mi>p</mi><msub><mi>λ</mi><mi>m</mi></msub><msub><mi>i</mi><mi>q</mi></msub></math>"#,
            ),
        ],
        try_it: &[("The brake bench: current against load", "#/plant?preset=wang-brake-bench")],
    },
    Lesson {
        id: "signal-chain",
        title: "2. From phase currents to a force: the signal chain",
        paragraphs: &[
            "A Hall sensor turns each phase current into a small current through a burden \
             resistor (6 A in, 25 mA out, into 500 Ω), an ADC samples it at 10 kHz. The raw \
             current carries the supply frequency, its harmonics and switching noise, so it is \
             low-pass filtered — Wang et al. use a 10th-order Butterworth filter, which must be \
             computed as second-order sections to stay stable.",
            "The three filtered phases give one RMS value (Kim et al., eq 7). For a balanced set \
             it is steady — the amplitude over √2 — so it follows the load without the 50 Hz \
             ripple of a single phase. Kim et al. take its peak over each spindle revolution and \
             map it to the peak cutting force with a straight line calibrated in a teach cut.",
        ],
        equations: &[(
            "Three-phase RMS current (paper 003, eq 7)",
            r#"<math display="block"><msub><mi>I</mi><mi>rms</mi></msub><mo>=</mo><msqrt><mfrac><mrow><msubsup><mi>I</mi><mi>u</mi><mn>2</mn></msubsup><mo>+</mo><msubsup><mi>I</mi><mi>v</mi><mn>2</mn></msubsup><mo>+</mo><msubsup><mi>I</mi><mi>w</mi><mn>2</mn></msubsup></mrow><mn>3</mn></mfrac></msqrt></math>"#,
        )],
        try_it: &[("Design the filter", "#/signal")],
    },
    Lesson {
        id: "cutting-force",
        title: "3. What the cutter feels",
        paragraphs: &[
            "Each tooth cuts a chip whose thickness grows and shrinks with its angle: h = S_f·sin φ \
             for a feed per tooth S_f. The tangential force is the chip area times the material's \
             specific cutting pressure; the radial force is a fixed fraction of it (Martelotti's \
             model, used by Kim et al.). The spindle torque is the tangential force times the \
             cutter radius, so the peak force per tooth is proportional to the peak torque — \
             which is why the spindle current can stand in for the force.",
            "Doubling the feed doubles the chip and so roughly the force: the feed override is \
             the one knob that acts on the force without touching the part program.",
        ],
        equations: &[
            (
                "Martelotti's chip-thickness force model (paper 003, eq 1–3)",
                r#"<math display="block"><msub><mi>F</mi><mi>T</mi></msub><mo>=</mo><msub><mi>K</mi><mi>T</mi></msub><mi>a</mi><msub><mi>S</mi><mi>f</mi></msub><mi>sin</mi><mi>φ</mi><mo>,</mo><mspace width="1em"/><msub><mi>F</mi><mi>R</mi></msub><mo>=</mo><mi>r</mi><msub><mi>F</mi><mi>T</mi></msub><mo>,</mo><mspace width="1em"/><msub><mi>T</mi><mi>c</mi></msub><mo>=</mo><mi>R</mi><msub><mi>F</mi><mi>T</mi></msub></math>"#,
            ),
            (
                "Peak force from peak torque (paper 003, eq 6)",
                r#"<math display="block"><msub><mi>F</mi><mrow><mi>c</mi><mo>,</mo><mi>max</mi></mrow></msub><mo>=</mo><mfrac><msqrt><mrow><mn>1</mn><mo>+</mo><msup><mi>r</mi><mn>2</mn></msup></mrow></msqrt><mi>R</mi></mfrac><msub><mi>T</mi><mrow><mi>c</mi><mo>,</mo><mi>max</mi></mrow></msub></math>"#,
            ),
        ],
        try_it: &[("Forces of a depth-step cut", "#/plant?preset=kim-step-doc")],
    },
    Lesson {
        id: "controllers",
        title: "4. Closing the loop",
        paragraphs: &[
            "Current restriction (Wang et al.): an upper and a lower limit; above the upper the \
             override steps down, below the lower it steps up. Simple, and exactly what many \
             commercial controls offer.",
            "Threshold-proportional (Kim et al.): the same band, but the step is proportional to \
             how far the force is beyond it; too narrow a band or too high a gain and the loop \
             oscillates.",
            "Fuzzy (Liu et al.): the error E and its change EC are sorted into seven sets each, \
             49 rules give a feed change. Rules from experience react hard; rules shaped by the \
             machine's dynamics react softer and settle faster.",
            "Lyapunov adaptive (Maneerat et al.): a sliding variable combines the force error and \
             its rate; an adaptive gain learns which feed gives the target force, so the loop \
             holds it without knowing the material in advance.",
            "Whatever the controller, a safety envelope sits after it: override limits, a rate \
             limit, the machine's dial positions, an arming delay after spindle start, sensor-fault \
             detection and an overload feed hold.",
        ],
        equations: &[(
            "Sliding variable and adaptive law (paper 001, eq 5)",
            r#"<math display="block"><mi>E</mi><mo>=</mo><mfrac><mrow><mi>d</mi><mover><mi>F</mi><mo>~</mo></mover></mrow><mrow><mi>d</mi><mi>t</mi></mrow></mfrac><mo>+</mo><mi>λ</mi><mover><mi>F</mi><mo>~</mo></mover><mo>,</mo><mspace width="1em"/><msub><mi>f</mi><mi>r</mi></msub><mo>=</mo><mover><mi>β</mi><mo>^</mo></mover><msub><mi>F</mi><mi>d</mi></msub><mo>−</mo><msub><mi>K</mi><mi>d</mi></msub><mi>E</mi><mo>,</mo><mspace width="1em"/><mover><mover><mi>β</mi><mo>^</mo></mover><mo>˙</mo></mover><mo>=</mo><mo>−</mo><msub><mi>γ</mi><mn>3</mn></msub><msub><mi>F</mi><mi>d</mi></msub><mi>E</mi></math>"#,
        )],
        try_it: &[("Fixed feed against threshold control", "#/compare?preset=kim-step-doc&variants=2&a.controller=fixed&b.controller=threshold"), ("Adaptive control at 320 N", "#/simulate?preset=maneerat-doc-4&controller=mrac"), ("Edit the fuzzy rules", "#/fuzzy")],
    },
];

/// The Learn page.
#[component]
pub fn LearnPage() -> impl IntoView {
    // `#/learn/<lesson>` scrolls to that lesson, also when the link is followed on this page.
    let scroll_to_lesson = || {
        let hash = window().location().hash().unwrap_or_default();
        if let Some(id) = crate::web::route::sub_path(&hash) {
            if let Some(element) = document().get_element_by_id(id) {
                element.scroll_into_view();
            }
        }
    };
    Effect::new(move |_| scroll_to_lesson());
    let handle = window_event_listener(leptos::ev::hashchange, move |_| scroll_to_lesson());
    on_cleanup(move || handle.remove());
    view! {
        <section class="page learn" aria-labelledby="learn-title">
            <h1 id="learn-title">"Learn: cutting force from motor current"</h1>
            <p class="lede">
                "Four short steps from the cutter to the controller. Each ends with a link that opens "
                "the lab where you can try it."
            </p>
            <nav aria-label="Lessons" class="lesson-index">
                <ol>
                    {LESSONS
                        .iter()
                        .map(|l| view! { <li><a href=format!("#/learn/{}", l.id)>{l.title}</a></li> })
                        .collect_view()}
                </ol>
            </nav>
            {LESSONS
                .iter()
                .map(|l| {
                    view! {
                        <article class="lesson" id=l.id aria-labelledby=format!("{}-title", l.id)>
                            <h2 id=format!("{}-title", l.id)>{l.title}</h2>
                            {l.paragraphs.iter().map(|p| view! { <p>{*p}</p> }).collect_view()}
                            {l
                                .equations
                                .iter()
                                .map(|(caption, mathml)| {
                                    view! {
                                        <figure class="equation">
                                            <div inner_html=*mathml></div>
                                            <figcaption>{*caption}</figcaption>
                                        </figure>
                                    }
                                })
                                .collect_view()}
                            {(!l.try_it.is_empty())
                                .then(|| {
                                    view! {
                                        <p class="try-it">
                                            {l
                                                .try_it
                                                .iter()
                                                .map(|(text, href)| {
                                                    view! { <a class="button-link" href=*href>{"Try it: "}{*text}</a> }
                                                })
                                                .collect_view()}
                                        </p>
                                    }
                                })}
                        </article>
                    }
                })
                .collect_view()}
        </section>
    }
}
