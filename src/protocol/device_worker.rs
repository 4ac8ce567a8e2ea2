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

/// Frames the virtual device runs at most per tick, so a tick stays short; behind the clock, it
/// catches up over the next ticks.
pub const MAX_VIRTUAL_FRAMES_PER_TICK: usize = 400;

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
/// next [`tick`](Self::tick), which runs the frames due since power-on (at most
/// [`MAX_VIRTUAL_FRAMES_PER_TICK`]).
pub struct ClockedDevice {
    device: DeviceEmulator,
    started_s: f64,
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
            started_s: now_s,
            time_scale: asked.time_scale,
            inbox: Vec::new(),
            out: Vec::with_capacity(64 * 1024),
        })
    }

    /// Bytes the host wrote; the device reads them at its next tick.
    pub fn receive(&mut self, bytes: &[u8]) {
        self.inbox.extend_from_slice(bytes);
    }

    /// At wall time `now_s`: the device reads its inbox, runs the frames due, and gives the
    /// bytes it sent (empty if none).
    pub fn tick(&mut self, now_s: f64) -> Vec<u8> {
        let due_s = (now_s - self.started_s) * self.time_scale;
        let inbox = std::mem::take(&mut self.inbox);
        self.device.receive(&inbox, &mut self.out);
        let mut frames = 0;
        while self.device.time_s() + self.device.frame_period_s() <= due_s
            && frames < MAX_VIRTUAL_FRAMES_PER_TICK
        {
            self.device.step_frame(&mut self.out);
            frames += 1;
        }
        std::mem::take(&mut self.out)
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
    use crate::protocol::frame::{Arm, Frame, Hello, VERSION_MAJOR, VERSION_MINOR};

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
    fn a_tick_runs_at_most_its_frames_and_the_next_ticks_catch_up() {
        let start = DeviceStart::new(&form(&[]), true);
        let mut clocked = ClockedDevice::start(&start, 0.0).unwrap();
        // One second late: 1000 frames due, run over three ticks.
        assert!(!clocked.tick(1.0).is_empty());
        let period_s = 0.001;
        let after_one = clocked.device_time_s();
        assert!((after_one - MAX_VIRTUAL_FRAMES_PER_TICK as f64 * period_s).abs() < 1e-9);
        clocked.tick(1.0);
        clocked.tick(1.0);
        assert!((clocked.device_time_s() - 1.0).abs() < 1e-9);
        assert!(clocked.tick(1.0).is_empty());
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
