//! One mesh cut into tiles by a face → tile map, each tile compact, with
//! the tile-border edges that are cuts (edges the source mesh continues
//! across into another tile) listed for the skirts.

use std::collections::HashMap;

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::weld::weld_map;

/// Face sides per edge of `mesh`, its vertices first welded by position
/// (bitwise), so attribute seams are not borders: `(remap, counts)`, the
/// counts keyed by the welded ends, smaller first.
pub fn welded_edges(mesh: &TriMesh) -> (Vec<u32>, HashMap<(u32, u32), u32>) {
    let remap = weld_map(&mesh.positions, 0.0).remap;
    let mut counts = HashMap::with_capacity(mesh.faces.len() * 3 / 2);
    for tri in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (remap[tri[k] as usize], remap[tri[(k + 1) % 3] as usize]);
            *counts.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    (remap, counts)
}

/// The border edges of `mesh` (one face side, vertices welded by
/// position), in the direction their face walks them.
pub fn border_edges(mesh: &TriMesh) -> Vec<[u32; 2]> {
    let (remap, counts) = welded_edges(mesh);
    let mut out = Vec::new();
    for tri in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let (x, y) = (remap[a as usize], remap[b as usize]);
            if counts.get(&(x.min(y), x.max(y))) == Some(&1) {
                out.push([a, b]);
            }
        }
    }
    out
}

/// A tile's mesh and its cut edges (local indices, in the direction its
/// face walks them, so the face lies on their left seen from outside).
#[derive(Clone, Debug, Default)]
pub struct TileMesh {
    /// The tile's triangles (compact: every vertex used).
    pub mesh: TriMesh,
    /// Border edges of the tile that are interior edges of the source.
    pub cuts: Vec<[u32; 2]>,
    /// The group (material) of each vertex, when the source has groups
    /// (empty otherwise).
    pub groups: Vec<u32>,
}

/// Splits `source` into `slots` tiles: face `f` goes to `slot_of(f)`
/// (`None`: dropped). Vertex order within a tile is first use by face
/// order, so the result is a function of the inputs alone. Cost: `O(F log
/// F)` (the edge table), one copy of the source. `groups` (one per
/// source vertex, or empty) are carried to the tiles' vertices.
pub fn split(
    source: &TriMesh,
    groups: &[u32],
    slots: usize,
    slot_of: impl Fn(usize) -> Option<usize>,
) -> Vec<TileMesh> {
    let (remap, edges) = welded_edges(source);
    let interior = |a: u32, b: u32| {
        let (a, b) = (remap[a as usize], remap[b as usize]);
        edges.get(&(a.min(b), a.max(b))).is_some_and(|&c| c >= 2)
    };
    let mut faces_of: Vec<Vec<u32>> = vec![Vec::new(); slots];
    for f in 0..source.faces.len() {
        if let Some(s) = slot_of(f) {
            faces_of[s].push(f as u32);
        }
    }
    let mut local = vec![u32::MAX; source.positions.len()];
    faces_of
        .into_iter()
        .map(|faces| {
            let mut used: Vec<u32> = Vec::new();
            let mut out_faces = Vec::with_capacity(faces.len());
            for &f in &faces {
                let tri = source.faces[f as usize].map(|v| {
                    if local[v as usize] == u32::MAX {
                        local[v as usize] = used.len() as u32;
                        used.push(v);
                    }
                    local[v as usize]
                });
                out_faces.push(tri);
            }
            let pick3 = |a: &Vec<Vec3>| used.iter().map(|&v| a[v as usize]).collect::<Vec<_>>();
            let mesh = TriMesh {
                positions: pick3(&source.positions),
                normals: source.normals.as_ref().map(pick3),
                colors: source
                    .colors
                    .as_ref()
                    .map(|c| used.iter().map(|&v| c[v as usize]).collect()),
                uvs: source
                    .uvs
                    .as_ref()
                    .map(|u| used.iter().map(|&v| u[v as usize]).collect()),
                faces: out_faces,
            };
            // Cuts: tile border edges (one face side in the tile) that the
            // source has two or more face sides on.
            let cuts = border_edges(&mesh)
                .into_iter()
                .filter(|&[a, b]| interior(used[a as usize], used[b as usize]))
                .collect();
            for &v in &used {
                local[v as usize] = u32::MAX;
            }
            let groups = if groups.is_empty() {
                Vec::new()
            } else {
                used.iter().map(|&v| groups[v as usize]).collect()
            };
            TileMesh { mesh, cuts, groups }
        })
        .collect()
}

/// The position bits of an edge's ends, in either direction: how a cut is
/// found again after the tile is re-simplified with its border locked.
pub fn edge_bits(mesh: &TriMesh, [a, b]: [u32; 2]) -> ([u32; 3], [u32; 3]) {
    let bits = |v: u32| mesh.positions[v as usize].to_array().map(f32::to_bits);
    let (x, y) = (bits(a), bits(b));
    (x.min(y), x.max(y))
}
