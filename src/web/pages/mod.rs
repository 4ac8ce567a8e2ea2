//! One module per section of the lab: a file, or a directory whose `mod.rs` composes the page
//! from its panels, one file each.
//!
//! | file | what |
//! |---|---|
//! | [`home`] | what the lab is for, the loop as a picture, where to start, the papers |
//! | [`simulate`] | one closed loop on a preset |
//! | [`compare`] | two to four controllers on one scenario |
//! | [`logs`] | engineers' own logs: read, analysed, calibrated from, replayed |
//! | [`fuzzy`] | paper 002's fuzzy rules: table, surface, viewer, FLL |
//! | [`plant`] | the simulated machine on its own, and the brake bench |
//! | [`signal_chain`] | the Butterworth design and what it does to the bench's current |
//! | [`tune`] | teach-in, sweeps and searches |
//! | [`hardware`] | a real machine over WebSerial, or the virtual device |
//! | [`learn`] | the ideas in four steps, with the papers' equations |
//! | [`lessons`] | guided experiments with checks, and the lesson panel beside the lab |

pub mod compare;
pub mod fuzzy;
pub mod hardware;
pub mod home;
pub mod learn;
pub mod lessons;
pub mod logs;
pub mod plant;
pub mod signal_chain;
pub mod simulate;
pub mod tune;
