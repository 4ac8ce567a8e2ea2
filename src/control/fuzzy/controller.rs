//! Paper 002's incremental fuzzy feed controller.
//!
//! Each control period (paper 002 eq 6 and §2):
//!
//! ```text
//! E(i)  = F_target − F(i)              (paper: I_ref − I)
//! EC(i) = E(i) − E(i−1)                (0 on the first step and after a reset)
//! U     = fuzzy(k_e·E, k_ec·EC)        (inputs saturated to the universe [−6, 6])
//! a_f(i+1) = a_f(i) + k_u·U
//! ```
//!
//! E is in newtons, positive when the cut is lighter than the target; EC is in newtons too,
//! positive when the cut is getting lighter. In cutlab's units
//! k_e = 6 / (F_target · error_range_pct / 100) and k_ec = 6 / (F_target · change_range_pct / 100),
//! both from the target of the current step, and k_u = output_range_pct / 6 percentage points of
//! override per unit of U. Since U lies in [−6, 6], one step changes the override by at most
//! `output_range_pct`; the override itself is limited by the safety envelope, not here.
//!
//! ## Per period or per second
//!
//! Eq 6 reads EC as the difference of two successive errors and eq 1 adds k_u·U once per period,
//! so both depend on the period T: a longer period sees a larger EC and, per second, a smaller
//! gain. Paper 002's Table 2 gives EC in A/s (−11.5 → 8.5 A in 0.05 s is its 400 A/s). Each
//! reading has a time base t (0 for per period, eq 6 and eq 1 as printed):
//!
//! ```text
//! EC  = (E(i) − E(i−1)) · t_ec/T        the change over t_ec: t_ec = 1 s reads EC in A/s (N/s)
//! Δu  = k_u·U · T/t_u                   k_u per t_u: t_u = 1 s makes it a rate, % per second
//! ```
//!
//! With t_ec = 1 s the change range is per second (the paper's 50 A/s at k_ec = 3/25); with
//! t_u = 1 s the output range is the override's rate of change at |U| = 6. Both at 0 keep the
//! per-period law, on every preset. A period that is not positive and finite reads both per period.
//!
//! Paper 002 regulates the spindle current with k_e = 6/25 A⁻¹ and k_ec = 3/25 A⁻¹ for
//! I_ref = 25 A, and k_u = 250 mm/min for a 1500 mm/min feed: an error of the whole reference
//! saturates E, a change of twice the reference saturates EC, and a saturated output changes the
//! feed by the whole programmed feed. cutlab states the same scalings relative to the target force
//! and the programmed feed, so the paper's numbers are the defaults (100 %, 200 %, 100 %) on every
//! preset. The feed a_f(i) the law increments is the one the machine applied, so the envelope's
//! limits cannot wind it up.
//!
//! ## Any engine of two inputs and one output
//!
//! The controller runs any [`Engine`] with two inputs and one output ([`FuzzyController::from_engine`]:
//! an FLL or FIS file brought by the engineer). Paper 002's engine is one such engine, with every
//! universe [−6, 6]. The mapping is stated on the universes, by position: the engine's **first
//! input is E, its second EC**, and its one output is U. With an input's universe [a, b], its
//! centre m = a + (b − a)/2 and half-width h = (b − a)/2,
//!
//! ```text
//! x_E  = sat_[a,b]( m + h · E  / (F_target · error_range_pct / 100) )
//! x_EC = sat_[a,b]( m + h · EC / (F_target · change_range_pct / 100) )    (EC's own a, b)
//! Δu   = (U − m_U) / h_U · output_range_pct · T/t_u                       (T/t_u = 1 per period)
//! ```
//!
//! so an error of the whole error range reaches the edge of the first input's universe, and the
//! output's edge is a change of the whole output range. On [−6, 6] this is k_e = 6 / (F_target ·
//! error_range_pct / 100) and k_u = output_range_pct / 6 above, computed by the same expressions,
//! so paper 002's tables run through this path give the same bits. An engine whose output is not
//! a number (no rule fired and its default is NaN) holds the override for that period.

use super::engine::{Defuzzifier, Engine};
use super::rules::{paper_002_engine, RuleTable};
use super::FuzzyError;
use crate::control::law::{ControlInput, Controller, LawTerm};

/// Scalings of [`FuzzyController`], relative to the target and the programmed feed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FuzzyParams {
    /// |E| that saturates the input, in percent of the target (paper: 25 A of 25 A = 100 %).
    pub error_range_pct: f64,
    /// |EC| that saturates the input, in percent of the target (paper: 50 A of 25 A = 200 %).
    pub change_range_pct: f64,
    /// Override change at |U| = 6, percentage points (paper: 6 · 250 mm/min of 1500 = 100 %).
    pub output_range_pct: f64,
    /// EC's time base t_ec: 0 reads EC per period (eq 6), t > 0 as the change over t (1 s:
    /// Table 2's A/s).
    pub change_time_base_s: f64,
    /// k_u's time base t_u: 0 applies k_u per period (eq 1), t > 0 per t (1 s: a rate).
    pub output_time_base_s: f64,
}

/// A universe [min, max] as its centre and half-width, the mapping's terms.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Universe {
    min: f64,
    max: f64,
    centre: f64,
    half_width: f64,
}

impl Universe {
    fn new(min: f64, max: f64) -> Self {
        let half_width = (max - min) / 2.0;
        Self {
            min,
            max,
            centre: min + half_width,
            half_width,
        }
    }

    /// `value` relative to `range` (1 at the range) on this universe, saturated at its edges.
    fn place(self, value: f64, range: f64) -> f64 {
        (self.centre + self.half_width / range * value).clamp(self.min, self.max)
    }
}

/// The incremental fuzzy controller of paper 002.
///
/// ```
/// use cutlab::control::fuzzy::controller::{FuzzyController, FuzzyParams};
/// use cutlab::control::fuzzy::engine::Defuzzifier;
/// use cutlab::control::fuzzy::rules::RuleBase;
/// use cutlab::control::law::{Controller, ControlInput};
/// let mut c = FuzzyController::new(&RuleBase::Dynamics.table(), Defuzzifier::WeightedAverage,
///     FuzzyParams { error_range_pct: 100.0, change_range_pct: 200.0, output_range_pct: 100.0,
///     change_time_base_s: 0.0, output_time_base_s: 0.0 }).unwrap();
/// let input = ControlInput { time_s: 10.0, dt_s: 0.05, force_n: 300.0, target_force_n: 300.0,
///     programmed_feed_mm_min: 1500.0, applied_override_pct: 100.0, time_since_start_s: 10.0 };
/// assert_eq!(c.step(&input), 100.0); // on target: ZO, ZO → ZO
/// ```
#[derive(Debug, Clone)]
pub struct FuzzyController {
    engine: Engine,
    params: FuzzyParams,
    /// The universes of E, EC and U.
    universes: [Universe; 3],
    previous_error_n: Option<f64>,
    output: [f64; 1],
    terms: [LawTerm; 4],
    /// The last step was held (a non-finite force): nothing was inferred, nothing fired.
    held: bool,
}

impl FuzzyController {
    /// Paper 002's controller for a rule table, defuzzified by `defuzzifier`.
    pub fn new(
        table: &RuleTable,
        defuzzifier: Defuzzifier,
        params: FuzzyParams,
    ) -> Result<Self, FuzzyError> {
        Self::from_engine(paper_002_engine(table, defuzzifier)?, params)
    }

    /// The controller for any engine of two inputs (E first, EC second) and one output U, mapped
    /// onto their universes as the module documentation states; an engine of another shape is an
    /// error that says what it has.
    ///
    /// ```
    /// use cutlab::control::fuzzy::controller::{FuzzyController, FuzzyParams};
    /// use cutlab::control::fuzzy::fll;
    /// let tipper = fll::parse("Engine: tipper\nInputVariable: service\n  range: 0 10\n\
    ///     term: good Triangle 0 5 10\nOutputVariable: tip\n  range: 0 30\n\
    ///     term: average Triangle 0 15 30\n  defuzzifier: Centroid\n\
    ///     RuleBlock: \n  rule: if service is good then tip is average").unwrap();
    /// let params = FuzzyParams { error_range_pct: 100.0, change_range_pct: 200.0,
    ///     output_range_pct: 20.0, change_time_base_s: 0.0, output_time_base_s: 0.0 };
    /// let why = FuzzyController::from_engine(tipper, params).unwrap_err();
    /// assert_eq!(why.to_string(), "engine \"tipper\" has 1 input and 1 output; the loop's \
    ///     controller needs 2 inputs (E, then EC) and 1 output (the override's change)");
    /// ```
    pub fn from_engine(engine: Engine, params: FuzzyParams) -> Result<Self, FuzzyError> {
        let (e, ec, u) = match (engine.inputs(), engine.outputs()) {
            ([e, ec], [u]) => (
                Universe::new(e.min, e.max),
                Universe::new(ec.min, ec.max),
                Universe::new(u.min, u.max),
            ),
            (inputs, outputs) => {
                let count =
                    |n: usize, what: &str| format!("{n} {what}{}", if n == 1 { "" } else { "s" });
                return Err(FuzzyError::new(format!(
                    "engine \"{}\" has {} and {}; the loop's controller needs 2 inputs (E, then \
                     EC) and 1 output (the override's change)",
                    engine.name,
                    count(inputs.len(), "input"),
                    count(outputs.len(), "output"),
                )));
            }
        };
        Ok(Self {
            engine,
            params,
            universes: [e, ec, u],
            previous_error_n: None,
            output: [0.0],
            terms: [
                LawTerm::new("E (scaled)", ""),
                LawTerm::new("EC (scaled)", ""),
                LawTerm::new("U", ""),
                LawTerm::new("Δ override", "%"),
            ],
            held: false,
        })
    }

    /// The engine, for drawing its surface and rules.
    pub fn engine(&self) -> &Engine {
        &self.engine
    }
}

impl Controller for FuzzyController {
    /// A non-finite force holds the override and leaves the error history as it was.
    fn step(&mut self, input: &ControlInput) -> f64 {
        let error_n = input.target_force_n - input.force_n;
        if !error_n.is_finite() {
            // What is plotted for a held period is what happened: no inputs, no increment.
            self.held = true;
            for t in &mut self.terms[..3] {
                t.value = f64::NAN;
            }
            self.terms[3].value = 0.0;
            return input.applied_override_pct;
        }
        self.held = false;
        let p = self.params;
        let period_s = input.dt_s;
        // (EC's scale, Δu's scale) of the readings' time bases: 1 per period.
        let per = |base_s: f64| base_s > 0.0 && period_s.is_finite() && period_s > 0.0;
        let change_scale = if per(p.change_time_base_s) {
            p.change_time_base_s / period_s
        } else {
            1.0
        };
        let output_scale = if per(p.output_time_base_s) {
            period_s / p.output_time_base_s
        } else {
            1.0
        };
        let change_n = (error_n - self.previous_error_n.unwrap_or(error_n)) * change_scale;
        self.previous_error_n = Some(error_n);
        let [e_universe, ec_universe, u_universe] = self.universes;
        let e = e_universe.place(error_n, input.target_force_n * p.error_range_pct / 100.0);
        let ec = ec_universe.place(change_n, input.target_force_n * p.change_range_pct / 100.0);
        self.engine.evaluate(&[e, ec], &mut self.output);
        let u = self.output[0];
        // An engine may answer NaN (no rule fired, default NaN): then nothing changes.
        let change_pct = if u.is_finite() {
            (u - u_universe.centre) / u_universe.half_width * p.output_range_pct * output_scale
        } else {
            0.0
        };
        self.terms[0].value = e;
        self.terms[1].value = ec;
        self.terms[2].value = u;
        self.terms[3].value = change_pct;
        input.applied_override_pct + change_pct
    }

    fn terms(&self) -> &[LawTerm] {
        &self.terms
    }

    fn rule_activations(&self) -> Option<&[f64]> {
        (!self.held).then(|| self.engine.activations())
    }

    fn reset(&mut self) {
        self.previous_error_n = None;
        self.held = false;
        self.engine.reset();
        for t in &mut self.terms {
            t.value = 0.0;
        }
    }
}

#[cfg(test)]
mod tests {
    //! The law checked against hand calculations.
    //!
    //! Every case uses a target of 300 N and the paper's scalings unless it says otherwise:
    //! k_e = 6 / (300 N · 100 %) = 0.02 N⁻¹, k_ec = 6 / (300 N · 200 %) = 0.01 N⁻¹ and
    //! k_u = 100 % / 6 = 16.67 percentage points per unit of U. With the weighted average (eq 7)
    //! and the experience table (U level = sat(E level + EC level)), U is worked out by hand from
    //! the seven triangles of [`super::super::rules::seven_terms`] (peaks 2 apart, so an input on a
    //! peak belongs to one set only and an input halfway between two belongs 0.5 to each).

    use super::*;
    use crate::control::fuzzy::rules::RuleBase;
    use crate::rng::Rng;

    const TARGET_N: f64 = 300.0;
    const TOL: f64 = 1e-12;

    fn params(error: f64, change: f64, output: f64) -> FuzzyParams {
        FuzzyParams {
            error_range_pct: error,
            change_range_pct: change,
            output_range_pct: output,
            change_time_base_s: 0.0,
            output_time_base_s: 0.0,
        }
    }

    fn paper() -> FuzzyParams {
        params(100.0, 200.0, 100.0)
    }

    fn controller(p: FuzzyParams) -> FuzzyController {
        FuzzyController::new(
            &RuleBase::Experience.table(),
            Defuzzifier::WeightedAverage,
            p,
        )
        .unwrap()
    }

    fn input(force_n: f64, applied_override_pct: f64) -> ControlInput {
        ControlInput {
            time_s: 10.0,
            dt_s: 0.05,
            force_n,
            target_force_n: TARGET_N,
            programmed_feed_mm_min: 1500.0,
            applied_override_pct,
            time_since_start_s: 10.0,
        }
    }

    /// (E scaled, EC scaled, U, Δ override %) after the latest step.
    fn terms(c: &FuzzyController) -> [f64; 4] {
        let t = c.terms();
        [t[0].value, t[1].value, t[2].value, t[3].value]
    }

    fn assert_close(actual: f64, expected: f64, what: &str) {
        assert!(
            (actual - expected).abs() <= TOL * (1.0 + expected.abs()),
            "{what}: {actual} vs {expected}"
        );
    }

    fn assert_terms(c: &FuzzyController, expected: [f64; 4], step: &str) {
        for ((actual, expected), name) in terms(c)
            .into_iter()
            .zip(expected)
            .zip(["E", "EC", "U", "Δ"])
        {
            assert_close(actual, expected, &format!("{step}: {name}"));
        }
    }

    #[test]
    fn the_error_is_target_minus_force_in_newtons_scaled_by_k_e() {
        // 250 N on a 300 N target: the cut is light, E = +50 N, k_e·E = 0.02 · 50 = 1 (ZO 0.5,
        // PS 0.5). The first step has no earlier error, so EC = 0 (ZO). Rules ZO,ZO → ZO (0) and
        // PS,ZO → PS (2), each at 0.5: U = 1, Δ = 1/6 · 100 % = 16.67 %, and the feed rises.
        let mut c = controller(paper());
        let request = c.step(&input(250.0, 100.0));
        assert_terms(&c, [1.0, 0.0, 1.0, 100.0 / 6.0], "light cut");
        assert_close(request, 100.0 + 100.0 / 6.0, "request");
        // 350 N: a heavy cut, E = −50 N → −1, U = −1, and the feed falls by the same amount.
        let mut c = controller(paper());
        let request = c.step(&input(350.0, 100.0));
        assert_terms(&c, [-1.0, 0.0, -1.0, -100.0 / 6.0], "heavy cut");
        assert_close(request, 100.0 - 100.0 / 6.0, "request");
    }

    #[test]
    fn the_change_of_error_is_the_difference_of_successive_errors_scaled_by_k_ec() {
        let mut c = controller(paper());
        // E = 0.
        c.step(&input(300.0, 100.0));
        // E = 100 N → 2 (PS); EC = 100 N − 0 N = 100 N → 0.01 · 100 = 1 (ZO 0.5, PS 0.5).
        // PS,ZO → PS (2) and PS,PS → PM (4), each at 0.5: U = 3, Δ = 50 %.
        c.step(&input(200.0, 100.0));
        assert_terms(&c, [2.0, 1.0, 3.0, 50.0], "error grows");
        // The error falls back to 0: EC = 0 − 100 N → −1 (NS 0.5, ZO 0.5). ZO,NS → NS (−2) and
        // ZO,ZO → ZO (0): U = −1.
        c.step(&input(300.0, 100.0));
        assert_terms(&c, [0.0, -1.0, -1.0, -100.0 / 6.0], "error shrinks");
        // EC is a difference of errors in newtons, so a change of target counts, and each input is
        // scaled by the target of its own step: target 400 N at the same 300 N force gives
        // E = 100 N · 6/400 N = 1.5 and EC = (100 N − 0 N) · 6/800 N = 0.75.
        let mut c = controller(paper());
        c.step(&input(300.0, 100.0));
        c.step(&ControlInput {
            target_force_n: 400.0,
            ..input(300.0, 100.0)
        });
        assert_close(terms(&c)[0], 1.5, "E after a target change");
        assert_close(terms(&c)[1], 0.75, "EC after a target change");
    }

    #[test]
    fn the_override_integrates_the_increments_from_the_applied_value() {
        // a_f(i+1) = a_f(i) + Δa_f(i) over five periods, each Δ worked out by hand:
        //   300 N: E 0, EC 0                  → U 0                              Δ 0
        //   200 N: E 2, EC 1                  → U 3                              Δ 50
        //   200 N: E 2, EC 0                  → PS,ZO → PS: U 2                  Δ 33.33
        //   300 N: E 0, EC −1                 → U −1                             Δ −16.67
        //   250 N: E 1 (ZO .5, PS .5), EC 0.5 (ZO .75, PS .25); AND = min gives
        //          ZO,ZO .5 → 0, ZO,PS .25 → 2, PS,ZO .5 → 2, PS,PS .25 → 4:
        //          U = (0.5 + 1 + 1) / 1.5 = 5/3                                 Δ 27.78
        // (AND = product would give U = 1.5 in the last period.)
        let forces = [300.0, 200.0, 200.0, 300.0, 250.0];
        let increments = [0.0, 50.0, 100.0 / 3.0, -100.0 / 6.0, 250.0 / 9.0];
        let mut c = controller(paper());
        let mut applied = 100.0;
        let mut expected = 100.0;
        for (k, (force, delta)) in forces.into_iter().zip(increments).enumerate() {
            let request = c.step(&input(force, applied));
            expected += delta;
            assert_close(terms(&c)[3], delta, &format!("Δ at period {k}"));
            assert_close(request, expected, &format!("a_f at period {k}"));
            applied = request;
        }
        assert_close(
            expected,
            100.0 + 50.0 + 100.0 / 3.0 - 100.0 / 6.0 + 250.0 / 9.0,
            "sum",
        );
        // The increment is added to what the machine applied, not to the last request: with the
        // envelope holding the override at 120 %, E = 2, EC = 0 asks for 120 + 33.33 %.
        let mut c = controller(paper());
        c.step(&input(200.0, 100.0));
        let request = c.step(&input(200.0, 120.0));
        assert_close(request, 120.0 + 100.0 / 3.0, "from the applied override");
    }

    #[test]
    fn k_u_scales_the_increment_and_k_e_k_ec_scale_the_inputs() {
        let forces = [300.0, 200.0, 200.0, 300.0, 250.0];
        let run = |p: FuzzyParams| -> Vec<[f64; 4]> {
            let mut c = controller(p);
            forces
                .iter()
                .map(|f| {
                    c.step(&input(*f, 100.0));
                    terms(&c)
                })
                .collect()
        };
        let base = run(paper());
        // Doubling k_u (the output range) doubles every Δa_f and leaves E, EC and U alone.
        for (single, double) in base.iter().zip(run(params(100.0, 200.0, 200.0))) {
            assert_close(double[3], 2.0 * single[3], "Δ with twice k_u");
            assert_eq!(&double[..3], &single[..3]);
        }
        // A doubled error range halves k_e: at 200 N, E = 100 N · 6/600 N = 1 instead of 2, with
        // EC = 1: ZO,ZO → 0, ZO,PS → 2, PS,ZO → 2, PS,PS → 4, all at 0.5: U = 2, Δ = 33.33 %.
        let wide_error = run(params(200.0, 200.0, 100.0));
        assert_close(wide_error[1][0], 1.0, "E with half k_e");
        assert_close(wide_error[1][1], 1.0, "EC with half k_e");
        assert_close(wide_error[1][3], 100.0 / 3.0, "Δ with half k_e");
        // A doubled change range halves k_ec: EC = 100 N · 6/1200 N = 0.5 (ZO .75, PS .25) with
        // E = 2 (PS): PS,ZO .75 → 2 and PS,PS .25 → 4: U = 2.5, Δ = 41.67 %.
        let wide_change = run(params(100.0, 400.0, 100.0));
        assert_close(wide_change[1][0], 2.0, "E with half k_ec");
        assert_close(wide_change[1][1], 0.5, "EC with half k_ec");
        assert_close(wide_change[1][3], 250.0 / 6.0, "Δ with half k_ec");
    }

    #[test]
    fn ec_read_as_a_rate_and_k_u_per_second_scale_with_the_period() {
        // The periods of `input` are 0.05 s. E: 0 N, then 100 N → 2 (PS).
        let steps = |p: FuzzyParams| {
            let mut c = controller(p);
            c.step(&input(300.0, 100.0));
            let request = c.step(&input(200.0, 100.0));
            (terms(&c), request)
        };
        // Per period (eq 6): EC = 100 N → 1, as in the hand calculation above.
        let (per_period, _) = steps(paper());
        assert_close(per_period[1], 1.0, "EC per period");
        // As a rate over 1 s: EC = 100 N / 0.05 s = 2000 N/s; k_ec = 6 / (300 N/s · 200 %)
        // = 0.01 s/N gives 20, saturated at 6. Over 0.05 s (one period) it is eq 6 again.
        let rate = |t| FuzzyParams {
            change_time_base_s: t,
            ..paper()
        };
        let (per_second, _) = steps(rate(1.0));
        assert_close(per_second[1], 6.0, "EC per second");
        let (per_table_2_row, _) = steps(rate(0.05));
        assert_eq!(per_table_2_row, per_period);
        // A smaller change: 1 N in 0.05 s is 20 N/s → 0.2 per second, 0.01 per period.
        let mut c = controller(rate(1.0));
        c.step(&input(300.0, 100.0));
        c.step(&input(299.0, 100.0));
        assert_close(terms(&c)[1], 0.2, "1 N in 0.05 s per second");
        // k_u per second: U = 3 asks for 50 % per second, 2.5 % in a 0.05 s period; E, EC and U
        // are the per-period law's.
        let (eq_1, request_eq_1) = steps(paper());
        let (rated, request_rated) = steps(FuzzyParams {
            output_time_base_s: 1.0,
            ..paper()
        });
        assert_eq!(&rated[..3], &eq_1[..3]);
        assert_close(rated[3], 50.0 * 0.05, "Δ per period at 50 %/s");
        assert_close(
            request_rated - 100.0,
            0.05 * (request_eq_1 - 100.0),
            "request",
        );
    }

    #[test]
    fn inputs_beyond_the_universe_saturate_at_its_edge() {
        // An error of exactly the error range (300 N at 0 N) is E = 6: PB with EC = 0 (ZO) gives
        // PB (centre 6), the whole output range. Ten times the range gives the same E and output.
        let request_at = |forces: &[f64]| -> (f64, [f64; 4]) {
            let mut c = controller(paper());
            let mut request = f64::NAN;
            for f in forces {
                request = c.step(&input(*f, 100.0));
            }
            (request, terms(&c))
        };
        for (edge, beyond, e, u) in [(0.0, -2700.0, 6.0, 6.0), (600.0, 3300.0, -6.0, -6.0)] {
            let (at_edge, edge_terms) = request_at(&[edge]);
            let (past_edge, past_terms) = request_at(&[beyond]);
            assert_terms_eq(edge_terms, [e, 0.0, u, 100.0 * u / 6.0]);
            assert_terms_eq(past_terms, [e, 0.0, u, 100.0 * u / 6.0]);
            assert_eq!(at_edge, past_edge);
        }
        // The change of error saturates the same way: from 300 N, a jump to −300 N is E = 600 N
        // and EC = 600 N, exactly the change range (6); a jump to −6000 N is 63 times as much.
        let (at_edge, edge_terms) = request_at(&[300.0, -300.0]);
        let (past_edge, past_terms) = request_at(&[300.0, -6000.0]);
        assert_terms_eq(edge_terms, [6.0, 6.0, 6.0, 100.0]);
        assert_terms_eq(past_terms, [6.0, 6.0, 6.0, 100.0]);
        assert_eq!(at_edge, past_edge);
    }

    fn assert_terms_eq(actual: [f64; 4], expected: [f64; 4]) {
        for (a, e) in actual.into_iter().zip(expected) {
            assert_close(a, e, &format!("{actual:?} vs {expected:?}"));
        }
    }

    #[test]
    fn the_increment_never_exceeds_the_output_range() {
        // U lies in the output universe [−6, 6], so |Δa_f| ≤ the output range whatever the force;
        // the override itself is the safety envelope's to limit (see `law`). The bound is reached
        // at the saturated corners with eq 7 and approached but not reached with the centroid.
        let mut rng = Rng::seed_from(11);
        for base in RuleBase::ALL {
            // A weighted sum adds the rules' values up: it is not bounded by the universe.
            let bounded = Defuzzifier::ALL
                .into_iter()
                .filter(|d| *d != Defuzzifier::WeightedSum);
            for defuzzifier in bounded {
                let p = params(100.0, 200.0, 37.0);
                let mut c = FuzzyController::new(&base.table(), defuzzifier, p).unwrap();
                let mut largest: f64 = 0.0;
                for k in 0..2000 {
                    let force = match k % 5 {
                        0 => TARGET_N + 1e6 * (rng.uniform() - 0.5),
                        1 => [0.0, 600.0, -1e9, 1e9][(k / 5) % 4],
                        _ => TARGET_N * 2.0 * rng.uniform(),
                    };
                    let applied = 255.0 * rng.uniform();
                    let request = c.step(&input(force, applied));
                    let delta = request - applied;
                    assert!(
                        delta.abs() <= 37.0 + 1e-9,
                        "{base:?}/{defuzzifier:?}: Δ {delta} at {force} N"
                    );
                    largest = largest.max(delta.abs());
                }
                if defuzzifier == Defuzzifier::WeightedAverage {
                    assert_close(largest, 37.0, &format!("{base:?}: largest Δ"));
                } else {
                    assert!(largest > 0.5 * 37.0, "{base:?}/{defuzzifier:?}: {largest}");
                }
            }
        }
    }

    #[test]
    fn the_exposed_terms_and_activations_are_the_values_the_law_used() {
        let mut rng = Rng::seed_from(5);
        for defuzzifier in Defuzzifier::ALL {
            let p = params(80.0, 150.0, 60.0);
            let mut c = FuzzyController::new(&RuleBase::Dynamics.table(), defuzzifier, p).unwrap();
            let mut previous_error_n = None;
            for _ in 0..300 {
                let target = 100.0 + 400.0 * rng.uniform();
                let force = target * (0.5 + rng.uniform());
                let applied = 50.0 + 100.0 * rng.uniform();
                let request = c.step(&ControlInput {
                    target_force_n: target,
                    ..input(force, applied)
                });
                // Recomputed from the documented law, independently of the controller's state.
                let error_n = target - force;
                let change_n = error_n - previous_error_n.unwrap_or(error_n);
                previous_error_n = Some(error_n);
                let e = (6.0 / (target * 0.8) * error_n).clamp(-6.0, 6.0);
                let ec = (6.0 / (target * 1.5) * change_n).clamp(-6.0, 6.0);
                let [te, tec, tu, tdelta] = terms(&c);
                assert_close(te, e, "E term");
                assert_close(tec, ec, "EC term");
                // The engine evaluated at the exposed inputs gives, bit for bit, the exposed U
                // and the exposed rule activations.
                let mut engine = c.engine().clone();
                let mut u = [0.0];
                engine.evaluate(&[te, tec], &mut u);
                assert_eq!(tu.to_bits(), u[0].to_bits(), "U term");
                assert_close(tdelta, u[0] / 6.0 * 60.0, "Δ term");
                assert_eq!(
                    (request - applied).to_bits(),
                    ((applied + tdelta) - applied).to_bits()
                );
                assert_close(request - applied, tdelta, "Δ applied");
                assert_eq!(c.rule_activations(), Some(engine.activations()));
            }
        }
    }

    /// An engine on universes of its own: E on [0, 10], EC on [−1, 3], U on [0, 20]; one rule
    /// that always fires, so U is the centre of its only term (weighted average).
    fn shifted(u_term_centre: f64, default: &str) -> Engine {
        crate::control::fuzzy::fll::parse(&format!(
            "Engine: shifted\nInputVariable: load\n  range: 0 10\n  term: all Rectangle 0 10\n\
             InputVariable: trend\n  range: -1 3\n  term: all Rectangle -1 3\n\
             OutputVariable: feed\n  range: 0 20\n  defuzzifier: WeightedAverage\n\
             default: {default}\n  term: here Triangle {} {u_term_centre} {}\n\
             RuleBlock: \n  conjunction: Minimum\n  rule: if load is all and trend is all then feed is here\n",
            u_term_centre - 1.0,
            u_term_centre + 1.0
        ))
        .unwrap()
    }

    #[test]
    fn e_and_ec_map_onto_the_first_and_second_inputs_universes_and_u_from_the_outputs() {
        // E = +50 N on a 300 N target with an error range of 100 %: a sixth of the way from the
        // centre 5 to the edge 10 of [0, 10]: 5 + 5 · 50/300. EC's universe [−1, 3] has centre 1
        // and half-width 2: the first step's EC = 0 is 1.
        let mut c = FuzzyController::from_engine(shifted(15.0, "0"), paper()).unwrap();
        let request = c.step(&input(250.0, 100.0));
        let [e, ec, u, delta] = terms(&c);
        assert_close(e, 5.0 + 5.0 * 50.0 / 300.0, "E on [0, 10]");
        assert_close(ec, 1.0, "EC at its centre");
        // U = 15 on [0, 20] (centre 10, half-width 10) is half the output range: +50 %.
        assert_close(u, 15.0, "U");
        assert_close(delta, 50.0, "Δ");
        assert_close(request, 150.0, "request");
        // EC = 100 N − 50 N = 50 N against a change range of 200 % of 300 N: 1 + 2 · 50/600.
        c.step(&input(300.0, 100.0));
        assert_close(terms(&c)[1], 1.0 - 2.0 * 50.0 / 600.0, "EC on [−1, 3]");
        // Beyond the ranges the inputs saturate at the universes' edges.
        c.step(&input(-5000.0, 100.0));
        assert_close(terms(&c)[0], 10.0, "E saturated");
        assert_close(terms(&c)[1], 3.0, "EC saturated");
        // An engine that answers NaN (its default, when no rule fires: here E's only term lies
        // at the far end of its universe) holds the override.
        let far = crate::control::fuzzy::fll::write(&shifted(15.0, "nan"))
            .replace("Rectangle 0 10", "Rectangle 9 10");
        let engine = crate::control::fuzzy::fll::parse(&far).unwrap();
        let mut quiet = FuzzyController::from_engine(engine, paper()).unwrap();
        assert_eq!(quiet.step(&input(300.0, 87.0)), 87.0);
        assert!(terms(&quiet)[2].is_nan());
        assert_eq!(terms(&quiet)[3], 0.0);
    }

    #[test]
    fn a_non_finite_force_holds_the_override_and_the_error_history() {
        let mut c = controller(paper());
        c.step(&input(300.0, 100.0)); // E = 0
        for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
            assert_eq!(c.step(&input(bad, 123.0)), 123.0);
            // The plot of a held period shows no inputs, no increment and no rule firing.
            let held = terms(&c);
            assert!(held[..3].iter().all(|v| v.is_nan()), "{held:?}");
            assert_eq!(held[3], 0.0);
            assert!(c.rule_activations().is_none());
        }
        // EC is measured from the last finite error (0 N), not from the held periods.
        c.step(&input(200.0, 100.0));
        assert_terms(&c, [2.0, 1.0, 3.0, 50.0], "after the hold");
        // After a reset the first step has no earlier error again: EC = 0.
        c.reset();
        assert_eq!(terms(&c), [0.0; 4]);
        // (Without the reset, 250 N after 200 N would be EC = 50 N − 100 N → −0.5.)
        c.step(&input(250.0, 100.0));
        assert_terms(&c, [1.0, 0.0, 1.0, 100.0 / 6.0], "after a reset");
    }
}
