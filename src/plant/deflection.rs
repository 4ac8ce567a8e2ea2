//! The cutting-force-induced error (paper 004's CFIE): the tool and the spindle deflect under the
//! force normal to the machined wall, and the wall comes out off by that deflection.
//!
//! Paper 004 takes its error model from an earlier indirect-monitoring system and prints none.
//! cutlab uses the textbook static one: the tool a cantilever clamped in the holder, stiffness
//! k_t = 3·E·I / L³ with I = π·d_e⁴ / 64, in series with the spindle's stiffness k_s at the nose,
//!
//! ```text
//! δ = F_n / k,    1/k = 1/k_t + 1/k_s
//! ```
//!
//! where d_e is the fluted tool's equivalent solid diameter ([`FLUTED_DIAMETER_RATIO`] of its
//! nominal diameter), L its stick-out and E its Young's modulus (carbide). The force is the mean
//! normal force of a control period, so the error is the mean wall position over the period:
//! what a CMM sees along the wall, without the tooth-passing ripple or the tool's dynamics.
//!
//! Paper 004's compensator turns a *predicted* force into the error it will cause through "a
//! predetermined model" ([`ErrorModel`]): the same springs, and the share of the force normal to
//! the wall that the mechanistic model gives for the program's cut ([`normal_share`]), since a
//! force prediction (the power law, a current-based estimate) gives the force's size, not its
//! direction.

use serde::{Deserialize, Serialize};

use super::mechanics::{mean_forces, Cutter, Immersion, ToolForces};
use super::scenario::ScenarioSpec;

/// Young's modulus of cemented carbide (WC–Co, 6–10 % Co: 550–650 GPa), GPa.
pub const CARBIDE_YOUNGS_MODULUS_GPA: f64 = 600.0;

/// A fluted end mill's equivalent solid diameter as a fraction of its nominal diameter (two- to
/// four-flute cutters: 0.75–0.85 for the second moment of area; Kops and Vo, 1990, give 0.8).
pub const FLUTED_DIAMETER_RATIO: f64 = 0.8;

/// Stick-out from the holder when nobody says, in tool diameters (a common 3×D end mill).
pub const DEFAULT_STICK_OUT_DIAMETERS: f64 = 3.0;

/// Radial stiffness at the spindle nose of a machining-centre spindle (20–200 N/µm; a mid-size
/// BT40 spindle about 50), N/mm.
pub const DEFAULT_SPINDLE_STIFFNESS_N_MM: f64 = 50_000.0;

/// The stick-outs a run accepts, mm: from a stub tool barely out of a shrink-fit holder to a
/// long-reach holder's tool (a run also needs the flutes to reach the deepest cut, and at most
/// [`MAX_STICK_OUT_DIAMETERS`] diameters out).
pub const STICK_OUT_RANGE_MM: (f64, f64) = (2.0, 400.0);

/// The longest stick-out accepted, in tool diameters: beyond about ten a slender tool chatters
/// long before its static deflection matters.
pub const MAX_STICK_OUT_DIAMETERS: f64 = 10.0;

/// The spindle stiffnesses a run accepts at the nose, N/µm: from a light high-speed spindle to a
/// heavy boring spindle.
pub const SPINDLE_STIFFNESS_RANGE_N_UM: (f64, f64) = (5.0, 500.0);

/// The tool materials' Young's moduli a run accepts, GPa: from high-speed steel (≈ 210) through
/// ceramics (300–400) to cemented carbide (550–650).
pub const YOUNGS_MODULUS_RANGE_GPA: (f64, f64) = (150.0, 700.0);

/// How a cutter sits in the machine: its stick-out from the holder, its material's Young's
/// modulus and the spindle's stiffness at the nose, each `None` for the default
/// ([`DEFAULT_STICK_OUT_DIAMETERS`] diameters, [`CARBIDE_YOUNGS_MODULUS_GPA`],
/// [`DEFAULT_SPINDLE_STIFFNESS_N_MM`]).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ToolMount {
    /// Stick-out from the holder, mm.
    pub stick_out_mm: Option<f64>,
    /// Radial stiffness at the spindle nose, N/µm.
    pub spindle_stiffness_n_um: Option<f64>,
    /// Young's modulus of the tool's material, GPa.
    pub youngs_modulus_gpa: Option<f64>,
}

impl ToolMount {
    /// The stick-out in use for a tool of `diameter_mm`, mm (the default where none is given).
    pub fn stick_out_or_default_mm(&self, diameter_mm: f64) -> f64 {
        self.stick_out_mm
            .unwrap_or(DEFAULT_STICK_OUT_DIAMETERS * diameter_mm)
    }

    /// The tool material's Young's modulus in use, GPa.
    pub fn youngs_modulus_or_default_gpa(&self) -> f64 {
        self.youngs_modulus_gpa
            .unwrap_or(CARBIDE_YOUNGS_MODULUS_GPA)
    }

    /// The spindle's stiffness in use at its nose, N/µm.
    pub fn spindle_stiffness_or_default_n_um(&self) -> f64 {
        self.spindle_stiffness_n_um
            .unwrap_or(DEFAULT_SPINDLE_STIFFNESS_N_MM / 1e3)
    }
}

/// The tool and spindle as springs between the force and the wall.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ToolStiffness {
    /// The tool's cantilever stiffness at its tip, N/mm.
    pub tool_n_mm: f64,
    /// The spindle's stiffness at its nose, N/mm.
    pub spindle_n_mm: f64,
}

impl ToolStiffness {
    /// A carbide tool of `diameter_mm` sticking out `stick_out_mm`, on a spindle of
    /// `spindle_n_mm`.
    ///
    /// ```
    /// use cutlab::plant::deflection::ToolStiffness;
    /// // Ø20 mm, 60 mm out: k_t = 3·600 GPa·π·16⁴/64 mm⁴ / 60³ mm³ ≈ 26.8 N/µm.
    /// let k = ToolStiffness::carbide(20.0, 60.0, 50_000.0);
    /// assert!((k.tool_n_mm - 26_808.0).abs() < 1.0);
    /// // In series with a 50 N/µm spindle: 17.5 N/µm, so 500 N deflect the wall 28.6 µm.
    /// assert!((k.surface_error_um(500.0) - 28.6).abs() < 0.1);
    /// ```
    pub fn carbide(diameter_mm: f64, stick_out_mm: f64, spindle_n_mm: f64) -> Self {
        Self::cantilever(
            diameter_mm,
            stick_out_mm,
            CARBIDE_YOUNGS_MODULUS_GPA,
            spindle_n_mm,
        )
    }

    /// A tool of `diameter_mm` and Young's modulus `youngs_modulus_gpa` sticking out
    /// `stick_out_mm`, on a spindle of `spindle_n_mm`.
    ///
    /// ```
    /// use cutlab::plant::deflection::ToolStiffness;
    /// // High-speed steel (210 GPa) against carbide (600 GPa): the tool bends 600/210 times as far.
    /// let hss = ToolStiffness::cantilever(10.0, 40.0, 210.0, f64::INFINITY);
    /// let carbide = ToolStiffness::carbide(10.0, 40.0, f64::INFINITY);
    /// assert!((hss.surface_error_um(100.0) / carbide.surface_error_um(100.0) - 600.0 / 210.0).abs() < 1e-9);
    /// ```
    pub fn cantilever(
        diameter_mm: f64,
        stick_out_mm: f64,
        youngs_modulus_gpa: f64,
        spindle_n_mm: f64,
    ) -> Self {
        let equivalent_mm = FLUTED_DIAMETER_RATIO * diameter_mm;
        let second_moment_mm4 = std::f64::consts::PI * equivalent_mm.powi(4) / 64.0;
        let youngs_n_mm2 = youngs_modulus_gpa * 1e3;
        Self {
            tool_n_mm: 3.0 * youngs_n_mm2 * second_moment_mm4 / stick_out_mm.powi(3),
            spindle_n_mm,
        }
    }

    /// The stiffness of `cutter` mounted as `mount` says (a carbide tool, and the defaults, where
    /// it says nothing).
    ///
    /// ```
    /// use cutlab::plant::deflection::{ToolMount, ToolStiffness, DEFAULT_SPINDLE_STIFFNESS_N_MM};
    /// use cutlab::plant::mechanics::Cutter;
    /// let cutter = Cutter { diameter_mm: 10.0, teeth: 4, helix_deg: 30.0, runout_mm: 0.0,
    ///                      runout_angle_deg: 0.0 };
    /// let mount = ToolMount { stick_out_mm: Some(35.0), ..ToolMount::default() };
    /// let k = ToolStiffness::of_cutter(&cutter, mount);
    /// assert_eq!(k, ToolStiffness::carbide(10.0, 35.0, DEFAULT_SPINDLE_STIFFNESS_N_MM));
    /// // A Ø10 mm carbide end mill 35 mm out on a 50 N/µm spindle: 300 N bend it ≈ 42 µm.
    /// assert!((k.surface_error_um(300.0) - 41.5).abs() < 1.0);
    /// ```
    pub fn of_cutter(cutter: &Cutter, mount: ToolMount) -> Self {
        Self::cantilever(
            cutter.diameter_mm,
            mount.stick_out_or_default_mm(cutter.diameter_mm),
            mount.youngs_modulus_or_default_gpa(),
            1e3 * mount.spindle_stiffness_or_default_n_um(),
        )
    }

    /// Tool and spindle in series, N/mm.
    pub fn combined_n_mm(&self) -> f64 {
        1.0 / (1.0 / self.tool_n_mm + 1.0 / self.spindle_n_mm)
    }

    /// The wall's error under a normal force of `normal_force_n`, µm (NaN stays NaN).
    pub fn surface_error_um(&self, normal_force_n: f64) -> f64 {
        1e3 * normal_force_n / self.combined_n_mm()
    }
}

/// The mean force normal to the feed in the plane, N, from the mean in-plane resultant and its
/// feed-direction part: √(F² − F_f²), 0 when rounding makes it negative.
pub fn normal_force_n(in_plane_resultant_n: f64, feed_force_n: f64) -> f64 {
    let square = in_plane_resultant_n * in_plane_resultant_n - feed_force_n * feed_force_n;
    if square.is_nan() {
        f64::NAN
    } else {
        square.max(0.0).sqrt()
    }
}

/// The share of the mean in-plane force normal to the feed, |F̄_y| / |F̄|, 0–1 (NaN for no
/// force): what turns a predicted force's size into the force that bends the tool off the wall.
pub fn normal_share(forces: &ToolForces) -> f64 {
    let resultant_n = forces.resultant_n();
    if resultant_n > 0.0 {
        forces.fy_n.abs() / resultant_n
    } else {
        f64::NAN
    }
}

/// Paper 004's "predetermined model" of the cutting-force-induced error: the error a predicted
/// in-plane force makes, through the tool's and spindle's springs and the normal share of the
/// force at the program's cut.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorModel {
    /// The springs between the force and the wall.
    pub stiffness: ToolStiffness,
    /// |F̄_y| / |F̄| of the mechanistic model at the program's first cut, 0–1.
    pub normal_share: f64,
}

impl ErrorModel {
    /// The model of `spec`'s program: its cutter mounted as `mount` says, and the normal share of its first cut (the first width and depth of cut, the
    /// first move's feed per tooth, the first region's material). The share depends on the
    /// engagement, hardly on the depth or the chip: a program whose width changes along the
    /// path (a taper) keeps the first cut's share, and its compensation the error of that.
    /// `None` for a program without a cut.
    ///
    /// ```
    /// use cutlab::plant::deflection::{ErrorModel, ToolMount};
    /// use cutlab::plant::Preset;
    /// let spec = Preset::KimStepDoc.scenario_spec().unwrap();
    /// let model = ErrorModel::of_program(&spec, ToolMount::default()).unwrap();
    /// assert!(model.normal_share > 0.0 && model.normal_share < 1.0);
    /// // 500 N predicted: the normal share of it bends the tool.
    /// let expected = model.stiffness.surface_error_um(model.normal_share * 500.0);
    /// assert_eq!(model.predicted_error_um(500.0), expected);
    /// ```
    pub fn of_program(spec: &ScenarioSpec, mount: ToolMount) -> Option<Self> {
        let cutter = &spec.cutter;
        let first_positive = |points: &[(f64, f64)]| {
            points
                .iter()
                .map(|&(_, v)| v)
                .find(|v| *v > 0.0 && v.is_finite())
        };
        let depth_mm = first_positive(&spec.depth_mm)?;
        let width_mm = first_positive(&spec.width_mm)?;
        let first_move = spec.moves.first()?;
        let feed_per_tooth_mm =
            first_move.feed_mm_min / (first_move.spindle_rpm * f64::from(cutter.teeth));
        let material = spec.materials.first()?.material;
        let forces = mean_forces(
            cutter,
            &material.coefficients(),
            &Immersion::new(spec.mode, width_mm, cutter.diameter_mm),
            depth_mm,
            feed_per_tooth_mm,
        );
        let normal_share = normal_share(&forces);
        normal_share.is_finite().then(|| Self {
            stiffness: ToolStiffness::of_cutter(cutter, mount),
            normal_share,
        })
    }

    /// The error a predicted in-plane force of `force_n` makes, µm.
    pub fn predicted_error_um(&self, force_n: f64) -> f64 {
        self.stiffness.surface_error_um(self.normal_share * force_n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_tool_is_the_cantilever_closed_form() {
        // δ = F·L³ / (3·E·I) for a tip load on a clamped round bar.
        let (d, l, f) = (10.0_f64, 45.0_f64, 200.0_f64);
        let k = ToolStiffness::carbide(d, l, f64::INFINITY);
        let i = std::f64::consts::PI * (0.8 * d).powi(4) / 64.0;
        let deflection_mm = f * l.powi(3) / (3.0 * 600e3 * i);
        assert!((k.surface_error_um(f) - 1e3 * deflection_mm).abs() < 1e-9);
        // Twice the stick-out: eight times the deflection.
        let longer = ToolStiffness::carbide(d, 2.0 * l, f64::INFINITY);
        assert!((longer.surface_error_um(f) / k.surface_error_um(f) - 8.0).abs() < 1e-9);
    }

    #[test]
    fn springs_in_series_deflect_by_the_sum() {
        let k = ToolStiffness {
            tool_n_mm: 20_000.0,
            spindle_n_mm: 50_000.0,
        };
        let f = 400.0;
        let sum_um = 1e3 * (f / 20_000.0 + f / 50_000.0);
        assert!((k.surface_error_um(f) - sum_um).abs() < 1e-9);
    }

    #[test]
    fn the_normal_force_is_the_in_plane_part_off_the_feed() {
        assert!((normal_force_n(500.0, 300.0) - 400.0).abs() < 1e-9);
        assert_eq!(normal_force_n(300.0, 300.0 + 1e-12), 0.0);
        assert!(normal_force_n(f64::NAN, 1.0).is_nan());
    }
}
