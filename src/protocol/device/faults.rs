//! The faults the device reads and reports: the over-current, the sensor fault of a non-finite
//! current or of a drive whose three phases do not sum to zero (the phase check), and the Fault
//! frame that reports each as a level.

use super::{cpct, DeviceEmulator, HoldCause};
use crate::protocol::frame::{Fault, FaultKind, Frame};

/// [`Fault::channel`] when the fault concerns no channel.
pub(super) const NO_CHANNEL: u8 = 0xFF;

/// The window, device time, over which the three phases of a drive are checked to sum to zero.
pub const PHASE_CHECK_WINDOW_S: f64 = 0.1;
/// Below this RMS phase current a drive's phase sum says nothing (noise and offsets dominate):
/// its sensors are not judged.
pub const PHASE_CHECK_MIN_A: f64 = 1.0;
/// A drive whose three phases' sum has an RMS above this fraction of the phases' RMS has an open
/// or stuck sensor (a healthy drive's sum is its sensors' noise and offsets: no preset raises
/// the fault, tests/host.rs).
pub const PHASE_SUM_TOLERANCE: f64 = 0.25;

/// The running sums of one drive's phase check ([`PHASE_CHECK_WINDOW_S`]).
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct PhaseWindow {
    sum_sq: f64,
    phase_sq: [f64; 3],
}

impl PhaseWindow {
    pub(super) fn add(&mut self, i: [f64; 3]) {
        let sum = i[0] + i[1] + i[2];
        if sum.is_finite() {
            self.sum_sq += sum * sum;
            for (sq, x) in self.phase_sq.iter_mut().zip(i) {
                *sq += x * x;
            }
        }
    }

    /// The verdict over `n` samples: `Some(channel offset)` of the sensor that reads least when
    /// the phases do not sum to zero, `None` when they do; `Err(())` when the current is too low
    /// to tell.
    fn verdict(&self, n: f64) -> Result<Option<usize>, ()> {
        let phase_rms = (self.phase_sq.iter().sum::<f64>() / (3.0 * n)).sqrt();
        // NaN (no finite sample in the window) says nothing either.
        if phase_rms.is_nan() || phase_rms <= PHASE_CHECK_MIN_A {
            return Err(());
        }
        let sum_rms = (self.sum_sq / n).sqrt();
        if sum_rms <= PHASE_SUM_TOLERANCE * phase_rms {
            return Ok(None);
        }
        let weakest = (0..3)
            .min_by(|&a, &b| self.phase_sq[a].total_cmp(&self.phase_sq[b]))
            .unwrap_or(0);
        Ok(Some(weakest))
    }
}

/// Ends a phase-check window of `n` samples: each drive with enough current is judged by its
/// three phases' sum (its verdict the channel bit of its open or stuck sensor, or none), a drive
/// with too little keeps its verdict.
pub(super) fn judge_phases(
    windows: &mut [PhaseWindow; 2],
    n: &mut usize,
    verdicts: &mut [Option<u8>; 2],
) {
    for (drive, (window, verdict)) in windows.iter().zip(verdicts.iter_mut()).enumerate() {
        if let Ok(v) = window.verdict(*n as f64) {
            // Channel bits: spindle u, v, w = 0, 1, 2; feed u, v, w = 3, 4, 5.
            *verdict = v.map(|k| (3 * drive + k) as u8);
        }
    }
    *windows = [PhaseWindow::default(); 2];
    *n = 0;
}

impl DeviceEmulator {
    pub(super) fn report_fault(
        &mut self,
        kind: FaultKind,
        active: bool,
        channel: u8,
        out: &mut Vec<u8>,
    ) {
        self.fault_seq = self.fault_seq.wrapping_add(1);
        let fault = Fault {
            seq: self.fault_seq,
            time_us: self.time_us(),
            kind,
            active: u8::from(active),
            channel,
            applied_override_cpct: cpct(self.applied.pct),
        };
        self.send(&Frame::Fault(fault), out);
    }

    pub(super) fn watch_currents(
        &mut self,
        over_current: bool,
        non_finite: bool,
        out: &mut Vec<u8>,
    ) {
        if over_current != self.over_current {
            self.over_current = over_current;
            if over_current {
                self.latch_hold(HoldCause::OverCurrent);
            }
            self.report_fault(FaultKind::OverCurrent, over_current, NO_CHANNEL, out);
        }
        let channel = self.phase_fault.iter().flatten().next().copied();
        let sensor_fault = non_finite || channel.is_some();
        if sensor_fault != self.sensor_fault {
            self.sensor_fault = sensor_fault;
            if let Some(c) = channel {
                self.log(format!(
                    "sensor fault on channel {c}: the drive's three phases do not sum to zero \
                     (an open or stuck transducer)"
                ));
            }
            self.report_fault(
                FaultKind::Sensor,
                sensor_fault,
                channel.unwrap_or(NO_CHANNEL),
                out,
            );
        }
    }
}
