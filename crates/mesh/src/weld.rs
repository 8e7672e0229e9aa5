//! Welding of duplicate positions.
//!
//! Formats without shared vertices (STL, "triangle soup" OBJ/glTF exports)
//! store each corner separately; every topology-based algorithm in lodkit
//! (vertex rings, boundary loops, edge collapse) needs them merged first.
//!
//! The merge is deterministic: vertices are visited in index order and each
//! joins the lowest-indexed earlier representative within the tolerance, so
//! the result depends only on the input, never on hashing order.

use glam::Vec3;
use rustc_hash::FxHashMap;

use crate::mesh::TriMesh;

/// Result of [`weld_map`]: `remap[old] = new`, `representative[new] = old`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct WeldMap {
    /// Per input vertex: its welded vertex.
    pub remap: Vec<u32>,
    /// Per welded vertex: the input vertex it keeps (the group's first).
    pub representative: Vec<u32>,
}

/// Groups positions closer than `tolerance` (Euclidean; `0.0` = bitwise
/// equal coordinates, with `-0.0 == 0.0`). Runs in expected O(n) with a
/// hash grid of cell size `tolerance`.
pub fn weld_map(positions: &[Vec3], tolerance: f32) -> WeldMap {
    let mut remap = Vec::with_capacity(positions.len());
    let mut representative: Vec<u32> = Vec::new();
    if tolerance <= 0.0 {
        let mut seen: FxHashMap<[u32; 3], u32> =
            FxHashMap::with_capacity_and_hasher(positions.len(), Default::default());
        for (i, p) in positions.iter().enumerate() {
            let key = [canon(p.x), canon(p.y), canon(p.z)];
            let next = representative.len() as u32;
            let id = *seen.entry(key).or_insert(next);
            if id == next {
                representative.push(i as u32);
            }
            remap.push(id);
        }
    } else {
        let inv = 1.0 / tolerance;
        let cell = |p: Vec3| ((p * inv).floor()).as_ivec3();
        let mut grid: FxHashMap<glam::IVec3, Vec<u32>> = FxHashMap::default();
        let t2 = tolerance * tolerance;
        for (i, p) in positions.iter().enumerate() {
            let c = cell(*p);
            let mut found: Option<u32> = None;
            for dz in -1..=1 {
                for dy in -1..=1 {
                    for dx in -1..=1 {
                        if let Some(list) = grid.get(&(c + glam::IVec3::new(dx, dy, dz))) {
                            for &r in list {
                                let rp = positions[representative[r as usize] as usize];
                                if rp.distance_squared(*p) <= t2 && found.is_none_or(|f| r < f) {
                                    found = Some(r);
                                }
                            }
                        }
                    }
                }
            }
            let id = match found {
                Some(r) => r,
                None => {
                    let r = representative.len() as u32;
                    representative.push(i as u32);
                    grid.entry(c).or_default().push(r);
                    r
                }
            };
            remap.push(id);
        }
    }
    WeldMap {
        remap,
        representative,
    }
}

fn canon(x: f32) -> u32 {
    if x == 0.0 { 0 } else { x.to_bits() }
}

/// Merges vertices closer than `tolerance`, keeping each group's first
/// vertex (and its attributes), and drops faces that become degenerate
/// (two corners merged). Returns the welded mesh and the number of faces
/// dropped.
pub fn weld(mesh: &TriMesh, tolerance: f32) -> (TriMesh, usize) {
    let map = weld_map(&mesh.positions, tolerance);
    let pick = |i: &u32| *i as usize;
    let out_positions: Vec<Vec3> = map
        .representative
        .iter()
        .map(|&i| mesh.positions[pick(&i)])
        .collect();
    let mut faces = Vec::with_capacity(mesh.faces.len());
    for f in &mesh.faces {
        let g = f.map(|v| map.remap[v as usize]);
        if g[0] != g[1] && g[1] != g[2] && g[0] != g[2] {
            faces.push(g);
        }
    }
    let dropped = mesh.faces.len() - faces.len();
    let gather = |v: &Vec<_>| map.representative.iter().map(|&i| v[i as usize]).collect();
    let out = TriMesh {
        positions: out_positions,
        normals: mesh.normals.as_ref().map(gather),
        colors: mesh
            .colors
            .as_ref()
            .map(|c| map.representative.iter().map(|&i| c[i as usize]).collect()),
        uvs: mesh
            .uvs
            .as_ref()
            .map(|u| map.representative.iter().map(|&i| u[i as usize]).collect()),
        faces,
    };
    (out, dropped)
}

/// Counts positions that duplicate an earlier one exactly.
pub fn duplicate_positions(positions: &[Vec3]) -> usize {
    positions.len() - weld_map(positions, 0.0).representative.len()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn soup() -> TriMesh {
        // Two triangles of a unit quad, stored as six separate corners.
        let p = [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 0.0, -0.0),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        TriMesh::new(p.to_vec(), vec![[0, 1, 2], [3, 4, 5]])
    }

    #[test]
    fn exact_weld_merges_shared_corners_and_signed_zero() {
        let (m, dropped) = weld(&soup(), 0.0);
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(dropped, 0);
        assert_eq!(duplicate_positions(&soup().positions), 2);
    }

    #[test]
    fn tolerance_weld_merges_near_points_and_drops_collapsed_faces() {
        let mut m = soup();
        m.positions[3] = Vec3::new(1e-4, 0.0, 0.0);
        m.positions.push(Vec3::new(0.0, 1.0 + 5e-5, 0.0));
        m.faces.push([5, 6, 0]); // collapses: 5 and 6 merge
        let (w, dropped) = weld(&m, 1e-3);
        assert_eq!(w.positions.len(), 4);
        assert_eq!(dropped, 1);
        assert_eq!(w.faces.len(), 2);
        // Far-apart points never merge.
        let (w2, _) = weld(&m, 1e-6);
        assert_eq!(w2.positions.len(), 6);
    }
}
