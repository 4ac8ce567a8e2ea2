//! Paper 004's sensorless force estimate: the force network learned on the machine's own trial
//! cuts (from its current-based estimates: [`crate::estimation::power_law_fit`]), evaluated on
//! what the CNC program knows of the cut — width, feed per tooth, depth, and the tool — and never
//! on the force itself. Paper 004 uses it "in predicting failure occurrence of online sensors":
//! where the current-based estimate leaves the network's prediction by more than the network's
//! own uncertainty allows, the current sensor is predicted to be failing
//! ([`crate::closed_loop::feedback_loop::estimates_disagree`], held for
//! [`crate::closed_loop::feedback_loop::SENSOR_FAILURE_PERSISTENCE_S`]).
//!
//! **How far to trust it.** A prediction's relative uncertainty (1 = ±100 %) is the band the
//! trial cuts leave about the network, [`UNCERTAINTY_STANDARD_ERRORS`] times the residuals' RMS on
//! the log scale, plus, for each input, its exponent's stated uncertainty times how far (in
//! e-folds) the cut is from the trial cuts' geometric centre: the band widens as a controller
//! takes the feed per tooth away from where the network was learned. An input that did not vary
//! over the trial cuts (one tool: the diameter and the teeth) keeps paper 004's published
//! exponent, ± [`super::power_law::EXPONENT_UNCERTAINTY`].
//!
//! **Shipped per preset.** Learning takes a teach cut and three trial runs of the program, too
//! long to wait for at each run's start in the browser; the network each mill preset learns with
//! its default settings is computed ahead and shipped ([`shipped_network`],
//! `www/data/sensorless-networks.json`, written by `cutlab learn --shipped-networks` in
//! `scripts/sample-data`, and held equal to a fresh learning by `tests/power_law_learning.rs`).
//!
//! NaN in an input gives NaN; a zero or negative input (no cut) gives zero force.

use serde::{Deserialize, Serialize};

use super::power_law::{PowerLawInput, PowerLawInputs};
use super::Preset;
use crate::machine::SensorlessEstimate;
use crate::math;

/// How many standard errors (of an exponent, or of the residuals) a stated uncertainty spans
/// (≈ 95 % for the ten or more degrees of freedom a useful set of trial cuts has).
pub const UNCERTAINTY_STANDARD_ERRORS: f64 = 2.0;

/// One input of a learned network.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NetworkInput {
    /// The cutting condition.
    pub input: PowerLawInput,
    /// Its exponent.
    pub exponent: f64,
    /// ± this much: the learned exponent's [`UNCERTAINTY_STANDARD_ERRORS`] standard errors, or
    /// [`super::power_law::EXPONENT_UNCERTAINTY`] for a published exponent held because the input did not vary.
    pub uncertainty: f64,
    /// The geometric mean of the input over the trial cuts (mm, mm per tooth, or teeth).
    pub centre: f64,
}

/// Paper 004's network as learned on trial cuts: F = b · Π p_k^w_k, the force's resultant.
///
/// ```
/// use cutlab::plant::power_law::{PowerLawInput, PowerLawInputs};
/// use cutlab::plant::sensorless::{NetworkInput, SensorlessNetwork};
/// let network = SensorlessNetwork {
///     bias_n: 1000.0,
///     inputs: vec![NetworkInput { input: PowerLawInput::FeedPerTooth, exponent: 0.75,
///                                 uncertainty: 0.1, centre: 0.1 }],
///     residual_rms_log: 0.02,
/// };
/// let at = PowerLawInputs { radial_width_mm: 20.0, feed_per_tooth_mm: 0.1, axial_depth_mm: 5.0,
///                           diameter_mm: 20.0, teeth_engaged: 1.0, cutter_teeth: 2.0 };
/// assert!((network.force_n(&at) - 1000.0 * 0.1f64.powf(0.75)).abs() < 1e-9);
/// // At the trial cuts' centre the band is the residuals'; half the feed adds 0.1·ln 2.
/// assert!((network.relative_uncertainty(&at) - 0.04).abs() < 1e-12);
/// let slower = PowerLawInputs { feed_per_tooth_mm: 0.05, ..at };
/// assert!((network.relative_uncertainty(&slower) - (0.04 + 0.1 * 2f64.ln())).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SensorlessNetwork {
    /// The bias b, N: the force at every input 1 (mm, per tooth, teeth).
    pub bias_n: f64,
    /// Every input the network reads, learned or held.
    pub inputs: Vec<NetworkInput>,
    /// Root-mean-square of the trial cuts' residuals on the log scale (≈ relative error).
    pub residual_rms_log: f64,
}

impl SensorlessNetwork {
    /// What the network gives where `inputs` is not a cut it can read: NaN for an input that
    /// is NaN, zero for one that is not positive (no cut); `None` for a cut.
    fn not_a_cut(&self, inputs: &PowerLawInputs) -> Option<f64> {
        self.inputs.iter().find_map(|k| {
            let v = inputs.value(k.input);
            if v.is_nan() {
                Some(f64::NAN)
            } else if v <= 0.0 {
                Some(0.0)
            } else {
                None
            }
        })
    }

    /// The force the network predicts for `inputs`, N (0 when an input it reads is not positive:
    /// no cut).
    pub fn force_n(&self, inputs: &PowerLawInputs) -> f64 {
        if let Some(value) = self.not_a_cut(inputs) {
            return value;
        }
        self.inputs.iter().fold(self.bias_n, |force_n, k| {
            force_n * math::pow(inputs.value(k.input), k.exponent)
        })
    }

    /// The prediction's relative uncertainty at `inputs` (see the module's docs); 0 where there
    /// is no cut (no force to be wrong about).
    pub fn relative_uncertainty(&self, inputs: &PowerLawInputs) -> f64 {
        if let Some(value) = self.not_a_cut(inputs) {
            return value;
        }
        self.inputs.iter().fold(
            UNCERTAINTY_STANDARD_ERRORS * self.residual_rms_log,
            |band, k| band + k.uncertainty * math::ln(inputs.value(k.input) / k.centre).abs(),
        )
    }

    /// The sensorless estimate at `inputs`: the force and how far to trust it.
    pub fn estimate(&self, inputs: &PowerLawInputs) -> SensorlessEstimate {
        SensorlessEstimate {
            force_n: self.force_n(inputs),
            relative_uncertainty: self.relative_uncertainty(inputs),
        }
    }
}

/// The networks the mill presets learn with their default settings, as `cutlab learn
/// --shipped-networks` writes them.
const SHIPPED_NETWORKS: &str = include_str!("../../www/data/sensorless-networks.json");

/// The shipped networks, each with the preset whose trial cuts it learned on. A file that does
/// not read (it cannot, short of a broken build) ships none: the plant then estimates with paper
/// 004's published weights, calibrated ([`super::simulator`]).
pub fn shipped_networks() -> &'static [(Preset, SensorlessNetwork)] {
    // Read once: every simulator a preset builds looks its network up here, and parsing the
    // JSON each time cost the wasm loop 1-2 % (docs/benchmarks.md, "The worker's build").
    static NETWORKS: std::sync::OnceLock<Vec<(Preset, SensorlessNetwork)>> =
        std::sync::OnceLock::new();
    NETWORKS.get_or_init(|| serde_json::from_str(SHIPPED_NETWORKS).unwrap_or_default())
}

/// The network `preset` learned on its own trial cuts, if it could learn one (a program with
/// one depth of cut cannot tell the depth's exponent from the bias: no network).
///
/// ```
/// use cutlab::plant::sensorless::shipped_network;
/// use cutlab::plant::Preset;
/// assert!(shipped_network(Preset::KimStepDoc).is_some());
/// assert!(shipped_network(Preset::LiuCurrentStep).is_none()); // no cutter, no trial cuts
/// ```
pub fn shipped_network(preset: Preset) -> Option<SensorlessNetwork> {
    shipped_networks()
        .iter()
        .find(|(p, _)| *p == preset)
        .map(|(_, network)| network.clone())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn no_cut_gives_no_force_and_no_band_and_nan_stays_nan() {
        let network = SensorlessNetwork {
            bias_n: 500.0,
            inputs: vec![NetworkInput {
                input: PowerLawInput::AxialDepth,
                exponent: 1.0,
                uncertainty: 0.05,
                centre: 2.0,
            }],
            residual_rms_log: 0.01,
        };
        let mut p = PowerLawInputs {
            radial_width_mm: 10.0,
            feed_per_tooth_mm: 0.1,
            axial_depth_mm: 0.0,
            diameter_mm: 10.0,
            teeth_engaged: 1.0,
            cutter_teeth: 2.0,
        };
        assert_eq!(network.estimate(&p).force_n, 0.0);
        assert_eq!(network.estimate(&p).relative_uncertainty, 0.0);
        p.axial_depth_mm = f64::NAN;
        assert!(network.force_n(&p).is_nan());
        p.axial_depth_mm = 4.0;
        assert!((network.force_n(&p) - 2000.0).abs() < 1e-9);
        assert!((network.relative_uncertainty(&p) - (0.02 + 0.05 * 2f64.ln())).abs() < 1e-12);
    }
}
