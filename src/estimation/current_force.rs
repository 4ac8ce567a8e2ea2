//! Linear current-to-force models and their calibration from a teach cut.
//!
//! Both papers that measure force through current find a straight line with an offset:
//!
//! * **Feed drive** (paper 000, eq 3 and eq 9, Fig. 11–12): the electromagnetic torque balances
//!   friction, preload and the feed force, T_m = L₀/(2πη)·[F₀ + F_p0(1 − η₀²) + F_c], and the RMS
//!   current follows the torque, so I_rms = I_idle(v) + s_f·F_c. The idle current is not zero and
//!   changes a little with feed speed (Fig. 12); cutlab takes it linear in |v|:
//!   I_idle(v) = i₀ + i_v·|v|.
//! * **Spindle drive** (paper 003, eq 6–7, Fig. 3 and 6–7): the peak RMS current per revolution is
//!   linear in the peak cutting force per revolution, I_rms = I_idle(n) + S(n)·F_peak, with the
//!   idle current and the sensitivity S depending on spindle speed n and jumping at the gear
//!   change. cutlab keeps one (speed, idle, sensitivity) row per calibrated speed and interpolates
//!   linearly between rows of the same gear; it never interpolates across the gear change.
//!
//! Estimation inverts the line: F = (I − I_idle) / s. A model knows the range it was calibrated
//! over and says when an estimate lies outside it ([`ForceEstimate::in_range`]).
//!
//! Non-finite inputs give a non-finite force, which the safety envelope treats as a sensor fault.

use serde::{Deserialize, Serialize};

use super::null_as_nan;

use super::speed::in_high_speed_range;
use crate::math::least_squares::{fit, Fit, FitError};

/// A force estimate and whether its inputs lie inside the calibrated range.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ForceEstimate {
    /// The estimated force.
    pub force_n: f64,
    /// False when the current or speed lies outside what the calibration saw (by more than 10 %
    /// of its span); the estimate is then an extrapolation.
    pub in_range: bool,
}

/// An estimate whose current (or speed) lies outside the calibrated range by more than this
/// fraction of the range's span is flagged as extrapolated.
pub const RANGE_SLACK_FRACTION: f64 = 0.1;

/// A closed interval of values seen during calibration.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Range {
    /// Smallest value seen (+∞ when none was: written as null).
    #[serde(deserialize_with = "null_as_nan")]
    pub min: f64,
    /// Largest value seen (−∞ when none was: written as null).
    #[serde(deserialize_with = "null_as_nan")]
    pub max: f64,
}

impl Range {
    fn of(values: impl Iterator<Item = f64>) -> Self {
        let (min, max) = values
            .filter(|v| v.is_finite())
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), v| {
                (lo.min(v), hi.max(v))
            });
        Self { min, max }
    }

    /// Whether `v` lies within the range widened by [`RANGE_SLACK_FRACTION`] of its span on each
    /// side.
    pub fn contains_loosely(&self, v: f64) -> bool {
        let slack = RANGE_SLACK_FRACTION * (self.max - self.min).abs();
        v >= self.min - slack && v <= self.max + slack
    }
}

/// How well a calibration fits.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FitQuality {
    /// Coefficient of determination of the current model.
    #[serde(deserialize_with = "null_as_nan")]
    pub r_squared: f64,
    /// Residual standard deviation of the current.
    #[serde(deserialize_with = "null_as_nan")]
    pub residual_std_a: f64,
    /// The same residual expressed as force (residual current / sensitivity).
    #[serde(deserialize_with = "null_as_nan")]
    pub residual_std_n: f64,
    /// Samples used.
    pub samples: usize,
}

impl FitQuality {
    fn from_fit(f: &Fit, sensitivity_a_per_n: f64) -> Self {
        Self {
            r_squared: f.r_squared,
            residual_std_a: f.residual_std,
            residual_std_n: f.residual_std / sensitivity_a_per_n.abs(),
            samples: f.samples,
        }
    }
}

/// Paper 000's feed-drive model: I_rms = i₀ + i_v·|v| + s·F_feed.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeedCurrentModel {
    /// Idle current at standstill, i₀.
    pub idle_current_a: f64,
    /// Growth of the idle current with feed speed, i_v.
    pub idle_current_a_per_mm_min: f64,
    /// Sensitivity s: RMS current per newton of feed force.
    pub sensitivity_a_per_n: f64,
    /// The current range seen in calibration.
    pub current_range_a: Range,
    /// The feed-speed range seen in calibration.
    pub feed_range_mm_min: Range,
    /// Fit quality.
    pub quality: FitQuality,
}

impl FeedCurrentModel {
    /// Fits the model to teach-cut samples of RMS current, feed speed and feed force (rows with a
    /// non-finite value are skipped).
    pub fn calibrate(
        current_a: &[f64],
        feed_mm_min: &[f64],
        force_n: &[f64],
    ) -> Result<Self, FitError> {
        let n = current_a.len().min(feed_mm_min.len()).min(force_n.len());
        let ones = vec![1.0; n];
        let speed: Vec<f64> = feed_mm_min[..n].iter().map(|v| v.abs()).collect();
        let f = fit(
            &[
                ("idle current", &ones),
                ("feed speed", &speed),
                ("force", &force_n[..n]),
            ],
            &current_a[..n],
        )?;
        let sensitivity = f.coefficients[2];
        if sensitivity <= 0.0 {
            return Err(FitError::RankDeficient { column: "force" });
        }
        Ok(Self {
            idle_current_a: f.coefficients[0],
            idle_current_a_per_mm_min: f.coefficients[1],
            sensitivity_a_per_n: sensitivity,
            current_range_a: Range::of(current_a[..n].iter().copied()),
            feed_range_mm_min: Range::of(speed.iter().copied()),
            quality: FitQuality::from_fit(&f, sensitivity),
        })
    }

    /// The idle current at feed speed `feed_mm_min`.
    pub fn idle_current_a(&self, feed_mm_min: f64) -> f64 {
        self.idle_current_a + self.idle_current_a_per_mm_min * feed_mm_min.abs()
    }

    /// The feed force for an RMS current at a feed speed.
    ///
    /// ```
    /// use cutlab::estimation::current_force::FeedCurrentModel;
    /// let force: Vec<f64> = (0..50).map(|i| 20.0 * f64::from(i % 10)).collect();
    /// let feed: Vec<f64> = (0..50).map(|i| 50.0 * f64::from(1 + i / 10)).collect();
    /// let current: Vec<f64> = force.iter().zip(&feed).map(|(f, v)| 0.8 + 0.001 * v + 0.004 * f).collect();
    /// let model = FeedCurrentModel::calibrate(&current, &feed, &force).unwrap();
    /// let e = model.estimate(0.8 + 0.001 * 100.0 + 0.004 * 150.0, 100.0);
    /// assert!((e.force_n - 150.0).abs() < 1e-9 && e.in_range);
    /// ```
    pub fn estimate(&self, current_a: f64, feed_mm_min: f64) -> ForceEstimate {
        ForceEstimate {
            force_n: (current_a - self.idle_current_a(feed_mm_min)) / self.sensitivity_a_per_n,
            in_range: self.current_range_a.contains_loosely(current_a)
                && self.feed_range_mm_min.contains_loosely(feed_mm_min.abs()),
        }
    }
}

/// One calibrated spindle speed of paper 003's model.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpindleSpeedRow {
    /// Spindle speed of this row.
    pub speed_rpm: f64,
    /// Idle (air-cut) RMS current at this speed.
    pub idle_current_a: f64,
    /// RMS current per newton of peak cutting force at this speed.
    pub sensitivity_a_per_n: f64,
    /// Fit quality at this speed.
    pub quality: FitQuality,
    /// Current range seen at this speed.
    pub current_range_a: Range,
}

/// Paper 003's spindle model: I_rms = I_idle(n) + S(n)·F_peak, per gear.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpindleCurrentModel {
    /// The spindle speed at which the gearbox changes range (paper 003: 900 rpm); rows on either
    /// side are never mixed.
    pub gear_change_rpm: f64,
    /// Calibrated rows, ascending in speed.
    pub rows: Vec<SpindleSpeedRow>,
}

/// Speeds within this fraction of each other are one calibration speed.
const SPEED_CLUSTER_TOLERANCE: f64 = 0.02;

impl SpindleCurrentModel {
    /// Fits one line per distinct spindle speed in the teach-cut samples. A speed is a run of
    /// sorted speeds each within 2 % of the one before: a spindle that droops under load gives a
    /// continuum of measured speeds, which is one speed, however wide the droop, while two
    /// programmed speeds leave a gap between them. Every speed needs at least three samples at
    /// two or more loads.
    pub fn calibrate(
        current_a: &[f64],
        speed_rpm: &[f64],
        force_n: &[f64],
        gear_change_rpm: f64,
    ) -> Result<Self, FitError> {
        let n = current_a.len().min(speed_rpm.len()).min(force_n.len());
        let mut order: Vec<usize> = (0..n)
            .filter(|&i| {
                current_a[i].is_finite() && speed_rpm[i].is_finite() && force_n[i].is_finite()
            })
            .collect();
        order.sort_by(|&a, &b| speed_rpm[a].total_cmp(&speed_rpm[b]));
        let mut rows = Vec::new();
        let mut start = 0;
        while start < order.len() {
            let base = speed_rpm[order[start]];
            let mut end = start + 1;
            while end < order.len()
                && speed_rpm[order[end]]
                    <= speed_rpm[order[end - 1]] * (1.0 + SPEED_CLUSTER_TOLERANCE)
                && in_high_speed_range(base, gear_change_rpm)
                    == in_high_speed_range(speed_rpm[order[end]], gear_change_rpm)
            {
                end += 1;
            }
            let group = &order[start..end];
            start = end;
            if group.len() < 3 {
                continue;
            }
            let currents: Vec<f64> = group.iter().map(|&i| current_a[i]).collect();
            let forces: Vec<f64> = group.iter().map(|&i| force_n[i]).collect();
            let ones = vec![1.0; group.len()];
            let Ok(f) = fit(&[("idle current", &ones), ("force", &forces)], &currents) else {
                continue;
            };
            if f.coefficients[1] <= 0.0 {
                continue;
            }
            let speed = group.iter().map(|&i| speed_rpm[i]).sum::<f64>() / group.len() as f64;
            rows.push(SpindleSpeedRow {
                speed_rpm: speed,
                idle_current_a: f.coefficients[0],
                sensitivity_a_per_n: f.coefficients[1],
                quality: FitQuality::from_fit(&f, f.coefficients[1]),
                current_range_a: Range::of(currents.iter().copied()),
            });
        }
        if rows.is_empty() {
            return Err(FitError::TooFewSamples {
                samples: order.len(),
                unknowns: 2,
            });
        }
        Ok(Self {
            gear_change_rpm,
            rows,
        })
    }

    /// Idle current and sensitivity at `speed_rpm`: interpolated between the two nearest rows of
    /// the same gear, held constant beyond the outermost row. The flag says whether the speed
    /// lies between calibrated rows.
    pub fn line_at(&self, speed_rpm: f64) -> (f64, f64, bool) {
        let high_range = in_high_speed_range(speed_rpm, self.gear_change_rpm);
        let same_gear: Vec<&SpindleSpeedRow> = self
            .rows
            .iter()
            .filter(|r| in_high_speed_range(r.speed_rpm, self.gear_change_rpm) == high_range)
            .collect();
        let Some(first) = same_gear.first() else {
            // No row in this gear: extrapolate from the nearest row of the other one.
            let nearest = self.rows.iter().min_by(|a, b| {
                (a.speed_rpm - speed_rpm)
                    .abs()
                    .total_cmp(&(b.speed_rpm - speed_rpm).abs())
            });
            return nearest.map_or((f64::NAN, f64::NAN, false), |r| {
                (r.idle_current_a, r.sensitivity_a_per_n, false)
            });
        };
        let last = same_gear[same_gear.len() - 1];
        if speed_rpm <= first.speed_rpm {
            let inside = (first.speed_rpm - speed_rpm) <= first.speed_rpm * SPEED_CLUSTER_TOLERANCE;
            return (first.idle_current_a, first.sensitivity_a_per_n, inside);
        }
        if speed_rpm >= last.speed_rpm {
            let inside = (speed_rpm - last.speed_rpm) <= last.speed_rpm * SPEED_CLUSTER_TOLERANCE;
            return (last.idle_current_a, last.sensitivity_a_per_n, inside);
        }
        let upper = same_gear
            .iter()
            .position(|r| r.speed_rpm >= speed_rpm)
            .unwrap_or(0);
        let (a, b) = (same_gear[upper.saturating_sub(1)], same_gear[upper]);
        let t = (speed_rpm - a.speed_rpm) / (b.speed_rpm - a.speed_rpm);
        (
            a.idle_current_a + t * (b.idle_current_a - a.idle_current_a),
            a.sensitivity_a_per_n + t * (b.sensitivity_a_per_n - a.sensitivity_a_per_n),
            true,
        )
    }

    /// The peak force per revolution for a peak RMS current at a spindle speed.
    pub fn estimate(&self, current_a: f64, speed_rpm: f64) -> ForceEstimate {
        let (idle, sensitivity, speed_inside) = self.line_at(speed_rpm);
        let current_inside = self.rows.iter().any(|r| {
            (r.speed_rpm - speed_rpm).abs() <= r.speed_rpm * 0.25
                && r.current_range_a.contains_loosely(current_a)
        });
        ForceEstimate {
            force_n: (current_a - idle) / sensitivity,
            in_range: speed_inside && current_inside,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Rng;

    /// Synthetic teach cut: idle and sensitivity rising with speed, a jump at 900 rpm.
    fn spindle_truth(speed: f64) -> (f64, f64) {
        if speed <= 900.0 {
            (2.0 + 0.001 * speed, 0.004 + 2e-6 * speed)
        } else {
            (3.0 + 0.001 * speed, 0.002 + 2e-6 * speed)
        }
    }

    fn teach_cut(noise_a: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
        let mut rng = Rng::seed_from(9);
        let (mut i, mut n, mut f) = (Vec::new(), Vec::new(), Vec::new());
        for speed in [300.0, 600.0, 850.0, 1200.0, 2000.0, 3000.0] {
            for k in 0..40 {
                let force = 50.0 * f64::from(k % 10);
                let (idle, s) = spindle_truth(speed);
                i.push(idle + s * force + rng.gaussian(noise_a));
                n.push(speed * (1.0 + 0.005 * (rng.uniform() - 0.5)));
                f.push(force);
            }
        }
        (i, n, f)
    }

    #[test]
    fn spindle_calibration_recovers_each_speed_and_keeps_the_gears_apart() {
        let (i, n, f) = teach_cut(0.0);
        let model = SpindleCurrentModel::calibrate(&i, &n, &f, 900.0).unwrap();
        assert_eq!(model.rows.len(), 6);
        for row in &model.rows {
            let (idle, s) = spindle_truth(row.speed_rpm);
            assert!((row.idle_current_a - idle).abs() < 1e-3, "{row:?}");
            assert!((row.sensitivity_a_per_n - s).abs() / s < 1e-3, "{row:?}");
            assert!(row.quality.r_squared > 0.999_999);
        }
        // Interpolation within the high gear, and the discontinuity at the gear change.
        let (_, s_low, _) = model.line_at(899.0);
        let (_, s_high, _) = model.line_at(1100.0);
        assert!(
            s_low > s_high,
            "sensitivity must drop across the gear change"
        );
        let e = model.estimate(
            spindle_truth(1500.0).0 + spindle_truth(1500.0).1 * 200.0,
            1500.0,
        );
        // Linear interpolation of a linear sensitivity is exact up to the speed jitter.
        assert!((e.force_n - 200.0).abs() < 2.0, "{e:?}");
        assert!(e.in_range);
        assert!(!model.estimate(50.0, 1500.0).in_range);
        assert!(!model.estimate(3.0, 5000.0).in_range);
    }

    #[test]
    fn noisy_calibration_reports_its_residual() {
        let (i, n, f) = teach_cut(0.05);
        let model = SpindleCurrentModel::calibrate(&i, &n, &f, 900.0).unwrap();
        for row in &model.rows {
            assert!((row.quality.residual_std_a - 0.05).abs() < 0.02, "{row:?}");
            assert!(row.quality.r_squared < 1.0);
        }
    }

    #[test]
    fn feed_model_rejects_a_teach_cut_without_load_changes() {
        let current = [1.0, 1.1, 1.2, 1.3];
        let feed = [100.0, 200.0, 300.0, 400.0];
        let force = [0.0; 4];
        assert!(FeedCurrentModel::calibrate(&current, &feed, &force).is_err());
    }
}
