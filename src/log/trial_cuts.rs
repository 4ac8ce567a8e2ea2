//! A shop's own trial cuts as a table: one row per cut, its conditions and the force an existing
//! monitor gave for it — what paper 004's network learns from (Fig. 2: the current sensor and the
//! indirect-monitoring model give the forces, the CNC the cut parameters).
//!
//! ```text
//! a_e [mm],f_z [mm],a_p [mm],d [mm],z,force [N]
//! 4,0.08,1,20,2,301.5
//! ```
//!
//! The file goes through the one log reader ([`super::load`]), so any dialect reads and every
//! damaged line is reported. Columns are found by name ([`CutColumn::names`]; the unit in the name,
//! if any, must be the one the network reads). The tool's diameter and teeth may be columns or
//! given once for the whole table. A row that is not a cut — a gap, text, a value that is not a
//! positive number — is left out *and listed* by its line, never dropped silently.
//! [`write_table`] writes the same table, so the lab's own trial cuts can be read back.

use std::fmt::Write as _;

use super::{name_words, unit_of, Column, ColumnKind, LineProblem, Log};
use crate::closed_loop::trial_cuts::PresetLearning;
use crate::estimation::power_law_fit::{learn, LearnError, LearnedPowerLaw, TrialCut};
use crate::plant::materials::Material;
use crate::plant::power_law::{PowerLawInputs, PowerLawMaterial, PowerLawReading};
use crate::plant::simulator::power_law_material;

/// A column of a trial-cut table: one quantity of each cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CutColumn {
    /// Radial width of cut a_e, mm.
    RadialWidth,
    /// Feed per tooth f_z, mm.
    FeedPerTooth,
    /// Axial depth of cut a_p, mm.
    AxialDepth,
    /// Tool diameter d, mm.
    Diameter,
    /// The cutter's teeth z.
    Teeth,
    /// The force the monitor gave for the cut (its resultant), N.
    Force,
}

impl CutColumn {
    /// Every quantity, in the order a table lists them.
    pub const ALL: [CutColumn; 6] = [
        CutColumn::RadialWidth,
        CutColumn::FeedPerTooth,
        CutColumn::AxialDepth,
        CutColumn::Diameter,
        CutColumn::Teeth,
        CutColumn::Force,
    ];

    /// The column name [`write_table`] writes (the first name [`CutColumn::names`] accepts, with
    /// its unit).
    pub fn header(self) -> &'static str {
        match self {
            CutColumn::RadialWidth => "a_e [mm]",
            CutColumn::FeedPerTooth => "f_z [mm]",
            CutColumn::AxialDepth => "a_p [mm]",
            CutColumn::Diameter => "d [mm]",
            CutColumn::Teeth => "z",
            CutColumn::Force => "force [N]",
        }
    }

    /// What a person calls it.
    pub fn label(self) -> &'static str {
        match self {
            CutColumn::RadialWidth => "width of cut a_e",
            CutColumn::FeedPerTooth => "feed per tooth f_z",
            CutColumn::AxialDepth => "depth of cut a_p",
            CutColumn::Diameter => "tool diameter d",
            CutColumn::Teeth => "teeth z",
            CutColumn::Force => "force",
        }
    }

    /// The names a column of this quantity may have, as words of [`name_words`] joined by a
    /// space (the unit and case do not matter: `A_e [mm]`, `ae`, `Width of cut (mm)`).
    pub fn names(self) -> &'static [&'static str] {
        match self {
            CutColumn::RadialWidth => &["a e", "ae", "width", "width of cut", "radial width"],
            CutColumn::FeedPerTooth => &["f z", "fz", "feed per tooth", "chip load"],
            CutColumn::AxialDepth => &["a p", "ap", "depth", "depth of cut", "axial depth"],
            CutColumn::Diameter => &["d", "diameter", "tool diameter"],
            CutColumn::Teeth => &["z", "teeth", "flutes"],
            CutColumn::Force => &["force", "resultant force", "cutting force"],
        }
    }

    /// The unit its values are in; a column whose name states another is refused.
    pub fn unit(self) -> Option<&'static str> {
        match self {
            CutColumn::Teeth => None,
            CutColumn::Force => Some("N"),
            _ => Some("mm"),
        }
    }
}

/// The tool, for a table without diameter or teeth columns.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct TableTool {
    /// Tool diameter, mm.
    pub diameter_mm: Option<f64>,
    /// The cutter's teeth.
    pub teeth: Option<u32>,
}

/// The trial cuts read from a table.
#[derive(Debug, Clone, PartialEq)]
pub struct TrialCutTable {
    /// The cuts, in file order.
    pub cuts: Vec<TrialCut>,
    /// The file line (from 1) of each cut.
    pub lines: Vec<u32>,
    /// The column each quantity was read from (`None`: given for the whole table).
    pub columns: Vec<(CutColumn, Option<String>)>,
    /// Rows left out, by line and column, with why.
    pub left_out: Vec<LineProblem>,
}

/// Reads the trial cuts of `log`, a table with one cut per row. The force is the column
/// `force_column` names, or the one [`CutColumn::Force`]'s names find; the tool's diameter and
/// teeth are its columns, or `tool`'s values where the table has none (giving a value for a
/// quantity the table has a column of is refused: one of them would be ignored).
pub fn read_table(
    log: &Log,
    force_column: Option<&str>,
    tool: TableTool,
) -> Result<TrialCutTable, String> {
    let find = |quantity: CutColumn| -> Result<Option<&Column>, String> {
        if quantity == CutColumn::Force {
            if let Some(name) = force_column {
                return match log.columns.iter().find(|c| c.name == name) {
                    Some(c) => checked(quantity, c).map(Some),
                    None => Err(format!(
                        "the force column {name:?} is not in the table; its columns: {}",
                        column_list(log)
                    )),
                };
            }
        }
        let mut found = log.columns.iter().filter(|c| {
            let words = name_words(&c.name).join(" ");
            quantity.names().contains(&words.as_str())
        });
        match (found.next(), found.next()) {
            (Some(a), Some(b)) => Err(format!(
                "two columns could be the {}: {:?} and {:?}{}",
                quantity.label(),
                a.name,
                b.name,
                if quantity == CutColumn::Force {
                    " (name the one to learn from)"
                } else {
                    ""
                }
            )),
            (Some(c), None) => checked(quantity, c).map(Some),
            (None, _) => Ok(None),
        }
    };
    let mut columns = Vec::new();
    let mut sources: Vec<ValuesFrom<'_>> = Vec::new();
    for quantity in CutColumn::ALL {
        let column = find(quantity)?;
        let given = match quantity {
            CutColumn::Diameter => tool.diameter_mm,
            CutColumn::Teeth => tool.teeth.map(f64::from),
            _ => None,
        };
        let source = match (column, given) {
            (Some(c), Some(_)) => {
                return Err(format!(
                    "the table has a {} column ({:?}) and a value for it was given too: give one",
                    quantity.label(),
                    c.name
                ))
            }
            (Some(c), None) => ValuesFrom::Column(c),
            (None, Some(v)) => ValuesFrom::Given(v),
            (None, None) => {
                return Err(format!(
                    "no column for the {} (named one of: {}); its columns: {}{}",
                    quantity.label(),
                    quantity
                        .names()
                        .iter()
                        .map(|n| format!("{n:?}"))
                        .collect::<Vec<_>>()
                        .join(", "),
                    column_list(log),
                    match quantity {
                        CutColumn::Diameter | CutColumn::Teeth =>
                            " — or give the tool's for the whole table",
                        _ => "",
                    }
                ))
            }
        };
        columns.push((
            quantity,
            match source {
                ValuesFrom::Column(c) => Some(c.name.clone()),
                ValuesFrom::Given(_) => None,
            },
        ));
        sources.push(source);
    }
    let mut table = TrialCutTable {
        cuts: Vec::new(),
        lines: Vec::new(),
        columns,
        left_out: Vec::new(),
    };
    for row in 0..log.rows {
        let line = log.row_lines.get(row).copied().unwrap_or(0);
        let mut values = [0.0; 6];
        let mut problem = None;
        for ((quantity, source), value) in CutColumn::ALL.iter().zip(&sources).zip(&mut values) {
            let (v, column) = match source {
                ValuesFrom::Column(c) => (c.values.get(row).copied().unwrap_or(f64::NAN), Some(c)),
                ValuesFrom::Given(v) => (*v, None),
            };
            let whole = *quantity != CutColumn::Teeth || v.fract() == 0.0;
            if !(v.is_finite() && v > 0.0 && whole) {
                problem = Some(LineProblem {
                    line: line as usize,
                    column: column.map(|c| c.name.clone()),
                    message: format!(
                        "the {} is {}, not {}: the row is left out",
                        quantity.label(),
                        if v.is_nan() {
                            "missing".to_string()
                        } else {
                            crate::input::readable(v)
                        },
                        if *quantity == CutColumn::Teeth {
                            "a whole number above 0"
                        } else {
                            "a number above 0"
                        }
                    ),
                });
                break;
            }
            *value = v;
        }
        if let Some(p) = problem {
            table.left_out.push(p);
            continue;
        }
        let [width, feed, depth, diameter, teeth, force] = values;
        table.cuts.push(TrialCut {
            inputs: PowerLawInputs {
                radial_width_mm: width,
                feed_per_tooth_mm: feed,
                axial_depth_mm: depth,
                diameter_mm: diameter,
                // Not read by the handbook reading the lab uses (as for the lab's own cuts).
                teeth_engaged: f64::NAN,
                cutter_teeth: teeth,
            },
            force_n: force,
        });
        table.lines.push(line);
    }
    Ok(table)
}

/// Paper 004's network learned from a table of trial cuts: what `cutlab learn --cuts` prints and
/// the Machine page shows.
#[derive(Debug, Clone, PartialEq)]
pub struct TableLearning {
    /// The cuts read, and the rows left out.
    pub table: TrialCutTable,
    /// The published weights the learned ones are compared with.
    pub material: PowerLawMaterial,
    /// The network learned on the table's forces.
    pub learned: LearnedPowerLaw,
}

/// Reads the trial cuts of `log` ([`read_table`]) and learns paper 004's network on them, in the
/// reading the lab uses, beside `material`'s published weights. A cut the learning refuses is
/// named by its line in the file.
pub fn learn_from_table(
    log: &Log,
    force_column: Option<&str>,
    tool: TableTool,
    material: Material,
) -> Result<TableLearning, String> {
    let table = read_table(log, force_column, tool)?;
    let material = power_law_material(material);
    let learned = learn(&table.cuts, PowerLawReading::USED, material).map_err(|e| match e {
        // The learning numbers the cuts it was given; a person reads lines of the file.
        LearnError::NotACut { index, problem } => format!(
            "line {}: {problem}",
            table.lines.get(index).copied().unwrap_or_default()
        ),
        e => e.to_string(),
    })?;
    Ok(TableLearning {
        table,
        material,
        learned,
    })
}

impl TableLearning {
    /// The column the force was read from.
    pub fn force_column(&self) -> &str {
        self.table
            .columns
            .iter()
            .find(|(q, _)| *q == CutColumn::Force)
            .and_then(|(_, c)| c.as_deref())
            .unwrap_or_default()
    }
}

/// Where a quantity's values come from.
enum ValuesFrom<'a> {
    Column(&'a Column),
    Given(f64),
}

/// `column` if it can hold `quantity`: numbers, in its unit.
fn checked(quantity: CutColumn, column: &Column) -> Result<&Column, String> {
    let holds = match column.kind {
        ColumnKind::Number => None,
        ColumnKind::Text => Some("text, not numbers"),
        ColumnKind::Time => Some("times (it was read as the time axis)"),
        ColumnKind::Empty => Some("nothing in any row"),
    };
    if let Some(holds) = holds {
        return Err(format!(
            "the {} column {:?} holds {holds}",
            quantity.label(),
            column.name
        ));
    }
    match (unit_of(&column.name), quantity.unit()) {
        (Some(unit), Some(expected)) if unit != expected => Err(format!(
            "the {} column {:?} is in {unit}: give it in {expected}",
            quantity.label(),
            column.name
        )),
        (Some(unit), None) => Err(format!(
            "the {} column {:?} has a unit ({unit}): it is a count",
            quantity.label(),
            column.name
        )),
        _ => Ok(column),
    }
}

fn column_list(log: &Log) -> String {
    log.columns
        .iter()
        .map(|c| format!("{:?}", c.name))
        .collect::<Vec<_>>()
        .join(", ")
}

/// Writes `cuts` as a trial-cut table that [`read_table`] reads back: every quantity a column,
/// with `extra` columns (name, one value per cut) after them — a second force, say. Numbers are
/// written in full (Rust's shortest round-trip form), so reading back gives the same bits.
pub fn write_table(cuts: &[TrialCut], extra: &[(&str, Vec<f64>)]) -> String {
    let mut out = String::new();
    let headers: Vec<&str> = CutColumn::ALL
        .iter()
        .map(|q| q.header())
        .chain(extra.iter().map(|(name, _)| *name))
        .collect();
    let _ = writeln!(out, "{}", headers.join(","));
    for (k, cut) in cuts.iter().enumerate() {
        let p = &cut.inputs;
        let mut fields = vec![
            p.radial_width_mm,
            p.feed_per_tooth_mm,
            p.axial_depth_mm,
            p.diameter_mm,
            p.cutter_teeth,
            cut.force_n,
        ];
        fields.extend(
            extra
                .iter()
                .map(|(_, values)| values.get(k).copied().unwrap_or(f64::NAN)),
        );
        let fields: Vec<String> = fields.iter().map(|v| format!("{v}")).collect();
        let _ = writeln!(out, "{}", fields.join(","));
    }
    out
}

/// A preset's trial cuts ([`PresetLearning`]) as a table: `force [N]` the lab's current-based
/// estimate (what paper 004's network learns from), `dynamometer force [N]` the force on the
/// tool; `None` for a learning whose preset has no cutter.
pub fn learning_table(learning: &PresetLearning) -> Option<String> {
    let cutter = learning.preset.scenario_spec()?.cutter;
    let cuts: Vec<TrialCut> = learning
        .cuts
        .iter()
        .map(|c| TrialCut {
            inputs: PowerLawInputs {
                radial_width_mm: c.radial_width_mm,
                feed_per_tooth_mm: c.feed_per_tooth_mm,
                axial_depth_mm: c.axial_depth_mm,
                diameter_mm: cutter.diameter_mm,
                teeth_engaged: f64::NAN,
                cutter_teeth: f64::from(cutter.teeth),
            },
            force_n: c.estimate_n,
        })
        .collect();
    let measured = learning.cuts.iter().map(|c| c.force_n).collect();
    Some(write_table(&cuts, &[("dynamometer force [N]", measured)]))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::log::load;

    #[test]
    fn a_table_reads_by_name_in_any_dialect_and_lists_the_rows_it_leaves_out() {
        let text = "Ae (mm);FZ [mm];Depth of cut [mm];Force [N]\n\
                    4;0,08;1;300\n\
                    5;0,1;;350\n\
                    6;0,12;3;-1\n\
                    6;0,12;4;900\n";
        let log = load(text.as_bytes(), None).unwrap();
        let tool = TableTool {
            diameter_mm: Some(20.0),
            teeth: Some(2),
        };
        let table = read_table(&log, None, tool).unwrap();
        assert_eq!(table.cuts.len(), 2);
        assert_eq!(table.lines, [2, 5]);
        assert_eq!(table.cuts[1].inputs.feed_per_tooth_mm, 0.12);
        assert_eq!(table.cuts[1].inputs.diameter_mm, 20.0);
        assert_eq!(table.left_out.len(), 2);
        assert_eq!(table.left_out[0].line, 3);
        assert_eq!(
            table.left_out[0].column.as_deref(),
            Some("Depth of cut [mm]")
        );
        assert!(table.left_out[0].message.contains("missing"));
        assert!(
            table.left_out[1].message.contains("-1"),
            "{:?}",
            table.left_out[1]
        );
    }

    #[test]
    fn what_cannot_be_read_is_refused_with_the_reason() {
        let tool = TableTool::default();
        let refuse = |text: &str, tool: TableTool| {
            read_table(&load(text.as_bytes(), None).unwrap(), None, tool).unwrap_err()
        };
        let e = refuse("a_e [mm],f_z [mm],a_p [mm],force [N]\n4,0.1,1,300\n", tool);
        assert!(
            e.contains("tool diameter") && e.contains("give the tool's"),
            "{e}"
        );
        let e = refuse(
            "a_e [in],f_z [mm],a_p [mm],d,z,force [N]\n4,0.1,1,20,2,300\n",
            tool,
        );
        assert!(e.contains("is in in: give it in mm"), "{e}");
        let e = refuse(
            "a_e,f_z,a_p,d,z,force,cutting force\n4,0.1,1,20,2,300,310\n",
            tool,
        );
        assert!(e.contains("two columns could be the force"), "{e}");
        let e = refuse(
            "a_e,f_z,a_p,d,z,force\n4,0.1,1,20,2,300\n",
            TableTool {
                diameter_mm: Some(20.0),
                teeth: None,
            },
        );
        assert!(e.contains("give one"), "{e}");
    }

    #[test]
    fn a_written_table_reads_back_bit_for_bit() {
        let cut = |w: f64, f: f64, a: f64, force: f64| TrialCut {
            inputs: PowerLawInputs {
                radial_width_mm: w,
                feed_per_tooth_mm: f,
                axial_depth_mm: a,
                diameter_mm: 20.0,
                teeth_engaged: f64::NAN,
                cutter_teeth: 2.0,
            },
            force_n: force,
        };
        let cuts = [
            cut(4.1, 0.1 / 3.0, 1.0, 301.25),
            cut(6.0, 0.12, 4.0, 1e3 / 7.0),
        ];
        let text = write_table(&cuts, &[("dynamometer force [N]", vec![1.0, 2.0])]);
        let log = load(text.as_bytes(), None).unwrap();
        let table = read_table(&log, None, TableTool::default()).unwrap();
        assert!(table.left_out.is_empty());
        for (read, written) in table.cuts.iter().zip(&cuts) {
            assert_eq!(read.force_n.to_bits(), written.force_n.to_bits());
            assert_eq!(
                read.inputs.feed_per_tooth_mm.to_bits(),
                written.inputs.feed_per_tooth_mm.to_bits()
            );
        }
        let other = read_table(&log, Some("dynamometer force [N]"), TableTool::default()).unwrap();
        assert_eq!(other.cuts[1].force_n, 2.0);
    }
}
