//! Metro-style surface distance between two meshes (`lodkit compare`).
//!
//! Implements the Metro tool (Cignoni, Rocchini and Scopigno, "Metro:
//! measuring error on simplified surfaces", 1998) as MeshLab's *Hausdorff
//! Distance* filter runs it: sample one surface (vertices, edges, faces),
//! find each sample's nearest point on the other surface, and report the
//! maximum (one-sided Hausdorff distance), mean and RMS of those distances;
//! then the same the other way round, and both combined.
//!
//! The pieces are reusable on their own:
//! - [`SurfaceSampler`] ([`sample`]) places the samples;
//! - [`SurfaceIndex`] ([`distance`]) answers closest-point queries on a mesh
//!   through a BVH, built once per target;
//! - [`DirectionStats`], [`SymmetricStats`] and [`CompareReport`]
//!   ([`report`]) hold the figures and serialise with serde;
//! - [`Reference`] ([`reference`]) measures one input against many
//!   meshes with the input's index built once, and [`level_samples`] sizes
//!   each measurement by the level's faces.
//!
//! # Defaults (all in one place)
//!
//! | option | default | meaning |
//! |---|---|---|
//! | `samples` | `max(10 × faces of the larger mesh, 1 000 000)` | per-kind count `N`, as MeshLab's `SampleNum` |
//! | `vertex_samples` | `true` | every referenced vertex (at most `N`, a seeded subset beyond) |
//! | `edge_samples` | `true` | `N` points along the unique edges, by length |
//! | `face_samples` | `true` | `N` points on the faces, by area |
//! | `seed` | [`DEFAULT_SEED`] | RNG seed; same inputs + seed → identical report |
//!
//! `N` applies to *each* enabled kind, exactly as in MeshLab's filter, so a
//! default run of the Stanford bunny (69 451 faces) takes 1 000 000 face
//! samples, 1 000 000 edge samples and its 34 834 referenced vertices:
//! 2 034 834 samples per direction. Running MeshLab's filter with
//! `samplenum = N` and the same three kinds enabled gives the same sample
//! distribution (see `scripts/meshlab_reference.py`).
//!
//! # Where lodkit departs from MeshLab, and why
//! - Unreferenced vertices are never sampled (MeshLab samples every vertex
//!   when `SampleNum` ≥ the vertex count): they are not part of the
//!   surface. The bounding box for relative figures is the referenced
//!   vertices' box too.
//! - Face samples are allocated to faces systematically rather than by
//!   independent draws (same expectation, lower variance; see [`sample`]).
//! - No maximum-distance cut-off: MeshLab ignores samples farther than its
//!   `maxdist` parameter (pymeshlab 2025.7 lists 50% of the bounding-box
//!   diagonal as the default); lodkit counts them all.
//! - Results do not depend on the thread count: chunked seeded RNG streams
//!   and in-order reductions.

mod distance;
mod reference;
mod report;
mod sample;

pub use distance::{Closest, SurfaceIndex};
pub use reference::{LEVEL_SAMPLES_PER_FACE, MIN_LEVEL_SAMPLES, Reference, level_samples};
pub use report::{CompareReport, DirectionStats, SymmetricStats};
pub use sample::{SampleCounts, SamplingPlan, SurfaceSampler, referenced_vertices, surface_bbox};

use rayon::prelude::*;

use crate::error::{Error, Result};
use crate::mesh::TriMesh;
use report::Accum;

/// Default samples per face of the larger mesh.
pub const DEFAULT_SAMPLES_PER_FACE: usize = 10;
/// Default lower bound on the per-kind sample count.
pub const DEFAULT_MIN_SAMPLES: usize = 1_000_000;
/// Default RNG seed (the year Metro was published).
pub const DEFAULT_SEED: u64 = 1998;
/// Largest per-kind sample count accepted (2³² − 1, about 4.3 billion): a
/// guard against counts whose sums would overflow, far beyond any useful
/// measurement.
pub const MAX_SAMPLES_PER_KIND: usize = u32::MAX as usize;

/// Options of [`compare`] and [`one_sided`]. See the [module
/// docs](self#defaults-all-in-one-place) for the defaults.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CompareOptions {
    /// Per-kind sample count `N` (MeshLab's `SampleNum`); `None` uses
    /// `max(10 × faces of the larger mesh, 1 000 000)`.
    pub samples: Option<usize>,
    /// RNG seed for face-sample positions, vertex subsets and allocation
    /// offsets.
    pub seed: u64,
    /// Sample the referenced vertices.
    pub vertex_samples: bool,
    /// Sample along the edges.
    pub edge_samples: bool,
    /// Sample the faces.
    pub face_samples: bool,
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions::DEFAULT
    }
}

impl CompareOptions {
    /// The defaults: `max(10 × faces, 1 000 000)` samples of every kind,
    /// seed [`DEFAULT_SEED`].
    pub const DEFAULT: CompareOptions = CompareOptions {
        samples: None,
        seed: DEFAULT_SEED,
        vertex_samples: true,
        edge_samples: true,
        face_samples: true,
    };

    /// The per-kind count `N` for meshes of `faces_a` and `faces_b` faces:
    /// `samples` if set, else `max(10 × max(faces_a, faces_b), 1 000 000)`.
    pub fn resolved_samples(&self, faces_a: usize, faces_b: usize) -> usize {
        self.samples.unwrap_or_else(|| {
            faces_a
                .max(faces_b)
                .saturating_mul(DEFAULT_SAMPLES_PER_FACE)
                .max(DEFAULT_MIN_SAMPLES)
        })
    }

    fn plan(&self, per_kind: usize) -> SamplingPlan {
        SamplingPlan {
            per_kind,
            vertices: self.vertex_samples,
            edges: self.edge_samples,
            faces: self.face_samples,
            seed: self.seed,
        }
    }
}

/// Measures surfaces `a` and `b` against each other: samples of A against
/// B, samples of B against A, and the two combined (symmetric max = the
/// Hausdorff distance; symmetric mean and RMS = the larger direction's, as
/// Metro reports them). Absolute figures are in the meshes' units; each
/// direction's percentages are of the sampled mesh's bounding-box
/// diagonal, the symmetric ones of the union box's diagonal.
///
/// Errors ([`Error::Invalid`]) if either mesh has no faces or is malformed
/// (index out of range, non-finite referenced vertex), or if the options
/// produce no sample at all on one of them (every kind disabled,
/// `samples == Some(0)`, or nothing to sample of the enabled kinds), or
/// if the per-kind count exceeds [`MAX_SAMPLES_PER_KIND`]. Degenerate
/// (zero-area) faces are fine.
///
/// Deterministic: the same meshes, options and seed give the same report
/// whatever the thread count. Cost: two BVH builds (`O(F log F)`), then
/// `O(S log F)` closest-point queries for `S` samples per direction, spread
/// over rayon's threads; memory `O(V + F)` plus one chunk of points per
/// thread (samples are generated chunk by chunk, never all at once).
pub fn compare(a: &TriMesh, b: &TriMesh, opts: &CompareOptions) -> Result<CompareReport> {
    Reference::new(a)?.compare(b, opts)
}

/// Samples `sampled` and measures each sample's distance to `target` (one
/// direction of Metro). `opts.samples == None` resolves against the larger
/// of `sampled` and `target` (see [`CompareOptions::resolved_samples`]).
/// Percentages are of `sampled`'s bounding-box diagonal.
///
/// Build `target` once with [`SurfaceIndex::new`] to measure many meshes
/// against it. Errors as [`compare`] does for `sampled`.
pub fn one_sided(
    sampled: &TriMesh,
    target: &SurfaceIndex,
    opts: &CompareOptions,
) -> Result<DirectionStats> {
    distance::check_surface(sampled)?;
    let n = opts.resolved_samples(sampled.faces.len(), target.face_count());
    if n as u64 > MAX_SAMPLES_PER_KIND as u64 {
        return Err(Error::Invalid(format!(
            "{n} samples per kind is over the limit of {MAX_SAMPLES_PER_KIND}"
        )));
    }
    let sampler = SurfaceSampler::new(sampled, &opts.plan(n));
    if sampler.is_empty() {
        return Err(Error::Invalid(
            "no samples: every sample kind is disabled, the sample count is 0, \
             or the surface has nothing of the enabled kinds"
                .into(),
        ));
    }
    let acc = measure(&sampler, target);
    let diagonal = sampler.surface_bbox().diagonal() as f64;
    Ok(DirectionStats::from_accum(&acc, sampler.counts(), diagonal))
}

/// Distances of every sample of `sampler` to `target`, reduced chunk by
/// chunk in parallel and merged in chunk order (deterministic).
fn measure(sampler: &SurfaceSampler<'_>, target: &SurfaceIndex) -> Accum {
    let parts: Vec<Accum> = (0..sampler.chunk_count())
        .into_par_iter()
        .map_init(Vec::new, |buf, c| {
            sampler.chunk(c, buf);
            let mut acc = Accum::EMPTY;
            for &p in buf.iter() {
                acc.add(p, target.distance(p));
            }
            acc
        })
        .collect();
    let mut total = Accum::EMPTY;
    for p in &parts {
        total.merge(p);
    }
    total
}

fn name_err(which: &str, e: Error) -> Error {
    match e {
        Error::Invalid(m) => Error::Invalid(format!("mesh {which}: {m}")),
        other => other,
    }
}
