//! `cutlab lesson check FILE…`: a teacher's check of lesson files without a browser. Each file is
//! read ([`Lesson::from_json`]: its schema, and every link, metric and setting it names); then
//! each step with conditions is done twice on the simulated lab ([`Checker`]): its reference
//! solution must meet every condition, and its starting point must not (a check the student
//! meets before doing anything checks nothing).

use std::fmt::Write as _;

use super::{CliError, Io};
use crate::lessons::locate::{line_of, path_text, PathPart};
use crate::lessons::native::{Checker, StepOutcome};
use crate::lessons::{Lesson, LessonError, StepCheck};

pub(crate) const ABOUT: &str =
    "Check lesson files (JSON, docs/lessons.md): their schema and every link, metric and\n\
setting they name; then run each step's reference solution on the simulated lab, which\n\
must meet the step's check, and the step's starting point, which must not. Every\n\
problem is printed as FILE:LINE: FIELD: MESSAGE and makes the exit status non-zero.";

#[derive(Debug, clap::Args)]
pub struct LessonArgs {
    #[command(subcommand)]
    command: LessonCommand,
}

#[derive(Debug, clap::Subcommand)]
enum LessonCommand {
    /// Check lesson files: schema, references, reference solutions (pass) and starting points (fail)
    Check {
        /// The lesson files (JSON)
        #[arg(value_name = "FILE", required = true)]
        files: Vec<String>,
    },
}

/// Runs `cutlab lesson`.
pub fn run(args: LessonArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let LessonCommand::Check { files } = args.command;
    let checker = Checker::new();
    let mut problems = 0;
    let mut failed_files = 0;
    for file in &files {
        let (report, file_problems) = check_file(file, &checker);
        write!(io.stdout, "{report}")?;
        problems += file_problems.len();
        failed_files += usize::from(!file_problems.is_empty());
        for problem in file_problems {
            writeln!(io.stdout, "{problem}")?;
        }
    }
    if problems == 0 {
        Ok(())
    } else {
        Err(CliError::new(format!(
            "{problems} problem{} in {failed_files} of {} lesson file{}",
            if problems == 1 { "" } else { "s" },
            files.len(),
            if files.len() == 1 { "" } else { "s" }
        )))
    }
}

/// Checks one file: what was checked, and each problem.
pub fn check_file(file: &str, checker: &Checker) -> (String, Vec<LessonError>) {
    let text = match std::fs::read_to_string(file) {
        Ok(text) => text,
        Err(e) => {
            let error = LessonError {
                file: file.to_string(),
                line: 1,
                field: String::new(),
                message: format!("cannot read the file: {e}"),
            };
            return (String::new(), vec![error]);
        }
    };
    let lesson = match Lesson::from_json(&text, file) {
        Ok(lesson) => lesson,
        Err(e) => return (String::new(), vec![e]),
    };
    if let Err(e) = lesson.named_after_file(&text, file) {
        return (String::new(), vec![e]);
    }
    let mut report = String::new();
    let mut problems = Vec::new();
    let steps = lesson.steps.len();
    let plural = if steps == 1 { "" } else { "s" };
    let _ = writeln!(report, "{file}: {} ({steps} step{plural})", lesson.title);
    for (i, step) in lesson.steps.iter().enumerate() {
        let StepCheck::Conditions { solution, .. } = &step.check else {
            let _ = writeln!(report, "  step {}: multiple choice", i + 1);
            continue;
        };
        let problem = |field: &str, message: String| {
            let path = [
                PathPart::Field("steps".into()),
                PathPart::Index(i),
                PathPart::Field(field.to_string()),
            ];
            LessonError {
                file: file.to_string(),
                line: line_of(&text, &path),
                field: path_text(&path),
                message,
            }
        };
        match checker.check_step(&lesson, i, solution) {
            Ok(Some(outcome)) if outcome.met() => {
                let _ = writeln!(
                    report,
                    "  step {}: the solution meets the check ({})",
                    i + 1,
                    measured(&outcome)
                );
            }
            Ok(Some(outcome)) => problems.push(problem(
                "solution",
                format!(
                    "the reference solution does not meet the check: {}",
                    unmet(&outcome)
                ),
            )),
            Ok(None) => {}
            Err(e) => problems.push(problem("solution", e)),
        }
        match checker.check_step(&lesson, i, &step.setup) {
            Ok(Some(outcome)) if outcome.met() => problems.push(problem(
                "setup",
                format!(
                    "the starting point already meets the check, so it checks nothing: {}",
                    measured(&outcome)
                ),
            )),
            Ok(Some(outcome)) => {
                let _ = writeln!(
                    report,
                    "  step {}: the starting point does not ({})",
                    i + 1,
                    unmet(&outcome)
                );
            }
            Ok(None) => {}
            Err(e) => problems.push(problem("setup", e)),
        }
    }
    (report, problems)
}

/// Every condition with what was measured.
fn measured(outcome: &StepOutcome) -> String {
    outcome
        .outcomes
        .iter()
        .map(|o| format!("{}: {}", o.wants, o.measured))
        .collect::<Vec<_>>()
        .join("; ")
}

/// The conditions not met, with what was measured.
fn unmet(outcome: &StepOutcome) -> String {
    outcome
        .outcomes
        .iter()
        .filter(|o| !o.met)
        .map(|o| format!("{}: {}", o.wants, o.measured))
        .collect::<Vec<_>>()
        .join("; ")
}
