//! Why `.pop`'s entropy mode carries its own binary range coder instead of
//! `constriction`'s: both code the same stream of context-modelled binary
//! decisions with the same adaptive probabilities (the particles crate's
//! `encode_entropy::model` states), so the only difference measured is
//! the arithmetic coder. The stream imitates octree occupancy coding:
//! 64 contexts, each with a fixed skew between 1% and 50% ones, chosen in
//! a deterministic pseudo-random order. Criterion reports symbols/s; the
//! payload sizes are printed once (they agree within a few bytes, so the
//! faster coder costs no compression). Run with
//! `cargo bench -p lodkit-bench --bench entropy_coder`.

use std::hint::black_box;
use std::num::NonZeroU32;
use std::time::Duration;

use constriction::stream::model::{DecoderModel, EncoderModel, EntropyModel};
use constriction::stream::queue::{DefaultRangeDecoder, DefaultRangeEncoder};
use constriction::stream::{Decode, Encode};
use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use lodkit_particles::internals::{BitCoder, EntropyReader, EntropyWriter, PRECISION, model};

const SYMBOLS: usize = 1 << 21;
const CONTEXTS: usize = 64;

/// `(context, bit)` pairs: context `c` has `P(1) = skew(c)`.
fn stream() -> Vec<(u8, bool)> {
    let skew = |c: usize| 0.01 + 0.49 * (c as f64 / (CONTEXTS - 1) as f64).powi(2);
    let mut x = 0x9E37_79B9_7F4A_7C15u64;
    let mut next = move || {
        x ^= x << 13;
        x ^= x >> 7;
        x ^= x << 17;
        x
    };
    (0..SYMBOLS)
        .map(|_| {
            let c = (next() % CONTEXTS as u64) as usize;
            let u = (next() >> 11) as f64 / (1u64 << 53) as f64;
            (c as u8, u < skew(c))
        })
        .collect()
}

/// A two-symbol model for constriction: `false` has `P = p0 / 2^16`.
#[derive(Clone, Copy)]
struct Binary(u32);

impl EntropyModel<PRECISION> for Binary {
    type Symbol = bool;
    type Probability = u32;
}

impl EncoderModel<PRECISION> for Binary {
    fn left_cumulative_and_probability(
        &self,
        symbol: impl std::borrow::Borrow<bool>,
    ) -> Option<(u32, NonZeroU32)> {
        if *symbol.borrow() {
            Some((self.0, NonZeroU32::new((1 << PRECISION) - self.0)?))
        } else {
            Some((0, NonZeroU32::new(self.0)?))
        }
    }
}

impl DecoderModel<PRECISION> for Binary {
    fn quantile_function(&self, quantile: u32) -> (bool, u32, NonZeroU32) {
        let p = |x: u32| NonZeroU32::new(x).unwrap_or(NonZeroU32::MIN);
        if quantile < self.0 {
            (false, 0, p(self.0))
        } else {
            (true, self.0, p((1 << PRECISION) - self.0))
        }
    }
}

fn own_encode(s: &[(u8, bool)]) -> Vec<u8> {
    let mut w = EntropyWriter::new();
    for &(c, b) in s {
        let mut b = b;
        w.bit(&mut b, usize::from(c)).expect("in-memory encode");
    }
    w.finish()
}

fn own_decode(bytes: &[u8], s: &[(u8, bool)]) -> usize {
    let mut r = EntropyReader::new(bytes).expect("own payload");
    let mut ones = 0;
    for &(c, _) in s {
        let mut b = false;
        r.bit(&mut b, usize::from(c)).expect("own payload");
        ones += usize::from(b);
    }
    ones
}

fn constriction_encode(s: &[(u8, bool)]) -> Vec<u32> {
    let mut e = DefaultRangeEncoder::new();
    let mut st = [0u16; CONTEXTS];
    for &(c, b) in s {
        let m = &mut st[usize::from(c)];
        e.encode_symbol(b, Binary(model::p0(*m)))
            .expect("probabilities are never zero");
        *m = model::next(*m, b);
    }
    e.into_compressed().expect("in-memory encode")
}

fn constriction_decode(words: Vec<u32>, s: &[(u8, bool)]) -> usize {
    let mut d = DefaultRangeDecoder::from_compressed(words).expect("own payload");
    let mut st = [0u16; CONTEXTS];
    let mut ones = 0;
    for &(c, _) in s {
        let m = &mut st[usize::from(c)];
        let b = d.decode_symbol(Binary(model::p0(*m))).expect("own payload");
        *m = model::next(*m, b);
        ones += usize::from(b);
    }
    ones
}

fn bench(c: &mut Criterion) {
    let s = stream();
    let ones = s.iter().filter(|x| x.1).count();
    let own = own_encode(&s);
    let words = constriction_encode(&s);
    // Both decoders must reproduce the stream before their speed means anything.
    assert_eq!(own_decode(&own, &s), ones);
    assert_eq!(constriction_decode(words.clone(), &s), ones);
    eprintln!(
        "{SYMBOLS} symbols: own coder {} bytes, constriction {} bytes",
        own.len(),
        words.len() * 4
    );
    let mut g = c.benchmark_group("binary_coder");
    g.sample_size(10).measurement_time(Duration::from_secs(3));
    g.throughput(Throughput::Elements(SYMBOLS as u64));
    g.bench_function("encode/own", |b| b.iter(|| black_box(own_encode(&s))));
    g.bench_function("encode/constriction", |b| {
        b.iter(|| black_box(constriction_encode(&s)))
    });
    g.bench_function("decode/own", |b| b.iter(|| black_box(own_decode(&own, &s))));
    g.bench_function("decode/constriction", |b| {
        b.iter(|| black_box(constriction_decode(words.clone(), &s)))
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
