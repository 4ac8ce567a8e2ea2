//! Lyapunov model-reference adaptive force control (paper 001, §3).
//!
//! Paper 001 models the force process as m·F̈ + α·Ḟ + β·F = k·f_r with α = mc + d and β = dc
//! (eq 2.3/4), and controls it with
//!
//! ```text
//! f_r = m̂·F̈_d + α̂·Ḟ_d + β̂·F_d − K_d·E,    F̃ = F − F_d,    E = dF̃/dt + λ·F̃        (eq 5)
//! ```
//!
//! where the hats are adaptive estimates (absorbing the unknown gain k). The printed adaptation
//! laws are garbled (every law shows the regressor Ḟ_d; see shared/seeds/README.md). Substituting
//! eq 5 into eq 4 gives the error dynamics of eq 7, m·F̃̈ + α·F̃̇ + β·F̃ = m̃·F̈_d + α̃·Ḟ_d +
//! β̃·F_d − K_d·E, whose parameter errors multiply F̈_d, Ḟ_d and F_d respectively; the Lyapunov
//! function of eq 9 then yields the gradient laws
//!
//! ```text
//! dm̂/dt = −γ₁·F̈_d·E,   dα̂/dt = −γ₂·Ḟ_d·E,   dβ̂/dt = −γ₃·F_d·E
//! ```
//!
//! which is what cutlab implements: only the regressors differ from the printed text. With a
//! constant target (every preset), F̈_d = Ḟ_d = 0: m̂ and α̂ stay put, β̂ acts as an adaptive
//! feed-forward gain, and −K_d·E is a PD action on the force error.
//!
//! Units. The control signal f_r is the feed; cutlab expresses it as the override in percent, and
//! forces relative to the target at the start of the run (φ = F / F_ref), so that
//! β̂ is "the override that would give the target force" in percent (it starts at 100 %), K_d is
//! in %·s, λ in 1/s and the γ in %/s. Each estimate is kept inside a bound by projection (the
//! integration simply stops at the bound), so a long stretch without cutting cannot drive it away.
//! The force derivative comes from a first-order filtered differentiator with time constant
//! `derivative_time_s`, because a raw difference of a noisy current estimate is mostly noise.

use super::law::{ControlInput, Controller, LawTerm};

/// Parameters of [`ModelReferenceAdaptive`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MracParams {
    /// Sliding-surface slope λ.
    pub lambda_per_s: f64,
    /// Gain K_d on the sliding variable E, in override-percent·s per unit of relative force.
    pub kd_pct_s: f64,
    /// Adaptation gain γ₃ of β̂.
    pub gamma_beta_pct_per_s: f64,
    /// Adaptation gains γ₁, γ₂ of m̂ and α̂ (active only while the target changes).
    pub gamma_dynamics_pct_per_s: f64,
    /// Initial β̂: the override expected to give the target force.
    pub initial_beta_pct: f64,
    /// Lower bound of β̂.
    pub min_beta_pct: f64,
    /// Upper bound of β̂.
    pub max_beta_pct: f64,
    /// Time constant of the filtered differentiator.
    pub derivative_time_s: f64,
}

/// A first-order filtered differentiator: the derivative of the input seen through a low-pass of
/// time constant τ, i.e. s / (τs + 1).
#[derive(Debug, Clone, Copy)]
struct FilteredDerivative {
    time_constant_s: f64,
    state: Option<f64>,
}

impl FilteredDerivative {
    fn step(&mut self, x: f64, dt_s: f64) -> f64 {
        let lagged = self.state.get_or_insert(x);
        // Exact discretisation of the low-pass for a held input: no instability for dt > τ.
        let alpha = 1.0 - crate::math::exp(-dt_s / self.time_constant_s);
        *lagged += alpha * (x - *lagged);
        (x - *lagged) / self.time_constant_s
    }
}

/// Paper 001's adaptive controller.
///
/// ```
/// use cutlab::control::mrac::{ModelReferenceAdaptive, MracParams};
/// use cutlab::control::law::{Controller, ControlInput};
/// let mut c = ModelReferenceAdaptive::new(MracParams { lambda_per_s: 2.0, kd_pct_s: 20.0,
///     gamma_beta_pct_per_s: 50.0, gamma_dynamics_pct_per_s: 0.0, initial_beta_pct: 100.0,
///     min_beta_pct: 5.0, max_beta_pct: 255.0, derivative_time_s: 0.2 });
/// let input = ControlInput { time_s: 0.0, dt_s: 0.1, force_n: 300.0, target_force_n: 300.0,
///     programmed_feed_mm_min: 200.0, applied_override_pct: 100.0, time_since_start_s: 5.0 };
/// // On target with no error the request is β̂ = 100 %.
/// assert!((c.step(&input) - 100.0).abs() < 1e-12);
/// ```
#[derive(Debug, Clone)]
pub struct ModelReferenceAdaptive {
    params: MracParams,
    reference_force_n: Option<f64>,
    force_rate: FilteredDerivative,
    target_rate: FilteredDerivative,
    target_acceleration: FilteredDerivative,
    m_hat: f64,
    alpha_hat: f64,
    beta_hat: f64,
    terms: [LawTerm; 4],
}

/// Bound on |m̂| and |α̂|: with a constant target they never move, and while the target ramps they
/// must not grow beyond a plausible share of the override.
const DYNAMICS_ESTIMATE_BOUND_PCT: f64 = 100.0;

impl ModelReferenceAdaptive {
    /// The controller; the registry's constructor checks the parameters' ranges.
    pub fn new(params: MracParams) -> Self {
        let differentiator = FilteredDerivative {
            time_constant_s: params.derivative_time_s,
            state: None,
        };
        Self {
            params,
            reference_force_n: None,
            force_rate: differentiator,
            target_rate: differentiator,
            target_acceleration: differentiator,
            m_hat: 0.0,
            alpha_hat: 0.0,
            beta_hat: params.initial_beta_pct,
            terms: [
                LawTerm::new("β̂", "%"),
                LawTerm::new("α̂", "%·s"),
                LawTerm::new("E", "1/s"),
                LawTerm::new("−K_d·E", "%"),
            ],
        }
    }
}

impl Controller for ModelReferenceAdaptive {
    /// A non-finite force leaves every state untouched and repeats the applied override.
    fn step(&mut self, input: &ControlInput) -> f64 {
        if !(input.force_n.is_finite() && input.target_force_n.is_finite()) {
            return input.applied_override_pct;
        }
        let p = self.params;
        let reference = *self.reference_force_n.get_or_insert(input.target_force_n);
        let phi = input.force_n / reference;
        let phi_d = input.target_force_n / reference;
        let dt = input.dt_s;

        let phi_rate = self.force_rate.step(phi, dt);
        let phi_d_rate = self.target_rate.step(phi_d, dt);
        let phi_d_acceleration = self.target_acceleration.step(phi_d_rate, dt);
        let error = phi - phi_d;
        let sliding = (phi_rate - phi_d_rate) + p.lambda_per_s * error;

        let gamma_dyn = p.gamma_dynamics_pct_per_s;
        self.m_hat = (self.m_hat - dt * gamma_dyn * phi_d_acceleration * sliding)
            .clamp(-DYNAMICS_ESTIMATE_BOUND_PCT, DYNAMICS_ESTIMATE_BOUND_PCT);
        self.alpha_hat = (self.alpha_hat - dt * gamma_dyn * phi_d_rate * sliding)
            .clamp(-DYNAMICS_ESTIMATE_BOUND_PCT, DYNAMICS_ESTIMATE_BOUND_PCT);
        self.beta_hat = (self.beta_hat - dt * p.gamma_beta_pct_per_s * phi_d * sliding)
            .clamp(p.min_beta_pct, p.max_beta_pct);

        let damping = -p.kd_pct_s * sliding;
        self.terms[0].value = self.beta_hat;
        self.terms[1].value = self.alpha_hat;
        self.terms[2].value = sliding;
        self.terms[3].value = damping;
        self.m_hat * phi_d_acceleration
            + self.alpha_hat * phi_d_rate
            + self.beta_hat * phi_d
            + damping
    }

    fn terms(&self) -> &[LawTerm] {
        &self.terms
    }

    fn reset(&mut self) {
        *self = Self::new(self.params);
    }

    /// Starts afresh with β̂ at the applied override (inside its bounds): the law's output at the
    /// target is then the override the machine runs at.
    fn take_over(&mut self, applied_override_pct: f64) {
        self.reset();
        if applied_override_pct.is_finite() {
            self.beta_hat =
                applied_override_pct.clamp(self.params.min_beta_pct, self.params.max_beta_pct);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> MracParams {
        MracParams {
            lambda_per_s: 2.0,
            kd_pct_s: 20.0,
            gamma_beta_pct_per_s: 50.0,
            gamma_dynamics_pct_per_s: 0.0,
            initial_beta_pct: 100.0,
            min_beta_pct: 5.0,
            max_beta_pct: 255.0,
            derivative_time_s: 0.2,
        }
    }

    /// A static plant F = g · override with a first-order lag, the simplest force process.
    fn settle(gain_n_per_pct: f64, periods: usize) -> (f64, f64) {
        let mut c = ModelReferenceAdaptive::new(params());
        let (dt, tau, target) = (0.05, 0.1, 300.0);
        let mut force = 0.0;
        let mut applied = 100.0;
        for i in 0..periods {
            let request = c.step(&ControlInput {
                time_s: i as f64 * dt,
                dt_s: dt,
                force_n: force,
                target_force_n: target,
                programmed_feed_mm_min: 200.0,
                applied_override_pct: applied,
                time_since_start_s: 10.0,
            });
            applied = request.clamp(0.0, 255.0);
            force += (1.0 - (-dt / tau).exp()) * (gain_n_per_pct * applied - force);
        }
        (force, c.beta_hat)
    }

    #[test]
    fn adapts_beta_to_the_override_that_holds_the_target() {
        // At 100 % the cut would give 450 N: the target 300 N needs 66.7 %.
        let (force, beta) = settle(4.5, 600);
        assert!((force - 300.0).abs() < 1.0, "force {force}");
        assert!((beta - 300.0 / 4.5).abs() < 1.0, "β̂ {beta}");
        // A light cut: 200 N at 100 % needs 150 %.
        let (force, beta) = settle(2.0, 600);
        assert!((force - 300.0).abs() < 1.0, "force {force}");
        assert!((beta - 150.0).abs() < 1.0, "β̂ {beta}");
    }

    #[test]
    fn beta_stays_within_its_bounds() {
        // No cut at all: the force never comes, β̂ saturates at its upper bound, not beyond.
        let (_, beta) = settle(0.0, 2000);
        assert_eq!(beta, 255.0);
    }
}
