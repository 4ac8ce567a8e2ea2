//! The signal chain: phase currents → low-pass → RMS or d-q currents → spectrum.
//!
//! Plain Rust over `&[f64]`: no web types, the same code natively and in `wasm32`. Everything
//! that shapes a simulated trace (filter design, filtering, RMS, Clarke/Park) uses
//! [`crate::math`]'s libm functions and IEEE arithmetic only, so it gives the same bits on both
//! targets; spectra use rustfft, whose twiddles may differ in the last bit between targets.
//!
//! ## Module map
//!
//! | module | what it holds | scipy counterpart |
//! |---|---|---|
//! | [`butterworth`] | [`butter`](butterworth::butter): Butterworth low/high/band-pass/band-stop of order 1–20, bilinear transform with pre-warping, as second-order sections | `butter(N, Wn, btype, fs=fs, output='sos')` |
//! | [`design_settings`] | a design's settings as one table (kind, order, cut-offs, rate) that the Signal chain page and `cutlab filter` parse alike, and the papers' filters | — |
//! | [`zpk`] | zeros/poles/gain and their pairing into sections | `zpk2sos(..., pairing='nearest')` |
//! | [`sos`] | [`Sos`](sos::Sos) and [`Biquad`](sos::Biquad): coefficients only (no state), frequency response, steady-state initial conditions | `sosfreqz`/`freqz_sos`, `sosfilt_zi` |
//! | [`filter`] | [`SosFilter`](filter::SosFilter) (one channel) and [`SosFilterBank`](filter::SosFilterBank) (interleaved channels, e.g. three phase currents): transposed direct form II | `sosfilt` |
//! | [`filtfilt`] | zero-phase forward–backward filtering of a whole log, with scipy's default odd padding | `sosfiltfilt` |
//! | [`rms`] | block, sliding-window, three-phase (paper 003 eq 7) and per-revolution peak RMS; an RMS detector (√ of the low-passed square) | — |
//! | [`dq`] | Clarke and Park transforms (amplitude- and power-invariant) and the PMSM torque of paper 000 eq 7–8 | — |
//! | [`spectrum`] | windowed single-sided amplitude spectrum, Welch PSD, peaks, spindle/tooth-passing markers, a check that time stamps are evenly spaced | `welch` |
//! | [`chain`] | the closed loop's signal chain: every sensor sample's phase currents low-passed and three-phase RMS'd, summed into one [`PeriodSummary`](chain::PeriodSummary) per control period | — |
//! | [`decimate`] | min/max decimation of long series for plotting | — |
//! | [`stats`] | [`MinMeanMax`](stats::MinMeanMax): running minimum, mean and maximum of a stream; the one [`median`](stats::median) | `numpy.median` |
//! | `complex` | complex arithmetic with the same bits natively and in wasm (private) | — |
//!
//! ## Design apart from state
//!
//! A design ([`sos::Sos`], [`butterworth::ButterworthSpec`], [`dq::PmsmParams`]) is a value made
//! by a constructor that returns `Result`; once made it is valid. A processor (`SosFilter`,
//! `SlidingRms`, `RmsDetector`, …) owns its state, allocates when it is built and never in
//! `process`, and has `process(x) -> y`, an in-place `process_slice` that gives exactly the bits
//! of calling `process` on every element, and `reset`.
//!
//! ## NaN and ±∞
//!
//! Design functions reject non-finite parameters with an error that names the field. Samples are
//! not checked (checking would cost a branch per sample and hide bad data): a NaN or ±∞ sample
//! enters an IIR filter's state and every later output of that filter is NaN until `reset` (or
//! `set_steady_state`). Block computations ([`rms::block_rms`], spectra) return NaN when any input
//! is NaN; [`decimate::min_max`] skips non-finite values so a plot still shows the rest.

pub mod butterworth;
pub mod chain;
pub mod decimate;
pub mod design_settings;
pub mod dq;
pub mod filter;
pub mod filtfilt;
pub mod rms;
pub mod sos;
pub mod spectrum;
pub mod stats;
pub mod zpk;

mod complex;
