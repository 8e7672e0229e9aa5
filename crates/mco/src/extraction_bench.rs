//! Measuring extraction speed next to a `memcpy` of the same index buffer
//! (the yardstick: extraction by referencing should cost little
//! more than copying its output). Used by `lodkit bench mco` and the
//! criterion bench.
//!
//! For each target triangle count the LOD number is looked up once, then
//! extraction into a reused buffer and `copy_from_slice` of the resulting
//! index buffer into a preallocated one are each timed as the best of
//! several batches (the minimum filters out scheduler noise), in the same
//! process, one after the other.

use std::hint::black_box;
use std::time::Instant;

use crate::model::McoModel;

/// One row of the comparison.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ExtractionTiming {
    pub target: usize,
    pub triangles: usize,
    pub lod: usize,
    /// Best time of one extraction, seconds.
    pub extract_s: f64,
    /// Best time of one copy of the same index buffer, seconds.
    pub memcpy_s: f64,
}

impl ExtractionTiming {
    pub fn ratio(&self) -> f64 {
        self.extract_s / self.memcpy_s.max(1e-12)
    }
    pub fn mtris_per_s(&self) -> f64 {
        self.triangles as f64 / self.extract_s.max(1e-12) / 1e6
    }
}

fn best_of(batches: usize, reps: usize, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..batches {
        let t = Instant::now();
        for _ in 0..reps {
            f();
        }
        best = best.min(t.elapsed().as_secs_f64() / reps as f64);
    }
    best
}

/// Times extraction and memcpy for each target triangle count.
/// `budget_s` bounds the time spent per target (roughly).
pub fn time_extraction(
    model: &McoModel,
    targets: &[usize],
    budget_s: f64,
) -> Vec<ExtractionTiming> {
    let mut out = Vec::with_capacity(targets.len());
    let mut idx = Vec::new();
    let mut copy: Vec<u32> = Vec::new();
    for &target in targets {
        let lod = crate::priority::lod_for_triangles(&model.acc, target);
        model.extract_lod(lod, &mut idx);
        let src = idx.clone();
        copy.clear();
        copy.resize(src.len(), 0);
        // Calibrate repetitions so one batch takes about budget/20.
        let t = Instant::now();
        model.extract_lod(lod, &mut idx);
        let once = t.elapsed().as_secs_f64().max(1e-7);
        let reps = ((budget_s / 20.0 / once) as usize).clamp(1, 100_000);
        let extract_s = best_of(10, reps, || {
            model.extract_lod(black_box(lod), &mut idx);
            black_box(&idx);
        });
        let memcpy_s = best_of(10, reps, || {
            copy.copy_from_slice(black_box(&src));
            black_box(&copy);
        });
        out.push(ExtractionTiming {
            target,
            triangles: src.len() / 3,
            lod,
            extract_s,
            memcpy_s,
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
