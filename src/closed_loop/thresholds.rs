//! The loop's force thresholds, derived from the target and the calibration: below the air-cut
//! force the safety envelope takes the tool for in air ([`air_cut_force_n`], capped by
//! [`MAX_AIR_CUT_FRACTION`] of the target and [`MAX_AIR_CUT_OF_CUT_FRACTION`] of the teach cut's
//! force), and above the cut-before-arming force a period before the loop arms is a cut the
//! controller cannot shape ([`cut_before_arming_force_n`]). [`super::settings::Plan::settle`]
//! computes both once per run.

use crate::safety::AIR_CUT_FRACTION;

/// Above the air estimate by this factor, an estimated force is a cut.
pub const AIR_MARGIN: f64 = 1.5;
/// The air-cut threshold never rises above this fraction of the target: a model that reads a
/// large force in air still leaves the controller the light cuts (paper 003's 1 mm entry cuts at
/// 40 % of the target at 100 %).
pub const MAX_AIR_CUT_FRACTION: f64 = 0.35;
/// Nor above this fraction of the force the teach cut cut at full override: a target far above
/// what the program's cut gives (5000 N on kim-step-doc's 300–700 N) would otherwise put every
/// cut under the threshold, and the envelope would hold the programmed feed all run as if the
/// tool never left the air, the controller silently off.
pub const MAX_AIR_CUT_OF_CUT_FRACTION: f64 = 0.5;

/// The estimated force below which the safety envelope takes the tool for in air: a fifth of
/// the target, raised to half again the force the calibrated model read in the teach cut's air
/// (its bias there), but never above [`MAX_AIR_CUT_FRACTION`] of the target, nor above
/// [`MAX_AIR_CUT_OF_CUT_FRACTION`] of the teach cut's median force at full override (NaN: not
/// known, no such bound).
///
/// ```
/// use cutlab::closed_loop::thresholds::air_cut_force_n;
/// assert_eq!(air_cut_force_n(320.0, f64::NAN, 465.0), 64.0);   // no air seen: 20 %
/// assert_eq!(air_cut_force_n(320.0, 68.0, 465.0), 102.0);      // 1.5 × the air reading
/// assert_eq!(air_cut_force_n(320.0, 300.0, f64::NAN), 112.0);  // at most 35 %
/// assert_eq!(air_cut_force_n(5000.0, 20.0, 465.0), 232.5);     // at most half the cut's force
/// ```
pub fn air_cut_force_n(
    target_force_n: f64,
    air_force_estimate_n: f64,
    median_force_at_full_override_n: f64,
) -> f64 {
    let base = AIR_CUT_FRACTION * target_force_n;
    let biased = AIR_MARGIN * air_force_estimate_n;
    let threshold = if biased > base { biased } else { base };
    threshold
        .min(MAX_AIR_CUT_FRACTION * target_force_n)
        .min(MAX_AIR_CUT_OF_CUT_FRACTION * median_force_at_full_override_n)
}

/// An estimate above this fraction of the target, before the loop arms, is a cut heavy enough to
/// warn about: a lighter one the controller takes over once armed without having loaded the tool.
pub const CUT_BEFORE_ARMING_FRACTION: f64 = 0.5;
/// An estimate this many standard deviations of the fit's residual above nothing is a cut, not
/// the estimate's noise.
pub const CUT_NOISE_SIGMAS: f64 = 3.0;

/// The estimated force above which a period before the loop arms shows a cut the controller
/// cannot shape (the cut-before-arming warning): above half the target (a lighter cut harms
/// nothing), and above what the estimate reads without any cut, whatever the target — half again
/// the largest force the teach cut's air read ([`AIR_MARGIN`]) and [`CUT_NOISE_SIGMAS`] times one
/// period's spread about the calibration line. A NaN (not known: no air in the teach cut, a
/// current read as the force) leaves its bound out.
///
/// ```
/// use cutlab::closed_loop::thresholds::cut_before_arming_force_n;
/// assert_eq!(cut_before_arming_force_n(372.0, 40.0, 10.0), 186.0); // half the target
/// assert_eq!(cut_before_arming_force_n(5.0, 40.0, 10.0), 60.0);    // 1.5 × the air reading
/// assert_eq!(cut_before_arming_force_n(5.0, -50.0, 15.0), 45.0);   // 3 σ of the estimate
/// assert_eq!(cut_before_arming_force_n(5.0, f64::NAN, f64::NAN), 2.5);
/// ```
pub fn cut_before_arming_force_n(
    target_force_n: f64,
    air_force_estimate_n: f64,
    residual_std_n: f64,
) -> f64 {
    // `f64::max` leaves a NaN out.
    (CUT_BEFORE_ARMING_FRACTION * target_force_n)
        .max(AIR_MARGIN * air_force_estimate_n)
        .max(CUT_NOISE_SIGMAS * residual_std_n)
}
