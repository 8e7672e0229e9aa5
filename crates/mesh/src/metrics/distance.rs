//! Closest-point queries on a triangle mesh through a bounding-volume
//! hierarchy: the "distance field" half of Metro (Cignoni, Rocchini and
//! Scopigno 1998), where every sample of one surface looks up its nearest
//! point on the other.
//!
//! MeshLab's Hausdorff Distance filter uses a uniform grid of faces
//! (vcglib's `GridStaticPtr`); lodkit uses parry3d's BVH over the triangles.
//! Both return the exact Euclidean distance to the nearest point of the
//! triangle set (unsigned, `solid = false`), so the numbers agree; only the
//! speed differs. Unlike MeshLab's filter there is no "max distance" cut-off:
//! every sample counts.
//!
//! A [`SurfaceIndex`] is built once per target mesh and can be queried from
//! many threads, so one reference can be measured against many meshes
//! without rebuilding the hierarchy.

use glam::Vec3;
use parry3d::shape::CompositeShapeRef;

use crate::error::{Error, Result};
use crate::mesh::{Aabb, TriMesh};

/// The nearest point of a surface to a query point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// The nearest point on the surface (object units).
    pub point: Vec3,
    /// Euclidean distance from the query to `point` (object units, ≥ 0).
    pub distance: f32,
    /// Index of the face `point` lies on (in the source mesh's `faces`).
    pub face: u32,
}

/// A triangle mesh prepared for closest-point queries.
///
/// Degenerate faces are kept: a zero-area face is measured as its longest
/// edge (a face repeating an index as the segment it spans). Unreferenced
/// vertices play no part.
///
/// Duplicate triangles (the same three corner positions, in any order and
/// through any vertex indices) are indexed once: they change no distance,
/// and a hierarchy over many identical boxes cannot prune any of them, so
/// every query would visit all copies (a linear scan per query on a file of
/// one triangle repeated a million times).
///
/// The hierarchy holds the positions scaled by a power of two that brings
/// the surface's largest extent into `[0.5, 1)`: parry3d's projections use
/// fixed tolerances, which at extents far from 1 (below about 1e-7 or above
/// about 1e9) give distances off by an order of magnitude. Scaling by a
/// power of two is exact, so a query's answer is the same at every scale
/// (bit for bit under power-of-two scales).
pub struct SurfaceIndex {
    shape: parry3d::shape::TriMesh,
    /// The power of two the hierarchy's positions were multiplied by.
    scale: f32,
    /// For each indexed triangle, its first face in the source mesh.
    source_face: Vec<u32>,
    face_count: usize,
    bbox: Aabb,
}

impl std::fmt::Debug for SurfaceIndex {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SurfaceIndex")
            .field("face_count", &self.face_count)
            .field("bbox", &self.bbox)
            .finish_non_exhaustive()
    }
}

impl SurfaceIndex {
    /// Builds the hierarchy over `mesh`'s distinct triangles (`O(F log F)`,
    /// plus one hash of each face to drop duplicates).
    ///
    /// Errors ([`Error::Invalid`]) if the mesh has no face, a face index is
    /// out of range, or a referenced vertex is not finite.
    pub fn new(mesh: &TriMesh) -> Result<Self> {
        check_surface(mesh)?;
        let (faces, source_face) = distinct_triangles(mesh);
        let bbox = super::sample::surface_bbox(mesh);
        let scale = unit_scale(&bbox);
        let positions = mesh.positions.iter().map(|&p| p * scale).collect();
        let shape = parry3d::shape::TriMesh::new(positions, faces)
            .map_err(|e| Error::Invalid(format!("cannot index the mesh: {e}")))?;
        Ok(SurfaceIndex {
            shape,
            scale,
            source_face,
            face_count: mesh.faces.len(),
            bbox,
        })
    }

    /// Number of faces indexed.
    pub fn face_count(&self) -> usize {
        self.face_count
    }

    /// Number of distinct triangles in the hierarchy (≤ [`Self::face_count`]):
    /// what a query's cost grows with, logarithmically.
    pub fn indexed_triangle_count(&self) -> usize {
        self.source_face.len()
    }

    /// Bounding box of the indexed surface (its referenced vertices).
    pub fn bbox(&self) -> Aabb {
        self.bbox
    }

    /// The nearest surface point to `p`. `p` must be finite; for a
    /// non-finite `p` the answer is `p` itself at distance 0 on face 0
    /// (there is no meaningful nearest point).
    pub fn closest(&self, p: Vec3) -> Closest {
        let q = p * self.scale;
        match CompositeShapeRef(&self.shape).project_local_point(q, f32::MAX, false) {
            Some((face, proj)) if q.is_finite() => Closest {
                point: proj.point / self.scale,
                distance: proj.point.distance(q) / self.scale,
                face: self.source_face[face as usize],
            },
            _ => Closest {
                point: p,
                distance: 0.0,
                face: 0,
            },
        }
    }

    /// Distance from `p` to the surface (object units).
    pub fn distance(&self, p: Vec3) -> f32 {
        self.closest(p).distance
    }

    /// Distances of many points, in the same order, computed in parallel.
    pub fn distances(&self, points: &[Vec3]) -> Vec<f32> {
        use rayon::prelude::*;
        points.par_iter().map(|&p| self.distance(p)).collect()
    }
}

/// The power of two that brings `bbox`'s largest side into `[0.5, 1)`,
/// lowered where needed so the largest scaled coordinate stays below 2^60
/// (queries a little outside the box must not overflow); 1 for an empty or
/// flat-to-a-point box.
fn unit_scale(bbox: &Aabb) -> f32 {
    let side = (bbox.max - bbox.min).max_element();
    let reach = bbox.min.abs().max(bbox.max.abs()).max_element();
    if !(side.is_normal() && reach.is_finite()) {
        return 1.0;
    }
    let mut e = -(side.log2().floor() as i32) - 1;
    if reach > 0.0 {
        e = e.min(60 - reach.log2().ceil() as i32);
    }
    2f32.powi(e.clamp(-120, 120))
}

/// The faces of `mesh` with duplicate triangles removed (the first of each
/// kept, in order), and each kept face's index in `mesh.faces`. Two faces
/// are duplicates when their corner positions are the same set of bit
/// patterns (`-0` and `0` counted equal).
fn distinct_triangles(mesh: &TriMesh) -> (Vec<[u32; 3]>, Vec<u32>) {
    let key = |f: &[u32; 3]| {
        let mut k = f.map(|i| {
            (mesh.positions[i as usize] + Vec3::ZERO)
                .to_array()
                .map(f32::to_bits)
        });
        k.sort_unstable();
        k
    };
    let mut seen = rustc_hash::FxHashSet::default();
    seen.reserve(mesh.faces.len());
    let mut faces = Vec::with_capacity(mesh.faces.len());
    let mut source = Vec::with_capacity(mesh.faces.len());
    for (i, f) in mesh.faces.iter().enumerate() {
        if seen.insert(key(f)) {
            faces.push(*f);
            source.push(i as u32);
        }
    }
    (faces, source)
}

/// Checks that `mesh` has a surface to sample or index: at least one face,
/// face indices in range, referenced vertices finite.
pub(crate) fn check_surface(mesh: &TriMesh) -> Result<()> {
    if mesh.faces.is_empty() {
        return Err(Error::Invalid(format!(
            "the mesh has no faces ({} vertices): a surface is needed",
            mesh.positions.len()
        )));
    }
    let n = mesh.positions.len();
    for (i, f) in mesh.faces.iter().enumerate() {
        for &v in f {
            match mesh.positions.get(v as usize) {
                None => {
                    return Err(Error::Invalid(format!(
                        "face {i} has index {v} but the mesh has {n} vertices"
                    )));
                }
                Some(p) if !p.is_finite() => {
                    return Err(Error::Invalid(format!(
                        "vertex {v} (of face {i}) is not finite ({p})"
                    )));
                }
                Some(_) => {}
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The same surface and queries at any scale give the same distances
    /// relative to that scale (parry3d's fixed tolerances would otherwise
    /// answer an order of magnitude off far from unit extents).
    #[test]
    fn distances_scale_with_the_surface() {
        let base = crate::shapes::icosphere(3);
        let queries: Vec<Vec3> = (0..64)
            .map(|i| {
                let t = i as f32 * 0.37;
                Vec3::new(t.cos(), (t * 1.3).sin(), (t * 0.7).cos()).normalize()
                    * (0.9 + 0.003 * i as f32)
            })
            .collect();
        let at = |s: f32| {
            let mut m = base.clone();
            for p in &mut m.positions {
                *p *= s;
            }
            let index = SurfaceIndex::new(&m).unwrap();
            queries
                .iter()
                .map(|&q| index.distance(q * s) / s)
                .collect::<Vec<f32>>()
        };
        let unit = at(1.0);
        for s in [1e-12f32, 1e-10, 1e-3, 1e6, 1e12, 1e15] {
            for (a, b) in at(s).iter().zip(&unit) {
                assert!(
                    (a - b).abs() <= 1e-4 * b.max(1e-3),
                    "scale {s}: {a} against {b}"
                );
            }
        }
    }

    fn triangle() -> TriMesh {
        TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::new(2.0, 0.0, 0.0),
                Vec3::new(0.0, 2.0, 0.0),
            ],
            vec![[0, 1, 2]],
        )
    }

    #[test]
    fn closest_point_in_each_voronoi_region() {
        let idx = SurfaceIndex::new(&triangle()).unwrap();
        // Above the interior: straight down.
        let c = idx.closest(Vec3::new(0.5, 0.5, 3.0));
        assert_eq!(c.point, Vec3::new(0.5, 0.5, 0.0));
        assert_eq!(c.distance, 3.0);
        assert_eq!(c.face, 0);
        // Beyond a vertex.
        let c = idx.closest(Vec3::new(-3.0, -4.0, 0.0));
        assert_eq!(c.point, Vec3::ZERO);
        assert_eq!(c.distance, 5.0);
        // Beyond the hypotenuse, on both sides of the plane.
        let d = idx.distance(Vec3::new(2.0, 2.0, 0.0));
        assert!((d - 2f32.sqrt()).abs() < 1e-6, "{d}");
        let d = idx.distance(Vec3::new(0.5, 0.5, -1.0));
        assert_eq!(d, 1.0);
    }

    #[test]
    fn picks_the_nearest_of_many_faces() {
        let mut m = triangle();
        // A second triangle 1 unit above the first.
        m.positions.extend([
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(2.0, 0.0, 1.0),
            Vec3::new(0.0, 2.0, 1.0),
        ]);
        m.faces.push([3, 4, 5]);
        let idx = SurfaceIndex::new(&m).unwrap();
        let c = idx.closest(Vec3::new(0.5, 0.5, 0.8));
        assert_eq!(c.face, 1);
        assert!((c.distance - 0.2).abs() < 1e-6);
        assert_eq!(
            idx.distances(&[Vec3::new(0.5, 0.5, 0.3), Vec3::new(0.5, 0.5, 2.0)]),
            vec![0.3, 1.0]
        );
    }

    /// One triangle repeated many times (in every corner order, through
    /// copies of its vertices) is indexed once, so queries stay
    /// logarithmic; distances and face numbers are those of the original.
    #[test]
    fn duplicate_faces_are_indexed_once() {
        let base = triangle();
        let mut positions = base.positions.clone();
        let mut faces = vec![];
        for i in 0..100_000u32 {
            match i % 3 {
                0 => faces.push([0, 1, 2]),
                1 => faces.push([2, 0, 1]),
                _ => {
                    let o = positions.len() as u32;
                    positions.extend_from_slice(&base.positions);
                    faces.push([o + 1, o, o + 2]);
                }
            }
        }
        // Plus one distinct face, and -0 against 0.
        let o = positions.len() as u32;
        positions.extend([
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(6.0, 0.0, 0.0),
            Vec3::new(5.0, 1.0, 0.0),
        ]);
        faces.push([o, o + 1, o + 2]);
        positions.push(-base.positions[0]);
        faces.push([positions.len() as u32 - 1, 1, 2]);
        let m = TriMesh::new(positions, faces);
        let idx = SurfaceIndex::new(&m).unwrap();
        assert_eq!(idx.face_count(), 100_002);
        assert_eq!(idx.indexed_triangle_count(), 2);
        let c = idx.closest(Vec3::new(0.2, 0.2, 1.0));
        assert_eq!(c.face, 0);
        assert!((c.distance - 1.0).abs() < 1e-6);
        assert_eq!(idx.closest(Vec3::new(5.2, 0.2, 0.0)).face, 100_000);
    }

    #[test]
    fn degenerate_faces_are_segments() {
        // Collinear face and a face repeating an index: both are segments
        // on the x axis from 0 to 2.
        for face in [[0, 1, 2], [0, 0, 2]] {
            let m = TriMesh::new(
                vec![Vec3::ZERO, Vec3::X, Vec3::new(2.0, 0.0, 0.0)],
                vec![face],
            );
            let idx = SurfaceIndex::new(&m).unwrap();
            assert_eq!(idx.distance(Vec3::new(1.5, 3.0, 4.0)), 5.0);
            assert_eq!(idx.distance(Vec3::new(5.0, 4.0, 0.0)), 5.0);
        }
    }

    #[test]
    fn rejects_meshes_without_a_surface() {
        let empty = TriMesh::default();
        assert!(matches!(SurfaceIndex::new(&empty), Err(Error::Invalid(_))));
        let points_only = TriMesh::new(vec![Vec3::ZERO; 3], vec![]);
        assert!(SurfaceIndex::new(&points_only).is_err());
        let bad_index = TriMesh::new(vec![Vec3::ZERO; 3], vec![[0, 1, 3]]);
        assert!(SurfaceIndex::new(&bad_index).is_err());
        let nan = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::NAN], vec![[0, 1, 2]]);
        assert!(SurfaceIndex::new(&nan).is_err());
    }
}
