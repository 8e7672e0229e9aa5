//! The baseline bit layer — §7.1 of Yemez & Schmitt, exactly: every symbol
//! of [`crate::coding::levels`] is one raw bit (7-bit child masks under
//! a parent with a particle, 8-bit masks under a phantom, one phantom flag
//! per new child below level `R`, `R − r` bits per coordinate for each new
//! particle of `P^r`, then the `N − R` precision bits of §7.2). The
//! contexts the entropy layer uses are ignored, so the stream size is the
//! count of eq. (5).
//!
//! Bits are packed most significant first; the last byte of a chunk is
//! padded with zeros.
use super::bit_coder::BitCoder;
use crate::error::{Result, stream_err};

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
    fn context_free(&self) -> bool {
        true
    }
    fn bit(&mut self, b: &mut bool, _ctx: usize) -> Result<()> {
        self.push(*b);
        Ok(())
    }
    fn symbols(&self) -> u64 {
        self.bits
    }
}

/// Reads raw bits; running past the end is an error, so a decoder can
/// never produce more symbols than the chunk has bits. Up to eight bytes
/// are held in a word, so a bit costs a shift, not a byte look-up.
#[derive(Debug)]
pub struct BitReader<'a> {
    data: &'a [u8],
    /// Next byte to load into `word`.
    next: usize,
    /// Bits not yet read, most significant first.
    word: u64,
    /// How many bits of `word` are left.
    left: u32,
}

impl<'a> BitReader<'a> {
    pub fn new(data: &'a [u8]) -> Self {
        BitReader {
            data,
            next: 0,
            word: 0,
            left: 0,
        }
    }

    /// Loads the next (up to) eight bytes.
    #[cold]
    fn refill(&mut self) -> Result<()> {
        let rest = self.data.get(self.next..).unwrap_or(&[]);
        if rest.is_empty() {
            return stream_err("chunk payload ends early");
        }
        let n = rest.len().min(8);
        let mut w = [0u8; 8];
        w[..n].copy_from_slice(&rest[..n]);
        self.word = u64::from_be_bytes(w);
        self.left = 8 * n as u32;
        self.next += n;
        Ok(())
    }
}

impl BitCoder for BitReader<'_> {
    #[inline]
    fn bit(&mut self, b: &mut bool, _ctx: usize) -> Result<()> {
        if self.left == 0 {
            self.refill()?;
        }
        *b = self.word >> 63 != 0;
        self.word <<= 1;
        self.left -= 1;
        Ok(())
    }
    #[inline]
    fn bits(&mut self, v: &mut u32, n: u32, _ctx: usize) -> Result<()> {
        if n == 0 || n > self.left {
            // Across a refill (or nothing to read): bit by bit.
            let mut out = 0u32;
            for _ in 0..n {
                let mut b = false;
                self.bit(&mut b, 0)?;
                out = (out << 1) | u32::from(b);
            }
            *v = out;
            return Ok(());
        }
        *v = (self.word >> (64 - n)) as u32;
        self.word <<= n;
        self.left -= n;
        Ok(())
    }
    fn context_free(&self) -> bool {
        true
    }
    fn symbols(&self) -> u64 {
        self.next as u64 * 8 - u64::from(self.left)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn multi_bit_reads_match_single_bit_reads_across_refills() {
        let mut w = BitWriter::new();
        let pattern: Vec<bool> = (0..100u32).map(|i| (i * 7 + i / 3) % 5 < 2).collect();
        for mut b in pattern.iter().copied() {
            w.bit(&mut b, 0).unwrap();
        }
        let bytes = w.finish();
        // Groups of three straddle the 64-bit word every few reads.
        let mut r = BitReader::new(&bytes);
        for chunk in pattern.chunks(3) {
            let mut v = 0u32;
            r.bits(&mut v, chunk.len() as u32, 0).unwrap();
            let want = chunk.iter().fold(0u32, |acc, &b| (acc << 1) | u32::from(b));
            assert_eq!(v, want);
        }
        // 100 bits in 13 bytes: 4 padding bits left, then the end.
        let mut v = 0u32;
        r.bits(&mut v, 4, 0).unwrap();
        assert_eq!(v, 0);
        assert!(r.bits(&mut v, 3, 0).is_err());
    }

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
