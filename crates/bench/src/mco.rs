//! The marching cube octree's extraction timed next to a `memcpy` of the
//! same index buffer (extraction by referencing should cost little more
//! than copying its output). Used by `lodkit bench mco`.
//!
//! For each target triangle count the LOD number is looked up once, then
//! extraction from the birth/death tables, the §6.1 reverse-order
//! traversal (both into a reused buffer) and `copy_from_slice` of the
//! resulting index buffer into a preallocated one are each timed as the
//! best of several batches (the minimum filters out scheduler noise), in
//! the same process, the batches of the three interleaved.

use std::hint::black_box;
use std::time::Instant;

use lodkit_mco::McoModel;

/// One row of the comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtractionTiming {
    pub target: usize,
    pub triangles: usize,
    pub lod: usize,
    /// Best time of one extraction (birth/death tables), seconds.
    pub extract_s: f64,
    /// Best time of one §6.1 reverse-order traversal, seconds.
    pub traversal_s: f64,
    /// Best time of one copy of the same index buffer, seconds.
    pub memcpy_s: f64,
}

impl ExtractionTiming {
    pub fn ratio(&self) -> f64 {
        self.extract_s / self.memcpy_s.max(1e-12)
    }
    pub fn traversal_ratio(&self) -> f64 {
        self.traversal_s / self.memcpy_s.max(1e-12)
    }
    pub fn mtris_per_s(&self) -> f64 {
        self.triangles as f64 / self.extract_s.max(1e-12) / 1e6
    }
}

/// Seconds per call of `f`, one batch of `reps` calls.
fn batch(reps: usize, f: &mut impl FnMut()) -> f64 {
    let t = Instant::now();
    for _ in 0..reps {
        f();
    }
    t.elapsed().as_secs_f64() / reps as f64
}

/// Repetitions so that one batch of `f` takes about `seconds`.
fn calibrate(seconds: f64, f: &mut impl FnMut()) -> usize {
    f(); // warm the caches
    let once = batch(1, f).max(1e-7);
    ((seconds / once) as usize).clamp(1, 100_000)
}

/// Batches per measurement; each of the three is timed once per round,
/// the rounds interleaved so that a burst of load on the machine hits all
/// three alike, and each keeps its best round.
const ROUNDS: usize = 12;

/// Times extraction, the §6.1 traversal and memcpy for each target
/// triangle count. `budget_s` bounds the time spent per target (roughly).
pub fn time_extraction(
    model: &McoModel,
    targets: &[usize],
    budget_s: f64,
) -> Vec<ExtractionTiming> {
    let mut out = Vec::with_capacity(targets.len());
    let mut idx = Vec::new();
    let mut idx_t = Vec::new();
    let mut copy: Vec<u32> = Vec::new();
    let per_batch = budget_s / (3 * ROUNDS) as f64;
    for &target in targets {
        let lod = model.lod_for_triangles(target);
        model.extract_lod(lod, &mut idx);
        let src = idx.clone();
        copy.clear();
        copy.resize(src.len(), 0);
        let mut extract = || {
            model.extract_lod(black_box(lod), &mut idx);
            black_box(&idx);
        };
        let mut traversal = || {
            model.extract_lod_traversal(black_box(lod), &mut idx_t);
            black_box(&idx_t);
        };
        let mut memcpy = || {
            copy.copy_from_slice(black_box(&src));
            black_box(&copy);
        };
        let reps = [
            calibrate(per_batch, &mut extract),
            calibrate(per_batch, &mut traversal),
            calibrate(per_batch, &mut memcpy),
        ];
        let mut best = [f64::INFINITY; 3];
        for _ in 0..ROUNDS {
            best[0] = best[0].min(batch(reps[0], &mut extract));
            best[1] = best[1].min(batch(reps[1], &mut traversal));
            best[2] = best[2].min(batch(reps[2], &mut memcpy));
        }
        out.push(ExtractionTiming {
            target,
            triangles: src.len() / 3,
            lod,
            extract_s: best[0],
            traversal_s: best[1],
            memcpy_s: best[2],
        });
    }
    out
}

/// Targets from 10k triangles to full size (doubling), full size included.
pub fn default_targets(full: usize) -> Vec<usize> {
    let mut t = Vec::new();
    let mut x = 10_000usize;
    while x < full {
        t.push(x);
        x *= 2;
    }
    t.push(full);
    t
}
