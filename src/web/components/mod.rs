//! Reusable pieces of the UI.

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
