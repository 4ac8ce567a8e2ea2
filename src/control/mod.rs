//! Feed-override controllers: one interface ([`law::Controller`]), one registry.

pub mod fixed;
pub mod fuzzy;
pub mod law;
pub mod mrac;
pub mod pi;
pub mod registry;
pub mod restriction;
pub mod threshold;
