//! # cutlab — adaptive cutting-force control of CNC milling, as a library
//!
//! The force on a milling cutter is measured indirectly from motor current and a controller
//! adjusts the feed override to hold it at a target. Every module here is plain Rust that builds
//! natively and for `wasm32-unknown-unknown`; the browser app (`web`, behind the `web` feature) and
//! the command line (`cli`, behind the `cli` feature) only show and steer it.
//!
//! ## Data flow
//!
//! ```text
//! scenario ─► CNC (programmed feed × override) ─► cutting process ─► feed / spindle drives
//!    ─► sensors (Hall, ADC) ─► Machine::step ─► one SensorSample
//!
//! every sample, pushed (SampleLoop::push) by a machine, a log or the serial line:
//!    SafetyEnvelope::observe (stuck / implausible currents, arming clock)
//!    ─► signal chain (filter, three-phase RMS, period sums)
//! every control period:
//!    estimator (current → force) ─► controller ─► SafetyEnvelope::command (limits, rate,
//!    quantisation, faults, overload) ─► OverrideCommand ─► back to the CNC
//!
//! before the loop, the teach cut: the same machine and signal chain open-loop through a schedule
//! of overrides, each period's current paired with a force (simulation truth, a dynamometer, or
//! the model of the cut) ─► least-squares fit ─► the estimator
//! ```
//!
//! A run is defined once ([`closed_loop::definition`]): the browser form, the command line and a
//! saved configuration parse every setting through the same table. Long work (teach cut, loop,
//! reference search, recordings) is a [`work::Work`] the browser slices and the CLI runs to the end.
//!
//! ## Modules
//!
//! In the order a sample travels:
//!
//! | module | what it holds |
//! |---|---|
//! | [`plant`] | the simulated machine: milling mechanics, feed and spindle drives, motor currents, sensors, the FANUC-style CNC, scenarios and the papers' presets |
//! | [`machine`] | the one interface between the closed loop and a machine: simulated, replayed or real |
//! | [`log`] | engineers' own CSV logs: the fast incremental reader (any dialect, damaged lines by line and column), analysis, the column → channel mapping, a log as a machine (replay of controllers) and calibration from a log |
//! | [`protocol`] | the serial protocol to a bridge device: COBS/CRC-32 framing and frames (a `no_std` codec), the device emulator and the native host |
//! | [`signal`] | Butterworth design (second-order sections), biquad-cascade filtering, zero-phase filtering, RMS, Clarke/Park, spectra, min/max decimation |
//! | [`estimation`] | current → force: paper 000's feed-drive and paper 003's spindle models, F/V speed identification, teach-cut calibration by least squares |
//! | [`control`] | the controller interface and registry: fixed feed, current restriction, threshold-proportional, fuzzy (a Mamdani engine with FLL), PI with anti-windup, Lyapunov MRAC |
//! | [`safety`] | the safety envelope after every controller: limits, rate limit, quantisation, arming, sensor faults, overload |
//! | [`closed_loop`] | the one loop that wires them, fed by pushed samples: the run definition, teach cut, signal chain, trace, metrics and the table of them, and the lab runs the CLI and the browser share |
//! | [`tuning`] | sweeps and Nelder–Mead over a controller's parameters across scenarios, on the loop above, and the teach-in proposal from a simulated, logged or saved teach cut |
//! | [`hardware`] | a machine (or the emulator) driven from the lab as it runs: link state, both watchdogs, arming, the same loop fed by pushed samples, recordings as CSV chunks, `cutlab host`'s run over a native link, the commissioning checks |
//! | [`lessons`] | guided experiments: a lesson file's steps, each a page and run definition of the lab with a check on the runs' metrics, a Compare run's variants or a filter, evaluated with the measured values |
//! | [`input`] | numbers typed into forms, parsed with messages for the field |
//! | [`rng`] | the seeded random source every simulation draws from |
//! | [`math`] | transcendental functions that give the same bits natively and in wasm |
//! | [`work`] | long computations done in pieces: the one interface the browser slices and the CLI runs to the end |
//! | `cli` | the `cutlab` command line (feature `cli`) |
//! | `charts` | plotters drawing functions over any `DrawingArea` (feature `charts`, part of `web`) |
//! | `web` | the Leptos browser app (feature `web`) |
//!
//! ## Conventions
//!
//! Units live in names (`force_n`, `feed_mm_min`, `cutoff_hz`, `dt_s`). A design or configuration
//! value is made by a constructor that returns `Result` for bad parameters; once it exists it is
//! valid, and the per-sample `process`/`step` methods cannot fail. Nothing a user can influence
//! panics: user data goes through `Result`s whose messages say where the problem is.

pub mod closed_loop;
pub mod control;
pub mod estimation;
pub mod hardware;
pub mod input;
pub mod lessons;
pub mod log;
pub mod machine;
pub mod math;
pub mod plant;
pub mod protocol;
pub mod rng;
pub mod safety;
pub mod sections;
pub mod signal;
pub mod truth_fields;
pub mod tuning;
pub mod work;

#[cfg(feature = "cli")]
pub mod cli;

#[cfg(feature = "charts")]
pub mod charts;

#[cfg(feature = "web")]
pub mod web;
