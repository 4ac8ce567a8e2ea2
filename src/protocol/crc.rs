//! CRC-32 as Ethernet, zlib and PNG compute it (the "CRC-32/ISO-HDLC" of the CRC catalogue):
//! polynomial 0x04C11DB7 processed bit-reversed (0xEDB88320), initial value 0xFFFFFFFF, input
//! and output reflected, final XOR 0xFFFFFFFF. Check value: CRC-32 of the nine ASCII bytes
//! `123456789` is 0xCBF43926.
//!
//! A 256-entry table built at compile time, one lookup per byte. `core` only: this file is part
//! of the codec a bridge's firmware can compile as it is (`tests/no_std/lib.rs`).

/// The reflected polynomial.
pub const POLYNOMIAL_REFLECTED: u32 = 0xEDB8_8320;

/// The CRC-32 of `123456789`, the catalogue's check value.
pub const CHECK: u32 = 0xCBF4_3926;

const TABLE: [u32; 256] = table();

const fn table() -> [u32; 256] {
    let mut table = [0u32; 256];
    let mut i = 0;
    while i < 256 {
        let mut c = i as u32;
        let mut bit = 0;
        while bit < 8 {
            c = if c & 1 != 0 {
                POLYNOMIAL_REFLECTED ^ (c >> 1)
            } else {
                c >> 1
            };
            bit += 1;
        }
        table[i] = c;
        i += 1;
    }
    table
}

/// A CRC-32 computed a piece at a time.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Crc32 {
    state: u32,
}

impl Default for Crc32 {
    fn default() -> Self {
        Self::new()
    }
}

impl Crc32 {
    /// The CRC of nothing so far.
    pub const fn new() -> Self {
        Self { state: 0xFFFF_FFFF }
    }

    /// Takes more bytes.
    pub fn update(&mut self, bytes: &[u8]) {
        let mut c = self.state;
        for &b in bytes {
            c = TABLE[usize::from((c as u8) ^ b)] ^ (c >> 8);
        }
        self.state = c;
    }

    /// The CRC of every byte taken.
    pub const fn value(&self) -> u32 {
        self.state ^ 0xFFFF_FFFF
    }
}

/// The CRC-32 of `bytes`.
///
/// ```
/// use cutlab::protocol::crc::{crc32, CHECK};
/// assert_eq!(crc32(b"123456789"), 0xCBF4_3926);
/// assert_eq!(CHECK, 0xCBF4_3926);
/// ```
pub fn crc32(bytes: &[u8]) -> u32 {
    let mut crc = Crc32::new();
    crc.update(bytes);
    crc.value()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Bit by bit, straight from the definition, to check the table against.
    fn slow(bytes: &[u8]) -> u32 {
        let mut c = 0xFFFF_FFFFu32;
        for &b in bytes {
            c ^= u32::from(b);
            for _ in 0..8 {
                c = if c & 1 != 0 {
                    (c >> 1) ^ POLYNOMIAL_REFLECTED
                } else {
                    c >> 1
                };
            }
        }
        !c
    }

    #[test]
    fn the_check_value_is_the_catalogues() {
        assert_eq!(crc32(b"123456789"), CHECK);
        assert_eq!(crc32(b""), 0);
        // zlib.crc32(b"The quick brown fox jumps over the lazy dog") in Python.
        assert_eq!(
            crc32(b"The quick brown fox jumps over the lazy dog"),
            0x414F_A339
        );
    }

    #[test]
    fn the_table_agrees_with_the_bitwise_definition_and_pieces_with_the_whole() {
        let bytes: [u8; 300] = core::array::from_fn(|i| (i * 7 + 3) as u8);
        assert_eq!(crc32(&bytes), slow(&bytes));
        let mut crc = Crc32::new();
        crc.update(&bytes[..100]);
        crc.update(&bytes[100..]);
        assert_eq!(crc.value(), crc32(&bytes));
    }
}
