//! Fuzzy rules: paper 002's membership functions, the 7×7 rule table (editable), the control
//! surface U(E, EC), a rule viewer for a chosen (E, EC) or a moment of a simulated run, and FLL
//! import and export.
//!
//! | file | panel |
//! |---|---|
//! | `mod.rs` | the page: the engine studied, from the table or an imported FLL |
//! | `table.rs` | the rule table, the rule bases and the defuzzifier |
//! | `viewer.rs` | the rules that fire at a chosen (E, EC) |
//! | `moment.rs` | a simulated run with the table, and the moment picked on it |
//! | `fll.rs` | FLL and FIS export and import |
//! | `engine.rs` | any engine's variables, terms and rules, and the links that run it as the loop's controller |
//! | `charts.rs` | the control surface, the run's inputs and the membership functions |
//! | [`table`] | the 7×7 rule table, cell by cell, with the rule bases one click away |
//! | [`charts`] | the control surface U(E, EC) and the run's E and EC |
//! | [`viewer`] | the rule viewer: the output and the rules that fire for a chosen E and EC |
//! | [`moment`] | a moment of a simulated run, chosen with a slider |
//! | [`fll`] | FLL (fuzzylite) and FIS (MATLAB) export and import
//! | [`engine`] | the engine whole: variables, terms, rules; "Use in Simulate/Compare" |

mod charts;
mod engine;
mod fll;
mod moment;
mod table;
mod viewer;

use std::sync::Arc;

use leptos::prelude::*;

use crate::control::fuzzy::engine::{Defuzzifier, Engine};
use crate::control::fuzzy::fll as fuzzylite;
use crate::control::fuzzy::rules::{paper_002_engine, paper_002_table, RuleBase, RuleTable};
use crate::control::registry::PAPER_002_DEFUZZIFIER;
use crate::web::components::fields::parse_number;
use crate::web::components::later::{effect_after_mount, Later};
use crate::web::components::page::PageShell;
use crate::web::components::run_form::{decode_rule_table, encode_rule_table};
use crate::web::route::{hash_with_query, query_params, replace_query, Page};
use charts::FuzzyCharts;
use engine::EnginePanel;
use fll::FllPanel;
use moment::{RunMoment, RunMomentPanel};
use table::RuleTablePanel;
use viewer::RuleViewer;

/// The engine being studied: paper 002's with an editable table, or one imported from FLL with
/// the reason it is not such a table.
#[derive(Clone)]
enum Source {
    Table,
    Imported(Arc<Engine>, String),
}

/// The output at the viewer's point and the rules that fire there, with their strengths.
type Firing = (f64, Vec<(usize, f64)>);

/// What the panels share: the table, the engine made of it and the viewer's point.
#[derive(Clone, Copy)]
struct Fuzzy {
    table: RwSignal<RuleTable>,
    defuzzifier: RwSignal<String>,
    source: RwSignal<Source>,
    /// The engine text (FLL or FIS) in the import field, as typed or read from a file.
    engine_text: RwSignal<String>,
    /// Why the last import (or the link's engine) was refused.
    import_error: RwSignal<Option<String>>,
    e_text: RwSignal<String>,
    ec_text: RwSignal<String>,
    /// The engine studied, whatever its shape.
    studied: Memo<Result<Arc<Engine>, String>>,
    /// The engine studied if it has two inputs (the rule viewer's and the surface's).
    engine: Memo<Result<Arc<Engine>, String>>,
    viewer: Memo<Option<Firing>>,
}

impl Fuzzy {
    fn new(table: RuleTable) -> Self {
        let table = RwSignal::new(table);
        let defuzzifier = RwSignal::new(PAPER_002_DEFUZZIFIER.name().to_string());
        let source = RwSignal::new(Source::Table);
        let e_text = RwSignal::new("2".to_string());
        let ec_text = RwSignal::new("-1".to_string());
        let studied = Memo::new(move |_| -> Result<Arc<Engine>, String> {
            let d = chosen(&defuzzifier.get());
            match source.get() {
                Source::Table => paper_002_engine(&table.get(), d)
                    .map(Arc::new)
                    .map_err(|e| e.to_string()),
                Source::Imported(engine, _) => {
                    let mut e = (*engine).clone();
                    e.set_defuzzifier(d);
                    Ok(Arc::new(e))
                }
            }
        });
        let engine = Memo::new(move |_| {
            studied.get().and_then(|e| {
                if e.inputs().len() == 2 && !e.outputs().is_empty() {
                    Ok(e)
                } else {
                    Err("the rule viewer and surface need an engine with two inputs".to_string())
                }
            })
        });
        let viewer = Memo::new(move |_| {
            let (Ok(e), Ok(ec)) = (parse_number(&e_text.get()), parse_number(&ec_text.get()))
            else {
                return None;
            };
            engine.with(|engine| {
                let mut engine = (**engine.as_ref().ok()?).clone();
                let mut out = vec![0.0; engine.outputs().len()];
                engine.evaluate(&[e, ec], &mut out);
                let firing: Vec<(usize, f64)> = engine
                    .activations()
                    .iter()
                    .copied()
                    .enumerate()
                    .filter(|(_, a)| *a > 0.0)
                    .collect();
                Some((out[0], firing))
            })
        });
        Self {
            table,
            defuzzifier,
            source,
            engine_text: RwSignal::new(String::new()),
            import_error: RwSignal::new(None),
            e_text,
            ec_text,
            studied,
            engine,
            viewer,
        }
    }

    /// Studies `engine`: paper 002's engine with some table comes into the editable table, any
    /// other is kept whole; the page shows the engine's own defuzzifier (changing it afterwards
    /// is a choice).
    fn study(&self, engine: Engine) {
        if let Some(output) = engine.outputs().first() {
            self.defuzzifier.set(output.defuzzifier.name().to_string());
        }
        match paper_002_table(&engine) {
            Ok(t) => {
                self.table.set(t);
                self.source.set(Source::Table);
            }
            Err(why) => self
                .source
                .set(Source::Imported(Arc::new(engine), why.to_string())),
        }
    }

    /// The page's link: the table (`rules=`), or the imported engine as FLL with the defuzzifier
    /// chosen (`engine=`, as Simulate's links carry one); the defuzzifier where not the default.
    /// Tracked.
    fn query(&self) -> Vec<(String, String)> {
        match self.source.get() {
            Source::Table => {
                let mut q = vec![("rules".to_string(), encode_rule_table(&self.table.get()))];
                let d = self.defuzzifier.get();
                if d != PAPER_002_DEFUZZIFIER.name() {
                    q.push(("defuzzifier".to_string(), d));
                }
                q
            }
            Source::Imported(..) => self
                .studied
                .with(|e| {
                    e.as_ref()
                        .ok()
                        .map(|e| fuzzylite::to_url_text(&fuzzylite::write(e)))
                })
                .map(|text| vec![("engine".to_string(), text)])
                .unwrap_or_default(),
        }
    }

    /// Takes the state a link (`query`) holds: its table or engine, its defuzzifier; an engine
    /// that does not read is reported beside the import field and the table kept.
    fn load(&self, query: &[(String, String)]) {
        let get = |key: &str| {
            query
                .iter()
                .find(|(k, _)| k == key)
                .map(|(_, v)| v.as_str())
        };
        if let Some(table) = get("rules").and_then(decode_rule_table) {
            self.table.set(table);
        }
        if let Some(text) = get("engine").map(fuzzylite::from_url_text) {
            match fuzzylite::parse(&text) {
                Ok(engine) => self.study(engine),
                Err(e) => self.import_error.set(Some(format!(
                    "The engine in the link could not be read: {e}"
                ))),
            }
            self.engine_text.set(text);
        }
        if let Some(d) = get("defuzzifier").filter(|d| Defuzzifier::from_name(d).is_some()) {
            self.defuzzifier.set(d.to_string());
        }
    }

    /// The defuzzifier chosen (tracked).
    fn chosen_defuzzifier(&self) -> Defuzzifier {
        chosen(&self.defuzzifier.get())
    }

    /// Whether the rule of cell (E level `e`, EC level `ec`) fires at the viewer's point.
    fn is_firing(&self, e: usize, ec: usize) -> bool {
        matches!(self.source.get(), Source::Table)
            && self.viewer.with(|v| {
                v.as_ref()
                    .is_some_and(|(_, f)| f.iter().any(|(r, _)| *r == e * 7 + ec))
            })
    }
}

/// The defuzzifier named `name` (the select's value, always one of [`Defuzzifier::ALL`]'s names;
/// paper 002's otherwise).
fn chosen(name: &str) -> Defuzzifier {
    Defuzzifier::from_name(name).unwrap_or(PAPER_002_DEFUZZIFIER)
}

/// This tab's storage of the page's last link and of the engine text in the import field: they
/// outlive a reload and a visit to another page (Simulate, with "Use in Simulate").
const STORED_LINK_KEY: &str = "cutlab.fuzzy.link";
/// See [`STORED_LINK_KEY`].
const STORED_TEXT_KEY: &str = "cutlab.fuzzy.engine-text";

fn stored(key: &str) -> Option<String> {
    let storage = window().session_storage().ok().flatten()?;
    storage.get_item(key).ok().flatten()
}

/// Keeps `value` under `key`; a browser that keeps nothing loses it with the page.
fn store(key: &str, value: &str) {
    if let Some(storage) = window().session_storage().ok().flatten() {
        let _ = storage.set_item(key, value);
    }
}

/// The Fuzzy rules page.
#[component]
pub fn FuzzyPage() -> impl IntoView {
    let mut query = query_params(&window().location().hash().unwrap_or_default());
    // A bare link (the menu's) opens what this tab last studied here.
    if query.is_empty() {
        query = stored(STORED_LINK_KEY)
            .map(|hash| query_params(&hash))
            .unwrap_or_default();
    }
    let fuzzy = Fuzzy::new(RuleBase::Dynamics.table());
    fuzzy.load(&query);
    // The text last typed (or read from a file) in this tab, imported or not, is kept too: it
    // is the student's, where the link's engine is only its written form.
    if let Some(text) = stored(STORED_TEXT_KEY).filter(|t| !t.trim().is_empty()) {
        fuzzy.engine_text.set(text);
    }
    effect_after_mount(move || {
        let query = fuzzy.query();
        store(STORED_LINK_KEY, &hash_with_query(Page::Fuzzy, &query));
        replace_query(Page::Fuzzy, &query);
    });
    Effect::new(move |_| fuzzy.engine_text.with(|text| store(STORED_TEXT_KEY, text)));
    let run = RunMoment::new(fuzzy);
    let run_for_charts = run.clone();
    view! {
        <PageShell id="fuzzy" title="Fuzzy rules">
            <p class="lede">
                "Paper 002's controller sorts the force error E and its change EC into seven sets each "
                "and looks up the feed change U in a 7×7 table. Edit the table cell by cell, see the "
                "control surface change, and watch which rules fire for an (E, EC) you choose or for "
                "a moment of a simulated run. Or import your own engine (fuzzylite's FLL or MATLAB's "
                "FIS): any engine of two inputs and one output runs as the loop's controller."
            </p>
            <div class="layout-fuzzy">
                <div class="panel">
                    <RuleTablePanel fuzzy=fuzzy />
                    <Later>
                        <RuleViewer fuzzy=fuzzy />
                    </Later>
                    <Later>
                        <RunMomentPanel fuzzy=fuzzy run=run.clone() />
                    </Later>
                    <Later>
                        <FllPanel fuzzy=fuzzy />
                    </Later>
                    <Later>
                        <EnginePanel fuzzy=fuzzy />
                    </Later>
                </div>
                <div class="charts">
                    <Later>
                        <FuzzyCharts fuzzy=fuzzy run=run_for_charts.clone() />
                    </Later>
                </div>
            </div>
        </PageShell>
    }
}
