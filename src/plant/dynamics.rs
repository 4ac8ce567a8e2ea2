//! First- and second-order lags, discretised exactly for an input held over each sample.
//!
//! The drives' bandwidths (feed servo ~40 Hz, spindle < 5 Hz, paper 003) and the Hall sensor's
//! bandwidth are lags. Discretising them by the matrix exponential keeps their step responses
//! exact at any sample rate, so a 1 kHz run and a 10 kHz run agree at the common instants.
//!
//! * first order:  y' = (u − y)·2π·f_c,           y\[k+1\] = y\[k\] + (1 − e^(−2π f_c Δt))·(u − y\[k\])
//! * second order: y'' + 2ζω·y' + ω²·y = ω²·u,    ω = 2π·f_n, exact ZOH via exp([[A, B], [0, 0]]·Δt)
//!
//! A cutoff of 0 or +∞ makes the lag a pass-through. A NaN input propagates to the output and
//! stays in the state until [`FirstOrderLag::reset`] / [`SecondOrderLag::reset`].

use crate::math;

use super::linalg;

/// A first-order low-pass lag with unit DC gain.
///
/// ```
/// use cutlab::plant::dynamics::FirstOrderLag;
/// let mut lag = FirstOrderLag::new(1.0, 0.001);
/// let mut y = 0.0;
/// for _ in 0..159 { y = lag.step(1.0); } // ≈ one time constant (1/2π s)
/// assert!((y - (1.0 - (-1.0f64).exp())).abs() < 0.01);
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FirstOrderLag {
    alpha: f64,
    y: f64,
}

impl FirstOrderLag {
    /// A lag with corner frequency `cutoff_hz` sampled every `dt_s` (a cutoff ≤ 0 or non-finite,
    /// or `dt_s` ≤ 0, gives a pass-through).
    pub fn new(cutoff_hz: f64, dt_s: f64) -> Self {
        let alpha = if cutoff_hz.is_finite() && cutoff_hz > 0.0 && dt_s > 0.0 {
            1.0 - math::exp(-std::f64::consts::TAU * cutoff_hz * dt_s)
        } else {
            1.0
        };
        Self { alpha, y: 0.0 }
    }

    /// Advances one sample with input `u` held over it; returns the output at its end.
    #[inline(always)]
    pub fn step(&mut self, u: f64) -> f64 {
        self.y += self.alpha * (u - self.y);
        self.y
    }

    /// The current output.
    pub fn value(&self) -> f64 {
        self.y
    }

    /// Sets the output (and state) to `y`.
    pub fn reset(&mut self, y: f64) {
        self.y = y;
    }
}

/// A second-order low-pass lag ω²/(s² + 2ζω·s + ω²) with unit DC gain.
///
/// ```
/// use cutlab::plant::dynamics::SecondOrderLag;
/// // A 40 Hz servo with ζ = 0.7 settles to a step within 2 % after about 4/(ζω) ≈ 23 ms.
/// let mut lag = SecondOrderLag::new(40.0, 0.7, 1e-4);
/// let y: Vec<f64> = (0..300).map(|_| lag.step(1.0)).collect();
/// assert!((y[299] - 1.0).abs() < 0.02);
/// assert!(y.iter().cloned().fold(0.0, f64::max) < 1.05); // ζ = 0.7 overshoots 4.6 %
/// ```
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SecondOrderLag {
    phi: [[f64; 2]; 2],
    gamma: [f64; 2],
    x: [f64; 2],
    pass_through: bool,
}

impl SecondOrderLag {
    /// A lag with natural frequency `natural_hz` and damping ratio `damping_ratio`, sampled every
    /// `dt_s` (a natural frequency ≤ 0 or non-finite gives a pass-through).
    pub fn new(natural_hz: f64, damping_ratio: f64, dt_s: f64) -> Self {
        if !(natural_hz.is_finite() && natural_hz > 0.0 && dt_s > 0.0) {
            return Self {
                phi: [[1.0, 0.0], [0.0, 1.0]],
                gamma: [0.0, 0.0],
                x: [0.0, 0.0],
                pass_through: true,
            };
        }
        let w = std::f64::consts::TAU * natural_hz;
        let zeta = if damping_ratio.is_finite() {
            damping_ratio.max(0.0)
        } else {
            1.0
        };
        let a = [[0.0, 1.0], [-w * w, -2.0 * zeta * w]];
        let b = [[0.0], [w * w]];
        let (phi, gamma) = linalg::zoh::<2, 1, 3>(&a, &b, dt_s);
        Self {
            phi,
            gamma: [gamma[0][0], gamma[1][0]],
            x: [0.0, 0.0],
            pass_through: false,
        }
    }

    /// Advances one sample with input `u` held over it; returns the output at its end.
    #[inline(always)]
    pub fn step(&mut self, u: f64) -> f64 {
        if self.pass_through {
            self.x = [u, 0.0];
            return u;
        }
        let [y, dy] = self.x;
        self.x = [
            self.phi[0][0] * y + self.phi[0][1] * dy + self.gamma[0] * u,
            self.phi[1][0] * y + self.phi[1][1] * dy + self.gamma[1] * u,
        ];
        self.x[0]
    }

    /// The current output.
    pub fn value(&self) -> f64 {
        self.x[0]
    }

    /// Sets the output to `y` at rest.
    pub fn reset(&mut self, y: f64) {
        self.x = [y, 0.0];
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn first_order_step_response_is_exact_at_any_sample_rate() {
        let fc = 5.0;
        for dt in [1e-4, 1e-3, 1e-2] {
            let mut lag = FirstOrderLag::new(fc, dt);
            let n = (0.05 / dt).round() as usize;
            let mut y = 0.0;
            for _ in 0..n {
                y = lag.step(2.0);
            }
            let t = n as f64 * dt;
            let exact = 2.0 * (1.0 - (-std::f64::consts::TAU * fc * t).exp());
            assert!((y - exact).abs() < 1e-12, "dt {dt}: {y} vs {exact}");
        }
    }

    #[test]
    fn second_order_step_response_matches_the_underdamped_closed_form() {
        let (natural_hz, zeta, dt) = (10.0, 0.3, 1e-3);
        let mut lag = SecondOrderLag::new(natural_hz, zeta, dt);
        let w = std::f64::consts::TAU * natural_hz;
        let wd = w * (1.0 - zeta * zeta).sqrt();
        for k in 1..=500 {
            let y = lag.step(1.0);
            let t = k as f64 * dt;
            let exact = 1.0
                - (-zeta * w * t).exp()
                    * ((wd * t).cos() + zeta / (1.0 - zeta * zeta).sqrt() * (wd * t).sin());
            assert!((y - exact).abs() < 1e-12, "t {t}: {y} vs {exact}");
        }
    }

    #[test]
    fn zero_cutoff_passes_the_input_through() {
        let mut a = FirstOrderLag::new(0.0, 1e-3);
        let mut b = SecondOrderLag::new(f64::INFINITY, 0.7, 1e-3);
        assert_eq!(a.step(3.5), 3.5);
        assert_eq!(b.step(-1.25), -1.25);
    }

    #[test]
    fn reset_restores_a_resting_state() {
        let mut lag = SecondOrderLag::new(40.0, 0.7, 1e-4);
        for _ in 0..10 {
            lag.step(5.0);
        }
        lag.reset(2.0);
        assert_eq!(lag.value(), 2.0);
        assert!((lag.step(2.0) - 2.0).abs() < 1e-12);
    }
}
