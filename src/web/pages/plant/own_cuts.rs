//! Paper 004's network learned from the user's own trial cuts: a CSV table, one row per cut, read
//! by the lab's log reader and learned by the core's one function for it
//! ([`learn_from_table`], what `cutlab learn --cuts` prints). A table of trial cuts has tens of
//! rows — its least squares takes well under a frame — so it is learned on the page as the
//! fields change, from the file's log read once when it was chosen; a file too big to be one is
//! refused, not read.

use leptos::prelude::*;

use crate::input::parse_number;
use crate::log::trial_cuts::{learn_from_table, TableLearning, TableTool};
use crate::log::Log;
use crate::plant::materials::Material;
use crate::web::js::read_chosen_file;

use super::learned_tables::{
    CutRow, ForceFit, LearnedExponentsTable, LearnedFrom, TrialCutResiduals,
};

/// A table of trial cuts larger than this is no table of cuts (a sample log goes to the Logs
/// page), bytes.
const MAX_TABLE_BYTES: usize = 1 << 20;

/// A chosen file, read once: its name and its log, or why it has none. The fields' changes learn
/// again from the log; the file's text is read into it and dropped.
struct ChosenTable {
    name: String,
    log: Result<Log, String>,
}

impl ChosenTable {
    /// Reads the file's text as a log, refusing a file too big to be a table of cuts.
    fn read(name: String, text: Result<String, String>) -> Self {
        let log = text.and_then(|text| {
            if text.len() > MAX_TABLE_BYTES {
                return Err(format!(
                    "{name} is {:.1} MB: a table of trial cuts has one row per cut (a log of \
                     samples is read on the Logs page)",
                    text.len() as f64 / 1e6
                ));
            }
            crate::log::load(text.as_bytes(), None).map_err(|e| format!("{name}: {e}"))
        });
        ChosenTable { name, log }
    }
}

/// What was learned from the chosen table with what the fields hold.
fn learned(
    chosen: &ChosenTable,
    material: &str,
    diameter: &str,
    teeth: &str,
    force_column: &str,
) -> Result<TableLearning, String> {
    let log = chosen.log.as_ref().map_err(Clone::clone)?;
    let optional = |label: &str, text: &str| -> Result<Option<f64>, String> {
        match text.trim() {
            "" => Ok(None),
            t => parse_number(t)
                .map(Some)
                .map_err(|e| format!("{label}: {e}")),
        }
    };
    let diameter_mm = optional("Tool diameter", diameter)?;
    let teeth = match optional("Teeth", teeth)? {
        Some(z) if z >= 1.0 && z.fract() == 0.0 && z <= f64::from(u32::MAX) => Some(z as u32),
        Some(z) => return Err(format!("Teeth: {z} is not a whole number above 0")),
        None => None,
    };
    let material = Material::from_name(material).unwrap_or(Material::Sm45c);
    let force = Some(force_column).filter(|c| !c.is_empty());
    learn_from_table(log, force, TableTool { diameter_mm, teeth }, material)
        .map_err(|e| format!("{}: {e}", chosen.name))
}

/// What was read and left out, then the learned exponents beside the published, the held ones,
/// and every cut's residual by its line.
fn result_view(learning: &TableLearning) -> impl IntoView {
    let table = &learning.table;
    let fits = vec![ForceFit {
        from: LearnedFrom::Force,
        forces_n: table.cuts.iter().map(|c| c.force_n).collect(),
        learned: learning.learned.clone(),
    }];
    let cuts = table
        .cuts
        .iter()
        .zip(&table.lines)
        .map(|(cut, &line)| CutRow {
            label: line as usize,
            radial_width_mm: cut.inputs.radial_width_mm,
            feed_per_tooth_mm: cut.inputs.feed_per_tooth_mm,
            axial_depth_mm: cut.inputs.axial_depth_mm,
        })
        .collect();
    let left_out = table
        .left_out
        .iter()
        .map(|p| {
            let column = p
                .column
                .as_deref()
                .map_or(String::new(), |c| format!(", {c}"));
            view! { <li>{format!("Line {}{column}: {}", p.line, p.message)}</li> }
        })
        .collect_view();
    view! {
        <p role="status">
            {format!(
                "{} trial cuts, the force from the column {:?}; published weights: {}.",
                table.cuts.len(),
                learning.force_column(),
                learning.material.label()
            )}
        </p>
        <ul aria-label="Rows left out" hidden=table.left_out.is_empty()>{left_out}</ul>
        <LearnedExponentsTable caption="Exponents learned from your cuts" fits=fits.clone() />
        <TrialCutResiduals caption="Your trial cuts and residuals" row_heading="Line" cuts fits />
    }
}

/// The panel: the table, the tool and material it needs, and what was learned from it.
#[component]
pub fn OwnCutsPanel() -> impl IntoView {
    let file = RwSignal::new(None::<ChosenTable>);
    let material = RwSignal::new(Material::Sm45c.name().to_string());
    let diameter = RwSignal::new(String::new());
    let teeth = RwSignal::new(String::new());
    let force_column = RwSignal::new(String::new());
    let result = Memo::new(move |_| {
        file.with(|chosen| {
            Some(learned(
                chosen.as_ref()?,
                &material.get(),
                &diameter.get(),
                &teeth.get(),
                &force_column.get(),
            ))
        })
    });
    let on_file = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |name, text| {
            file.set(Some(ChosenTable::read(name, text)));
        });
    };
    let text_field = |id: &'static str, label: &'static str, value: RwSignal<String>, hint| {
        view! {
            <div class="field">
                <label for=id>{label}</label>
                <input
                    id=id
                    type="text"
                    inputmode="decimal"
                    placeholder=hint
                    prop:value=move || value.get()
                    on:input=move |ev| value.set(event_target_value(&ev))
                />
            </div>
        }
    };
    view! {
        <section class="panel" aria-labelledby="own-cuts-title">
            <h2 id="own-cuts-title">"Paper 004's network, learned from your own trial cuts"</h2>
            <p class="hint">
                "A CSV table, one row per cut: a_e [mm], f_z [mm], a_p [mm], force [N] (the force your \
                 current-based monitor gave for the cut) and the tool's d [mm] and z, or the tool below. \
                 Columns are found by name; a row that is not a cut is left out and listed. \
                 www/data/kim-step-doc-trial-cuts.csv is an example (cutlab learn --cuts FILE does the same)."
            </p>
            <div class="field">
                <label for="own-cuts-file">"Trial-cut table (CSV)"</label>
                <input id="own-cuts-file" type="file" accept=".csv,.txt,text/csv" on:change=on_file />
            </div>
            <div class="field">
                <label for="own-cuts-material">"Material (published weights)"</label>
                <select
                    id="own-cuts-material"
                    on:change=move |ev| material.set(event_target_value(&ev))
                    prop:value=move || material.get()
                >
                    {Material::ALL
                        .map(|m| view! { <option value=m.name()>{m.label()}</option> })
                        .collect_view()}
                </select>
            </div>
            {text_field("own-cuts-diameter", "Tool diameter (mm), if the table has no d column", diameter, "blank: the table's")}
            {text_field("own-cuts-teeth", "Teeth, if the table has no z column", teeth, "blank: the table's")}
            {text_field("own-cuts-force", "Force column (blank: the one named force)", force_column, "blank: found by name")}
            {move || result.with(|result| match result {
                None => None,
                Some(Err(e)) => Some(view! { <p class="field-error" role="alert">{e.clone()}</p> }.into_any()),
                Some(Ok(learning)) => Some(result_view(learning).into_any()),
            })}
        </section>
    }
}
