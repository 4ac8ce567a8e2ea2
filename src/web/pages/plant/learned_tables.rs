//! The two tables of paper 004's network learned from trial cuts, for one force or several: the
//! learned exponents beside the published ones, and each cut's forces and residuals. The
//! preset's learning ([`super::learning`]) shows two forces (the force on the tool and the
//! current-based estimate), the user's own table ([`super::own_cuts`]) one; the headings follow
//! from how many there are.

use leptos::prelude::*;

use crate::estimation::power_law_fit::LearnedPowerLaw;
use crate::plant::power_law::PowerLawInput;
use crate::web::components::page::TableScroll;

/// Which force a network was learned on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LearnedFrom {
    /// The force on the tool, or the one the user's monitor gave for each cut.
    Force,
    /// The lab's current-based estimate of it.
    Estimate,
}

impl LearnedFrom {
    /// As a column heading, without its unit.
    fn heading(self) -> &'static str {
        match self {
            LearnedFrom::Force => "Force",
            LearnedFrom::Estimate => "Estimate",
        }
    }

    /// In a sentence, to tell two fits apart.
    fn name(self) -> &'static str {
        match self {
            LearnedFrom::Force => "force",
            LearnedFrom::Estimate => "estimate",
        }
    }
}

/// One force the network was learned on, with what was learned.
#[derive(Clone)]
pub struct ForceFit {
    /// Which force.
    pub from: LearnedFrom,
    /// The force of each cut, N, in the order of the residuals.
    pub forces_n: Vec<f64>,
    /// The network learned on it.
    pub learned: LearnedPowerLaw,
}

/// Each fit's text for a heading or a sentence: `alone` for a single fit, else `named` of the
/// fit's force (two fits need telling apart).
fn per_fit(fits: &[ForceFit], alone: &str, named: impl Fn(&str) -> String) -> Vec<String> {
    fits.iter()
        .map(|fit| {
            if fits.len() > 1 {
                named(fit.from.name())
            } else {
                alone.to_string()
            }
        })
        .collect()
}

/// Column headings of the table's header row.
fn headings(texts: Vec<String>) -> impl IntoView {
    texts
        .into_iter()
        .map(|text| view! { <th scope="col">{text}</th> })
        .collect_view()
}

/// A trial cut's row: its label and the inputs the network reads.
pub struct CutRow {
    /// The row's heading: the cut's number, or its line in the file.
    pub label: usize,
    /// a_e, mm.
    pub radial_width_mm: f64,
    /// f, mm per tooth.
    pub feed_per_tooth_mm: f64,
    /// a_p, mm.
    pub axial_depth_mm: f64,
}

/// What a table shows where a value is missing.
const MISSING: &str = "—";

/// The learned exponents of each fit beside the published (and, where given, the mechanistic
/// model's), with the held exponents, each fit's bias and its residual RMS below.
#[component]
pub fn LearnedExponentsTable(
    /// What was learned from: "Learned exponents" (the uncertainty's note is added).
    caption: &'static str,
    /// The fits, one column each; the first gives the rows, the published and the held values.
    fits: Vec<ForceFit>,
    /// The mechanistic model's local exponent of each input, as a last column; `None`: no column.
    #[prop(optional)]
    mechanistic: Option<Vec<(PowerLawInput, String)>>,
) -> impl IntoView {
    let fit_headings = headings(per_fit(&fits, "Learned", |name| format!("From the {name}")));
    let first = fits.first().map(|fit| &fit.learned);
    let rows = first
        .map(|l| l.learned.as_slice())
        .unwrap_or_default()
        .iter()
        .map(|exponent| {
            let learned = fits
                .iter()
                .map(|fit| {
                    let text = fit
                        .learned
                        .learned
                        .iter()
                        .find(|e| e.input == exponent.input)
                        .map_or(MISSING.to_string(), |e| e.with_uncertainty());
                    view! { <td>{text}</td> }
                })
                .collect_view();
            let mechanistic = mechanistic.as_ref().map(|texts| {
                let text = texts
                    .iter()
                    .find(|(input, _)| *input == exponent.input)
                    .map_or(MISSING, |(_, t)| t.as_str())
                    .to_string();
                view! { <td>{text}</td> }
            });
            view! {
                <tr>
                    <th scope="row">{exponent.input.symbol()}</th>
                    {learned}
                    <td>{format!("{:.2}", exponent.published)}</td>
                    {mechanistic}
                </tr>
            }
        })
        .collect_view();
    let held = first
        .map(|l| l.held.as_slice())
        .unwrap_or_default()
        .iter()
        .map(|(input, w)| format!("{} {w:.2}", input.symbol()))
        .collect::<Vec<_>>()
        .join(", ");
    let biases = fits
        .iter()
        .zip(per_fit(&fits, "", |name| format!(" from the {name}")))
        .map(|(fit, from)| format!("{:.1} N{from}", fit.learned.bias_n))
        .collect::<Vec<_>>()
        .join(", ");
    let rms = fits
        .iter()
        .map(|fit| format!("{:.2} %", 100.0 * fit.learned.residual_rms_log))
        .collect::<Vec<_>>()
        .join(" and ");
    view! {
        <table class="metrics">
            <caption>{format!("{caption} (± two standard errors)")}</caption>
            <thead>
                <tr>
                    <th scope="col">"Input"</th>
                    {fit_headings}
                    <th scope="col">"Published"</th>
                    {mechanistic.is_some().then(|| view! { <th scope="col">"Mechanistic"</th> })}
                </tr>
            </thead>
            <tbody>{rows}</tbody>
        </table>
        <p class="hint">
            {format!(
                "Held at the published exponents (they do not vary over the cuts): {held}. Bias \
                 {biases}; residual RMS {rms}."
            )}
        </p>
    }
}

/// Each trial cut's inputs, every fit's force and every fit's residual.
#[component]
pub fn TrialCutResiduals(
    /// The table's caption and accessible name.
    caption: &'static str,
    /// The heading of the rows' labels: "Cut", "Line".
    row_heading: &'static str,
    /// The cuts, in the order of the fits' forces and residuals.
    cuts: Vec<CutRow>,
    /// The fits: a force column each, then a residual column each.
    fits: Vec<ForceFit>,
) -> impl IntoView {
    let force_headings = headings(
        fits.iter()
            .map(|fit| format!("{} (N)", fit.from.heading()))
            .collect(),
    );
    let residual_headings = headings(per_fit(&fits, "Residual (%)", |name| {
        format!("Residual, {name} fit (%)")
    }));
    let rows = cuts
        .iter()
        .enumerate()
        .map(|(k, cut)| {
            let value = |values: &[f64], format: fn(f64) -> String| {
                let text = values.get(k).map_or(MISSING.to_string(), |&v| format(v));
                view! { <td>{text}</td> }
            };
            let forces = fits
                .iter()
                .map(|fit| value(&fit.forces_n, |f| format!("{f:.1}")))
                .collect_view();
            let residuals = fits
                .iter()
                .map(|fit| value(&fit.learned.residuals_pct, |r| format!("{r:+.2}")))
                .collect_view();
            view! {
                <tr>
                    <th scope="row">{cut.label}</th>
                    <td>{format!("{:.2}", cut.radial_width_mm)}</td>
                    <td>{format!("{:.4}", cut.feed_per_tooth_mm)}</td>
                    <td>{format!("{:.2}", cut.axial_depth_mm)}</td>
                    {forces}
                    {residuals}
                </tr>
            }
        })
        .collect_view();
    view! {
        <TableScroll label=caption.to_string()>
            <table class="metrics">
                <caption>{caption}</caption>
                <thead>
                    <tr>
                        <th scope="col">{row_heading}</th>
                        <th scope="col">"a_e (mm)"</th>
                        <th scope="col">"f (mm)"</th>
                        <th scope="col">"a_p (mm)"</th>
                        {force_headings}
                        {residual_headings}
                    </tr>
                </thead>
                <tbody>{rows}</tbody>
            </table>
        </TableScroll>
    }
}
