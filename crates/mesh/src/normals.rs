//! Face and vertex normals.
//!
//! Vertex normals are area-weighted: the sum of the (unnormalised) cross
//! products of the incident faces, which weighs each face by twice its area
//! (the choice of the marching-cube-octree thesis §4.3.1 for mesh input).
//!
//! [`creased_normals`] is the same sum restricted, per corner, to the faces
//! within a crease angle of the corner's own face, so a hard edge stays
//! hard and the rest is smooth; a vertex whose corners end up with
//! different normals is split into one vertex per distinct normal (the
//! convention of three.js's `toCreasedNormals` and of Blender's auto
//! smooth). [`NormalsMode`] is the `--normals keep|none|auto[=DEGREES]`
//! choice the CLI applies to what it writes.

use glam::Vec3;
use rustc_hash::FxHashMap;

use crate::mesh::TriMesh;

/// The crease angle `auto` uses when none is given, in degrees: edges
/// sharper than this stay hard. 60° is three.js's and glTF exporters'
/// usual default; it keeps a cube's edges and a scan's smooth surface.
pub const DEFAULT_CREASE_DEGREES: f32 = 60.0;

/// What to do with a mesh's vertex normals before it is written.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NormalsMode {
    /// Write the normals the mesh has (none if it has none).
    Keep,
    /// Write no normals.
    None,
    /// Compute smooth normals with this crease angle (degrees, in
    /// `0..=180`; 180 = no crease), replacing any the mesh has.
    Auto(f32),
}

impl NormalsMode {
    /// The default: `Auto(DEFAULT_CREASE_DEGREES)` for a mesh without
    /// normals, `Keep` for one with them.
    pub fn default_for(mesh: &TriMesh) -> NormalsMode {
        if mesh.normals.is_some() {
            NormalsMode::Keep
        } else {
            NormalsMode::Auto(DEFAULT_CREASE_DEGREES)
        }
    }

    /// `mesh` with its normals as this mode asks (a copy only when they
    /// change). `Auto` may add vertices (see [`creased_normals`]).
    pub fn apply<'a>(self, mesh: &'a TriMesh) -> std::borrow::Cow<'a, TriMesh> {
        use std::borrow::Cow;
        match self {
            NormalsMode::Keep => Cow::Borrowed(mesh),
            NormalsMode::None if mesh.normals.is_none() => Cow::Borrowed(mesh),
            NormalsMode::None => Cow::Owned(TriMesh {
                normals: None,
                ..mesh.clone()
            }),
            NormalsMode::Auto(deg) => Cow::Owned(creased_normals(mesh, deg)),
        }
    }
}

/// `mesh` with smooth vertex normals that stay hard across creases.
///
/// For each corner (face `f`, vertex `v`) the normal is the area-weighted
/// sum of the normals of the faces around `v`'s *position* (so vertices
/// already split at a UV or colour seam are smoothed across it) whose unit
/// normal is within `crease_degrees` of `f`'s (`>= 180` takes them all; a
/// degenerate corner face takes them all too). Corners of one vertex with
/// the same normal share it; each further distinct normal becomes a new
/// vertex appended after the existing ones (a copy of every attribute), so
/// a mesh without creases keeps its vertex order and count. Unreferenced
/// vertices and corners with no non-degenerate face get +Z: every normal
/// written is a unit vector. Deterministic (faces in order, fixed sums).
/// Cost: O(corners × faces per vertex); memory: a few words per corner.
pub fn creased_normals(mesh: &TriMesh, crease_degrees: f32) -> TriMesh {
    let n = mesh.positions.len();
    let weld = crate::weld::weld_map(&mesh.positions, 0.0);
    let groups = weld.representative.len();
    // Incident faces of each welded position (CSR).
    let mut start = vec![0u32; groups + 1];
    for f in &mesh.faces {
        for &v in f {
            start[weld.remap[v as usize] as usize + 1] += 1;
        }
    }
    for g in 0..groups {
        start[g + 1] += start[g];
    }
    let mut fill = start.clone();
    let mut incident = vec![0u32; start[groups] as usize];
    for (fi, f) in mesh.faces.iter().enumerate() {
        for &v in f {
            let g = weld.remap[v as usize] as usize;
            incident[fill[g] as usize] = fi as u32;
            fill[g] += 1;
        }
    }
    let area: Vec<Vec3> = (0..mesh.faces.len())
        .map(|f| {
            let [a, b, c] = mesh.triangle(f);
            (b - a).cross(c - a)
        })
        .collect();
    let unit: Vec<Vec3> = area.iter().map(|a| a.normalize_or_zero()).collect();
    let cos = if crease_degrees >= 180.0 {
        -2.0
    } else {
        crease_degrees.max(0.0).to_radians().cos()
    };

    let mut out = TriMesh {
        positions: mesh.positions.clone(),
        normals: Some(vec![Vec3::Z; n]),
        colors: mesh.colors.clone(),
        uvs: mesh.uvs.clone(),
        faces: Vec::with_capacity(mesh.faces.len()),
    };
    let mut assigned = vec![false; n];
    // (vertex, normal bits) -> the output vertex that carries it.
    let mut variants: FxHashMap<(u32, [u32; 3]), u32> = FxHashMap::default();
    for (fi, f) in mesh.faces.iter().enumerate() {
        let own = unit[fi];
        let mut face = [0u32; 3];
        for (k, &v) in f.iter().enumerate() {
            let g = weld.remap[v as usize] as usize;
            let mut sum = Vec3::ZERO;
            for &o in &incident[start[g] as usize..start[g + 1] as usize] {
                let o = o as usize;
                if own == Vec3::ZERO || own.dot(unit[o]) >= cos {
                    sum += area[o];
                }
            }
            let normal = sum.try_normalize().unwrap_or(Vec3::Z);
            let normals = out.normals.as_mut().expect("set above");
            face[k] = if !assigned[v as usize] {
                assigned[v as usize] = true;
                normals[v as usize] = normal;
                variants.insert((v, normal.to_array().map(f32::to_bits)), v);
                v
            } else if normals[v as usize] == normal {
                v
            } else {
                let key = (v, normal.to_array().map(f32::to_bits));
                *variants.entry(key).or_insert_with(|| {
                    let i = out.positions.len() as u32;
                    out.positions.push(mesh.positions[v as usize]);
                    normals.push(normal);
                    if let (Some(dst), Some(src)) = (out.colors.as_mut(), mesh.colors.as_ref()) {
                        dst.push(src[v as usize]);
                    }
                    if let (Some(dst), Some(src)) = (out.uvs.as_mut(), mesh.uvs.as_ref()) {
                        dst.push(src[v as usize]);
                    }
                    i
                })
            };
        }
        out.faces.push(face);
    }
    out
}

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
    #[test]
    fn cube_keeps_hard_edges_and_sphere_stays_smooth() {
        // A unit cube with 8 shared corners: every corner touches 3 faces
        // at 90°, so at 60° each corner splits into 3 vertices (24 in all)
        // and each normal is an axis.
        let p: Vec<Vec3> = (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect();
        let q = |a: u32, b: u32, c: u32, d: u32| [[a, b, c], [a, c, d]];
        let mut faces = Vec::new();
        for quad in [
            q(0, 2, 3, 1),
            q(4, 5, 7, 6),
            q(0, 1, 5, 4),
            q(2, 6, 7, 3),
            q(0, 4, 6, 2),
            q(1, 3, 7, 5),
        ] {
            faces.extend(quad);
        }
        let cube = TriMesh::new(p, faces);
        let c = creased_normals(&cube, 60.0);
        c.validate().unwrap();
        assert_eq!(c.positions.len(), 24);
        for n in c.normals.as_ref().unwrap() {
            assert!((n.abs().max_element() - 1.0).abs() < 1e-6, "{n}");
        }
        // At 180° nothing splits and the result is the plain smooth normal.
        let s = creased_normals(&cube, 180.0);
        assert_eq!(s.positions.len(), 8);
        assert_eq!(s.normals.unwrap(), vertex_normals(&cube));
        // A finely tessellated sphere has no crease at 60°.
        let sphere = crate::shapes::icosphere(3);
        let t = creased_normals(&sphere, 60.0);
        assert_eq!(t.positions.len(), sphere.positions.len());
        assert_eq!(creased_normals(&sphere, 60.0), t, "deterministic");
    }

    #[test]
    fn modes_keep_drop_or_compute() {
        let sphere = crate::shapes::icosphere(1);
        assert_eq!(NormalsMode::default_for(&sphere), NormalsMode::Keep);
        let bare = TriMesh {
            normals: None,
            ..sphere.clone()
        };
        assert_eq!(
            NormalsMode::default_for(&bare),
            NormalsMode::Auto(DEFAULT_CREASE_DEGREES)
        );
        assert!(NormalsMode::None.apply(&sphere).normals.is_none());
        assert!(NormalsMode::Keep.apply(&bare).normals.is_none());
        assert!(NormalsMode::Auto(30.0).apply(&bare).normals.is_some());
    }

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
