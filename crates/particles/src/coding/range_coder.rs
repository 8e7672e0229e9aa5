//! The entropy-coded bit layer — beyond the paper (its §10 leaves entropy
//! coding for future work).
//!
//! Every symbol of [`crate::coding::levels`] is a binary decision
//! coded with an adaptive model chosen by its context (child occupancy is
//! conditioned on the already-coded face neighbours at the same level and
//! on the parent's face neighbours, in the spirit of MPEG G-PCC's
//! neighbour-dependent occupancy contexts).
//!
//! The adaptive binary model: counts `(n0, n1)` with a
//! Krichevsky–Trofimov estimate, halved at [`COUNT_LIMIT`], probabilities
//! clamped so no symbol costs more than 9 bits and none less than about
//! 0.0028 bits. A model is one `u16` state; its probability and its two
//! successors are looked up in tables built at compile time, so coding a
//! symbol takes no division.
//!
//! The arithmetic coder is a binary range coder (32-bit range, carries
//! resolved with a cached byte, as in LZMA's coder): a decision splits the
//! range at `(range >> 16) · p0` — one multiplication — and renormalises a
//! byte at a time: no division per symbol, which a general range coder
//! (`constriction`'s) needs. `cargo bench -p lodkit-bench --bench
//! entropy_coder` codes one stream with both on the same adaptive
//! probabilities, so the choice stays checked.
//!
//! Each chunk restarts from fresh models so chunks decode independently.
use super::bit_coder::BitCoder;
use super::contexts::NUM_CONTEXTS;
use crate::error::{Result, stream_err};

/// Fixed-point precision of the binary model.
pub const PRECISION: usize = 16;
const ONE: u32 = 1 << PRECISION;
/// Smallest probability of either symbol (128 / 65536): with counts
/// halved at 64 the estimate never goes below ≈ 1/130 anyway, and the
/// floor bounds how many symbols a hostile payload can expand to.
const MIN_P: u32 = 128;
/// Counts are halved when their sum passes this: old statistics fade.
/// Fast adaptation pays: Morton order walks from one surface patch to
/// the next (smaller limits code fewer structure bits per particle).
pub const COUNT_LIMIT: u32 = 64;
/// Most symbols one payload bit can carry: each costs at least
/// `-log2(1 - MIN_P / 2^16)` ≈ 0.00282 bits, so 360 per bit is a hard
/// bound a decoder can enforce on hostile input.
pub const MAX_SYMBOLS_PER_BIT: u64 = 360;

/// Counts run over `0..=COUNT_LIMIT`; a state is `n0 · SIDE + n1`.
const SIDE: usize = COUNT_LIMIT as usize + 1;
const STATES: usize = SIDE * SIDE;

/// `P(false)` of every state, in `1/2^16`.
static P0: [u16; STATES] = p0_table();
/// The state after coding `false` (`[0]`) or `true` (`[1]`).
static NEXT: [[u16; STATES]; 2] = [next_table(false), next_table(true)];

/// One adaptive binary model, as the coders use it: a `u16` state (fresh
/// models are `0`), its `P(false)` in `1/2^16` and its successor. Public
/// so the coder can be benchmarked against a general-purpose range coder
/// on exactly the same probabilities (`crates/bench/benches/entropy_coder.rs`).
pub mod model {
    /// `P(false)` of `state`, in `1/2^16`.
    #[inline(always)]
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // the bench crate reads it
    pub fn p0(state: u16) -> u32 {
        u32::from(super::P0[usize::from(state)])
    }
    /// The state after coding `bit` in `state`.
    #[inline(always)]
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // the bench crate reads it
    pub fn next(state: u16, bit: bool) -> u16 {
        super::NEXT[usize::from(bit)][usize::from(state)]
    }
}

const fn p0_table() -> [u16; STATES] {
    let mut t = [0u16; STATES];
    let mut i = 0;
    while i < STATES {
        let (n0, n1) = ((i / SIDE) as u64, (i % SIDE) as u64);
        let p = ((2 * n0 + 1) << PRECISION) / (2 * (n0 + n1) + 2);
        let p = if p < MIN_P as u64 {
            MIN_P as u64
        } else if p > (ONE - MIN_P) as u64 {
            (ONE - MIN_P) as u64
        } else {
            p
        };
        t[i] = p as u16;
        i += 1;
    }
    t
}

const fn next_table(bit: bool) -> [u16; STATES] {
    let mut t = [0u16; STATES];
    let mut i = 0;
    while i < STATES {
        let (mut n0, mut n1) = ((i / SIDE) as u32, (i % SIDE) as u32);
        if bit {
            n1 += 1;
        } else {
            n0 += 1;
        }
        if n0 + n1 > COUNT_LIMIT {
            n0 = n0.div_ceil(2);
            n1 = n1.div_ceil(2);
        }
        // States whose counts sum past the limit are never reached; keep
        // their successors in range anyway.
        if n0 > COUNT_LIMIT {
            n0 = COUNT_LIMIT;
        }
        if n1 > COUNT_LIMIT {
            n1 = COUNT_LIMIT;
        }
        t[i] = (n0 as usize * SIDE + n1 as usize) as u16;
        i += 1;
    }
    t
}

/// The decoder's form of a model: its state in the low 16 bits and the
/// state's `P(false)` in the high 16, so one load gives the probability
/// (no dependent look-up of [`P0`] on the chain from one symbol to the
/// next).
const fn entry(state: u16) -> u32 {
    (P0[state as usize] as u32) << 16 | state as u32
}

/// The entry after decoding `false` (`[0]`) or `true` (`[1]`) in state `s`.
static NEXT_ENTRY: [[u32; STATES]; 2] = {
    let mut t = [[0u32; STATES]; 2];
    let mut b = 0;
    while b < 2 {
        let mut i = 0;
        while i < STATES {
            t[b][i] = entry(NEXT[b][i]);
            i += 1;
        }
        b += 1;
    }
    t
};

/// Decoder models: [`NUM_CONTEXTS`] rounded up to a power of two, so that
/// a context masked to it needs no bounds check (valid contexts are below
/// [`NUM_CONTEXTS`]; the mask changes none of them).
const READ_MODELS: usize = NUM_CONTEXTS.next_power_of_two();

/// Renormalise once the range drops below this (one byte shifts out).
const TOP: u32 = 1 << 24;

/// The models of every context, held in the coder itself rather than
/// behind a pointer: a store to a model then provably leaves the coder's
/// range and code alone, so they stay in registers across symbols.
type Contexts = [u16; NUM_CONTEXTS];

fn fresh_contexts() -> Contexts {
    [0; NUM_CONTEXTS]
}

/// Context-adaptive encoder of one chunk.
pub struct EntropyWriter {
    low: u64,
    range: u32,
    /// The last byte not yet written: a carry may still change it.
    cache: u8,
    /// `cache` plus the 0xFF bytes behind it that a carry would flip.
    pending: u64,
    out: Vec<u8>,
    ctx: Contexts,
    symbols: u64,
}

impl Default for EntropyWriter {
    fn default() -> Self {
        Self::new()
    }
}

impl EntropyWriter {
    pub fn new() -> Self {
        EntropyWriter {
            low: 0,
            range: u32::MAX,
            cache: 0,
            pending: 1,
            out: Vec::new(),
            ctx: fresh_contexts(),
            symbols: 0,
        }
    }

    fn shift_low(&mut self) {
        if self.low < 0xFF00_0000 || self.low > 0xFFFF_FFFF {
            let carry = (self.low >> 32) as u8;
            let mut byte = self.cache;
            while self.pending > 0 {
                self.out.push(byte.wrapping_add(carry));
                byte = 0xFF;
                self.pending -= 1;
            }
            self.cache = (self.low >> 24) as u8;
        }
        self.pending += 1;
        self.low = (self.low & 0x00FF_FFFF) << 8;
    }

    /// Codes one decision with `P(false) = p0 / 2^16`.
    #[inline]
    fn encode(&mut self, bit: bool, p0: u32) {
        let bound = (self.range >> PRECISION) * p0;
        if bit {
            self.low += u64::from(bound);
            self.range -= bound;
        } else {
            self.range = bound;
        }
        while self.range < TOP {
            self.range <<= 8;
            self.shift_low();
        }
    }

    /// The payload bytes. The coder's first byte is always zero (no carry
    /// reaches above the initial range) and is left out.
    pub fn finish(mut self) -> Vec<u8> {
        for _ in 0..5 {
            self.shift_low();
        }
        debug_assert_eq!(self.out.first(), Some(&0));
        self.out.remove(0);
        self.out
    }
}

impl BitCoder for EntropyWriter {
    #[inline(always)]
    fn bit(&mut self, b: &mut bool, ctx: usize) -> Result<()> {
        let s = self.ctx[ctx] as usize;
        self.encode(*b, u32::from(P0[s]));
        self.ctx[ctx] = NEXT[usize::from(*b)][s];
        self.symbols += 1;
        Ok(())
    }
    fn symbols(&self) -> u64 {
        self.symbols
    }
}

/// The arithmetic state of the range decoder, apart from the models, so
/// that a run of symbols can keep it in registers (a copy on the stack
/// that no model store can alias).
#[derive(Clone, Copy)]
struct RangeDecoder {
    range: u32,
    code: u32,
    /// Next payload byte to shift in.
    pos: usize,
}

impl RangeDecoder {
    #[inline(always)]
    fn decode(&mut self, bytes: &[u8], p0: u32) -> bool {
        let bound = (self.range >> PRECISION) * p0;
        let bit = self.code >= bound;
        // Without a branch: the decoded bit is data (precision bits are
        // close to random), and a mispredicted branch per symbol costs
        // more than the masks. `bound < range`, so nothing wraps.
        let m = u32::from(bit).wrapping_neg();
        self.code -= bound & m;
        self.range = ((self.range - bound) & m) | (bound & !m);
        while self.range < TOP {
            self.range <<= 8;
            let b = bytes.get(self.pos).copied().unwrap_or(0);
            self.code = (self.code << 8) | u32::from(b);
            self.pos += 1;
        }
        bit
    }
}

/// Context-adaptive decoder of one chunk; refuses to produce more symbols
/// than [`MAX_SYMBOLS_PER_BIT`] per payload bit. Bytes past the end of the
/// payload read as zero (the encoder's flush makes them unnecessary for a
/// valid payload; a truncated one decodes to garbage that the structure
/// checks or the symbol budget stop).
pub struct EntropyReader<'a> {
    bytes: &'a [u8],
    dec: RangeDecoder,
    /// Per context, its model as an [`entry`].
    ctx: [u32; READ_MODELS],
    symbols: u64,
    budget: u64,
}

impl<'a> EntropyReader<'a> {
    pub fn new(payload: &'a [u8]) -> Result<Self> {
        if payload.len() < 4 {
            return stream_err("entropy payload is shorter than the coder's 4-byte start");
        }
        let code = u32::from_be_bytes([payload[0], payload[1], payload[2], payload[3]]);
        if code == u32::MAX {
            return stream_err("entropy payload cannot start a range decoder");
        }
        Ok(EntropyReader {
            bytes: payload,
            dec: RangeDecoder {
                range: u32::MAX,
                code,
                pos: 4,
            },
            ctx: [entry(0); READ_MODELS],
            symbols: 0,
            budget: (payload.len() as u64 * 8 + 64) * MAX_SYMBOLS_PER_BIT,
        })
    }
}

impl BitCoder for EntropyReader<'_> {
    #[inline(always)]
    fn bit(&mut self, b: &mut bool, ctx: usize) -> Result<()> {
        self.reserve(1)?;
        self.bit_reserved(b, ctx)
    }
    #[inline(always)]
    fn reserve(&mut self, n: u64) -> Result<()> {
        if self.symbols + n > self.budget {
            return stream_err("entropy payload decodes to more symbols than its size allows");
        }
        Ok(())
    }
    #[inline(always)]
    fn bit_reserved(&mut self, b: &mut bool, ctx: usize) -> Result<()> {
        let m = &mut self.ctx[ctx & (READ_MODELS - 1)];
        *b = self.dec.decode(self.bytes, *m >> 16);
        *m = NEXT_ENTRY[usize::from(*b)][(*m & 0xffff) as usize];
        self.symbols += 1;
        Ok(())
    }
    /// Each bit's two possible successors are looked up (context, model
    /// state, probability) while the bit itself is still being decoded,
    /// and the right one is selected once it is known: the chain from one
    /// decoded bit to the next is then a select, a multiplication and a
    /// comparison instead of the context arithmetic and two dependent
    /// table loads — at about half the time per occupancy symbol.
    #[inline(always)]
    fn bits_chained(
        &mut self,
        bits: &mut u32,
        todo: u32,
        ctx: impl Fn(u32, u32) -> usize,
    ) -> Result<()> {
        debug_assert!(todo < 1 << 8);
        self.reserve(8)?;
        let mut rest = todo;
        if rest == 0 {
            return Ok(());
        }
        let mut v = *bits & !todo;
        // Locals, so that the model stores below leave them in registers.
        let mut dec = self.dec;
        let bytes = self.bytes;
        let mut k = rest.trailing_zeros();
        rest &= rest - 1;
        const MASK: usize = READ_MODELS - 1;
        let mut c = ctx(k, v & ((1 << k) - 1)) & MASK;
        let mut e = self.ctx[c];
        let mut n = 1;
        while rest != 0 {
            let next = rest.trailing_zeros();
            rest &= rest - 1;
            let known = v & ((1 << next) - 1);
            let c0 = ctx(next, known) & MASK;
            let c1 = ctx(next, known | 1 << k) & MASK;
            let (e0, e1) = (self.ctx[c0], self.ctx[c1]);
            let bit = dec.decode(bytes, e >> 16);
            self.ctx[c] = NEXT_ENTRY[usize::from(bit)][(e & 0xffff) as usize];
            v |= u32::from(bit) << k;
            let prev = c;
            // Selected with masks, not a branch: the bit is data.
            let m = usize::from(bit).wrapping_neg();
            c = c0 ^ ((c0 ^ c1) & m);
            e = e0 ^ ((e0 ^ e1) & m as u32);
            if c == prev {
                // Read before the model was updated (never the case for
                // the contexts of `code_level`, which differ by child).
                e = self.ctx[c];
            }
            k = next;
            n += 1;
        }
        let bit = dec.decode(bytes, e >> 16);
        self.ctx[c] = NEXT_ENTRY[usize::from(bit)][(e & 0xffff) as usize];
        v |= u32::from(bit) << k;
        self.dec = dec;
        self.symbols += n;
        *bits = v;
        Ok(())
    }
    fn symbols(&self) -> u64 {
        self.symbols
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn skewed_bits_round_trip_and_compress() {
        let bits: Vec<bool> = (0..20_000u32)
            .map(|i| i.wrapping_mul(2_654_435_761) % 10 == 0)
            .collect();
        let mut w = EntropyWriter::new();
        for (i, &b) in bits.iter().enumerate() {
            let mut b = b;
            w.bit(&mut b, i % 3).unwrap();
        }
        let bytes = w.finish();
        // 10% ones: entropy 0.469 bits per symbol.
        assert!((bytes.len() * 8) < bits.len() / 2, "{} bytes", bytes.len());
        let mut r = EntropyReader::new(&bytes).unwrap();
        for (i, &want) in bits.iter().enumerate() {
            let mut b = false;
            r.bit(&mut b, i % 3).unwrap();
            assert_eq!(b, want);
        }
    }

    #[test]
    fn a_chunk_without_symbols_still_starts_a_decoder() {
        let bytes = EntropyWriter::new().finish();
        assert!(bytes.len() >= 4, "{} bytes", bytes.len());
        assert!(EntropyReader::new(&bytes).is_ok());
    }

    #[test]
    fn long_runs_of_likely_symbols_carry_correctly() {
        // Long runs of the likely symbol push `low` towards carries; rare
        // unlikely ones in between exercise the pending 0xFF bytes.
        let bits: Vec<bool> = (0..200_000u32)
            .map(|i| i % 5_003 == 0 || (i / 50_000) % 2 == 1)
            .collect();
        let mut w = EntropyWriter::new();
        for &b in &bits {
            let mut b = b;
            w.bit(&mut b, 0).unwrap();
        }
        let bytes = w.finish();
        assert!(bytes.len() < 2_000, "{} bytes", bytes.len());
        let mut r = EntropyReader::new(&bytes).unwrap();
        for (i, &want) in bits.iter().enumerate() {
            let mut b = false;
            r.bit(&mut b, 0).unwrap();
            assert_eq!(b, want, "symbol {i}");
        }
    }

    #[test]
    fn probability_table_matches_the_kt_estimate() {
        assert_eq!(P0[0], 1 << 15);
        // n0 = 3, n1 = 1: (2·3 + 1) / (2·4 + 2) = 0.7.
        assert_eq!(P0[3 * SIDE + 1], ((7u64 << 16) / 10) as u16);
        // n0 = 64, n1 = 0: 129 / 130, the most skewed reachable estimate.
        assert_eq!(P0[64 * SIDE], ((129u64 << 16) / 130) as u16);
        // 63 / 1 and one more zero: 64 / 1 halve to 32 / 1.
        assert_eq!(NEXT[0][63 * SIDE + 1] as usize, 32 * SIDE + 1);
    }

    #[test]
    fn garbage_payloads_decode_without_panicking() {
        for seed in 0..64u32 {
            let bytes: Vec<u8> = (0..64u32)
                .map(|i| (i.wrapping_mul(2_654_435_761) ^ seed.wrapping_mul(40_503)) as u8)
                .collect();
            let Ok(mut r) = EntropyReader::new(&bytes) else {
                continue;
            };
            let mut n = 0;
            let mut b = false;
            while r.bit(&mut b, n % 7).is_ok() {
                n += 1;
            }
            assert!(n as u64 <= (64 * 8 + 64) * MAX_SYMBOLS_PER_BIT);
        }
    }
}
