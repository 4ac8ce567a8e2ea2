//! The link through the injected faults ([`FaultInjection`]): the receiver's stall and the
//! unplugged cable, frames lost or corrupted either way, and every frame the device sends encoded
//! into the bytes out.
//!
//! [`FaultInjection`]: super::FaultInjection

use super::DeviceEmulator;
use crate::protocol::codec::{encode_frame, MAX_FRAME_LEN};
use crate::protocol::frame::Frame;

impl DeviceEmulator {
    /// Updates the stall and unplug state for the current time.
    pub(super) fn update_link_faults(&mut self) {
        let t = self.time_s();
        let f = self.config.faults;
        let stalled = f.stall_at_s.is_some_and(|at| t >= at && t < at + f.stall_s);
        if stalled != self.stalled {
            self.stalled = stalled;
            self.log(if stalled {
                format!("receiver stalled for {} s (injected)", f.stall_s)
            } else {
                "receiver running again".to_string()
            });
        }
        let unplugged = f.unplug_at_s.is_some_and(|at| t >= at);
        if unplugged && !self.unplugged {
            self.unplugged = true;
            self.log("cable unplugged (injected): nothing goes in or out".to_string());
        }
    }

    /// Whether injection loses or corrupts a received frame.
    pub(super) fn injected_loss(&mut self) -> bool {
        let f = self.config.faults;
        if f.drop_rate > 0.0 && self.rng.uniform() < f.drop_rate {
            self.stats.frames_dropped += 1;
            return true;
        }
        if f.noise_rate > 0.0 && self.rng.uniform() < f.noise_rate {
            self.stats.frames_corrupted += 1;
            return true;
        }
        false
    }

    /// Encodes `frame` into `out`, through the injected faults.
    pub(super) fn send(&mut self, frame: &Frame, out: &mut Vec<u8>) {
        if self.unplugged {
            return;
        }
        self.stats.frames_sent += 1;
        let f = self.config.faults;
        if f.drop_rate > 0.0 && self.rng.uniform() < f.drop_rate {
            self.stats.frames_dropped += 1;
            return;
        }
        let mut buf = [0u8; MAX_FRAME_LEN];
        let Ok(n) = encode_frame(frame, &mut buf) else {
            return;
        };
        let bytes = buf.get_mut(..n).unwrap_or_default();
        if f.noise_rate > 0.0 && self.rng.uniform() < f.noise_rate && n > 2 {
            // A bit flipped anywhere between the delimiters.
            let i = 1 + (self.rng.next_u64() % (n as u64 - 2)) as usize;
            let bit = (self.rng.next_u64() % 8) as u8;
            if let Some(b) = bytes.get_mut(i) {
                *b ^= 1 << bit;
            }
            self.stats.frames_corrupted += 1;
        }
        out.extend_from_slice(bytes);
    }
}
