//! Estimation: motor current → cutting force.

pub mod least_squares;
