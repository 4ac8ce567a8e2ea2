//! The lessons shipped in `www/lessons/`, built into the lab so a link to one opens without a
//! fetch, in the order the Lessons page lists them (the order the papers' ideas build on each
//! other). A test checks every file of the folder is here and reads without a problem.

use super::{Lesson, LessonError};

/// Each shipped lesson's file name (in `www/lessons/`) and text.
pub const SHIPPED: [(&str, &str); 10] = [
    (
        "current-as-force.json",
        include_str!("../../www/lessons/current-as-force.json"),
    ),
    (
        "filtering-and-rms.json",
        include_str!("../../www/lessons/filtering-and-rms.json"),
    ),
    (
        "teach-cut.json",
        include_str!("../../www/lessons/teach-cut.json"),
    ),
    (
        "threshold-gap.json",
        include_str!("../../www/lessons/threshold-gap.json"),
    ),
    (
        "adaptive-convergence.json",
        include_str!("../../www/lessons/adaptive-convergence.json"),
    ),
    (
        "fuzzy-rules.json",
        include_str!("../../www/lessons/fuzzy-rules.json"),
    ),
    (
        "entry-and-envelope.json",
        include_str!("../../www/lessons/entry-and-envelope.json"),
    ),
    (
        "sensorless-cross-check.json",
        include_str!("../../www/lessons/sensorless-cross-check.json"),
    ),
    (
        "tuning-trade-off.json",
        include_str!("../../www/lessons/tuning-trade-off.json"),
    ),
    (
        "own-log.json",
        include_str!("../../www/lessons/own-log.json"),
    ),
];

/// Every shipped lesson, read, in order; a lesson that does not read is its error (the tests
/// keep there being none).
pub fn shipped() -> Vec<Result<Lesson, LessonError>> {
    SHIPPED
        .iter()
        .map(|(file, text)| Lesson::from_json(text, &format!("www/lessons/{file}")))
        .collect()
}

/// The shipped lesson with id `id`.
pub fn shipped_lesson(id: &str) -> Option<Lesson> {
    shipped().into_iter().flatten().find(|l| l.id == id)
}
