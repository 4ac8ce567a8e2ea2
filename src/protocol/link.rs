//! Byte links in real time (native only): the device emulator driven by the wall clock, the
//! host's end of a link with its watchdog, each part the device runs as a [`Machine`], and the
//! closed loop over a link ([`run_on_link`]). Both ends read on a thread of their own so that a
//! blocking `Read` (a pipe, a child's stdout, a serial port opened as a file) can be waited on
//! with a timeout; both are generic over `Read`/`Write`, so tests connect them in-process with
//! pipes.

use std::cell::RefCell;
use std::io::{Read, Write};
use std::rc::Rc;
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, TryRecvError};
use std::time::{Duration, Instant};

use super::device::DeviceEmulator;
use super::frame::{Capabilities, VERSION_MAJOR};
use super::host::{DeviceSummary, HostSession, LinkEvent, LinkSample, LinkStats};
use crate::closed_loop::lab::{
    cut_model_teach_force, metrics_config, LabRun, RunMachines, RunResult, RunSpec,
};
use crate::closed_loop::metrics::compute;
use crate::closed_loop::runner::{Calibration, LoopError, TeachForce};
use crate::machine::{Machine, MachineStep, OverrideCommand};
use crate::work::Work;

/// Bytes read at most per chunk.
const READ_CHUNK: usize = 4096;

/// Reads `input` on a thread of its own and hands the chunks over a channel, which disconnects
/// at end of file or on a read error.
pub fn spawn_reader<R: Read + Send + 'static>(mut input: R) -> Receiver<Vec<u8>> {
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        let mut buf = vec![0u8; READ_CHUNK];
        loop {
            match input.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    if tx.send(buf.get(..n).unwrap_or_default().to_vec()).is_err() {
                        break;
                    }
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(_) => break,
            }
        }
    });
    rx
}

/// Frames the device runs at most before it looks at its input again: when it has fallen behind
/// the clock and catches up, a command still waits no more than 5 ms of device time.
const MAX_FRAMES_PER_BURST: usize = 5;

/// Why the device stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeviceExit {
    /// Its input ended (the host closed the line).
    InputClosed,
    /// Its output was closed (the host went away).
    OutputClosed,
}

/// Runs `device` in real time scaled by `time_scale` (device seconds per wall second) until
/// `input` ends: what arrives on `input` is handed to the device as it comes, what the device
/// sends is written to `output` and flushed after every burst, its diagnostics go to
/// `diagnostics` a line at a time. Device timestamps stay in device time.
pub fn run_device<R: Read + Send + 'static>(
    device: &mut DeviceEmulator,
    input: R,
    output: &mut dyn Write,
    diagnostics: &mut dyn Write,
    time_scale: f64,
) -> DeviceExit {
    let rx = spawn_reader(input);
    let start = Instant::now();
    let mut out = Vec::with_capacity(64 * 1024);
    let exit = loop {
        // Everything that has arrived.
        let mut closed = false;
        loop {
            match rx.try_recv() {
                Ok(bytes) => device.receive(&bytes, &mut out),
                Err(TryRecvError::Empty) => break,
                Err(TryRecvError::Disconnected) => {
                    closed = true;
                    break;
                }
            }
        }
        let due_s = start.elapsed().as_secs_f64() * time_scale;
        let mut frames = 0;
        while device.time_s() + device.frame_period_s() <= due_s && frames < MAX_FRAMES_PER_BURST {
            device.step_frame(&mut out);
            frames += 1;
        }
        for line in device.drain_diagnostics() {
            let _ = writeln!(diagnostics, "{line}");
        }
        if !out.is_empty() {
            if output
                .write_all(&out)
                .and_then(|()| output.flush())
                .is_err()
            {
                break DeviceExit::OutputClosed;
            }
            out.clear();
        }
        if closed {
            break DeviceExit::InputClosed;
        }
        if frames == 0 {
            // Nothing due: wait for input or for the next frame, whichever comes first.
            let next_s = (device.time_s() + device.frame_period_s()) / time_scale;
            let wait = Duration::from_secs_f64((next_s - start.elapsed().as_secs_f64()).max(0.0));
            match rx.recv_timeout(wait) {
                Ok(bytes) => device.receive(&bytes, &mut out),
                Err(RecvTimeoutError::Timeout) => {}
                Err(RecvTimeoutError::Disconnected) => break DeviceExit::InputClosed,
            }
        }
    };
    let s = device.stats();
    let d = device.decoder_stats();
    let _ = writeln!(
        diagnostics,
        "device: {} parts, {} frames sent ({} dropped, {} corrupted by injection), {} received, \
         {} bytes dropped by the decoder, {} discarded by a stall or unplug, {} watchdog \
         fallbacks",
        s.parts,
        s.frames_sent,
        s.frames_dropped,
        s.frames_corrupted,
        s.frames_received,
        d.bytes_dropped,
        s.bytes_discarded,
        s.watchdog_fallbacks
    );
    exit
}

/// Settings of the host's end of a link.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HostOptions {
    /// The host's watchdog: no sample for this long (wall time) while a part runs → the link
    /// is lost: alarm, disarm, and the part ends there.
    pub link_timeout_s: f64,
    /// How long the device may take to answer the Hello (it may be starting up).
    pub handshake_timeout_s: f64,
}

impl Default for HostOptions {
    fn default() -> Self {
        Self {
            link_timeout_s: 2.0,
            handshake_timeout_s: 10.0,
        }
    }
}

/// Why a link could not be set up.
#[derive(Debug, Clone, PartialEq)]
pub struct HostError(pub String);

impl std::fmt::Display for HostError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for HostError {}

/// The host's end of a byte link to a device, after the handshake.
pub struct HostLink {
    session: HostSession,
    rx: Receiver<Vec<u8>>,
    writer: Box<dyn Write + Send>,
    options: HostOptions,
    capabilities: Capabilities,
    /// The link is dead (host watchdog, end of file, write error): every part ends at once.
    lost: bool,
    /// A part's samples are streaming.
    part_running: bool,
    /// The command in force, and the sequence number and device time it was last sent with.
    command: Option<OverrideCommand>,
    command_seq: u32,
    command_sent_s: f64,
    /// The latest command's round trip is still to be measured.
    latency_pending: bool,
    /// Device time the host last sent anything.
    last_sent_s: f64,
    last_arm_s: f64,
    /// Device time of the latest sample.
    device_time_s: f64,
    out: Vec<u8>,
}

impl HostLink {
    /// Says Hello over `reader`/`writer` and waits for the device's Capabilities (repeating the
    /// Hello every quarter second).
    pub fn connect<R: Read + Send + 'static>(
        reader: R,
        writer: Box<dyn Write + Send>,
        options: HostOptions,
    ) -> Result<Self, HostError> {
        let rx = spawn_reader(reader);
        let mut session = HostSession::new();
        let mut writer = writer;
        let start = Instant::now();
        let mut out = Vec::new();
        let capabilities = loop {
            if let Some(c) = session.capabilities() {
                break *c;
            }
            let elapsed = start.elapsed().as_secs_f64();
            if elapsed > options.handshake_timeout_s {
                let s = session.stats();
                return Err(HostError(format!(
                    "no answer to Hello within {} s ({} bytes received, {} of them dropped)",
                    options.handshake_timeout_s, s.bytes_received, s.bytes_dropped
                )));
            }
            out.clear();
            session.hello(&mut out);
            writer
                .write_all(&out)
                .and_then(|()| writer.flush())
                .map_err(|e| HostError(format!("cannot write to the device: {e}")))?;
            let until = Instant::now() + Duration::from_millis(250);
            while session.capabilities().is_none() {
                let left = until.saturating_duration_since(Instant::now());
                if left.is_zero() {
                    break;
                }
                match rx.recv_timeout(left) {
                    Ok(bytes) => session.receive(&bytes),
                    Err(RecvTimeoutError::Timeout) => break,
                    Err(RecvTimeoutError::Disconnected) => {
                        return Err(HostError(
                            "the device closed the link before answering Hello".to_string(),
                        ))
                    }
                }
            }
        };
        if capabilities.version_major != VERSION_MAJOR {
            return Err(HostError(format!(
                "the device speaks protocol {}.{}; this host speaks {VERSION_MAJOR}.x",
                capabilities.version_major, capabilities.version_minor
            )));
        }
        let rate = f64::from(capabilities.sample_rate_hz);
        if !(rate.is_finite() && rate > 0.0) {
            return Err(HostError(format!(
                "the device declares a sample rate of {rate} Hz"
            )));
        }
        Ok(Self {
            session,
            rx,
            writer,
            options,
            capabilities,
            lost: false,
            part_running: false,
            command: None,
            command_seq: 0,
            command_sent_s: 0.0,
            latency_pending: false,
            last_sent_s: 0.0,
            last_arm_s: f64::NEG_INFINITY,
            device_time_s: 0.0,
            out: Vec::with_capacity(1024),
        })
    }

    /// What the device said it is.
    pub fn capabilities(&self) -> &Capabilities {
        &self.capabilities
    }

    /// The protocol session (counts and events).
    pub fn session(&self) -> &HostSession {
        &self.session
    }

    /// Whether the link was lost.
    pub fn lost(&self) -> bool {
        self.lost
    }

    /// Sends what is in `self.out`; a write error loses the link.
    fn flush_out(&mut self) {
        if self.out.is_empty() || self.lost {
            self.out.clear();
            return;
        }
        let result = self
            .writer
            .write_all(&self.out)
            .and_then(|()| self.writer.flush());
        self.out.clear();
        self.last_sent_s = self.device_time_s;
        if let Err(e) = result {
            self.lose(format!("cannot write to the device ({e}): link lost"));
        }
    }

    fn lose(&mut self, text: String) {
        if !self.lost {
            self.lost = true;
            self.part_running = false;
            self.session.link_lost(text);
        }
    }

    /// The heartbeat interval: a fifth of the device's watchdog timeout.
    fn heartbeat_interval_s(&self) -> f64 {
        (f64::from(self.capabilities.watchdog_timeout_ms) / 5000.0).max(0.005)
    }

    /// The next sample of the running part, waiting for it up to the host's watchdog.
    fn next_sample(&mut self) -> Option<LinkSample> {
        let deadline = Instant::now() + Duration::from_secs_f64(self.options.link_timeout_s);
        loop {
            if self.lost {
                return None;
            }
            if let Some(s) = self.session.next_sample() {
                self.device_time_s = s.device_time_s;
                return Some(s);
            }
            let left = deadline.saturating_duration_since(Instant::now());
            match self.rx.recv_timeout(left) {
                Ok(bytes) => self.session.receive(&bytes),
                Err(RecvTimeoutError::Timeout) => {
                    // Best effort: the line may be dead, but a device that only lost its
                    // sending side hears the Disarm.
                    self.session.disarm(&mut self.out);
                    let _ = self
                        .writer
                        .write_all(&self.out)
                        .and_then(|()| self.writer.flush());
                    self.out.clear();
                    self.lose(format!(
                        "host watchdog: no sample for {} s: link lost; alarm, disarm, the part \
                         ends here",
                        self.options.link_timeout_s
                    ));
                    return None;
                }
                Err(RecvTimeoutError::Disconnected) => {
                    self.lose("the device closed the link: link lost".to_string());
                    return None;
                }
            }
        }
    }

    /// Arms the device for a new part. A part still running (a loop that stopped before its
    /// program's end) is handed back to the machine's own dial and left to end first.
    fn begin_part(&mut self) -> bool {
        if self.part_running {
            self.session
                .event("the previous part is still running: disarm, wait for its end");
            self.session.disarm(&mut self.out);
            self.flush_out();
        }
        while self.part_running {
            match self.next_sample() {
                Some(s) if s.program_end => self.part_running = false,
                Some(_) => {}
                None => return false,
            }
        }
        self.session.start_part();
        self.session.event("arm (cycle start)");
        self.command = None;
        self.last_arm_s = self.device_time_s;
        self.session.arm(&mut self.out);
        self.flush_out();
        self.part_running = !self.lost;
        self.part_running
    }

    /// Sends `command` if it changed or went unacknowledged, a heartbeat when due, and an Arm
    /// while the device is in its watchdog fallback.
    fn keep_up(&mut self, command: OverrideCommand) {
        let now = self.device_time_s;
        let interval = self.heartbeat_interval_s();
        if self.latency_pending && self.session.acknowledged(self.command_seq) {
            self.latency_pending = false;
            self.session.record_latency(now - self.command_sent_s);
        }
        if self.session.in_fallback() && now - self.last_arm_s >= interval {
            self.last_arm_s = now;
            self.session
                .event("re-arming the device after its watchdog fallback");
            self.session.arm(&mut self.out);
        }
        let changed = self.command != Some(command);
        let unacknowledged = !self.session.acknowledged(self.command_seq)
            && now - self.command_sent_s >= 2.0 * interval;
        if changed || unacknowledged {
            self.command = Some(command);
            self.command_seq = self.session.set_override(command, &mut self.out);
            self.command_sent_s = now;
            self.latency_pending = true;
        } else if now - self.last_sent_s >= interval {
            self.session.heartbeat(&mut self.out);
        }
        self.flush_out();
    }

    /// Ends the session: disarms the device.
    pub fn finish(&mut self) {
        if !self.lost {
            self.session.disarm(&mut self.out);
            self.flush_out();
        }
    }
}

/// One part the device runs, as a [`Machine`]: its first step arms the device (the emulator
/// loads a part and starts the cycle), it ends at the program end or when the link is lost.
pub struct LinkPart {
    link: Rc<RefCell<HostLink>>,
    sample_rate_hz: f64,
    started: bool,
    done: bool,
    last: MachineStep,
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
        }
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

/// A closed-loop run made over a link.
pub struct LinkRun {
    /// The run (its trace marked incomplete and its metrics recomputed when the link was lost).
    pub result: Result<RunResult, HostError>,
    /// What crossed the link.
    pub stats: LinkStats,
    /// What happened on it.
    pub events: Vec<LinkEvent>,
    /// Whether the host's watchdog (or an I/O error) ended it.
    pub link_lost: bool,
    /// The device.
    pub device: DeviceSummary,
}

/// Runs `spec`'s teach cut and closed loop on the device at the other end of `link`, through the
/// same [`LabRun`] `cutlab sim` uses: the first part is the teach cut, the second the run. With
/// `calibration` (a saved calibration file) there is no teach cut: the first part is the run.
/// The teach cut takes its force from the simulation's truth when the device sends it, otherwise
/// from the model of the preset's cut ([`cut_model_teach_force`]); a program whose cut changes
/// along the path needs a calibration. `duration_s` stops the closed loop early.
pub fn run_on_link(
    link: HostLink,
    spec: &RunSpec,
    duration_s: Option<f64>,
    calibration: Option<Calibration>,
) -> LinkRun {
    let device = DeviceSummary::of(link.capabilities());
    let teach_force = if device.sim_truth {
        Some(TeachForce::SimulationTruth)
    } else {
        cut_model_teach_force(spec.preset)
    };
    let link = Rc::new(RefCell::new(link));
    let part = || Box::new(LinkPart::new(Rc::clone(&link)));
    let run = match (calibration, teach_force) {
        (Some(calibration), _) => LabRun::calibrated_on(spec, part(), calibration),
        (None, Some(teach_force)) => LabRun::on_machines(
            spec,
            RunMachines::Separate {
                teach: part(),
                run: part(),
            },
            teach_force,
        ),
        (None, None) => Err(LoopError::NoTeachForce),
    };
    let result = run.and_then(|mut run| {
        if let Some(d) = duration_s {
            run.limit_duration_s(d);
        }
        run.run_to_end()
    });
    let result = result.map_err(|e: LoopError| HostError(e.to_string()));
    let mut link = link.borrow_mut();
    link.finish();
    let lost = link.lost();
    let result = result.map(|mut r| {
        if lost {
            // The loop saw the part end; it ended because the link did.
            r.trace.completed = false;
            r.metrics = compute(&r.trace, &metrics_config(r.spec.preset, &r.settings));
        }
        r
    });
    let session = link.session();
    LinkRun {
        result,
        stats: session.stats(),
        events: session.events().to_vec(),
        link_lost: lost,
        device,
    }
}
