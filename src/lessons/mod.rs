//! Lessons: guided experiments on the lab with checks (schema in `docs/lessons.md`).
//!
//! A lesson is a JSON file in `www/lessons/`: an id, a title, what it teaches, the paper it comes
//! from, and steps. A step opens a page of the lab with a run definition — the link the lab
//! itself writes ([`setup::Setup`]) — asks a question or sets a task, offers hints one at a time,
//! and states its check: a multiple-choice answer, or conditions ([`check::StepCondition`]) on the
//! finished runs' metrics and definitions, on a Compare run's variants, on the Signal chain
//! page's filter, or on the Logs page's replays. A step with conditions carries a reference solution, another link, which
//! `cutlab lesson check` and the tests run to show the check can be met, while the step's own
//! starting point must not meet it.
//!
//! | file | what |
//! |---|---|
//! | [`setup`] | the page and run definition a step sets up, read by the lab's own parsers |
//! | [`check`] | conditions, and their evaluation on the runs or the filter |
//! | [`native`] | doing a step's work without a browser: the runs its setup defines, its filter, its replays |
//! | [`locate`] | the line of a field in a lesson's text, for messages |
//! | [`progress`] | a student's progress, as the browser keeps and exports it |
//! | [`shipped`] | the lessons in `www/lessons/`, built into the lab |
//!
//! A lesson file's every problem is a [`LessonError`]: `file:line: field: message`.

pub mod check;
pub mod locate;
pub mod native;
pub mod progress;
pub mod setup;
pub mod shipped;

use std::fmt;

use serde::Deserialize;

use check::{StepCondition, StepConditionText};
use locate::{line_of, path_text, PathPart};
use setup::{LabPage, Setup};

/// The papers a lesson can come from (`docs/papers`).
pub const PAPERS: [&str; 5] = ["000", "001", "002", "003", "004"];

/// A lesson, read and checked.
#[derive(Debug, Clone, PartialEq)]
pub struct Lesson {
    /// Its name in links (`#/lessons/current-as-force`) and in the saved progress.
    pub id: String,
    /// The title.
    pub title: String,
    /// What it teaches, in a sentence or two.
    pub teaches: String,
    /// The paper it walks ("000"–"004").
    pub paper: String,
    /// The steps, in order.
    pub steps: Vec<LessonStep>,
}

/// One step of a lesson.
#[derive(Debug, Clone, PartialEq)]
pub struct LessonStep {
    /// A short heading.
    pub title: String,
    /// The page and run definition the step opens.
    pub setup: Setup,
    /// The question or the task.
    pub task: String,
    /// Hints, opened one at a time.
    pub hints: Vec<String>,
    /// How the step is checked.
    pub check: StepCheck,
    /// What is said once the step is done: why the answer is what it is.
    pub explain: String,
}

/// How a step is checked.
#[derive(Debug, Clone, PartialEq)]
pub enum StepCheck {
    /// A multiple-choice question, checked in the page.
    Choice {
        /// The choices.
        choices: Vec<String>,
        /// The right one, from 0.
        answer: usize,
    },
    /// Conditions on the student's work, all to be met.
    Conditions {
        /// The conditions.
        conditions: Vec<StepCondition>,
        /// The reference solution: a setup that meets them.
        solution: Setup,
    },
}

/// A problem with a lesson file: where it is and what it is.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct LessonError {
    /// The file, as it was named.
    pub file: String,
    /// The line, from 1.
    pub line: usize,
    /// The field at fault (`steps[1].check.conditions[0].metric`); empty for the whole file.
    pub field: String,
    /// What is wrong.
    pub message: String,
}

impl fmt::Display for LessonError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.field.is_empty() {
            write!(f, "{}:{}: {}", self.file, self.line, self.message)
        } else {
            write!(
                f,
                "{}:{}: {}: {}",
                self.file, self.line, self.field, self.message
            )
        }
    }
}

impl std::error::Error for LessonError {}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct LessonText {
    id: String,
    title: String,
    teaches: String,
    paper: String,
    steps: Vec<StepText>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct StepText {
    title: String,
    setup: String,
    task: String,
    #[serde(default)]
    hints: Vec<String>,
    check: CheckText,
    #[serde(default)]
    solution: Option<String>,
    #[serde(default)]
    explain: String,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct CheckText {
    #[serde(default)]
    choices: Option<Vec<String>>,
    #[serde(default)]
    answer: Option<usize>,
    #[serde(default)]
    conditions: Option<Vec<StepConditionText>>,
}

/// The path to a field of step `step`.
fn step_path(step: usize, rest: &[&str]) -> Vec<PathPart> {
    let mut path = vec![PathPart::Field("steps".into()), PathPart::Index(step)];
    path.extend(rest.iter().map(|f| PathPart::Field((*f).to_string())));
    path
}

impl Lesson {
    /// Reads the lesson in `text` (the file `file`), checking every reference: each setup and
    /// solution is a link the lab reads, each condition names a metric or setting that exists
    /// and fits its step's page.
    ///
    /// ```
    /// use cutlab::lessons::Lesson;
    /// let text = r##"{"id": "x", "title": "T", "teaches": "t", "paper": "003",
    ///   "steps": [{"title": "s", "setup": "#/simulate?preset=kim-step-doc&controller=fixed",
    ///     "task": "Which?", "check": {"choices": ["a", "b"], "answer": 1}}]}"##;
    /// assert_eq!(Lesson::from_json(text, "x.json").unwrap().steps.len(), 1);
    /// let bad = text.replace("kim-step-doc", "kim");
    /// let e = Lesson::from_json(&bad, "x.json").unwrap_err();
    /// assert_eq!((e.line, e.field.as_str()), (2, "steps[0].setup"));
    /// ```
    pub fn from_json(text: &str, file: &str) -> Result<Lesson, LessonError> {
        let raw: LessonText = serde_json::from_str(text).map_err(|e| LessonError {
            file: file.to_string(),
            line: e.line(),
            field: String::new(),
            message: e
                .to_string()
                .split(" at line ")
                .next()
                .unwrap_or_default()
                .to_string(),
        })?;
        let error = |path: Vec<PathPart>, message: String| LessonError {
            file: file.to_string(),
            line: line_of(text, &path),
            field: path_text(&path),
            message,
        };
        let field = |name: &str| vec![PathPart::Field(name.to_string())];
        if raw.id.is_empty()
            || !raw
                .id
                .bytes()
                .all(|b| b.is_ascii_lowercase() || b.is_ascii_digit() || b == b'-')
        {
            return Err(error(
                field("id"),
                "an id is lower-case letters, digits and hyphens (it is part of a link)".into(),
            ));
        }
        if !PAPERS.contains(&raw.paper.as_str()) {
            return Err(error(
                field("paper"),
                format!(
                    "\"{}\" is not a paper; papers: {}",
                    raw.paper,
                    PAPERS.join(", ")
                ),
            ));
        }
        if raw.steps.is_empty() {
            return Err(error(
                field("steps"),
                "a lesson has at least one step".into(),
            ));
        }
        let mut steps = Vec::with_capacity(raw.steps.len());
        for (i, step) in raw.steps.into_iter().enumerate() {
            let setup = read_setup(&step.setup).map_err(|m| error(step_path(i, &["setup"]), m))?;
            let check = match (step.check.choices, step.check.conditions) {
                (Some(choices), None) => {
                    let answer = step.check.answer.ok_or_else(|| {
                        error(
                            step_path(i, &["check"]),
                            "a multiple-choice check names its answer (from 0)".into(),
                        )
                    })?;
                    if choices.len() < 2 {
                        return Err(error(
                            step_path(i, &["check", "choices"]),
                            format!(
                                "a question needs at least two choices; this one has {}",
                                choices.len()
                            ),
                        ));
                    }
                    if answer >= choices.len() {
                        return Err(error(
                            step_path(i, &["check", "answer"]),
                            format!(
                                "the answer is one of the {} choices, counted from 0",
                                choices.len()
                            ),
                        ));
                    }
                    if step.solution.is_some() {
                        return Err(error(
                            step_path(i, &["solution"]),
                            "a multiple-choice step's solution is its answer".into(),
                        ));
                    }
                    StepCheck::Choice { choices, answer }
                }
                (None, Some(texts)) => {
                    if step.check.answer.is_some() {
                        return Err(error(
                            step_path(i, &["check", "answer"]),
                            "an answer belongs to choices, not to conditions".into(),
                        ));
                    }
                    if texts.is_empty() {
                        return Err(error(
                            step_path(i, &["check", "conditions"]),
                            "a check has at least one condition".into(),
                        ));
                    }
                    let mut conditions = Vec::with_capacity(texts.len());
                    for (j, text) in texts.iter().enumerate() {
                        let at = |name: &str| {
                            let mut path = step_path(i, &["check", "conditions"]);
                            path.push(PathPart::Index(j));
                            path.push(PathPart::Field(name.to_string()));
                            path
                        };
                        let condition = text
                            .resolve()
                            .map_err(|(name, message)| error(at(name), message))?;
                        condition.fits(setup.page).map_err(|(name, m)| {
                            let mut path = step_path(i, &["check", "conditions"]);
                            path.push(PathPart::Index(j));
                            if !name.is_empty() {
                                path.push(PathPart::Field(name.to_string()));
                            }
                            error(path, m)
                        })?;
                        conditions.push(condition);
                    }
                    let solution_text = step.solution.ok_or_else(|| {
                        error(
                            step_path(i, &["solution"]),
                            "a step with conditions gives its reference solution (a link)".into(),
                        )
                    })?;
                    // The page first: a solution on another page would otherwise be refused for
                    // a key that page reads differently, which says nothing of the real mistake.
                    let at_solution = || step_path(i, &["solution"]);
                    let solution =
                        Setup::from_link(&solution_text).map_err(|m| error(at_solution(), m))?;
                    if solution.page != setup.page {
                        return Err(error(
                            at_solution(),
                            format!(
                                "the solution is on the {} page, the step on the {} page: a \
                                 solution is the step's own page, as the student leaves it",
                                solution.page.slug(),
                                setup.page.slug()
                            ),
                        ));
                    }
                    solution.define().map_err(|m| error(at_solution(), m))?;
                    // A solution on another experiment would meet the check on that one,
                    // which is not the experiment the student is given.
                    for key in experiment_keys(setup.page) {
                        let (given, solved) = (setup.value(key), solution.value(key));
                        if given != solved {
                            return Err(error(
                                at_solution(),
                                format!(
                                    "the solution's {key} is {}, the setup's {}: a solution \
                                     solves the step's own experiment, so give the same {key}",
                                    solved.map_or("the default".into(), |v| format!("\"{v}\"")),
                                    given.map_or("the default".into(), |v| format!("\"{v}\"")),
                                ),
                            ));
                        }
                    }
                    StepCheck::Conditions {
                        conditions,
                        solution,
                    }
                }
                _ => {
                    return Err(error(
                        step_path(i, &["check"]),
                        "a check has either choices (with an answer) or conditions".into(),
                    ))
                }
            };
            steps.push(LessonStep {
                title: step.title,
                setup,
                task: step.task,
                hints: step.hints,
                check,
                explain: step.explain,
            });
        }
        Ok(Lesson {
            id: raw.id,
            title: raw.title,
            teaches: raw.teaches,
            paper: raw.paper,
            steps,
        })
    }
}

impl Lesson {
    /// Whether the lesson is in a file named after its id, `ID.json`, as the lab ships it and a
    /// link `#/lessons/ID` finds it; an error at its `id` otherwise. `cutlab lesson check` asks it
    /// of every file it checks (`text` is the file's, for the line).
    ///
    /// ```
    /// use cutlab::lessons::Lesson;
    /// let text = r##"{"id": "x", "title": "T", "teaches": "t", "paper": "003",
    ///   "steps": [{"title": "s", "setup": "#/simulate?preset=kim-step-doc&controller=fixed",
    ///     "task": "Which?", "check": {"choices": ["a", "b"], "answer": 1}}]}"##;
    /// let lesson = Lesson::from_json(text, "lessons/x.json").unwrap();
    /// assert!(lesson.named_after_file(text, "lessons/x.json").is_ok());
    /// let e = lesson.named_after_file(text, "lessons/y.json").unwrap_err();
    /// assert_eq!((e.line, e.field.as_str()), (1, "id"));
    /// ```
    pub fn named_after_file(&self, text: &str, file: &str) -> Result<(), LessonError> {
        let path = std::path::Path::new(file);
        let stem = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default();
        let json = path.extension().is_some_and(|e| e == "json");
        if json && stem == self.id {
            return Ok(());
        }
        let field = vec![PathPart::Field("id".into())];
        Err(LessonError {
            file: file.to_string(),
            line: line_of(text, &field),
            field: path_text(&field),
            message: format!(
                "the lesson \"{}\" is in a file named {}: name it {}.json, as the lab finds it",
                self.id,
                path.file_name().and_then(|s| s.to_str()).unwrap_or(file),
                self.id
            ),
        })
    }
}

/// The keys of a setup on `page` that choose the experiment itself (a run page's preset, the
/// Logs page's sample log), which a step's solution keeps as its setup gives them. (The Signal
/// chain page's `preset` is a filter, which the student may well choose.)
fn experiment_keys(page: LabPage) -> &'static [&'static str] {
    match page {
        LabPage::Simulate | LabPage::Compare => &["preset"],
        LabPage::Logs => &["sample"],
        _ => &[],
    }
}

/// A link read and its run definition checked by the lab's parsers.
fn read_setup(link: &str) -> Result<Setup, String> {
    let setup = Setup::from_link(link)?;
    setup.define()?;
    Ok(setup)
}
