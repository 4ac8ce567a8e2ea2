//! One part the device runs, as a [`Machine`] over a [`HostLink`].

use std::cell::RefCell;
use std::rc::Rc;

use super::{HostLink, TEACH_CUT_FELL_BACK};
use crate::machine::{Machine, MachineStep, OverrideCommand};
use crate::protocol::frame::sample_flag;

/// One part the device runs, as a [`Machine`]: its first step arms the device (the emulator
/// loads a part and starts the cycle), it ends at the program end or when the link is lost.
pub struct LinkPart {
    link: Rc<RefCell<HostLink>>,
    sample_rate_hz: f64,
    started: bool,
    done: bool,
    last: MachineStep,
    /// The part ends for the loop at this machine time (a duration limit).
    stop_at_s: Option<f64>,
    /// It did end there.
    stopped_at_limit: Rc<RefCell<bool>>,
    /// A teach cut's part: it ends at the first sample of a watchdog fallback.
    abandons_on_fallback: bool,
}

impl LinkPart {
    /// The next part on `link`.
    pub fn new(link: Rc<RefCell<HostLink>>) -> Self {
        let sample_rate_hz = f64::from(link.borrow().capabilities.sample_rate_hz);
        Self {
            link,
            sample_rate_hz,
            started: false,
            done: false,
            last: MachineStep::default(),
            stop_at_s: None,
            stopped_at_limit: Rc::new(RefCell::new(false)),
            abandons_on_fallback: false,
        }
    }

    /// The same part as a teach cut's: from the first sample of a device watchdog fallback on,
    /// the machine runs at the fallback override while the teach schedule would label each period
    /// with the override it commanded, so the part ends there, the session says so, and the link
    /// arms no further part ([`HostLink::fell_back_in_part`]): no calibration is made of it.
    pub fn abandoning_on_fallback(mut self) -> Self {
        self.abandons_on_fallback = true;
        self
    }

    /// Ends the part for the loop at machine time `stop_at_s` (a duration limit); the flag
    /// returned says, afterwards, whether it did end there.
    pub fn stop_at(&mut self, stop_at_s: Option<f64>) -> Rc<RefCell<bool>> {
        self.stop_at_s = stop_at_s;
        Rc::clone(&self.stopped_at_limit)
    }
}

impl Machine for LinkPart {
    fn sample_rate_hz(&self) -> f64 {
        self.sample_rate_hz
    }

    fn step(&mut self, command: OverrideCommand) -> MachineStep {
        if self.done {
            return self.last;
        }
        let mut link = self.link.borrow_mut();
        if !self.started {
            self.started = true;
            if !link.begin_part() {
                self.done = true;
                return self.last;
            }
        }
        link.keep_up(command);
        match link.next_sample() {
            Some(s) => {
                self.last = s.step;
                if s.program_end {
                    self.done = true;
                    link.part_running = false;
                    link.session.event("program end");
                } else if link.alarm.is_some() {
                    // A device fault: the loop ends with this sample; the link holds the part.
                    self.done = true;
                } else if self.abandons_on_fallback && s.flags & sample_flag::FALLBACK != 0 {
                    self.done = true;
                    link.fell_back_in_part = Some(link.session.part());
                    link.session.event(TEACH_CUT_FELL_BACK);
                    link.write_events();
                } else if self.stop_at_s.is_some_and(|t| s.step.sensors.time_s >= t) {
                    self.done = true;
                    *self.stopped_at_limit.borrow_mut() = true;
                }
                s.step
            }
            None => {
                self.done = true;
                self.last
            }
        }
    }

    fn finished(&self) -> bool {
        self.done
    }
}
