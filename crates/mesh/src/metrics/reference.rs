//! One input measured against many of its levels of detail: the input's
//! distance index built once, and a per-level sample count that follows the
//! level's size.
//!
//! A build compares its input with twenty-odd meshes (the HQMS chain, the
//! continuous model's cuts, the progressive stream's levels). [`compare`]
//! builds both hierarchies per call; [`Reference`] keeps the input's and
//! builds only the level's, which is the smaller of the two.
//!
//! # Adaptive sample counts
//!
//! [`level_samples`] gives `LEVEL_SAMPLES_PER_FACE` (4) samples per face
//! of the *level* for each kind, at least [`MIN_LEVEL_SAMPLES`] (50 000)
//! and at most [`DEFAULT_MIN_SAMPLES`] (1 000 000, `compare`'s own floor).
//! Why the level's faces and not the input's: the distance between a fine
//! input and a coarser level varies over the scale of the level's faces
//! (each level face spans many input faces and lies close to them), so
//! four samples per level face per kind (eight with edges and faces
//! together, about half a face apart) resolve it; the floor keeps every
//! input vertex sampled up to 50 000 referenced vertices (vertex samples
//! take at most `N`), where the input-to-level maximum sits. A level of
//! 1 000 faces is measured with 50 000 samples per kind instead of a
//! million. On the Stanford bunny's HQMS chain the means move by under
//! 1 % and the maxima read up to about 10 % lower than with a million
//! samples (a maximum over fewer samples can only be lower).
//!
//! [`compare`]: super::compare
//! [`DEFAULT_MIN_SAMPLES`]: super::DEFAULT_MIN_SAMPLES

use super::{CompareOptions, CompareReport, SurfaceIndex, SymmetricStats, name_err, one_sided};
use crate::error::Result;
use crate::mesh::TriMesh;

/// Per-kind samples per face of the measured level ([`level_samples`]).
pub const LEVEL_SAMPLES_PER_FACE: usize = 4;
/// Fewest per-kind samples [`level_samples`] gives.
pub const MIN_LEVEL_SAMPLES: usize = 50_000;

/// The per-kind sample count for measuring a level of `level_faces` faces
/// against its input: `clamp(4 × level_faces, 50 000, 1 000 000)` (see the
/// [module docs](self#adaptive-sample-counts) for why).
pub fn level_samples(level_faces: usize) -> usize {
    level_faces
        .saturating_mul(LEVEL_SAMPLES_PER_FACE)
        .clamp(MIN_LEVEL_SAMPLES, super::DEFAULT_MIN_SAMPLES)
}

/// An input mesh prepared to be measured against many other meshes: its
/// [`SurfaceIndex`] is built once, in [`Reference::new`].
#[derive(Debug)]
pub struct Reference<'m> {
    mesh: &'m TriMesh,
    index: SurfaceIndex,
}

impl<'m> Reference<'m> {
    /// Builds the input's index (`O(F log F)`). Errors as
    /// [`SurfaceIndex::new`] does (no face, index out of range, non-finite
    /// referenced vertex), the message prefixed with "mesh A".
    pub fn new(mesh: &'m TriMesh) -> Result<Self> {
        let index = SurfaceIndex::new(mesh).map_err(|e| name_err("A", e))?;
        Ok(Reference { mesh, index })
    }

    /// The input mesh.
    pub fn mesh(&self) -> &'m TriMesh {
        self.mesh
    }

    /// The input's distance index.
    pub fn index(&self) -> &SurfaceIndex {
        &self.index
    }

    /// [`compare`](super::compare)`(input, other, opts)` (A is the input,
    /// B is `other`), without rebuilding the input's index: `compare` is
    /// this call on a fresh `Reference`. Errors as `compare` does.
    pub fn compare(&self, other: &TriMesh, opts: &CompareOptions) -> Result<CompareReport> {
        let ib = SurfaceIndex::new(other).map_err(|e| name_err("B", e))?;
        let n = opts.resolved_samples(self.mesh.faces.len(), other.faces.len());
        let fixed = CompareOptions {
            samples: Some(n),
            ..*opts
        };
        let a_to_b = one_sided(self.mesh, &ib, &fixed).map_err(|e| name_err("A", e))?;
        let b_to_a = one_sided(other, &self.index, &fixed).map_err(|e| name_err("B", e))?;
        let union = self.index.bbox().union(&ib.bbox()).diagonal() as f64;
        let symmetric = SymmetricStats::combine(&a_to_b, &b_to_a, union);
        Ok(CompareReport {
            a_to_b,
            b_to_a,
            symmetric,
            samples_per_kind: n as u64,
            seed: opts.seed,
        })
    }

    /// [`Reference::compare`] with `samples` per kind, or
    /// [`level_samples`]`(level faces)` when `samples` is `None`; the other
    /// options are the defaults. The report's `samples_per_kind` says which
    /// count was used.
    pub fn compare_level(&self, level: &TriMesh, samples: Option<usize>) -> Result<CompareReport> {
        let opts = CompareOptions {
            samples: Some(samples.unwrap_or_else(|| level_samples(level.faces.len()))),
            ..CompareOptions::default()
        };
        self.compare(level, &opts)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes::icosphere;

    #[test]
    fn reference_compare_is_compare() {
        let a = icosphere(3);
        let b = icosphere(1);
        let opts = CompareOptions {
            samples: Some(20_000),
            ..CompareOptions::default()
        };
        let r = Reference::new(&a).unwrap();
        assert_eq!(
            r.compare(&b, &opts).unwrap(),
            super::super::compare(&a, &b, &opts).unwrap()
        );
        let adaptive = r.compare_level(&b, None).unwrap();
        assert_eq!(adaptive.samples_per_kind, MIN_LEVEL_SAMPLES as u64);
        assert!(Reference::new(&TriMesh::default()).is_err());
        assert!(r.compare(&TriMesh::default(), &opts).is_err());
    }

    #[test]
    fn level_samples_follow_the_level() {
        assert_eq!(level_samples(0), MIN_LEVEL_SAMPLES);
        assert_eq!(level_samples(1_000), MIN_LEVEL_SAMPLES);
        assert_eq!(level_samples(20_000), 80_000);
        assert_eq!(level_samples(usize::MAX), super::super::DEFAULT_MIN_SAMPLES);
    }
}
