//! Byte links in real time (native only): the device emulator driven by the wall clock, and the
//! reader thread both ends use so that a blocking `Read` (a pipe, a child's stdout, a serial
//! port opened as a file) can be waited on with a timeout.

use std::io::{Read, Write};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError, TryRecvError};
use std::time::{Duration, Instant};

use super::device::DeviceEmulator;

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

/// Frames the device runs at most before it looks at its input again.
const MAX_FRAMES_PER_BURST: usize = 20;

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
