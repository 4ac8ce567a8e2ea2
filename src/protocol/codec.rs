//! Frames on the wire: `0x00, COBS(payload ‖ CRC-32 of payload, little-endian), 0x00`.
//!
//! Every frame begins and ends with the delimiter zero, so garbage between two frames (line
//! noise, a half frame from before a reset) always ends at the next frame's leading zero and
//! costs no valid frame. Two delimiters in a row are an empty frame, ignored.
//!
//! The [`Decoder`] takes bytes one at a time into a fixed buffer and gives a frame, or the
//! reason one was rejected, at each delimiter. It resynchronises by construction: whatever it
//! rejects ends at a zero, and the next byte starts afresh. Bytes of a block longer than any
//! valid frame are dropped up to the next delimiter. [`DecoderStats`] counts what was dropped.
//!
//! `core` only, no allocation, and no panic on any byte sequence (the fuzz test in
//! tests/protocol.rs feeds it random and mutated streams).

use super::cobs;
use super::crc::crc32;
use super::frame::{Frame, FrameError, MAX_PAYLOAD_LEN};

/// The frame delimiter.
pub const DELIMITER: u8 = 0x00;

/// Bytes of CRC after the payload.
pub const CRC_LEN: usize = 4;

/// The longest COBS block (between delimiters) of a valid frame.
pub const MAX_BLOCK_LEN: usize = cobs::max_encoded_len(MAX_PAYLOAD_LEN + CRC_LEN);

/// The longest frame on the wire, both delimiters included.
pub const MAX_FRAME_LEN: usize = MAX_BLOCK_LEN + 2;

/// Encodes `frame` with its delimiters into `out`; returns the length written.
///
/// ```
/// use cutlab::protocol::codec::{encode_frame, MAX_FRAME_LEN};
/// use cutlab::protocol::frame::{Frame, Arm};
/// let mut out = [0u8; MAX_FRAME_LEN];
/// let n = encode_frame(&Frame::Arm(Arm { seq: 1 }), &mut out).unwrap();
/// assert_eq!(&out[..n], &[0x00, 0x03, 0x21, 0x01, 0x01, 0x01, 0x05, 0xcc, 0x96, 0x3f, 0x82, 0x00]);
/// ```
pub fn encode_frame(frame: &Frame, out: &mut [u8]) -> Result<usize, FrameError> {
    let mut raw = [0u8; MAX_PAYLOAD_LEN + CRC_LEN];
    let n = frame.write_payload(raw.get_mut(..MAX_PAYLOAD_LEN).unwrap_or_default())?;
    let payload = raw.get(..n).unwrap_or_default();
    let crc = crc32(payload).to_le_bytes();
    raw.get_mut(n..n + CRC_LEN)
        .ok_or(FrameError::BufferTooSmall)?
        .copy_from_slice(&crc);
    let body = raw.get(..n + CRC_LEN).unwrap_or_default();
    *out.first_mut().ok_or(FrameError::BufferTooSmall)? = DELIMITER;
    let encoded = cobs::encode(body, out.get_mut(1..).unwrap_or_default())
        .ok_or(FrameError::BufferTooSmall)?;
    *out.get_mut(1 + encoded).ok_or(FrameError::BufferTooSmall)? = DELIMITER;
    Ok(encoded + 2)
}

/// Why a block between delimiters was rejected.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum DecodeError {
    /// Longer than any valid frame: dropped up to the next delimiter.
    Oversized,
    /// Not valid COBS (a truncated frame, or noise).
    Cobs,
    /// Too short to hold a type byte and a CRC.
    TooShort,
    /// The CRC does not match: corrupted on the way.
    Crc,
    /// The CRC matches but the payload is not a frame this version knows (an unknown type, or
    /// shorter than its layout).
    Frame(FrameError),
}

impl core::fmt::Display for DecodeError {
    fn fmt(&self, f: &mut core::fmt::Formatter<'_>) -> core::fmt::Result {
        match self {
            DecodeError::Oversized => f.write_str("oversized frame"),
            DecodeError::Cobs => f.write_str("invalid COBS block"),
            DecodeError::TooShort => f.write_str("too short for a frame"),
            DecodeError::Crc => f.write_str("CRC mismatch"),
            DecodeError::Frame(e) => write!(f, "{e}"),
        }
    }
}

/// What a [`Decoder`] has seen.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct DecoderStats {
    /// Every byte taken.
    pub bytes_received: u64,
    /// Bytes that did not end up in a valid frame: garbage, rejected and oversized frames, and
    /// the zeros beyond the two that may stand between blocks (a third zero in a row ends one
    /// more empty block after an empty one: it belongs to no frame, so a line of nothing but
    /// zeros is all dropped bytes, not silence). The delimiters of rejected blocks are not
    /// counted. Frames of an unknown type are not counted here: they were intact.
    pub bytes_dropped: u64,
    /// Frames decoded.
    pub frames_decoded: u64,
    /// Blocks rejected (every [`DecodeError`] but an unknown type).
    pub frames_rejected: u64,
    /// Of those, CRC mismatches.
    pub crc_errors: u64,
    /// Of those, oversized blocks.
    pub oversized: u64,
    /// Intact frames of a type this version does not know, skipped.
    pub unknown_frames: u64,
}

/// A streaming frame decoder with a fixed buffer.
#[derive(Debug, Clone)]
pub struct Decoder {
    block: [u8; MAX_BLOCK_LEN],
    len: usize,
    /// Inside an oversized block: drop until the next delimiter.
    discarding: bool,
    /// The latest delimiter ended an empty block: one more in a row is a spare zero.
    after_empty_block: bool,
    stats: DecoderStats,
}

impl Default for Decoder {
    fn default() -> Self {
        Self::new()
    }
}

impl Decoder {
    /// A decoder waiting for its first delimiter-free byte.
    pub const fn new() -> Self {
        Self {
            block: [0u8; MAX_BLOCK_LEN],
            len: 0,
            discarding: false,
            after_empty_block: false,
            stats: DecoderStats {
                bytes_received: 0,
                bytes_dropped: 0,
                frames_decoded: 0,
                frames_rejected: 0,
                crc_errors: 0,
                oversized: 0,
                unknown_frames: 0,
            },
        }
    }

    /// What it has seen so far.
    pub fn stats(&self) -> DecoderStats {
        self.stats
    }

    /// Bytes held of a frame not yet ended.
    pub fn pending_len(&self) -> usize {
        self.len
    }

    /// Takes one byte; at a delimiter that ends a block, the frame or why it was rejected.
    ///
    /// ```
    /// use cutlab::protocol::codec::{Decoder, encode_frame, MAX_FRAME_LEN};
    /// use cutlab::protocol::frame::{Frame, Arm};
    /// let mut out = [0u8; MAX_FRAME_LEN];
    /// let n = encode_frame(&Frame::Arm(Arm { seq: 7 }), &mut out).unwrap();
    /// let mut d = Decoder::new();
    /// let mut got = None;
    /// for &b in b"noise".iter().chain(&out[..n]) {
    ///     if let Some(Ok(f)) = d.push(b) { got = Some(f); }
    /// }
    /// assert_eq!(got, Some(Frame::Arm(Arm { seq: 7 })));
    /// assert_eq!((d.stats().bytes_dropped, d.stats().frames_rejected), (5, 1));
    /// ```
    pub fn push(&mut self, byte: u8) -> Option<Result<Frame, DecodeError>> {
        let s = &mut self.stats;
        s.bytes_received = s.bytes_received.saturating_add(1);
        if byte == DELIMITER {
            let len = core::mem::take(&mut self.len);
            if core::mem::take(&mut self.discarding) {
                self.after_empty_block = false;
                return None;
            }
            if len == 0 {
                if core::mem::replace(&mut self.after_empty_block, true) {
                    s.bytes_dropped = s.bytes_dropped.saturating_add(1);
                }
                return None;
            }
            self.after_empty_block = false;
            let result = decode_block(self.block.get(..len).unwrap_or_default());
            let s = &mut self.stats;
            match &result {
                Ok(_) => s.frames_decoded = s.frames_decoded.saturating_add(1),
                Err(DecodeError::Frame(FrameError::UnknownType(_))) => {
                    s.unknown_frames = s.unknown_frames.saturating_add(1);
                }
                Err(e) => {
                    s.frames_rejected = s.frames_rejected.saturating_add(1);
                    s.bytes_dropped = s.bytes_dropped.saturating_add(len as u64);
                    if *e == DecodeError::Crc {
                        s.crc_errors = s.crc_errors.saturating_add(1);
                    }
                }
            }
            return Some(result);
        }
        if self.discarding {
            s.bytes_dropped = s.bytes_dropped.saturating_add(1);
            return None;
        }
        match self.block.get_mut(self.len) {
            Some(slot) => {
                *slot = byte;
                self.len += 1;
                None
            }
            None => {
                // One byte more than any frame: the block is dropped, this byte included.
                s.bytes_dropped = s.bytes_dropped.saturating_add(self.len as u64 + 1);
                s.frames_rejected = s.frames_rejected.saturating_add(1);
                s.oversized = s.oversized.saturating_add(1);
                self.len = 0;
                self.discarding = true;
                Some(Err(DecodeError::Oversized))
            }
        }
    }

    /// The frames (and rejections) in `bytes`, decoded as the iterator advances.
    pub fn frames<'d, 'b>(&'d mut self, bytes: &'b [u8]) -> Frames<'d, 'b> {
        Frames {
            decoder: self,
            bytes,
            pos: 0,
        }
    }
}

/// The frames in a slice of bytes: see [`Decoder::frames`].
pub struct Frames<'d, 'b> {
    decoder: &'d mut Decoder,
    bytes: &'b [u8],
    pos: usize,
}

impl Iterator for Frames<'_, '_> {
    type Item = Result<Frame, DecodeError>;

    fn next(&mut self) -> Option<Self::Item> {
        while let Some(&b) = self.bytes.get(self.pos) {
            self.pos += 1;
            if let Some(result) = self.decoder.push(b) {
                return Some(result);
            }
        }
        None
    }
}

/// Decodes one block (the bytes between two delimiters).
pub fn decode_block(block: &[u8]) -> Result<Frame, DecodeError> {
    let mut raw = [0u8; MAX_BLOCK_LEN];
    let n = cobs::decode(block, &mut raw).map_err(|_| DecodeError::Cobs)?;
    let body = raw.get(..n).unwrap_or_default();
    if n < 1 + CRC_LEN {
        return Err(DecodeError::TooShort);
    }
    let (payload, crc) = body.split_at(n - CRC_LEN);
    let mut expected = [0u8; CRC_LEN];
    expected.copy_from_slice(crc);
    if crc32(payload) != u32::from_le_bytes(expected) {
        return Err(DecodeError::Crc);
    }
    Frame::read_payload(payload).map_err(DecodeError::Frame)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::protocol::frame::{Arm, Heartbeat};

    #[test]
    fn a_frame_survives_noise_before_it_and_a_truncated_frame_before_that() {
        let mut a = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&Frame::Arm(Arm { seq: 9 }), &mut a).unwrap();
        let mut stream = [0u8; 64];
        // Half a frame (its sender reset), then the whole frame.
        stream[..5].copy_from_slice(&a[..5]);
        stream[5..5 + n].copy_from_slice(&a[..n]);
        let mut d = Decoder::new();
        let got: Vec<_> = d.frames(&stream[..5 + n]).collect();
        assert_eq!(got.len(), 2);
        assert!(got[0].is_err());
        assert_eq!(got[1], Ok(Frame::Arm(Arm { seq: 9 })));
        assert_eq!(d.stats().bytes_dropped, 4);
    }

    #[test]
    fn an_oversized_block_is_dropped_to_the_next_delimiter() {
        let mut d = Decoder::new();
        let junk = [0x55u8; MAX_BLOCK_LEN + 10];
        let errors: Vec<_> = d.frames(&junk).collect();
        assert_eq!(errors, vec![Err(DecodeError::Oversized)]);
        let mut hb = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(
            &Frame::Heartbeat(Heartbeat {
                seq: 1,
                time_us: 2,
                ..Heartbeat::default()
            }),
            &mut hb,
        )
        .unwrap();
        let got: Vec<_> = d.frames(&hb[..n]).collect();
        assert_eq!(
            got,
            vec![Ok(Frame::Heartbeat(Heartbeat {
                seq: 1,
                time_us: 2,
                ..Heartbeat::default()
            }))]
        );
        assert_eq!(d.stats().bytes_dropped, junk.len() as u64);
        assert_eq!(d.stats().oversized, 1);
    }

    #[test]
    fn zeros_beyond_the_two_between_frames_are_counted_dropped() {
        let mut a = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&Frame::Arm(Arm { seq: 9 }), &mut a).unwrap();
        let mut d = Decoder::new();
        // Back to back, and one zero shared between two frames: nothing dropped.
        let shared: Vec<u8> = a[..n].iter().chain(&a[1..n]).copied().collect();
        for bytes in [&a[..n], &a[..n], &shared[..]] {
            assert!(d.frames(bytes).all(|f| f.is_ok()));
        }
        assert_eq!(d.stats().bytes_dropped, 0);
        // A line of nothing but zeros: every zero but the first carries nothing (with the last
        // frame's trailing zero, the first could stand between two frames).
        assert_eq!(d.frames(&[0u8; 1000]).count(), 0);
        assert_eq!(d.stats().bytes_dropped, 999);
        assert_eq!(d.frames(&a[..n]).count(), 1);
        assert_eq!(d.stats().bytes_dropped, 1000);
    }

    #[test]
    fn a_flipped_bit_fails_the_crc() {
        let mut a = [0u8; MAX_FRAME_LEN];
        let n = encode_frame(&Frame::Arm(Arm { seq: 9 }), &mut a).unwrap();
        a[3] ^= 0x10;
        let got: Vec<_> = Decoder::new().frames(&a[..n]).collect();
        assert_eq!(got, vec![Err(DecodeError::Crc)]);
    }
}
