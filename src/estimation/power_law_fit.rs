//! Paper 004's network learned from the machine's own cuts: trial cuts of varying depth, width
//! and feed per tooth, each with a force the machine measured (a current-based estimate, or a
//! dynamometer), give the power law's exponents and bias for this machine, tool and material.
//!
//! Paper 004 trains a linear network in log space (eq 3–4) until its output matches the forces of
//! an existing current-based monitor. A linear network trained to convergence on a squared error
//! reaches the least-squares solution, so cutlab solves that directly:
//!
//! ```text
//! ln F = ln b + Σ_k w_k · ln p_k          over the inputs p_k that vary between the cuts
//! ```
//!
//! by [`crate::math::least_squares::fit`], which also gives each weight's standard error. An input
//! that does not vary over the cuts (one tool: its diameter and teeth) cannot be told from the
//! bias; its exponent is *held* at the published one and its effect folded into the bias, and the
//! result says so. The network learned is the resultant's, the one force the lab's estimate
//! gives; paper 004's three component rows differ by less than 0.01 in every exponent, so the
//! resultant's published exponent is their mean ([`published_resultant_exponent`]).
//!
//! The learned model then predicts the force from what the CNC knows: [`LearnedPowerLaw::network`]
//! is the plant's sensorless estimate ([`crate::plant::sensorless`]), which paper 004's sensor
//! failure prediction compares the current-based estimate with.

use std::fmt;

use super::cut_forces::CutGeometry;
use crate::math;
use crate::math::least_squares::{fit, FitError};
use crate::plant::power_law::{
    PowerLawInput, PowerLawInputs, PowerLawMaterial, PowerLawReading, EXPONENT_UNCERTAINTY,
};
use crate::plant::sensorless::{NetworkInput, SensorlessNetwork};

pub use crate::plant::sensorless::UNCERTAINTY_STANDARD_ERRORS;

/// A relative spread below this (on the log scale) counts as "does not vary": the input is held.
const CONSTANT_LOG_SPREAD: f64 = 1e-9;

/// One trial cut: its conditions and the force measured on it.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TrialCut {
    /// The cutting conditions.
    pub inputs: PowerLawInputs,
    /// The resultant force measured on the cut, N.
    pub force_n: f64,
}

/// One exponent of the learned network.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LearnedExponent {
    /// The input it is the exponent of.
    pub input: PowerLawInput,
    /// The learned exponent.
    pub exponent: f64,
    /// ± this many ([`UNCERTAINTY_STANDARD_ERRORS`] standard errors).
    pub uncertainty: f64,
    /// Paper 004's exponent for the input (the mean of its three component rows).
    pub published: f64,
}

impl LearnedExponent {
    /// The exponent and its uncertainty as `cutlab learn` and the Machine page write them:
    /// "0.78 ± 0.04".
    pub fn with_uncertainty(&self) -> String {
        format!("{:.2} ± {:.2}", self.exponent, self.uncertainty)
    }
}

/// The network learned from a set of trial cuts.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LearnedPowerLaw {
    /// How the published columns were read (which input each exponent belongs to).
    pub reading: PowerLawReading,
    /// The bias b, N: the force at every input 1 (mm, per tooth, teeth).
    pub bias_n: f64,
    /// The exponents learned, one per input that varies over the cuts.
    pub learned: Vec<LearnedExponent>,
    /// The inputs that did not vary, with the published exponent each is held at.
    pub held: Vec<(PowerLawInput, f64)>,
    /// Each cut's residual, percent: 100·(measured / predicted − 1).
    pub residuals_pct: Vec<f64>,
    /// Root-mean-square of the residuals on the log scale (≈ relative error).
    pub residual_rms_log: f64,
    /// The network as the plant evaluates it for its sensorless estimate: every exponent, learned
    /// or held, with its uncertainty and the trial cuts' centre.
    pub network: SensorlessNetwork,
}

/// Why a network could not be learned.
#[derive(Debug, Clone, PartialEq)]
pub enum LearnError {
    /// A cut with a force or an input that is not a positive finite number (no cut: log of 0).
    NotACut {
        /// Index of the cut, from 0.
        index: usize,
        /// What is wrong.
        problem: String,
    },
    /// Too few cuts for the exponents that vary, plus the bias, plus two degrees of freedom.
    TooFewCuts {
        /// Cuts given.
        cuts: usize,
        /// Cuts needed.
        needed: usize,
    },
    /// The inputs do not vary independently (e.g. depth and width stepped together).
    Collinear(FitError),
}

impl fmt::Display for LearnError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LearnError::NotACut { index, problem } => {
                write!(f, "trial cut {}: {problem}", index + 1)
            }
            LearnError::TooFewCuts { cuts, needed } => write!(
                f,
                "{cuts} trial cuts cannot determine the exponents that vary: give at least {needed}"
            ),
            // The fit's own hint is a teach cut's; trial cuts are varied differently.
            LearnError::Collinear(FitError::RankDeficient { column }) => write!(
                f,
                "the trial cuts do not vary {column} independently of the other inputs: vary \
                 width, feed per tooth and depth apart (paper 004's stepped specimen crosses them)"
            ),
            LearnError::Collinear(e) => write!(f, "{e}"),
        }
    }
}

impl std::error::Error for LearnError {}

/// Paper 004's exponent of `input` for the resultant under `reading`: the mean of its three
/// component rows (which differ by less than 0.01); 0 for an input the reading does not use.
pub fn published_resultant_exponent(
    material: PowerLawMaterial,
    reading: PowerLawReading,
    input: PowerLawInput,
) -> f64 {
    let Some(column) = reading.columns().iter().position(|&c| c == input) else {
        return 0.0;
    };
    material
        .weights()
        .iter()
        .map(|row| row[column])
        .sum::<f64>()
        / 3.0
}

/// Learns the resultant's power law from `cuts`, the inputs of `reading`; exponents of inputs
/// that do not vary are held at `material`'s published ones.
///
/// ```
/// use cutlab::estimation::power_law_fit::{learn, TrialCut};
/// use cutlab::plant::power_law::{PowerLawInput, PowerLawInputs, PowerLawMaterial, PowerLawReading};
/// // Forces from F = 500 · a_e^0.9 · f^0.7 · a_p (one Ø20 mm, 2-tooth cutter).
/// let mut cuts = Vec::new();
/// for a_e in [5.0, 10.0, 20.0] {
///     for f in [0.05, 0.1, 0.2] {
///         for a_p in [1.0, 2.0, 4.0] {
///             let inputs = PowerLawInputs { radial_width_mm: a_e, feed_per_tooth_mm: f,
///                 axial_depth_mm: a_p, diameter_mm: 20.0, teeth_engaged: 1.0, cutter_teeth: 2.0 };
///             let force_n = 500.0 * f64::powf(a_e, 0.9) * f64::powf(f, 0.7) * a_p;
///             cuts.push(TrialCut { inputs, force_n });
///         }
///     }
/// }
/// let law = learn(&cuts, PowerLawReading::Handbook, PowerLawMaterial::CarbonSteel).unwrap();
/// let feed = law.learned.iter().find(|e| e.input == PowerLawInput::FeedPerTooth).unwrap();
/// assert!((feed.exponent - 0.7).abs() < 1e-9);
/// assert_eq!(law.held.len(), 2); // the diameter and the teeth: one cutter
/// assert!((law.force_n(&cuts[0].inputs) - cuts[0].force_n).abs() < 1e-6);
/// ```
pub fn learn(
    cuts: &[TrialCut],
    reading: PowerLawReading,
    material: PowerLawMaterial,
) -> Result<LearnedPowerLaw, LearnError> {
    let columns = reading.columns();
    for (index, cut) in cuts.iter().enumerate() {
        let bad = |what: &str, v: f64| LearnError::NotACut {
            index,
            problem: format!("{what} must be a positive number, got {v}"),
        };
        if !(cut.force_n.is_finite() && cut.force_n > 0.0) {
            return Err(bad("the force (N)", cut.force_n));
        }
        for &input in &columns {
            let v = cut.inputs.value(input);
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(input.symbol(), v));
            }
        }
    }
    let logs = |input: PowerLawInput| -> Vec<f64> {
        cuts.iter()
            .map(|c| math::ln(c.inputs.value(input)))
            .collect()
    };
    let (varying, constant): (Vec<PowerLawInput>, Vec<PowerLawInput>) =
        columns.iter().partition(|&&input| {
            let l = logs(input);
            let lo = l.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = l.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            hi - lo > CONSTANT_LOG_SPREAD
        });
    let needed = varying.len() + 1 + 2;
    if cuts.len() < needed {
        return Err(LearnError::TooFewCuts {
            cuts: cuts.len(),
            needed,
        });
    }
    let held: Vec<(PowerLawInput, f64)> = constant
        .iter()
        .map(|&input| {
            (
                input,
                published_resultant_exponent(material, reading, input),
            )
        })
        .collect();
    // The held inputs' part of ln F, known: taken off the target before the fit.
    let held_log = |c: &TrialCut| -> f64 {
        held.iter()
            .map(|&(input, w)| w * math::ln(c.inputs.value(input)))
            .sum()
    };
    let target: Vec<f64> = cuts
        .iter()
        .map(|c| math::ln(c.force_n) - held_log(c))
        .collect();
    let ones = vec![1.0; cuts.len()];
    let regressors: Vec<Vec<f64>> = varying.iter().map(|&i| logs(i)).collect();
    let mut design: Vec<(&'static str, &[f64])> = vec![("bias", &ones)];
    design.extend(
        varying
            .iter()
            .zip(&regressors)
            .map(|(i, r)| (i.symbol(), r.as_slice())),
    );
    let solved = fit(&design, &target).map_err(LearnError::Collinear)?;
    let learned: Vec<LearnedExponent> = varying
        .iter()
        .enumerate()
        .map(|(k, &input)| LearnedExponent {
            input,
            exponent: solved.coefficients[k + 1],
            uncertainty: UNCERTAINTY_STANDARD_ERRORS * solved.standard_errors[k + 1],
            published: published_resultant_exponent(material, reading, input),
        })
        .collect();
    // The trial cuts' geometric centre in each input: where the network's band is narrowest.
    let centre =
        |input: PowerLawInput| math::exp(logs(input).iter().sum::<f64>() / cuts.len() as f64);
    let network_inputs = learned
        .iter()
        .map(|e| (e.input, e.exponent, e.uncertainty))
        .chain(
            held.iter()
                .map(|&(input, w)| (input, w, EXPONENT_UNCERTAINTY)),
        )
        .map(|(input, exponent, uncertainty)| NetworkInput {
            input,
            exponent,
            uncertainty,
            centre: centre(input),
        })
        .collect();
    let bias_n = math::exp(solved.coefficients[0]);
    let mut law = LearnedPowerLaw {
        reading,
        bias_n,
        learned,
        held,
        residuals_pct: Vec::new(),
        residual_rms_log: 0.0,
        network: SensorlessNetwork {
            bias_n,
            inputs: network_inputs,
            residual_rms_log: 0.0,
        },
    };
    let log_residuals: Vec<f64> = cuts
        .iter()
        .map(|c| math::ln(c.force_n / law.force_n(&c.inputs)))
        .collect();
    law.residual_rms_log =
        (log_residuals.iter().map(|r| r * r).sum::<f64>() / cuts.len() as f64).sqrt();
    law.network.residual_rms_log = law.residual_rms_log;
    law.residuals_pct = log_residuals
        .iter()
        .map(|r| 100.0 * (math::exp(*r) - 1.0))
        .collect();
    Ok(law)
}

impl LearnedPowerLaw {
    /// The force the network predicts for `inputs`, N (0 when an input it reads is not positive:
    /// no cut).
    pub fn force_n(&self, inputs: &PowerLawInputs) -> f64 {
        self.network.force_n(inputs)
    }

    /// The learned exponent of `input`, if it varied over the cuts.
    pub fn exponent(&self, input: PowerLawInput) -> Option<&LearnedExponent> {
        self.learned.iter().find(|e| e.input == input)
    }
}

/// A designed set of trial cuts, as paper 004's stepped specimen: four depths in steps of 1 mm,
/// three widths (a fifth to three tenths of the diameter) and three feeds per tooth
/// (0.08–0.12 mm) crossed, 36 cuts on the cutter of `diameter_mm` with `teeth`. The ranges are
/// modest around a common finishing-to-roughing cut so that a power law fitted over them stays
/// close to the local behaviour of a force that is not one.
pub fn stepped_specimen(diameter_mm: f64, teeth: u32) -> Vec<PowerLawInputs> {
    let mut cuts = Vec::new();
    for width_fraction in [0.2, 0.25, 0.3] {
        for feed_per_tooth_mm in [0.08, 0.1, 0.12] {
            for axial_depth_mm in [1.0, 2.0, 3.0, 4.0] {
                cuts.push(PowerLawInputs {
                    radial_width_mm: width_fraction * diameter_mm,
                    feed_per_tooth_mm,
                    axial_depth_mm,
                    diameter_mm,
                    teeth_engaged: f64::NAN,
                    cutter_teeth: f64::from(teeth),
                });
            }
        }
    }
    cuts
}

/// The mechanistic model's mean resultant for the conditions `inputs` cut with `cut` (its cutter,
/// mode and material; the inputs' own diameter and teeth are the cutter's), N: what a trial cut
/// of the stepped specimen gives in the simulated machine, on average over a revolution. NaN for
/// conditions that are not a cut the model can take.
pub fn mechanistic_resultant_n(cut: &CutGeometry, inputs: &PowerLawInputs) -> f64 {
    // Any speed: the mean force depends on the chip, not on how fast it is cut.
    let spindle_rpm = 1000.0;
    let feed_mm_min = inputs.feed_per_tooth_mm * spindle_rpm * f64::from(cut.cutter.teeth);
    cut.mean_forces(
        feed_mm_min,
        spindle_rpm,
        inputs.axial_depth_mm,
        inputs.radial_width_mm,
    )
    .map_or(f64::NAN, |f| f.resultant_n())
}

/// The local exponent of `force_n` in `input` at `at`: d ln F / d ln p by a central difference
/// of ±1 % — what a power law fitted near `at` would find for a model that is not one (the
/// mechanistic model's feed exponent K_c·f / (K_c·f + K_e), for instance).
pub fn local_exponent(
    force_n: impl Fn(&PowerLawInputs) -> f64,
    at: &PowerLawInputs,
    input: PowerLawInput,
) -> f64 {
    let step = 0.01;
    let moved = |factor: f64| {
        let mut p = *at;
        let v = p.value(input) * factor;
        match input {
            PowerLawInput::RadialWidth => p.radial_width_mm = v,
            PowerLawInput::FeedPerTooth => p.feed_per_tooth_mm = v,
            PowerLawInput::AxialDepth => p.axial_depth_mm = v,
            PowerLawInput::Diameter => p.diameter_mm = v,
            PowerLawInput::TeethEngaged => p.teeth_engaged = v,
            PowerLawInput::CutterTeeth => p.cutter_teeth = v,
        }
        force_n(&p)
    };
    (math::ln(moved(1.0 + step)) - math::ln(moved(1.0 - step)))
        / (math::ln(1.0 + step) - math::ln(1.0 - step))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    fn inputs(a_e: f64, f: f64, a_p: f64) -> PowerLawInputs {
        PowerLawInputs {
            radial_width_mm: a_e,
            feed_per_tooth_mm: f,
            axial_depth_mm: a_p,
            diameter_mm: 20.0,
            teeth_engaged: 1.0,
            cutter_teeth: 2.0,
        }
    }

    #[test]
    fn noisy_cuts_give_the_true_exponents_within_the_stated_uncertainty() {
        let mut rng = Rng::seed_from(4);
        let mut cuts = Vec::new();
        for a_e in [4.0_f64, 8.0, 12.0, 20.0] {
            for f in [0.04_f64, 0.08, 0.16] {
                for a_p in [1.0, 2.0, 3.0, 5.0] {
                    let truth = 300.0 * a_e.powf(1.1) * f.powf(0.75) * a_p;
                    let force_n = truth * (1.0 + rng.gaussian(0.03));
                    cuts.push(TrialCut {
                        inputs: inputs(a_e, f, a_p),
                        force_n,
                    });
                }
            }
        }
        let law = learn(
            &cuts,
            PowerLawReading::Handbook,
            PowerLawMaterial::CarbonSteel,
        )
        .unwrap();
        for (input, truth) in [
            (PowerLawInput::RadialWidth, 1.1),
            (PowerLawInput::FeedPerTooth, 0.75),
            (PowerLawInput::AxialDepth, 1.0),
        ] {
            let e = law.exponent(input).unwrap();
            assert!(e.uncertainty > 0.0 && e.uncertainty < 0.1, "{e:?}");
            assert!((e.exponent - truth).abs() < e.uncertainty, "{e:?}");
        }
        assert!((law.residual_rms_log - 0.03).abs() < 0.01);
        assert_eq!(law.residuals_pct.len(), cuts.len());
    }

    #[test]
    fn a_cut_without_force_or_depth_is_refused_with_its_number() {
        let mut cuts: Vec<TrialCut> = (1..=8)
            .map(|k| TrialCut {
                inputs: inputs(10.0, 0.1, f64::from(k)),
                force_n: 100.0 * f64::from(k),
            })
            .collect();
        cuts[2].force_n = f64::NAN;
        let e = learn(
            &cuts,
            PowerLawReading::Handbook,
            PowerLawMaterial::CarbonSteel,
        )
        .unwrap_err();
        assert_eq!(
            e.to_string(),
            "trial cut 3: the force (N) must be a positive number, got NaN"
        );
        cuts[2].force_n = 300.0;
        cuts[4].inputs.axial_depth_mm = 0.0;
        let e = learn(
            &cuts,
            PowerLawReading::Handbook,
            PowerLawMaterial::CarbonSteel,
        )
        .unwrap_err();
        assert!(e.to_string().starts_with("trial cut 5: a_p"), "{e}");
    }

    #[test]
    fn too_few_or_collinear_cuts_are_refused() {
        let cuts: Vec<TrialCut> = (1..=3)
            .map(|k| TrialCut {
                inputs: inputs(10.0, 0.1, f64::from(k)),
                force_n: 100.0 * f64::from(k),
            })
            .collect();
        assert_eq!(
            learn(
                &cuts,
                PowerLawReading::Handbook,
                PowerLawMaterial::CarbonSteel
            ),
            Err(LearnError::TooFewCuts { cuts: 3, needed: 4 })
        );
        // Depth and width stepped together: their exponents cannot be told apart.
        let cuts: Vec<TrialCut> = (1..=8)
            .map(|k| TrialCut {
                inputs: inputs(2.0 * f64::from(k), 0.1, f64::from(k)),
                force_n: 100.0 * f64::from(k),
            })
            .collect();
        assert!(matches!(
            learn(
                &cuts,
                PowerLawReading::Handbook,
                PowerLawMaterial::CarbonSteel
            ),
            Err(LearnError::Collinear(_))
        ));
    }

    #[test]
    fn the_local_exponent_of_a_power_law_is_its_exponent() {
        let law = |p: &PowerLawInputs| 7.0 * p.feed_per_tooth_mm.powf(0.6) * p.axial_depth_mm;
        let at = inputs(10.0, 0.1, 2.0);
        assert!((local_exponent(law, &at, PowerLawInput::FeedPerTooth) - 0.6).abs() < 1e-9);
        assert!((local_exponent(law, &at, PowerLawInput::RadialWidth)).abs() < 1e-12);
    }

    #[test]
    fn the_published_resultant_exponent_is_the_mean_of_the_rows() {
        let w = published_resultant_exponent(
            PowerLawMaterial::CarbonSteel,
            PowerLawReading::Handbook,
            PowerLawInput::FeedPerTooth,
        );
        assert!((w - (0.747 + 0.748 + 0.751) / 3.0).abs() < 1e-12);
        assert_eq!(
            published_resultant_exponent(
                PowerLawMaterial::CarbonSteel,
                PowerLawReading::Handbook,
                PowerLawInput::TeethEngaged
            ),
            0.0
        );
    }
}
