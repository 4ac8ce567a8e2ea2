//! The chip-load window: [`ChipLoad`], the feed per tooth a cutter may take in the work
//! material; [`chip_load_band_pct`], the overrides it leaves at a period's programmed feed and
//! spindle speed; and [`ChipLoadEnd`], which end of it held the override.

/// The chip-load window: the feed per tooth a cutter of `teeth` teeth may take in the work
/// material. Below `min_mm` the edge rubs instead of cutting (its edge radius is of that order);
/// above `max_mm` the chip overloads the edge. The override that keeps a period's feed per tooth
/// inside follows from the programmed feed and spindle speed:
/// `f_z = programmed feed × override / (teeth × rpm)`.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ChipLoad {
    /// Teeth of the cutter.
    pub teeth: u32,
    /// Smallest feed per tooth, mm.
    pub min_mm: f64,
    /// Largest feed per tooth, mm.
    pub max_mm: f64,
}

impl ChipLoad {
    /// The overrides, %, that keep the feed per tooth inside the window at `programmed_feed_mm_min`
    /// and `spindle_rpm`; `None` where the two give no feed per tooth (the spindle or the axes
    /// standing still).
    ///
    /// ```
    /// use cutlab::safety::ChipLoad;
    /// let window = ChipLoad { teeth: 2, min_mm: 0.02, max_mm: 0.15 };
    /// // 200 mm/min at 1000 rpm is 0.1 mm per tooth: 20–150 % keeps it inside.
    /// let (lo, hi) = window.override_range_pct(200.0, 1000.0).unwrap();
    /// assert!((lo - 20.0).abs() < 1e-9 && (hi - 150.0).abs() < 1e-9);
    /// assert!(window.override_range_pct(0.0, 1000.0).is_none());
    /// ```
    pub fn override_range_pct(
        &self,
        programmed_feed_mm_min: f64,
        spindle_rpm: f64,
    ) -> Option<(f64, f64)> {
        let per_tooth_at_100 = programmed_feed_mm_min / (f64::from(self.teeth) * spindle_rpm);
        (per_tooth_at_100.is_finite() && per_tooth_at_100 > 0.0).then(|| {
            (
                100.0 * self.min_mm / per_tooth_at_100,
                100.0 * self.max_mm / per_tooth_at_100,
            )
        })
    }

    /// The feed per tooth at `override_pct`, mm (NaN where the spindle stands).
    pub fn feed_per_tooth_mm(
        &self,
        programmed_feed_mm_min: f64,
        spindle_rpm: f64,
        override_pct: f64,
    ) -> f64 {
        programmed_feed_mm_min * override_pct / 100.0 / (f64::from(self.teeth) * spindle_rpm)
    }
}

/// The overrides the envelope commands inside in a period at `programmed_feed_mm_min` and
/// `spindle_rpm`, %: the band `(min, max)` narrowed to those that keep the feed per tooth inside
/// `window`; the whole band without a window, or where the feed and speed give no feed per tooth.
/// A window that lies outside the band gives the band's nearer end (the band is the machine's).
///
/// ```
/// use cutlab::safety::{chip_load_band_pct, ChipLoad};
/// let window = ChipLoad { teeth: 2, min_mm: 0.02, max_mm: 0.15 };
/// // 200 mm/min at 1000 rpm: 20–150 % keeps the feed per tooth inside, within 0–255 %.
/// assert_eq!(chip_load_band_pct(Some(&window), (0.0, 255.0), 200.0, 1000.0), (20.0, 150.0));
/// assert_eq!(chip_load_band_pct(Some(&window), (10.0, 120.0), 200.0, 1000.0), (20.0, 120.0));
/// assert_eq!(chip_load_band_pct(None, (10.0, 120.0), 200.0, 1000.0), (10.0, 120.0));
/// ```
pub fn chip_load_band_pct(
    window: Option<&ChipLoad>,
    (min_pct, max_pct): (f64, f64),
    programmed_feed_mm_min: f64,
    spindle_rpm: f64,
) -> (f64, f64) {
    match window.and_then(|w| w.override_range_pct(programmed_feed_mm_min, spindle_rpm)) {
        Some((lo, hi)) => (lo.clamp(min_pct, max_pct), hi.clamp(min_pct, max_pct)),
        None => (min_pct, max_pct),
    }
}

/// Which end of the chip-load window held the override.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum ChipLoadEnd {
    /// The smallest feed per tooth: the edge would rub.
    Lowest,
    /// The largest: the edge would be overloaded.
    Highest,
}
