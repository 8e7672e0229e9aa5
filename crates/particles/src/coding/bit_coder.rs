//! The symbol interface both bit layers implement: [`super::raw_bits`]
//! (the paper's §7.1 raw bits) and [`super::range_coder`] (adaptive binary
//! range coding). The level and precision coders ([`super::levels`],
//! [`super::precision_layers`]) code every symbol through it, so the
//! encoder and the decoder run the same traversal.
use crate::error::Result;

/// One binary symbol at a time, with a context for adaptive layers.
pub trait BitCoder {
    /// Writes `*b` (encoder) or reads it into `*b` (decoder).
    fn bit(&mut self, b: &mut bool, ctx: usize) -> Result<()>;
    /// Symbols coded so far.
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // the bench crate reads it
    fn symbols(&self) -> u64;
    /// `n ≤ 32` bits of `*v`, most significant first, context `ctx + i`
    /// for bit `i` (from the top).
    fn bits(&mut self, v: &mut u32, n: u32, ctx: usize) -> Result<()> {
        let mut out = 0u32;
        for i in 0..n {
            let mut b = (*v >> (n - 1 - i)) & 1 == 1;
            self.bit(&mut b, ctx + i as usize)?;
            out = (out << 1) | u32::from(b);
        }
        *v = out;
        Ok(())
    }
    /// Checks that `n` more symbols may be coded. A decoder refuses more
    /// symbols than its payload can carry (a hostile payload must not
    /// expand without bound); checking once for a run of symbols keeps the
    /// test off the per-symbol path of [`BitCoder::bit_reserved`].
    fn reserve(&mut self, _n: u64) -> Result<()> {
        Ok(())
    }
    /// [`BitCoder::bit`] for a symbol that a successful
    /// [`BitCoder::reserve`] covers: a decoder need not check its budget
    /// again (the raw reader still fails at the end of its payload).
    #[inline(always)]
    fn bit_reserved(&mut self, b: &mut bool, ctx: usize) -> Result<()> {
        self.bit(b, ctx)
    }
    /// Codes bit `k` of `*bits` for each `k` set in `todo` (`todo < 2^8`),
    /// lowest first, each with context `ctx(k, *bits & (2^k − 1))`: the
    /// context may depend on the decisions below `k` (and on bits of
    /// `*bits` outside `todo`, which stay as they are), never on those
    /// above. The encoder's `*bits` holds the truth; the decoder's bits in
    /// `todo` are zero on entry. `ctx` must be a pure function; a decoder
    /// may evaluate it ahead, for both values of the pending bit, to take
    /// the context's table look-ups off the chain from one decoded bit to
    /// the next. Reserves its symbols itself.
    #[inline(always)]
    fn bits_chained(
        &mut self,
        bits: &mut u32,
        todo: u32,
        ctx: impl Fn(u32, u32) -> usize,
    ) -> Result<()> {
        let mut rest = todo;
        while rest != 0 {
            let k = rest.trailing_zeros();
            rest &= rest - 1;
            let mut b = (*bits >> k) & 1 == 1;
            self.bit(&mut b, ctx(k, *bits & ((1 << k) - 1)))?;
            *bits = (*bits & !(1 << k)) | (u32::from(b) << k);
        }
        Ok(())
    }
    /// Whether the contexts are ignored (the baseline's raw bits): symbols
    /// with different contexts may then be coded together with
    /// [`BitCoder::bits`], which a raw reader does with one shift.
    fn context_free(&self) -> bool {
        false
    }
}
