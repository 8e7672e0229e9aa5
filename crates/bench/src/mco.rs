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
//!
//! View-dependent cuts ([`time_view_cuts`]) are timed along a camera path
//! (an orbit around the model), each camera cut once per round as a
//! renderer would frame after frame, at a pixel tolerance searched so that
//! the path's cuts average a target triangle count.

use std::hint::black_box;
use std::time::Instant;

use lodkit_mco::{Camera, McoModel, ViewCut};
use lodkit_mesh::glam::Vec3;

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

/// A camera path: `frames` cameras orbiting the model's centre at
/// `distance` times its root cube's diagonal, slightly above it, looking
/// at the centre (a 60° field of view on a 1080-pixel viewport).
pub fn orbit(model: &McoModel, frames: usize, distance: f32) -> Vec<Camera> {
    let (lo, hi) = model.bounds();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length());
    (0..frames)
        .map(|i| {
            let a = i as f32 / frames.max(1) as f32 * std::f32::consts::TAU;
            let dir = Vec3::new(a.cos(), 0.35, a.sin()).normalize();
            Camera::looking_at(c + dir * r * distance, c)
        })
        .collect()
}

/// Mean triangles of the cuts of `cameras` at `tolerance_px`.
fn mean_triangles(model: &McoModel, cameras: &[Camera], tolerance_px: f32) -> f64 {
    let mut cut = ViewCut::new();
    let total: usize = cameras
        .iter()
        .map(|c| cut.update(model, c, tolerance_px).len() / 3)
        .sum();
    total as f64 / cameras.len().max(1) as f64
}

/// The pixel tolerance whose cuts along `cameras` average about
/// `triangles` (bisection on a log scale; the count falls as the
/// tolerance grows).
pub fn tolerance_for(model: &McoModel, cameras: &[Camera], triangles: usize) -> f32 {
    let (mut lo, mut hi) = (1e-3f32, 1e4f32);
    for _ in 0..40 {
        let mid = (lo * hi).sqrt();
        if mean_triangles(model, cameras, mid) > triangles as f64 {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    (lo * hi).sqrt()
}

/// View-dependent cut timings along a camera path.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ViewTiming {
    pub tolerance_px: f32,
    pub cameras: usize,
    /// Smallest, mean and largest triangle count of the path's cuts.
    pub triangles: [usize; 3],
    /// Mean expanded nodes per cut.
    pub expanded: f64,
    /// Per cut through a kept [`ViewCut`] (`update`), seconds: median and
    /// worst camera, each camera's best round.
    pub kept_s: [f64; 2],
    /// Per cut by [`McoModel::extract_view`] (fresh scratch space every
    /// call), seconds: median and worst camera.
    pub fresh_s: [f64; 2],
    /// Per cut through a kept [`ViewCut`] by the search on the node
    /// arrays (`ViewCut::update_by_nodes`, what every cut did before the
    /// compact layout), timed interleaved with the others so that the
    /// machine's load weighs on both alike; seconds, median and worst.
    pub nodes_s: [f64; 2],
    /// A `memcpy` of the mean cut's index buffer, seconds.
    pub memcpy_s: f64,
}

fn median_and_max(mut v: Vec<f64>) -> [f64; 2] {
    v.sort_by(f64::total_cmp);
    [v[v.len() / 2], *v.last().unwrap_or(&0.0)]
}

/// Times the cuts of `cameras` at `tolerance_px`, `rounds` times each
/// (the cameras in path order within a round, as frames): each camera
/// keeps its best round, then the median and worst camera are reported.
pub fn time_view_cuts(
    model: &McoModel,
    cameras: &[Camera],
    tolerance_px: f32,
    rounds: usize,
) -> ViewTiming {
    let n = cameras.len();
    let mut kept = vec![f64::INFINITY; n];
    let mut fresh = vec![f64::INFINITY; n];
    let mut nodes = vec![f64::INFINITY; n];
    let mut by_nodes = ViewCut::new();
    let mut out_nodes = Vec::new();
    let mut tris = vec![0usize; n];
    let mut expanded = 0usize;
    let mut cut = ViewCut::new();
    let mut out = Vec::new();
    cut.update(model, &cameras[0], tolerance_px); // builds the subtree bounds
    by_nodes.update_by_nodes(model, &cameras[0], tolerance_px, &mut out_nodes); // and its own
    for round in 0..rounds.max(1) {
        for (i, cam) in cameras.iter().enumerate() {
            let t = Instant::now();
            black_box(cut.update(model, black_box(cam), tolerance_px));
            kept[i] = kept[i].min(t.elapsed().as_secs_f64());
            let t = Instant::now();
            black_box(model.extract_view(black_box(cam), tolerance_px, &mut out));
            fresh[i] = fresh[i].min(t.elapsed().as_secs_f64());
            let t = Instant::now();
            black_box(by_nodes.update_by_nodes(
                model,
                black_box(cam),
                tolerance_px,
                &mut out_nodes,
            ));
            nodes[i] = nodes[i].min(t.elapsed().as_secs_f64());
            assert_eq!(out_nodes, out, "the two searches differ");
            assert_eq!(
                cut.indices(),
                &out[..],
                "the kept cut differs from a fresh one"
            );
            if round == 0 {
                tris[i] = out.len() / 3;
                expanded += cut.expanded_nodes();
            }
        }
    }
    let mean = tris.iter().sum::<usize>() / n.max(1);
    let src = vec![7u32; 3 * mean];
    let mut dst = vec![0u32; src.len()];
    let mut memcpy = || {
        dst.copy_from_slice(black_box(&src));
        black_box(&dst);
    };
    let reps = calibrate(1e-3, &mut memcpy);
    let memcpy_s = (0..ROUNDS)
        .map(|_| batch(reps, &mut memcpy))
        .fold(f64::INFINITY, f64::min);
    ViewTiming {
        tolerance_px,
        cameras: n,
        triangles: [
            tris.iter().copied().min().unwrap_or(0),
            mean,
            tris.iter().copied().max().unwrap_or(0),
        ],
        expanded: expanded as f64 / n.max(1) as f64,
        kept_s: median_and_max(kept),
        fresh_s: median_and_max(fresh),
        nodes_s: median_and_max(nodes),
        memcpy_s,
    }
}
