//! Paper 004's network learned from the user's own trial cuts: a CSV table, one row per cut, read
//! by the lab's log reader and learned by the core's one function for it
//! ([`learn_from_table`], what `cutlab learn --cuts` prints). A table of trial cuts has tens of
//! rows — its least squares takes well under a frame — so it is learned on the page as the
//! fields change; a file too big to be one is refused, not read.

use leptos::prelude::*;

use crate::input::parse_number;
use crate::log::trial_cuts::{learn_from_table, TableLearning, TableTool};
use crate::plant::materials::Material;
use crate::web::components::page::TableScroll;
use crate::web::js::read_chosen_file;

/// A table of trial cuts larger than this is no table of cuts (a sample log goes to the Logs
/// page), bytes.
const MAX_TABLE_BYTES: usize = 1 << 20;

/// What the fields hold and what was learned from them.
fn learned(
    file: &(String, String),
    material: &str,
    diameter: &str,
    teeth: &str,
    force_column: &str,
) -> Result<TableLearning, String> {
    let (name, text) = file;
    if text.len() > MAX_TABLE_BYTES {
        return Err(format!(
            "{name} is {:.1} MB: a table of trial cuts has one row per cut (a log of samples is \
             read on the Logs page)",
            text.len() as f64 / 1e6
        ));
    }
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
    let log = crate::log::load(text.as_bytes(), None).map_err(|e| format!("{name}: {e}"))?;
    let force = Some(force_column).filter(|c| !c.is_empty());
    learn_from_table(&log, force, TableTool { diameter_mm, teeth }, material)
        .map_err(|e| format!("{name}: {e}"))
}

/// The learned exponents beside the published, the held ones, and every cut's residual by line.
fn result_view(learning: &TableLearning) -> impl IntoView {
    let learned = &learning.learned;
    let rows = learned
        .learned
        .iter()
        .map(|e| {
            view! {
                <tr>
                    <th scope="row">{e.input.symbol()}</th>
                    <td>{e.with_uncertainty()}</td>
                    <td>{format!("{:.2}", e.published)}</td>
                </tr>
            }
        })
        .collect_view();
    let held = learned
        .held
        .iter()
        .map(|(input, w)| format!("{} {w:.2}", input.symbol()))
        .collect::<Vec<_>>()
        .join(", ");
    let cuts = learning
        .table
        .cuts
        .iter()
        .zip(&learning.table.lines)
        .zip(&learned.residuals_pct)
        .map(|((cut, line), residual)| {
            view! {
                <tr>
                    <th scope="row">{*line}</th>
                    <td>{format!("{:.2}", cut.inputs.radial_width_mm)}</td>
                    <td>{format!("{:.4}", cut.inputs.feed_per_tooth_mm)}</td>
                    <td>{format!("{:.2}", cut.inputs.axial_depth_mm)}</td>
                    <td>{format!("{:.1}", cut.force_n)}</td>
                    <td>{format!("{residual:+.2}")}</td>
                </tr>
            }
        })
        .collect_view();
    let left_out = learning
        .table
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
                learning.table.cuts.len(),
                learning.force_column(),
                learning.material.label()
            )}
        </p>
        <ul aria-label="Rows left out" hidden=learning.table.left_out.is_empty()>{left_out}</ul>
        <table class="metrics">
            <caption>"Exponents learned from your cuts (± two standard errors)"</caption>
            <thead>
                <tr>
                    <th scope="col">"Input"</th>
                    <th scope="col">"Learned"</th>
                    <th scope="col">"Published"</th>
                </tr>
            </thead>
            <tbody>{rows}</tbody>
        </table>
        <p class="hint">
            {format!(
                "Held at the published exponents (they do not vary over the cuts): {held}. Bias {:.1} N; \
                 residual RMS {:.2} %.",
                learned.bias_n,
                100.0 * learned.residual_rms_log
            )}
        </p>
        <TableScroll label="Your trial cuts and residuals".to_string()>
            <table class="metrics">
                <caption>"Your trial cuts and residuals"</caption>
                <thead>
                    <tr>
                        <th scope="col">"Line"</th>
                        <th scope="col">"a_e (mm)"</th>
                        <th scope="col">"f (mm)"</th>
                        <th scope="col">"a_p (mm)"</th>
                        <th scope="col">"Force (N)"</th>
                        <th scope="col">"Residual (%)"</th>
                    </tr>
                </thead>
                <tbody>{cuts}</tbody>
            </table>
        </TableScroll>
    }
}

/// The panel: the table, the tool and material it needs, and what was learned from it.
#[component]
pub fn OwnCutsPanel() -> impl IntoView {
    let file = RwSignal::new(None::<(String, Result<String, String>)>);
    let material = RwSignal::new(Material::Sm45c.name().to_string());
    let diameter = RwSignal::new(String::new());
    let teeth = RwSignal::new(String::new());
    let force_column = RwSignal::new(String::new());
    let result = Memo::new(move |_| {
        file.with(|f| {
            let (name, text) = f.as_ref()?;
            Some(text.clone().and_then(|text| {
                learned(
                    &(name.clone(), text),
                    &material.get(),
                    &diameter.get(),
                    &teeth.get(),
                    &force_column.get(),
                )
            }))
        })
    });
    let on_file = move |ev: leptos::ev::Event| {
        read_chosen_file(&ev, move |name, text| file.set(Some((name, text))));
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
            {move || match result.get() {
                None => None,
                Some(Err(e)) => Some(view! { <p class="field-error" role="alert">{e}</p> }.into_any()),
                Some(Ok(learning)) => Some(result_view(&learning).into_any()),
            }}
        </section>
    }
}
