//! Face and vertex normals.
//!
//! Vertex normals are area-weighted: the sum of the (unnormalised) cross
//! products of the incident faces, which weighs each face by twice its area
//! (the choice of the marching-cube-octree thesis §4.3.1 for mesh input).

use glam::Vec3;

use crate::mesh::TriMesh;

/// Unit normal of each face (zero for a degenerate face).
pub fn face_normals(mesh: &TriMesh) -> Vec<Vec3> {
    (0..mesh.faces.len())
        .map(|f| {
            let [a, b, c] = mesh.triangle(f);
            (b - a).cross(c - a).normalize_or_zero()
        })
        .collect()
}

/// Area-weighted unit vertex normals. A vertex with no (non-degenerate)
/// incident face gets +Z so the result is always a valid unit vector.
pub fn vertex_normals(mesh: &TriMesh) -> Vec<Vec3> {
    let mut acc = vec![Vec3::ZERO; mesh.positions.len()];
    for f in 0..mesh.faces.len() {
        let [a, b, c] = mesh.triangle(f);
        let n = (b - a).cross(c - a);
        for &v in &mesh.faces[f] {
            acc[v as usize] += n;
        }
    }
    acc.into_iter()
        .map(|n| n.try_normalize().unwrap_or(Vec3::Z))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn flat_quad_normals_point_up_and_isolated_vertex_gets_z() {
        let p = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::Y,
            Vec3::splat(9.0),
        ];
        let m = TriMesh::new(p, vec![[0, 1, 2], [0, 2, 3]]);
        for n in vertex_normals(&m) {
            assert!((n - Vec3::Z).length() < 1e-6);
        }
        assert_eq!(face_normals(&m), vec![Vec3::Z, Vec3::Z]);
    }

    #[test]
    fn larger_face_dominates() {
        // Vertex 0 is shared by a big face in the XY plane and a small one in XZ.
        let p = vec![
            Vec3::ZERO,
            Vec3::X * 10.0,
            Vec3::Y * 10.0,
            Vec3::X * 0.1,
            Vec3::Z * 0.1,
        ];
        let m = TriMesh::new(p, vec![[0, 1, 2], [0, 3, 4]]);
        let n = vertex_normals(&m)[0];
        assert!(n.z > 0.99);
    }
}
