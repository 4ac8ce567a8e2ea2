//! The cut of a calibration without a dynamometer, as one table: the Logs page's "Modelled from
//! the cut" fields and the `--material`, `--diameter-mm`, `--teeth` and `--mode` options of
//! `cutlab calibrate` and `cutlab tune --teach-in --log` are its rows, parsed by [`parse_cut`]
//! into the [`CutGeometry`] whose model stands in for the force. The depth and width of cut are
//! the page's (the command line reads them from each row of the log).

use super::cut_forces::{cutting_material, CutGeometry};
use crate::input::table::{Kind, Problem, Reader, Row, RowError, Shown, Table, Value};
use crate::plant::materials::Material;
use crate::plant::mechanics::{Cutter, MillingMode, DIAMETER_RANGE_MM, MAX_TEETH};

/// Every setting of a modelled cut.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum CutSetting {
    /// The material cut (one with cutting coefficients of its own).
    Material,
    /// The cutter's diameter.
    Diameter,
    /// Its number of teeth.
    Teeth,
    /// Up, down or slot milling.
    Mode,
    /// The axial depth of cut; blank: each row's depth column.
    Depth,
    /// The radial width of cut.
    Width,
}

/// A depth or width of cut: from a hundredth of a millimetre to the largest cutter's diameter.
const CUT_MM: Kind = Kind::Number {
    min: 0.01,
    max: DIAMETER_RANGE_MM.1,
};

impl Table for CutSetting {
    const ROWS: &'static [Self] = &[
        CutSetting::Material,
        CutSetting::Diameter,
        CutSetting::Teeth,
        CutSetting::Mode,
        CutSetting::Depth,
        CutSetting::Width,
    ];

    fn row(self) -> Row {
        use CutSetting as C;
        match self {
            C::Material => Row::new("material", "material", "Material", "")
                .takes(Kind::Choice, Shown::Choice("sm45c"))
                .noun("material")
                .help("the material cut: its cutting coefficients model each period's force"),
            C::Diameter => Row::new("diameter", "diameter-mm", "Cutter diameter", "mm")
                .takes(
                    Kind::Number {
                        min: DIAMETER_RANGE_MM.0,
                        max: DIAMETER_RANGE_MM.1,
                    },
                    Shown::Number(10.0),
                )
                .help("cutter diameter"),
            C::Teeth => Row::new("teeth", "teeth", "Cutter teeth", "")
                .takes(
                    Kind::Count {
                        min: 1,
                        max: MAX_TEETH as usize,
                    },
                    Shown::Count(4),
                )
                .noun("teeth")
                .help("number of teeth of the cutter"),
            C::Mode => Row::new("mode", "mode", "Milling mode", "")
                .takes(Kind::Choice, Shown::Choice("down"))
                .noun("milling mode")
                .help("up, down or slot milling"),
            C::Depth => Row::new("depth", "", "Depth of cut (empty: the depth column)", "mm")
                .takes(CUT_MM, Shown::Blank)
                .help("axial depth of cut; blank: each row's depth column"),
            C::Width => Row::new("width", "", "Width of cut", "mm")
                .takes(CUT_MM, Shown::Number(3.0))
                .help("radial width of cut"),
        }
    }

    fn choices(self) -> Vec<(&'static str, &'static str)> {
        match self {
            // The composite part is two materials: a cut is in one of them.
            CutSetting::Material => Material::ALL
                .iter()
                .filter(|m| cutting_material(m.name()).is_ok())
                .map(|m| (m.name(), m.label()))
                .collect(),
            CutSetting::Mode => MillingMode::ALL
                .iter()
                .map(|m| (m.name(), m.label()))
                .collect(),
            _ => Vec::new(),
        }
    }

    /// The composite part is named with the reason it is refused.
    fn read(self, text: &str) -> Result<Option<Value>, RowError<Self>> {
        match self {
            CutSetting::Material if !text.trim().is_empty() => cutting_material(text.trim())
                .map(|m| Some(Value::Choice(m.name())))
                .map_err(|why| RowError::new(self, Problem::Other(why))),
            _ => crate::input::table::read_text(self, text),
        }
    }
}

/// A modelled cut as asked for.
#[derive(Debug, Clone, PartialEq)]
pub struct Cut {
    /// Cutter, milling mode and the material's coefficients.
    pub geometry: CutGeometry,
    /// The material cut.
    pub material: Material,
    /// The axial depth; `None`: each row's depth column.
    pub depth_mm: Option<f64>,
    /// The radial width.
    pub width_mm: f64,
}

impl Cut {
    /// The cut for people: "material sm45c, Ø10 mm, 4 teeth, down milling".
    pub fn describe(&self) -> String {
        format!(
            "material {}, Ø{} mm, {} teeth, {} milling",
            self.material.name(),
            crate::input::readable(self.geometry.cutter.diameter_mm),
            self.geometry.cutter.teeth,
            self.geometry.mode.name()
        )
    }
}

/// Parses the typed text of a modelled cut (rows not given, or blank, take their defaults; the
/// depth stays blank): every setting that does not parse or is out of range is reported.
///
/// ```
/// use cutlab::estimation::cut_settings::{parse_cut, CutSetting};
/// let cut = parse_cut(&[(CutSetting::Diameter, "20"), (CutSetting::Mode, "slot")]).unwrap();
/// assert_eq!((cut.geometry.cutter.diameter_mm, cut.depth_mm, cut.width_mm), (20.0, None, 3.0));
/// let e = parse_cut(&[(CutSetting::Teeth, "0"), (CutSetting::Material, "composite")]).unwrap_err();
/// assert_eq!(e.len(), 2);
/// ```
pub fn parse_cut<T: AsRef<str>>(
    texts: &[(CutSetting, T)],
) -> Result<Cut, Vec<RowError<CutSetting>>> {
    let mut reader = Reader::new(texts);
    let material = reader
        .choice(CutSetting::Material)
        .and_then(Material::from_name);
    let diameter_mm = reader.number(CutSetting::Diameter);
    let teeth = reader.count(CutSetting::Teeth);
    let mode = reader
        .choice(CutSetting::Mode)
        .and_then(MillingMode::from_name);
    let depth_mm = reader.number(CutSetting::Depth);
    let width_mm = reader.number(CutSetting::Width);
    let asked = match (material, diameter_mm, teeth, mode, width_mm) {
        (Some(material), Some(diameter_mm), Some(teeth), Some(mode), Some(width_mm)) => {
            Some((material, diameter_mm, teeth, mode, width_mm))
        }
        _ => None,
    };
    let (material, diameter_mm, teeth, mode, width_mm) = reader.finish(asked)?;
    // The rows' ranges lie inside what a cutter may be.
    let teeth = u32::try_from(teeth).unwrap_or(u32::MAX);
    let cutter = Cutter::new(diameter_mm, teeth, 0.0).map_err(|e| {
        vec![RowError::new(
            CutSetting::Diameter,
            Problem::Other(e.to_string()),
        )]
    })?;
    Ok(Cut {
        geometry: CutGeometry {
            cutter,
            mode,
            coefficients: material.coefficients(),
        },
        material,
        depth_mm,
        width_mm,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::input::table::check_table;

    #[test]
    fn the_table_holds_and_its_defaults_make_a_cut() {
        assert_eq!(check_table::<CutSetting>(), Ok(()));
        let cut = parse_cut::<&str>(&[]).unwrap();
        assert_eq!(
            cut.describe(),
            "material sm45c, Ø10 mm, 4 teeth, down milling"
        );
        // Every diameter and tooth count the rows take makes a cutter.
        for (d, z) in [(DIAMETER_RANGE_MM.0, "1"), (DIAMETER_RANGE_MM.1, "16")] {
            let d = d.to_string();
            assert!(
                parse_cut(&[(CutSetting::Diameter, d.as_str()), (CutSetting::Teeth, z)]).is_ok()
            );
        }
    }

    #[test]
    fn refusals_name_their_setting_in_the_words_the_command_line_adds_its_option_to() {
        let e = parse_cut(&[(CutSetting::Material, "composite")]).unwrap_err();
        assert_eq!(e[0].setting, CutSetting::Material);
        assert!(e[0]
            .for_cli()
            .starts_with("--material: composite is two materials"));
        let e = parse_cut(&[(CutSetting::Mode, "sideways")]).unwrap_err();
        assert_eq!(
            e[0].for_cli(),
            "--mode: unknown milling mode \"sideways\"; choices: up, down, slot"
        );
        let e = parse_cut(&[(CutSetting::Width, "-3"), (CutSetting::Depth, "abc")]).unwrap_err();
        let settings: Vec<CutSetting> = e.iter().map(|e| e.setting).collect();
        assert_eq!(settings, [CutSetting::Depth, CutSetting::Width]);
        assert_eq!(e[1].problem.to_string(), "must be positive, got -3");
    }
}
