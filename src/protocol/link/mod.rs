//! Byte links in real time (native only): the device emulator driven by the wall clock, the
//! host's end of a link with its watchdog and its answers to the device's faults, and each part
//! the device runs as a [`crate::machine::Machine`] ([`LinkPart`], in `part.rs`; the closed loop
//! over a link is the application's: `crate::hardware::link_run`).
//!
//! Both ends read on a thread of their own ([`spawn_reader`]) so that a blocking `Read` (a pipe,
//! a child's stdout, a serial port opened as a file) can be waited on with a timeout; the queue
//! between that thread and its end is bounded, so a sender faster than the receiver is held back
//! rather than filling memory. Both are generic over `Read`/`Write`, so tests connect them
//! in-process with pipes. The host speaks over a [`Line`]: that threaded reader and a writer, or a
//! [`LockstepLine`] to an emulator in the same process with no latency and no clock, which makes
//! a run over the protocol deterministic (docs/protocol.md §8, "What the protocol costs").
//!
//! | file | what |
//! |---|---|
//! | this file | the device emulator on the wall clock, the host's link and its lines |
//! | `part` | [`LinkPart`]: one part the device runs, as the Machine the closed loop drives |

use std::cell::RefCell;
use std::io::{Read, Write};
use std::rc::Rc;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, TryRecvError};
use std::sync::Arc;
use std::time::{Duration, Instant};

use super::device::DeviceEmulator;
use super::frame::{AckResult, Capabilities, FaultKind, VERSION_MAJOR, VERSION_MINOR};
use super::host::{
    check_link_timeout_s, HostSession, LinkSample, DEFAULT_LINK_TIMEOUT_S, HELLO_INTERVAL_S,
};
use super::keep_up::KeepUp;
use super::line_budget::LineBudget;
use crate::machine::OverrideCommand;

mod part;
pub use part::LinkPart;

/// Bytes read at most per chunk.
pub const READ_CHUNK: usize = 4096;

/// `seconds` as a wait: the one place the link turns a number of seconds into a [`Duration`].
/// It never panics: NaN and negative seconds wait nothing, more than a `Duration` holds waits
/// the longest one (whoever waits that long is still waiting for an event, not a clock).
///
/// ```
/// use std::time::Duration;
/// use cutlab::protocol::link::wait_s;
/// assert_eq!(wait_s(0.25), Duration::from_millis(250));
/// assert_eq!((wait_s(-1.0), wait_s(f64::NAN)), (Duration::ZERO, Duration::ZERO));
/// assert_eq!(wait_s(1e300), Duration::MAX);
/// ```
pub fn wait_s(seconds: f64) -> Duration {
    if seconds > 0.0 {
        Duration::try_from_secs_f64(seconds).unwrap_or(Duration::MAX)
    } else {
        Duration::ZERO
    }
}

/// How long from now until `seconds` after `start`: zero once it has passed, the longest wait
/// when `start + seconds` is beyond what an [`Instant`] holds.
fn left_until(start: Instant, seconds: f64) -> Duration {
    start
        .checked_add(wait_s(seconds))
        .map_or(Duration::MAX, |deadline| {
            deadline.saturating_duration_since(Instant::now())
        })
}

/// Chunks the device's reader queues before it waits (64 KiB): a host sends a few frames per
/// control period, so a full queue is a flood, and the reader stops reading until the device has
/// caught up — the pipe, then the writer, wait with it, and memory stays bounded.
pub const DEVICE_QUEUE_CHUNKS: usize = 16;

/// Chunks the host's reader queues before it waits (1 MiB: 0.4 s of a 1 kHz emulator at 20×
/// real time with its SimTruth frames), enough to ride out a busy moment of the host without
/// holding the device up, and bounded all the same.
pub const HOST_QUEUE_CHUNKS: usize = 256;

/// The receiving end of [`spawn_reader`]: chunks in the order they were read, and how many bytes
/// are queued (read but not yet taken).
pub struct ChunkReceiver {
    rx: Receiver<Vec<u8>>,
    queued_bytes: Arc<AtomicUsize>,
}

impl ChunkReceiver {
    fn taken(&self, chunk: Vec<u8>) -> Vec<u8> {
        self.queued_bytes.fetch_sub(chunk.len(), Ordering::Relaxed);
        chunk
    }

    /// The next chunk if one is queued.
    pub fn try_recv(&self) -> Result<Vec<u8>, TryRecvError> {
        self.rx.try_recv().map(|c| self.taken(c))
    }

    /// The next chunk, waiting up to `timeout` for it.
    pub fn recv_timeout(&self, timeout: Duration) -> Result<Vec<u8>, RecvTimeoutError> {
        self.rx.recv_timeout(timeout).map(|c| self.taken(c))
    }

    /// Bytes read and not yet taken: the queue, and the chunk the reader holds while it waits
    /// for room. At most `(capacity + 1) × READ_CHUNK`.
    pub fn queued_bytes(&self) -> usize {
        self.queued_bytes.load(Ordering::Relaxed)
    }
}

/// Reads `input` on a thread of its own and hands the chunks over a channel of
/// `capacity_chunks` chunks, which disconnects at end of file or on a read error. When the
/// channel is full the reader waits for room before it reads again, so a writer faster than the
/// consumer is held back instead of filling memory.
pub fn spawn_reader<R: Read + Send + 'static>(
    mut input: R,
    capacity_chunks: usize,
) -> ChunkReceiver {
    let (tx, rx) = mpsc::sync_channel(capacity_chunks);
    let queued_bytes = Arc::new(AtomicUsize::new(0));
    let counter = Arc::clone(&queued_bytes);
    std::thread::spawn(move || {
        let mut buf = vec![0u8; READ_CHUNK];
        loop {
            match input.read(&mut buf) {
                Ok(0) => break,
                Ok(n) => {
                    counter.fetch_add(n, Ordering::Relaxed);
                    if tx.send(buf.get(..n).unwrap_or_default().to_vec()).is_err() {
                        break;
                    }
                }
                Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                Err(_) => break,
            }
        }
    });
    ChunkReceiver { rx, queued_bytes }
}

/// Frames the device runs at most before it looks at its input again: when it has fallen behind
/// the clock and catches up, a command still waits no more than 5 ms of device time.
const MAX_FRAMES_PER_BURST: usize = 5;

/// Chunks of input the device takes at most before it runs the frames that are due (and one
/// more while it waits for the next frame): a flood on its input costs it a bounded time per
/// frame, so its clock, its samples and its heartbeats keep their rate. A host's frames for one
/// pass fit in one chunk many times over.
const MAX_CHUNKS_PER_PASS: usize = 2;

/// Why the device stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DeviceExit {
    /// Its input ended (the host closed the line).
    InputClosed,
    /// Its output was closed (the host went away).
    OutputClosed,
}

/// How a device run ended, and what its input queue held at most.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DeviceRun {
    /// Why it stopped.
    pub exit: DeviceExit,
    /// The most bytes ever read from the input and not yet handed to the device (bounded by
    /// [`DEVICE_QUEUE_CHUNKS`] + 1 chunks, however fast the input comes).
    pub peak_queued_bytes: usize,
}

/// Runs `device` in real time scaled by `time_scale` (device seconds per wall second) until
/// `input` ends: what arrives on `input` is handed to the device as it comes — at most
/// two chunks between two runs of the frames that are due, so no flood
/// starves its clock — what the device sends is written to `output` and flushed after every
/// burst, its diagnostics go to `diagnostics` a line at a time, and, with `trace`, what it
/// applied at each sample as CSV ([`super::device::DeviceTraceRow`]; the device must keep a
/// trace, [`super::device::DeviceConfig::trace`]). Device timestamps stay in device time.
pub fn run_device<R: Read + Send + 'static>(
    device: &mut DeviceEmulator,
    input: R,
    output: &mut dyn Write,
    diagnostics: &mut dyn Write,
    mut trace: Option<&mut dyn Write>,
    time_scale: f64,
) -> DeviceRun {
    if let Some(t) = trace.as_mut() {
        let _ = writeln!(t, "{}", super::device::DeviceTraceRow::CSV_HEADER);
    }
    let rx = spawn_reader(input, DEVICE_QUEUE_CHUNKS);
    let start = Instant::now();
    let mut out = Vec::with_capacity(64 * 1024);
    let mut peak_queued_bytes = 0;
    let exit = loop {
        peak_queued_bytes = peak_queued_bytes.max(rx.queued_bytes());
        // What has arrived, up to the pass's share.
        let mut closed = false;
        for _ in 0..MAX_CHUNKS_PER_PASS {
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
        if let Some(t) = trace.as_mut() {
            for row in device.take_trace() {
                let _ = writeln!(t, "{}", row.csv_line());
            }
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
            let wait = left_until(start, next_s);
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
         fallbacks; at most {} bytes of input queued",
        s.parts,
        s.frames_sent,
        s.frames_dropped,
        s.frames_corrupted,
        s.frames_received,
        d.bytes_dropped,
        s.bytes_discarded,
        s.watchdog_fallbacks,
        peak_queued_bytes
    );
    DeviceRun {
        exit,
        peak_queued_bytes,
    }
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
            link_timeout_s: DEFAULT_LINK_TIMEOUT_S,
            handshake_timeout_s: 5.0 * DEFAULT_LINK_TIMEOUT_S,
        }
    }
}

impl HostOptions {
    /// A host watchdog of `link_timeout_s` (checked against [`super::host::LINK_TIMEOUT_RANGE_S`]),
    /// the handshake waiting five times as long.
    ///
    /// ```
    /// use cutlab::protocol::link::HostOptions;
    /// assert_eq!(HostOptions::new(2.0).unwrap(), HostOptions::default());
    /// assert!(HostOptions::new(1e300).is_err());
    /// ```
    pub fn new(link_timeout_s: f64) -> Result<Self, HostError> {
        let link_timeout_s = check_link_timeout_s(link_timeout_s).map_err(HostError)?;
        Ok(Self {
            link_timeout_s,
            handshake_timeout_s: 5.0 * link_timeout_s,
        })
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

/// The host's side of a line to a device: bytes out, chunks of bytes in.
pub trait Line {
    /// Writes `bytes` and flushes them.
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()>;
    /// The next bytes that arrived, waiting up to `timeout` for them.
    fn receive(&mut self, timeout: Duration) -> Result<Vec<u8>, RecvTimeoutError>;
}

/// A line over a reader, read on a thread of its own ([`spawn_reader`]), and a writer: a pipe to
/// a child process, a serial port opened as a file.
struct ThreadedLine {
    rx: ChunkReceiver,
    writer: Box<dyn Write + Send>,
}

impl Line for ThreadedLine {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.writer.write_all(bytes)?;
        self.writer.flush()
    }

    fn receive(&mut self, timeout: Duration) -> Result<Vec<u8>, RecvTimeoutError> {
        self.rx.recv_timeout(timeout)
    }
}

/// The device emulator at the end of a line with no latency and no clock of its own: what the
/// host sends reaches the device at once, and waiting for bytes runs the device's frames until
/// it sends some. A run over it is deterministic — the same bytes, quantisation and host as
/// over a real line, without the line's delays — so it tells what the protocol's 1 kHz samples
/// and counts cost apart from what its latency costs (docs/protocol.md §8). Timeouts count in
/// device seconds.
pub struct LockstepLine {
    device: Rc<RefCell<DeviceEmulator>>,
    pending: Vec<u8>,
}

impl LockstepLine {
    /// A line to `device` (shared, so the caller can read its counts afterwards).
    pub fn new(device: Rc<RefCell<DeviceEmulator>>) -> Self {
        Self {
            device,
            pending: Vec::new(),
        }
    }
}

impl Line for LockstepLine {
    fn send(&mut self, bytes: &[u8]) -> std::io::Result<()> {
        self.device.borrow_mut().receive(bytes, &mut self.pending);
        Ok(())
    }

    fn receive(&mut self, timeout: Duration) -> Result<Vec<u8>, RecvTimeoutError> {
        let mut device = self.device.borrow_mut();
        let until_s = device.time_s() + timeout.as_secs_f64();
        while self.pending.is_empty() {
            if device.time_s() >= until_s {
                return Err(RecvTimeoutError::Timeout);
            }
            device.step_frame(&mut self.pending);
        }
        Ok(std::mem::take(&mut self.pending))
    }
}

/// Why a teach cut's part was abandoned on a watchdog fallback (the session's event and the
/// run's error).
pub const TEACH_CUT_FELL_BACK: &str = "teach cut abandoned: the device's watchdog fell back, so \
    the cut no longer follows the teach cut's overrides; no calibration made, run it again";

/// The host's end of a byte link to a device, after the handshake.
pub struct HostLink {
    session: HostSession,
    line: Box<dyn Line>,
    options: HostOptions,
    capabilities: Capabilities,
    /// The link is dead (host watchdog, end of file, write error): every part ends at once.
    lost: bool,
    /// The part under way when it died.
    lost_in_part: Option<u32>,
    /// A teach cut's part in which the device's watchdog fell back: the part was abandoned, and
    /// no further part is armed.
    fell_back_in_part: Option<u32>,
    /// A part's samples are streaming.
    part_running: bool,
    /// The command, heartbeats and re-arming, in device time.
    keep_up: KeepUp,
    /// Device time of the latest sample.
    device_time_s: f64,
    out: Vec<u8>,
    /// The device fault that made the host stop the loop (docs/protocol.md §5), and the part
    /// it came in.
    alarm: Option<HostAlarm>,
    /// The loop's latest command.
    last_command: OverrideCommand,
    /// Where events go as they happen (the command line: stderr), and how many went.
    event_log: Option<Box<dyn Write + Send>>,
    events_logged: usize,
}

/// A device fault (or a stuck override, or a latched hold) the host answered with an alarm: the
/// loop stopped there.
#[derive(Debug, Clone, PartialEq)]
pub struct HostAlarm {
    /// The device's fault; `None` for what the host found itself (a stuck override, a feed
    /// hold latched at the device).
    pub kind: Option<FaultKind>,
    /// The part it came in (1 = the first armed).
    pub part: u32,
    /// What the host did, in words.
    pub text: String,
}

impl HostLink {
    /// Says Hello over `reader`/`writer` and waits for the device's Capabilities (repeating the
    /// Hello every quarter second).
    pub fn connect<R: Read + Send + 'static>(
        reader: R,
        writer: Box<dyn Write + Send>,
        options: HostOptions,
    ) -> Result<Self, HostError> {
        let line = ThreadedLine {
            rx: spawn_reader(reader, HOST_QUEUE_CHUNKS),
            writer,
        };
        Self::connect_line(Box::new(line), options)
    }

    /// Says Hello over `line` and waits for the device's Capabilities, as
    /// [`HostLink::connect`] does.
    pub fn connect_line(mut line: Box<dyn Line>, options: HostOptions) -> Result<Self, HostError> {
        let mut session = HostSession::new();
        let start = Instant::now();
        let mut out = Vec::new();
        let capabilities = loop {
            if let Some(c) = session.capabilities() {
                break *c;
            }
            let elapsed = start.elapsed().as_secs_f64();
            if elapsed > options.handshake_timeout_s {
                return Err(HostError(format!(
                    "no answer to Hello within {} s ({})",
                    options.handshake_timeout_s,
                    session.stats().received()
                )));
            }
            out.clear();
            session.hello(&mut out);
            line.send(&out)
                .map_err(|e| HostError(format!("cannot write to the device: {e}")))?;
            let hello_sent = Instant::now();
            while session.capabilities().is_none() {
                let left = left_until(hello_sent, HELLO_INTERVAL_S);
                if left.is_zero() {
                    break;
                }
                match line.receive(left) {
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
                "the device speaks protocol {}.{}; this host speaks \
                 {VERSION_MAJOR}.{VERSION_MINOR} and refuses another major version \
                 (docs/protocol.md §6)",
                capabilities.version_major, capabilities.version_minor
            )));
        }
        let rate = f64::from(capabilities.sample_rate_hz);
        if !(rate.is_finite() && rate > 0.0) {
            return Err(HostError(format!(
                "the device declares a sample rate of {rate} Hz"
            )));
        }
        if let Some(why) = LineBudget::of(&capabilities).refusal() {
            return Err(HostError(why));
        }
        Ok(Self {
            session,
            line,
            options,
            capabilities,
            lost: false,
            lost_in_part: None,
            fell_back_in_part: None,
            part_running: false,
            keep_up: KeepUp::new(&capabilities),
            device_time_s: 0.0,
            out: Vec::with_capacity(1024),
            alarm: None,
            last_command: OverrideCommand::default(),
            event_log: None,
            events_logged: 0,
        })
    }

    /// Writes every event to `log` as it happens (a run on a real machine takes minutes; the
    /// operator wants to see an alarm when it comes, not at the end).
    pub fn log_events_to(&mut self, log: Box<dyn Write + Send>) {
        self.event_log = Some(log);
        self.write_events();
    }

    fn write_events(&mut self) {
        let Some(log) = self.event_log.as_mut() else {
            return;
        };
        for e in self.session.events().iter().skip(self.events_logged) {
            let _ = writeln!(log, "host: part {}, {:.3} s: {}", e.part, e.time_s, e.text);
        }
        let _ = log.flush();
        self.events_logged = self.session.events().len();
    }

    /// The alarm a device fault raised, if one did.
    pub fn alarm(&self) -> Option<&HostAlarm> {
        self.alarm.as_ref()
    }

    /// The override the host holds when it stops a loop before the program's end: the device's
    /// own fallback override, which its builder chose as safe to cut at.
    pub fn safe_override_pct(&self) -> f64 {
        f64::from(self.capabilities.fallback_override_cpct) / 100.0
    }

    /// Answers the faults the device raised (docs/protocol.md §5), a stuck override and a
    /// feed hold latched at the device: the first while the host holds the device stops the
    /// loop (the part ends for it) and is kept as the alarm.
    fn watch_faults(&mut self) {
        let mut found: Vec<(Option<FaultKind>, String)> = Vec::new();
        for kind in self.session.take_alarm_faults() {
            let text = match kind {
                FaultKind::EStop => "alarm: the device's E-stop input is active: the loop stops; \
                     the host disarms the device (commands are refused under E-stop, and after \
                     the reset the machine's own dial applies)"
                    .to_string(),
                k => format!(
                    "alarm: device fault {} raised: the loop stops; the host holds the safe \
                     override ({} %) while the device still runs the part, then disarms",
                    k.name(),
                    self.safe_override_pct()
                ),
            };
            found.push((Some(kind), text));
        }
        if let Some(stuck) = self.session.take_stuck_override() {
            found.push((None, format!("alarm: {stuck}: the loop stops")));
        }
        if self.part_running && self.session.hold_latched() {
            found.push((
                None,
                "alarm: the device holds the feed, latched: the loop stops; the operator resets \
                 it once the cause is cleared (cutlab host --reset-hold)"
                    .to_string(),
            ));
        }
        for (kind, text) in found {
            if self.alarm.is_some() {
                continue;
            }
            self.session.event(text.clone());
            self.alarm = Some(HostAlarm {
                kind,
                part: self.session.part(),
                text,
            });
        }
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
        let result = self.line.send(&self.out);
        self.out.clear();
        self.keep_up.sent(self.device_time_s);
        if let Err(e) = result {
            self.lose(format!("cannot write to the device ({e}): link lost"));
        }
    }

    fn lose(&mut self, text: String) {
        if !self.lost {
            self.lost = true;
            self.lost_in_part = Some(self.session.part());
            self.part_running = false;
            self.session.link_lost(text);
            self.write_events();
        }
    }

    /// The part under way when the link was lost, if it was.
    pub fn lost_in_part(&self) -> Option<u32> {
        self.lost_in_part
    }

    /// The teach cut's part that was abandoned because the device's watchdog fell back in it.
    pub fn fell_back_in_part(&self) -> Option<u32> {
        self.fell_back_in_part
    }

    /// The event that recorded the link's loss.
    pub fn lost_reason(&self) -> String {
        self.session
            .events()
            .iter()
            .rev()
            .find(|e| e.text.contains("link lost"))
            .map_or_else(|| "link lost".to_string(), |e| e.text.clone())
    }

    /// The next sample of the running part, waiting for it up to the host's watchdog.
    fn next_sample(&mut self) -> Option<LinkSample> {
        let start = Instant::now();
        loop {
            if self.lost {
                return None;
            }
            if let Some(s) = self.session.next_sample() {
                self.device_time_s = s.device_time_s;
                self.watch_faults();
                self.write_events();
                return Some(s);
            }
            let left = left_until(start, self.options.link_timeout_s);
            match self.line.receive(left) {
                Ok(bytes) => self.session.receive(&bytes),
                Err(RecvTimeoutError::Timeout) => {
                    // Best effort: the line may be dead, but a device that only lost its
                    // sending side hears the Disarm.
                    self.session.disarm(&mut self.out);
                    let _ = self.line.send(&self.out);
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
            self.write_events();
        }
    }

    /// Arms the device for a new part. A part still running (a loop that stopped before its
    /// program's end) is handed back to the machine's own dial and left to end first.
    fn begin_part(&mut self) -> bool {
        if self.alarm.is_some() || self.lost || self.fell_back_in_part.is_some() {
            // After an alarm, with the link lost, or after an abandoned teach cut, the host
            // arms nothing more.
            return false;
        }
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
        self.keep_up.armed(self.device_time_s);
        self.session.arm(&mut self.out);
        self.flush_out();
        self.write_events();
        self.part_running = !self.lost;
        self.part_running
    }

    /// Sends `command` if it changed or went unacknowledged, a heartbeat when due, and an Arm
    /// while the device is in its watchdog fallback ([`KeepUp`]).
    fn keep_up(&mut self, command: OverrideCommand) {
        self.last_command = command;
        self.keep_up.keep_up(
            &mut self.session,
            command,
            self.device_time_s,
            &mut self.out,
        );
        self.flush_out();
    }

    /// Ends the session and disarms the device. A part the loop left before its program's end
    /// after a device fault's alarm, or with the envelope's feed hold in force, is first held
    /// at the safe override — the feed hold kept — until it ends (docs/protocol.md §5); after
    /// an E-stop, or when the loop reached its time limit, the device is handed back at once.
    pub fn finish(&mut self) {
        if !self.lost && self.part_running {
            let estop = self
                .alarm
                .as_ref()
                .is_some_and(|a| a.kind == Some(FaultKind::EStop));
            let feed_hold = self.last_command.feed_hold;
            if self.session.hold_latched() {
                // The device holds the feed on its own until the operator's reset: the part
                // cannot end, and nothing the host sends would change it.
                self.session.event(
                    "the device holds the feed, latched: the host disarms; the hold stays until \
                     the operator resets it",
                );
            } else if !estop && (self.alarm.is_some() || feed_hold) {
                self.hold_until_part_ends(feed_hold);
            }
        }
        if !self.lost {
            self.session.disarm(&mut self.out);
            self.flush_out();
        }
        self.write_events();
    }

    /// Commands the safe override (with `feed_hold`) and keeps it up until the running part
    /// ends or the link is lost.
    fn hold_until_part_ends(&mut self, feed_hold: bool) {
        let hold = OverrideCommand {
            override_pct: self.safe_override_pct(),
            feed_hold,
        };
        self.session.event(if feed_hold {
            format!(
                "holding the feed hold and the safe override ({} %) until the part ends: the \
                 operator ends the cycle at the machine (interrupting the host leaves the device \
                 to its watchdog's fallback)",
                hold.override_pct
            )
        } else {
            format!(
                "holding the safe override ({} %) until the part ends",
                hold.override_pct
            )
        });
        while self.part_running {
            self.keep_up(hold);
            match self.next_sample() {
                Some(s) if s.program_end => {
                    self.part_running = false;
                    self.session.event("program end");
                }
                // A hold latched at the device outlasts the part: nothing more to wait for.
                Some(_) if self.session.hold_latched() => break,
                Some(_) => {}
                None => break,
            }
        }
    }

    /// The operator's reset of a feed hold latched at the device (`cutlab host --reset-hold`):
    /// sends Reset and waits, up to the host's watchdog, for its Ack. The answer says whether the
    /// hold was released.
    pub fn reset_hold(&mut self) -> Result<String, HostError> {
        let seq = self.session.reset(&mut self.out);
        self.flush_out();
        let start = Instant::now();
        while !self.session.acknowledged(seq) {
            if self.lost {
                return Err(HostError(self.lost_reason()));
            }
            match self
                .line
                .receive(left_until(start, self.options.link_timeout_s))
            {
                Ok(bytes) => self.session.receive(&bytes),
                Err(_) => {
                    return Err(HostError(format!(
                        "no answer to the reset within {} s",
                        self.options.link_timeout_s
                    )))
                }
            }
        }
        let ack = self.session.last_ack();
        Ok(match ack.map(|a| a.result) {
            Some(AckResult::Applied) => "the feed hold is released (none was latched, or the \
                 operator's reset cleared it)"
                .to_string(),
            Some(AckResult::CauseActive) => "the device keeps the feed hold: its cause (an \
                 over-current, the E-stop) is still there"
                .to_string(),
            Some(other) => format!("the device answered the reset with {other:?}"),
            None => "no answer".to_string(),
        })
    }
}
