//! The closed loop: scenario → machine → signal chain → estimator → controller → safety envelope
//! → override, recorded as a trace and judged by metrics.

pub mod calibration_file;
pub mod calibration_store;
pub mod chain;
pub mod config;
pub mod definition;
pub mod file_format;
pub mod lab;
pub mod metrics;
pub mod paper_comparisons;
pub mod precomputed;
pub mod runner;
pub mod summary;
pub mod trace;
