//! The baseline bit layer — §7.1 of Yemez & Schmitt, exactly: every symbol
//! of [`crate::hierarchical_coding`] is one raw bit (7-bit child masks under
//! a parent with a particle, 8-bit masks under a phantom, one phantom flag
//! per new child below level `R`, `R − r` bits per coordinate for each new
//! particle of `P^r`, then the `N − R` precision bits of §7.2). The
//! contexts the entropy layer uses are ignored, so the stream size is the
//! count of eq. (5).
//!
//! Bits are packed most significant first; the last byte of a chunk is
//! padded with zeros.
use crate::error::{Result, stream_err};
use crate::hierarchical_coding::BitCoder;

/// Writes raw bits.
#[derive(Debug, Default)]
pub struct BitWriter {
    bytes: Vec<u8>,
    bits: u64,
}

impl BitWriter {
    pub fn new() -> Self {
        Self::default()
    }
    /// Number of bits written so far.
    pub fn bit_len(&self) -> u64 {
        self.bits
    }
    /// The packed bytes.
    pub fn finish(self) -> Vec<u8> {
        self.bytes
    }
    fn push(&mut self, b: bool) {
        if self.bits.is_multiple_of(8) {
            self.bytes.push(0);
        }
        if b {
            let last = self.bytes.len() - 1;
            self.bytes[last] |= 0x80 >> (self.bits % 8);
        }
        self.bits += 1;
    }
}

impl BitCoder for BitWriter {
    fn bit(&mut self, b: &mut bool, _ctx: usize) -> Result<()> {
        self.push(*b);
        Ok(())
    }
    fn symbols(&self) -> u64 {
        self.bits
    }
}

/// Reads raw bits; running past the end is an error, so a decoder can
/// never produce more symbols than the chunk has bits.
#[derive(Debug)]
pub struct BitReader<'a> {
    data: &'a [u8],
    pos: u64,
}

impl<'a> BitReader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        BitReader { data, pos: 0 }
    }
}

impl BitCoder for BitReader<'_> {
    fn bit(&mut self, b: &mut bool, _ctx: usize) -> Result<()> {
        let byte = (self.pos / 8) as usize;
        let Some(&v) = self.data.get(byte) else {
            return stream_err("chunk payload ends early");
        };
        *b = v & (0x80 >> (self.pos % 8)) != 0;
        self.pos += 1;
        Ok(())
    }
    fn symbols(&self) -> u64 {
        self.pos
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_round_trip_and_reading_past_the_end_fails() {
        let pattern = [
            true, false, true, true, false, false, true, false, true, true,
        ];
        let mut w = BitWriter::new();
        for mut b in pattern {
            w.bit(&mut b, 0).unwrap();
        }
        assert_eq!(w.bit_len(), 10);
        let bytes = w.finish();
        assert_eq!(bytes.len(), 2);
        let mut r = BitReader::new(&bytes);
        for want in pattern {
            let mut b = false;
            r.bit(&mut b, 0).unwrap();
            assert_eq!(b, want);
        }
        let mut b = false;
        for _ in 0..6 {
            r.bit(&mut b, 0).unwrap();
        }
        assert!(r.bit(&mut b, 0).is_err());
    }
}
