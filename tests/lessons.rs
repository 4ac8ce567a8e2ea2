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
