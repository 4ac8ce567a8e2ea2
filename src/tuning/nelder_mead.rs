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
        let mut search = self.search(bounds, start);
        while let Some(point) = search.ask() {
            let c = cost(&point);
            search.tell(c);
        }
        search.minimum()
    }

    /// The same search, one evaluation at a time: [`Search::ask`] for a point, [`Search::tell`]
    /// its cost. The browser runs each evaluation in slices between frames this way.
    pub fn search(&self, bounds: &[(f64, f64)], start: &[f64]) -> Search {
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
        Search {
            settings: *self,
            bounds: bounds.to_vec(),
            start: start_unit,
            simplex: Vec::with_capacity(bounds.len() + 1),
            evaluations: 0,
            step: Step::Initial,
            pending: None,
            best: None,
            converged: false,
            ways: [0; WAYS],
        }
    }
}

/// What the search does with the next cost it is told.
#[derive(Debug, Clone, PartialEq)]
enum Step {
    /// Evaluating the initial simplex's vertices.
    Initial,
    /// Waiting for the reflected point's cost.
    Reflect,
    /// Waiting for the expanded point's cost; the reflected point and its cost.
    Expand(Vec<f64>, f64),
    /// Waiting for the contracted point's cost, to beat `reference`.
    Contract(f64),
    /// Shrinking the simplex towards its best vertex; the next vertex to replace.
    Shrink(usize),
    /// Finished.
    Done,
}

/// Which way a told cost sent the search (counted, to rank [`Search::candidates`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Way {
    /// A vertex of the initial simplex.
    Vertex,
    /// The reflection beat the best vertex: expand.
    Expanding,
    /// The reflection replaces the worst vertex.
    Accepted,
    /// The reflection beat only the worst vertex: contract outside.
    ContractingOutside,
    /// The reflection beat no vertex: contract inside.
    ContractingInside,
    /// The expansion beat the reflection.
    ExpansionKept,
    /// The reflection beat the expansion.
    ReflectionKept,
    /// The contraction replaces the worst vertex.
    ContractionKept,
    /// The contraction failed: shrink.
    Shrinking,
    /// A vertex of a shrink.
    ShrinkVertex,
    /// Nothing (the search is over).
    Finished,
}

/// How many kinds of [`Way`] there are.
const WAYS: usize = Way::Finished as usize + 1;

/// A Nelder–Mead search in progress (see [`NelderMead::search`]).
#[derive(Debug, Clone, PartialEq)]
pub struct Search {
    settings: NelderMead,
    bounds: Vec<(f64, f64)>,
    start: Vec<f64>,
    /// Vertices in unit-cube coordinates with their costs.
    simplex: Vec<(Vec<f64>, f64)>,
    evaluations: usize,
    step: Step,
    /// The point asked for and not yet told, in unit-cube coordinates.
    pending: Option<Vec<f64>>,
    /// The best point told so far and its cost: a search stopped by its budget between a
    /// reflection and the expansion it asked for keeps the reflected point this way.
    best: Option<(Vec<f64>, f64)>,
    converged: bool,
    /// How often each way has been gone.
    ways: [u32; WAYS],
}

impl Search {
    /// The next point to evaluate, in the problem's units; `None` once the search is over.
    pub fn ask(&mut self) -> Option<Vec<f64>> {
        if self.pending.is_none() {
            let next = self.next_unit_point()?;
            self.pending = Some(next);
        }
        self.pending.as_deref().map(|u| self.to_problem(u))
    }

    /// The cost of the point [`ask`](Self::ask) gave (non-finite counts as +∞). Telling without
    /// asking does nothing.
    pub fn tell(&mut self, cost: f64) {
        let Some(point) = self.pending.take() else {
            return;
        };
        self.evaluations += 1;
        let cost = if cost.is_finite() {
            cost
        } else {
            f64::INFINITY
        };
        if self.best.as_ref().is_none_or(|(_, best)| cost < *best) {
            self.best = Some((point.clone(), cost));
        }
        let way = self.way_of(cost);
        self.ways[way as usize] += 1;
        let n = self.bounds.len();
        let step = std::mem::replace(&mut self.step, Step::Done);
        self.step = match (way, step) {
            (Way::Vertex, _) => {
                self.simplex.push((point, cost));
                Step::Initial
            }
            (Way::Expanding, _) => Step::Expand(point, cost),
            (Way::Accepted, _) | (Way::ContractionKept, _) | (Way::ExpansionKept, _) => {
                self.simplex[n] = (point, cost);
                Step::Reflect
            }
            // Contract towards the better of the worst point and its reflection.
            (Way::ContractingOutside | Way::ContractingInside, _) => {
                Step::Contract(cost.min(self.simplex[n].1))
            }
            (Way::ReflectionKept, Step::Expand(reflected, reflected_cost)) => {
                self.simplex[n] = (reflected, reflected_cost);
                Step::Reflect
            }
            (Way::Shrinking, _) => Step::Shrink(1),
            (Way::ShrinkVertex, Step::Shrink(i)) => {
                self.simplex[i] = (point, cost);
                if i < n {
                    Step::Shrink(i + 1)
                } else {
                    Step::Reflect
                }
            }
            (_, step) => step,
        };
    }

    /// Which way the search goes when the pending point's cost is `cost` (finite or +∞).
    fn way_of(&self, cost: f64) -> Way {
        let n = self.bounds.len();
        match &self.step {
            Step::Initial => Way::Vertex,
            Step::Reflect if cost < self.simplex[0].1 => Way::Expanding,
            Step::Reflect if cost < self.simplex[n - 1].1 => Way::Accepted,
            Step::Reflect if cost < self.simplex[n].1 => Way::ContractingOutside,
            Step::Reflect => Way::ContractingInside,
            Step::Expand(_, reflected_cost) if cost < *reflected_cost => Way::ExpansionKept,
            Step::Expand(..) => Way::ReflectionKept,
            Step::Contract(reference) if cost < *reference => Way::ContractionKept,
            Step::Contract(_) => Way::Shrinking,
            Step::Shrink(_) => Way::ShrinkVertex,
            Step::Done => Way::Finished,
        }
    }

    /// The points the search can ask after the pending one (see [`Search::ask`]), the likeliest
    /// first; empty when nothing is pending.
    ///
    /// What the search asks next depends only on where the pending point's cost falls among the
    /// costs it compares it with (its simplex's, and the reflected point's or the contraction's
    /// reference), so one cost from each interval between them gives every point it can ask. A
    /// way the search has gone more often so far ranks first. Evaluating these ahead changes
    /// nothing of the search, which is told real costs only: a point evaluated ahead is used if
    /// the search asks for it, bit for bit the same point.
    ///
    /// ```
    /// use cutlab::tuning::nelder_mead::NelderMead;
    /// let bowl = |p: &[f64]| (p[0] - 0.3).powi(2) + (p[1] + 0.2).powi(2);
    /// let mut search = NelderMead::default().search(&[(-1.0, 1.0), (-1.0, 1.0)], &[0.8, 0.8]);
    /// while let Some(point) = search.ask() {
    ///     let ahead = search.candidates();
    ///     search.tell(bowl(&point));
    ///     if let Some(next) = search.ask() {
    ///         assert!(ahead.contains(&next));
    ///     }
    /// }
    /// ```
    pub fn candidates(&self) -> Vec<Vec<f64>> {
        if self.pending.is_none() {
            return Vec::new();
        }
        // The costs a told one is compared with. Both ends of every interval between them: each
        // of them (a cost equal to one goes the way of the interval above it, as every
        // comparison is strict) and the number just below it, with the lowest finite cost and
        // +∞ (a failed run). Both ends, because whether the search has converged can change
        // within an interval (with the spread of the simplex's costs, monotonically).
        let mut thresholds: Vec<f64> = self.simplex.iter().map(|(_, c)| *c).collect();
        match &self.step {
            Step::Expand(_, reflected_cost) => thresholds.push(*reflected_cost),
            Step::Contract(reference) => thresholds.push(*reference),
            _ => {}
        }
        thresholds.retain(|c| c.is_finite());
        let mut costs: Vec<f64> = thresholds.iter().map(|c| c.next_down()).collect();
        costs.extend(thresholds);
        costs.push(f64::MIN);
        costs.push(f64::INFINITY);
        costs.sort_by(f64::total_cmp);
        costs.dedup();
        let mut found: Vec<(Way, Vec<f64>)> = Vec::new();
        for cost in costs {
            let mut then = self.clone();
            let way = then.way_of(cost);
            then.tell(cost);
            if let Some(point) = then.ask() {
                if !found.iter().any(|(_, p)| same_point(p, &point)) {
                    found.push((way, point));
                }
            }
        }
        // Stable: ties keep the order of the costs.
        found.sort_by_key(|(way, _)| std::cmp::Reverse(self.ways[*way as usize]));
        found.into_iter().map(|(_, point)| point).collect()
    }

    /// The search's evaluation budget.
    pub fn max_evaluations(&self) -> usize {
        self.settings.max_evaluations
    }

    /// Evaluations told so far.
    pub fn evaluations(&self) -> usize {
        self.evaluations
    }

    /// True once [`ask`](Self::ask) has nothing more to ask.
    pub fn is_done(&self) -> bool {
        self.step == Step::Done
    }

    /// The best point told so far (the start point before any cost was told).
    pub fn minimum(&self) -> Minimum {
        let best = self
            .best
            .clone()
            .unwrap_or_else(|| (self.start.clone(), f64::INFINITY));
        Minimum {
            point: self.to_problem(&best.0),
            cost: best.1,
            evaluations: self.evaluations,
            converged: self.converged,
        }
    }

    fn to_problem(&self, u: &[f64]) -> Vec<f64> {
        u.iter()
            .zip(&self.bounds)
            .map(|(&u, &(lo, hi))| lo + u.clamp(0.0, 1.0) * (hi - lo))
            .collect()
    }

    /// The unit-cube point the current step needs evaluated (ordering the simplex and testing
    /// the tolerances first when a new iteration starts); `None` when done.
    ///
    /// The budget is checked before every evaluation, not only when an iteration starts: an
    /// expansion, a contraction or a shrink (n more points) would otherwise run past it.
    fn next_unit_point(&mut self) -> Option<Vec<f64>> {
        let n = self.bounds.len();
        let iteration_starts = match &self.step {
            Step::Initial => self.simplex.len() > n,
            Step::Reflect => true,
            _ => false,
        };
        // At an iteration's start the tolerances are tested first, so a search that has
        // converged says so even when its budget is spent too.
        if !iteration_starts
            && !matches!(self.step, Step::Done)
            && self.evaluations >= self.settings.max_evaluations
        {
            self.step = Step::Done;
            return None;
        }
        match &self.step {
            Step::Done => None,
            Step::Initial if self.simplex.len() <= n => {
                let i = self.simplex.len();
                let mut vertex = self.start.clone();
                if i > 0 {
                    let j = i - 1;
                    vertex[j] += if vertex[j] + INITIAL_STEP <= 1.0 {
                        INITIAL_STEP
                    } else {
                        -INITIAL_STEP
                    };
                }
                Some(vertex)
            }
            Step::Initial | Step::Reflect => {
                if n == 0 || self.has_converged() {
                    self.converged = true;
                    self.step = Step::Done;
                    None
                } else if self.evaluations >= self.settings.max_evaluations {
                    self.step = Step::Done;
                    None
                } else {
                    self.step = Step::Reflect;
                    Some(self.along(1.0))
                }
            }
            Step::Expand(..) => Some(self.along(2.0)),
            Step::Contract(reference) => {
                let t = if *reference < self.simplex[n].1 {
                    0.5
                } else {
                    -0.5
                };
                Some(self.along(t))
            }
            Step::Shrink(i) => {
                let (best, vertex) = (&self.simplex[0].0, &self.simplex[*i].0);
                Some(
                    best.iter()
                        .zip(vertex)
                        .map(|(b, v)| b + 0.5 * (v - b))
                        .collect(),
                )
            }
        }
    }

    /// Orders the simplex and tests the tolerances.
    fn has_converged(&mut self) -> bool {
        let n = self.bounds.len();
        self.simplex.sort_by(|a, b| a.1.total_cmp(&b.1));
        let (best, worst) = (self.simplex[0].1, self.simplex[n].1);
        let spread = self
            .simplex
            .iter()
            .skip(1)
            .map(|(v, _)| distance(v, &self.simplex[0].0))
            .fold(0.0, f64::max);
        (worst - best).abs() <= self.settings.cost_tolerance
            && spread <= self.settings.point_tolerance
    }

    /// The point `centroid + t·(centroid − worst)`, clamped into the cube (the simplex sorted).
    fn along(&self, t: f64) -> Vec<f64> {
        let n = self.bounds.len();
        let centroid: Vec<f64> = (0..n)
            .map(|j| self.simplex[..n].iter().map(|(v, _)| v[j]).sum::<f64>() / n as f64)
            .collect();
        centroid
            .iter()
            .zip(&self.simplex[n].0)
            .map(|(c, w)| (c + t * (c - w)).clamp(0.0, 1.0))
            .collect()
    }
}

/// Whether two points are the same bit for bit.
pub(crate) fn same_point(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
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
            // The initial simplex's second vertex (0.65) is already where the cost is NaN.
            &[0.4],
        );
        assert!(m.cost.is_finite() && m.point[0] <= 0.5, "{m:?}");
        assert!((m.point[0] - 0.2).abs() < 0.01, "{m:?}");
        assert!(calls <= 25, "{calls} evaluations");
        assert_eq!(m.evaluations, calls);
    }

    /// Costs that take a search through expansions (a bowl), contractions (a narrow valley)
    /// and shrinks (a plateau).
    const BOWL: fn(&[f64]) -> f64 = |p| p.iter().map(|x| (x - 0.2).powi(2)).sum();
    const VALLEY: fn(&[f64]) -> f64 = |p| {
        let y = p.get(1).copied().unwrap_or(0.0);
        (p[0] - 0.3).powi(2) + 50.0 * (y - p[0] * p[0]).powi(2)
    };
    const PLATEAU: fn(&[f64]) -> f64 = |p| if p[0] > 0.6 { 1.0 } else { p[0] };

    /// Counts the evaluations of a search of `cost` over `dimensions` parameters on [0, 1] with
    /// budget `max`, returning (calls, the minimum).
    fn budgeted(cost: fn(&[f64]) -> f64, dimensions: usize, max: usize) -> (usize, Minimum) {
        let mut calls = 0;
        let m = NelderMead {
            max_evaluations: max,
            // Never met: only the budget stops the search.
            cost_tolerance: 0.0,
            point_tolerance: 0.0,
        }
        .minimize(
            |p| {
                calls += 1;
                cost(p)
            },
            &vec![(0.0, 1.0); dimensions],
            &vec![0.9; dimensions],
        );
        (calls, m)
    }

    #[test]
    fn the_budget_holds_exactly_through_expansions_contractions_and_shrinks() {
        // The audit's cases (30 → 32, 3 → 4, 5 → 7, 1 → 3 before the fix) and every budget up
        // to 40 on a bowl (expansions), a narrow valley (contractions) and a cost with a plateau
        // that forces shrinks.
        for cost in [BOWL, VALLEY, PLATEAU] {
            for dimensions in [1, 2, 3] {
                for max in 1..=40 {
                    let (calls, m) = budgeted(cost, dimensions, max);
                    assert_eq!(calls, max, "{dimensions} parameters, budget {max}");
                    assert_eq!(m.evaluations, max);
                    assert!(!m.converged);
                }
            }
        }
    }

    #[test]
    fn the_point_asked_next_is_always_among_the_candidates() {
        // Every way a search can go — expansions, both contractions, shrinks, failed (NaN)
        // evaluations, the budget and the tolerances — over one to three parameters.
        let holed: fn(&[f64]) -> f64 = |p| {
            if p[0] > 0.7 {
                f64::NAN
            } else {
                (p[0] - 0.4).abs() + p.iter().skip(1).map(|x| (x - 0.6).abs()).sum::<f64>()
            }
        };
        let mut asked = 0;
        let mut first_choice = 0;
        for cost in [BOWL, VALLEY, PLATEAU, holed] {
            for dimensions in [1, 2, 3] {
                let mut search = NelderMead {
                    max_evaluations: 80,
                    cost_tolerance: 1e-6,
                    point_tolerance: 1e-4,
                }
                .search(&vec![(0.0, 1.0); dimensions], &vec![0.9; dimensions]);
                while let Some(point) = search.ask() {
                    let candidates = search.candidates();
                    search.tell(cost(&point));
                    if let Some(next) = search.ask() {
                        let at = candidates.iter().position(|c| same_point(c, &next));
                        assert!(
                            at.is_some(),
                            "{dimensions} parameters: {next:?} not in {candidates:?}"
                        );
                        asked += 1;
                        first_choice += usize::from(at == Some(0));
                    }
                }
                assert!(search.candidates().is_empty());
            }
        }
        // The ranking by the ways gone so far picks the next point first more often than not.
        assert!(2 * first_choice > asked, "{first_choice} of {asked}");
    }

    #[test]
    fn a_search_stopped_before_its_expansion_keeps_the_reflected_point() {
        // One parameter from 0.9: vertices 0.9 and 0.65, the reflection 0.4 beats both, and the
        // budget of 3 ends the search before the expansion is evaluated.
        let (calls, m) = budgeted(|p| (p[0] - 0.1).abs(), 1, 3);
        assert_eq!(calls, 3);
        assert!((m.point[0] - 0.4).abs() < 1e-12, "{m:?}");
        assert!((m.cost - 0.3).abs() < 1e-12, "{m:?}");
    }
}
