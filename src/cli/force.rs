//! `cutlab force`: mean and peak milling forces of one cut, by simulating whole revolutions of
//! the mechanistic model ([`crate::plant::mechanics`]), beside the closed-form means.

use serde::Serialize;

use super::{help_text_for, wants_help, write_json, CliError, Io, OptionSpec, Options};
use crate::estimation::cut_forces::cutting_material;
use crate::plant::materials::CuttingCoefficients;
use crate::plant::mechanics::{
    mean_forces, Cutter, Immersion, MillingForceModel, MillingMode, ToolForces, MAX_EDGE_TURNS,
};
use crate::plant::PlantError;

const OPTIONS: &[OptionSpec] = &[
    OptionSpec::value("diameter-mm", "D", "cutter diameter, mm"),
    OptionSpec::value("teeth", "Z", "number of teeth (1-16)"),
    OptionSpec::value(
        "helix-deg",
        "H",
        "helix angle, degrees (default 0: straight teeth)",
    ),
    OptionSpec::value("axial-depth-mm", "A", "axial depth of cut, mm"),
    OptionSpec::value(
        "radial-width-mm",
        "W",
        "radial width of cut, mm (default: the diameter)",
    ),
    OptionSpec::value("mode", "up|down|slot", "milling mode"),
    OptionSpec::value("feed-per-tooth-mm", "F", "feed per tooth, mm"),
    OptionSpec::value("rpm", "N", "spindle speed, rev/min"),
    OptionSpec::value(
        "material",
        "NAME",
        "work material: sm45c, aluminium, gc30, tool-steel",
    ),
    OptionSpec::value("ktc", "N/mm²", "tangential cutting coefficient K_tc"),
    OptionSpec::value("krc", "N/mm²", "radial cutting coefficient K_rc"),
    OptionSpec::value("kac", "N/mm²", "axial cutting coefficient K_ac"),
    OptionSpec::value("kte", "N/mm", "tangential edge coefficient K_te"),
    OptionSpec::value("kre", "N/mm", "radial edge coefficient K_re"),
    OptionSpec::value("kae", "N/mm", "axial edge coefficient K_ae"),
    OptionSpec::value(
        "runout-um",
        "R",
        "radial runout of the cutter, µm (default 0)",
    ),
    OptionSpec::value(
        "runout-deg",
        "DEG",
        "angle of the runout from tooth 0 (default 0)",
    ),
    OptionSpec::value(
        "revolutions",
        "N",
        "whole revolutions to simulate (default 4)",
    ),
    OptionSpec::value(
        "steps-per-rev",
        "N",
        "angle steps per revolution (default 7200)",
    ),
];

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

fn positive_option(options: &Options, name: &str) -> Result<f64, CliError> {
    let v: f64 = options.require(name)?;
    if v.is_finite() && v > 0.0 {
        Ok(v)
    } else {
        Err(CliError::new(format!(
            "--{name}: must be a finite number > 0, got {v}"
        )))
    }
}

fn coefficients(
    options: &Options,
) -> Result<(Option<&'static str>, CuttingCoefficients), CliError> {
    let given: Vec<&str> = COEFFICIENT_OPTIONS
        .iter()
        .copied()
        .filter(|n| options.text(n).is_some())
        .collect();
    match (options.text("material"), given.is_empty()) {
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
            for (slot, name) in v.iter_mut().zip(COEFFICIENT_OPTIONS) {
                *slot = options.get(name)?.ok_or_else(|| {
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

/// Runs `cutlab force`.
pub fn run(args: &[String], io: &mut Io<'_>) -> Result<(), CliError> {
    if wants_help(args) {
        return help_text_for(
            io,
            "cutlab force --diameter-mm D --teeth Z [--helix-deg H] --axial-depth-mm A \
             [--radial-width-mm W] --mode up|down|slot --feed-per-tooth-mm F --rpm N \
             (--material NAME | --ktc … --kae …)",
            "Mean and peak milling forces of one cut, from whole revolutions of the mechanistic\n\
             model (Altintas ch. 2; paper 003 eq 1-6), with the closed-form means beside them.\n\
             Forces act on the tool in the feed frame: x along the feed, y to its left, z along\n\
             the tool axis.",
            OPTIONS,
        );
    }
    let options = Options::parse(args, OPTIONS)?;
    options.reject_positionals("")?;
    let diameter_mm = positive_option(&options, "diameter-mm")?;
    let teeth: u32 = options.require("teeth")?;
    let helix_deg: f64 = options.get_or("helix-deg", 0.0)?;
    let runout_um: f64 = options.get_or("runout-um", 0.0)?;
    let runout_deg: f64 = options.get_or("runout-deg", 0.0)?;
    let cutter = Cutter::new(diameter_mm, teeth, helix_deg)
        .and_then(|c| c.with_runout(runout_um * 1e-3, runout_deg))
        .map_err(option_error)?;
    let axial_depth_mm = positive_option(&options, "axial-depth-mm")?;
    if axial_depth_mm > cutter.max_axial_depth_mm() {
        return Err(CliError::new(format!(
            "--axial-depth-mm: {axial_depth_mm} mm is deeper than a {} mm cutter with a {}° helix \
             can be modelled (at most {:.0} mm, where the edge wraps {} turns)",
            cutter.diameter_mm,
            cutter.helix_deg,
            cutter.max_axial_depth_mm(),
            MAX_EDGE_TURNS - 2.0
        )));
    }
    let mode_text: String = options.require("mode")?;
    let mode = MillingMode::from_name(&mode_text).ok_or_else(|| {
        CliError::new(format!(
            "--mode: expected up, down or slot, got {mode_text:?}"
        ))
    })?;
    let radial_width_mm = match options.text("radial-width-mm") {
        Some(_) => positive_option(&options, "radial-width-mm")?,
        None => diameter_mm,
    };
    let feed_per_tooth_mm = positive_option(&options, "feed-per-tooth-mm")?;
    cutter
        .check_cut(axial_depth_mm, feed_per_tooth_mm)
        .map_err(|e| match e.field.as_str() {
            "axial_depth_mm" => CliError::new(format!("--axial-depth-mm: {}", e.message)),
            _ => CliError::new(format!("--feed-per-tooth-mm: {}", e.message)),
        })?;
    let rpm = positive_option(&options, "rpm")?;
    let (material, k) = coefficients(&options)?;
    let revolutions: u32 = options.get_or("revolutions", 4)?;
    let steps_per_rev: u32 = options.get_or("steps-per-rev", 7200)?;
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
