//! The Hardware page's virtual device as its worker runs it: the emulator on a wall clock, ticked
//! by a timer, fed the bytes the host wrote and giving back the bytes it sent — the browser's
//! counterpart of [`super::link`]'s clocked device, without threads or I/O.
//!
//! The page sends a [`DeviceStart`] (the device form's texts by row key, and the truth switch) to
//! a worker of the computation module (`src/bin/cutlab-worker.rs`), which parses it with the one
//! [`parse_device`] into a [`ClockedDevice`] and ticks it every [`VIRTUAL_TICK_MS`]; the plant
//! thus lives in the worker's module, not the page's.
//!
//! ```
//! use cutlab::protocol::device_settings::DeviceSetting;
//! use cutlab::protocol::device_worker::{ClockedDevice, DeviceStart};
//! let start = DeviceStart::new(&[(DeviceSetting::Program, "kim-step-doc".to_string())], true);
//! let mut device = ClockedDevice::start(&DeviceStart::from_json(&start.to_json()).unwrap(), 0.0)
//!     .unwrap();
//! // 20 ms of wall time at real time: the device's clock is 20 frames of 1 ms on.
//! device.tick(0.020);
//! assert!((device.device_time_s() - 0.020).abs() < 1e-9);
//! ```

use serde::{Deserialize, Serialize};

use super::device::DeviceEmulator;
use super::device_settings::{parse_device, DeviceSetting};
use crate::input::table::{RowError, Table};

/// How often the virtual device runs, ms.
pub const VIRTUAL_TICK_MS: u32 = 10;

/// Frames the virtual device runs at most per tick, so a tick stays short; what a tick cannot
/// run is not caught up later (see [`ClockedDevice`]).
pub const MAX_VIRTUAL_FRAMES_PER_TICK: usize = 400;

/// The most wall time one tick moves the virtual device's clock on by, ms: two ticks. A tick
/// later than that finds a browser that was away (descheduled, throttled, busy), and the
/// simulated machine was paused meanwhile (see [`ClockedDevice`]).
pub const MAX_VIRTUAL_STEP_MS: u32 = 2 * VIRTUAL_TICK_MS;

/// What the page asks its device worker for: the device form's texts, by row key, and whether to
/// send the simulation's truth (off: a real bridge's twin, `cutlab device --no-truth`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DeviceStart {
    /// `(key, text)` of each row the form shows.
    pub texts: Vec<(String, String)>,
    /// Send SimTruth frames.
    pub sim_truth: bool,
}

impl DeviceStart {
    /// The request for the form's `texts`.
    pub fn new(texts: &[(DeviceSetting, String)], sim_truth: bool) -> Self {
        Self {
            texts: texts
                .iter()
                .map(|(s, text)| (s.row().key.to_string(), text.clone()))
                .collect(),
            sim_truth,
        }
    }

    /// As sent to the worker.
    pub fn to_json(&self) -> String {
        // Strings and a bool: nothing here can fail to serialise.
        serde_json::to_string(self).unwrap_or_default()
    }

    /// As the worker reads it.
    pub fn from_json(json: &str) -> Result<Self, String> {
        serde_json::from_str(json)
            .map_err(|e| format!("the virtual device's worker got a start it cannot read ({e})"))
    }
}

/// The device form's errors as one sentence, for "The virtual device cannot start: …".
pub fn refusal(errors: &[RowError<DeviceSetting>]) -> String {
    errors
        .iter()
        .map(|e| e.to_string())
        .collect::<Vec<_>>()
        .join("; ")
}

/// The device emulator on a wall clock at a time scale: what arrives waits in an inbox for the
/// next [`tick`](Self::tick), which runs the frames due.
///
/// ## A simulated machine pauses while the browser is away
///
/// A real machine's clock runs on whatever its host does, and a host that stops answering for
/// the device's watchdog timeout *is* a fault: the bridge firmware and `cutlab device` (its
/// clock [`super::link::run_device`], anchored to power-on) keep that strict. This device is a
/// simulation in the same browser as its host, and when the browser is descheduled both stop:
/// on waking, a clock anchored to power-on would find scale × the delay due at once and run it
/// before it could read the host's answer — a host that only looks silent, punished by the
/// watchdog (at 8× a 60 ms stall is 0.48 s of device time, about the default 0.5 s watchdog).
/// So each tick moves the clock on by the wall time since the last tick, at most
/// [`MAX_VIRTUAL_STEP_MS`], times the scale; frames it cannot run
/// ([`MAX_VIRTUAL_FRAMES_PER_TICK`]) are not caught up either. Time beyond is not simulated:
/// the machine, its plant and its watchdog pause with the browser. What the device hears is
/// unchanged: a host that keeps writing nothing while the ticks come — or a receiver stall or
/// pulled cable injected at the device — still trips the watchdog after its timeout in device
/// time.
pub struct ClockedDevice {
    device: DeviceEmulator,
    /// Wall time of the latest tick (or of power-on).
    last_tick_s: f64,
    /// Device time the clock has reached: the frames up to it are due.
    due_s: f64,
    time_scale: f64,
    inbox: Vec<u8>,
    out: Vec<u8>,
}

impl ClockedDevice {
    /// Powers on the device `request` describes, its clock starting at `now_s` (wall seconds).
    /// The form's errors and the emulator's refusal come back as one sentence.
    pub fn start(request: &DeviceStart, now_s: f64) -> Result<Self, String> {
        let texts = request
            .texts
            .iter()
            .map(|(key, text)| {
                DeviceSetting::from_key(key)
                    .map(|s| (s, text.as_str()))
                    .ok_or_else(|| format!("the virtual device has no setting \"{key}\""))
            })
            .collect::<Result<Vec<_>, _>>()?;
        let mut asked = parse_device(&texts).map_err(|e| refusal(&e))?;
        asked.config.sim_truth = request.sim_truth;
        let device = DeviceEmulator::new(asked.config).map_err(|e| e.to_string())?;
        Ok(Self {
            device,
            last_tick_s: now_s,
            due_s: 0.0,
            time_scale: asked.time_scale,
            inbox: Vec::new(),
            out: Vec::with_capacity(64 * 1024),
        })
    }

    /// Bytes the host wrote; the device reads them at its next tick.
    pub fn receive(&mut self, bytes: &[u8]) {
        self.inbox.extend_from_slice(bytes);
    }

    /// At wall time `now_s`: the device reads its inbox, its clock moves on by the wall time
    /// since the last tick (at most [`MAX_VIRTUAL_STEP_MS`]) times the scale, it runs the frames
    /// due (at most [`MAX_VIRTUAL_FRAMES_PER_TICK`]), and gives the bytes it sent (empty if
    /// none). A wall clock that stands still or goes back moves nothing.
    pub fn tick(&mut self, now_s: f64) -> Vec<u8> {
        let max_step_s = f64::from(MAX_VIRTUAL_STEP_MS) / 1000.0;
        let wall_step_s = now_s - self.last_tick_s;
        if wall_step_s > 0.0 {
            self.last_tick_s = now_s;
            self.due_s += wall_step_s.min(max_step_s) * self.time_scale;
        }
        let inbox = std::mem::take(&mut self.inbox);
        self.device.receive(&inbox, &mut self.out);
        let mut frames = 0;
        let period_s = self.device.frame_period_s();
        while self.device.time_s() + period_s <= self.due_s && frames < MAX_VIRTUAL_FRAMES_PER_TICK
        {
            self.device.step_frame(&mut self.out);
            frames += 1;
        }
        if frames == MAX_VIRTUAL_FRAMES_PER_TICK {
            // What this tick could not run is dropped, not caught up.
            self.due_s = self.device.time_s();
        }
        std::mem::take(&mut self.out)
    }

    /// The device's counts (its watchdog's fallbacks among them).
    pub fn stats(&self) -> super::device::DeviceStats {
        self.device.stats()
    }

    /// Device seconds since power-on.
    pub fn device_time_s(&self) -> f64 {
        self.device.time_s()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::codec::{encode_frame, MAX_FRAME_LEN};
    use crate::protocol::frame::{Arm, Frame, Heartbeat, Hello, VERSION_MAJOR, VERSION_MINOR};

    fn form(extra: &[(DeviceSetting, &str)]) -> Vec<(DeviceSetting, String)> {
        let mut texts = vec![(DeviceSetting::Program, "maneerat-doc-1".to_string())];
        texts.extend(extra.iter().map(|(s, t)| (*s, t.to_string())));
        texts
    }

    /// What a host says first: Hello, then Arm (a part starts and streams samples).
    fn hello_and_arm() -> Vec<u8> {
        let mut bytes = Vec::new();
        for frame in [
            Frame::Hello(Hello {
                version_major: VERSION_MAJOR,
                version_minor: VERSION_MINOR,
            }),
            Frame::Arm(Arm { seq: 1 }),
        ] {
            let mut buf = [0u8; MAX_FRAME_LEN];
            let n = encode_frame(&frame, &mut buf).unwrap();
            bytes.extend_from_slice(&buf[..n]);
        }
        bytes
    }

    #[test]
    fn a_ticked_device_sends_what_the_emulator_driven_directly_sends() {
        let texts = form(&[
            (DeviceSetting::TimeScale, "4"),
            (DeviceSetting::DropRate, "0.1"),
        ]);
        let start = DeviceStart::from_json(&DeviceStart::new(&texts, false).to_json()).unwrap();
        let mut clocked = ClockedDevice::start(&start, 100.0).unwrap();
        let mut asked = parse_device(&texts).unwrap();
        asked.config.sim_truth = false;
        let mut direct = DeviceEmulator::new(asked.config).unwrap();
        let mut expected = Vec::new();
        // Hello and Arm, then 50 ms of wall time in 10 ms ticks at 4× real time: 200 frames of
        // 1 ms.
        clocked.receive(&hello_and_arm());
        direct.receive(&hello_and_arm(), &mut expected);
        let mut sent = Vec::new();
        for tick in 1..=5 {
            sent.extend(clocked.tick(100.0 + 0.010 * f64::from(tick)));
        }
        // 200 frames, give or take the last one (the wall clock's sums are not exact).
        assert!((clocked.device_time_s() - 0.200).abs() < 1.5e-3);
        while direct.time_s() < clocked.device_time_s() {
            direct.step_frame(&mut expected);
        }
        assert!(expected.len() > 1000, "{} bytes", expected.len());
        assert!(
            sent == expected,
            "{} bytes sent, {} expected",
            sent.len(),
            expected.len()
        );
    }

    #[test]
    fn a_tick_runs_at_most_its_frames_and_what_it_cannot_run_is_not_caught_up() {
        // 1000× real time: a 10 ms tick asks for 10 s of frames, and runs 400.
        let start = DeviceStart::new(&form(&[(DeviceSetting::TimeScale, "1000")]), true);
        let mut clocked = ClockedDevice::start(&start, 0.0).unwrap();
        let period_s = 0.001;
        let per_tick_s = MAX_VIRTUAL_FRAMES_PER_TICK as f64 * period_s;
        assert!(!clocked.tick(0.010).is_empty());
        assert!((clocked.device_time_s() - per_tick_s).abs() < 1e-9);
        // The same wall time again: nothing more is due.
        assert!(clocked.tick(0.010).is_empty());
        assert!((clocked.device_time_s() - per_tick_s).abs() < 1e-9);
        clocked.tick(0.020);
        assert!((clocked.device_time_s() - 2.0 * per_tick_s).abs() < 1e-9);
    }

    #[test]
    fn a_late_tick_moves_the_clock_on_by_at_most_its_bounded_step() {
        let start = DeviceStart::new(&form(&[]), true);
        let mut clocked = ClockedDevice::start(&start, 0.0).unwrap();
        // One second late at real time: 20 ms of device time, not 1 s.
        clocked.tick(1.0);
        let step_s = f64::from(MAX_VIRTUAL_STEP_MS) / 1000.0;
        assert!((clocked.device_time_s() - step_s).abs() < 1e-9);
        // On time again: 10 ms more; a wall clock that goes back moves nothing.
        clocked.tick(1.010);
        assert!((clocked.device_time_s() - step_s - 0.010).abs() < 1e-9);
        clocked.tick(0.5);
        assert!((clocked.device_time_s() - step_s - 0.010).abs() < 1e-9);
    }

    /// A Heartbeat from the host, as a page sends one.
    fn heartbeat(seq: u32) -> Vec<u8> {
        let frame = Frame::Heartbeat(Heartbeat {
            seq,
            ..Heartbeat::default()
        });
        let mut buf = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&frame, &mut buf).unwrap();
        buf[..n].to_vec()
    }

    /// Ticks a device armed at 8× real time every 10 ms for 1 s of wall time, the host answering
    /// each tick with a heartbeat before the next — but the browser away for `gap_s` after
    /// 0.2 s, its ticks and its host alike. Its watchdog's fallbacks.
    fn fallbacks_over_a_wall_gap(extra: &[(DeviceSetting, &str)], gap_s: f64) -> u64 {
        let mut texts = vec![(DeviceSetting::TimeScale, "8")];
        texts.extend_from_slice(extra);
        let start = DeviceStart::new(&form(&texts), false);
        let mut clocked = ClockedDevice::start(&start, 0.0).unwrap();
        clocked.receive(&hello_and_arm());
        let mut now_s = 0.0;
        for seq in 1..=100 {
            now_s += if seq == 20 { gap_s } else { 0.010 };
            clocked.tick(now_s);
            clocked.receive(&heartbeat(seq));
        }
        assert!(clocked.device_time_s() > 7.0, "{}", clocked.device_time_s());
        clocked.stats().watchdog_fallbacks
    }

    #[test]
    fn a_long_wall_gap_without_a_fault_does_not_trip_the_watchdog() {
        // Two seconds away at 8×: the clock would owe 16 s, far over the 0.5 s watchdog.
        assert_eq!(fallbacks_over_a_wall_gap(&[], 2.0), 0);
        // Even with a watchdog shorter than one tick of the old catch-up (400 frames, 0.4 s).
        assert_eq!(
            fallbacks_over_a_wall_gap(&[(DeviceSetting::Watchdog, "0.2")], 2.0),
            0
        );
    }

    #[test]
    fn a_receiver_stall_still_trips_the_watchdog_across_a_wall_gap() {
        // The device deaf to the host for 2 s of device time from 1 s: the host silent to it.
        let stall = [
            (DeviceSetting::StallAt, "1"),
            (DeviceSetting::StallFor, "2"),
        ];
        assert_eq!(fallbacks_over_a_wall_gap(&stall, 0.010), 1);
        assert_eq!(fallbacks_over_a_wall_gap(&stall, 2.0), 1);
    }

    #[test]
    fn a_bad_form_text_gives_the_forms_words() {
        let start = DeviceStart::new(&form(&[(DeviceSetting::DropRate, "2")]), true);
        let Err(e) = ClockedDevice::start(&start, 0.0) else {
            panic!("a drop rate of 2 started");
        };
        assert_eq!(e, "Drop rate: drop rate 2 is outside 0–1");
        let errors = parse_device(&form(&[(DeviceSetting::DropRate, "2")])).unwrap_err();
        assert_eq!(refusal(&errors), e);
        let mut unknown = DeviceStart::new(&form(&[]), true);
        unknown.texts.push(("nope".into(), "1".into()));
        let Err(e) = ClockedDevice::start(&unknown, 0.0) else {
            panic!("an unknown setting started");
        };
        assert_eq!(e, "the virtual device has no setting \"nope\"");
        assert!(DeviceStart::from_json("{").is_err());
    }

    #[test]
    fn the_time_scales_help_states_the_ticks_limits() {
        let help = DeviceSetting::TimeScale.row().help;
        let per_tick =
            format!("at most {MAX_VIRTUAL_FRAMES_PER_TICK} frames per {VIRTUAL_TICK_MS} ms tick");
        assert!(help.contains(&per_tick), "{help}");
    }
}
