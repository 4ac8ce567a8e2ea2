//! Paper 004's empirical power-law force model, a "sensorless" estimate from the cutting
//! conditions alone.
//!
//! Paper 004 (Shen, Li, Yu) writes each force component of face milling as a power law of the
//! radial width a_e, the feed per tooth f, the axial depth a_p, the tool diameter d and the number
//! of teeth in the cut z_e (eq 1–2), and learns it as a linear network in log space (eq 3):
//!
//! ```text
//! ln F_k = ln b_k + W_k,ae·ln a_e + W_k,f·ln f + W_k,ap·ln a_p + W_k,d·ln d + W_k,ze·ln z_e
//! F_k    = b_k · a_e^W_k,ae · f^W_k,f · a_p^W_k,ap · d^W_k,d · z_e^W_k,ze          k = x, y, z
//! ```
//!
//! The published weights W and biases b (the paper's "bias vector {K_Cx, K_Cy, K_Cz}", the
//! combined effect of material, geometry and conditions) are in [`PowerLawMaterial::weights`] and
//! [`PowerLawMaterial::bias_n`], for carbon steel and for cast iron (the paper labels both
//! matrices W_cns and calls the second specimen both "cast steel" and "cast iron"; cutlab follows
//! the caption, cast iron).
//!
//! **Units.** The paper states none. cutlab takes the handbook units of such power laws: a_e, f
//! (per tooth), a_p and d in millimetres, z_e a count (the mean number of teeth in the cut), F in
//! newtons. With these units the published carbon-steel biases give 12.6 kN on paper 001's cut
//! (Ø10 mm, 4 teeth, a_e 3 mm, f 0.075 mm, a_p 2 mm, z_e 0.74), about 60 times the mechanistic
//! model's 205 N. No other reading of the units rescues them: d alone in metres divides the force
//! by 1000^1.006 ≈ 1030 (12 N, 17 times too small), and every length in metres by
//! 1000^3.85 ≈ 3·10¹¹. The biases belong to the paper's own machine, tool (a Ø20 mm face mill)
//! and units, which the text does not recover (tests/plant_mechanics.rs checks these figures).
//! The exponents are what carries over, within [`EXPONENT_UNCERTAINTY`]: [`PowerLawModel::calibrated`] rescales the biases so the
//! model matches one teach cut, which is what the paper's bias ("the combination effect of
//! material properties, cutting geometry and cutting conditions") is for. The simulator does
//! this once per material against the mechanistic mean force of the scenario's nominal cut.
//!
//! A zero or negative input (no cut) gives zero force; NaN gives NaN.

use serde::{Deserialize, Serialize};

use super::{positive, PlantError};
use crate::math;

/// How far each published exponent may be from this machine's, tool's and material's: Kienzle's
/// feed exponent 1 − m_c ranges about 0.6–0.9 between materials and tools (the paper's 0.75 sits
/// in the middle, the mechanistic model's chip-thickness law is 1), so ±0.25. The cross-check
/// widens its tolerance by the uncertainty this gives ([`PowerLawModel::relative_uncertainty`]).
pub const EXPONENT_UNCERTAINTY: f64 = 0.25;

/// The materials paper 004 publishes weights for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PowerLawMaterial {
    /// Carbon steel (cutlab's SM45C stands for it).
    CarbonSteel,
    /// Cast iron (cutlab's GC30 stands for it).
    CastIron,
}

impl PowerLawMaterial {
    /// Both materials.
    pub const ALL: [PowerLawMaterial; 2] =
        [PowerLawMaterial::CarbonSteel, PowerLawMaterial::CastIron];

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            PowerLawMaterial::CarbonSteel => "carbon-steel",
            PowerLawMaterial::CastIron => "cast-iron",
        }
    }

    /// Label for forms.
    pub fn label(self) -> &'static str {
        match self {
            PowerLawMaterial::CarbonSteel => "Carbon steel (paper 004)",
            PowerLawMaterial::CastIron => "Cast iron (paper 004)",
        }
    }

    /// Paper 004's weight matrix: rows x, y, z; columns a_e, f, a_p, d, z_e.
    pub fn weights(self) -> [[f64; 5]; 3] {
        match self {
            PowerLawMaterial::CarbonSteel => [
                [1.103, 0.747, 1.002, 0.997, -1.299],
                [1.098, 0.748, 0.997, 1.006, -1.299],
                [1.100, 0.751, 0.995, 1.004, -1.301],
            ],
            PowerLawMaterial::CastIron => [
                [1.003, 0.737, 0.902, 0.997, -0.999],
                [0.998, 0.738, 0.897, 1.006, -0.999],
                [1.000, 0.741, 0.895, 1.004, -1.001],
            ],
        }
    }

    /// Paper 004's bias vector {K_Cx, K_Cy, K_Cz}, in newtons for inputs in mm.
    pub fn bias_n(self) -> [f64; 3] {
        match self {
            PowerLawMaterial::CarbonSteel => [316.91, 814.92, 452.73],
            PowerLawMaterial::CastIron => [185.41, 476.77, 264.87],
        }
    }
}

/// The cutting conditions the power law reads.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PowerLawInputs {
    /// Radial width of cut a_e.
    pub radial_width_mm: f64,
    /// Feed per tooth f.
    pub feed_per_tooth_mm: f64,
    /// Axial depth of cut a_p.
    pub axial_depth_mm: f64,
    /// Tool diameter d.
    pub diameter_mm: f64,
    /// Teeth in the cut z_e (mean over a revolution).
    pub teeth_engaged: f64,
}

impl PowerLawInputs {
    fn as_array(&self) -> [f64; 5] {
        [
            self.radial_width_mm,
            self.feed_per_tooth_mm,
            self.axial_depth_mm,
            self.diameter_mm,
            self.teeth_engaged,
        ]
    }
}

/// The three force components of the power law and their x-y resultant.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct PowerLawForces {
    /// F_Cx.
    pub fx_n: f64,
    /// F_Cy.
    pub fy_n: f64,
    /// F_Cz.
    pub fz_n: f64,
}

impl PowerLawForces {
    /// √(F_x² + F_y²).
    pub fn resultant_n(&self) -> f64 {
        math::hypot(self.fx_n, self.fy_n)
    }
}

/// A power-law model: weights and biases.
///
/// ```
/// use cutlab::plant::power_law::{PowerLawInputs, PowerLawMaterial, PowerLawModel};
/// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel);
/// let p = PowerLawInputs { radial_width_mm: 1.0, feed_per_tooth_mm: 1.0, axial_depth_mm: 1.0,
///                          diameter_mm: 1.0, teeth_engaged: 1.0 };
/// assert!((m.forces(&p).fy_n - 814.92).abs() < 1e-9); // all inputs 1: F = b
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PowerLawModel {
    /// Exponents, rows x, y, z; columns a_e, f, a_p, d, z_e.
    pub weights: [[f64; 5]; 3],
    /// Multipliers b_x, b_y, b_z.
    pub bias_n: [f64; 3],
}

impl PowerLawModel {
    /// The published model for `material`.
    pub fn published(material: PowerLawMaterial) -> Self {
        Self {
            weights: material.weights(),
            bias_n: material.bias_n(),
        }
    }

    /// A model with finite weights and positive biases.
    pub fn new(weights: [[f64; 5]; 3], bias_n: [f64; 3]) -> Result<Self, PlantError> {
        for (i, row) in weights.iter().enumerate() {
            for (j, w) in row.iter().enumerate() {
                if !w.is_finite() {
                    return Err(PlantError::new(
                        format!("weights[{i}][{j}]"),
                        format!("must be finite, got {w}"),
                    ));
                }
            }
        }
        for (i, b) in bias_n.iter().enumerate() {
            positive(&format!("bias_n[{i}]"), *b)?;
        }
        Ok(Self { weights, bias_n })
    }

    /// The same model with every bias multiplied by `factor` (> 0), e.g. the ratio of a teach
    /// cut's measured force to this model's prediction.
    ///
    /// ```
    /// use cutlab::plant::power_law::{PowerLawMaterial, PowerLawModel};
    /// let m = PowerLawModel::published(PowerLawMaterial::CastIron).scaled(0.5).unwrap();
    /// assert_eq!(m.bias_n[0], 185.41 * 0.5);
    /// ```
    pub fn scaled(self, factor: f64) -> Result<Self, PlantError> {
        positive("factor", factor)?;
        Ok(Self {
            bias_n: self.bias_n.map(|b| b * factor),
            ..self
        })
    }

    /// The same model with its biases scaled so that the x-y resultant at `inputs` is
    /// `resultant_n` (> 0): a one-point calibration to a teach cut.
    ///
    /// ```
    /// use cutlab::plant::power_law::{PowerLawInputs, PowerLawMaterial, PowerLawModel};
    /// let p = PowerLawInputs { radial_width_mm: 5.0, feed_per_tooth_mm: 0.1, axial_depth_mm: 2.0,
    ///                          diameter_mm: 20.0, teeth_engaged: 0.5 };
    /// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel).calibrated(&p, 400.0).unwrap();
    /// assert!((m.forces(&p).resultant_n() - 400.0).abs() < 1e-9);
    /// ```
    pub fn calibrated(self, inputs: &PowerLawInputs, resultant_n: f64) -> Result<Self, PlantError> {
        positive("resultant_n", resultant_n)?;
        let now = self.forces(inputs).resultant_n();
        if !(now.is_finite() && now > 0.0) {
            return Err(PlantError::new(
                "inputs",
                "the calibration cut must have positive, finite conditions",
            ));
        }
        self.scaled(resultant_n / now)
    }

    /// The relative uncertainty of this model's force at `inputs` when it was calibrated at
    /// `calibrated_on`: [`EXPONENT_UNCERTAINTY`] per e-fold change of each input,
    /// δ = Σ_i δw·|ln(p_i / p_i,0)| (the error of a power-law ratio whose exponents are off by δw).
    /// Zero at the calibration cut; infinite when an input is not positive (nothing to compare).
    ///
    /// ```
    /// use cutlab::plant::power_law::{PowerLawInputs, PowerLawMaterial, PowerLawModel};
    /// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel);
    /// let at = PowerLawInputs { radial_width_mm: 5.0, feed_per_tooth_mm: 0.1, axial_depth_mm: 2.0,
    ///                           diameter_mm: 20.0, teeth_engaged: 0.5 };
    /// assert_eq!(m.relative_uncertainty(&at, &at), 0.0);
    /// // Half the feed per tooth: ±0.25·ln 2 ≈ ±17 %.
    /// let slower = PowerLawInputs { feed_per_tooth_mm: 0.05, ..at };
    /// assert!((m.relative_uncertainty(&slower, &at) - 0.25 * 2f64.ln()).abs() < 1e-12);
    /// ```
    pub fn relative_uncertainty(
        &self,
        inputs: &PowerLawInputs,
        calibrated_on: &PowerLawInputs,
    ) -> f64 {
        inputs
            .as_array()
            .iter()
            .zip(calibrated_on.as_array())
            .map(|(&now, then)| {
                if now > 0.0 && then > 0.0 {
                    EXPONENT_UNCERTAINTY * math::ln(now / then).abs()
                } else {
                    f64::INFINITY
                }
            })
            .sum()
    }

    /// The forces as the power law (eq 1–2): F_k = b_k·Π p_i^W_ki.
    pub fn forces(&self, inputs: &PowerLawInputs) -> PowerLawForces {
        let p = inputs.as_array();
        if p.iter().any(|v| v.is_nan()) {
            return PowerLawForces {
                fx_n: f64::NAN,
                fy_n: f64::NAN,
                fz_n: f64::NAN,
            };
        }
        if p.iter().any(|&v| v <= 0.0) {
            return PowerLawForces::default();
        }
        let component = |k: usize| {
            self.weights[k]
                .iter()
                .zip(p)
                .fold(self.bias_n[k], |acc, (w, v)| acc * math::pow(v, *w))
        };
        PowerLawForces {
            fx_n: component(0),
            fy_n: component(1),
            fz_n: component(2),
        }
    }

    /// The forces as the paper's network computes them (eq 3): inputs through ln, weighted and
    /// summed with ln b, back through exp. Equal to [`PowerLawModel::forces`] up to rounding.
    pub fn forces_log_network(&self, inputs: &PowerLawInputs) -> PowerLawForces {
        let p = inputs.as_array();
        if p.iter().any(|v| v.is_nan()) {
            return PowerLawForces {
                fx_n: f64::NAN,
                fy_n: f64::NAN,
                fz_n: f64::NAN,
            };
        }
        if p.iter().any(|&v| v <= 0.0) {
            return PowerLawForces::default();
        }
        let logs = p.map(math::ln);
        let component = |k: usize| {
            let n = math::ln(self.bias_n[k])
                + self.weights[k]
                    .iter()
                    .zip(logs)
                    .map(|(w, l)| w * l)
                    .sum::<f64>();
            math::exp(n)
        };
        PowerLawForces {
            fx_n: component(0),
            fy_n: component(1),
            fz_n: component(2),
        }
    }
}

/// A [`PowerLawModel`] calibrated on a cut, evaluated again and again as the cut goes on: each
/// input's powers p_i^W_ki and its uncertainty term are kept with the input's value and reused
/// while it does not change. In a run the tool's diameter and teeth never change and the depth
/// and width seldom do, so of the 15 `pow` and 5 `ln` per evaluation only the feed per tooth's 3
/// and 1 remain. The products and sums are taken in the same order as
/// [`PowerLawModel::forces`] and [`PowerLawModel::relative_uncertainty`]: the same bits.
///
/// ```
/// use cutlab::plant::power_law::{CachedPowerLaw, PowerLawInputs, PowerLawMaterial, PowerLawModel};
/// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel);
/// let at = PowerLawInputs { radial_width_mm: 5.0, feed_per_tooth_mm: 0.1, axial_depth_mm: 2.0,
///                           diameter_mm: 20.0, teeth_engaged: 0.5 };
/// let mut cached = CachedPowerLaw::new(m, at);
/// let slower = PowerLawInputs { feed_per_tooth_mm: 0.05, ..at };
/// assert_eq!(cached.evaluate(&slower), (m.forces(&slower).resultant_n(), m.relative_uncertainty(&slower, &at)));
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CachedPowerLaw {
    model: PowerLawModel,
    calibrated_on: PowerLawInputs,
    /// Per input: its value's bits (NaN's never match: a NaN is never cached), p^W for x, y, z,
    /// and the uncertainty term.
    cache: [(u64, [f64; 3], f64); 5],
}

impl CachedPowerLaw {
    /// `model`, calibrated on `calibrated_on`, with nothing cached yet.
    pub fn new(model: PowerLawModel, calibrated_on: PowerLawInputs) -> Self {
        Self {
            model,
            calibrated_on,
            cache: [(f64::NAN.to_bits(), [f64::NAN; 3], f64::NAN); 5],
        }
    }

    /// The model and the cut it was calibrated on.
    pub fn model(&self) -> (&PowerLawModel, &PowerLawInputs) {
        (&self.model, &self.calibrated_on)
    }

    /// `(forces(inputs).resultant_n(), relative_uncertainty(inputs, calibrated_on))`, bit for
    /// bit.
    pub fn evaluate(&mut self, inputs: &PowerLawInputs) -> (f64, f64) {
        let p = inputs.as_array();
        if p.iter().any(|&v| v.is_nan() || v <= 0.0) {
            // Not a cut (or not a number): the plain path gives zero, NaN or infinity.
            return (
                self.model.forces(inputs).resultant_n(),
                self.model.relative_uncertainty(inputs, &self.calibrated_on),
            );
        }
        let then = self.calibrated_on.as_array();
        for (i, (&v, slot)) in p.iter().zip(self.cache.iter_mut()).enumerate() {
            if slot.0 != v.to_bits() {
                let w = &self.model.weights;
                let u = if then[i] > 0.0 {
                    EXPONENT_UNCERTAINTY * math::ln(v / then[i]).abs()
                } else {
                    f64::INFINITY
                };
                *slot = (v.to_bits(), [0, 1, 2].map(|k| math::pow(v, w[k][i])), u);
            }
        }
        let component = |k: usize| {
            self.cache
                .iter()
                .fold(self.model.bias_n[k], |acc, slot| acc * slot.1[k])
        };
        let forces = PowerLawForces {
            fx_n: component(0),
            fy_n: component(1),
            fz_n: component(2),
        };
        let uncertainty = self.cache.iter().map(|slot| slot.2).sum();
        (forces.resultant_n(), uncertainty)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn inputs() -> PowerLawInputs {
        PowerLawInputs {
            radial_width_mm: 5.0,
            feed_per_tooth_mm: 0.08,
            axial_depth_mm: 1.5,
            diameter_mm: 20.0,
            teeth_engaged: 0.7,
        }
    }

    #[test]
    fn network_and_power_law_agree() {
        for m in PowerLawMaterial::ALL {
            let model = PowerLawModel::published(m);
            let a = model.forces(&inputs());
            let b = model.forces_log_network(&inputs());
            for (u, v) in [(a.fx_n, b.fx_n), (a.fy_n, b.fy_n), (a.fz_n, b.fz_n)] {
                assert!((u - v).abs() < 1e-12 * u.abs(), "{m:?}: {u} vs {v}");
            }
        }
    }

    #[test]
    fn doubling_the_depth_scales_by_two_to_the_depth_weight() {
        let model = PowerLawModel::published(PowerLawMaterial::CarbonSteel);
        let a = model.forces(&inputs());
        let mut deeper = inputs();
        deeper.axial_depth_mm *= 2.0;
        let b = model.forces(&deeper);
        assert!((b.fx_n / a.fx_n - 2f64.powf(1.002)).abs() < 1e-12);
    }

    #[test]
    fn no_cut_gives_no_force_and_bad_models_are_refused() {
        let model = PowerLawModel::published(PowerLawMaterial::CastIron);
        let mut air = inputs();
        air.teeth_engaged = 0.0;
        assert_eq!(model.forces(&air), PowerLawForces::default());
        let e = PowerLawModel::new([[0.0; 5]; 3], [1.0, -1.0, 1.0]).unwrap_err();
        assert_eq!(e.field, "bias_n[1]");
    }
}
