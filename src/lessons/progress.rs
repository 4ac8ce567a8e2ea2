//! A student's progress through the lessons, as the browser keeps it (`localStorage`) and
//! exports it: for each lesson, the step open and the steps done; and the lesson open beside the
//! lab, if any. Read leniently: what is damaged or unknown is dropped, never an error, since
//! nothing a student can do with a damaged record is worth stopping the lab for.

use std::collections::BTreeMap;

use serde::{Deserialize, Serialize};

use super::Lesson;

/// The key the browser keeps the progress under.
pub const STORAGE_KEY: &str = "cutlab.lessons";

/// One lesson's progress.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct LessonProgress {
    /// The step open, from 0.
    pub step: usize,
    /// The steps done, from 0, ascending.
    pub done: Vec<usize>,
}

/// Every lesson's progress.
#[derive(Debug, Clone, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct StudentProgress {
    /// The lesson open beside the lab.
    pub open: Option<String>,
    /// By lesson id.
    pub lessons: BTreeMap<String, LessonProgress>,
}

impl StudentProgress {
    /// Reads the stored text; nothing or damaged text is no progress.
    ///
    /// ```
    /// use cutlab::lessons::progress::StudentProgress;
    /// let mut p = StudentProgress::default();
    /// p.mark_done("threshold-gap", 1);
    /// assert_eq!(StudentProgress::from_json(&p.to_json()), p);
    /// assert_eq!(StudentProgress::from_json("{damaged"), StudentProgress::default());
    /// ```
    pub fn from_json(text: &str) -> StudentProgress {
        serde_json::from_str(text).unwrap_or_default()
    }

    /// The text to store or export.
    pub fn to_json(&self) -> String {
        serde_json::to_string_pretty(self).unwrap_or_default()
    }

    /// The progress of `lesson`.
    pub fn of(&self, lesson: &str) -> LessonProgress {
        self.lessons.get(lesson).cloned().unwrap_or_default()
    }

    /// Marks step `step` of `lesson` done.
    pub fn mark_done(&mut self, lesson: &str, step: usize) {
        let entry = self.lessons.entry(lesson.to_string()).or_default();
        if let Err(at) = entry.done.binary_search(&step) {
            entry.done.insert(at, step);
        }
    }

    /// Opens step `step` of `lesson`.
    pub fn open_step(&mut self, lesson: &str, step: usize) {
        self.open = Some(lesson.to_string());
        self.lessons.entry(lesson.to_string()).or_default().step = step;
    }

    /// The progress as a teacher reads it, for the download: each lesson by its id and title,
    /// the step open and the steps done counted from 1 as the panel counts them ("Step 2 of 4"),
    /// each with its title. (The browser keeps [`StudentProgress::to_json`], counted from 0,
    /// which this does not replace: nothing a student saved is read differently.) A lesson the
    /// lab no longer ships keeps its id and numbers, with no titles.
    ///
    /// ```
    /// use cutlab::lessons::progress::StudentProgress;
    /// use cutlab::lessons::shipped::shipped;
    /// let lessons: Vec<_> = shipped().into_iter().flatten().collect();
    /// let mut p = StudentProgress::default();
    /// p.mark_done("own-log", 0);
    /// p.open_step("own-log", 1);
    /// let report: serde_json::Value = serde_json::from_str(&p.to_report_json(&lessons)).unwrap();
    /// let own_log = &report["lessons"][0];
    /// assert_eq!(own_log["title"], "Your own machine's log");
    /// assert_eq!(own_log["open_step"]["number"], 2);
    /// assert_eq!(own_log["done"][0]["number"], 1);
    /// assert_eq!(own_log["done"][0]["title"], "Open a log");
    /// ```
    pub fn to_report_json(&self, lessons: &[Lesson]) -> String {
        let step = |lesson: Option<&Lesson>, index: usize| StepReport {
            number: index + 1,
            title: lesson
                .and_then(|l| l.steps.get(index))
                .map(|s| s.title.clone()),
        };
        let report = ProgressReport {
            steps_counted_from: 1,
            open: self.open.clone(),
            lessons: self
                .lessons
                .iter()
                .map(|(id, progress)| {
                    let lesson = lessons.iter().find(|l| &l.id == id);
                    LessonReport {
                        id: id.clone(),
                        title: lesson.map(|l| l.title.clone()),
                        steps: lesson.map(|l| l.steps.len()),
                        open_step: step(lesson, progress.step),
                        done: progress.done.iter().map(|i| step(lesson, *i)).collect(),
                    }
                })
                .collect(),
        };
        serde_json::to_string_pretty(&report).unwrap_or_default()
    }

    /// How many of `steps` steps of `lesson` are done.
    pub fn done_count(&self, lesson: &str, steps: usize) -> usize {
        self.of(lesson).done.iter().filter(|s| **s < steps).count()
    }
}

/// The downloaded progress ([`StudentProgress::to_report_json`]).
#[derive(Serialize)]
struct ProgressReport {
    /// Always 1: every step number below counts as the panel does.
    steps_counted_from: u8,
    open: Option<String>,
    lessons: Vec<LessonReport>,
}

#[derive(Serialize)]
struct LessonReport {
    id: String,
    title: Option<String>,
    steps: Option<usize>,
    open_step: StepReport,
    done: Vec<StepReport>,
}

#[derive(Serialize)]
struct StepReport {
    /// From 1.
    number: usize,
    title: Option<String>,
}

/// What the lesson panel says of a step's completion: the progress remembers a step once done,
/// but the panel never says "Step done" under a check the work shown now fails.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StepStatus {
    /// Not done, or not met by the work shown: nothing said (the check says why).
    Open,
    /// The work shown now meets the check.
    Done,
    /// Done earlier; nothing checked since the step opened.
    DoneEarlier,
    /// Done earlier, but the work shown now does not meet the check.
    DoneEarlierNotNow,
}

impl StepStatus {
    /// The status of a step done before (`done_before`, as the progress keeps it) whose check of
    /// the work shown now is met (`Some(true)`), failed (`Some(false)`) or not made (`None`).
    ///
    /// ```
    /// use cutlab::lessons::progress::StepStatus;
    /// assert_eq!(StepStatus::of(true, Some(false)), StepStatus::DoneEarlierNotNow);
    /// assert_eq!(StepStatus::of(false, Some(true)), StepStatus::Done);
    /// ```
    pub fn of(done_before: bool, met_now: Option<bool>) -> StepStatus {
        match (done_before, met_now) {
            (_, Some(true)) => StepStatus::Done,
            (true, None) => StepStatus::DoneEarlier,
            (true, Some(false)) => StepStatus::DoneEarlierNotNow,
            (false, _) => StepStatus::Open,
        }
    }

    /// What the panel says, `work` naming what is checked ("run", "answer"); `None` for
    /// [`StepStatus::Open`].
    pub fn words(self, work: &str) -> Option<String> {
        match self {
            StepStatus::Open => None,
            StepStatus::Done => Some("Step done.".into()),
            StepStatus::DoneEarlier => Some("You did this step earlier.".into()),
            StepStatus::DoneEarlierNotNow => Some(format!(
                "You met this step earlier; the {work} now shown does not meet it."
            )),
        }
    }

    /// Whether the step's explanation is shown beside it (not under a check failed now).
    pub fn explains(self) -> bool {
        matches!(self, StepStatus::Done | StepStatus::DoneEarlier)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_step_done_twice_counts_once_and_steps_stay_in_order() {
        let mut p = StudentProgress::default();
        p.mark_done("a", 2);
        p.mark_done("a", 0);
        p.mark_done("a", 2);
        assert_eq!(p.of("a").done, [0, 2]);
        assert_eq!(p.done_count("a", 2), 1);
        p.open_step("a", 1);
        assert_eq!((p.open.as_deref(), p.of("a").step), (Some("a"), 1));
    }

    #[test]
    fn a_step_done_earlier_is_never_called_done_under_a_check_failed_now() {
        // The reviewer's sensorless-cross-check step 2: met, then a run at override 70 failed.
        let status = StepStatus::of(true, Some(false));
        assert_eq!(
            status.words("run").as_deref(),
            Some("You met this step earlier; the run now shown does not meet it.")
        );
        assert!(!status.explains());
        assert_eq!(
            StepStatus::of(true, None).words("run").as_deref(),
            Some("You did this step earlier.")
        );
        assert_eq!(StepStatus::of(false, Some(false)).words("run"), None);
        assert_eq!(
            StepStatus::of(false, Some(true)).words("run").as_deref(),
            Some("Step done.")
        );
        assert!(StepStatus::of(false, Some(true)).explains());
    }
}
