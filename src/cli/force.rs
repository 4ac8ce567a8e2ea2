//! `cutlab force`: mean and peak milling forces of one cut, by simulating whole revolutions of
//! the mechanistic model ([`crate::plant::mechanics`]), beside the closed-form means.

use serde::Serialize;

use super::args::{reject_extra, required, value, value_or};
use super::{write_json, CliError, Io};
use crate::estimation::cut_forces::cutting_material;
use crate::input::readable;
use crate::plant::materials::CuttingCoefficients;
use crate::plant::mechanics::{
    mean_forces, Cutter, Immersion, MillingForceModel, MillingMode, ToolForces, MAX_EDGE_TURNS,
};
use crate::plant::PlantError;

pub(crate) const ABOUT: &str =
    "Mean and peak milling forces of one cut, from whole revolutions of the mechanistic\n\
model (Altintas ch. 2; paper 003 eq 1-6), with the closed-form means beside them.\n\
Forces act on the tool in the feed frame: x along the feed, y to its left, z along\n\
the tool axis.";

#[derive(Debug, clap::Args)]
pub struct ForceArgs {
    #[arg(
        long = "diameter-mm",
        help = "cutter diameter, mm",
        value_name = "D",
        allow_hyphen_values = true
    )]
    diameter_mm: Option<String>,
    #[arg(
        long = "teeth",
        help = "number of teeth (1-16)",
        value_name = "Z",
        allow_hyphen_values = true
    )]
    teeth: Option<String>,
    #[arg(
        long = "helix-deg",
        help = "helix angle, degrees (default 0: straight teeth)",
        value_name = "H",
        allow_hyphen_values = true
    )]
    helix_deg: Option<String>,
    #[arg(
        long = "axial-depth-mm",
        help = "axial depth of cut, mm",
        value_name = "A",
        allow_hyphen_values = true
    )]
    axial_depth_mm: Option<String>,
    #[arg(
        long = "radial-width-mm",
        help = "radial width of cut, mm, up to the diameter (default: the diameter; a slot's is \
                the diameter)",
        value_name = "W",
        allow_hyphen_values = true
    )]
    radial_width_mm: Option<String>,
    #[arg(
        long = "mode",
        help = "milling mode",
        value_name = "up|down|slot",
        allow_hyphen_values = true
    )]
    mode: Option<String>,
    #[arg(
        long = "feed-per-tooth-mm",
        help = "feed per tooth, mm",
        value_name = "F",
        allow_hyphen_values = true
    )]
    feed_per_tooth_mm: Option<String>,
    #[arg(
        long = "rpm",
        help = "spindle speed, rev/min",
        value_name = "N",
        allow_hyphen_values = true
    )]
    rpm: Option<String>,
    #[arg(
        long = "material",
        help = "work material: sm45c, aluminium, gc30, tool-steel",
        value_name = "NAME",
        allow_hyphen_values = true
    )]
    material: Option<String>,
    #[arg(
        long = "ktc",
        help = "tangential cutting coefficient K_tc",
        value_name = "N/mm²",
        allow_hyphen_values = true
    )]
    ktc: Option<String>,
    #[arg(
        long = "krc",
        help = "radial cutting coefficient K_rc",
        value_name = "N/mm²",
        allow_hyphen_values = true
    )]
    krc: Option<String>,
    #[arg(
        long = "kac",
        help = "axial cutting coefficient K_ac",
        value_name = "N/mm²",
        allow_hyphen_values = true
    )]
    kac: Option<String>,
    #[arg(
        long = "kte",
        help = "tangential edge coefficient K_te",
        value_name = "N/mm",
        allow_hyphen_values = true
    )]
    kte: Option<String>,
    #[arg(
        long = "kre",
        help = "radial edge coefficient K_re",
        value_name = "N/mm",
        allow_hyphen_values = true
    )]
    kre: Option<String>,
    #[arg(
        long = "kae",
        help = "axial edge coefficient K_ae",
        value_name = "N/mm",
        allow_hyphen_values = true
    )]
    kae: Option<String>,
    #[arg(
        long = "runout-um",
        help = "radial runout of the cutter, µm (default 0)",
        value_name = "R",
        allow_hyphen_values = true
    )]
    runout_um: Option<String>,
    #[arg(
        long = "runout-deg",
        help = "angle of the runout from tooth 0 (default 0)",
        value_name = "DEG",
        allow_hyphen_values = true
    )]
    runout_deg: Option<String>,
    #[arg(
        long = "revolutions",
        help = "whole revolutions to simulate (default 4)",
        value_name = "N",
        allow_hyphen_values = true
    )]
    revolutions: Option<String>,
    #[arg(
        long = "steps-per-rev",
        help = "angle steps per revolution (default 7200)",
        value_name = "N",
        allow_hyphen_values = true
    )]
    steps_per_rev: Option<String>,
    /// Stray words: refused with a hint where such input goes.
    #[arg(hide = true)]
    extra: Vec<String>,
}

/// The fastest spindle a mill has (high-speed spindles reach 60 000–100 000 rev/min); beyond it a
/// speed is a typing mistake, and the feed and power it implies overflow.
const MAX_SPINDLE_RPM: f64 = 200_000.0;

const COEFFICIENT_OPTIONS: [&str; 6] = ["ktc", "krc", "kac", "kte", "kre", "kae"];

#[derive(Serialize)]
struct Means {
    mean_fx_n: f64,
    mean_fy_n: f64,
    mean_fz_n: f64,
    mean_resultant_n: f64,
    mean_torque_nm: f64,
    mean_power_w: f64,
}

impl Means {
    fn from(f: &ToolForces, rpm: f64) -> Self {
        Self {
            mean_fx_n: f.fx_n,
            mean_fy_n: f.fy_n,
            mean_fz_n: f.fz_n,
            mean_resultant_n: f.resultant_n(),
            mean_torque_nm: f.torque_nm,
            mean_power_w: f.power_w(rpm),
        }
    }
}

#[derive(Serialize)]
struct ForceReport {
    frame: &'static str,
    material: Option<&'static str>,
    coefficients: CuttingCoefficients,
    diameter_mm: f64,
    teeth: u32,
    helix_deg: f64,
    runout_um: f64,
    mode: &'static str,
    axial_depth_mm: f64,
    radial_width_mm: f64,
    entry_deg: f64,
    exit_deg: f64,
    feed_per_tooth_mm: f64,
    rpm: f64,
    feed_mm_min: f64,
    revolutions: u32,
    steps_per_rev: u32,
    mean_fx_n: f64,
    mean_fy_n: f64,
    mean_fz_n: f64,
    mean_resultant_n: f64,
    mean_torque_nm: f64,
    mean_power_w: f64,
    peak_resultant_n: f64,
    peak_torque_nm: f64,
    closed_form: Means,
}

/// Turns a plant error into a CLI error naming the option it came from.
fn option_error(e: PlantError) -> CliError {
    let option = match e.field.as_str() {
        "ktc_n_mm2" => "ktc".to_string(),
        "krc_n_mm2" => "krc".to_string(),
        "kac_n_mm2" => "kac".to_string(),
        "kte_n_mm" => "kte".to_string(),
        "kre_n_mm" => "kre".to_string(),
        "kae_n_mm" => "kae".to_string(),
        "runout_mm" => "runout-um".to_string(),
        "runout_angle_deg" => "runout-deg".to_string(),
        other => other.replace('_', "-"),
    };
    CliError::new(format!("--{option}: {}", e.message))
}

fn positive_option(name: &str, text: &Option<String>) -> Result<f64, CliError> {
    let v: f64 = required(name, text)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(CliError::new(format!(
            "--{name}: must be a finite number > 0, got {v}"
        )))
    }
}

fn coefficients(args: &ForceArgs) -> Result<(Option<&'static str>, CuttingCoefficients), CliError> {
    let texts = [
        &args.ktc, &args.krc, &args.kac, &args.kte, &args.kre, &args.kae,
    ];
    let given: Vec<&str> = COEFFICIENT_OPTIONS
        .iter()
        .zip(texts)
        .filter(|(_, t)| t.is_some())
        .map(|(n, _)| *n)
        .collect();
    match (args.material.as_deref(), given.is_empty()) {
        (Some(_), false) => Err(CliError::new(format!(
            "--material and --{} exclude each other: give a material or all six coefficients",
            given[0]
        ))),
        (Some(name), true) => {
            let m =
                cutting_material(name).map_err(|e| CliError::new(format!("--material: {e}")))?;
            Ok((Some(m.name()), m.coefficients()))
        }
        (None, _) => {
            let mut v = [0.0; 6];
            for ((slot, name), text) in v.iter_mut().zip(COEFFICIENT_OPTIONS).zip(texts) {
                *slot = value(name, text)?.ok_or_else(|| {
                    CliError::new(format!(
                        "missing required option --{name} (or give --material)"
                    ))
                })?;
            }
            let k = CuttingCoefficients::new(v[0], v[1], v[2], v[3], v[4], v[5])
                .map_err(option_error)?;
            Ok((None, k))
        }
    }
}

/// A width the cut would not use is refused, never ignored: a slot's radial width is the
/// cutter's diameter, and no cut is wider than the cutter ([`Immersion::new`] would read either
/// as full immersion). A width equal to the diameter says what the cut does and passes.
fn check_radial_width(
    mode: MillingMode,
    radial_width_mm: f64,
    diameter_mm: f64,
) -> Result<(), CliError> {
    if radial_width_mm == diameter_mm {
        return Ok(());
    }
    let (width, diameter) = (readable(radial_width_mm), readable(diameter_mm));
    if mode == MillingMode::Slot {
        return Err(CliError::new(format!(
            "--radial-width-mm: a slot's radial width is the cutter's diameter ({diameter} mm), \
             not {width} mm; leave --radial-width-mm out for a slot, or give --mode up or down \
             for a cut {width} mm wide"
        )));
    }
    if radial_width_mm > diameter_mm {
        return Err(CliError::new(format!(
            "--radial-width-mm: {width} mm is wider than the {diameter} mm cutter; the widest \
             cut is the full diameter (--mode slot)"
        )));
    }
    Ok(())
}

/// Runs `cutlab force`.
pub fn run(args: ForceArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    reject_extra(&args.extra, "")?;
    let diameter_mm = positive_option("diameter-mm", &args.diameter_mm)?;
    let teeth: u32 = required("teeth", &args.teeth)?;
    let helix_deg: f64 = value_or("helix-deg", &args.helix_deg, 0.0)?;
    let runout_um: f64 = value_or("runout-um", &args.runout_um, 0.0)?;
    let runout_deg: f64 = value_or("runout-deg", &args.runout_deg, 0.0)?;
    let cutter = Cutter::new(diameter_mm, teeth, helix_deg)
        .and_then(|c| c.with_runout(runout_um * 1e-3, runout_deg))
        .map_err(option_error)?;
    let axial_depth_mm = positive_option("axial-depth-mm", &args.axial_depth_mm)?;
    if axial_depth_mm > cutter.max_axial_depth_mm() {
        return Err(CliError::new(format!(
            "--axial-depth-mm: {} mm is deeper than a {} mm cutter with a {}° helix \
             can be modelled (at most {:.0} mm, where the edge wraps {} turns)",
            readable(axial_depth_mm),
            cutter.diameter_mm,
            cutter.helix_deg,
            cutter.max_axial_depth_mm(),
            MAX_EDGE_TURNS - 2.0
        )));
    }
    let mode_text: String = required("mode", &args.mode)?;
    let mode = MillingMode::from_name(&mode_text).ok_or_else(|| {
        CliError::new(format!(
            "--mode: expected up, down or slot, got {mode_text:?}"
        ))
    })?;
    let radial_width_mm = match args.radial_width_mm.as_deref() {
        Some(_) => positive_option("radial-width-mm", &args.radial_width_mm)?,
        None => diameter_mm,
    };
    check_radial_width(mode, radial_width_mm, diameter_mm)?;
    let feed_per_tooth_mm = positive_option("feed-per-tooth-mm", &args.feed_per_tooth_mm)?;
    cutter
        .check_cut(axial_depth_mm, feed_per_tooth_mm)
        .map_err(|e| match e.field.as_str() {
            "axial_depth_mm" => CliError::new(format!("--axial-depth-mm: {}", e.message)),
            _ => CliError::new(format!("--feed-per-tooth-mm: {}", e.message)),
        })?;
    let rpm = positive_option("rpm", &args.rpm)?;
    if rpm > MAX_SPINDLE_RPM {
        return Err(CliError::new(format!(
            "--rpm: {} rev/min is beyond any milling spindle (at most {MAX_SPINDLE_RPM} rev/min)",
            readable(rpm)
        )));
    }
    let (material, k) = coefficients(&args)?;
    let revolutions: u32 = value_or("revolutions", &args.revolutions, 4)?;
    let steps_per_rev: u32 = value_or("steps-per-rev", &args.steps_per_rev, 7200)?;
    if !(1..=1000).contains(&revolutions) {
        return Err(CliError::new(format!(
            "--revolutions: must lie in 1..=1000, got {revolutions}"
        )));
    }
    if !(36..=1_000_000).contains(&steps_per_rev) {
        return Err(CliError::new(format!(
            "--steps-per-rev: must lie in 36..=1000000, got {steps_per_rev}"
        )));
    }

    let model = MillingForceModel::new(cutter).map_err(option_error)?;
    let immersion = Immersion::new(mode, radial_width_mm, diameter_mm);
    // Midpoint rule over whole revolutions: exact for the smooth parts, O(Δφ) at the entry and
    // exit jumps of the edge forces.
    let n = u64::from(revolutions) * u64::from(steps_per_rev);
    let step = std::f64::consts::TAU / f64::from(steps_per_rev);
    let mut sum = ToolForces::default();
    let mut peak_resultant_n = 0.0f64;
    let mut peak_torque_nm = 0.0f64;
    for i in 0..n {
        let angle = (i % u64::from(steps_per_rev)) as f64 * step + 0.5 * step;
        let f = model.forces(&k, &immersion, axial_depth_mm, feed_per_tooth_mm, angle);
        sum.fx_n += f.fx_n;
        sum.fy_n += f.fy_n;
        sum.fz_n += f.fz_n;
        sum.torque_nm += f.torque_nm;
        peak_resultant_n = peak_resultant_n.max(f.resultant_n());
        peak_torque_nm = peak_torque_nm.max(f.torque_nm);
    }
    let count = n as f64;
    let mean = ToolForces {
        fx_n: sum.fx_n / count,
        fy_n: sum.fy_n / count,
        fz_n: sum.fz_n / count,
        torque_nm: sum.torque_nm / count,
    };
    let closed = mean_forces(&cutter, &k, &immersion, axial_depth_mm, feed_per_tooth_mm);
    let report = ForceReport {
        frame: "forces on the tool; x along the feed, y to its left, z along the tool axis",
        material,
        coefficients: k,
        diameter_mm,
        teeth,
        helix_deg,
        runout_um,
        mode: mode.name(),
        axial_depth_mm,
        radial_width_mm: immersion.radial_width_mm(diameter_mm),
        entry_deg: immersion.entry_rad.to_degrees(),
        exit_deg: immersion.exit_rad.to_degrees(),
        feed_per_tooth_mm,
        rpm,
        feed_mm_min: feed_per_tooth_mm * f64::from(teeth) * rpm,
        revolutions,
        steps_per_rev,
        mean_fx_n: mean.fx_n,
        mean_fy_n: mean.fy_n,
        mean_fz_n: mean.fz_n,
        mean_resultant_n: mean.resultant_n(),
        mean_torque_nm: mean.torque_nm,
        mean_power_w: mean.power_w(rpm),
        peak_resultant_n,
        peak_torque_nm,
        closed_form: Means::from(&closed, rpm),
    };
    // JSON prints an overflowed number as null: say so instead.
    let numbers = [
        report.mean_fx_n,
        report.mean_fy_n,
        report.mean_fz_n,
        report.mean_resultant_n,
        report.mean_torque_nm,
        report.mean_power_w,
        report.peak_resultant_n,
        report.peak_torque_nm,
    ];
    if numbers.iter().any(|v| !v.is_finite()) {
        return Err(CliError::new(
            "the forces overflow f64: the cutting coefficients or the cut are beyond any \
             physical value",
        ));
    }
    write_json(io.stdout, &report)
}
