//! Statistics of sampled distances, as Metro (Cignoni, Rocchini and
//! Scopigno 1998) and MeshLab's Hausdorff Distance filter report them: the
//! minimum, the maximum (the one-sided Hausdorff distance), the mean (L1)
//! and the root mean square (L2) over all samples, each sample weighing the
//! same. Absolute figures are in the meshes' units; relative ones are
//! percentages of a bounding-box diagonal (which one is documented on each
//! field).
//!
//! Accumulation is in `f64`, chunk by chunk, and chunks are merged in chunk
//! order, so the figures do not depend on threads or scheduling.

use glam::Vec3;
use serde::Serialize;

use super::sample::SampleCounts;

/// Running sums over a set of distances.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Accum {
    pub n: u64,
    pub min: f64,
    pub max: f64,
    /// The sample where `max` was first reached.
    pub max_at: Vec3,
    pub sum: f64,
    pub sum_sq: f64,
}

impl Accum {
    pub const EMPTY: Accum = Accum {
        n: 0,
        min: f64::INFINITY,
        max: f64::NEG_INFINITY,
        max_at: Vec3::ZERO,
        sum: 0.0,
        sum_sq: 0.0,
    };

    #[inline]
    pub fn add(&mut self, p: Vec3, d: f32) {
        let d = d as f64;
        self.n += 1;
        self.min = self.min.min(d);
        if d > self.max {
            self.max = d;
            self.max_at = p;
        }
        self.sum += d;
        self.sum_sq += d * d;
    }

    /// Appends `o`, which covers samples after `self`'s.
    pub fn merge(&mut self, o: &Accum) {
        self.n += o.n;
        self.min = self.min.min(o.min);
        if o.max > self.max {
            self.max = o.max;
            self.max_at = o.max_at;
        }
        self.sum += o.sum;
        self.sum_sq += o.sum_sq;
    }
}

/// Distances from the samples of one surface to the other surface.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct DirectionStats {
    /// Number of samples (`vertex_samples + edge_samples + face_samples`).
    pub samples: u64,
    /// Samples placed on vertices.
    pub vertex_samples: u64,
    /// Samples placed along edges.
    pub edge_samples: u64,
    /// Samples placed on faces.
    pub face_samples: u64,
    /// Smallest sample distance (object units).
    pub min: f64,
    /// Largest sample distance: the one-sided Hausdorff distance (object
    /// units).
    pub max: f64,
    /// Mean sample distance (object units).
    pub mean: f64,
    /// Root mean square of the sample distances (object units).
    pub rms: f64,
    /// The sample where `max` was reached.
    pub max_at: [f32; 3],
    /// Diagonal of the bounding box of the *sampled* surface's referenced
    /// vertices, the box MeshLab's filter uses (it also counts unreferenced
    /// vertices, lodkit does not).
    pub diagonal: f64,
    /// `max` as a percentage of `diagonal` (0 when the diagonal is 0).
    pub max_pct: f64,
    /// `mean` as a percentage of `diagonal` (0 when the diagonal is 0).
    pub mean_pct: f64,
    /// `rms` as a percentage of `diagonal` (0 when the diagonal is 0).
    pub rms_pct: f64,
}

impl DirectionStats {
    /// Finishes `acc` (which must hold at least one sample).
    pub(crate) fn from_accum(acc: &Accum, counts: SampleCounts, diagonal: f64) -> Self {
        let n = acc.n.max(1) as f64;
        let mean = acc.sum / n;
        let rms = (acc.sum_sq / n).sqrt();
        DirectionStats {
            samples: acc.n,
            vertex_samples: counts.vertices as u64,
            edge_samples: counts.edges as u64,
            face_samples: counts.faces as u64,
            min: acc.min,
            max: acc.max,
            mean,
            rms,
            max_at: acc.max_at.to_array(),
            diagonal,
            max_pct: pct(acc.max, diagonal),
            mean_pct: pct(mean, diagonal),
            rms_pct: pct(rms, diagonal),
        }
    }
}

/// The two directions combined, Metro's way: each figure is the larger of
/// the two one-sided figures.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SymmetricStats {
    /// Samples in both directions together.
    pub samples: u64,
    /// The symmetric Hausdorff distance, `max(a_to_b.max, b_to_a.max)`.
    pub max: f64,
    /// `max(a_to_b.mean, b_to_a.mean)` (not a pooled mean).
    pub mean: f64,
    /// `max(a_to_b.rms, b_to_a.rms)` (not a pooled RMS).
    pub rms: f64,
    /// Diagonal of the union of both surfaces' bounding boxes.
    pub diagonal: f64,
    /// `max` as a percentage of the union diagonal.
    pub max_pct: f64,
    /// `mean` as a percentage of the union diagonal.
    pub mean_pct: f64,
    /// `rms` as a percentage of the union diagonal.
    pub rms_pct: f64,
}

impl SymmetricStats {
    pub(crate) fn combine(ab: &DirectionStats, ba: &DirectionStats, diagonal: f64) -> Self {
        let max = ab.max.max(ba.max);
        let mean = ab.mean.max(ba.mean);
        let rms = ab.rms.max(ba.rms);
        SymmetricStats {
            samples: ab.samples + ba.samples,
            max,
            mean,
            rms,
            diagonal,
            max_pct: pct(max, diagonal),
            mean_pct: pct(mean, diagonal),
            rms_pct: pct(rms, diagonal),
        }
    }
}

/// The result of [`super::compare`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CompareReport {
    /// Samples of A measured against B.
    pub a_to_b: DirectionStats,
    /// Samples of B measured against A.
    pub b_to_a: DirectionStats,
    /// Both directions combined (see [`SymmetricStats`]).
    pub symmetric: SymmetricStats,
    /// The per-kind sample count `N` that was used (resolved default or the
    /// caller's).
    pub samples_per_kind: u64,
    /// The RNG seed that was used.
    pub seed: u64,
}

impl std::fmt::Display for CompareReport {
    /// A fixed-width table, one row per direction, absolute and relative.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        writeln!(
            f,
            "{:<10} {:>9} {:>12} {:>12} {:>12} {:>9} {:>9} {:>9}",
            "direction", "samples", "max", "mean", "rms", "max%", "mean%", "rms%"
        )?;
        let row = |f: &mut std::fmt::Formatter<'_>,
                   name: &str,
                   n: u64,
                   s: [f64; 6]|
         -> std::fmt::Result {
            writeln!(
                f,
                "{:<10} {:>9} {:>12.6e} {:>12.6e} {:>12.6e} {:>9.4} {:>9.4} {:>9.4}",
                name, n, s[0], s[1], s[2], s[3], s[4], s[5]
            )
        };
        for (name, d) in [("A->B", &self.a_to_b), ("B->A", &self.b_to_a)] {
            row(
                f,
                name,
                d.samples,
                [d.max, d.mean, d.rms, d.max_pct, d.mean_pct, d.rms_pct],
            )?;
        }
        let s = &self.symmetric;
        row(
            f,
            "symmetric",
            s.samples,
            [s.max, s.mean, s.rms, s.max_pct, s.mean_pct, s.rms_pct],
        )?;
        write!(
            f,
            "% of bbox diagonal: A->B of A ({:.6}), B->A of B ({:.6}), symmetric of A∪B ({:.6})",
            self.a_to_b.diagonal, self.b_to_a.diagonal, s.diagonal
        )
    }
}

fn pct(v: f64, diagonal: f64) -> f64 {
    if diagonal > 0.0 {
        100.0 * v / diagonal
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn accum_statistics() {
        let mut a = Accum::EMPTY;
        for (i, d) in [3.0f32, 4.0].into_iter().enumerate() {
            a.add(Vec3::splat(i as f32), d);
        }
        let mut b = Accum::EMPTY;
        b.add(Vec3::splat(9.0), 4.0); // ties do not move max_at
        a.merge(&b);
        let counts = SampleCounts {
            vertices: 1,
            edges: 1,
            faces: 1,
        };
        let s = DirectionStats::from_accum(&a, counts, 50.0);
        assert_eq!(s.samples, 3);
        assert_eq!((s.min, s.max), (3.0, 4.0));
        assert_eq!(s.max_at, [1.0; 3]);
        assert!((s.mean - 11.0 / 3.0).abs() < 1e-12);
        assert!((s.rms - (41.0f64 / 3.0).sqrt()).abs() < 1e-12);
        assert_eq!(s.max_pct, 8.0);
        let z = DirectionStats::from_accum(&a, counts, 0.0);
        assert_eq!(z.max_pct, 0.0);
    }

    #[test]
    fn symmetric_takes_the_larger_direction() {
        let mut a = Accum::EMPTY;
        a.add(Vec3::ZERO, 1.0);
        a.add(Vec3::ZERO, 3.0);
        let mut b = Accum::EMPTY;
        b.add(Vec3::ZERO, 2.125);
        let c = SampleCounts::default();
        let ab = DirectionStats::from_accum(&a, c, 10.0);
        let ba = DirectionStats::from_accum(&b, c, 10.0);
        let s = SymmetricStats::combine(&ab, &ba, 20.0);
        assert_eq!(s.samples, 3);
        assert_eq!(s.max, 3.0);
        // mean from B→A, rms from A→B: each figure takes its larger side.
        assert_eq!(s.mean, 2.125);
        assert_eq!(s.rms, 5f64.sqrt());
        assert_eq!(s.max_pct, 15.0);
    }
}
