//! The closed loop: scenario → machine → signal chain → estimator → controller → safety envelope
//! → override, recorded as a trace and judged by metrics.
//!
//! In the order a run is made (each file imports only those above it):
//!
//! | file | what it holds |
//! |---|---|
//! | [`paper_defaults`] | the defaults a preset's paper states: a controller's parameters ([`paper_defaults::preset_controller`]) and paper 002's control period |
//! | [`definition`] | the run definition: every setting a person may change ([`definition::RunSetting`], one table for the form, the command line and a saved configuration) and [`definition::RunSpec`], a run as asked for |
//! | [`error`] | [`error::LoopError`], why a run could not be set up or made |
//! | [`thresholds`] | the loop's force thresholds from the target and the calibration: the air-cut force and its caps, the cut-before-arming force |
//! | [`settings`] | the one resolution of a request on a machine: [`settings::plan`] before the teach cut, [`settings::Plan::settle`] after it |
//! | [`run_table`] | the run's settings as rows of the generic tables ([`crate::input::table`]), with the defaults a fresh form shows |
//! | [`sample_loop`] | the pushed-sample shape every loop shares, and [`sample_loop::OnMachine`], which pulls from a machine |
//! | [`teach_cut`] | the teach cut as a sample loop, fitted by [`crate::estimation::teach_fit`] |
//! | [`trace`] | one row per control period and the safety events |
//! | [`feedback_loop`] | the closed loop itself |
//! | [`metrics`] | what a trace is judged by |
//! | [`lab`] | runs on the papers' presets: teach cut then loop, in pieces; several runs in turn |
//! | [`batch`] | runs of one plant stepped together, each equal bit for bit to the run alone |
//! | [`trial_cuts`] | trial cuts read from a run's depth sections, for paper 004's network |
//! | [`flat_row`] | a row of numbers as it travels to and from a computation worker, its order written once |
//! | [`recording_jobs`] | the other jobs a computation worker does: bench and open-loop recordings, packed as raw numbers, and a teach-in's teach cuts |
//! | [`transfer`] | runs sent to a computation worker and back, bit for bit (the browser's worker pool) |
//! | [`references`] | the fixed-feed reference runs the savings are measured against |
//! | [`summary`] | the metrics as a table, and the best of several runs |
//! | [`paper_comparisons`] | the comparisons the papers make, as runs the lab repeats |
//! | [`calibration_file`], [`calibration_store`] | a calibration saved as JSON, and the ones a browser keeps |
//! | [`config`], [`file_format`] | a saved configuration of runs, and the format check every saved file shares |
//! | [`precomputed`] | the default scenario's teach cut and references, shipped with the lab |

pub mod batch;
pub mod calibration_file;
pub mod calibration_store;
pub mod config;
pub mod definition;
pub mod error;
pub mod feedback_loop;
pub mod file_format;
pub mod flat_row;
pub mod lab;
pub mod metrics;
pub mod paper_comparisons;
pub mod paper_defaults;
pub mod precomputed;
pub mod recording_jobs;
pub mod references;
pub mod run_table;
pub mod sample_loop;
pub mod settings;
pub mod summary;
pub mod teach_cut;
pub mod thresholds;
pub mod trace;
pub mod transfer;
pub mod trial_cuts;
