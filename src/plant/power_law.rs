//! Paper 004's empirical power-law force model, a "sensorless" estimate from the cutting
//! conditions alone.
//!
//! Paper 004 (Shen, Li, Yu) writes each force component of face milling as a power law of the
//! radial width a_e, the feed per tooth f, the axial depth a_p, the tool diameter d and the number
//! of teeth z_e (eq 1–2), and learns it as a linear network in log space (eq 3):
//!
//! ```text
//! ln F_k = ln b_k + W_k,1·ln p_1 + … + W_k,5·ln p_5
//! F_k    = b_k · p_1^W_k,1 · … · p_5^W_k,5                                   k = x, y, z
//! ```
//!
//! The published weights W and biases b (the paper's "bias vector {K_Cx, K_Cy, K_Cz}", the
//! combined effect of material, geometry and conditions) are in [`PowerLawMaterial::weights`] and
//! [`PowerLawMaterial::bias_n`], for carbon steel and for cast iron (the paper labels both
//! matrices W_cns and calls the second specimen both "cast steel" and "cast iron"; cutlab follows
//! the caption, cast iron).
//!
//! **Which input each column belongs to** is a [`PowerLawReading`]. As printed (p = {a_e, f, a_p,
//! d, z_e}) the force rises with the diameter (d^+1.0) and falls with the teeth (z_e^−1.3), the
//! opposite of any milling force: the mean chip thickness over a cut of width a_e falls as
//! a_e/d, and every tooth in the cut adds its chip. The handbook form of the same law,
//! F = C·a_e^u·f^y·a_p^x·z / d^q with z the cutter's number of teeth — which the paper's own eq 1
//! and 3 follow by giving z_e no learned exponent (it stands to the first power) — reads the
//! fourth column (≈ +1.0) as the teeth's exponent and the fifth (≈ −1.3) as the diameter's.
//! [`PowerLawReading::ALL`] holds three readings, each with the sentence it rests on, and
//! [`PowerLawReading::USED`] is the one whose published biases land within
//! [`PowerLawReading::AGREEMENT_FACTOR`] of the mechanistic mean force on every mill preset's
//! cut (tests/plant_mechanics.rs against `scripts/reference/power_law_readings.py`; the figures
//! in docs/papers.md).
//!
//! **Units.** The paper states none. cutlab takes the handbook units of such power laws: a_e, f
//! (per tooth), a_p and d in millimetres, the teeth a count, F in newtons. The biases still belong
//! to the paper's own machine, tool (a Ø20 mm face mill) and material, so the exponents are what
//! carries over, within [`EXPONENT_UNCERTAINTY`]: [`PowerLawModel::calibrated`] rescales the
//! biases so the model matches one teach cut, which is what the paper's bias ("the combination
//! effect of material properties, cutting geometry and cutting conditions") is for. The
//! simulator does this once per material against the mechanistic mean force of the scenario's
//! nominal cut.
//!
//! A zero or negative input among those the reading uses (no cut) gives zero force; NaN gives NaN.

use serde::{Deserialize, Serialize};

use super::{positive, PlantError};
use crate::math;

/// How far each published exponent may be from this machine's, tool's and material's: Kienzle's
/// feed exponent 1 − m_c ranges about 0.6–0.9 between materials and tools (the paper's 0.75 sits
/// in the middle, the mechanistic model's chip-thickness law is 1), so ±0.25. The sensor failure
/// prediction widens its tolerance by the uncertainty this gives
/// ([`PowerLawModel::relative_uncertainty`]); a learned network holds an input that did not vary
/// over its trial cuts at the published exponent, ± this ([`super::sensorless`]).
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
    /// The cutter's number of teeth z (the handbooks' z).
    pub cutter_teeth: f64,
}

impl PowerLawInputs {
    /// The value of `input`.
    pub fn value(&self, input: PowerLawInput) -> f64 {
        match input {
            PowerLawInput::RadialWidth => self.radial_width_mm,
            PowerLawInput::FeedPerTooth => self.feed_per_tooth_mm,
            PowerLawInput::AxialDepth => self.axial_depth_mm,
            PowerLawInput::Diameter => self.diameter_mm,
            PowerLawInput::TeethEngaged => self.teeth_engaged,
            PowerLawInput::CutterTeeth => self.cutter_teeth,
        }
    }
}

/// One condition a power-law exponent can belong to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PowerLawInput {
    /// a_e, mm.
    RadialWidth,
    /// f, mm per tooth.
    FeedPerTooth,
    /// a_p, mm.
    AxialDepth,
    /// d, mm.
    Diameter,
    /// z_e, the mean number of teeth in the cut.
    TeethEngaged,
    /// z, the cutter's number of teeth.
    CutterTeeth,
}

impl PowerLawInput {
    /// The symbol the docs use.
    pub fn symbol(self) -> &'static str {
        match self {
            PowerLawInput::RadialWidth => "a_e",
            PowerLawInput::FeedPerTooth => "f",
            PowerLawInput::AxialDepth => "a_p",
            PowerLawInput::Diameter => "d",
            PowerLawInput::TeethEngaged => "z_e",
            PowerLawInput::CutterTeeth => "z",
        }
    }
}

/// How paper 004's weight matrix is read: the input each of its five columns is the exponent of.
/// The columns themselves (and the biases) are the published numbers in every reading.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum PowerLawReading {
    /// The columns in the order the paper prints its input vector: a_e, f, a_p, d, z_e.
    AsPrinted,
    /// The d and z_e columns swapped, z_e still the mean number of teeth in the cut.
    Swapped,
    /// The handbook form: the d and teeth columns swapped and the teeth the cutter's count z.
    Handbook,
}

impl PowerLawReading {
    /// Every reading compared.
    pub const ALL: [PowerLawReading; 3] = [
        PowerLawReading::AsPrinted,
        PowerLawReading::Swapped,
        PowerLawReading::Handbook,
    ];

    /// The reading the published sensorless estimate uses: the one that matches the physics (force
    /// falling with the diameter at a given width, rising with the teeth) and, with the published
    /// biases in mm, lands within [`Self::AGREEMENT_FACTOR`] of the mechanistic mean force on
    /// every mill preset's cut.
    pub const USED: PowerLawReading = PowerLawReading::Handbook;

    /// How far from the mechanistic mean resultant the [`Self::USED`] reading's published forces
    /// may be on a mill preset's cut, either way: a factor of 2, the spread to expect of one
    /// published fit carried to another tool, machine and grade of steel without calibration.
    pub const AGREEMENT_FACTOR: f64 = 2.0;

    /// Short name.
    pub fn name(self) -> &'static str {
        match self {
            PowerLawReading::AsPrinted => "as-printed",
            PowerLawReading::Swapped => "swapped",
            PowerLawReading::Handbook => "handbook",
        }
    }

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            PowerLawReading::AsPrinted => "as printed",
            PowerLawReading::Swapped => "d and z_e swapped",
            PowerLawReading::Handbook => "handbook form",
        }
    }

    /// The input each column of the weight matrix is the exponent of.
    pub fn columns(self) -> [PowerLawInput; 5] {
        use PowerLawInput::*;
        match self {
            PowerLawReading::AsPrinted => [
                RadialWidth,
                FeedPerTooth,
                AxialDepth,
                Diameter,
                TeethEngaged,
            ],
            PowerLawReading::Swapped => [
                RadialWidth,
                FeedPerTooth,
                AxialDepth,
                TeethEngaged,
                Diameter,
            ],
            PowerLawReading::Handbook => {
                [RadialWidth, FeedPerTooth, AxialDepth, CutterTeeth, Diameter]
            }
        }
    }

    /// The sentence the reading rests on.
    pub fn source(self) -> &'static str {
        match self {
            PowerLawReading::AsPrinted => {
                "paper 004, the network's definition: \"p = {a_e, f, a_p, d, z_e}, R = 5, \
                 W = [W_x,a_e W_x,f W_x,a_p W_x,d W_x,z_e; …]\", the weight matrix's columns in \
                 the order of the inputs"
            }
            PowerLawReading::Swapped => {
                "paper 004, eq 1: \"F_C = C_F_C · a_e^(C_F_e) · f^(C_F_f) · a_p^(C_F_p) · \
                 d^(C_F_d) · z_e\" and eq 3's \"[In(C_F_c) + In(K_F_x) + In(z_e)]\": z_e stands \
                 to the first power, so the column near +1.0 is z_e's and the one near −1.3 is \
                 d's"
            }
            PowerLawReading::Handbook => {
                "the handbooks' milling force formula F_c = C_F·a_e^u·f_z^y·a_p^x·Z / d^q, \
                 \"Z — the cutter's number of teeth\" (e.g. F_C = C_F·a_e^0.86·a_f^0.72·\
                 d^−0.86·a_p·Z, https://m.jc35.com/st9018/article_51212.html), which eq 1 \
                 follows: the columns swapped as eq 1 implies, and the teeth the cutter's count, \
                 since a_e^u already carries the share of each revolution a tooth cuts"
            }
        }
    }

    /// `inputs` in column order.
    fn arrange(self, inputs: &PowerLawInputs) -> [f64; 5] {
        self.columns().map(|input| inputs.value(input))
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

/// A power-law model: weights, biases and the reading that assigns the weights' columns.
///
/// ```
/// use cutlab::plant::power_law::{PowerLawInputs, PowerLawMaterial, PowerLawModel, PowerLawReading};
/// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel, PowerLawReading::USED);
/// let p = PowerLawInputs { radial_width_mm: 1.0, feed_per_tooth_mm: 1.0, axial_depth_mm: 1.0,
///                          diameter_mm: 1.0, teeth_engaged: 1.0, cutter_teeth: 1.0 };
/// assert!((m.forces(&p).fy_n - 814.92).abs() < 1e-9); // all inputs 1: F = b
/// // The handbook reading: twice the diameter at the same width, 2^−1.299 of the force.
/// let wider_tool = PowerLawInputs { diameter_mm: 2.0, ..p };
/// assert!((m.forces(&wider_tool).fy_n / 814.92 - 2f64.powf(-1.299)).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PowerLawModel {
    /// Exponents, rows x, y, z; columns as `reading` assigns them.
    pub weights: [[f64; 5]; 3],
    /// Multipliers b_x, b_y, b_z.
    pub bias_n: [f64; 3],
    /// Which input each column of `weights` is the exponent of.
    pub reading: PowerLawReading,
}

impl PowerLawModel {
    /// The published model for `material`, its columns read as `reading`.
    pub fn published(material: PowerLawMaterial, reading: PowerLawReading) -> Self {
        Self {
            weights: material.weights(),
            bias_n: material.bias_n(),
            reading,
        }
    }

    /// A model with finite weights and positive biases.
    pub fn new(
        weights: [[f64; 5]; 3],
        bias_n: [f64; 3],
        reading: PowerLawReading,
    ) -> Result<Self, PlantError> {
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
        Ok(Self {
            weights,
            bias_n,
            reading,
        })
    }

    /// The same model with every bias multiplied by `factor` (> 0), e.g. the ratio of a teach
    /// cut's measured force to this model's prediction.
    ///
    /// ```
    /// use cutlab::plant::power_law::{PowerLawMaterial, PowerLawModel, PowerLawReading};
    /// let m = PowerLawModel::published(PowerLawMaterial::CastIron, PowerLawReading::USED)
    ///     .scaled(0.5)
    ///     .unwrap();
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
    /// use cutlab::plant::power_law::{PowerLawInputs, PowerLawMaterial, PowerLawModel, PowerLawReading};
    /// let p = PowerLawInputs { radial_width_mm: 5.0, feed_per_tooth_mm: 0.1, axial_depth_mm: 2.0,
    ///                          diameter_mm: 20.0, teeth_engaged: 0.5, cutter_teeth: 2.0 };
    /// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel, PowerLawReading::USED)
    ///     .calibrated(&p, 400.0)
    ///     .unwrap();
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
    /// `calibrated_on`: [`EXPONENT_UNCERTAINTY`] per e-fold change of each input the reading uses,
    /// δ = Σ_i δw·|ln(p_i / p_i,0)| (the error of a power-law ratio whose exponents are off by δw).
    /// Zero at the calibration cut; infinite when an input is not positive (nothing to compare).
    ///
    /// ```
    /// use cutlab::plant::power_law::{PowerLawInputs, PowerLawMaterial, PowerLawModel, PowerLawReading};
    /// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel, PowerLawReading::USED);
    /// let at = PowerLawInputs { radial_width_mm: 5.0, feed_per_tooth_mm: 0.1, axial_depth_mm: 2.0,
    ///                           diameter_mm: 20.0, teeth_engaged: 0.5, cutter_teeth: 2.0 };
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
        self.reading
            .arrange(inputs)
            .iter()
            .zip(self.reading.arrange(calibrated_on))
            .map(|(&now, then)| {
                if now > 0.0 && then > 0.0 {
                    EXPONENT_UNCERTAINTY * math::ln(now / then).abs()
                } else {
                    f64::INFINITY
                }
            })
            .sum()
    }

    /// The forces as the power law (eq 1–2): F_k = b_k·Π p_i^W_ki, p_i the input the reading
    /// gives column i.
    pub fn forces(&self, inputs: &PowerLawInputs) -> PowerLawForces {
        let p = self.reading.arrange(inputs);
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
        let p = self.reading.arrange(inputs);
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
/// use cutlab::plant::power_law::{CachedPowerLaw, PowerLawInputs, PowerLawMaterial, PowerLawModel, PowerLawReading};
/// let m = PowerLawModel::published(PowerLawMaterial::CarbonSteel, PowerLawReading::USED);
/// let at = PowerLawInputs { radial_width_mm: 5.0, feed_per_tooth_mm: 0.1, axial_depth_mm: 2.0,
///                           diameter_mm: 20.0, teeth_engaged: 0.5, cutter_teeth: 2.0 };
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
        let p = self.model.reading.arrange(inputs);
        if p.iter().any(|&v| v.is_nan() || v <= 0.0) {
            // Not a cut (or not a number): the plain path gives zero, NaN or infinity.
            return (
                self.model.forces(inputs).resultant_n(),
                self.model.relative_uncertainty(inputs, &self.calibrated_on),
            );
        }
        let then = self.model.reading.arrange(&self.calibrated_on);
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
            cutter_teeth: 2.0,
        }
    }

    #[test]
    fn network_and_power_law_agree() {
        for m in PowerLawMaterial::ALL {
            for reading in PowerLawReading::ALL {
                let model = PowerLawModel::published(m, reading);
                let a = model.forces(&inputs());
                let b = model.forces_log_network(&inputs());
                for (u, v) in [(a.fx_n, b.fx_n), (a.fy_n, b.fy_n), (a.fz_n, b.fz_n)] {
                    assert!(
                        (u - v).abs() < 1e-12 * u.abs(),
                        "{m:?} {reading:?}: {u} vs {v}"
                    );
                }
            }
        }
    }

    #[test]
    fn doubling_the_depth_scales_by_two_to_the_depth_weight() {
        for reading in PowerLawReading::ALL {
            let model = PowerLawModel::published(PowerLawMaterial::CarbonSteel, reading);
            let a = model.forces(&inputs());
            let mut deeper = inputs();
            deeper.axial_depth_mm *= 2.0;
            let b = model.forces(&deeper);
            assert!((b.fx_n / a.fx_n - 2f64.powf(1.002)).abs() < 1e-12);
        }
    }

    /// The physics the readings are judged by: at a given width a larger tool cuts thinner chips
    /// (mean chip thickness ∝ a_e/d), and a cutter with more teeth cuts more chips at once.
    #[test]
    fn only_the_swapped_readings_lower_the_force_with_the_diameter_and_raise_it_with_the_teeth() {
        for reading in PowerLawReading::ALL {
            let model = PowerLawModel::published(PowerLawMaterial::CarbonSteel, reading);
            let at = model.forces(&inputs()).resultant_n();
            let larger_tool = PowerLawInputs {
                diameter_mm: 40.0,
                ..inputs()
            };
            let more_teeth = PowerLawInputs {
                teeth_engaged: 1.4,
                cutter_teeth: 4.0,
                ..inputs()
            };
            let physical = model.forces(&larger_tool).resultant_n() < at
                && model.forces(&more_teeth).resultant_n() > at;
            assert_eq!(
                physical,
                reading != PowerLawReading::AsPrinted,
                "{reading:?}"
            );
        }
    }

    #[test]
    fn every_reading_uses_each_published_column_once_and_has_a_source() {
        for reading in PowerLawReading::ALL {
            let columns = reading.columns();
            for (i, input) in columns.iter().enumerate() {
                assert!(!columns[..i].contains(input), "{reading:?}");
            }
            assert!(!reading.source().is_empty());
        }
    }

    #[test]
    fn no_cut_gives_no_force_and_bad_models_are_refused() {
        for reading in PowerLawReading::ALL {
            let model = PowerLawModel::published(PowerLawMaterial::CastIron, reading);
            let air = PowerLawInputs {
                radial_width_mm: 0.0,
                ..inputs()
            };
            assert_eq!(model.forces(&air), PowerLawForces::default());
        }
        let e =
            PowerLawModel::new([[0.0; 5]; 3], [1.0, -1.0, 1.0], PowerLawReading::USED).unwrap_err();
        assert_eq!(e.field, "bias_n[1]");
    }
}
