//! The force of a logged cut from what the machine knows — feed, spindle speed, depth and width —
//! through the mechanistic model: calibration from (current, feed, depth) samples, for a shop
//! without a dynamometer.
//!
//! Each row's force is the closed-form mean cutting force over a revolution (the force the
//! controllers regulate, |F̄| in the x-y plane) for the tool, the material's cutting
//! coefficients and the engagement; the current-to-force line is then fitted against it exactly
//! as against a measured force. The fit is as good as the coefficients: a material whose K_tc is
//! 20 % off gives sensitivities 20 % off, which a teach cut with a dynamometer would not.

use crate::plant::materials::{CuttingCoefficients, Material};
use crate::plant::mechanics::{mean_forces, Cutter, Immersion, MillingMode, ToolForces};

/// The cut a log was made with, apart from what each row says.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CutGeometry {
    /// The cutter (diameter, teeth; the helix does not change a mean force).
    pub cutter: Cutter,
    /// Up, down or slot milling.
    pub mode: MillingMode,
    /// The material's coefficients.
    pub coefficients: CuttingCoefficients,
}

/// The material of one cut by name: one of [`Material::ALL`] with cutting coefficients of its own
/// (the composite part is two materials, and a cut is in one of them). The message names the
/// choices, so `cutlab force` and `cutlab calibrate` refuse the same names alike.
///
/// ```
/// use cutlab::estimation::cut_forces::cutting_material;
/// assert!(cutting_material("sm45c").is_ok());
/// assert!(cutting_material("composite").unwrap_err().contains("two materials"));
/// assert!(cutting_material("cheese").unwrap_err().contains("unknown material"));
/// ```
pub fn cutting_material(name: &str) -> Result<Material, String> {
    let singles = || {
        Material::ALL
            .into_iter()
            .filter(|m| *m != Material::Composite)
            .map(Material::name)
            .collect::<Vec<_>>()
            .join(", ")
    };
    match Material::from_name(name) {
        Some(Material::Composite) => Err(format!(
            "composite is two materials (sm45c then aluminium); give one of them: {}",
            singles()
        )),
        Some(m) => Ok(m),
        None => Err(format!(
            "unknown material {name:?}; materials: {}",
            singles()
        )),
    }
}

impl CutGeometry {
    /// The mean forces of a row over a revolution: `None` where the row cannot say (non-finite
    /// values, no spindle speed), zero in air (no depth, no width or no feed). The spindle model
    /// is fitted against `resultant_n()` (the force the controllers regulate), the feed model
    /// against −F̄ₓ, the force the feed drive pushes against (negative in down milling, where the
    /// cut pulls the table along).
    ///
    /// ```
    /// use cutlab::estimation::cut_forces::CutGeometry;
    /// use cutlab::plant::materials::Material;
    /// use cutlab::plant::mechanics::{Cutter, MillingMode};
    /// let cut = CutGeometry {
    ///     cutter: Cutter::new(20.0, 2, 30.0).unwrap(),
    ///     mode: MillingMode::Slot,
    ///     coefficients: Material::Sm45c.coefficients(),
    /// };
    /// // 200 mm/min at 1000 rpm with two teeth is 0.1 mm per tooth.
    /// let f = cut.mean_forces(200.0, 1000.0, 2.0, 20.0).unwrap().resultant_n();
    /// assert!(f > 0.0);
    /// let same_chip = cut.mean_forces(400.0, 2000.0, 2.0, 20.0).unwrap().resultant_n();
    /// assert!((same_chip - f).abs() < 1e-9);
    /// assert_eq!(cut.mean_forces(200.0, 1000.0, 0.0, 20.0).unwrap().resultant_n(), 0.0);
    /// assert!(cut.mean_forces(200.0, 0.0, 2.0, 20.0).is_none());
    /// ```
    pub fn mean_forces(
        &self,
        feed_mm_min: f64,
        spindle_rpm: f64,
        depth_mm: f64,
        width_mm: f64,
    ) -> Option<ToolForces> {
        let known = [feed_mm_min, spindle_rpm, depth_mm, width_mm]
            .iter()
            .all(|v| v.is_finite());
        if !known || spindle_rpm.abs() < 1.0 {
            return None;
        }
        if depth_mm <= 0.0 || width_mm <= 0.0 || feed_mm_min.abs() <= 0.0 {
            return Some(ToolForces::default());
        }
        let feed_per_tooth_mm =
            feed_mm_min.abs() / (spindle_rpm.abs() * f64::from(self.cutter.teeth));
        let immersion = Immersion::new(self.mode, width_mm, self.cutter.diameter_mm);
        Some(mean_forces(
            &self.cutter,
            &self.coefficients,
            &immersion,
            depth_mm,
            feed_per_tooth_mm,
        ))
    }
}
