//! Feed-override controllers: one interface ([`law::Controller`]), one registry.
//!
//! | file | what |
//! |---|---|
//! | [`law`] | the interface every controller implements, and what it reports of itself |
//! | [`registry`] | every controller the lab offers: parameters with units, defaults and ranges, building one for a run |
//! | [`run_names`] | how runs of several configurations side by side are named, by the law each runs |
//! | [`fixed`] | fixed feed, the baseline |
//! | [`restriction`] | paper 000's current restriction |
//! | [`threshold`] | paper 003's threshold-proportional control |
//! | [`fuzzy`] | paper 002's fuzzy control: a Mamdani engine, its rule tables, FLL |
//! | [`pi`] | PI with back-calculation anti-windup |
//! | [`mrac`] | paper 001's Lyapunov model-reference adaptive control |

pub mod fixed;
pub mod fuzzy;
pub mod law;
pub mod mrac;
pub mod pi;
pub mod registry;
pub mod restriction;
pub mod run_names;
pub mod threshold;
