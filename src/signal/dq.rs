//! Clarke and Park transforms and the PMSM torque of paper 000 (eq 4–8).
//!
//! ## Conventions (decided here, since paper 000 mixes two)
//!
//! - Phases `a, b, c` in positive sequence: for a current vector at electrical angle `φ`,
//!   `i_a = I·cos φ`, `i_b = I·cos(φ − 2π/3)`, `i_c = I·cos(φ + 2π/3)`.
//! - Clarke: `α` along phase a, `β` 90° ahead. Park: `d` along the rotor flux at electrical angle
//!   `θ`, `q` 90° ahead of `d`:
//!   `d = α·cos θ + β·sin θ`, `q = −α·sin θ + β·cos θ`.
//! - Two scalings, both named ([`Scaling`]): **amplitude-invariant** (factor 2/3; a balanced
//!   current of amplitude `I` has `|dq| = I`) and **power-invariant** (factor √(2/3); the
//!   transform is orthonormal, `p = v_d·i_d + v_q·i_q` with no 3/2).
//!
//! Paper 000 writes its phases as `i_u = I cos θ`, `i_v = I cos(θ + 2π/3)`,
//! `i_w = I cos(θ − 2π/3)` (eq 4), so its `v` and `w` are this module's `c` and `b`; its eq 6 is
//! the **power-invariant** transform (√(2/3)) with the sign of `q` reversed (its second row is
//! `+sin`). Its torque, eq 7, `T = 3/2·p·(λ_m·i_q + (L_d − L_q)·i_d·i_q)`, holds for
//! **amplitude-invariant** currents; with eq 6's power-invariant currents it would be 3/2 too
//! large. [`PmsmParams::torque_nm`] therefore takes the scaling of the currents it is given and
//! returns the same physical torque for either. Eq 8 (`i_d = 0`) is
//! [`PmsmParams::torque_id_zero_nm`].
//!
//! Angles go through [`crate::math`], so results have the same bits natively and in wasm. NaN or
//! ±∞ in an input current or angle gives NaN in the outputs that depend on it.

use std::fmt;

use crate::math;

/// How the three-phase to two-axis transforms are scaled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Scaling {
    /// Factor 2/3: a balanced current of amplitude `I` gives `|α + iβ| = |d + iq| = I`.
    AmplitudeInvariant,
    /// Factor √(2/3): orthonormal, so power is `v_d·i_d + v_q·i_q`; a balanced amplitude `I`
    /// gives `√(3/2)·I` (paper 000 eq 6).
    PowerInvariant,
}

impl Scaling {
    /// Both scalings.
    pub const ALL: [Scaling; 2] = [Scaling::AmplitudeInvariant, Scaling::PowerInvariant];

    /// A label for people.
    ///
    /// ```
    /// use cutlab::signal::dq::Scaling;
    /// assert_eq!(Scaling::PowerInvariant.label(), "Power-invariant (√(2/3))");
    /// ```
    pub fn label(self) -> &'static str {
        match self {
            Self::AmplitudeInvariant => "Amplitude-invariant (2/3)",
            Self::PowerInvariant => "Power-invariant (√(2/3))",
        }
    }

    /// The machine name.
    ///
    /// ```
    /// use cutlab::signal::dq::Scaling;
    /// assert_eq!(Scaling::ALL.map(|s| s.name()), ["amplitude-invariant", "power-invariant"]);
    /// ```
    pub fn name(self) -> &'static str {
        match self {
            Self::AmplitudeInvariant => "amplitude-invariant",
            Self::PowerInvariant => "power-invariant",
        }
    }

    /// The factor that multiplies `a − (b + c)/2` in α.
    fn factor(self) -> f64 {
        match self {
            Self::AmplitudeInvariant => 2.0 / 3.0,
            Self::PowerInvariant => (2.0f64 / 3.0).sqrt(),
        }
    }

    /// Multiply a current in this scaling by this to get it amplitude-invariant.
    fn to_amplitude_invariant(self) -> f64 {
        match self {
            Self::AmplitudeInvariant => 1.0,
            Self::PowerInvariant => (2.0f64 / 3.0).sqrt(),
        }
    }
}

/// Stationary two-axis components (α along phase a, β 90° ahead), in the unit of the inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlphaBeta {
    /// Along phase a.
    pub alpha: f64,
    /// 90° ahead of phase a.
    pub beta: f64,
}

/// Rotor-frame components (d along the rotor flux, q 90° ahead), in the unit of the inputs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dq {
    /// Direct axis, along the rotor flux.
    pub d: f64,
    /// Quadrature axis, 90° ahead of d: the torque-producing current.
    pub q: f64,
}

/// Clarke transform of three phase values.
///
/// The zero-sequence part `(a + b + c)/3` is dropped (a star-connected motor has none, paper 000
/// eq 5).
///
/// ```
/// use cutlab::signal::dq::{clarke, Scaling};
/// use std::f64::consts::PI;
/// let (i, phi): (f64, f64) = (10.0, 0.4);
/// let ab = clarke(
///     i * phi.cos(),
///     i * (phi - 2.0 * PI / 3.0).cos(),
///     i * (phi + 2.0 * PI / 3.0).cos(),
///     Scaling::AmplitudeInvariant,
/// );
/// assert!((ab.alpha - i * phi.cos()).abs() < 1e-12);
/// assert!((ab.beta - i * phi.sin()).abs() < 1e-12);
/// ```
pub fn clarke(a: f64, b: f64, c: f64, scaling: Scaling) -> AlphaBeta {
    let k = scaling.factor();
    AlphaBeta {
        alpha: k * (a - 0.5 * (b + c)),
        beta: k * (3.0f64.sqrt() / 2.0) * (b - c),
    }
}

/// Inverse Clarke transform (zero-sequence 0): phase values `[a, b, c]`.
///
/// ```
/// use cutlab::signal::dq::{clarke, inverse_clarke, Scaling};
/// for scaling in Scaling::ALL {
///     let abc = inverse_clarke(clarke(3.0, -1.0, -2.0, scaling), scaling);
///     assert!((abc[0] - 3.0).abs() < 1e-12 && (abc[2] + 2.0).abs() < 1e-12);
/// }
/// ```
pub fn inverse_clarke(ab: AlphaBeta, scaling: Scaling) -> [f64; 3] {
    // Amplitude-invariant inverse: a = α, b = −α/2 + (√3/2)β, c = −α/2 − (√3/2)β; the
    // power-invariant one is that scaled by √(2/3).
    let k = match scaling {
        Scaling::AmplitudeInvariant => 1.0,
        Scaling::PowerInvariant => (2.0f64 / 3.0).sqrt(),
    };
    let half_sqrt3 = 3.0f64.sqrt() / 2.0;
    [
        k * ab.alpha,
        k * (-0.5 * ab.alpha + half_sqrt3 * ab.beta),
        k * (-0.5 * ab.alpha - half_sqrt3 * ab.beta),
    ]
}

/// Park transform: α-β to the rotor frame at electrical angle `theta_rad`.
///
/// ```
/// use cutlab::signal::dq::{park, AlphaBeta};
/// // A vector along β seen from a rotor at 90°: all d.
/// let dq = park(AlphaBeta { alpha: 0.0, beta: 2.0 }, std::f64::consts::FRAC_PI_2);
/// assert!((dq.d - 2.0).abs() < 1e-15 && dq.q.abs() < 1e-15);
/// ```
pub fn park(ab: AlphaBeta, theta_rad: f64) -> Dq {
    let (sin, cos) = (math::sin(theta_rad), math::cos(theta_rad));
    Dq {
        d: ab.alpha * cos + ab.beta * sin,
        q: -ab.alpha * sin + ab.beta * cos,
    }
}

/// Inverse Park transform: the rotor frame back to α-β.
///
/// ```
/// use cutlab::signal::dq::{inverse_park, park, Dq};
/// let back = park(inverse_park(Dq { d: 1.0, q: -3.0 }, 0.7), 0.7);
/// assert!((back.d - 1.0).abs() < 1e-15 && (back.q + 3.0).abs() < 1e-15);
/// ```
pub fn inverse_park(dq: Dq, theta_rad: f64) -> AlphaBeta {
    let (sin, cos) = (math::sin(theta_rad), math::cos(theta_rad));
    AlphaBeta {
        alpha: dq.d * cos - dq.q * sin,
        beta: dq.d * sin + dq.q * cos,
    }
}

/// Three phase currents straight to the rotor frame: Clarke, then Park at `theta_rad`.
///
/// ```
/// use cutlab::signal::dq::{abc_to_dq, Scaling};
/// use std::f64::consts::PI;
/// // Current of amplitude 5 A leading the rotor's d axis by 90°: pure q (all torque).
/// let theta = 1.1;
/// let phi = theta + PI / 2.0;
/// let dq = abc_to_dq(
///     5.0 * phi.cos(),
///     5.0 * (phi - 2.0 * PI / 3.0).cos(),
///     5.0 * (phi + 2.0 * PI / 3.0).cos(),
///     theta,
///     Scaling::AmplitudeInvariant,
/// );
/// assert!(dq.d.abs() < 1e-12 && (dq.q - 5.0).abs() < 1e-12);
/// ```
pub fn abc_to_dq(a: f64, b: f64, c: f64, theta_rad: f64, scaling: Scaling) -> Dq {
    park(clarke(a, b, c, scaling), theta_rad)
}

/// A motor parameter that cannot be used.
#[derive(Debug, Clone, PartialEq)]
pub struct PmsmParamError {
    /// Which parameter.
    pub name: &'static str,
    /// The value given.
    pub value: f64,
}

impl fmt::Display for PmsmParamError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} must be a finite number ≥ 0 (pole pairs ≥ 1), got {}",
            self.name, self.value
        )
    }
}

impl std::error::Error for PmsmParamError {}

/// A permanent-magnet synchronous motor's torque-relevant parameters (paper 000 eq 7).
///
/// ```
/// use cutlab::signal::dq::{Dq, PmsmParams, Scaling};
/// let motor = PmsmParams::new(4, 0.1, 0.002, 0.003).unwrap();
/// // Eq 8: i_d = 0 gives T = 3/2 · p · λ_m · i_q = 1.5 · 4 · 0.1 · 10 = 6 N·m.
/// assert!((motor.torque_id_zero_nm(10.0) - 6.0).abs() < 1e-12);
/// // The same physical current in either scaling gives the same torque.
/// let k = 1.5f64.sqrt();
/// let amplitude = motor.torque_nm(Dq { d: -2.0, q: 10.0 }, Scaling::AmplitudeInvariant);
/// let power = motor.torque_nm(Dq { d: -2.0 * k, q: 10.0 * k }, Scaling::PowerInvariant);
/// assert!((amplitude - power).abs() < 1e-12);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PmsmParams {
    pole_pairs: u32,
    flux_linkage_wb: f64,
    d_inductance_h: f64,
    q_inductance_h: f64,
}

impl PmsmParams {
    /// Pole pairs `p` (paper 000's "pole of the motor"), the peak rotor flux linkage `λ_m` in
    /// webers, and the d- and q-axis inductances in henries.
    pub fn new(
        pole_pairs: u32,
        flux_linkage_wb: f64,
        d_inductance_h: f64,
        q_inductance_h: f64,
    ) -> Result<Self, PmsmParamError> {
        if pole_pairs == 0 {
            return Err(PmsmParamError {
                name: "pole pairs",
                value: 0.0,
            });
        }
        for (name, value) in [
            ("flux linkage (Wb)", flux_linkage_wb),
            ("d-axis inductance (H)", d_inductance_h),
            ("q-axis inductance (H)", q_inductance_h),
        ] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(PmsmParamError { name, value });
            }
        }
        Ok(Self {
            pole_pairs,
            flux_linkage_wb,
            d_inductance_h,
            q_inductance_h,
        })
    }

    /// Electromagnetic torque, N·m, from d-q currents in amperes in the given `scaling`
    /// (paper 000 eq 7 for amplitude-invariant currents):
    /// `T = 3/2 · p · (λ_m·i_q + (L_d − L_q)·i_d·i_q)`.
    pub fn torque_nm(&self, current_a: Dq, scaling: Scaling) -> f64 {
        let k = scaling.to_amplitude_invariant();
        let (i_d, i_q) = (k * current_a.d, k * current_a.q);
        1.5 * f64::from(self.pole_pairs)
            * (self.flux_linkage_wb * i_q + (self.d_inductance_h - self.q_inductance_h) * i_d * i_q)
    }

    /// Paper 000 eq 8: the torque with `i_d = 0` (maximum torque per ampere for a surface
    /// magnet motor), `T = 3/2 · p · λ_m · i_q`, for an amplitude-invariant `i_q` in amperes.
    pub fn torque_id_zero_nm(&self, i_q_a: f64) -> f64 {
        1.5 * f64::from(self.pole_pairs) * self.flux_linkage_wb * i_q_a
    }

    /// Torque per ampere of amplitude-invariant `i_q` at `i_d = 0`: `3/2 · p · λ_m`, N·m/A.
    pub fn torque_constant_nm_per_a(&self) -> f64 {
        1.5 * f64::from(self.pole_pairs) * self.flux_linkage_wb
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    fn balanced(amplitude: f64, phi: f64) -> [f64; 3] {
        [
            amplitude * phi.cos(),
            amplitude * (phi - 2.0 * PI / 3.0).cos(),
            amplitude * (phi + 2.0 * PI / 3.0).cos(),
        ]
    }

    #[test]
    fn scalings_give_the_documented_magnitudes() {
        let [a, b, c] = balanced(7.0, 0.9);
        let amp = clarke(a, b, c, Scaling::AmplitudeInvariant);
        let pow = clarke(a, b, c, Scaling::PowerInvariant);
        assert!((amp.alpha.hypot(amp.beta) - 7.0).abs() < 1e-12);
        assert!((pow.alpha.hypot(pow.beta) - 7.0 * 1.5f64.sqrt()).abs() < 1e-12);
    }

    #[test]
    fn power_invariant_transform_preserves_power() {
        let i = [3.0, -1.0, -2.0];
        let v = [100.0, -30.0, -70.0];
        let theta = 0.77;
        let di = abc_to_dq(i[0], i[1], i[2], theta, Scaling::PowerInvariant);
        let dv = abc_to_dq(v[0], v[1], v[2], theta, Scaling::PowerInvariant);
        let p_abc: f64 = i.iter().zip(&v).map(|(a, b)| a * b).sum();
        assert!((di.d * dv.d + di.q * dv.q - p_abc).abs() < 1e-9);
    }

    #[test]
    fn paper_000_eq_6_is_power_invariant_with_v_w_swapped_and_q_negated() {
        // Eq 6 written out literally, phases u, v, w as in eq 4.
        let theta: f64 = 0.6;
        let (u, v, w) = (4.0, -1.5, -2.5);
        let k = (2.0f64 / 3.0).sqrt();
        let d_paper = k
            * (theta.cos() * u
                + (theta + 2.0 * PI / 3.0).cos() * v
                + (theta - 2.0 * PI / 3.0).cos() * w);
        let q_paper = k
            * (theta.sin() * u
                + (theta + 2.0 * PI / 3.0).sin() * v
                + (theta - 2.0 * PI / 3.0).sin() * w);
        let ours = abc_to_dq(u, w, v, theta, Scaling::PowerInvariant);
        assert!((ours.d - d_paper).abs() < 1e-12);
        assert!((ours.q + q_paper).abs() < 1e-12);
    }

    #[test]
    fn bad_motor_parameters_are_errors() {
        assert!(PmsmParams::new(0, 0.1, 0.0, 0.0).is_err());
        let e = PmsmParams::new(2, f64::NAN, 0.0, 0.0).unwrap_err();
        assert!(e.to_string().starts_with("flux linkage (Wb)"));
    }
}
