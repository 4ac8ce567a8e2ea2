//! Reusable pieces of the UI.
//!
//! | file | what |
//! |---|---|
//! | [`page`] | the one page shell |
//! | [`table_form`] | one form for any table of the core's settings: the typed text of its rows and a field per row |
//! | [`fields`] | labelled form fields that keep what was typed and say why it is not accepted |
//! | [`help`] | a "?" that opens a term's explanation in place: metrics' glossary, settings' help |
//! | [`paper_link`] | "paper 00x" in any text as a link to the home page's reference list |
//! | [`run_form`] | the forms that define a run: the scenario (the run definition's table) and a controller with its parameters |
//! | [`chart`] | a chart on a canvas a person can explore: zoom, pan, readout, legend |
//! | [`heat_map`] | a heat map on a canvas, cells picked by click or keyboard |
//! | [`run_view`] | charts, metrics table and event log of closed-loop runs |
//! | [`savings`] | the savings rows of the metrics tables |
//! | [`teach_cuts`], [`recent`] | the last teach cuts' calibrations and other recent answers, by key |
//! | [`saved_calibrations`] | the calibrations saved in this browser |
//! | [`runner`] | a job's status, progress and Cancel, the job in the workers |
//! | [`pool`] | the computation workers: runs, references, recordings and teach cuts off the page's thread, one worker per core |
//! | [`later`] | a page mounted in pieces, and its own work after its mount (the reason, once) |
//! | [`download`] | saving what the lab made as a file |

pub mod chart;
pub mod download;
pub mod fields;
pub mod heat_map;
pub mod help;
pub mod later;
pub mod page;
pub mod paper_link;
pub mod pool;
pub mod recent;
pub mod run_form;
pub mod run_view;
pub mod runner;
pub mod saved_calibrations;
pub mod savings;
pub mod table_form;
pub mod teach_cuts;
