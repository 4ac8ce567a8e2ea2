//! Spindle speed from the F/V converter (paper 003, §3 and Fig. 4).
//!
//! The frequency-to-voltage converter sees the motor, so its voltage is proportional to the
//! spindle speed *within each gear range*, with a different slope in each. The control knows the
//! gear from the programmed speed (the gearbox changes at 900 rpm); the actual speed — with its
//! acceleration and any droop under load — comes from the voltage. The slopes are calibrated from
//! the teach cut by a least-squares line through the origin in each gear.

use serde::{Deserialize, Serialize};

use super::null_as_nan;

/// The spindle gear change of paper 003's machining centre.
pub const GEAR_CHANGE_RPM: f64 = 900.0;

/// Speed identification from the F/V voltage, one slope per gear range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FvSpeedModel {
    /// Programmed speeds at or below this use the low-speed (high-ratio) range.
    pub gear_change_rpm: f64,
    /// Volts per spindle rpm in the low-speed range; NaN (written as null) if never calibrated.
    #[serde(deserialize_with = "null_as_nan")]
    pub low_range_v_per_rpm: f64,
    /// Volts per spindle rpm in the high-speed range; NaN (written as null) if never calibrated.
    #[serde(deserialize_with = "null_as_nan")]
    pub high_range_v_per_rpm: f64,
}

impl FvSpeedModel {
    /// Fits the slope of each range from samples of (programmed speed, actual speed, voltage);
    /// samples with a non-finite value or a stopped spindle are skipped.
    ///
    /// ```
    /// use cutlab::estimation::speed::FvSpeedModel;
    /// let speed = [300.0, 600.0, 1200.0, 2400.0];
    /// let volts: Vec<f64> = speed.iter().map(|n| if *n <= 900.0 { 0.005 * n } else { 0.0012 * n }).collect();
    /// let m = FvSpeedModel::calibrate(&speed, &speed, &volts, 900.0);
    /// assert!((m.speed_rpm(3.0, 600.0) - 600.0).abs() < 1e-9);
    /// assert!((m.speed_rpm(2.4, 2000.0) - 2000.0).abs() < 1e-9);
    /// ```
    pub fn calibrate(
        programmed_rpm: &[f64],
        actual_rpm: &[f64],
        fv_voltage_v: &[f64],
        gear_change_rpm: f64,
    ) -> Self {
        let mut sums = [(0.0, 0.0); 2];
        for ((p, n), v) in programmed_rpm.iter().zip(actual_rpm).zip(fv_voltage_v) {
            if !(p.is_finite() && n.is_finite() && v.is_finite()) || n.abs() < 1.0 {
                continue;
            }
            let range = usize::from(in_high_speed_range(*p, gear_change_rpm));
            sums[range].0 += n.abs() * v;
            sums[range].1 += n * n;
        }
        let slope = |(nv, nn): (f64, f64)| if nn > 0.0 { nv / nn } else { f64::NAN };
        Self {
            gear_change_rpm,
            low_range_v_per_rpm: slope(sums[0]),
            high_range_v_per_rpm: slope(sums[1]),
        }
    }

    /// The spindle speed for an F/V voltage, in the gear range of the programmed speed. Falls back
    /// to the programmed speed when the range was never calibrated.
    pub fn speed_rpm(&self, fv_voltage_v: f64, programmed_rpm: f64) -> f64 {
        let slope = if in_high_speed_range(programmed_rpm, self.gear_change_rpm) {
            self.high_range_v_per_rpm
        } else {
            self.low_range_v_per_rpm
        };
        if slope.is_finite() && slope > 0.0 {
            fv_voltage_v / slope
        } else {
            programmed_rpm
        }
    }
}

/// Whether a spindle speed runs in the high-speed gear: at or above the gear-change speed, the
/// convention of the simulated drive ([`crate::plant::spindle_drive::SpindleDriveConfig::gear_for`])
/// and of paper 003's machine (900 rpm itself in the 1:1.157 gear).
///
/// ```
/// use cutlab::estimation::speed::in_high_speed_range;
/// assert!(in_high_speed_range(900.0, 900.0));
/// assert!(!in_high_speed_range(899.9, 900.0));
/// ```
pub fn in_high_speed_range(speed_rpm: f64, gear_change_rpm: f64) -> bool {
    speed_rpm.abs() >= gear_change_rpm
}
