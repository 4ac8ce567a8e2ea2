//! Learn: a short guided path through the idea, with the papers' key equations and "try it"
//! links that open the other pages with the right preset.
//!
//! The equations are static MathML written here (no user input reaches `inner_html`), which
//! every current browser renders natively and screen readers read as mathematics.

use leptos::prelude::*;

use crate::control::fuzzy::rules::RuleBase;
use crate::web::components::page::PageShell;
use crate::web::components::paper_link::WithPaperLinks;
use crate::web::components::run_form::encode_rule_table;
use crate::web::route::{hash_with_query, Page};

/// One step of the guided path.
struct PathStep {
    id: &'static str,
    title: &'static str,
    paragraphs: &'static [&'static str],
    /// `(caption, MathML)`.
    equations: &'static [(&'static str, &'static str)],
    /// `(link text, where it leads)`.
    try_it: &'static [(&'static str, TryIt)],
}

/// Where a "try it" link leads: always a page preset to what the lesson talks about.
enum TryIt {
    /// A hash with its query, e.g. `#/signal?preset=wang-10th-5hz`.
    Hash(&'static str),
    /// The Fuzzy rules page showing one of paper 002's built-in rule tables.
    FuzzyRules(RuleBase),
}

impl TryIt {
    fn href(&self) -> String {
        match self {
            TryIt::Hash(hash) => hash.to_string(),
            TryIt::FuzzyRules(base) => hash_with_query(
                Page::Fuzzy,
                &[("rules".to_string(), encode_rule_table(&base.table()))],
            ),
        }
    }
}

const LESSONS: &[PathStep] = &[
    PathStep {
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
                "Feed-drive torque balance (paper 000, eq 3): T_m is the motor torque, L₀ the \
                 ball screw's lead, η the screw's efficiency (η₀ its preload's), F₀ the guides' \
                 friction, F_p0 the screw's preload and F_c the cutting force along the axis",
                r#"<math display="block"><msub><mi>T</mi><mi>m</mi></msub><mo>=</mo><mfrac><msub><mi>L</mi><mn>0</mn></msub><mrow><mn>2</mn><mi>π</mi><mi>η</mi></mrow></mfrac><mrow><mo>[</mo><msub><mi>F</mi><mn>0</mn></msub><mo>+</mo><msub><mi>F</mi><mrow><mi>p</mi><mn>0</mn></mrow></msub><mo>(</mo><mn>1</mn><mo>−</mo><msubsup><mi>η</mi><mn>0</mn><mn>2</mn></msubsup><mo>)</mo><mo>+</mo><msub><mi>F</mi><mi>c</mi></msub><mo>]</mo></mrow></math>"#,
            ),
            (
                "PMSM torque with i_d = 0 (paper 000, eq 8): p is the motor's pole pairs, λ_m the \
                 magnets' flux linkage and i_q the torque-producing (q-axis) current",
                r#"<math display="block"><msub><mi>T</mi><mi>m</mi></msub><mo>=</mo><mfrac><mn>3</mn><mn>2</mn></mfrac><mi>p</mi><msub><mi>λ</mi><mi>m</mi></msub><msub><mi>i</mi><mi>q</mi></msub></math>"#,
            ),
        ],
        try_it: &[(
            "The brake bench: current against load",
            TryIt::Hash("#/plant?preset=wang-brake-bench"),
        )],
    },
    PathStep {
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
            "Three-phase RMS current (paper 003, eq 7): I_u, I_v and I_w are the filtered \
             currents of the motor's three phases at one instant",
            r#"<math display="block"><msub><mi>I</mi><mi>rms</mi></msub><mo>=</mo><msqrt><mrow><mo>(</mo><msubsup><mi>I</mi><mi>u</mi><mn>2</mn></msubsup><mo>+</mo><msubsup><mi>I</mi><mi>v</mi><mn>2</mn></msubsup><mo>+</mo><msubsup><mi>I</mi><mi>w</mi><mn>2</mn></msubsup><mo>)</mo><mo>/</mo><mn>3</mn></mrow></msqrt></math>"#,
        )],
        try_it: &[
            (
                "Paper 000's 10th-order Butterworth low-pass",
                TryIt::Hash("#/signal?preset=wang-10th-5hz"),
            ),
            (
                "Paper 003's spindle-current filter",
                TryIt::Hash("#/signal?preset=kim-spindle-260hz"),
            ),
        ],
    },
    PathStep {
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
                "Martelotti's chip-thickness force model (paper 003, eq 1–3): F_T and F_R are one \
                 tooth's tangential and radial forces, K_T the material's specific cutting \
                 pressure, a the depth of cut, S_f the feed per tooth, φ the tooth's angle, r the \
                 radial-to-tangential ratio, R the cutter's radius and T_c the cutting torque",
                r#"<math display="block"><msub><mi>F</mi><mi>T</mi></msub><mo>=</mo><msub><mi>K</mi><mi>T</mi></msub><mi>a</mi><msub><mi>S</mi><mi>f</mi></msub><mi>sin</mi><mi>φ</mi><mo>,</mo><mspace width="1em"/><msub><mi>F</mi><mi>R</mi></msub><mo>=</mo><mi>r</mi><msub><mi>F</mi><mi>T</mi></msub><mo>,</mo><mspace width="1em"/><msub><mi>T</mi><mi>c</mi></msub><mo>=</mo><mi>R</mi><msub><mi>F</mi><mi>T</mi></msub></math>"#,
            ),
            (
                "Peak force from peak torque (paper 003, eq 6): the largest resultant force \
                 F_c,max follows from the largest cutting torque T_c,max, with r and R as above",
                r#"<math display="block"><msub><mi>F</mi><mrow><mi>c</mi><mo>,</mo><mi>max</mi></mrow></msub><mo>=</mo><mfrac><msqrt><mrow><mn>1</mn><mo>+</mo><msup><mi>r</mi><mn>2</mn></msup></mrow></msqrt><mi>R</mi></mfrac><msub><mi>T</mi><mrow><mi>c</mi><mo>,</mo><mi>max</mi></mrow></msub></math>"#,
            ),
        ],
        try_it: &[(
            "Forces of a depth-step cut",
            TryIt::Hash("#/plant?preset=kim-step-doc"),
        )],
    },
    PathStep {
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
            "PI with anti-windup (the textbook baseline, not from the papers): a proportional and \
             an integral term on the relative force error. When the safety envelope clamps, \
             rate-limits or quantises the request, back-calculation pulls the integral toward \
             what was actually applied instead of letting it wind up.",
            "Lyapunov adaptive (Maneerat et al.): a sliding variable combines the force error and \
             its rate; an adaptive gain learns which feed gives the target force, so the loop \
             holds it without knowing the material in advance.",
            "Whatever the controller, a safety envelope sits after it: override limits, a rate \
             limit, the machine's dial positions, an arming delay after spindle start, sensor-fault \
             detection and an overload feed hold.",
        ],
        equations: &[
            (
                "Current restriction (paper 000, §1 and §5): one step Δ of the override dial (10 %) \
                 down above the band, up below it, from the override u_a the machine applied; b is \
                 the band's width relative to the target F_t",
                r#"<math display="block"><mi>u</mi><mo>←</mo><mrow><mo>{</mo><mtable columnalign="left left"><mtr><mtd><msub><mi>u</mi><mi>a</mi></msub><mo>−</mo><mi>Δ</mi></mtd><mtd><mtext>if</mtext><mspace width="0.5em"/><mi>F</mi><mo>&gt;</mo><msub><mi>F</mi><mi>t</mi></msub><mo>(</mo><mn>1</mn><mo>+</mo><mi>b</mi><mo>/</mo><mn>2</mn><mo>)</mo></mtd></mtr><mtr><mtd><msub><mi>u</mi><mi>a</mi></msub><mo>+</mo><mi>Δ</mi></mtd><mtd><mtext>if</mtext><mspace width="0.5em"/><mi>F</mi><mo>&lt;</mo><msub><mi>F</mi><mi>t</mi></msub><mo>(</mo><mn>1</mn><mo>−</mo><mi>b</mi><mo>/</mo><mn>2</mn><mo>)</mo></mtd></mtr><mtr><mtd><msub><mi>u</mi><mi>a</mi></msub></mtd><mtd><mtext>otherwise</mtext></mtd></mtr></mtable></mrow></math>"#,
            ),
            (
                "Threshold-proportional control (paper 003, §8 and Fig. 9): the step is K_p times the \
                 excess beyond the band, in percent of the target F_t; g is the band's width \
                 relative to F_t, and the override also holds for 3 s after spindle start",
                r#"<math display="block"><mi>u</mi><mo>←</mo><mrow><mo>{</mo><mtable columnalign="left left"><mtr><mtd><msub><mi>u</mi><mi>a</mi></msub><mo>−</mo><msub><mi>K</mi><mi>p</mi></msub><mo>·</mo><mn>100</mn><mo>·</mo><mfrac><mrow><mi>F</mi><mo>−</mo><msub><mi>F</mi><mi>max</mi></msub></mrow><msub><mi>F</mi><mi>t</mi></msub></mfrac></mtd><mtd><mtext>if</mtext><mspace width="0.5em"/><mi>F</mi><mo>&gt;</mo><msub><mi>F</mi><mi>max</mi></msub></mtd></mtr><mtr><mtd><msub><mi>u</mi><mi>a</mi></msub><mo>+</mo><msub><mi>K</mi><mi>p</mi></msub><mo>·</mo><mn>100</mn><mo>·</mo><mfrac><mrow><msub><mi>F</mi><mi>min</mi></msub><mo>−</mo><mi>F</mi></mrow><msub><mi>F</mi><mi>t</mi></msub></mfrac></mtd><mtd><mtext>if</mtext><mspace width="0.5em"/><mi>F</mi><mo>&lt;</mo><msub><mi>F</mi><mi>min</mi></msub></mtd></mtr><mtr><mtd><msub><mi>u</mi><mi>a</mi></msub></mtd><mtd><mtext>otherwise</mtext></mtd></mtr></mtable></mrow><mo>,</mo><mspace width="1em"/><msub><mi>F</mi><mrow><mi>max</mi><mo>,</mo><mi>min</mi></mrow></msub><mo>=</mo><msub><mi>F</mi><mi>t</mi></msub><mo>(</mo><mn>1</mn><mo>±</mo><mi>g</mi><mo>/</mo><mn>2</mn><mo>)</mo></math>"#,
            ),
            (
                "Incremental fuzzy feed law (paper 002, eq 6): k_e and k_ec scale E and EC onto the \
                 universe [−6, 6] (saturated there), k_u scales the fuzzy output U to a feed change; \
                 a_f(i) is the feed the machine applied, as an override",
                r#"<math display="block"><mtable columnalign="left"><mtr><mtd><mi>E</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>=</mo><msub><mi>F</mi><mi>t</mi></msub><mo>−</mo><mi>F</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>,</mo><mspace width="1em"/><mi>EC</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>=</mo><mi>E</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>−</mo><mi>E</mi><mo>(</mo><mi>i</mi><mo>−</mo><mn>1</mn><mo>)</mo><mo>,</mo></mtd></mtr><mtr><mtd><msub><mi>a</mi><mi>f</mi></msub><mo>(</mo><mi>i</mi><mo>+</mo><mn>1</mn><mo>)</mo><mo>=</mo><msub><mi>a</mi><mi>f</mi></msub><mo>(</mo><mi>i</mi><mo>)</mo><mo>+</mo><mi>Δ</mi><msub><mi>a</mi><mi>f</mi></msub><mo>,</mo><mspace width="1em"/><mi>Δ</mi><msub><mi>a</mi><mi>f</mi></msub><mo>=</mo><msub><mi>k</mi><mi>u</mi></msub><mi>U</mi><mo>(</mo><msub><mi>k</mi><mi>e</mi></msub><mi>E</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>,</mo><msub><mi>k</mi><mi>ec</mi></msub><mi>EC</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>)</mo></mtd></mtr></mtable></math>"#,
            ),
            (
                "Weighted-average defuzzification (paper 002, eq 7; what the closed loop uses) over \
                 the 49 rules j: H_j is rule j's activation, the minimum of its two memberships, and Δa_fj \
                 the centre of its output term",
                r#"<math display="block"><mi>U</mi><mo>=</mo><mfrac><mrow><munder><mo>∑</mo><mi>j</mi></munder><mi>Δ</mi><msub><mi>a</mi><mrow><mi>f</mi><mi>j</mi></mrow></msub><msub><mi>H</mi><mi>j</mi></msub></mrow><mrow><munder><mo>∑</mo><mi>j</mi></munder><msub><mi>H</mi><mi>j</mi></msub></mrow></mfrac></math>"#,
            ),
            (
                "Centroid defuzzification (a choice on the Fuzzy rules page, computed exactly): each \
                 rule clips its output term μ_j at H_j, and the maximum of them is the output set μ_U",
                r#"<math display="block"><mi>U</mi><mo>=</mo><mfrac><mrow><mo>∫</mo><mi>u</mi><msub><mi>μ</mi><mi>U</mi></msub><mo>(</mo><mi>u</mi><mo>)</mo><mrow><mi>d</mi><mi>u</mi></mrow></mrow><mrow><mo>∫</mo><msub><mi>μ</mi><mi>U</mi></msub><mo>(</mo><mi>u</mi><mo>)</mo><mrow><mi>d</mi><mi>u</mi></mrow></mrow></mfrac><mo>,</mo><mspace width="1em"/><msub><mi>μ</mi><mi>U</mi></msub><mo>(</mo><mi>u</mi><mo>)</mo><mo>=</mo><munder><mi>max</mi><mi>j</mi></munder><mi>min</mi><mo>(</mo><msub><mi>H</mi><mi>j</mi></msub><mo>,</mo><msub><mi>μ</mi><mi>j</mi></msub><mo>(</mo><mi>u</mi><mo>)</mo><mo>)</mo></math>"#,
            ),
            (
                "PI with back-calculation anti-windup (Åström & Hägglund), stepped once per control \
                 period T: what the envelope and the machine took from the last request, \
                 u_a(i) − u_req(i−1), pulls the integral back with time constant T_t",
                r#"<math display="block"><mtable columnalign="left"><mtr><mtd><mi>e</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>=</mo><mfrac><mrow><msub><mi>F</mi><mi>t</mi></msub><mo>−</mo><mi>F</mi><mo>(</mo><mi>i</mi><mo>)</mo></mrow><msub><mi>F</mi><mi>t</mi></msub></mfrac><mo>,</mo><mspace width="1em"/><msub><mi>u</mi><mi>req</mi></msub><mo>(</mo><mi>i</mi><mo>)</mo><mo>=</mo><msub><mi>u</mi><mn>0</mn></msub><mo>+</mo><msub><mi>K</mi><mi>p</mi></msub><mo>·</mo><mn>100</mn><mo>·</mo><mi>e</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>+</mo><mi>I</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>,</mo></mtd></mtr><mtr><mtd><mi>I</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>=</mo><mi>I</mi><mo>(</mo><mi>i</mi><mo>−</mo><mn>1</mn><mo>)</mo><mo>+</mo><mi>T</mi><mrow><mo>[</mo><msub><mi>K</mi><mi>i</mi></msub><mo>·</mo><mn>100</mn><mo>·</mo><mi>e</mi><mo>(</mo><mi>i</mi><mo>)</mo><mo>+</mo><mfrac><mrow><msub><mi>u</mi><mi>a</mi></msub><mo>(</mo><mi>i</mi><mo>)</mo><mo>−</mo><msub><mi>u</mi><mi>req</mi></msub><mo>(</mo><mi>i</mi><mo>−</mo><mn>1</mn><mo>)</mo></mrow><msub><mi>T</mi><mi>t</mi></msub></mfrac><mo>]</mo></mrow></mtd></mtr></mtable></math>"#,
            ),
            (
                "Sliding variable and adaptive law (paper 001, eq 5): F̃ is the force error, λ \
                 how fast the sliding variable E asks it to decay, f_r the commanded feed, F_d the \
                 target force, K_d the PD gain, β̂ the estimate of the process's steady-state \
                 coefficient β = d·c (how much feed a force takes), learned as the cut goes, and \
                 γ₃ its learning rate",
                r#"<math display="block"><mi>E</mi><mo>=</mo><mfrac><mrow><mi>d</mi><mover><mi>F</mi><mo>~</mo></mover></mrow><mrow><mi>d</mi><mi>t</mi></mrow></mfrac><mo>+</mo><mi>λ</mi><mover><mi>F</mi><mo>~</mo></mover><mo>,</mo><mspace width="1em"/><msub><mi>f</mi><mi>r</mi></msub><mo>=</mo><mover><mi>β</mi><mo>^</mo></mover><msub><mi>F</mi><mi>d</mi></msub><mo>−</mo><msub><mi>K</mi><mi>d</mi></msub><mi>E</mi><mo>,</mo><mspace width="1em"/><mover><mover><mi>β</mi><mo>^</mo></mover><mo>˙</mo></mover><mo>=</mo><mo>−</mo><msub><mi>γ</mi><mn>3</mn></msub><msub><mi>F</mi><mi>d</mi></msub><mi>E</mi></math>"#,
            ),
        ],
        try_it: &[
            (
                "Current restriction against threshold control",
                TryIt::Hash(
                    "#/compare?preset=kim-step-doc&variants=2&a.controller=restriction&b.controller=threshold",
                ),
            ),
            (
                "Fixed feed against threshold control",
                TryIt::Hash(
                    "#/compare?preset=kim-step-doc&variants=2&a.controller=fixed&b.controller=threshold",
                ),
            ),
            (
                "Edit the dynamics-based fuzzy rules",
                TryIt::FuzzyRules(RuleBase::Dynamics),
            ),
            (
                "Experience-based against dynamics-based fuzzy rules",
                TryIt::Hash(
                    "#/compare?preset=liu-current-step&variants=2&a.controller=fuzzy-experience&b.controller=fuzzy-dynamics",
                ),
            ),
            (
                "PI with anti-windup over depth steps",
                TryIt::Hash("#/simulate?preset=kim-step-doc&controller=pi"),
            ),
            (
                "Adaptive control at 320 N",
                TryIt::Hash("#/simulate?preset=maneerat-doc-4&controller=mrac"),
            ),
        ],
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
        <PageShell id="learn" title="Learn: cutting force from motor current" class="learn">
            <p class="lede">
                "Four short steps from the cutter to the controller. Each ends with a link that opens "
                "the lab where you can try it. The "
                <a href=Page::Lessons.href()>"lessons"</a>
                " then set you tasks on the lab and check your runs."
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
                            {l.paragraphs.iter().map(|p| view! { <p><WithPaperLinks text=*p /></p> }).collect_view()}
                            {l
                                .equations
                                .iter()
                                .map(|(caption, mathml)| {
                                    view! {
                                        <figure class="equation" tabindex="0">
                                            <div inner_html=*mathml></div>
                                            <figcaption><WithPaperLinks text=*caption /></figcaption>
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
                                                .map(|(text, target)| {
                                                    view! { <a class="button-link" href=target.href()>{"Try it: "}{*text}</a> }
                                                })
                                                .collect_view()}
                                        </p>
                                    }
                                })}
                        </article>
                    }
                })
                .collect_view()}
        </PageShell>
    }
}
