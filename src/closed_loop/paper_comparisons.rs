//! The comparisons the papers make, as runs the lab repeats: each states the paper's claim, and
//! its finding is *measured* from the runs just made — never a sentence written beforehand that
//! an edit, a new seed or a changed model could silently contradict. The Compare page offers each
//! one click away; `tests/closed_loop.rs` holds the verdicts docs/papers.md reports, and
//! `tests/docs.rs` writes docs/papers.md's grid for paper 002 through the same judgement
//! ([`fig_7_judgement`]).

use super::definition::RunSpec;
use super::definition::{parse_texts, RunSetting, SettingError};
use super::lab::RunResult;
use super::metrics::FLUCTUATION_WINDOW_S;
use super::paper_defaults::preset_controller;
use super::summary::format_metric;
use crate::control::registry::ControllerKind;
use crate::plant::Preset;

/// What the runs show about a claim.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    /// The measured figures, in a sentence.
    pub measured: String,
    /// Whether they bear the claim out; `None` where the figures speak for themselves (no
    /// yes/no question in the claim) or are not all there yet (savings still to come).
    pub reproduced: Option<bool>,
}

impl Finding {
    /// The sentence a page shows: the figures, then the verdict.
    pub fn text(&self) -> String {
        match self.reproduced {
            Some(true) => format!("Measured: {} Reproduced.", self.measured),
            Some(false) => format!("Measured: {} Not reproduced.", self.measured),
            None => format!("Measured: {}", self.measured),
        }
    }
}

/// One comparison a paper makes.
pub struct PaperComparison {
    /// The button's label.
    pub label: &'static str,
    /// The experiment.
    pub preset: Preset,
    /// The controllers compared, in the order of the runs `judge` takes.
    pub controllers: &'static [ControllerKind],
    /// Settings other than the preset's, as typed in a form.
    pub settings: &'static [(RunSetting, &'static str)],
    /// What the paper claims, with its figure.
    pub claim: &'static str,
    /// What the runs (one per controller, in order) show.
    pub judge: fn(&[&RunResult]) -> Finding,
}

impl PaperComparison {
    /// The runs: one per controller at the preset's (or the paper's) defaults, with the
    /// comparison's settings, seed 1.
    pub fn specs(&self) -> Result<Vec<RunSpec>, Vec<SettingError>> {
        self.controllers
            .iter()
            .map(|&kind| {
                parse_texts(
                    self.preset,
                    preset_controller(self.preset, kind),
                    self.settings,
                )
            })
            .collect()
    }

    /// The finding of `runs`, if they are this comparison's: one per controller, in order, on its
    /// preset. `None` for other runs (the user has changed the comparison since).
    pub fn finding(&self, runs: &[&RunResult]) -> Option<Finding> {
        let matches = runs.len() == self.controllers.len()
            && runs
                .iter()
                .zip(self.controllers)
                .all(|(r, k)| r.spec.preset == self.preset && r.spec.controller.kind() == *k);
        matches.then(|| (self.judge)(runs))
    }
}

/// Every comparison, in the order a page lists them.
pub const PAPER_COMPARISONS: [PaperComparison; 7] = [
    PaperComparison {
        label: "Paper 003: fixed feed vs threshold control over DOC steps",
        preset: Preset::KimStepDoc,
        controllers: &[ControllerKind::Fixed, ControllerKind::Threshold],
        settings: &[],
        claim: "Paper 003 (Fig. 10): the threshold law holds the force through the depth steps \
                that a fixed feed follows.",
        judge: holds_better_than_fixed,
    },
    PaperComparison {
        label: "Paper 003: across the material change",
        preset: Preset::KimMaterialTaper,
        controllers: &[ControllerKind::Fixed, ControllerKind::Threshold],
        settings: &[],
        claim: "Paper 003 (Fig. 11): the controller speeds up in the aluminium section and so \
                finishes sooner than a fixed feed safe for the steel.",
        judge: speeds_up_where_the_cut_is_light,
    },
    PaperComparison {
        label: "Paper 002: experience vs dynamics rules, sampled every 0.1 s",
        preset: Preset::LiuCurrentStep,
        controllers: &[
            ControllerKind::FuzzyExperience,
            ControllerKind::FuzzyDynamics,
        ],
        settings: &[(RunSetting::ControlPeriod, "0.1")],
        claim: PAPER_002_CLAIM,
        judge: dynamics_rules_settle_sooner,
    },
    PaperComparison {
        label: "Paper 002: experience vs dynamics rules, sampled every 0.2 s",
        preset: Preset::LiuCurrentStep,
        controllers: &[
            ControllerKind::FuzzyExperience,
            ControllerKind::FuzzyDynamics,
        ],
        settings: &[(RunSetting::ControlPeriod, "0.2")],
        claim: PAPER_002_CLAIM,
        judge: dynamics_rules_settle_sooner,
    },
    PaperComparison {
        label: "Paper 001: adaptive control at DOC 4 mm",
        preset: Preset::ManeeratDoc4,
        controllers: &[
            ControllerKind::Fixed,
            ControllerKind::Mrac,
            ControllerKind::Pi,
        ],
        settings: &[],
        claim: "Paper 001 (Fig. 9): the adaptive law converges to the 320 N target.",
        judge: adaptive_law_converges,
    },
    PaperComparison {
        label: "Paper 001's own model with a dynamometer",
        preset: Preset::ManeeratSecondOrder,
        controllers: &[
            ControllerKind::Fixed,
            ControllerKind::Mrac,
            ControllerKind::Pi,
        ],
        settings: &[],
        claim: "Paper 001's second-order process (eq 2.3) with the force read by a dynamometer, \
                as in its experiments: the adaptive law converges to the target.",
        judge: adaptive_law_converges,
    },
    PaperComparison {
        label: "Paper 000 vs 003: restriction vs threshold vs PI",
        preset: Preset::KimCircularTaper,
        controllers: &[
            ControllerKind::Restriction,
            ControllerKind::Threshold,
            ControllerKind::Pi,
        ],
        settings: &[],
        claim: "Paper 000 holds the current between two limits by stepping the override; \
                paper 003 moves it in proportion to the excess beyond its thresholds; PI acts on \
                the error itself. Neither paper compares them: the lab measures how closely each \
                holds the force and how often it moves the override.",
        judge: how_each_holds_the_force,
    },
];

/// Paper 002's Fig. 7 as the lab reads it: the paper's scalings with EC in A/s (Table 2) and k_u
/// added each sampling period (eq 1), the preset's defaults. docs/papers.md has the grid over
/// these readings, the periods and the step sizes that shows where the claim holds.
const PAPER_002_CLAIM: &str = "Paper 002 (Fig. 7): after a step in load the dynamics-based rules \
    bring the current back to the reference sooner than the experience-based ones, with small \
    fluctuation (its scalings, EC in A/s as in Table 2, k_u added each sampling period).";

/// A number as a finding writes it: as the metrics table shows it, "—" if not finite.
fn figure(v: f64) -> String {
    if v.is_finite() {
        format_metric(v)
    } else {
        "—".to_string()
    }
}

fn name(r: &RunResult) -> &'static str {
    r.spec.controller.kind().name()
}

/// Paper 003's claim: the controller's mean force error is far below the fixed feed's.
fn holds_better_than_fixed(runs: &[&RunResult]) -> Finding {
    let [fixed, controlled] = runs else {
        return incomplete();
    };
    let (f, c) = (&fixed.metrics, &controlled.metrics);
    Finding {
        measured: format!(
            "mean force error {} % with {} against {} % at the fixed feed; {} s above the force \
             limit against {} s.",
            figure(c.force_mean_abs_error_pct),
            name(controlled),
            figure(f.force_mean_abs_error_pct),
            figure(c.time_above_limit_s),
            figure(f.time_above_limit_s),
        ),
        reproduced: Some(c.force_mean_abs_error_pct < 0.5 * f.force_mean_abs_error_pct),
    }
}

/// Paper 003's material change: the controller raises the override above 100 % where the cut is
/// light and saves time against the safe fixed feed.
fn speeds_up_where_the_cut_is_light(runs: &[&RunResult]) -> Finding {
    let [_, controlled] = runs else {
        return incomplete();
    };
    let highest = controlled
        .trace
        .rows
        .iter()
        .filter(|r| r.armed)
        .map(|r| r.override_pct)
        .fold(f64::NAN, f64::max);
    let saving = controlled.metrics.saving_vs_safe_fixed_pct;
    Finding {
        measured: match saving {
            Some(s) => format!(
                "{} reaches {} % override and finishes {} % sooner than the fastest fixed feed \
                 that keeps the peak force at the target.",
                name(controlled),
                figure(highest),
                figure(s)
            ),
            None => format!(
                "{} reaches {} % override; the saving against a safe fixed feed follows once \
                 the reference runs are done.",
                name(controlled),
                figure(highest)
            ),
        },
        reproduced: saving.map(|s| highest > 100.0 && s > 0.0),
    }
}

/// Below this, a force's fluctuation is the noise of the simulation, not the controller's: two
/// runs both under it fluctuate alike.
const NEGLIGIBLE_FLUCTUATION_PCT: f64 = 0.05;

/// How long the force must stay inside the settling band before its step's window ends for the
/// step to count as settled: a force that enters the band in the last periods of a limit cycle
/// has not shown that it stays.
pub const SETTLED_FOR_S: f64 = 2.0;

/// The longest settling time over `r`'s steps, each backed by [`SETTLED_FOR_S`] inside the band;
/// `None` if a step never settled so (or there is no step).
fn settled_after_steps_s(r: &RunResult) -> Option<f64> {
    let end_s = r.trace.rows.last()?.time_s;
    let steps = &r.metrics.steps;
    let mut longest: Option<f64> = None;
    for (k, step) in steps.iter().enumerate() {
        let window_end_s = steps.get(k + 1).map_or(end_s, |next| next.time_s);
        let settled = step
            .settling_time_s
            .filter(|t| step.time_s + t + SETTLED_FOR_S <= window_end_s)?;
        longest = Some(longest.map_or(settled, |l| l.max(settled)));
    }
    longest
}

/// One settling time is clearly sooner than another at this fraction of it or less (a fifth
/// sooner); closer times are read as alike.
pub const CLEARLY_SOONER: f64 = 0.8;

/// Paper 002's Fig. 7 judged on a pair of runs (experience-based rules, dynamics-based rules):
/// the figures the Compare page's finding states and docs/papers.md's grid tabulates, and the
/// verdict on them. One definition, so the page and the docs cannot read the runs differently.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Fig7Judgement {
    /// When the experience rules' force settled after the load step(s) and stayed
    /// ([`SETTLED_FOR_S`]), s after the step; `None`: never before the run's end.
    pub experience_settling_s: Option<f64>,
    /// The same for the dynamics rules.
    pub dynamics_settling_s: Option<f64>,
    /// The experience rules' force fluctuation over the last [`FLUCTUATION_WINDOW_S`] of the
    /// cut, % of the target.
    pub experience_fluctuation_pct: f64,
    /// The same for the dynamics rules.
    pub dynamics_fluctuation_pct: f64,
    /// Both fluctuate less than the simulation's noise: neither fluctuates more.
    pub both_steady: bool,
    /// Fig. 7's claim holds: the dynamics rules settle clearly sooner (in [`CLEARLY_SOONER`] of
    /// the experience rules' time at most, or where those never settle) and fluctuate no more.
    pub holds: bool,
}

/// Judges Fig. 7's claim on a run of each rule table (same preset, settings and seed).
///
/// ```
/// use cutlab::closed_loop::definition::RunSpec;
/// use cutlab::closed_loop::lab::simulate;
/// use cutlab::closed_loop::paper_comparisons::fig_7_judgement;
/// use cutlab::control::registry::ControllerKind;
/// use cutlab::plant::Preset;
/// let run = |kind| {
///     let mut spec = RunSpec::new(Preset::LiuCurrentStep, kind);
///     spec.settings.control_period_s = Some(0.1);
///     simulate(&spec).unwrap()
/// };
/// let judged = fig_7_judgement(
///     &run(ControllerKind::FuzzyExperience),
///     &run(ControllerKind::FuzzyDynamics),
/// );
/// // At 0.1 s the experience table keeps cycling; the dynamics table settles within 10 s.
/// assert!(judged.holds && judged.experience_settling_s.is_none());
/// assert!(judged.dynamics_settling_s.unwrap() < 10.0);
/// assert!(judged.experience_fluctuation_pct > 5.0 && judged.dynamics_fluctuation_pct < 0.5);
/// ```
pub fn fig_7_judgement(experience: &RunResult, dynamics: &RunResult) -> Fig7Judgement {
    let (e_settle, d_settle) = (
        settled_after_steps_s(experience),
        settled_after_steps_s(dynamics),
    );
    let (e_wobble, d_wobble) = (
        experience.metrics.late_force_fluctuation_pct,
        dynamics.metrics.late_force_fluctuation_pct,
    );
    let settles_sooner = match (e_settle, d_settle) {
        (_, None) => false,
        (None, Some(_)) => true,
        (Some(e), Some(d)) => d <= CLEARLY_SOONER * e,
    };
    let both_steady =
        e_wobble < NEGLIGIBLE_FLUCTUATION_PCT && d_wobble < NEGLIGIBLE_FLUCTUATION_PCT;
    let fluctuates_no_more = both_steady || d_wobble <= e_wobble;
    Fig7Judgement {
        experience_settling_s: e_settle,
        dynamics_settling_s: d_settle,
        experience_fluctuation_pct: e_wobble,
        dynamics_fluctuation_pct: d_wobble,
        both_steady,
        holds: settles_sooner && fluctuates_no_more,
    }
}

/// Paper 002's Fig. 7 on the Compare page: [`fig_7_judgement`]'s figures and verdict.
fn dynamics_rules_settle_sooner(runs: &[&RunResult]) -> Finding {
    let [experience, dynamics] = runs else {
        return incomplete();
    };
    let judged = fig_7_judgement(experience, dynamics);
    let settle_text = |t: Option<f64>| match t {
        Some(t) => format!("{} s", figure(t)),
        None => "never".to_string(),
    };
    Finding {
        measured: format!(
            "after the load step the dynamics rules settle to ±{} % in {} against {} for the \
             experience rules; over the last {} s the force fluctuates {} % against {} % of \
             the target{}.",
            figure(dynamics.metrics.settling_band_pct),
            settle_text(judged.dynamics_settling_s),
            settle_text(judged.experience_settling_s),
            figure(FLUCTUATION_WINDOW_S),
            figure(judged.dynamics_fluctuation_pct),
            figure(judged.experience_fluctuation_pct),
            if judged.both_steady {
                " (both steady)"
            } else {
                ""
            }
        ),
        reproduced: Some(judged.holds),
    }
}

/// Paper 001: the adaptive law (the second run) holds the target within 10 % mean error; the
/// entry peak is reported beside the fixed feed's, since the paper does not show its entry.
fn adaptive_law_converges(runs: &[&RunResult]) -> Finding {
    let [fixed, adaptive, ..] = runs else {
        return incomplete();
    };
    let (f, a) = (&fixed.metrics, &adaptive.metrics);
    let target = adaptive.settings.target_force_n;
    Finding {
        measured: format!(
            "{} holds {} N with {} % mean force error (the fixed feed {} %); its peak is {} N \
             (+{} %) against the fixed feed's {} N.",
            name(adaptive),
            figure(target),
            figure(a.force_mean_abs_error_pct),
            figure(f.force_mean_abs_error_pct),
            figure(a.peak_force_n),
            figure(100.0 * (a.peak_force_n / target - 1.0)),
            figure(f.peak_force_n),
        ),
        reproduced: Some(a.completed && a.force_mean_abs_error_pct < 10.0),
    }
}

/// Paper 000 against 003 against PI: no claim to judge, the figures side by side.
fn how_each_holds_the_force(runs: &[&RunResult]) -> Finding {
    let list = |value: fn(&RunResult) -> String| {
        runs.iter()
            .map(|r| format!("{} {}", name(r), value(r)))
            .collect::<Vec<_>>()
            .join(", ")
    };
    Finding {
        measured: format!(
            "mean force error {}; override changes {}.",
            list(|r| format!("{} %", figure(r.metrics.force_mean_abs_error_pct))),
            list(|r| r.metrics.override_changes.to_string()),
        ),
        reproduced: None,
    }
}

fn incomplete() -> Finding {
    Finding {
        measured: "the runs are not this comparison's.".to_string(),
        reproduced: None,
    }
}
