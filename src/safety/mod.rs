//! The safety envelope: the last word between any controller and the machine.
//!
//! Every override request passes through [`SafetyEnvelope::command`], in every mode (simulation,
//! log replay, hardware), whatever the controller. The envelope
//!
//! 1. holds a fixed *arming* override until the spindle has run for the arming delay (its
//!    starting current says nothing about the cut, paper 003);
//! 2. holds the entry override while the estimated force says the tool is in air
//!    ([`EnvelopeConfig::air_cut_force_n`]) and, once it enters a cut, until the cutter is
//!    engaged ([`EnvelopeConfig::entry_hold_s`]) or the load reaches the target: no controller
//!    enters a cut wound up, and none raises the feed while the cutter is still engaging (which
//!    loads the tool beyond the fixed feed);
//! 3. keeps the override where the feed per tooth stays inside the chip-load window of the tool in
//!    the work material ([`EnvelopeConfig::chip_load`]), whatever the programmed feed and speed;
//! 4. clamps the request to `[min, max]` and rate-limits it (a continuous internal value moves
//!    by at most `max_rate_pct_per_s · dt` per period);
//! 5. quantises it to what the machine can take (a 16-position dial, 1 % steps, or continuous),
//!    never outside `[min, max]`;
//! 6. watches the sensors ([`SafetyEnvelope::observe`], every sample): non-finite, stuck or
//!    out-of-range currents and missing samples raise a fault, during which the override is held
//!    (or moves to a fallback value) and the controller's request is ignored;
//! 7. raises an overload alarm when the estimated force stays above a hard limit for longer than
//!    a set time, and then latches feed hold.
//!
//! Each of these emits a [`SafetyEvent`] for the event log.
//!
//! Guarantees, checked by property tests with random (also non-finite) inputs: the commanded
//! override is always finite, inside `[min, max]`, one of the machine's positions, and moves per
//! period by at most the rate limit plus one quantisation step — except where the chip-load window
//! moves (a block with another programmed feed or speed): the window wins at once.
//!
//! In the order the envelope is built (each file imports only those above it):
//!
//! | file | what it holds |
//! |---|---|
//! | [`chip_load`] | the chip-load window ([`ChipLoad`]), the override band it leaves ([`chip_load_band_pct`]) and which end held ([`ChipLoadEnd`]) |
//! | [`config`] | the settings ([`EnvelopeConfig`]): the machine's override positions ([`OverrideResolution`]), arming ([`ArmingTrigger`]), what a sensor fault does ([`FaultAction`]), and their checks ([`EnvelopeError`]) |
//! | [`events`] | what the envelope saw and did, for the event log: [`SensorFault`], [`SafetyEvent`] |
//! | [`envelope`] | the envelope itself ([`SafetyEnvelope`]): every sample observed, every request commanded |
//! | `tests` | the envelope's tests, rule by rule and as properties over random (also non-finite) inputs |

pub mod chip_load;
pub mod config;
pub mod envelope;
pub mod events;
#[cfg(test)]
mod tests;

pub use chip_load::{chip_load_band_pct, ChipLoad, ChipLoadEnd};
pub use config::{
    ArmingTrigger, EnvelopeConfig, EnvelopeError, FaultAction, OverrideResolution, AIR_CUT_FRACTION,
};
pub use envelope::SafetyEnvelope;
pub use events::{SafetyEvent, SensorFault};
