//! Every internal signal of one plant sample, with units, for plots, CSV and tests.
//!
//! [`crate::machine::SensorSample`] and [`crate::machine::PlantTruth`] are what the closed loop
//! sees; [`PlantSignals`] holds the truth and everything else a user may want to plot: the CNC's
//! commanded feed and dial code, both feed axes' torques and currents, the spindle's motor torque
//! and gear, the paper-004 power-law estimate. [`COLUMNS`] names each scalar with its unit, so a trace can be
//! written as CSV or listed in a chart picker from one table.
//!
//! Signals a plant does not have (feed per tooth in the bond graph, brake torque in the mill) are
//! NaN. The brake bench cuts nothing: its depth and width are 0.

use serde::Serialize;

use super::cnc::ControlStep;
use super::materials::Material;
use super::spindle_drive::SpindleGear;
use crate::machine::PlantTruth;

/// One feed axis in one sample.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct AxisSignals {
    /// Axis velocity.
    pub velocity_mm_min: f64,
    /// Cutting force the axis carries (positive resists positive motion).
    pub load_force_n: f64,
    /// Motor torque after the servo's lag.
    pub torque_nm: f64,
    /// i_q (phase-current amplitude).
    pub iq_a: f64,
    /// True phase currents.
    pub phase_currents_a: [f64; 3],
}

/// Everything one sample of a plant knows.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PlantSignals {
    /// Time since the start.
    pub time_s: f64,
    /// The ground truth the closed loop gets beside the sensors: forces, torque, power, depth,
    /// width and feed per tooth at the tool, path and tool position, removal rate, true RMS
    /// currents. Serialised flat, its fields beside the others.
    #[serde(flatten)]
    pub truth: PlantTruth,
    /// Commanded distance along the path.
    pub commanded_position_mm: f64,
    /// Index of the block being commanded.
    pub block: usize,
    /// Programmed feed.
    pub programmed_feed_mm_min: f64,
    /// Override the controller asked for.
    pub requested_override_pct: f64,
    /// Override the machine applies.
    pub applied_override_pct: f64,
    /// Dial code on X20.7/X20.4/X20.3/X20.2, if the override comes through the dial.
    pub dial_code: Option<u8>,
    /// Feed hold in force.
    pub feed_hold: bool,
    /// Commanded path feed.
    pub commanded_feed_mm_min: f64,
    /// Actual path feed.
    pub feed_mm_min: f64,
    /// Spindle speed command.
    pub spindle_command_rpm: f64,
    /// Spindle speed.
    pub spindle_speed_rpm: f64,
    /// Gear in use (None when stopped).
    pub spindle_gear: Option<SpindleGear>,
    /// Material at the tool (None in air).
    pub material: Option<Material>,
    /// Entry angle φ_st.
    pub entry_deg: f64,
    /// Exit angle φ_ex.
    pub exit_deg: f64,
    /// Paper 004's power-law resultant for the current conditions (its bias calibrated once to
    /// the mechanistic mean of the scenario's nominal cut).
    pub power_law_force_n: f64,
    /// X axis.
    pub axis_x: AxisSignals,
    /// Y axis.
    pub axis_y: AxisSignals,
    /// Spindle motor torque (lagged load plus acceleration).
    pub spindle_motor_torque_nm: f64,
    /// True spindle phase currents.
    pub spindle_phase_currents_a: [f64; 3],
    /// F/V converter output.
    pub fv_voltage_v: f64,
    /// Feed phase currents as read (Hall + ADC).
    pub feed_currents_read_a: [f64; 3],
    /// Spindle phase currents as read.
    pub spindle_currents_read_a: [f64; 3],
    /// Brake excitation current (brake bench only).
    pub brake_excitation_a: f64,
    /// Brake torque (brake bench only).
    pub brake_torque_nm: f64,
}

impl PlantSignals {
    /// A sample's signals with what every plant reports alike — the time, the truth, and the
    /// control's override, feed hold, block, commanded and actual feed and position — and the
    /// rest at their defaults, for the plant to fill in.
    #[inline(always)]
    pub fn from_control(time_s: f64, truth: PlantTruth, control: &ControlStep) -> Self {
        let cnc = &control.cnc;
        // Every field written out (no `..Default::default()`): the mill builds this every
        // sample, and the size-optimised browser build would call the default out of line.
        let axis = AxisSignals {
            velocity_mm_min: 0.0,
            load_force_n: 0.0,
            torque_nm: 0.0,
            iq_a: 0.0,
            phase_currents_a: [0.0; 3],
        };
        Self {
            time_s,
            truth,
            commanded_position_mm: cnc.commanded_position_mm,
            block: cnc.block,
            programmed_feed_mm_min: cnc.programmed_feed_mm_min,
            requested_override_pct: control.command.override_pct,
            applied_override_pct: control.applied.pct,
            dial_code: control.applied.dial_code,
            feed_hold: control.feed_hold,
            commanded_feed_mm_min: cnc.commanded_feed_mm_min,
            feed_mm_min: cnc.feed_mm_min,
            spindle_command_rpm: 0.0,
            spindle_speed_rpm: 0.0,
            spindle_gear: None,
            material: None,
            entry_deg: 0.0,
            exit_deg: 0.0,
            power_law_force_n: 0.0,
            axis_x: axis,
            axis_y: axis,
            spindle_motor_torque_nm: 0.0,
            spindle_phase_currents_a: [0.0; 3],
            fv_voltage_v: 0.0,
            feed_currents_read_a: [0.0; 3],
            spindle_currents_read_a: [0.0; 3],
            brake_excitation_a: 0.0,
            brake_torque_nm: 0.0,
        }
    }
}

/// One column of a trace: a name, its unit and how to read it.
#[derive(Clone, Copy)]
pub struct TraceColumn {
    /// Column name.
    pub name: &'static str,
    /// Unit ("" for dimensionless or flags).
    pub unit: &'static str,
    /// Reads the value (flags as 0/1, missing options as NaN).
    pub get: fn(&PlantSignals) -> f64,
}

impl std::fmt::Debug for TraceColumn {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{} [{}]", self.name, self.unit)
    }
}

fn gear_index(g: Option<SpindleGear>) -> f64 {
    match g {
        None => f64::NAN,
        Some(SpindleGear::High) => 0.0,
        Some(SpindleGear::Low) => 1.0,
    }
}

fn material_index(m: Option<Material>) -> f64 {
    m.and_then(|m| Material::ALL.iter().position(|x| *x == m))
        .map_or(f64::NAN, |i| i as f64)
}

macro_rules! col {
    ($name:literal, $unit:literal, |$s:ident| $e:expr) => {
        TraceColumn {
            name: $name,
            unit: $unit,
            get: |$s: &PlantSignals| $e,
        }
    };
}

/// Every scalar of [`PlantSignals`], in CSV order.
///
/// ```
/// use cutlab::plant::signals::{COLUMNS, PlantSignals};
/// let s = PlantSignals { feed_mm_min: 150.0, ..Default::default() };
/// let c = COLUMNS.iter().find(|c| c.name == "feed").unwrap();
/// assert_eq!(((c.get)(&s), c.unit), (150.0, "mm/min"));
/// ```
pub const COLUMNS: &[TraceColumn] = &[
    col!("time", "s", |s| s.time_s),
    col!("path_position", "mm", |s| s.truth.path_position_mm),
    col!("commanded_position", "mm", |s| s.commanded_position_mm),
    col!("tool_x", "mm", |s| s.truth.tool_x_mm),
    col!("tool_y", "mm", |s| s.truth.tool_y_mm),
    col!("block", "", |s| s.block as f64),
    col!("programmed_feed", "mm/min", |s| s.programmed_feed_mm_min),
    col!("requested_override", "%", |s| s.requested_override_pct),
    col!("applied_override", "%", |s| s.applied_override_pct),
    col!("dial_code", "", |s| s.dial_code.map_or(f64::NAN, f64::from)),
    col!("feed_hold", "", |s| f64::from(u8::from(s.feed_hold))),
    col!("commanded_feed", "mm/min", |s| s.commanded_feed_mm_min),
    col!("feed", "mm/min", |s| s.feed_mm_min),
    col!("feed_per_tooth", "mm", |s| s.truth.feed_per_tooth_mm),
    col!("spindle_command", "rpm", |s| s.spindle_command_rpm),
    col!("spindle_speed", "rpm", |s| s.spindle_speed_rpm),
    col!("spindle_gear", "0 high / 1 low", |s| gear_index(
        s.spindle_gear
    )),
    col!("depth", "mm", |s| s.truth.depth_mm),
    col!("width", "mm", |s| s.truth.width_mm),
    col!("material", "index", |s| material_index(s.material)),
    col!("entry", "deg", |s| s.entry_deg),
    col!("exit", "deg", |s| s.exit_deg),
    col!("force_x", "N", |s| s.truth.force_x_n),
    col!("force_y", "N", |s| s.truth.force_y_n),
    col!("force_z", "N", |s| s.truth.force_z_n),
    col!("force_resultant", "N", |s| s.truth.force_resultant_n),
    col!("feed_force", "N", |s| s.truth.feed_force_n),
    col!("spindle_torque", "N·m", |s| s.truth.spindle_torque_nm),
    col!("cutting_power", "W", |s| s.truth.cutting_power_w),
    col!("material_removal", "mm³/s", |s| s
        .truth
        .material_removal_mm3_s),
    col!("power_law_force", "N", |s| s.power_law_force_n),
    col!("x_velocity", "mm/min", |s| s.axis_x.velocity_mm_min),
    col!("x_load_force", "N", |s| s.axis_x.load_force_n),
    col!("x_torque", "N·m", |s| s.axis_x.torque_nm),
    col!("x_iq", "A", |s| s.axis_x.iq_a),
    col!("x_iu", "A", |s| s.axis_x.phase_currents_a[0]),
    col!("x_iv", "A", |s| s.axis_x.phase_currents_a[1]),
    col!("x_iw", "A", |s| s.axis_x.phase_currents_a[2]),
    col!("y_velocity", "mm/min", |s| s.axis_y.velocity_mm_min),
    col!("y_load_force", "N", |s| s.axis_y.load_force_n),
    col!("y_torque", "N·m", |s| s.axis_y.torque_nm),
    col!("y_iq", "A", |s| s.axis_y.iq_a),
    col!("y_iu", "A", |s| s.axis_y.phase_currents_a[0]),
    col!("y_iv", "A", |s| s.axis_y.phase_currents_a[1]),
    col!("y_iw", "A", |s| s.axis_y.phase_currents_a[2]),
    col!("feed_current_rms", "A", |s| s.truth.feed_current_rms_a),
    col!("spindle_motor_torque", "N·m", |s| s
        .spindle_motor_torque_nm),
    col!("spindle_current_rms", "A", |s| s
        .truth
        .spindle_current_rms_a),
    col!("spindle_iu", "A", |s| s.spindle_phase_currents_a[0]),
    col!("spindle_iv", "A", |s| s.spindle_phase_currents_a[1]),
    col!("spindle_iw", "A", |s| s.spindle_phase_currents_a[2]),
    col!("fv_voltage", "V", |s| s.fv_voltage_v),
    col!("feed_iu_read", "A", |s| s.feed_currents_read_a[0]),
    col!("feed_iv_read", "A", |s| s.feed_currents_read_a[1]),
    col!("feed_iw_read", "A", |s| s.feed_currents_read_a[2]),
    col!("spindle_iu_read", "A", |s| s.spindle_currents_read_a[0]),
    col!("spindle_iv_read", "A", |s| s.spindle_currents_read_a[1]),
    col!("spindle_iw_read", "A", |s| s.spindle_currents_read_a[2]),
    col!("brake_excitation", "A", |s| s.brake_excitation_a),
    col!("brake_torque", "N·m", |s| s.brake_torque_nm),
];

/// The CSV header: `name [unit]` per column (`name` alone when dimensionless).
///
/// ```
/// assert!(cutlab::plant::signals::csv_header().starts_with("time [s],path_position [mm],"));
/// ```
pub fn csv_header() -> String {
    COLUMNS
        .iter()
        .map(|c| {
            if c.unit.is_empty() {
                c.name.to_string()
            } else {
                format!("{} [{}]", c.name, c.unit)
            }
        })
        .collect::<Vec<_>>()
        .join(",")
}

/// One CSV row for `s` (NaN as an empty cell).
///
/// ```
/// use cutlab::plant::signals::{csv_row, PlantSignals};
/// let row = csv_row(&PlantSignals { time_s: 0.5, ..Default::default() });
/// assert!(row.starts_with("0.500000,0,"));
/// ```
pub fn csv_row(s: &PlantSignals) -> String {
    COLUMNS
        .iter()
        .map(|c| format_value((c.get)(s)))
        .collect::<Vec<_>>()
        .join(",")
}

fn format_value(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else if v == v.trunc() && v.abs() < 1e15 {
        format!("{v:.0}")
    } else {
        format!("{v:.6}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn column_names_are_unique_and_the_header_matches_the_rows() {
        let mut names: Vec<&str> = COLUMNS.iter().map(|c| c.name).collect();
        names.sort_unstable();
        names.dedup();
        assert_eq!(names.len(), COLUMNS.len());
        let row = csv_row(&PlantSignals::default());
        assert_eq!(row.split(',').count(), csv_header().split(',').count());
    }

    #[test]
    fn missing_options_are_empty_cells() {
        let s = PlantSignals {
            spindle_gear: Some(SpindleGear::Low),
            ..Default::default()
        };
        let row = csv_row(&s);
        let cells: Vec<&str> = row.split(',').collect();
        let gear = COLUMNS
            .iter()
            .position(|c| c.name == "spindle_gear")
            .unwrap();
        let dial = COLUMNS.iter().position(|c| c.name == "dial_code").unwrap();
        assert_eq!(cells[gear], "1");
        assert_eq!(cells[dial], "");
    }
}
