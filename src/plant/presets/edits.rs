//! What a person may change of a mill preset, each edit with its accepted range.

use std::fmt;

use serde::{Deserialize, Serialize};

use super::definitions::MillParameters;
use crate::input::readable;
use crate::plant::deflection::{
    MAX_STICK_OUT_DIAMETERS, SPINDLE_STIFFNESS_RANGE_N_UM, STICK_OUT_RANGE_MM,
    YOUNGS_MODULUS_RANGE_GPA,
};
use crate::plant::materials::Material;
use crate::plant::mechanics::MAX_TEETH;
use crate::plant::simulator::SimConfig;
use crate::plant::PlantError;

/// Changes a user makes to a mill preset; `None` keeps the preset's value (and is left out of
/// the serialised form).
///
/// Each edit must lie in a physically sane range, checked by [`PlantEdits::check`] (and by
/// [`crate::plant::Preset::machine_with`]):
///
/// | edit | accepted | why |
/// |---|---|---|
/// | `spindle_rpm` | 10 rpm … the spindle drive's top speed (6914 rpm by default) | the spindle could never reach a faster command, and the feed waits for it |
/// | `programmed_feed_mm_min` | 1 … 20 000 mm/min | a machining centre's cutting feeds (the control clamps above its own maximum, 10 000 mm/min by default) |
/// | `tool_diameter_mm` | 0.5 … 100 mm | end mills, from micro tools to the largest |
/// | `teeth` | 1 … 16 | what the force model holds |
/// | `depth_scale` | 0.01 … the factor that makes the deepest cut 4 tool diameters | a long-series end mill's flute length (standard ones: 2–3 diameters) |
/// | `sensor_noise_a` | 0 … 5 A | beyond the feed channel's full scale (±4.8 A) noise only saturates it |
/// | `tool_stick_out_mm` | 2 … 400 mm, at least the deepest cut, at most 10 tool diameters | a stub tool to a long-reach one; the flutes must reach the cut, and a longer tool chatters before its static deflection matters |
/// | `spindle_stiffness_n_um` | 5 … 500 N/µm | a light high-speed spindle to a heavy boring spindle |
/// | `tool_youngs_modulus_gpa` | 150 … 700 GPa | high-speed steel to cemented carbide |
/// | `load_step_pct` | −90 … +150 % (liu-current-step only) | from a tenth of the depth to 2.5 times it: up to the paper's full-scale E of 25 A above I_ref and beyond, on a 10 mm insert edge |
///
/// A tool diameter that makes the preset's own deepest cut deeper than 4 diameters is refused
/// as `tool_diameter_mm`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlantEdits {
    /// Work material of every region.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub material: Option<Material>,
    /// Spindle speed of every block.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spindle_rpm: Option<f64>,
    /// Programmed feed of every block.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub programmed_feed_mm_min: Option<f64>,
    /// Factor on the axial depth profile.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub depth_scale: Option<f64>,
    /// Cutter diameter.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_diameter_mm: Option<f64>,
    /// Number of teeth.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub teeth: Option<u32>,
    /// Standard deviation of the Hall sensors' noise, both channels.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor_noise_a: Option<f64>,
    /// Size of paper 002's load step, percent of the depth of cut (liu-current-step only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub load_step_pct: Option<f64>,
    /// The tool's stick-out from its holder, mm (the force-induced error's cantilever).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_stick_out_mm: Option<f64>,
    /// The spindle's radial stiffness at its nose, N/µm (the force-induced error's other spring).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub spindle_stiffness_n_um: Option<f64>,
    /// The Young's modulus of the tool's material, GPa (the cantilever's stiffness).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub tool_youngs_modulus_gpa: Option<f64>,
}

impl PlantEdits {
    /// The edits that change what the machine does: all but the tool's stick-out and material
    /// and the spindle's stiffness, which change only the force-induced error's model (the
    /// simulated force and currents are a rigid tool's).
    ///
    /// ```
    /// use cutlab::plant::presets::PlantEdits;
    /// let edits = PlantEdits { tool_stick_out_mm: Some(60.0), teeth: Some(3), ..PlantEdits::default() };
    /// assert_eq!(edits.of_the_machine(), PlantEdits { teeth: Some(3), ..PlantEdits::default() });
    /// ```
    pub fn of_the_machine(self) -> Self {
        Self {
            tool_stick_out_mm: None,
            spindle_stiffness_n_um: None,
            tool_youngs_modulus_gpa: None,
            ..self
        }
    }

    /// How the tool sits in the machine, as these edits state it (the force-induced error's
    /// springs; `None` fields take the defaults).
    pub fn tool_mount(&self) -> crate::plant::deflection::ToolMount {
        crate::plant::deflection::ToolMount {
            stick_out_mm: self.tool_stick_out_mm,
            spindle_stiffness_n_um: self.spindle_stiffness_n_um,
            youngs_modulus_gpa: self.tool_youngs_modulus_gpa,
        }
    }

    /// The lowest spindle speed accepted; the highest is the spindle drive's top speed.
    pub const MIN_SPINDLE_RPM: f64 = 10.0;
    /// The programmed feeds accepted, [lowest, highest].
    pub const FEED_MM_MIN: [f64; 2] = [1.0, 20_000.0];
    /// The tool diameters accepted, [smallest, largest].
    pub const TOOL_DIAMETER_MM: [f64; 2] = [0.5, 100.0];
    /// The deepest cut accepted, in tool diameters.
    pub const MAX_DEPTH_PER_DIAMETER: f64 = 4.0;
    /// The smallest depth scale accepted: below, the tool scratches rather than cuts.
    pub const MIN_DEPTH_SCALE: f64 = 0.01;
    /// The sensor noise accepted (standard deviation), [least, most].
    pub const SENSOR_NOISE_A: [f64; 2] = [0.0, 5.0];
    /// The load steps accepted, percent of the depth, [least, most].
    pub const LOAD_STEP_PCT: [f64; 2] = [-90.0, 150.0];

    /// Checks every edit against its accepted range for the mill preset cutting `cut` on
    /// `machine` (see the table on [`PlantEdits`]); the error names the first edit out of
    /// range and the range.
    ///
    /// ```
    /// use cutlab::plant::presets::{PlantEdits, Preset};
    /// let p = Preset::ManeeratDoc1; // DOC 1 mm with a Ø10 mm cutter
    /// let (cut, machine) = (p.mill_parameters().unwrap(), p.sim_config(0));
    /// let deep = PlantEdits { depth_scale: Some(40.0), ..PlantEdits::default() };
    /// assert!(deep.check(cut, &machine).is_ok()); // 40 mm = 4 diameters
    /// let deeper = PlantEdits { depth_scale: Some(41.0), ..PlantEdits::default() };
    /// let e = deeper.check(cut, &machine).unwrap_err();
    /// assert_eq!((e.field, e.min, e.max), ("depth_scale", 0.01, 40.0));
    /// assert_eq!(e.to_string(), "depth_scale: 41 is outside the accepted 0.01–40 (the deepest cut at most 4 tool diameters)");
    /// ```
    pub fn check(&self, cut: &MillParameters, machine: &SimConfig) -> Result<(), EditError> {
        let within = Self::within;
        self.check_load_step()?;
        within(
            "spindle_rpm",
            self.spindle_rpm,
            [
                Self::MIN_SPINDLE_RPM,
                machine.spindle_drive.max_spindle_rpm(),
            ],
            "rpm",
            "up to the spindle's top speed",
        )?;
        within(
            "programmed_feed_mm_min",
            self.programmed_feed_mm_min,
            Self::FEED_MM_MIN,
            "mm/min",
            "a machining centre's cutting feeds",
        )?;
        within(
            "tool_diameter_mm",
            self.tool_diameter_mm,
            Self::TOOL_DIAMETER_MM,
            "mm",
            "end mills",
        )?;
        within(
            "teeth",
            self.teeth.map(f64::from),
            [1.0, f64::from(MAX_TEETH)],
            "teeth",
            "what the force model holds",
        )?;
        within(
            "sensor_noise_a",
            self.sensor_noise_a,
            Self::SENSOR_NOISE_A,
            "A",
            "beyond the feed channel's full scale noise only saturates it",
        )?;
        let depth_why = "the deepest cut at most 4 tool diameters";
        let deepest_mm = cut.depth_mm.iter().map(|&(_, d)| d).fold(0.0, f64::max);
        let diameter_mm = self.tool_diameter_mm.unwrap_or(cut.cutter.diameter_mm);
        within(
            "spindle_stiffness_n_um",
            self.spindle_stiffness_n_um,
            [
                SPINDLE_STIFFNESS_RANGE_N_UM.0,
                SPINDLE_STIFFNESS_RANGE_N_UM.1,
            ],
            "N/µm",
            "a light high-speed spindle to a heavy boring spindle",
        )?;
        within(
            "tool_youngs_modulus_gpa",
            self.tool_youngs_modulus_gpa,
            [YOUNGS_MODULUS_RANGE_GPA.0, YOUNGS_MODULUS_RANGE_GPA.1],
            "GPa",
            "high-speed steel to cemented carbide",
        )?;
        within(
            "tool_stick_out_mm",
            self.tool_stick_out_mm,
            [STICK_OUT_RANGE_MM.0, STICK_OUT_RANGE_MM.1],
            "mm",
            "a stub tool to a long-reach one",
        )?;
        let deepest_cut_mm = deepest_mm * self.depth_scale.unwrap_or(1.0);
        within(
            "tool_stick_out_mm",
            self.tool_stick_out_mm,
            [
                deepest_cut_mm.max(STICK_OUT_RANGE_MM.0),
                (MAX_STICK_OUT_DIAMETERS * diameter_mm).min(STICK_OUT_RANGE_MM.1),
            ],
            "mm",
            "the flutes reaching the deepest cut, at most 10 tool diameters out",
        )?;
        let deepest_allowed_mm = Self::MAX_DEPTH_PER_DIAMETER * diameter_mm;
        match self.depth_scale {
            Some(k) => within(
                "depth_scale",
                Some(k),
                [Self::MIN_DEPTH_SCALE, deepest_allowed_mm / deepest_mm],
                "",
                depth_why,
            ),
            // The preset's own depth on a smaller tool.
            None => within(
                "tool_diameter_mm",
                self.tool_diameter_mm,
                [
                    Self::TOOL_DIAMETER_MM[0].max(deepest_mm / Self::MAX_DEPTH_PER_DIAMETER),
                    Self::TOOL_DIAMETER_MM[1],
                ],
                "mm",
                depth_why,
            ),
        }
    }
}

impl PlantEdits {
    /// `value`, if given, inside `[min, max]`; the error names `field` and the range.
    fn within(
        field: &'static str,
        value: Option<f64>,
        [min, max]: [f64; 2],
        unit: &'static str,
        why: &'static str,
    ) -> Result<(), EditError> {
        match value {
            Some(v) if !(v >= min && v <= max) => Err(EditError {
                field,
                value: v,
                min,
                max,
                unit,
                why,
            }),
            _ => Ok(()),
        }
    }

    /// Checks the load step against its accepted range (see the table on [`PlantEdits`]).
    ///
    /// ```
    /// use cutlab::plant::presets::PlantEdits;
    /// let full_scale = PlantEdits { load_step_pct: Some(100.0), ..PlantEdits::default() };
    /// assert!(full_scale.check_load_step().is_ok());
    /// let e = PlantEdits { load_step_pct: Some(-95.0), ..PlantEdits::default() }
    ///     .check_load_step()
    ///     .unwrap_err();
    /// assert_eq!(e.to_string(), "load_step_pct: -95 % is outside the accepted -90–150 % (from a tenth of the depth to 2.5 times it)");
    /// ```
    pub fn check_load_step(&self) -> Result<(), EditError> {
        Self::within(
            "load_step_pct",
            self.load_step_pct,
            Self::LOAD_STEP_PCT,
            "%",
            "from a tenth of the depth to 2.5 times it",
        )
    }
}

/// A plant edit outside the range cutlab accepts (see [`PlantEdits`]).
#[derive(Debug, Clone, PartialEq)]
pub struct EditError {
    /// The edit, named as in [`PlantEdits`].
    pub field: &'static str,
    /// The value asked for.
    pub value: f64,
    /// The smallest value accepted.
    pub min: f64,
    /// The largest value accepted.
    pub max: f64,
    /// The unit of all three ("" for a factor).
    pub unit: &'static str,
    /// What the range stands for.
    pub why: &'static str,
}

impl fmt::Display for EditError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let with_unit = |v: f64| {
            let number = readable(v);
            if self.unit.is_empty() {
                number
            } else {
                format!("{number} {}", self.unit)
            }
        };
        write!(
            f,
            "{}: {} is outside the accepted {}–{} ({})",
            self.field,
            with_unit(self.value),
            readable(self.min),
            with_unit(self.max),
            self.why
        )
    }
}

impl std::error::Error for EditError {}

impl From<EditError> for PlantError {
    fn from(e: EditError) -> Self {
        let message = e.to_string();
        let message = message
            .strip_prefix(&format!("{}: ", e.field))
            .unwrap_or(&message)
            .to_string();
        PlantError::new(e.field, message)
    }
}
