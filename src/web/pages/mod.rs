//! One module per section of the lab: a file, or a directory whose `mod.rs` composes the page
//! from its panels, one file each.

pub mod compare;
pub mod fuzzy;
pub mod hardware;
pub mod learn;
pub mod logs;
pub mod plant;
pub mod signal_chain;
pub mod simulate;
pub mod tune;
