//! Synthetic shapes for tests and benchmarks: every shape is a pure
//! function of its parameters (same arguments → identical mesh), welded,
//! with counter-clockwise outward-facing triangles.
//!
//! | shape | closed | use |
//! |---|---|---|
//! | [`uv_sphere`], [`icosphere`], [`torus`] | yes | analytic distances, genus 0 / 1 |
//! | [`blob`] | yes | any size (1M+ triangle benchmarks), non-uniform curvature |
//! | [`terrain`] | no, one boundary loop | open surfaces, `--lock-border` |
//! | [`holey_sphere`] | no, several small holes | hole filling |
//! | [`non_manifold`] | no | fins and bow-tie vertices |

mod blob;
mod blob_stream;
mod defects;
mod spheres;
mod subdivided;
mod torus;

pub use blob::{DEFAULT_NOISE_SEED, blob, blob_with_seed};
pub use blob_stream::{BlobCounts, blob_counts, write_blob_ply};
pub use defects::{holey_sphere, non_manifold, terrain};
pub use spheres::{icosphere, uv_sphere};
pub use subdivided::write_subdivided_ply;
pub use torus::torus;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::topology::topology_stats;

    fn euler(m: &crate::TriMesh) -> i64 {
        let s = topology_stats(m);
        m.positions.len() as i64 - s.edges as i64 + m.faces.len() as i64
    }

    #[test]
    fn closed_shapes_are_closed_manifolds_with_the_right_genus() {
        for (m, chi) in [
            (uv_sphere(16, 8), 2),
            (icosphere(3), 2),
            (torus(1.0, 0.3, 24, 12), 0),
            (blob(20_000), 2),
        ] {
            m.validate().unwrap();
            let s = topology_stats(&m);
            assert_eq!(s.boundary_edges, 0);
            assert_eq!(s.non_manifold_edges, 0);
            assert_eq!(s.non_manifold_vertices, 0);
            assert_eq!(s.components, 1);
            assert_eq!(euler(&m), chi);
        }
    }

    #[test]
    fn closed_shapes_face_outward() {
        for m in [uv_sphere(16, 8), icosphere(2), blob(5_000)] {
            let c = glam::Vec3::ZERO;
            let outward = (0..m.faces.len())
                .filter(|&f| {
                    let [a, b, cc] = m.triangle(f);
                    (b - a).cross(cc - a).dot((a + b + cc) / 3.0 - c) > 0.0
                })
                .count();
            assert_eq!(outward, m.faces.len());
        }
    }

    #[test]
    fn icosphere_counts() {
        assert_eq!(icosphere(0).faces.len(), 20);
        assert_eq!(icosphere(3).faces.len(), 20 * 64);
        assert_eq!(icosphere(3).positions.len(), 10 * 64 + 2);
    }

    #[test]
    fn blob_hits_the_requested_size_and_is_deterministic() {
        for target in [1_000, 100_000] {
            let m = blob(target);
            let err = (m.faces.len() as f64 - target as f64).abs() / target as f64;
            assert!(err < 0.05, "{target}: {}", m.faces.len());
        }
        assert_eq!(blob(3_000), blob(3_000));
        assert_ne!(blob_with_seed(3_000, 1), blob_with_seed(3_000, 2));
    }

    #[test]
    fn defect_shapes_have_their_defects() {
        let t = terrain(10, 8);
        let s = topology_stats(&t);
        assert_eq!(
            (t.faces.len(), s.boundary_loops, s.boundary_edges),
            (160, 1, 36)
        );
        let h = holey_sphere(3, 4);
        let s = topology_stats(&h);
        assert_eq!(s.boundary_loops, 4);
        assert_eq!(s.non_manifold_edges, 0);
        let n = non_manifold();
        n.validate().unwrap();
        let s = topology_stats(&n);
        assert!(s.non_manifold_edges >= 1 && s.non_manifold_vertices >= 1);
    }
}
