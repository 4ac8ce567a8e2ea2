//! Reusable pieces of the UI.
//!
//! | module | what it holds |
//! |---|---|
//! | `table_form` | one form for any table of the core's settings: the typed text of its rows and a field per row |
//! | `fields` | labelled text fields and drop-downs with an error slot |
//! | `run_form` | the run's forms: the scenario (the run definition's table) and a controller with its parameters |
//! | `page` | the one page shell |
//! | `later` | a page mounted in pieces, and its own work after its mount (the reason, once) |
//! | `runner` | long work in pieces between frames, its progress and its cancel |
//! | `chart`, `heat_map` | explorable charts on a canvas |
//! | `run_view`, `savings`, `teach_cuts`, `recent` | a run's charts and metrics, its savings against fixed feed, kept calibrations |
//! | `download`, `saved_calibrations`, `work_job` | files offered for download, calibrations in this browser, work shared with a runner |

pub mod chart;
pub mod download;
pub mod fields;
pub mod heat_map;
pub mod later;
pub mod page;
pub mod recent;
pub mod run_form;
pub mod run_view;
pub mod runner;
pub mod saved_calibrations;
pub mod savings;
pub mod table_form;
pub mod teach_cuts;
pub mod work_job;
