//! One module per section of the lab.

pub mod compare;
pub mod fuzzy;
pub mod hardware;
pub mod learn;
pub mod logs;
pub mod plant;
pub mod signal_chain;
pub mod simulate;
pub mod tune;
