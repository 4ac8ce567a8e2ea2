//! Lessons: every shipped lesson reads, each step's reference solution meets its check on the
//! simulated lab and its starting point does not (no check is vacuous), and a malformed lesson is
//! refused with its file, line and field — by the library and by `cutlab lesson check`.
#![cfg(feature = "cli")]
// Test code: unwrapping and panicking on a broken expectation is the point.
#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)]

mod common;

use cutlab::lessons::native::Checker;
use cutlab::lessons::shipped::{shipped, SHIPPED};
use cutlab::lessons::{Lesson, StepCheck};

#[test]
fn every_file_in_www_lessons_is_shipped_and_reads() {
    let mut files: Vec<String> = std::fs::read_dir("www/lessons")
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .filter(|name| name.ends_with(".json"))
        .collect();
    files.sort();
    let mut listed: Vec<String> = SHIPPED.iter().map(|(f, _)| f.to_string()).collect();
    listed.sort();
    assert_eq!(files, listed);
    let lessons: Vec<Lesson> = shipped().into_iter().map(|l| l.unwrap()).collect();
    assert_eq!(lessons.len(), 10);
    let mut ids: Vec<&str> = lessons.iter().map(|l| l.id.as_str()).collect();
    ids.sort_unstable();
    ids.dedup();
    assert_eq!(ids.len(), 10, "lesson ids are unique");
    // Every file is named after its lesson's id, so a link and a file agree.
    for ((file, _), lesson) in SHIPPED.iter().zip(&lessons) {
        assert_eq!(*file, format!("{}.json", lesson.id));
    }
    // The papers are all walked.
    for paper in cutlab::lessons::PAPERS {
        assert!(
            lessons.iter().any(|l| l.paper == paper),
            "no lesson on paper {paper}"
        );
    }
}

#[test]
fn every_reference_solution_meets_its_check_and_no_starting_point_does() {
    let checker = Checker::new();
    let mut checked = 0;
    for lesson in shipped().into_iter().map(|l| l.unwrap()) {
        for (i, step) in lesson.steps.iter().enumerate() {
            let StepCheck::Conditions { solution, .. } = &step.check else {
                continue;
            };
            let done = checker.check_step(&lesson, i, solution).unwrap().unwrap();
            assert!(
                done.met(),
                "{} step {}: solution {:?}",
                lesson.id,
                i + 1,
                done.outcomes
            );
            let start = checker
                .check_step(&lesson, i, &step.setup)
                .unwrap()
                .unwrap();
            assert!(
                !start.met(),
                "{} step {}: the starting point meets the check: {:?}",
                lesson.id,
                i + 1,
                start.outcomes
            );
            // Each outcome says what was measured, with its unit where it has one.
            for outcome in &done.outcomes {
                assert_ne!(outcome.measured, "not measured", "{}", outcome.wants);
            }
            checked += 1;
        }
    }
    assert!(checked >= 10, "only {checked} steps with conditions");
}

/// The error the library gives for fixture `name`, as `file:line: field: message`.
fn refusal(name: &str) -> String {
    let file = format!("tests/data/lessons/{name}");
    let text = std::fs::read_to_string(&file).unwrap();
    Lesson::from_json(&text, &file).unwrap_err().to_string()
}

#[test]
fn a_malformed_lesson_is_refused_with_its_file_line_and_field() {
    let syntax = refusal("syntax-error.json");
    assert!(
        syntax.starts_with("tests/data/lessons/syntax-error.json:6: expected `,`"),
        "{syntax}"
    );
    let wrong_type = refusal("wrong-type.json");
    assert!(
        wrong_type.starts_with("tests/data/lessons/wrong-type.json:11: invalid type: string"),
        "{wrong_type}"
    );
    let metric = refusal("unknown-metric.json");
    assert!(
        metric.starts_with(
            "tests/data/lessons/unknown-metric.json:14: steps[0].check.conditions[1].metric: \
             \"force_error_percent\" is not a metric; metrics: "
        ),
        "{metric}"
    );
    let replay = refusal("unknown-replay-value.json");
    assert!(
        replay.starts_with(
            "tests/data/lessons/unknown-replay-value.json:14: steps[0].check.conditions[1].replay: \
             \"override_steps\" is not a value of a replay; values: periods, end_time_s, "
        ),
        "{replay}"
    );
    assert_eq!(
        refusal("replay-without-controller.json"),
        "tests/data/lessons/replay-without-controller.json:13: steps[0].check.conditions[0].of: a \
         replay condition names the controller replayed: of (threshold, pi, …)"
    );
    let setting = refusal("unknown-setting.json");
    assert_eq!(
        setting,
        "tests/data/lessons/unknown-setting.json:16: steps[0].solution: \"k_p\" is not a \
         setting of the simulate page"
    );
}

#[test]
fn lesson_check_names_each_problem_and_fails_and_passes_a_good_lesson() {
    let (result, out) = common::cutlab_text(
        &[
            "lesson",
            "check",
            "tests/data/lessons/unknown-metric.json",
            "tests/data/lessons/vacuous.json",
        ],
        "",
    );
    assert_eq!(result.unwrap_err(), "2 problems in 2 of 2 lesson files");
    assert!(
        out.contains(
            "tests/data/lessons/unknown-metric.json:14: steps[0].check.conditions[1].metric: "
        ),
        "{out}"
    );
    assert!(
        out.contains(
            "tests/data/lessons/vacuous.json:9: steps[0].setup: the starting point already meets \
             the check, so it checks nothing: time above limit at most 1 s: 0.72 s"
        ),
        "{out}"
    );
    let (result, out) = common::cutlab_text(
        &["lesson", "check", "www/lessons/filtering-and-rms.json"],
        "",
    );
    assert!(result.is_ok(), "{result:?}\n{out}");
    assert!(
        out.contains("step 2: the solution meets the check"),
        "{out}"
    );
    // A replay's check is run natively on the sample log, through the Logs page's replays.
    let (result, out) = common::cutlab_text(&["lesson", "check", "www/lessons/own-log.json"], "");
    assert!(result.is_ok(), "{result:?}\n{out}");
    // The counts docs/lessons.md and the step's explanation quote are the tool's.
    assert!(
        out.contains(
            "step 4: the solution meets the check (override changes of the PI with anti-windup \
             replay below that of the Threshold-proportional replay: 27 vs 29 for the \
             Threshold-proportional replay)"
        ),
        "{out}"
    );
    let own_log = shipped()
        .into_iter()
        .map(|l| l.unwrap())
        .find(|l| l.id == "own-log")
        .unwrap();
    assert!(own_log.steps[3]
        .explain
        .contains("(27 against 29 on the sample export"));
    let (result, out) = common::cutlab_text(
        &[
            "lesson",
            "check",
            "tests/data/lessons/unknown-replay-value.json",
        ],
        "",
    );
    assert!(result.is_err(), "{out}");
    assert!(
        out.contains("unknown-replay-value.json:14: steps[0].check.conditions[1].replay: "),
        "{out}"
    );
}

/// The shipped lesson `id`.
fn lesson(id: &str) -> Lesson {
    shipped()
        .into_iter()
        .map(|l| l.unwrap())
        .find(|l| l.id == id)
        .unwrap()
}

#[test]
fn a_teachers_mistakes_are_refused_at_their_field() {
    // A solution on another page is refused for that, not for a key the other page reads.
    assert_eq!(
        refusal("solution-other-page.json"),
        "tests/data/lessons/solution-other-page.json:33: steps[1].solution: the solution is on \
         the compare page, the step on the simulate page: a solution is the step's own page, as \
         the student leaves it"
    );
    // A solution on another preset checks another experiment than the student's.
    assert_eq!(
        refusal("solution-other-preset.json"),
        "tests/data/lessons/solution-other-preset.json:33: steps[1].solution: the solution's \
         preset is \"kim-step-doc\", the setup's \"maneerat-doc-2\": a solution solves the step's \
         own experiment, so give the same preset"
    );
    // One run on Simulate: "cycle time of A below that of A" compared a run with itself.
    assert_eq!(
        refusal("than-on-simulate.json"),
        "tests/data/lessons/than-on-simulate.json:29: steps[1].check.conditions[0].than: than \
         compares one Compare variant with another; the simulate page has one run, so give a \
         value instead"
    );
    assert_eq!(
        refusal("no-choices.json"),
        "tests/data/lessons/no-choices.json:12: steps[0].check.choices: a question needs at \
         least two choices; this one has 0"
    );
}

#[test]
fn lesson_check_refuses_a_lesson_not_named_after_its_file() {
    let (result, out) = common::cutlab_text(
        &["lesson", "check", "tests/data/lessons/named-otherwise.json"],
        "",
    );
    assert!(result.is_err(), "{out}");
    assert!(
        out.contains(
            "tests/data/lessons/named-otherwise.json:2: id: the lesson \"pi-gain\" is in a file \
             named named-otherwise.json: name it pi-gain.json, as the lab finds it"
        ),
        "{out}"
    );
}

#[test]
fn own_log_steps_keep_the_log_the_student_opened_and_name_what_to_click() {
    use cutlab::lessons::setup::Setup;
    use cutlab::log::link::SAMPLES;
    let own_log = lesson("own-log");
    // Step 1 names the button the Logs page shows, not a file name it never shows.
    let (file, label) = SAMPLES[0];
    assert!(
        own_log.steps[0].task.contains(label),
        "{}",
        own_log.steps[0].task
    );
    assert!(!own_log.steps[0].task.contains(file));
    // The address the Logs page writes once the sample is open and S_Strom is grouped by Phase.
    let analysed = format!("#/logs?sample={file}&column=S_Strom%20%5BA%5D&by=Phase");
    for step in &own_log.steps[1..3] {
        // The next step keeps that analysis ("in the same analysis")…
        assert!(step.setup.held_by(&analysed), "{}", step.setup.link());
        // …and a reload from the lesson's link opens the sample again.
        assert_eq!(step.setup.value("sample"), Some(file));
        assert!(!step.setup.held_by("#/logs"));
    }
    // Step 4 sets up its replay form over it.
    assert!(!own_log.steps[3].setup.held_by(&analysed));
    // A run page is reset to the step's starting point when the student changed a setting.
    let simulate = Setup::from_link("#/simulate?preset=kim-step-doc&controller=fixed").unwrap();
    assert!(!simulate.held_by("#/simulate?preset=kim-step-doc&controller=fixed&override=70"));
}

#[test]
fn current_as_force_says_what_its_check_measures_and_why_a_controller_fails() {
    use cutlab::lessons::setup::Setup;
    let lesson = lesson("current-as-force");
    let step = &lesson.steps[1];
    assert!(
        step.task.contains("try another controller"),
        "{}",
        step.task
    );
    let checker = Checker::new();
    let run = |controller: &str| {
        let link = format!("#/simulate?preset=kim-step-doc&controller={controller}");
        checker
            .check_step(&lesson, 1, &Setup::from_link(&link).unwrap())
            .unwrap()
            .unwrap()
    };
    // The hint says PI and MRAC at their defaults stay above the limit too long, and the
    // threshold law meets the bound: the check agrees.
    for slow in ["pi", "mrac"] {
        let out = run(slow);
        assert!(!out.met(), "{slow}: {:?}", out.outcomes);
        assert!(step
            .hints
            .iter()
            .any(|h| h.contains("PI") && h.contains("MRAC")));
    }
    assert!(run("threshold").met());
}

#[test]
fn a_metric_not_measured_says_why() {
    use cutlab::lessons::setup::Setup;
    let lesson = lesson("adaptive-convergence");
    // The reviewer's γ₃ = 500: "measured not measured" with no reason.
    let link = "#/simulate?preset=maneerat-doc-2&controller=mrac&gamma_beta_pct_per_s=500";
    let out = Checker::new()
        .check_step(&lesson, 1, &Setup::from_link(link).unwrap())
        .unwrap()
        .unwrap();
    let settling = &out.outcomes[0];
    assert_eq!(settling.value, None, "{settling:?}");
    assert!(
        settling.measured.starts_with("not measured: "),
        "{}",
        settling.measured
    );
    assert_eq!(
        settling.measured,
        "not measured: the force never settled after a depth step"
    );
}

#[test]
fn step_titles_say_what_their_task_asks() {
    let tuning = lesson("tuning-trade-off");
    assert_eq!(
        tuning.steps[1].title,
        "Trade a second of cycle time for accuracy"
    );
    assert!(tuning.steps[1]
        .task
        .contains("at most about a second longer"));
}
