//! Work materials and their mechanistic cutting coefficients.
//!
//! The mechanistic model (Altintas, *Manufacturing Automation*, ch. 2; paper 003 eq 1–2 is its
//! edge-free special case) writes the force on an edge element of height dz cutting a chip of
//! thickness h as
//!
//! ```text
//! dF_t = (K_tc·h + K_te)·dz     tangential
//! dF_r = (K_rc·h + K_re)·dz     radial
//! dF_a = (K_ac·h + K_ae)·dz     axial
//! ```
//!
//! with shearing coefficients K_·c in N/mm² and edge (ploughing) coefficients K_·e in N/mm.
//! Paper 003's specific cutting pressure is K_T = K_tc and its radial ratio is r = K_rc/K_tc.
//!
//! The papers print no coefficients. Each entry's doc says where its numbers come from; where no
//! published identification was at hand the values were *chosen* at the scale of published
//! specific cutting forces and say so. They make the simulated currents look like the papers';
//! they are not a calibration of any paper's machine.

use serde::{Deserialize, Serialize};

use super::{non_negative, positive, PlantError};

/// The six mechanistic cutting coefficients of one tool–material pair.
///
/// ```
/// use cutlab::plant::materials::{CuttingCoefficients, Material};
/// let k = Material::Sm45c.coefficients();
/// assert_eq!(k.ktc_n_mm2, 2200.0);
/// assert!(CuttingCoefficients::new(-1.0, 0.0, 0.0, 0.0, 0.0, 0.0).is_err());
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct CuttingCoefficients {
    /// Tangential shearing coefficient K_tc.
    pub ktc_n_mm2: f64,
    /// Radial shearing coefficient K_rc.
    pub krc_n_mm2: f64,
    /// Axial shearing coefficient K_ac.
    pub kac_n_mm2: f64,
    /// Tangential edge coefficient K_te.
    pub kte_n_mm: f64,
    /// Radial edge coefficient K_re.
    pub kre_n_mm: f64,
    /// Axial edge coefficient K_ae.
    pub kae_n_mm: f64,
}

impl CuttingCoefficients {
    /// Coefficients with K_tc > 0 and the others ≥ 0 (the axial ones may be negative for a
    /// left-hand helix; give them as the magnitude for a right-hand cutter).
    pub fn new(
        ktc_n_mm2: f64,
        krc_n_mm2: f64,
        kac_n_mm2: f64,
        kte_n_mm: f64,
        kre_n_mm: f64,
        kae_n_mm: f64,
    ) -> Result<Self, PlantError> {
        Ok(Self {
            ktc_n_mm2: positive("ktc_n_mm2", ktc_n_mm2)?,
            krc_n_mm2: non_negative("krc_n_mm2", krc_n_mm2)?,
            kac_n_mm2: non_negative("kac_n_mm2", kac_n_mm2)?,
            kte_n_mm: non_negative("kte_n_mm", kte_n_mm)?,
            kre_n_mm: non_negative("kre_n_mm", kre_n_mm)?,
            kae_n_mm: non_negative("kae_n_mm", kae_n_mm)?,
        })
    }

    /// Checks a value built field by field (e.g. deserialised).
    pub fn validate(&self) -> Result<(), PlantError> {
        Self::new(
            self.ktc_n_mm2,
            self.krc_n_mm2,
            self.kac_n_mm2,
            self.kte_n_mm,
            self.kre_n_mm,
            self.kae_n_mm,
        )
        .map(|_| ())
    }

    /// Paper 003's radial-to-tangential force ratio r = K_rc / K_tc (eq 2, edge forces aside).
    ///
    /// ```
    /// use cutlab::plant::materials::Material;
    /// let r = Material::Aluminium.coefficients().radial_ratio();
    /// assert!((r - 168.8 / 796.0).abs() < 1e-12);
    /// ```
    pub fn radial_ratio(&self) -> f64 {
        self.krc_n_mm2 / self.ktc_n_mm2
    }
}

/// A work material of the lab's scenarios.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Material {
    /// SM45C (KS; = JIS S45C, ≈ AISI 1045), normalised, ≈ 200 HB; paper 003's steel, cut with
    /// a carbide end mill.
    ///
    /// Chosen for cutlab at the scale of published specific cutting forces of unalloyed
    /// 0.45 % C steel (Sandvik Coromant's k_c1 ≈ 1600–1700 N/mm² at h = 1 mm with m_c = 0.25,
    /// i.e. ≈ 2500–2900 N/mm² at h = 0.1 mm): K_tc = 2200 N/mm², K_te = 35 N/mm give
    /// 2550 N/mm² at h = 0.1 mm. The ratios K_rc/K_tc = 0.36 and K_ac/K_tc = 0.2 are typical
    /// of carbide end mills with a 30° helix in steel (Altintas, ch. 2).
    Sm45c,
    /// Aluminium alloy 7050-T7451 with a carbide end mill: the coefficients of the worked example
    /// in Altintas, *Manufacturing Automation* (2nd ed., 2012, §2.5), identified by Budak,
    /// Altintas & Armarego (J. Manuf. Sci. Eng. 118, 1996): K_tc = 796, K_rc = 168.8,
    /// K_ac = 222 N/mm²; K_te = 27.7, K_re = 30.8, K_ae = 1.8 N/mm. Paper 003 only says
    /// "aluminum"; 7050 stands for it.
    Aluminium,
    /// GC30 grey cast iron (KS; ≈ JIS FC300, ≈ 220 HB), paper 003's Fig. 7 material.
    ///
    /// Chosen for cutlab: grey iron needs about 0.6 of the specific cutting force of medium-carbon
    /// steel (Sandvik Coromant's k_c1 ≈ 1100 N/mm² for grey iron against ≈ 1650 for C45), so
    /// K_tc = 1300, K_rc = 550, K_ac = 300 N/mm²; K_te = 20, K_re = 30, K_ae = 2 N/mm.
    Gc30,
    /// A hardened tool steel (≈ 50 HRC). Paper 001 cut "SKD41", read here as a JIS SKD die steel
    /// (SKD11/SKD61 family) in the hardened state.
    ///
    /// Chosen for cutlab: hardened steels need about 1.6 times the specific cutting force of
    /// C45, so K_tc = 3600, K_rc = 1500, K_ac = 750 N/mm²; K_te = 45, K_re = 60, K_ae = 5 N/mm.
    ToolSteel,
    /// Paper 003's "composite material" of the material-change test (Fig. 11): a block of SM45C
    /// joined to aluminium, cut SM45C first. It is two materials, not one: a scenario region of
    /// this material becomes an SM45C region and an aluminium region of equal length
    /// ([`Material::layers`]); [`Material::coefficients`] gives the SM45C half.
    Composite,
}

/// The smallest feed per tooth a sharp carbide edge cuts rather than rubs, mm.
const SMALLEST_CHIP_MM: f64 = 0.01;
/// Below this diameter a cutter's feed per tooth scales with its diameter, mm.
const SMALL_CUTTER_MM: f64 = 8.0;

impl Material {
    /// Every material, in listing order.
    pub const ALL: [Material; 5] = [
        Material::Sm45c,
        Material::Aluminium,
        Material::Gc30,
        Material::ToolSteel,
        Material::Composite,
    ];

    /// Short name for the CLI and URLs.
    pub fn name(self) -> &'static str {
        match self {
            Material::Sm45c => "sm45c",
            Material::Aluminium => "aluminium",
            Material::Gc30 => "gc30",
            Material::ToolSteel => "tool-steel",
            Material::Composite => "composite",
        }
    }

    /// Label for forms.
    pub fn label(self) -> &'static str {
        match self {
            Material::Sm45c => "SM45C / AISI 1045 steel",
            Material::Aluminium => "Aluminium (7050-T7451)",
            Material::Gc30 => "Grey cast iron GC30",
            Material::ToolSteel => "Hardened tool steel (≈ 50 HRC)",
            Material::Composite => "Composite: SM45C then aluminium (paper 003)",
        }
    }

    /// Where the coefficients come from, in one line.
    pub fn source(self) -> &'static str {
        match self {
            Material::Sm45c => "chosen at the scale of Sandvik k_c1 for 0.45 % C steel; ratios after Altintas ch. 2",
            Material::Aluminium => "Altintas, Manufacturing Automation, §2.5 (Budak, Altintas & Armarego 1996), Al 7050-T7451",
            Material::Gc30 => "chosen: ≈ 0.6 × medium-carbon steel (Sandvik k_c1 for grey iron)",
            Material::ToolSteel => "chosen: ≈ 1.6 × medium-carbon steel for ≈ 50 HRC",
            Material::Composite => "paper 003 Fig. 11: SM45C joined to aluminium",
        }
    }

    /// The material named `name` (as [`Material::name`], case-insensitive; "aluminum", "al",
    /// "s45c", "aisi1045", "1045" and "fc300" are accepted too).
    ///
    /// ```
    /// use cutlab::plant::materials::Material;
    /// assert_eq!(Material::from_name("Aluminum"), Some(Material::Aluminium));
    /// assert_eq!(Material::from_name("brass"), None);
    /// ```
    pub fn from_name(name: &str) -> Option<Material> {
        let n = name.trim().to_ascii_lowercase();
        let found = match n.as_str() {
            "aluminum" | "al" | "al7050" => Material::Aluminium,
            "s45c" | "aisi1045" | "1045" => Material::Sm45c,
            "fc300" => Material::Gc30,
            "toolsteel" | "tool_steel" | "skd41" => Material::ToolSteel,
            _ => return Material::ALL.into_iter().find(|m| m.name() == n),
        };
        Some(found)
    }

    /// The cutting coefficients (for [`Material::Composite`], those of its SM45C half).
    pub fn coefficients(self) -> CuttingCoefficients {
        let (ktc_n_mm2, krc_n_mm2, kac_n_mm2, kte_n_mm, kre_n_mm, kae_n_mm) = match self {
            Material::Sm45c | Material::Composite => (2200.0, 790.0, 440.0, 35.0, 45.0, 3.0),
            Material::Aluminium => (796.0, 168.8, 222.0, 27.7, 30.8, 1.8),
            Material::Gc30 => (1300.0, 550.0, 300.0, 20.0, 30.0, 2.0),
            Material::ToolSteel => (3600.0, 1500.0, 750.0, 45.0, 60.0, 5.0),
        };
        CuttingCoefficients {
            ktc_n_mm2,
            krc_n_mm2,
            kac_n_mm2,
            kte_n_mm,
            kre_n_mm,
            kae_n_mm,
        }
    }

    /// The feed per tooth a carbide end mill of `diameter_mm` may take in this material, mm:
    /// (smallest, largest).
    ///
    /// The smallest is the chip a sharp carbide edge still cuts rather than rubs: edge radii are
    /// 0.01–0.03 mm and the minimum chip thickness about a third of the edge radius, so 0.01 mm
    /// in every material. The largest is the lab's choice inside the ranges the cutting-data
    /// guides give for solid carbide end mills of 10–20 mm by ISO material group (Sandvik
    /// Coromant, *Metal cutting technology — technical guide*, milling chapter; *Machinery's
    /// Handbook*, 31st ed., "Speeds and feeds for milling"): unalloyed steel (ISO P, ≈ 200 HB)
    /// 0.15 mm, grey cast iron (ISO K) 0.18 mm, aluminium (ISO N) 0.25 mm, hardened steel (ISO H,
    /// ≈ 50 HRC) 0.08 mm. Smaller cutters take proportionally less: below 8 mm both ends scale
    /// with the diameter. A composite spans the windows of both its materials: the window is a
    /// limit of the chip, and which material the tool is in is the program's (a CAM system would
    /// give each region its own); the force the controller holds keeps the harder one's chip
    /// down.
    ///
    /// ```
    /// use cutlab::plant::materials::Material;
    /// assert_eq!(Material::Sm45c.feed_per_tooth_window_mm(20.0), (0.01, 0.15));
    /// assert_eq!(Material::Composite.feed_per_tooth_window_mm(20.0), (0.01, 0.25));
    /// let (lo, hi) = Material::Aluminium.feed_per_tooth_window_mm(4.0);
    /// assert!((lo - 0.005).abs() < 1e-12 && (hi - 0.125).abs() < 1e-12);
    /// ```
    pub fn feed_per_tooth_window_mm(self, diameter_mm: f64) -> (f64, f64) {
        let (min_mm, max_mm) = match self {
            Material::Sm45c => (SMALLEST_CHIP_MM, 0.15),
            Material::Gc30 => (SMALLEST_CHIP_MM, 0.18),
            Material::Aluminium => (SMALLEST_CHIP_MM, 0.25),
            Material::ToolSteel => (SMALLEST_CHIP_MM, 0.08),
            Material::Composite => {
                let (a, b) = Material::Sm45c.feed_per_tooth_window_mm(diameter_mm);
                let (c, d) = Material::Aluminium.feed_per_tooth_window_mm(diameter_mm);
                return (a.min(c), b.max(d));
            }
        };
        let scale = (diameter_mm / SMALL_CUTTER_MM).min(1.0);
        (min_mm * scale, max_mm * scale)
    }

    /// The single materials this one is made of, each with the fraction of a region's length it
    /// fills, in cutting order.
    ///
    /// ```
    /// use cutlab::plant::materials::Material;
    /// assert_eq!(Material::Gc30.layers(), &[(1.0, Material::Gc30)]);
    /// assert_eq!(Material::Composite.layers()[1], (0.5, Material::Aluminium));
    /// ```
    pub fn layers(self) -> &'static [(f64, Material)] {
        match self {
            Material::Sm45c => &[(1.0, Material::Sm45c)],
            Material::Aluminium => &[(1.0, Material::Aluminium)],
            Material::Gc30 => &[(1.0, Material::Gc30)],
            Material::ToolSteel => &[(1.0, Material::ToolSteel)],
            Material::Composite => &[(0.5, Material::Sm45c), (0.5, Material::Aluminium)],
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_material_has_valid_coefficients_and_a_unique_name() {
        for m in Material::ALL {
            m.coefficients().validate().unwrap();
            assert_eq!(Material::from_name(m.name()), Some(m));
            assert!(!m.label().is_empty() && !m.source().is_empty());
            let total: f64 = m.layers().iter().map(|(f, _)| f).sum();
            assert!((total - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn steel_cuts_harder_than_cast_iron_and_aluminium() {
        let k = |m: Material| m.coefficients().ktc_n_mm2;
        assert!(k(Material::ToolSteel) > k(Material::Sm45c));
        assert!(k(Material::Sm45c) > k(Material::Gc30));
        assert!(k(Material::Gc30) > k(Material::Aluminium));
    }

    #[test]
    fn bad_coefficients_name_their_field() {
        let e = CuttingCoefficients::new(1000.0, f64::NAN, 0.0, 0.0, 0.0, 0.0).unwrap_err();
        assert_eq!(e.field, "krc_n_mm2");
    }
}
