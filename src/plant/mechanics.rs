//! Milling mechanics: the cutter, its immersion in the work, and the forces on it.
//!
//! ## Frame and angles
//!
//! Forces are those the work exerts on the tool, in the *feed frame*: x along the feed, y to its
//! left (x rotated 90° counter-clockwise seen from the spindle), z along the tool axis. The tool
//! turns clockwise seen from the spindle (M03). A tooth's angular position φ is measured
//! clockwise from +y, so φ = 90° points along the feed, where the chip is thickest (Altintas,
//! *Manufacturing Automation*, ch. 2; paper 003 Fig. 1).
//!
//! Up milling cuts material on the +y side: the tooth enters at φ_st = 0 and leaves at
//! φ_ex = arccos(1 − 2a_e/D). Down milling cuts on the −y side: φ_st = π − arccos(1 − 2a_e/D),
//! φ_ex = π. A slot (or a_e ≥ D) spans 0…π.
//!
//! ## Forces (paper 003 eq 1–3, generalised by Altintas ch. 2)
//!
//! The uncut chip thickness is h(φ) = s_t·sin φ (paper 003 eq 1, s_t the feed per tooth), plus a
//! per-tooth offset Δ_j when the cutter runs out. On an edge element of height dz:
//!
//! ```text
//! dF_t = (K_tc·h + K_te)·dz,  dF_r = (K_rc·h + K_re)·dz,  dF_a = (K_ac·h + K_ae)·dz   (h > 0)
//! dF_x = −dF_t·cos φ − dF_r·sin φ
//! dF_y = +dF_t·sin φ − dF_r·cos φ
//! dF_z = +dF_a
//! dT   = r_j·dF_t                                                       (paper 003 eq 3)
//! ```
//!
//! With K_te = K_re = 0 and r = K_rc/K_tc this is paper 003's Martelotti model, F_T = K_T·a·s_t·sin φ,
//! F_R = r·F_T (eq 1–2); see [`Martelotti`] for eq 4–6.
//!
//! A helical edge (helix angle β) lags with height: φ_j(z) = φ_j − k_β·z, k_β = 2·tan β / D.
//! Instead of summing axial slices, cutlab integrates over z exactly: with u = φ_j(z),
//! dz = −du/k_β, so each tooth's force is (1/k_β)·[G(u)] between the angles its edge spans
//! inside the immersion, G being the closed-form antiderivative of dF over φ. This is the limit
//! of infinitely many slices and costs two sine/cosine pairs per sample. β = 0 uses dF·a at the
//! single angle.
//!
//! ## Mean forces
//!
//! Over whole revolutions, with no runout, every helix gives the same mean as the straight
//! cutter (Altintas eq 2.x):
//!
//! ```text
//! F̄x = (Z·a/2π)·{ (s_t/4)·[K_tc·cos 2φ − K_rc·(2φ − sin 2φ)] + [−K_te·sin φ + K_re·cos φ] }  φ_st→φ_ex
//! F̄y = (Z·a/2π)·{ (s_t/4)·[K_tc·(2φ − sin 2φ) + K_rc·cos 2φ] − [K_te·cos φ + K_re·sin φ] }   φ_st→φ_ex
//! F̄z = (Z·a/2π)·[ −K_ac·s_t·cos φ + K_ae·φ ]                                                  φ_st→φ_ex
//! T̄  = (Z·a·R/2π)·[ −K_tc·s_t·cos φ + K_te·φ ]                                                φ_st→φ_ex
//! ```
//!
//! implemented by [`mean_forces`] and checked against simulated revolutions in the tests.
//!
//! ## Runout
//!
//! An axis offset ρ at angle λ gives tooth j the radius r_j = R + ρ·cos(λ − j·2π/Z) and the chip
//! h_j = s_t·sin φ + (r_j − r_(j−1)) (one-tooth memory: when a tooth's chip would be negative it
//! does not cut; the thicker chip the next tooth then meets is not modelled, so keep ρ below the
//! feed per tooth). The offsets sum to zero over the teeth, so the mean forces change only where
//! a tooth with Δ_j < 0 stops cutting: the thin ends of its chip, a fraction ≈ |Δ_j|/s_t of the
//! immersion next to φ = 0 or π.
//!
//! Non-finite inputs to [`MillingForceModel::forces`] give non-finite forces; a zero or negative
//! depth or immersion gives zero force. A zero feed per tooth (the axes stopped while the spindle
//! turns in the cut) leaves the edge forces: the edges rub.

use serde::{Deserialize, Serialize};
use std::f64::consts::{PI, TAU};

use super::materials::CuttingCoefficients;
use super::{finite, in_range, non_negative, positive, PlantError};
use crate::input::readable;
use crate::math;

/// The most turns of the cutter a helical edge may wrap within the cut (see
/// [`Cutter::max_axial_depth_mm`]); a real flute wraps less than one.
pub const MAX_EDGE_TURNS: f64 = 64.0;

/// The largest cutter the model stands for: an end mill (a face mill is another tool, and a
/// 10⁶ mm "cutter" is a typo).
pub const MAX_DIAMETER_MM: f64 = 200.0;

/// The cutter diameters the lab's forms and options take, mm: from a small end mill to a large
/// one (the model itself stands for up to [`MAX_DIAMETER_MM`]).
pub const DIAMETER_RANGE_MM: (f64, f64) = (0.5, 100.0);

/// The longest flute of an end mill, in diameters: a deeper cut is no cut a mill makes.
pub const MAX_DEPTH_DIAMETERS: f64 = 5.0;

/// The largest feed per tooth the model takes: roughing end mills stay below 1 mm, and beyond a
/// few millimetres the chip-thickness model means nothing.
pub const MAX_FEED_PER_TOOTH_MM: f64 = 5.0;

/// The most teeth a cutter may have (per-tooth state lives in fixed arrays).
pub const MAX_TEETH: u32 = 16;

/// An end mill.
///
/// ```
/// use cutlab::plant::mechanics::Cutter;
/// let c = Cutter::new(20.0, 2, 30.0).unwrap();
/// assert!((c.helix_lag_rad_per_mm() - 2.0 * 30f64.to_radians().tan() / 20.0).abs() < 1e-15);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Cutter {
    /// Diameter D.
    pub diameter_mm: f64,
    /// Number of teeth (flutes) Z, 1…16.
    pub teeth: u32,
    /// Helix angle β of a right-hand cutter; 0 for straight teeth.
    pub helix_deg: f64,
    /// Radial runout ρ: offset of the cutting circle's centre from the spindle axis.
    pub runout_mm: f64,
    /// Angle λ of the runout offset, measured like φ from tooth 0.
    pub runout_angle_deg: f64,
}

impl Cutter {
    /// A cutter without runout.
    pub fn new(diameter_mm: f64, teeth: u32, helix_deg: f64) -> Result<Self, PlantError> {
        let c = Self {
            diameter_mm,
            teeth,
            helix_deg,
            runout_mm: 0.0,
            runout_angle_deg: 0.0,
        };
        c.validate()?;
        Ok(c)
    }

    /// The same cutter running out by `runout_mm` at `angle_deg`.
    ///
    /// ```
    /// use cutlab::plant::mechanics::Cutter;
    /// let c = Cutter::new(10.0, 4, 30.0).unwrap().with_runout(0.005, 0.0).unwrap();
    /// assert_eq!(c.runout_mm, 0.005);
    /// assert!(Cutter::new(10.0, 4, 30.0).unwrap().with_runout(6.0, 0.0).is_err());
    /// ```
    pub fn with_runout(self, runout_mm: f64, angle_deg: f64) -> Result<Self, PlantError> {
        let c = Self {
            runout_mm,
            runout_angle_deg: angle_deg,
            ..self
        };
        c.validate()?;
        Ok(c)
    }

    /// Checks every field.
    pub fn validate(&self) -> Result<(), PlantError> {
        positive("diameter_mm", self.diameter_mm)?;
        if self.diameter_mm > MAX_DIAMETER_MM {
            return Err(PlantError::new(
                "diameter_mm",
                format!(
                    "{} mm is larger than any end mill (at most {MAX_DIAMETER_MM} mm)",
                    crate::input::readable(self.diameter_mm)
                ),
            ));
        }
        if self.teeth == 0 || self.teeth > MAX_TEETH {
            return Err(PlantError::new(
                "teeth",
                format!("must lie in 1..={MAX_TEETH}, got {}", self.teeth),
            ));
        }
        in_range("helix_deg", self.helix_deg, 0.0, 60.0)?;
        non_negative("runout_mm", self.runout_mm)?;
        if self.runout_mm >= 0.1 * self.diameter_mm {
            return Err(PlantError::new(
                "runout_mm",
                format!(
                    "must be below a tenth of the diameter ({} mm), got {}",
                    0.1 * self.diameter_mm,
                    self.runout_mm
                ),
            ));
        }
        finite("runout_angle_deg", self.runout_angle_deg)?;
        Ok(())
    }

    /// Checks that a cut is one this cutter can make: an axial depth within its flute
    /// ([`MAX_DEPTH_DIAMETERS`] diameters) and a feed per tooth up to [`MAX_FEED_PER_TOOTH_MM`].
    ///
    /// ```
    /// use cutlab::plant::mechanics::Cutter;
    /// let c = Cutter::new(10.0, 2, 30.0).unwrap();
    /// assert!(c.check_cut(20.0, 0.1).is_ok());
    /// let e = c.check_cut(1000.0, 0.1).unwrap_err();
    /// assert_eq!(e.field, "axial_depth_mm");
    /// assert!(c.check_cut(3.0, 1e300).is_err());
    /// ```
    pub fn check_cut(&self, axial_depth_mm: f64, feed_per_tooth_mm: f64) -> Result<(), PlantError> {
        let deepest_mm = MAX_DEPTH_DIAMETERS * self.diameter_mm;
        if !(0.0..=deepest_mm).contains(&axial_depth_mm) {
            return Err(PlantError::new(
                "axial_depth_mm",
                format!(
                    "{} mm is deeper than the flute of a {} mm end mill (at most {} mm, \
                     {MAX_DEPTH_DIAMETERS} diameters)",
                    readable(axial_depth_mm),
                    readable(self.diameter_mm),
                    readable(deepest_mm)
                ),
            ));
        }
        if !(0.0..=MAX_FEED_PER_TOOTH_MM).contains(&feed_per_tooth_mm) {
            return Err(PlantError::new(
                "feed_per_tooth_mm",
                format!(
                    "{} mm is beyond any feed per tooth (at most {MAX_FEED_PER_TOOTH_MM} mm)",
                    readable(feed_per_tooth_mm)
                ),
            ));
        }
        Ok(())
    }

    /// Radius R = D/2.
    pub fn radius_mm(&self) -> f64 {
        0.5 * self.diameter_mm
    }

    /// Angle between neighbouring teeth, 2π/Z.
    pub fn tooth_pitch_rad(&self) -> f64 {
        TAU / f64::from(self.teeth)
    }

    /// The deepest cut the force model integrates exactly: a helical edge that wraps more than
    /// [`MAX_EDGE_TURNS`] turns round the cutter is refused rather than cut short. Unbounded
    /// for a straight cutter.
    ///
    /// ```
    /// use cutlab::plant::mechanics::Cutter;
    /// let c = Cutter::new(20.0, 2, 30.0).unwrap();
    /// assert!(c.max_axial_depth_mm() > 6000.0); // far beyond any flute
    /// assert!(Cutter::new(20.0, 2, 0.0).unwrap().max_axial_depth_mm().is_infinite());
    /// ```
    pub fn max_axial_depth_mm(&self) -> f64 {
        let lag = self.helix_lag_rad_per_mm();
        if lag > 0.0 {
            (MAX_EDGE_TURNS - 2.0) * TAU / lag
        } else {
            f64::INFINITY
        }
    }

    /// k_β = 2·tan β / D: how far the edge lags per millimetre of height.
    pub fn helix_lag_rad_per_mm(&self) -> f64 {
        2.0 * math::tan(self.helix_deg.to_radians()) / self.diameter_mm
    }

    /// Radius of tooth `j` with runout, r_j = R + ρ·cos(λ − j·2π/Z).
    pub fn tooth_radius_mm(&self, j: u32) -> f64 {
        self.radius_mm()
            + self.runout_mm
                * math::cos(
                    self.runout_angle_deg.to_radians() - f64::from(j) * self.tooth_pitch_rad(),
                )
    }
}

/// Which side of the cutter meets the work.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MillingMode {
    /// Up (conventional) milling: the chip starts thin. Material on the cutter's left.
    Up,
    /// Down (climb) milling: the chip starts thick. Material on the cutter's right.
    Down,
    /// Slotting: full immersion whatever the width.
    Slot,
}

impl MillingMode {
    /// Every mode.
    pub const ALL: [MillingMode; 3] = [MillingMode::Up, MillingMode::Down, MillingMode::Slot];

    /// Short name (`up`, `down`, `slot`).
    pub fn name(self) -> &'static str {
        match self {
            MillingMode::Up => "up",
            MillingMode::Down => "down",
            MillingMode::Slot => "slot",
        }
    }

    /// Label for forms.
    pub fn label(self) -> &'static str {
        match self {
            MillingMode::Up => "Up milling",
            MillingMode::Down => "Down milling",
            MillingMode::Slot => "Slot",
        }
    }

    /// The mode named `name`.
    ///
    /// ```
    /// use cutlab::plant::mechanics::MillingMode;
    /// assert_eq!(MillingMode::from_name("Down"), Some(MillingMode::Down));
    /// assert_eq!(MillingMode::ALL.len(), 3);
    /// ```
    pub fn from_name(name: &str) -> Option<Self> {
        let n = name.trim().to_ascii_lowercase();
        Self::ALL.into_iter().find(|m| m.name() == n)
    }
}

/// An angle with its sine and cosine.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Angle {
    rad: f64,
    sin: f64,
    cos: f64,
}

impl Angle {
    fn new(rad: f64) -> Self {
        Self {
            rad,
            sin: math::sin(rad),
            cos: math::cos(rad),
        }
    }

    /// This angle plus `by` (whose sine and cosine are `by_sin`, `by_cos`), by the addition
    /// theorem: no transcendental call.
    #[inline(always)]
    fn plus(self, by_rad: f64, by_sin: f64, by_cos: f64) -> Self {
        Self {
            rad: self.rad + by_rad,
            sin: self.sin * by_cos + self.cos * by_sin,
            cos: self.cos * by_cos - self.sin * by_sin,
        }
    }

    /// The same direction shifted by whole turns (sine and cosine unchanged).
    #[inline(always)]
    fn shifted(self, turns: f64) -> Self {
        Self {
            rad: self.rad + TAU * turns,
            ..self
        }
    }
}

/// The arc of tooth positions that are in the work: φ_st ≤ φ ≤ φ_ex.
///
/// ```
/// use cutlab::plant::mechanics::{Immersion, MillingMode};
/// let half = Immersion::new(MillingMode::Up, 5.0, 10.0);
/// assert!((half.exit_rad - std::f64::consts::FRAC_PI_2).abs() < 1e-12);
/// assert_eq!(Immersion::new(MillingMode::Down, 0.0, 10.0).span_rad(), 0.0);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Immersion {
    /// Entry angle φ_st.
    pub entry_rad: f64,
    /// Exit angle φ_ex.
    pub exit_rad: f64,
    entry: Angle,
    exit: Angle,
}

impl Immersion {
    /// The immersion of a cut of radial width `radial_width_mm` with a cutter of `diameter_mm`.
    /// A width ≤ 0 (or NaN) is an air cut; a width ≥ D, or slot mode, is full immersion.
    pub fn new(mode: MillingMode, radial_width_mm: f64, diameter_mm: f64) -> Self {
        // Written so that NaN lands in the empty branch.
        let ratio = if radial_width_mm > 0.0 && diameter_mm > 0.0 {
            (radial_width_mm / diameter_mm).min(1.0)
        } else {
            0.0
        };
        if ratio <= 0.0 && mode != MillingMode::Slot {
            return Self::from_angles_unchecked(0.0, 0.0);
        }
        let swept = math::acos(1.0 - 2.0 * ratio);
        match mode {
            MillingMode::Slot => Self::from_angles_unchecked(0.0, PI),
            MillingMode::Up => Self::from_angles_unchecked(0.0, swept),
            MillingMode::Down => Self::from_angles_unchecked(PI - swept, PI),
        }
    }

    /// An immersion from its angles, 0 ≤ entry ≤ exit ≤ π.
    pub fn from_angles(entry_rad: f64, exit_rad: f64) -> Result<Self, PlantError> {
        in_range("entry_rad", entry_rad, 0.0, PI)?;
        in_range("exit_rad", exit_rad, entry_rad, PI)?;
        Ok(Self::from_angles_unchecked(entry_rad, exit_rad))
    }

    fn from_angles_unchecked(entry_rad: f64, exit_rad: f64) -> Self {
        Self {
            entry_rad,
            exit_rad,
            entry: Angle::new(entry_rad),
            exit: Angle::new(exit_rad),
        }
    }

    /// φ_ex − φ_st.
    pub fn span_rad(&self) -> f64 {
        self.exit_rad - self.entry_rad
    }

    /// The radial width this immersion corresponds to, D·(cos φ_st − cos φ_ex)/2.
    pub fn radial_width_mm(&self, diameter_mm: f64) -> f64 {
        0.5 * diameter_mm * (self.entry.cos - self.exit.cos)
    }

    /// Mean number of teeth in the cut, Z·(φ_ex − φ_st)/2π (paper 004's z_e).
    ///
    /// ```
    /// use cutlab::plant::mechanics::{Immersion, MillingMode};
    /// assert_eq!(Immersion::new(MillingMode::Slot, 10.0, 10.0).teeth_engaged(4), 2.0);
    /// ```
    pub fn teeth_engaged(&self, teeth: u32) -> f64 {
        f64::from(teeth) * self.span_rad() / TAU
    }
}

/// Forces and torque on the tool, in the feed frame.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize)]
pub struct ToolForces {
    /// Along the feed.
    pub fx_n: f64,
    /// Normal to the feed, to its left.
    pub fy_n: f64,
    /// Along the tool axis.
    pub fz_n: f64,
    /// Cutting torque about the tool axis.
    pub torque_nm: f64,
}

impl ToolForces {
    /// |F| in the x-y plane, the force the controllers regulate.
    ///
    /// ```
    /// use cutlab::plant::mechanics::ToolForces;
    /// let f = ToolForces { fx_n: 3.0, fy_n: 4.0, fz_n: 12.0, torque_nm: 0.0 };
    /// assert_eq!(f.resultant_n(), 5.0);
    /// ```
    pub fn resultant_n(&self) -> f64 {
        // √(x² + y²) directly (exactly rounded everywhere): cutting forces are far from the
        // overflow `hypot` guards against, and this runs every sample.
        (self.fx_n * self.fx_n + self.fy_n * self.fy_n).sqrt()
    }

    /// Cutting power T·ω at spindle speed `rpm`.
    ///
    /// ```
    /// use cutlab::plant::mechanics::ToolForces;
    /// let f = ToolForces { torque_nm: 10.0, ..Default::default() };
    /// assert!((f.power_w(1000.0) - 10.0 * 1000.0 * std::f64::consts::TAU / 60.0).abs() < 1e-9);
    /// ```
    pub fn power_w(&self, rpm: f64) -> f64 {
        self.torque_nm * super::rad_s_from_rpm(rpm)
    }
}

/// Instantaneous mechanistic milling forces of one cutter.
///
/// ```
/// use cutlab::plant::materials::Material;
/// use cutlab::plant::mechanics::{Cutter, Immersion, MillingForceModel, MillingMode};
/// let model = MillingForceModel::new(Cutter::new(20.0, 2, 0.0).unwrap()).unwrap();
/// let k = Material::Sm45c.coefficients();
/// let slot = Immersion::new(MillingMode::Slot, 20.0, 20.0);
/// // Tooth 0 at φ = 90°, straight teeth: F_y = F_t = (K_tc·s_t + K_te)·a.
/// let f = model.forces(&k, &slot, 3.0, 0.1, std::f64::consts::FRAC_PI_2);
/// assert!((f.fy_n - (2200.0 * 0.1 + 35.0) * 3.0).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MillingForceModel {
    cutter: Cutter,
    teeth: usize,
    /// Sine and cosine of j·2π/Z.
    tooth_offset: [(f64, f64, f64); MAX_TEETH as usize],
    /// r_j in mm.
    tooth_radius_mm: [f64; MAX_TEETH as usize],
    /// Δ_j = r_j − r_(j−1) in mm.
    chip_offset_mm: [f64; MAX_TEETH as usize],
    helix_lag_rad_per_mm: f64,
    /// Its reciprocal (∞ for straight teeth, which never use it).
    helix_mm_per_lag_rad: f64,
    /// The depth [`MillingForceModel::forces_at`] last saw and the helix lag across it, with its
    /// sine and cosine: the depth changes rarely, the lag's trigonometry need not run per sample.
    lag_depth_mm: f64,
    lag: Angle,
}

/// 1/2π, to count turns by a multiplication.
const TURNS_PER_RAD: f64 = 1.0 / TAU;

/// Below this lag across the whole depth (radians) the helix is treated as straight.
const STRAIGHT_LAG_RAD: f64 = 1e-9;

impl MillingForceModel {
    /// The model for `cutter`.
    pub fn new(cutter: Cutter) -> Result<Self, PlantError> {
        cutter.validate()?;
        let teeth = cutter.teeth as usize;
        let mut tooth_offset = [(0.0, 0.0, 1.0); MAX_TEETH as usize];
        let mut tooth_radius_mm = [0.0; MAX_TEETH as usize];
        let mut chip_offset_mm = [0.0; MAX_TEETH as usize];
        let pitch = cutter.tooth_pitch_rad();
        for j in 0..teeth {
            let a = pitch * j as f64;
            tooth_offset[j] = (a, math::sin(a), math::cos(a));
            tooth_radius_mm[j] = cutter.tooth_radius_mm(j as u32);
        }
        for j in 0..teeth {
            let previous = (j + teeth - 1) % teeth;
            chip_offset_mm[j] = if cutter.runout_mm > 0.0 {
                tooth_radius_mm[j] - tooth_radius_mm[previous]
            } else {
                0.0
            };
        }
        Ok(Self {
            cutter,
            teeth,
            tooth_offset,
            tooth_radius_mm,
            chip_offset_mm,
            helix_lag_rad_per_mm: cutter.helix_lag_rad_per_mm(),
            helix_mm_per_lag_rad: 1.0 / cutter.helix_lag_rad_per_mm(),
            lag_depth_mm: 0.0,
            lag: Angle::new(0.0),
        })
    }

    /// The cutter.
    pub fn cutter(&self) -> &Cutter {
        &self.cutter
    }

    /// Forces with tooth 0's bottom edge at `angle_rad` (measured like φ), cutting `k` at axial
    /// depth `axial_depth_mm` with feed per tooth `feed_per_tooth_mm` through `immersion`.
    pub fn forces(
        &self,
        k: &CuttingCoefficients,
        immersion: &Immersion,
        axial_depth_mm: f64,
        feed_per_tooth_mm: f64,
        angle_rad: f64,
    ) -> ToolForces {
        let lag = self.helix_lag(axial_depth_mm);
        let base = Angle::new(angle_rad.rem_euclid(TAU));
        self.forces_with(k, immersion, axial_depth_mm, feed_per_tooth_mm, base, lag)
    }

    /// [`Self::forces`] with tooth 0's angle given with its cosine and sine (the simulator keeps
    /// them by rotation, [`crate::math::Phasor`]) and the helix lag's trigonometry kept while the
    /// depth stays: no transcendental call per sample.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(crate) fn forces_at(
        &mut self,
        k: &CuttingCoefficients,
        immersion: &Immersion,
        axial_depth_mm: f64,
        feed_per_tooth_mm: f64,
        angle_rad: f64,
        cos_angle: f64,
        sin_angle: f64,
    ) -> ToolForces {
        if axial_depth_mm != self.lag_depth_mm {
            self.lag = self.helix_lag(axial_depth_mm);
            self.lag_depth_mm = axial_depth_mm;
        }
        let base = Angle {
            rad: math::wrap_turn(angle_rad),
            sin: sin_angle,
            cos: cos_angle,
        };
        self.forces_with(
            k,
            immersion,
            axial_depth_mm,
            feed_per_tooth_mm,
            base,
            self.lag,
        )
    }

    /// The helix lag across `axial_depth_mm`, 0 for straight teeth.
    fn helix_lag(&self, axial_depth_mm: f64) -> Angle {
        let lag = self.helix_lag_rad_per_mm * axial_depth_mm;
        if lag > STRAIGHT_LAG_RAD {
            Angle::new(lag)
        } else {
            Angle::new(0.0)
        }
    }

    #[inline(always)]
    fn forces_with(
        &self,
        k: &CuttingCoefficients,
        immersion: &Immersion,
        axial_depth_mm: f64,
        feed_per_tooth_mm: f64,
        base: Angle,
        lag_angle: Angle,
    ) -> ToolForces {
        let mut out = ToolForces::default();
        if axial_depth_mm.is_nan() || feed_per_tooth_mm.is_nan() || base.rad.is_nan() {
            return ToolForces {
                fx_n: f64::NAN,
                fy_n: f64::NAN,
                fz_n: f64::NAN,
                torque_nm: f64::NAN,
            };
        }
        // Written so that an infinite depth or feed saturates to no cut rather than ∞·0 = NaN.
        let cuts = axial_depth_mm > 0.0
            && feed_per_tooth_mm >= 0.0
            && immersion.span_rad() > 0.0
            && axial_depth_mm.is_finite()
            && feed_per_tooth_mm.is_finite();
        if !cuts {
            return out;
        }
        let f = feed_per_tooth_mm;
        let helical = lag_angle.rad > STRAIGHT_LAG_RAD;
        for j in 0..self.teeth {
            let delta = self.chip_offset_mm[j];
            let Some((entry, exit)) = tooth_window(immersion, delta, f) else {
                continue;
            };
            let (off, off_sin, off_cos) = self.tooth_offset[j];
            let bottom = base.plus(off, off_sin, off_cos);
            let mut sums = [0.0; 4]; // x, y, z, tangential
            if helical {
                let top = bottom.plus(-lag_angle.rad, -lag_angle.sin, lag_angle.cos);
                // The edge spans [top, bottom]; intersect with every turn of [entry, exit].
                let k_min = -floor_small((exit.rad - top.rad) * TURNS_PER_RAD);
                let k_max = floor_small((bottom.rad - entry.rad) * TURNS_PER_RAD);
                let mut turn = k_min;
                let mut guard = 0;
                while turn <= k_max && guard < MAX_EDGE_TURNS as u32 {
                    let lo_edge = entry.shifted(turn);
                    let hi_edge = exit.shifted(turn);
                    let lo = if lo_edge.rad > top.rad { lo_edge } else { top };
                    let hi = if hi_edge.rad < bottom.rad {
                        hi_edge
                    } else {
                        bottom
                    };
                    if hi.rad > lo.rad {
                        let g_hi = antiderivative(k, f, delta, hi);
                        let g_lo = antiderivative(k, f, delta, lo);
                        for i in 0..4 {
                            sums[i] += g_hi[i] - g_lo[i];
                        }
                    }
                    turn += 1.0;
                    guard += 1;
                }
                for s in sums.iter_mut() {
                    *s *= self.helix_mm_per_lag_rad;
                }
            } else {
                let phi = math::wrap_turn(bottom.rad);
                if phi >= entry.rad && phi <= exit.rad {
                    let h = f * bottom.sin + delta;
                    let ft = k.ktc_n_mm2 * h + k.kte_n_mm;
                    let fr = k.krc_n_mm2 * h + k.kre_n_mm;
                    let fa = k.kac_n_mm2 * h + k.kae_n_mm;
                    sums = [
                        (-ft * bottom.cos - fr * bottom.sin) * axial_depth_mm,
                        (ft * bottom.sin - fr * bottom.cos) * axial_depth_mm,
                        fa * axial_depth_mm,
                        ft * axial_depth_mm,
                    ];
                }
            }
            out.fx_n += sums[0];
            out.fy_n += sums[1];
            out.fz_n += sums[2];
            out.torque_nm += sums[3] * self.tooth_radius_mm[j] * 1e-3;
        }
        out
    }
}

/// ⌊x⌋ for the few turns an edge spans, by rounding arithmetic ([`math::round_ties_even`]:
/// `floor` is a library call on the baseline x86-64 target); exact for |x| < 2⁵¹, which the turn
/// counts are far below.
#[inline(always)]
fn floor_small(x: f64) -> f64 {
    let r = math::round_ties_even(x);
    if r > x {
        r - 1.0
    } else {
        r
    }
}

/// The part of the immersion where tooth j's chip is positive: with Δ < 0 the tooth cuts only
/// where s_t·sin φ > −Δ. `None` if it does not cut at all.
#[inline(always)]
fn tooth_window(immersion: &Immersion, delta_mm: f64, f: f64) -> Option<(Angle, Angle)> {
    if delta_mm >= 0.0 {
        return Some((immersion.entry, immersion.exit));
    }
    let r = -delta_mm / f;
    if r >= 1.0 {
        return None;
    }
    let c = (1.0 - r * r).sqrt();
    let first = math::asin(r);
    let start = Angle {
        rad: first,
        sin: r,
        cos: c,
    };
    let end = Angle {
        rad: PI - first,
        sin: r,
        cos: -c,
    };
    let entry = if start.rad > immersion.entry_rad {
        start
    } else {
        immersion.entry
    };
    let exit = if end.rad < immersion.exit_rad {
        end
    } else {
        immersion.exit
    };
    (exit.rad > entry.rad).then_some((entry, exit))
}

/// ∫ dF dφ per unit height at `at`, for h = f·sin φ + Δ: [x, y, z, tangential].
#[inline(always)]
fn antiderivative(k: &CuttingCoefficients, f: f64, delta: f64, at: Angle) -> [f64; 4] {
    let (phi, s, c) = (at.rad, at.sin, at.cos);
    let half_sq = 0.5 * s * s; // ∫ sin·cos
    let sin_sq = 0.5 * phi - 0.5 * s * c; // ∫ sin²
    let t0 = k.ktc_n_mm2 * delta + k.kte_n_mm;
    let r0 = k.krc_n_mm2 * delta + k.kre_n_mm;
    let a0 = k.kac_n_mm2 * delta + k.kae_n_mm;
    [
        -k.ktc_n_mm2 * f * half_sq - t0 * s - k.krc_n_mm2 * f * sin_sq + r0 * c,
        k.ktc_n_mm2 * f * sin_sq - t0 * c - k.krc_n_mm2 * f * half_sq - r0 * s,
        -k.kac_n_mm2 * f * c + a0 * phi,
        -k.ktc_n_mm2 * f * c + t0 * phi,
    ]
}

/// Mean forces and torque over whole revolutions (no runout), in the closed form of Altintas
/// ch. 2 given in the module docs.
///
/// ```
/// use cutlab::plant::materials::CuttingCoefficients;
/// use cutlab::plant::mechanics::{mean_forces, Cutter, Immersion, MillingMode};
/// let k = CuttingCoefficients::new(2000.0, 800.0, 400.0, 0.0, 0.0, 0.0).unwrap();
/// let c = Cutter::new(20.0, 2, 30.0).unwrap();
/// let f = mean_forces(&c, &k, &Immersion::new(MillingMode::Slot, 20.0, 20.0), 4.0, 0.1);
/// // Slot, no edge forces: F̄x = −Z·a·s_t·K_rc/4, F̄y = Z·a·s_t·K_tc/4.
/// assert!((f.fx_n + 2.0 * 4.0 * 0.1 * 800.0 / 4.0).abs() < 1e-9);
/// assert!((f.fy_n - 2.0 * 4.0 * 0.1 * 2000.0 / 4.0).abs() < 1e-9);
/// ```
pub fn mean_forces(
    cutter: &Cutter,
    k: &CuttingCoefficients,
    immersion: &Immersion,
    axial_depth_mm: f64,
    feed_per_tooth_mm: f64,
) -> ToolForces {
    if !(axial_depth_mm > 0.0 && feed_per_tooth_mm >= 0.0 && immersion.span_rad() > 0.0) {
        return ToolForces::default();
    }
    let f = feed_per_tooth_mm;
    let scale = f64::from(cutter.teeth) * axial_depth_mm / TAU;
    let x = |p: f64| {
        0.25 * f * (k.ktc_n_mm2 * math::cos(2.0 * p) - k.krc_n_mm2 * (2.0 * p - math::sin(2.0 * p)))
            + (-k.kte_n_mm * math::sin(p) + k.kre_n_mm * math::cos(p))
    };
    let y = |p: f64| {
        0.25 * f * (k.ktc_n_mm2 * (2.0 * p - math::sin(2.0 * p)) + k.krc_n_mm2 * math::cos(2.0 * p))
            - (k.kte_n_mm * math::cos(p) + k.kre_n_mm * math::sin(p))
    };
    let z = |p: f64| -k.kac_n_mm2 * f * math::cos(p) + k.kae_n_mm * p;
    let t = |p: f64| -k.ktc_n_mm2 * f * math::cos(p) + k.kte_n_mm * p;
    let (st, ex) = (immersion.entry_rad, immersion.exit_rad);
    ToolForces {
        fx_n: scale * (x(ex) - x(st)),
        fy_n: scale * (y(ex) - y(st)),
        fz_n: scale * (z(ex) - z(st)),
        torque_nm: scale * cutter.radius_mm() * 1e-3 * (t(ex) - t(st)),
    }
}

/// Paper 003's Martelotti model (eq 1–6): F_T = K_T·a·s_t·sin φ, F_R = r·F_T, T_c = R·F_T, and
/// for full immersion with few teeth the peak force per tooth F_c,max = √(1 + r²)/R · T_c,max.
///
/// ```
/// use cutlab::plant::mechanics::Martelotti;
/// let m = Martelotti { specific_pressure_n_mm2: 2000.0, radial_ratio: 0.4, radius_mm: 10.0 };
/// let peak_torque = m.peak_torque_full_immersion_nm(3.0, 0.1); // eq 4: R·F_T(90°)
/// assert!((peak_torque - 10e-3 * 2000.0 * 3.0 * 0.1).abs() < 1e-12);
/// let peak_force = m.peak_force_from_peak_torque_n(peak_torque); // eq 6
/// assert!((peak_force - (1.0f64 + 0.16).sqrt() * 600.0).abs() < 1e-9);
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Martelotti {
    /// Specific cutting pressure K_T (= K_tc).
    pub specific_pressure_n_mm2: f64,
    /// Radial-to-tangential force ratio r (= K_rc/K_tc).
    pub radial_ratio: f64,
    /// Cutter radius R.
    pub radius_mm: f64,
}

impl Martelotti {
    /// Eq 1: tangential force on one tooth at angle φ.
    pub fn tangential_force_n(&self, axial_depth_mm: f64, feed_per_tooth_mm: f64, phi: f64) -> f64 {
        self.specific_pressure_n_mm2 * axial_depth_mm * feed_per_tooth_mm * math::sin(phi)
    }

    /// Eq 2: radial force on one tooth at angle φ.
    pub fn radial_force_n(&self, axial_depth_mm: f64, feed_per_tooth_mm: f64, phi: f64) -> f64 {
        self.radial_ratio * self.tangential_force_n(axial_depth_mm, feed_per_tooth_mm, phi)
    }

    /// Eq 3: cutting torque of one tooth at angle φ.
    pub fn torque_nm(&self, axial_depth_mm: f64, feed_per_tooth_mm: f64, phi: f64) -> f64 {
        self.radius_mm * 1e-3 * self.tangential_force_n(axial_depth_mm, feed_per_tooth_mm, phi)
    }

    /// Eq 4: peak torque per tooth in full immersion, at φ = 90°.
    pub fn peak_torque_full_immersion_nm(
        &self,
        axial_depth_mm: f64,
        feed_per_tooth_mm: f64,
    ) -> f64 {
        self.torque_nm(
            axial_depth_mm,
            feed_per_tooth_mm,
            std::f64::consts::FRAC_PI_2,
        )
    }

    /// Eq 6: peak force per tooth from the peak torque, √(1 + r²)/R · T_c,max.
    pub fn peak_force_from_peak_torque_n(&self, peak_torque_nm: f64) -> f64 {
        (1.0 + self.radial_ratio * self.radial_ratio).sqrt() / (self.radius_mm * 1e-3)
            * peak_torque_nm
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::plant::materials::Material;

    fn model(teeth: u32, helix: f64) -> MillingForceModel {
        MillingForceModel::new(Cutter::new(10.0, teeth, helix).unwrap()).unwrap()
    }

    #[test]
    fn immersion_angles_follow_the_mode() {
        let up = Immersion::new(MillingMode::Up, 2.5, 10.0);
        assert_eq!(up.entry_rad, 0.0);
        assert!((up.exit_rad - (0.5f64).acos()).abs() < 1e-12);
        let down = Immersion::new(MillingMode::Down, 2.5, 10.0);
        assert!((down.entry_rad - (PI - (0.5f64).acos())).abs() < 1e-12);
        assert_eq!(down.exit_rad, PI);
        assert!((up.radial_width_mm(10.0) - 2.5).abs() < 1e-12);
        assert!((down.radial_width_mm(10.0) - 2.5).abs() < 1e-12);
        assert_eq!(Immersion::new(MillingMode::Up, 30.0, 10.0).exit_rad, PI);
        assert_eq!(
            Immersion::new(MillingMode::Up, f64::NAN, 10.0).span_rad(),
            0.0
        );
    }

    #[test]
    fn helical_force_tends_to_the_straight_force_for_a_shallow_cut() {
        let k = Material::Sm45c.coefficients();
        let im = Immersion::new(MillingMode::Slot, 10.0, 10.0);
        let a = 1e-4;
        let straight = model(3, 0.0).forces(&k, &im, a, 0.05, 1.0);
        let helical = model(3, 30.0).forces(&k, &im, a, 0.05, 1.0);
        assert!((straight.fy_n - helical.fy_n).abs() < 1e-3 * straight.fy_n.abs());
        assert!((straight.torque_nm - helical.torque_nm).abs() < 1e-3 * straight.torque_nm);
    }

    #[test]
    fn no_depth_no_feed_or_no_immersion_gives_no_force() {
        let k = Material::Sm45c.coefficients();
        let m = model(2, 30.0);
        let slot = Immersion::new(MillingMode::Slot, 10.0, 10.0);
        assert_eq!(m.forces(&k, &slot, 0.0, 0.1, 1.0), ToolForces::default());
        assert_eq!(m.forces(&k, &slot, 2.0, -0.1, 1.0), ToolForces::default());
        let air = Immersion::new(MillingMode::Up, 0.0, 10.0);
        assert_eq!(m.forces(&k, &air, 2.0, 0.1, 1.0), ToolForces::default());
        assert!(m.forces(&k, &slot, 2.0, f64::NAN, 1.0).fx_n.is_nan());
        assert_eq!(
            m.forces(&k, &slot, f64::INFINITY, 0.1, 1.0),
            ToolForces::default()
        );
    }

    #[test]
    fn without_feed_only_the_edges_rub() {
        let k = Material::Sm45c.coefficients();
        let slot = Immersion::new(MillingMode::Slot, 10.0, 10.0);
        let f = model(1, 0.0).forces(&k, &slot, 2.0, 0.0, std::f64::consts::FRAC_PI_2);
        assert!((f.fy_n - k.kte_n_mm * 2.0).abs() < 1e-12);
        assert!((f.fx_n + k.kre_n_mm * 2.0).abs() < 1e-12);
    }

    #[test]
    fn a_tooth_out_of_the_cut_exerts_nothing() {
        // Up milling with a quarter immersion: φ = 200° is outside [0, 60°].
        let k = Material::Sm45c.coefficients();
        let im = Immersion::new(MillingMode::Up, 2.5, 10.0);
        let f = model(1, 0.0).forces(&k, &im, 2.0, 0.1, 200f64.to_radians());
        assert_eq!(f, ToolForces::default());
    }

    #[test]
    fn deep_helical_cuts_that_wrap_a_full_turn_are_finite_and_positive() {
        let k = Material::Sm45c.coefficients();
        let im = Immersion::new(MillingMode::Slot, 10.0, 10.0);
        // k_β·a = 2·tan 45°/10·40 = 8 rad > 2π.
        let f = model(2, 45.0).forces(&k, &im, 40.0, 0.05, 0.3);
        assert!(f.torque_nm.is_finite() && f.torque_nm > 0.0);
    }
}
