//! Consistent Overhead Byte Stuffing (Cheshire and Baker, 1999): rewrites a block of bytes so it
//! contains no zero, at a cost of one byte per 254 (and one at the start), so that a zero can
//! delimit frames on the wire.
//!
//! The encoded block is a run of groups, each a code byte `n` (1–255) followed by `n − 1` data
//! bytes; every group with `n < 255` stands for its data followed by a zero, except the last,
//! whose zero is implied by the end of the block. `[0x11, 0x00, 0x22]` encodes as
//! `[0x02, 0x11, 0x02, 0x22]`.
//!
//! `core` only, no allocation, and no panic on any input: the caller's buffers bound everything.

/// The most bytes `len` bytes can encode to.
///
/// ```
/// use cutlab::protocol::cobs::max_encoded_len;
/// assert_eq!(max_encoded_len(0), 1);
/// assert_eq!(max_encoded_len(254), 255);
/// assert_eq!(max_encoded_len(255), 257);
/// ```
pub const fn max_encoded_len(len: usize) -> usize {
    // One code byte per started group of 254 data bytes (at least one group).
    len + 1 + len.saturating_sub(1) / 254
}

/// Why a block does not decode.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CobsError {
    /// The output buffer is too small.
    Overflow,
    /// The block holds a zero byte (a code byte may not be zero, nor a data byte).
    ZeroByte,
    /// A group's code promises more bytes than the block has left (a truncated frame).
    Truncated,
}

/// Encodes `src` into `dst`; returns the length written, or `None` if `dst` is too small
/// (at most [`max_encoded_len`] of `src.len()` bytes are needed).
///
/// ```
/// use cutlab::protocol::cobs::encode;
/// let mut out = [0u8; 8];
/// let n = encode(&[0x11, 0x00, 0x22], &mut out).unwrap();
/// assert_eq!(&out[..n], &[0x02, 0x11, 0x02, 0x22]);
/// ```
pub fn encode(src: &[u8], dst: &mut [u8]) -> Option<usize> {
    // `code_at` is where the current group's code byte goes; it is written when the group ends.
    let mut code_at = 0usize;
    let mut out = 1usize;
    let mut code: u8 = 1;
    for (i, &byte) in src.iter().enumerate() {
        if byte == 0 {
            *dst.get_mut(code_at)? = code;
            code_at = out;
            out += 1;
            code = 1;
            continue;
        }
        *dst.get_mut(out)? = byte;
        out += 1;
        code += 1;
        // A full group ends here; the next starts only if data follows (the reference encoder
        // writes no empty group at the end).
        if code == 0xFF && i + 1 < src.len() {
            *dst.get_mut(code_at)? = code;
            code_at = out;
            out += 1;
            code = 1;
        }
    }
    *dst.get_mut(code_at)? = code;
    Some(out)
}

/// Decodes the block `src` (without its delimiter) into `dst`; returns the length written.
///
/// ```
/// use cutlab::protocol::cobs::{decode, CobsError};
/// let mut out = [0u8; 8];
/// let n = decode(&[0x02, 0x11, 0x02, 0x22], &mut out).unwrap();
/// assert_eq!(&out[..n], &[0x11, 0x00, 0x22]);
/// assert_eq!(decode(&[0x05, 0x11], &mut out), Err(CobsError::Truncated));
/// ```
pub fn decode(src: &[u8], dst: &mut [u8]) -> Result<usize, CobsError> {
    let mut read = 0usize;
    let mut out = 0usize;
    while read < src.len() {
        let code = src.get(read).copied().ok_or(CobsError::Truncated)?;
        if code == 0 {
            return Err(CobsError::ZeroByte);
        }
        read += 1;
        let data_len = usize::from(code) - 1;
        let end = read + data_len;
        let data = src.get(read..end).ok_or(CobsError::Truncated)?;
        if data.contains(&0) {
            return Err(CobsError::ZeroByte);
        }
        dst.get_mut(out..out + data_len)
            .ok_or(CobsError::Overflow)?
            .copy_from_slice(data);
        out += data_len;
        read = end;
        // Every group but a full one (code 255) and the last stands for a zero after its data.
        if code != 0xFF && read < src.len() {
            *dst.get_mut(out).ok_or(CobsError::Overflow)? = 0;
            out += 1;
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn round_trip(data: &[u8]) {
        let mut enc = [0u8; 600];
        let n = encode(data, &mut enc).unwrap();
        assert!(n <= max_encoded_len(data.len()), "{n} for {}", data.len());
        assert!(!enc[..n].contains(&0));
        let mut dec = [0u8; 600];
        let m = decode(&enc[..n], &mut dec).unwrap();
        assert_eq!(&dec[..m], data);
    }

    #[test]
    fn the_papers_examples_encode_as_published() {
        // Examples from Cheshire and Baker's paper (and the Wikipedia article on COBS).
        let cases: &[(&[u8], &[u8])] = &[
            (&[0x00], &[0x01, 0x01]),
            (&[0x00, 0x00], &[0x01, 0x01, 0x01]),
            (&[0x00, 0x11, 0x00], &[0x01, 0x02, 0x11, 0x01]),
            (&[0x11, 0x22, 0x00, 0x33], &[0x03, 0x11, 0x22, 0x02, 0x33]),
            (&[0x11, 0x22, 0x33, 0x44], &[0x05, 0x11, 0x22, 0x33, 0x44]),
            (&[0x11, 0x00, 0x00, 0x00], &[0x02, 0x11, 0x01, 0x01, 0x01]),
        ];
        let run: [u8; 255] = core::array::from_fn(|i| (i + 1) as u8);
        let mut full = [0u8; 260];
        let n = encode(&run[..254], &mut full).unwrap();
        assert_eq!((n, full[0], full[254]), (255, 0xFF, 0xFE));
        let n = encode(&run, &mut full).unwrap();
        assert_eq!((n, full[0], full[255], full[256]), (257, 0xFF, 0x02, 0xFF));
        for (data, expected) in cases {
            let mut enc = [0u8; 16];
            let n = encode(data, &mut enc).unwrap();
            assert_eq!(&enc[..n], *expected, "{data:02x?}");
            round_trip(data);
        }
    }

    #[test]
    fn long_runs_without_zeros_round_trip_at_every_length_around_the_group_size() {
        for len in [0, 1, 253, 254, 255, 256, 508, 509, 510] {
            let data: [u8; 510] = core::array::from_fn(|i| (i % 255 + 1) as u8);
            round_trip(&data[..len]);
            let zeros = [0u8; 510];
            round_trip(&zeros[..len]);
        }
    }

    #[test]
    fn small_buffers_and_bad_blocks_are_errors_not_panics() {
        let mut tiny = [0u8; 2];
        assert_eq!(encode(&[1, 2, 3], &mut tiny), None);
        assert_eq!(
            decode(&[0x04, 1, 2, 3], &mut tiny),
            Err(CobsError::Overflow)
        );
        assert_eq!(decode(&[0x02, 0x00], &mut tiny), Err(CobsError::ZeroByte));
        assert_eq!(decode(&[0x00], &mut tiny), Err(CobsError::ZeroByte));
        assert_eq!(decode(&[0x03, 0x01], &mut tiny), Err(CobsError::Truncated));
        assert_eq!(decode(&[], &mut tiny), Ok(0));
    }
}
