//! The signal chain of the closed loop, per sensor sample, summarised once per control period.
//!
//! ```text
//! phase currents i_u, i_v, i_w ─► Butterworth low-pass (per phase) ─► three-phase RMS (eq 7)
//!                               ─► mean over the control period
//! ```
//!
//! for both the spindle and the feed drive. The control period of a mill is a whole number of
//! spindle revolutions, so the period mean removes the tooth-passing ripple exactly; that mean is
//! what paper 003's quasi-static sensitivity relates to the cutting load. The period also keeps
//! the truth a simulation offers beside it — the mean force vector's magnitude, the quantity the
//! papers' force targets refer to — and the minimum and maximum of the raw signals for plotting.
//!
//! Filtering and RMS come from [`crate::signal`]; nothing here allocates after construction.
//! A current that is not a number (NaN, ±∞: a log's gap, a sensor's dropout) is replaced by the
//! same phase's last reading before the filters see it, so the estimate recovers with the sensor;
//! flagging the fault and holding the override meanwhile is the safety envelope's work.
//! The phase currents are gathered into blocks of [`BLOCK_FRAMES`] samples and filtered a block
//! at a time (the filter bank's vector kernel, with the same bits as sample by sample), and the
//! RMS of each sample is summed in order when the block is flushed, so a period's summary is the
//! same whether its samples come one by one or in a slice.

use crate::machine::{DynamometerReading, MachineStep};
use crate::signal::filter::{NoChannels, SosFilterBank};
use crate::signal::rms::three_phase_rms;
use crate::signal::sos::Sos;
use crate::signal::stats::MinMeanMax;

/// One control period, summarised.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct PeriodSummary {
    /// Samples in the period.
    pub samples: usize,
    /// Time of the period's last sample.
    pub end_time_s: f64,
    /// Mean three-phase RMS of the filtered spindle currents.
    pub spindle_current_rms_a: f64,
    /// Mean three-phase RMS of the filtered feed currents.
    pub feed_current_rms_a: f64,
    /// Mean F/V converter voltage.
    pub spindle_fv_voltage_v: f64,
    /// Mean reported spindle speed.
    pub spindle_speed_rpm: f64,
    /// Programmed spindle speed at the period's end.
    pub spindle_command_rpm: f64,
    /// Mean path feed.
    pub feed_mm_min: f64,
    /// |mean of (F_x, F_y)| over the period (NaN without truth).
    pub force_mean_resultant_n: f64,
    /// Mean feed-direction force (NaN without truth).
    pub feed_force_n: f64,
    /// Smallest and largest instantaneous resultant force.
    pub force_min_max_n: (f64, f64),
    /// Smallest and largest raw feed phase current i_u.
    pub feed_current_u_min_max_a: (f64, f64),
    /// Mean depth of cut (NaN without truth).
    pub depth_mm: f64,
    /// Mean width of cut.
    pub width_mm: f64,
    /// Mean material removal rate.
    pub material_removal_mm3_s: f64,
    /// Path position at the end.
    pub path_position_mm: f64,
    /// |mean of the dynamometer's (F_x, F_y)| over the period (NaN without a dynamometer).
    pub dynamometer_resultant_n: f64,
    /// Mean of the dynamometer's feed-direction force (NaN without a dynamometer).
    pub dynamometer_feed_force_n: f64,
}

/// Samples gathered before the filters run over them as one slice.
pub const BLOCK_FRAMES: usize = 128;

/// Puts in place of each current of `frames` (interleaved `u v w`) that is not a number the same
/// phase's last one that was, and leaves in `last` each phase's last number.
///
/// A low-pass filter remembers its input: one NaN (a log's empty cell, a sensor's dropout) would
/// make its state, and every estimate after it, NaN for good, while the safety envelope — which
/// watches the raw samples, flags the fault and holds the override — clears the fault 100 ms
/// later. Holding the last reading keeps the filter's memory finite, so the estimate recovers
/// with the sensor. Currents that are all numbers are left as they are, bit for bit.
fn hold_non_finite(frames: &mut [f64], last: &mut [f64; 3]) {
    let (frames, _) = frames.as_chunks_mut::<3>();
    if frames.iter().flatten().all(|i| i.is_finite()) {
        if let Some(newest) = frames.last() {
            *last = *newest;
        }
        return;
    }
    for frame in frames {
        for (i, held) in frame.iter_mut().zip(last.iter_mut()) {
            if i.is_finite() {
                *held = *i;
            } else {
                *i = *held;
            }
        }
    }
}

/// Per-sample processing and the running sums of one period.
#[derive(Debug, Clone)]
pub struct SignalChain {
    spindle_filter: SosFilterBank,
    feed_filter: SosFilterBank,
    /// Phase currents not yet filtered, interleaved `u v w u v w …`: the first `3·gathered`
    /// values of each.
    spindle_block: Box<[f64; 3 * BLOCK_FRAMES]>,
    feed_block: Box<[f64; 3 * BLOCK_FRAMES]>,
    gathered: usize,
    /// Each phase's last current that was a number, held in place of one that is not.
    spindle_last_finite: [f64; 3],
    feed_last_finite: [f64; 3],
    sums: Sums,
}

#[derive(Debug, Clone, Copy, Default)]
struct Sums {
    n: usize,
    end_time_s: f64,
    spindle_rms: f64,
    feed_rms: f64,
    fv: f64,
    speed: f64,
    command_rpm: f64,
    feed: f64,
    fx: f64,
    fy: f64,
    feed_force: f64,
    force: MinMeanMax,
    iu: MinMeanMax,
    depth: f64,
    width: f64,
    mrr: f64,
    position: f64,
    truth_seen: bool,
    dynamometer_n: usize,
    dynamometer_x: f64,
    dynamometer_y: f64,
    dynamometer_feed: f64,
}

impl SignalChain {
    /// A chain with the given low-pass filters on the spindle and feed phase currents.
    pub fn new(spindle_lowpass: &Sos, feed_lowpass: &Sos) -> Result<Self, NoChannels> {
        Ok(Self {
            spindle_filter: SosFilterBank::new(spindle_lowpass, 3)?,
            feed_filter: SosFilterBank::new(feed_lowpass, 3)?,
            spindle_block: Box::new([0.0; 3 * BLOCK_FRAMES]),
            feed_block: Box::new([0.0; 3 * BLOCK_FRAMES]),
            gathered: 0,
            spindle_last_finite: [0.0; 3],
            feed_last_finite: [0.0; 3],
            sums: Sums::default(),
        })
    }

    /// Takes one sample.
    #[inline(always)]
    pub fn push(&mut self, step: &MachineStep) {
        let s = &step.sensors;
        let at = 3 * self.gathered;
        for k in 0..3 {
            self.spindle_block[at + k] = s.spindle_phase_currents_a[k];
            self.feed_block[at + k] = s.feed_phase_currents_a[k];
        }
        self.gathered += 1;
        if self.gathered == BLOCK_FRAMES {
            self.flush();
        }
        let sums = &mut self.sums;
        sums.n += 1;
        sums.end_time_s = s.time_s;
        sums.fv += s.spindle_fv_voltage_v;
        sums.speed += s.spindle_speed_rpm;
        sums.command_rpm = s.spindle_command_rpm;
        sums.feed += s.feed_mm_min;
        sums.iu.push(s.feed_phase_currents_a[0]);
        if let Some(t) = &step.truth {
            sums.fx += t.force_x_n;
            sums.fy += t.force_y_n;
            sums.feed_force += t.feed_force_n;
            sums.force.push(t.force_resultant_n);
            sums.depth += t.depth_mm;
            sums.width += t.width_mm;
            sums.mrr += t.material_removal_mm3_s;
            sums.position = t.path_position_mm;
            sums.truth_seen = true;
        }
    }

    /// Takes one sample of a dynamometer's reading, beside the sample of the same instant.
    pub fn push_dynamometer(&mut self, reading: &DynamometerReading) {
        let sums = &mut self.sums;
        sums.dynamometer_n += 1;
        sums.dynamometer_x += reading.force_x_n;
        sums.dynamometer_y += reading.force_y_n;
        sums.dynamometer_feed += reading.feed_force_n;
    }

    /// Filters the gathered phase currents and adds each sample's three-phase RMS to the sums.
    fn flush(&mut self) {
        let n = 3 * self.gathered;
        self.gathered = 0;
        let (spindle, feed) = (&mut self.spindle_block[..n], &mut self.feed_block[..n]);
        hold_non_finite(spindle, &mut self.spindle_last_finite);
        hold_non_finite(feed, &mut self.feed_last_finite);
        self.spindle_filter.process_slice(spindle);
        self.feed_filter.process_slice(feed);
        let sums = &mut self.sums;
        for i in spindle.as_chunks::<3>().0 {
            sums.spindle_rms += three_phase_rms(i[0], i[1], i[2]);
        }
        for i in feed.as_chunks::<3>().0 {
            sums.feed_rms += three_phase_rms(i[0], i[1], i[2]);
        }
    }

    /// Ends the period: returns its summary and starts the next one.
    pub fn finish_period(&mut self) -> PeriodSummary {
        self.flush();
        let s = std::mem::take(&mut self.sums);
        let n = s.n.max(1) as f64;
        let truth = |v: f64| if s.truth_seen { v / n } else { f64::NAN };
        PeriodSummary {
            samples: s.n,
            end_time_s: s.end_time_s,
            spindle_current_rms_a: s.spindle_rms / n,
            feed_current_rms_a: s.feed_rms / n,
            spindle_fv_voltage_v: s.fv / n,
            spindle_speed_rpm: s.speed / n,
            spindle_command_rpm: s.command_rpm,
            feed_mm_min: s.feed / n,
            force_mean_resultant_n: if s.truth_seen {
                crate::math::hypot(s.fx / n, s.fy / n)
            } else {
                f64::NAN
            },
            feed_force_n: truth(s.feed_force),
            // NaN without truth: nothing was pushed.
            force_min_max_n: s.force.min_max(),
            feed_current_u_min_max_a: s.iu.min_max(),
            depth_mm: truth(s.depth),
            width_mm: truth(s.width),
            material_removal_mm3_s: truth(s.mrr),
            path_position_mm: if s.truth_seen { s.position } else { f64::NAN },
            dynamometer_resultant_n: if s.dynamometer_n > 0 {
                let m = s.dynamometer_n as f64;
                crate::math::hypot(s.dynamometer_x / m, s.dynamometer_y / m)
            } else {
                f64::NAN
            },
            dynamometer_feed_force_n: if s.dynamometer_n > 0 {
                s.dynamometer_feed / s.dynamometer_n as f64
            } else {
                f64::NAN
            },
        }
    }

    /// Back to the start: filter states cleared, nothing summed.
    pub fn reset(&mut self) {
        self.spindle_filter.reset();
        self.feed_filter.reset();
        self.gathered = 0;
        self.spindle_last_finite = [0.0; 3];
        self.feed_last_finite = [0.0; 3];
        self.sums = Sums::default();
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::machine::SensorSample;
    use crate::signal::butterworth::{butter, ButterworthSpec, Cutoff, FilterKind};

    fn chain() -> SignalChain {
        let lowpass = butter(&ButterworthSpec {
            kind: FilterKind::Lowpass,
            order: 4,
            cutoff_hz: Cutoff::Single(500.0),
            sample_rate_hz: 10_000.0,
        })
        .unwrap();
        SignalChain::new(&lowpass, &lowpass).unwrap()
    }

    fn sample(n: usize, spindle_a: [f64; 3], feed_a: [f64; 3]) -> MachineStep {
        MachineStep {
            sensors: SensorSample {
                time_s: n as f64 * 1e-4,
                spindle_phase_currents_a: spindle_a,
                feed_phase_currents_a: feed_a,
                ..Default::default()
            },
            truth: None,
        }
    }

    #[test]
    fn a_current_that_is_not_a_number_is_held_and_the_estimate_recovers() {
        // A steady three-phase set: the reading held in place of a lost one equals it, so the
        // damaged stream must give the clean stream's summaries bit for bit, in the period of the
        // damage and every one after (a NaN in a filter's memory would make them all NaN).
        let (spindle, feed) = ([3.0, -1.0, -2.0], [1.0, -0.5, -0.5]);
        let (mut clean, mut damaged) = (chain(), chain());
        for period in 0..4 {
            for k in 0..600 {
                let n = period * 600 + k;
                clean.push(&sample(n, spindle, feed));
                let (mut s, mut f) = (spindle, feed);
                match n {
                    700 => s[1] = f64::NAN,
                    701 => s = [f64::INFINITY; 3],
                    1500 => f[2] = f64::NEG_INFINITY,
                    _ => {}
                }
                damaged.push(&sample(n, s, f));
            }
            let (a, b) = (clean.finish_period(), damaged.finish_period());
            assert!(b.spindle_current_rms_a.is_finite(), "period {period}");
            assert_eq!(
                a.spindle_current_rms_a, b.spindle_current_rms_a,
                "period {period}"
            );
            assert_eq!(
                a.feed_current_rms_a, b.feed_current_rms_a,
                "period {period}"
            );
        }
        // Reset forgets the held readings: a NaN first thing is held as no current.
        damaged.reset();
        damaged.push(&sample(0, [f64::NAN; 3], feed));
        assert_eq!(damaged.finish_period().spindle_current_rms_a, 0.0);
    }
}
