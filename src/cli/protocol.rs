//! `cutlab protocol decode` and `cutlab protocol encode`: the feed-override protocol's frames
//! between bytes and JSON lines ([`crate::protocol::json`]), for debugging a bridge with a serial
//! sniffer and for tests.

use serde_json::json;

use super::{CliError, Io};
use crate::protocol::codec::{encode_frame, Decoder, MAX_FRAME_LEN};
use crate::protocol::json::{frame_from_json, frame_to_json, parse_line};

/// Help of `cutlab protocol`.
pub const ABOUT: &str = "The feed-override protocol's frames (docs/protocol.md) between bytes \
and JSON lines. `decode` reads bytes on stdin as they come and prints one JSON object per frame, \
then a summary of what the decoder dropped; `encode` reads one JSON object per line (the form \
decode prints) and writes the frames' bytes. Encode is strict: every field of the frame type is \
required (but a `flags` byte, 0 when left out), and a field the type does not have, a field \
given twice, a number beyond a 32-bit field's range or a NUL in a text field is an error; the \
error names the line, the frame type and the field.";

/// `cutlab protocol`: decode or encode.
#[derive(Debug, clap::Args)]
pub struct ProtocolArgs {
    #[command(subcommand)]
    command: Option<ProtocolCommand>,
}

#[derive(Debug, clap::Subcommand)]
enum ProtocolCommand {
    /// Bytes on stdin → one JSON object per frame, then {"summary": …}
    Decode(DecodeArgs),
    /// JSON lines on stdin → the frames' bytes on stdout
    Encode(EncodeArgs),
}

/// Options of `cutlab protocol decode`.
#[derive(Debug, clap::Args)]
pub struct DecodeArgs {
    /// Also print a line for every rejected block ({"type": "rejected", "reason": …})
    #[arg(long)]
    rejects: bool,
}

/// Options of `cutlab protocol encode`.
#[derive(Debug, clap::Args)]
pub struct EncodeArgs {}

/// Runs `cutlab protocol`.
pub fn run(args: ProtocolArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    match args.command {
        Some(ProtocolCommand::Decode(a)) => decode(&a, io),
        Some(ProtocolCommand::Encode(_)) => encode(io),
        None => Err(CliError::new(
            "cutlab protocol needs a subcommand: decode or encode (see cutlab protocol --help)",
        )),
    }
}

fn decode(args: &DecodeArgs, io: &mut Io<'_>) -> Result<(), CliError> {
    let mut decoder = Decoder::new();
    let mut buf = vec![0u8; 4096];
    loop {
        let n = match io.stdin.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(e.into()),
        };
        for result in decoder.frames(buf.get(..n).unwrap_or_default()) {
            match result {
                Ok(frame) => writeln!(io.stdout, "{}", frame_to_json(&frame))?,
                Err(e) if args.rejects => writeln!(
                    io.stdout,
                    "{}",
                    json!({"type": "rejected", "reason": e.to_string()})
                )?,
                Err(_) => {}
            }
        }
        // Lines as the frames come: a sniffer on a live line wants them now.
        io.stdout.flush()?;
    }
    let s = decoder.stats();
    writeln!(
        io.stdout,
        "{}",
        json!({"summary": {
            "bytes_received": s.bytes_received,
            "bytes_dropped": s.bytes_dropped,
            "frames_decoded": s.frames_decoded,
            "frames_rejected": s.frames_rejected,
            "crc_errors": s.crc_errors,
            "oversized": s.oversized,
            "unknown_frames": s.unknown_frames,
            "bytes_pending": decoder.pending_len(),
        }})
    )?;
    Ok(())
}

fn encode(io: &mut Io<'_>) -> Result<(), CliError> {
    let mut line = Vec::new();
    let mut number = 0usize;
    loop {
        line.clear();
        if io.stdin.read_until(b'\n', &mut line)? == 0 {
            break;
        }
        number += 1;
        let text = std::str::from_utf8(&line).map_err(|e| {
            CliError::new(format!(
                "line {number}: not UTF-8 text (byte {} is not)",
                e.valid_up_to() + 1
            ))
        })?;
        let text = text.trim();
        if text.is_empty() || text.starts_with('#') {
            continue;
        }
        let value = parse_line(text).map_err(|e| CliError::new(format!("line {number}: {e}")))?;
        // decode's summary line and its --rejects lines are not frames: skipped, so
        // decode | encode round-trips.
        if value.get("summary").is_some() || value.get("type") == Some(&json!("rejected")) {
            continue;
        }
        let frame =
            frame_from_json(&value).map_err(|e| CliError::new(format!("line {number}: {e}")))?;
        let mut out = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&frame, &mut out)
            .map_err(|e| CliError::new(format!("line {number}: {e}")))?;
        io.stdout.write_all(out.get(..n).unwrap_or_default())?;
    }
    Ok(())
}
