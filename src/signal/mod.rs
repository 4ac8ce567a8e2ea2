//! The signal chain: phase currents → low-pass → RMS or d-q currents → spectrum.
