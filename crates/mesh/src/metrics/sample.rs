//! Surface sampling for Metro-style distances: points on a mesh's vertices,
//! edges and faces, generated in fixed-size chunks so that the work can be
//! spread over threads while every run produces the same points.
//!
//! The three kinds follow MeshLab's Hausdorff Distance filter (vcglib's
//! `SurfaceSampling::VertexUniform`, `EdgeUniform` and `Montecarlo`), where
//! one count `N` applies to each enabled kind:
//!
//! - **vertex samples**: every *referenced* vertex, or a seeded uniform subset
//!   of `N` of them when the mesh has more. MeshLab samples unreferenced
//!   vertices too (they are not surface and, on the Stanford bunny, they
//!   double the measured maximum); lodkit never does.
//! - **edge samples**: `N` points spread along the unique edges in proportion
//!   to their length, evenly spaced inside each edge (endpoints excluded,
//!   they are the vertex samples), as vcglib does. Zero-length edges and
//!   edges of faces that repeat an index get none.
//! - **face samples**: `N` uniformly distributed points, area-weighted. Where
//!   MeshLab draws each sample's face independently (pure Monte Carlo),
//!   lodkit allocates the counts per face by systematic sampling (a random
//!   offset, then every `area/N`): the expected number of samples per face
//!   is the same, `N × area_f / area`, but the count cannot fluctuate, which
//!   lowers the variance of the mean and makes sure no large face is missed.
//!   Positions inside a face are uniform (reflected barycentric pair).
//!   Zero-area faces get none.
//!
//! Determinism: sample `j` belongs to chunk `j / CHUNK`; each chunk draws
//! from its own SplitMix64 stream (Steele, Lea and Flood 2014, as
//! `rand_xoshiro` implements it) seeded by `(seed, chunk)`, so the points do
//! not depend on the number of threads or on scheduling.

use glam::{DVec3, Vec3};
use rand_xoshiro::SplitMix64;
use rand_xoshiro::rand_core::{Rng, SeedableRng};

use crate::mesh::{Aabb, TriMesh};

/// Samples per chunk: the unit of parallel work and of RNG streams.
pub const CHUNK: usize = 8192;

/// How many samples of each kind a [`SurfaceSampler`] produces.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct SampleCounts {
    /// Vertex samples.
    pub vertices: usize,
    /// Edge samples.
    pub edges: usize,
    /// Face samples.
    pub faces: usize,
}

impl SampleCounts {
    /// All samples.
    pub fn total(&self) -> usize {
        self.vertices + self.edges + self.faces
    }
}

/// Which kinds to sample and how many of each (MeshLab's `SampleNum`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct SamplingPlan {
    /// Per-kind count `N`: at most `N` vertex samples, exactly `N` edge
    /// samples and exactly `N` face samples (when the mesh has edge length
    /// and area to put them on).
    pub per_kind: usize,
    /// Sample the referenced vertices.
    pub vertices: bool,
    /// Sample along the unique edges.
    pub edges: bool,
    /// Sample the faces.
    pub faces: bool,
    /// Seed of every RNG stream (same seed, same points).
    pub seed: u64,
}

/// A prepared sampling of one mesh. Building it is `O(V + F log F)`;
/// [`SurfaceSampler::chunk`] then generates any chunk of points on demand.
#[derive(Debug, Clone)]
pub struct SurfaceSampler<'m> {
    mesh: &'m TriMesh,
    /// Vertex samples, ascending vertex index.
    vertices: Vec<u32>,
    /// Unique undirected edges `(lo, hi)`, ascending.
    edges: Vec<[u32; 2]>,
    /// `edge_starts[e]..edge_starts[e + 1]` are edge `e`'s sample indices
    /// (relative to the first edge sample); `edges.len() + 1` entries, or
    /// empty when there are no edge samples.
    edge_starts: Vec<u64>,
    /// Same for faces, indexed like `mesh.faces`.
    face_starts: Vec<u64>,
    counts: SampleCounts,
    seed: u64,
}

impl<'m> SurfaceSampler<'m> {
    /// Prepares the samples of `mesh` for `plan`. Never fails: a mesh with
    /// no referenced vertex, no edge length or no area simply gets no
    /// samples of that kind. Face indices must be `< positions.len()` (the
    /// [`TriMesh`] invariant; [`super::SurfaceIndex::new`] checks it).
    pub fn new(mesh: &'m TriMesh, plan: &SamplingPlan) -> Self {
        let n = plan.per_kind;
        let mut counts = SampleCounts::default();

        let mut vertices = Vec::new();
        if plan.vertices && n > 0 {
            vertices = referenced_vertices(mesh);
            if vertices.len() > n {
                let mut rng = SplitMix64::seed_from_u64(stream_seed(plan.seed, TAG_VERTEX, 0));
                // Partial Fisher-Yates: the first `n` slots become a uniform
                // random subset; sorted again for locality of the queries.
                for i in 0..n {
                    let j = i + below(&mut rng, (vertices.len() - i) as u64) as usize;
                    vertices.swap(i, j);
                }
                vertices.truncate(n);
                vertices.sort_unstable();
            }
            counts.vertices = vertices.len();
        }

        let mut edges = Vec::new();
        let mut edge_starts = Vec::new();
        if plan.edges && n > 0 {
            edges = unique_edges(mesh);
            let lengths: Vec<f64> = edges
                .iter()
                .map(|&[a, b]| {
                    let pa = mesh.positions[a as usize].as_dvec3();
                    let pb = mesh.positions[b as usize].as_dvec3();
                    pa.distance(pb)
                })
                .collect();
            let offset = unit(&mut SplitMix64::seed_from_u64(stream_seed(
                plan.seed, TAG_EDGE, 0,
            )));
            edge_starts = systematic_starts(&lengths, n, offset);
            counts.edges = edge_starts.last().map_or(0, |&s| s as usize);
            if counts.edges == 0 {
                edges.clear();
                edge_starts.clear();
            }
        }

        let mut face_starts = Vec::new();
        if plan.faces && n > 0 {
            let areas: Vec<f64> = (0..mesh.faces.len())
                .map(|f| face_area_f64(mesh, f))
                .collect();
            let offset = unit(&mut SplitMix64::seed_from_u64(stream_seed(
                plan.seed, TAG_FACE, 0,
            )));
            face_starts = systematic_starts(&areas, n, offset);
            counts.faces = face_starts.last().map_or(0, |&s| s as usize);
            if counts.faces == 0 {
                face_starts.clear();
            }
        }

        SurfaceSampler {
            mesh,
            vertices,
            edges,
            edge_starts,
            face_starts,
            counts,
            seed: plan.seed,
        }
    }

    /// The number of samples of each kind this sampler produces.
    pub fn counts(&self) -> SampleCounts {
        self.counts
    }

    /// Total number of samples.
    pub fn len(&self) -> usize {
        self.counts.total()
    }

    /// Whether the sampler produces no sample.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Number of chunks (`ceil(len / CHUNK)`).
    pub fn chunk_count(&self) -> usize {
        self.len().div_ceil(CHUNK)
    }

    /// The bounding box of the sampled surface: its referenced vertices
    /// (all of them, whatever subset is sampled). This is the box whose
    /// diagonal the relative figures use.
    pub fn surface_bbox(&self) -> Aabb {
        surface_bbox(self.mesh)
    }

    /// Replaces `out` with the points of chunk `c` (samples
    /// `c * CHUNK .. min((c + 1) * CHUNK, len)`): vertex samples first, then
    /// edge samples, then face samples. `c >= chunk_count()` gives none.
    pub fn chunk(&self, c: usize, out: &mut Vec<Vec3>) {
        out.clear();
        let start = c.saturating_mul(CHUNK).min(self.len());
        let end = start.saturating_add(CHUNK).min(self.len());
        let nv = self.counts.vertices;
        let ne = self.counts.edges;

        // Vertex samples.
        for j in start.min(nv)..end.min(nv) {
            out.push(self.mesh.positions[self.vertices[j] as usize]);
        }

        // Edge samples (indices relative to the first edge sample).
        let (e0, e1) = (start.clamp(nv, nv + ne) - nv, end.clamp(nv, nv + ne) - nv);
        if e0 < e1 {
            let mut e = locate(&self.edge_starts, e0 as u64);
            for j in e0 as u64..e1 as u64 {
                while self.edge_starts[e + 1] <= j {
                    e += 1;
                }
                let k = self.edge_starts[e + 1] - self.edge_starts[e];
                let i = j - self.edge_starts[e];
                let t = (i + 1) as f32 / (k + 1) as f32;
                let [a, b] = self.edges[e];
                let pa = self.mesh.positions[a as usize];
                let pb = self.mesh.positions[b as usize];
                out.push(pa.lerp(pb, t));
            }
        }

        // Face samples (indices relative to the first face sample).
        let (f0, f1) = (start.max(nv + ne) - (nv + ne), end.max(nv + ne) - (nv + ne));
        if f0 < f1 {
            let mut rng = SplitMix64::seed_from_u64(stream_seed(self.seed, TAG_FACE, c as u64 + 1));
            let mut f = locate(&self.face_starts, f0 as u64);
            for j in f0 as u64..f1 as u64 {
                while self.face_starts[f + 1] <= j {
                    f += 1;
                }
                let [a, b, c] = self.mesh.triangle(f);
                let (mut u, mut v) = (unit(&mut rng), unit(&mut rng));
                if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                out.push(a + (b - a) * u as f32 + (c - a) * v as f32);
            }
        }
    }

    /// All sample points, in sample order (for callers that sample once and
    /// measure against several targets).
    pub fn points(&self) -> Vec<Vec3> {
        use rayon::prelude::*;
        let chunks: Vec<Vec<Vec3>> = (0..self.chunk_count())
            .into_par_iter()
            .map(|c| {
                let mut v = Vec::with_capacity(CHUNK);
                self.chunk(c, &mut v);
                v
            })
            .collect();
        chunks.concat()
    }
}

/// Indices of the vertices used by at least one face, ascending.
pub fn referenced_vertices(mesh: &TriMesh) -> Vec<u32> {
    let mut used = vec![false; mesh.positions.len()];
    for f in &mesh.faces {
        for &v in f {
            if let Some(u) = used.get_mut(v as usize) {
                *u = true;
            }
        }
    }
    (0..used.len() as u32)
        .filter(|&i| used[i as usize])
        .collect()
}

/// Bounding box of the referenced vertices (empty if there are none).
pub fn surface_bbox(mesh: &TriMesh) -> Aabb {
    let mut b = Aabb::EMPTY;
    for f in &mesh.faces {
        for &v in f {
            if let Some(p) = mesh.positions.get(v as usize) {
                b.min = b.min.min(*p);
                b.max = b.max.max(*p);
            }
        }
    }
    b
}

/// Unique undirected edges of the faces, `(lo, hi)` ascending; self-edges
/// (a face repeating an index) are skipped.
fn unique_edges(mesh: &TriMesh) -> Vec<[u32; 2]> {
    let mut edges: Vec<[u32; 2]> = Vec::with_capacity(mesh.faces.len() * 3);
    for &[a, b, c] in &mesh.faces {
        for (p, q) in [(a, b), (b, c), (c, a)] {
            if p != q {
                edges.push([p.min(q), p.max(q)]);
            }
        }
    }
    edges.sort_unstable();
    edges.dedup();
    edges
}

/// Area of face `f`, computed in `f64`.
fn face_area_f64(mesh: &TriMesh, f: usize) -> f64 {
    let [a, b, c] = mesh.triangle(f).map(Vec3::as_dvec3);
    0.5 * DVec3::cross(b - a, c - a).length()
}

/// Systematic allocation of `n` samples over items of the given (finite,
/// non-negative) weights: item `i` gets samples `starts[i]..starts[i + 1]`
/// with `starts[i] = floor(n × W_i / W + offset)`, `W_i` the weight before
/// `i`, `offset ∈ [0, 1)`. The counts add up to exactly `n`, and the expected
/// count of item `i` over offsets is `n × w_i / W`. Returns `[0; len + 1]`
/// when the total weight is zero.
fn systematic_starts(weights: &[f64], n: usize, offset: f64) -> Vec<u64> {
    let total: f64 = weights.iter().sum();
    let mut starts = Vec::with_capacity(weights.len() + 1);
    if !(total > 0.0 && total.is_finite()) {
        starts.resize(weights.len() + 1, 0);
        return starts;
    }
    let nf = n as f64;
    let mut cum = 0.0f64;
    starts.push(0);
    for (i, w) in weights.iter().enumerate() {
        cum += w;
        let s = if i + 1 == weights.len() {
            n as u64
        } else {
            ((nf * (cum / total) + offset).floor() as u64).min(n as u64)
        };
        // Monotone by construction; `max` guards against rounding.
        let prev = *starts.last().unwrap_or(&0);
        starts.push(s.max(prev));
    }
    starts
}

/// The item whose range `starts[i]..starts[i + 1]` holds sample `j`
/// (`j < *starts.last()`).
fn locate(starts: &[u64], j: u64) -> usize {
    starts.partition_point(|&s| s <= j).saturating_sub(1)
}

const TAG_VERTEX: u64 = 1;
const TAG_EDGE: u64 = 2;
const TAG_FACE: u64 = 3;

/// Seed of an independent stream for `(seed, tag, index)`.
fn stream_seed(seed: u64, tag: u64, index: u64) -> u64 {
    mix64(seed ^ mix64(tag.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ mix64(index)))
}

/// SplitMix64's output function (a bijective 64-bit mixer), which seeds
/// independent streams from `(seed, tag, index)`.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Uniform in `[0, 1)` with 53 random bits.
fn unit(rng: &mut SplitMix64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Uniform in `0..n` (`n > 0`), by rejection (no modulo bias).
fn below(rng: &mut SplitMix64, n: u64) -> u64 {
    let zone = u64::MAX - u64::MAX % n;
    loop {
        let x = rng.next_u64();
        if x < zone {
            return x % n;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn plan(n: usize) -> SamplingPlan {
        SamplingPlan {
            per_kind: n,
            vertices: true,
            edges: true,
            faces: true,
            seed: 7,
        }
    }

    /// Two triangles of areas 1 and 3 in the z = 0 plane, plus an
    /// unreferenced vertex far away.
    fn two_triangles() -> TriMesh {
        TriMesh::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 2.0, 0.0),
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(10.0, 0.6, 0.0),
                Vec3::new(20.0, 0.0, 0.0),
                Vec3::new(0.0, 0.0, 100.0),
            ],
            vec![[0, 1, 2], [3, 5, 4]],
        )
    }

    fn all_points(s: &SurfaceSampler) -> Vec<Vec3> {
        let mut v = Vec::new();
        let mut buf = Vec::new();
        for c in 0..s.chunk_count() {
            s.chunk(c, &mut buf);
            v.extend_from_slice(&buf);
        }
        v
    }

    #[test]
    fn counts_per_kind_match_the_plan() {
        let m = two_triangles();
        let s = SurfaceSampler::new(&m, &plan(20_000));
        assert_eq!(
            s.counts(),
            SampleCounts {
                vertices: 6,
                edges: 20_000,
                faces: 20_000
            }
        );
        let pts = all_points(&s);
        assert_eq!(pts.len(), 40_006);
        assert_eq!(s.points(), pts);
    }

    #[test]
    fn unreferenced_vertices_are_never_sampled() {
        let m = two_triangles();
        let s = SurfaceSampler::new(&m, &plan(100));
        let pts = all_points(&s);
        assert!(pts.iter().all(|p| p.z == 0.0), "the vertex at z=100 leaked");
        assert_eq!(s.surface_bbox().max.z, 0.0);
        assert_eq!(referenced_vertices(&m), vec![0, 1, 2, 3, 4, 5]);
    }

    #[test]
    fn face_samples_follow_area() {
        let m = two_triangles();
        let p = SamplingPlan {
            vertices: false,
            edges: false,
            ..plan(40_000)
        };
        let s = SurfaceSampler::new(&m, &p);
        let pts = all_points(&s);
        let first = pts.iter().filter(|p| p.x < 5.0).count();
        // Areas 1 and 3: systematic allocation gives 10 000 ± 1.
        assert!((9_999..=10_001).contains(&first), "{first}");
        // Every point lies inside its triangle.
        for p in &pts {
            if p.x < 5.0 {
                assert!(p.x >= 0.0 && p.y >= 0.0 && 2.0 * p.x + p.y <= 2.0 + 1e-5);
            } else {
                assert!(p.y >= 0.0 && p.y <= 0.6 + 1e-6 && p.x >= 10.0 && p.x <= 20.0);
            }
        }
        // Uniform inside the first triangle: the mean is its centroid.
        let c = pts
            .iter()
            .filter(|p| p.x < 5.0)
            .fold(DVec3::ZERO, |acc, p| acc + p.as_dvec3())
            / first as f64;
        assert!(
            (c - DVec3::new(1.0 / 3.0, 2.0 / 3.0, 0.0)).length() < 0.01,
            "{c}"
        );
    }

    #[test]
    fn edge_samples_are_even_and_follow_length() {
        // One segment-like triangle: edges of length 3, 4 and 5.
        let m = TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::new(3.0, 0.0, 0.0),
                Vec3::new(0.0, 4.0, 0.0),
            ],
            vec![[0, 1, 2]],
        );
        let p = SamplingPlan {
            vertices: false,
            faces: false,
            ..plan(1200)
        };
        let s = SurfaceSampler::new(&m, &p);
        let pts = all_points(&s);
        assert_eq!(pts.len(), 1200);
        let on_x = pts.iter().filter(|p| p.y == 0.0).count();
        let on_y = pts.iter().filter(|p| p.x == 0.0).count();
        assert!((299..=301).contains(&on_x), "{on_x}");
        assert!((399..=401).contains(&on_y), "{on_y}");
        // No endpoint is repeated as an edge sample.
        assert!(!pts.contains(&Vec3::ZERO));
    }

    #[test]
    fn vertex_subset_is_capped_and_seeded() {
        let m = two_triangles();
        let p = SamplingPlan {
            edges: false,
            faces: false,
            ..plan(4)
        };
        let a = all_points(&SurfaceSampler::new(&m, &p));
        assert_eq!(a.len(), 4);
        let b = all_points(&SurfaceSampler::new(&m, &p));
        assert_eq!(a, b);
    }

    #[test]
    fn same_seed_same_points_other_seed_other_points() {
        let m = two_triangles();
        let a = all_points(&SurfaceSampler::new(&m, &plan(30_000)));
        let b = all_points(&SurfaceSampler::new(&m, &plan(30_000)));
        assert_eq!(a, b);
        let c = all_points(&SurfaceSampler::new(
            &m,
            &SamplingPlan {
                seed: 8,
                ..plan(30_000)
            },
        ));
        assert_ne!(a, c);
    }

    #[test]
    fn degenerate_faces_get_no_face_or_self_edge_samples() {
        let m = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)],
            // collinear, and one repeating an index
            vec![[0, 1, 2], [0, 0, 1]],
        );
        let s = SurfaceSampler::new(&m, &plan(100));
        assert_eq!(s.counts().faces, 0);
        assert_eq!(s.counts().edges, 100);
        assert_eq!(s.counts().vertices, 3);
        assert!(all_points(&s).iter().all(|p| p.is_finite() && p.y == 0.0));
    }

    #[test]
    fn systematic_starts_add_up() {
        let w = [0.0, 1.0, 0.0, 2.5, 0.5];
        for &off in &[0.0, 0.3, 0.999] {
            let s = systematic_starts(&w, 17, off);
            assert_eq!(s.len(), 6);
            assert_eq!(*s.last().unwrap(), 17);
            assert!(s.windows(2).all(|p| p[0] <= p[1]));
            assert_eq!(s[1], s[0], "zero weight gets nothing");
        }
        assert_eq!(systematic_starts(&[0.0, 0.0], 5, 0.5), vec![0, 0, 0]);
    }
}
