//! Nelder–Mead minimisation inside a box, derivative-free and deterministic.
//!
//! The simplex lives in the unit cube: each parameter is mapped linearly from its bounds to
//! [0, 1], and every trial point is clamped back into the cube, so no evaluation ever leaves the
//! bounds (the controllers refuse values outside their ranges). The coefficients are the standard
//! ones (reflection 1, expansion 2, contraction ½, shrink ½; Nelder & Mead 1965, as in
//! `scipy.optimize.minimize(method="Nelder-Mead")`), the initial simplex steps 25 % of each range
//! from the start point (away from the nearer bound), and the search stops after `max_evaluations`
//! or once the simplex's costs agree within `cost_tolerance` and its points within
//! `point_tolerance` of the unit cube.

/// Where the search stopped and why.
#[derive(Debug, Clone, PartialEq)]
pub struct Minimum {
    /// The best point found, in the problem's own units.
    pub point: Vec<f64>,
    /// Its cost.
    pub cost: f64,
    /// Evaluations used.
    pub evaluations: usize,
    /// True when the tolerances were met, false when the evaluation budget ran out first.
    pub converged: bool,
}

/// Settings of the search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NelderMead {
    /// Largest number of cost evaluations.
    pub max_evaluations: usize,
    /// Stop when the simplex's highest and lowest costs differ by less than this.
    pub cost_tolerance: f64,
    /// … and its vertices lie within this distance of the best one (unit-cube coordinates).
    pub point_tolerance: f64,
}

impl Default for NelderMead {
    fn default() -> Self {
        Self {
            max_evaluations: 60,
            cost_tolerance: 1e-4,
            point_tolerance: 1e-3,
        }
    }
}

/// The initial simplex's step, as a fraction of each parameter's range.
const INITIAL_STEP: f64 = 0.25;

impl NelderMead {
    /// Minimises `cost` over the box `bounds` (lo ≤ hi for each parameter) from `start`, which is
    /// clamped into the box. A non-finite cost counts as +∞ (the point is never kept). Empty
    /// bounds evaluate `cost` once at the empty point.
    ///
    /// ```
    /// use cutlab::tuning::nelder_mead::NelderMead;
    /// // A bowl with its bottom at (0.3, -1.2), inside the box.
    /// let bowl = |p: &[f64]| (p[0] - 0.3).powi(2) + 2.0 * (p[1] + 1.2).powi(2);
    /// let search = NelderMead { max_evaluations: 400, ..NelderMead::default() };
    /// let m = search.minimize(bowl, &[(-2.0, 2.0), (-2.0, 2.0)], &[1.5, 1.5]);
    /// assert!((m.point[0] - 0.3).abs() < 0.01 && (m.point[1] + 1.2).abs() < 0.01, "{m:?}");
    /// ```
    pub fn minimize(
        &self,
        mut cost: impl FnMut(&[f64]) -> f64,
        bounds: &[(f64, f64)],
        start: &[f64],
    ) -> Minimum {
        let n = bounds.len();
        let to_problem = |u: &[f64]| -> Vec<f64> {
            u.iter()
                .zip(bounds)
                .map(|(&u, &(lo, hi))| lo + u.clamp(0.0, 1.0) * (hi - lo))
                .collect()
        };
        // Counted through a cell: the loop reads the count while `evaluate` holds the cost.
        let evaluations = std::cell::Cell::new(0usize);
        let mut evaluate = |u: &[f64]| {
            evaluations.set(evaluations.get() + 1);
            let c = cost(&to_problem(u));
            if c.is_finite() {
                c
            } else {
                f64::INFINITY
            }
        };
        let start_unit: Vec<f64> = bounds
            .iter()
            .enumerate()
            .map(|(i, &(lo, hi))| {
                let x = start.get(i).copied().unwrap_or(lo);
                if hi > lo && x.is_finite() {
                    ((x - lo) / (hi - lo)).clamp(0.0, 1.0)
                } else {
                    0.0
                }
            })
            .collect();
        let mut simplex: Vec<(Vec<f64>, f64)> = Vec::with_capacity(n + 1);
        let c0 = evaluate(&start_unit);
        simplex.push((start_unit.clone(), c0));
        for i in 0..n {
            let mut vertex = start_unit.clone();
            vertex[i] += if vertex[i] + INITIAL_STEP <= 1.0 {
                INITIAL_STEP
            } else {
                -INITIAL_STEP
            };
            let c = evaluate(&vertex);
            simplex.push((vertex, c));
        }
        let mut converged = n == 0;
        while !converged && evaluations.get() < self.max_evaluations {
            simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
            let (best, worst) = (simplex[0].1, simplex[n].1);
            let spread = simplex
                .iter()
                .skip(1)
                .map(|(v, _)| distance(v, &simplex[0].0))
                .fold(0.0, f64::max);
            if (worst - best).abs() <= self.cost_tolerance && spread <= self.point_tolerance {
                converged = true;
                break;
            }
            let centroid: Vec<f64> = (0..n)
                .map(|j| simplex[..n].iter().map(|(v, _)| v[j]).sum::<f64>() / n as f64)
                .collect();
            let along = |t: f64| -> Vec<f64> {
                centroid
                    .iter()
                    .zip(&simplex[n].0)
                    .map(|(c, w)| (c + t * (c - w)).clamp(0.0, 1.0))
                    .collect()
            };
            let reflected = along(1.0);
            let cr = evaluate(&reflected);
            if cr < simplex[0].1 {
                let expanded = along(2.0);
                let ce = evaluate(&expanded);
                simplex[n] = if ce < cr {
                    (expanded, ce)
                } else {
                    (reflected, cr)
                };
            } else if cr < simplex[n - 1].1 {
                simplex[n] = (reflected, cr);
            } else {
                // Contract towards the better of the worst point and its reflection.
                let (t, reference) = if cr < worst { (0.5, cr) } else { (-0.5, worst) };
                let contracted = along(t);
                let cc = evaluate(&contracted);
                if cc < reference {
                    simplex[n] = (contracted, cc);
                } else {
                    let best_point = simplex[0].0.clone();
                    for vertex in simplex.iter_mut().skip(1) {
                        let shrunk: Vec<f64> = best_point
                            .iter()
                            .zip(&vertex.0)
                            .map(|(b, v)| b + 0.5 * (v - b))
                            .collect();
                        let c = evaluate(&shrunk);
                        *vertex = (shrunk, c);
                    }
                }
            }
        }
        simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (point, cost) = simplex.swap_remove(0);
        Minimum {
            point: to_problem(&point),
            cost,
            evaluations: evaluations.get(),
            converged,
        }
    }
}

fn distance(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x - y) * (x - y))
        .sum::<f64>()
        .sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_the_rosenbrock_valley_floor() {
        let rosenbrock = |p: &[f64]| (1.0 - p[0]).powi(2) + 100.0 * (p[1] - p[0] * p[0]).powi(2);
        let search = NelderMead {
            max_evaluations: 2000,
            cost_tolerance: 1e-12,
            point_tolerance: 1e-7,
        };
        let m = search.minimize(rosenbrock, &[(-2.0, 2.0), (-1.0, 3.0)], &[-1.2, 1.0]);
        assert!(m.converged, "{m:?}");
        assert!(
            (m.point[0] - 1.0).abs() < 1e-3 && (m.point[1] - 1.0).abs() < 2e-3,
            "{m:?}"
        );
    }

    #[test]
    fn a_minimum_outside_the_box_stops_on_its_wall() {
        let slope = |p: &[f64]| p[0];
        let m = NelderMead::default().minimize(slope, &[(2.0, 5.0)], &[4.0]);
        assert!((m.point[0] - 2.0).abs() < 1e-3, "{m:?}");
    }

    #[test]
    fn non_finite_costs_are_never_kept_and_the_budget_holds() {
        let mut calls = 0;
        let m = NelderMead {
            max_evaluations: 25,
            ..NelderMead::default()
        }
        .minimize(
            |p: &[f64]| {
                calls += 1;
                if p[0] > 0.5 {
                    f64::NAN
                } else {
                    (p[0] - 0.2).abs()
                }
            },
            &[(0.0, 1.0)],
            &[0.9],
        );
        assert!(m.cost.is_finite() && m.point[0] <= 0.5, "{m:?}");
        assert!(calls <= 25 + 2, "{calls} evaluations");
        assert_eq!(m.evaluations, calls);
    }
}
