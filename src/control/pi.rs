//! PI control of the force with back-calculation anti-windup: the textbook baseline.
//!
//! With the relative error e = (F_target − F) / F_target,
//!
//! ```text
//! u = u₀ + P + I,   P = K_p · 100 · e,   dI/dt = K_i · 100 · e + (u_applied − u_requested) / T_t
//! ```
//!
//! where u is the override in percent. The second term of dI/dt is back-calculation (Åström &
//! Hägglund, *Advanced PID Control*, 2006, §3.5): whenever the safety envelope clamps,
//! rate-limits or quantises the request, the integrator is pulled toward the value that would
//! have produced what was actually applied, with time constant T_t, instead of winding up. The
//! applied override comes from the machine itself ([`ControlInput::applied_override_pct`]), so
//! the same code is correct whatever limits the envelope or the machine impose.

use super::law::{relative_force_error, ControlInput, Controller, LawTerm};

/// Parameters of [`PiController`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PiParams {
    /// Proportional gain: override percentage points per percent of relative force error.
    pub kp: f64,
    /// Integral gain, per second, in the same units as `kp`.
    pub ki_per_s: f64,
    /// Back-calculation (tracking) time constant; 0 < T_t, stable at any control period (the
    /// tracking is discretised exactly). Åström & Hägglund suggest
    /// T_t ≈ √(T_i·T_d); without D, about T_i = K_p/K_i or less.
    pub tracking_time_s: f64,
    /// The override the integrator starts from.
    pub initial_override_pct: f64,
}

/// PI force controller with anti-windup.
///
/// ```
/// use cutlab::control::pi::{PiController, PiParams};
/// use cutlab::control::law::{Controller, ControlInput};
/// let mut c = PiController::new(PiParams { kp: 0.5, ki_per_s: 1.0, tracking_time_s: 0.5,
///     initial_override_pct: 100.0 });
/// let input = ControlInput { time_s: 0.0, dt_s: 0.1, force_n: 330.0, target_force_n: 300.0,
///     programmed_feed_mm_min: 200.0, applied_override_pct: 100.0, time_since_start_s: 5.0 };
/// // e = −0.1: P = −5 %, I = 1.0 · 100 · (−0.1) · 0.1 s = −1 %.
/// assert!((c.step(&input) - 94.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone)]
pub struct PiController {
    params: PiParams,
    integral_pct: f64,
    last_request_pct: Option<f64>,
    terms: [LawTerm; 3],
}

impl PiController {
    /// The controller; the registry's constructor checks the parameters' ranges.
    pub fn new(params: PiParams) -> Self {
        Self {
            params,
            integral_pct: 0.0,
            last_request_pct: None,
            terms: [
                LawTerm::new("P", "%"),
                LawTerm::new("I", "%"),
                LawTerm::new("windup correction", "%"),
            ],
        }
    }
}

impl Controller for PiController {
    /// A non-finite force freezes the integrator and repeats the applied override.
    fn step(&mut self, input: &ControlInput) -> f64 {
        let error = relative_force_error(input);
        if !error.is_finite() {
            return input.applied_override_pct;
        }
        let p = self.params;
        // What the envelope and machine took away from the previous request.
        let windup_pct = match self.last_request_pct {
            Some(requested) if input.applied_override_pct.is_finite() => {
                input.applied_override_pct - requested
            }
            _ => 0.0,
        };
        // Back-calculation, discretised exactly: over one period the integrator moves the fraction
        // 1 − exp(−dt/T_t) of the way to what the machine applied. An explicit Euler step
        // (dt/T_t) overshoots once the period exceeds T_t and diverges: T_t = 1 ms at a 40 ms
        // period ran the integral to −inf on kim-step-doc.
        let tracking = 1.0 - crate::math::exp(-input.dt_s / p.tracking_time_s);
        self.integral_pct += input.dt_s * p.ki_per_s * 100.0 * error + tracking * windup_pct;
        let proportional_pct = p.kp * 100.0 * error;
        let request = p.initial_override_pct + proportional_pct + self.integral_pct;
        self.last_request_pct = Some(request);
        self.terms[0].value = proportional_pct;
        self.terms[1].value = self.integral_pct;
        self.terms[2].value = windup_pct;
        request
    }

    fn terms(&self) -> &[LawTerm] {
        &self.terms
    }

    /// Bumpless: the integrator holds the applied override's difference from the initial one, so
    /// the first request is the applied override plus the proportional term.
    fn take_over(&mut self, applied_override_pct: f64) {
        self.reset();
        if applied_override_pct.is_finite() {
            self.integral_pct = applied_override_pct - self.params.initial_override_pct;
        }
    }

    fn reset(&mut self) {
        self.integral_pct = 0.0;
        self.last_request_pct = None;
        for t in &mut self.terms {
            t.value = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_tracking_time_far_below_the_period_stays_finite_and_tracks_the_clamp() {
        // T_t = 1 ms at 40 ms periods, the envelope holding the override at 150 % while the
        // force stays low: the Euler step multiplied the windup by 40 each period.
        let mut c = PiController::new(PiParams {
            kp: 0.3,
            ki_per_s: 1.0,
            tracking_time_s: 0.001,
            initial_override_pct: 100.0,
        });
        let mut applied = 100.0;
        for i in 0..2000 {
            let request = c.step(&ControlInput {
                time_s: 0.04 * f64::from(i),
                dt_s: 0.04,
                force_n: 100.0,
                target_force_n: 300.0,
                programmed_feed_mm_min: 200.0,
                applied_override_pct: applied,
                time_since_start_s: 10.0,
            });
            assert!(request.is_finite(), "period {i}: {request}");
            applied = request.clamp(10.0, 150.0);
        }
        // Pinned at the ceiling, the integrator sits near it instead of winding up.
        assert!(c.integral_pct.abs() < 200.0, "{}", c.integral_pct);
    }

    #[test]
    fn the_tracking_is_stable_for_every_tracking_time_in_range_at_every_period() {
        // The registry's range of T_t is 0.001–100 s; control periods from 0.1 ms to 1 s. Any
        // T_t below half the period made the Euler step's factor 1 − dt/T_t exceed 1 in size.
        let mut rng = crate::rng::Rng::seed_from(9);
        for tracking_time_s in [0.001, 0.003, 0.01, 0.1, 1.0, 10.0, 100.0] {
            for dt_s in [1e-4, 0.01, 0.04, 0.2, 1.0] {
                let mut c = PiController::new(PiParams {
                    kp: 10.0 * rng.uniform(),
                    ki_per_s: 100.0 * rng.uniform(),
                    tracking_time_s,
                    initial_override_pct: 100.0,
                });
                let (mut applied, mut load) = (100.0, 1.0);
                for i in 0..2000 {
                    if i % 50 == 0 {
                        load = 0.2 + 3.0 * rng.uniform();
                    }
                    let request = c.step(&ControlInput {
                        time_s: dt_s * f64::from(i),
                        dt_s,
                        force_n: 3.0 * load * applied,
                        target_force_n: 300.0,
                        programmed_feed_mm_min: 200.0,
                        applied_override_pct: applied,
                        time_since_start_s: 10.0,
                    });
                    assert!(
                        request.is_finite() && request.abs() < 1e9,
                        "T_t {tracking_time_s} s, dt {dt_s} s, period {i}: {request}"
                    );
                    applied = request.clamp(10.0, 150.0);
                }
            }
        }
    }

    fn input(force_n: f64, applied: f64) -> ControlInput {
        ControlInput {
            time_s: 0.0,
            dt_s: 0.1,
            force_n,
            target_force_n: 100.0,
            programmed_feed_mm_min: 100.0,
            applied_override_pct: applied,
            time_since_start_s: 10.0,
        }
    }

    fn params() -> PiParams {
        PiParams {
            kp: 0.5,
            ki_per_s: 1.0,
            tracking_time_s: 0.5,
            initial_override_pct: 100.0,
        }
    }

    #[test]
    fn integral_accumulates_a_constant_error() {
        let mut c = PiController::new(params());
        let mut applied = 100.0;
        let mut last = 0.0;
        for _ in 0..10 {
            last = c.step(&input(90.0, applied));
            applied = last;
        }
        // e = 0.1 each step: P = 5, I = 10 · 0.1 s · 100 · 0.1 = 10.
        assert!((last - 115.0).abs() < 1e-9, "{last}");
    }

    #[test]
    fn back_calculation_stops_windup_at_a_clamp() {
        let mut with_clamp = PiController::new(params());
        // The envelope caps the override at 120 % while the force stays far below target.
        let mut applied = 100.0;
        for _ in 0..200 {
            let request = with_clamp.step(&input(50.0, applied));
            applied = request.min(120.0);
        }
        // Without anti-windup the integral would be 200 · 0.1 · 50 = 1000 %; back-calculation
        // settles where dt·K_i·100·e = (1 − exp(−dt/T_t))·(request − 120): with dt·K_i·100·e =
        // 5 % and T_t = 0.5 s, request = 120 + 5/(1 − e^−0.2) ≈ 147.6 % (the Euler step's
        // equilibrium, 120 + 25 = 145 %, is its first-order approximation).
        let request = with_clamp.step(&input(50.0, applied));
        let expected = 120.0 + 5.0 / (1.0 - (-0.2f64).exp());
        assert!(
            (request - expected).abs() < 1e-6,
            "request {request} vs {expected}"
        );
        // Once the force overshoots, the request leaves the clamp within a few periods.
        let mut periods = 0;
        while with_clamp.step(&input(150.0, applied)) >= 120.0 {
            periods += 1;
            assert!(periods < 10, "still wound up after {periods} periods");
        }
    }

    #[test]
    fn non_finite_force_holds_and_leaves_state_untouched() {
        let mut c = PiController::new(params());
        c.step(&input(90.0, 100.0));
        let before = c.integral_pct;
        assert_eq!(c.step(&input(f64::NAN, 103.0)), 103.0);
        assert_eq!(c.integral_pct, before);
    }

    #[test]
    fn reset_restores_the_start() {
        let mut c = PiController::new(params());
        let first = c.step(&input(80.0, 100.0));
        c.step(&input(80.0, first));
        c.reset();
        assert_eq!(c.step(&input(80.0, 100.0)), first);
    }
}
