//! Trial cuts read from a run: the steady part of each depth section of a trace, with its
//! conditions, the force the plant made and the force the lab estimated from the currents —
//! what paper 004's network learns from ([`crate::estimation::power_law_fit`]).
//!
//! [`preset_trial_cuts`] makes them as a shop would on its own machine: the preset's program
//! cut at a fixed feed, once per feed, each depth section a trial cut.

use super::definition::RunSpec;
use super::error::LoopError;
use super::lab::simulate;
use super::settings::OperatingPoint;
use super::trace::{Trace, TraceRow};
use crate::control::registry::ControllerKind;
use crate::estimation::cut_forces::CutGeometry;
use crate::estimation::power_law_fit::{
    learn, local_exponent, mechanistic_resultant_n, LearnError, LearnedPowerLaw, TrialCut,
};
use crate::plant::power_law::{PowerLawInput, PowerLawInputs, PowerLawMaterial, PowerLawReading};
use crate::plant::presets::PlantKind;
use crate::plant::sensorless::SensorlessNetwork;
use crate::plant::simulator::power_law_material;
use crate::plant::Preset;

/// The feeds [`preset_trial_cuts`] cuts a program at when nobody says, percent of its programmed
/// feed: three feeds per tooth, so the feed's exponent can be learned beside the depth's.
pub const DEFAULT_TRIAL_FEEDS_PCT: [f64; 3] = [60.0, 80.0, 100.0];

/// The trial cuts of a preset's program: each depth section's steady mean, at each feed.
#[derive(Debug, Clone, PartialEq)]
pub struct PresetTrialCuts {
    /// With the force on the tool (the simulation's truth, as a dynamometer would read it).
    pub measured: Vec<TrialCut>,
    /// With the lab's current-based estimate of the same cuts.
    pub estimated: Vec<TrialCut>,
    /// The published weights the learned ones are compared with: the part's first material's.
    pub material: PowerLawMaterial,
}

/// Cuts `preset`'s program at a fixed feed of each of `feeds_pct` (percent of its programmed
/// feed; the run definition's other settings the preset's) and reads the trial cuts of each run.
/// `None` for a preset without a cutter (the bench, paper 001's process, paper 002's bond graph).
pub fn preset_trial_cuts(
    preset: Preset,
    feeds_pct: &[f64],
) -> Option<Result<PresetTrialCuts, LoopError>> {
    let scenario = preset.scenario_spec()?;
    let (teeth, diameter_mm) = (scenario.cutter.teeth, scenario.cutter.diameter_mm);
    let material = power_law_material(scenario.materials.first()?.material);
    let programmed =
        OperatingPoint::of_preset(&RunSpec::new(preset, ControllerKind::Fixed)).feed_mm_min;
    let mut cuts = PresetTrialCuts {
        measured: Vec::new(),
        estimated: Vec::new(),
        material,
    };
    for pct in feeds_pct {
        let mut spec = RunSpec::new(preset, ControllerKind::Fixed);
        spec.plant.programmed_feed_mm_min = Some(programmed * pct / 100.0);
        let run = match simulate(&spec) {
            Ok(run) => run,
            Err(e) => return Some(Err(e)),
        };
        for (force, out) in [
            (TrialForce::Measured, &mut cuts.measured),
            (TrialForce::Estimated, &mut cuts.estimated),
        ] {
            out.extend(trial_cuts(&run.trace, teeth, diameter_mm, force));
        }
    }
    Some(Ok(cuts))
}

/// Which force a trial cut carries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TrialForce {
    /// The force on the tool (the simulation's truth, a dynamometer's reading).
    Measured,
    /// The lab's current-based estimate.
    Estimated,
}

/// Periods a section needs, after its transient half is left out, to count as a trial cut.
const MIN_STEADY_PERIODS: usize = 5;

/// One trial cut per section of constant depth (in work) in `trace`: the mean over the later half
/// of the section, the first half being the feed's and the force's transient after the step.
/// `teeth` and `diameter_mm` are the cutter's.
pub fn trial_cuts(trace: &Trace, teeth: u32, diameter_mm: f64, force: TrialForce) -> Vec<TrialCut> {
    let rows = &trace.rows;
    let mut cuts = Vec::new();
    let mut start = 0;
    for end in 1..=rows.len() {
        let boundary =
            end == rows.len() || (rows[end].depth_mm - rows[start].depth_mm).abs() > 1e-9;
        if !boundary {
            continue;
        }
        let steady = &rows[start + (end - start) / 2..end];
        start = end;
        if steady.len() < MIN_STEADY_PERIODS || steady[0].depth_mm <= 0.0 {
            continue;
        }
        let mean = |value: fn(&TraceRow) -> f64| {
            steady.iter().map(value).sum::<f64>() / steady.len() as f64
        };
        let teeth_f = f64::from(teeth);
        let feed_per_tooth_mm = steady
            .iter()
            .map(|r| r.feed_mm_min / (r.spindle_speed_rpm * teeth_f))
            .sum::<f64>()
            / steady.len() as f64;
        let inputs = PowerLawInputs {
            radial_width_mm: mean(|r| r.width_mm),
            feed_per_tooth_mm,
            axial_depth_mm: steady[0].depth_mm,
            diameter_mm,
            // Not read by the handbook reading the lab uses; the mean over a revolution is the
            // cutter's engagement, which a trace does not carry.
            teeth_engaged: f64::NAN,
            cutter_teeth: teeth_f,
        };
        let force_n = match force {
            TrialForce::Measured => mean(|r| r.force_n),
            TrialForce::Estimated => mean(|r| r.force_est_n),
        };
        cuts.push(TrialCut { inputs, force_n });
    }
    cuts
}

/// One trial cut as the learning shows it: its conditions and both forces.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LearningCut {
    /// a_e, mm.
    pub radial_width_mm: f64,
    /// f, mm per tooth.
    pub feed_per_tooth_mm: f64,
    /// a_p, mm.
    pub axial_depth_mm: f64,
    /// The force on the tool, N.
    pub force_n: f64,
    /// The lab's current-based estimate of it, N.
    pub estimate_n: f64,
}

/// Paper 004's network learned on a preset's trial cuts, from the force and from the estimate,
/// beside the mechanistic model's local exponents: what `cutlab learn` prints and the Machine
/// page shows.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PresetLearning {
    /// The preset whose program made the cuts.
    pub preset: Preset,
    /// The trial cuts, in the order of the fits' residuals.
    pub cuts: Vec<LearningCut>,
    /// The published weights the learned ones are compared with.
    pub material: PowerLawMaterial,
    /// Learned on the force on the tool.
    pub from_force: LearnedPowerLaw,
    /// Learned on the lab's current-based estimate.
    pub from_estimate: LearnedPowerLaw,
    /// For each learned input, the mechanistic model's local exponent (smallest, largest) over
    /// the cuts: what a power law fitted near each cut would find.
    pub mechanistic: Vec<(PowerLawInput, f64, f64)>,
}

impl PresetLearning {
    /// The mechanistic model's local exponent for `input` over the cuts, as `cutlab learn` and
    /// the Machine page write it: one value where it hardly varies ("0.78"), else its range
    /// ("0.71–0.86"); `None` for an input the network did not learn.
    pub fn mechanistic_text(&self, input: PowerLawInput) -> Option<String> {
        self.mechanistic
            .iter()
            .find(|(i, _, _)| *i == input)
            .map(|&(_, lo, hi)| {
                if (hi - lo).abs() < 0.005 {
                    format!("{lo:.2}")
                } else {
                    format!("{lo:.2}–{hi:.2}")
                }
            })
    }
}

/// Why a preset's network could not be learned.
#[derive(Debug, Clone, PartialEq)]
pub enum LearningError {
    /// The preset has no cutter (the bench, paper 001's process, paper 002's bond graph).
    NoCutter(Preset),
    /// A trial run failed.
    Run(LoopError),
    /// The cuts do not determine the network; `from` says which force ("force", "estimate").
    Learn {
        /// Which force the network was learned on.
        from: &'static str,
        /// Why.
        error: LearnError,
    },
}

impl std::fmt::Display for LearningError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LearningError::NoCutter(preset) => write!(
                f,
                "{} has no cutter to make trial cuts with; use a mill preset",
                preset.name()
            ),
            LearningError::Run(e) => write!(f, "a trial run failed: {e}"),
            LearningError::Learn { from, error } => write!(f, "learning from the {from}: {error}"),
        }
    }
}

impl std::error::Error for LearningError {}

/// Learns paper 004's network on `preset`'s trial cuts at `feeds_pct` ([`preset_trial_cuts`]),
/// in the reading the lab uses, against the published weights of the part's material.
pub fn learn_on_preset(preset: Preset, feeds_pct: &[f64]) -> Result<PresetLearning, LearningError> {
    let cuts = preset_trial_cuts(preset, feeds_pct)
        .ok_or(LearningError::NoCutter(preset))?
        .map_err(LearningError::Run)?;
    let material = cuts.material;
    let learned = |cuts: &[TrialCut], from: &'static str| {
        learn(cuts, PowerLawReading::USED, material)
            .map_err(|error| LearningError::Learn { from, error })
    };
    let from_force = learned(&cuts.measured, "force")?;
    let from_estimate = learned(&cuts.estimated, "estimate")?;
    let geometry = preset.scenario_spec().and_then(|spec| {
        Some(CutGeometry {
            coefficients: spec.materials.first()?.material.coefficients(),
            cutter: spec.cutter,
            mode: spec.mode,
        })
    });
    let mechanistic = match &geometry {
        Some(cut) => from_force
            .learned
            .iter()
            .filter_map(|e| {
                let (lo, hi) = cuts
                    .measured
                    .iter()
                    .map(|c| {
                        local_exponent(|p| mechanistic_resultant_n(cut, p), &c.inputs, e.input)
                    })
                    .filter(|v| v.is_finite())
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                        (lo.min(v), hi.max(v))
                    });
                (lo <= hi).then_some((e.input, lo, hi))
            })
            .collect(),
        None => Vec::new(),
    };
    Ok(PresetLearning {
        preset,
        cuts: cuts
            .measured
            .iter()
            .zip(&cuts.estimated)
            .map(|(m, e)| LearningCut {
                radial_width_mm: m.inputs.radial_width_mm,
                feed_per_tooth_mm: m.inputs.feed_per_tooth_mm,
                axial_depth_mm: m.inputs.axial_depth_mm,
                force_n: m.force_n,
                estimate_n: e.force_n,
            })
            .collect(),
        material,
        from_force,
        from_estimate,
        mechanistic,
    })
}

/// The network each mill preset learns on its trial cuts at [`DEFAULT_TRIAL_FEEDS_PCT`] from
/// the lab's current-based estimates ([`PresetLearning::from_estimate`]): what the plant ships
/// for its sensorless estimate ([`crate::plant::sensorless::shipped_network`]). From the
/// estimate, as paper 004 trains its network on the existing current-based monitor's values
/// and as a shop without a dynamometer can: the network then predicts what a healthy sensor
/// reads, its calibration's bias included, and a sensor that leaves it is failing. A preset
/// whose program cannot teach a network (one depth of cut: the depth's exponent cannot be told
/// from the bias) is left out.
pub fn preset_networks() -> Result<Vec<(Preset, SensorlessNetwork)>, LearningError> {
    let mut networks = Vec::new();
    // Only the simulated mill estimates its force from what the CNC knows.
    let mills = Preset::ALL
        .into_iter()
        .filter(|p| p.plant_kind() == PlantKind::Mill);
    for preset in mills {
        match learn_on_preset(preset, &DEFAULT_TRIAL_FEEDS_PCT) {
            Ok(learning) => networks.push((preset, learning.from_estimate.network)),
            Err(LearningError::NoCutter(_) | LearningError::Learn { .. }) => {}
            Err(e) => return Err(e),
        }
    }
    Ok(networks)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(time_s: f64, depth_mm: f64, force_n: f64) -> TraceRow {
        TraceRow {
            time_s,
            depth_mm,
            width_mm: 20.0,
            feed_mm_min: 200.0,
            spindle_speed_rpm: 1000.0,
            force_n,
            force_est_n: force_n * 1.1,
            ..TraceRow::default()
        }
    }

    #[test]
    fn each_depth_section_gives_its_steady_mean() {
        let mut trace = Trace::default();
        // Air, then 1 mm (transient 50 → 100 N, then 100 N), then a section too short to count.
        for k in 0..10 {
            trace.rows.push(row(f64::from(k), 0.0, 0.0));
        }
        for k in 0..20 {
            let force = if k < 10 { 50.0 } else { 100.0 };
            trace.rows.push(row(10.0 + f64::from(k), 1.0, force));
        }
        for k in 0..6 {
            trace.rows.push(row(30.0 + f64::from(k), 2.0, 200.0));
        }
        let cuts = trial_cuts(&trace, 2, 20.0, TrialForce::Measured);
        assert_eq!(cuts.len(), 1);
        assert_eq!(cuts[0].force_n, 100.0);
        assert_eq!(cuts[0].inputs.axial_depth_mm, 1.0);
        assert!((cuts[0].inputs.feed_per_tooth_mm - 0.1).abs() < 1e-12);
        let estimated = trial_cuts(&trace, 2, 20.0, TrialForce::Estimated);
        assert!((estimated[0].force_n - 110.0).abs() < 1e-9);
    }
}
