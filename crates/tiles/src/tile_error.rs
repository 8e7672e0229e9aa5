//! Each internal tile's measured error: how far what a client draws when
//! it shows the tile is from the input the tile stands for, both ways.
//!
//! A tile `T` of depth `k` (cell `C`) replaces its subtree. The error of
//! drawing it is the larger of
//! - `T → S`: how far the tile's surface is from the reference surface
//!   `S` (the input, or a finer level that stands for it up to that
//!   level's own error), and
//! - `R → L`: how far the reference in the cell (`R`, faces of `S` whose
//!   centroid lies in `C`) is from level `k` (`L`: the depth-`k` tiles,
//!   and the level's faces in the cells of leaves at or above depth `k`,
//!   which stand where a client shows those leaves).
//!
//! Where a client shows neighbours of different levels, the sliver
//! between their borders is the skirts' business (`skirts.rs`), not the
//! error's: the error says how far each level is from the input.
//!
//! Measuring `R` against `T` alone (the cell's input against the cell's
//! tile) counts every piece of input whose simplified faces moved into a
//! neighbouring cell (a face belongs to the cell of its centroid, and a
//! coarse face's centroid may lie across the cell wall from much of the
//! input it covers): the measure then grows with the size of the level's
//! faces at the cell walls, not with their distance from the input, and
//! on smooth scans, where a level's faces are large and close, reads one
//! to two orders of magnitude over the true distance. So both sides are
//! taken near the cell: `S` and `L` restricted to the faces whose
//! centroid lies in `C` grown by [`MARGIN`] of its side on every side.
//! A restricted surface can only be farther from a point than the whole
//! one, so the result is an upper bound of the distances to the whole
//! input and the whole level (honest), and equal to them wherever those
//! are under the margin.
//!
//! Samples: [`level_samples`] of the tile's faces per kind, in each
//! direction (as `Reference::compare_level`). Cost per tile: two
//! distance hierarchies (over `S` and `L` near the cell, about
//! `(1 + 2 × MARGIN)²` times the cell's own faces on a surface) and
//! the samples' closest-point queries.

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::{CompareOptions, SurfaceIndex, level_samples, one_sided};

use crate::Result;
use crate::octree_partition::{CellKey, Grid};

/// How far (a fraction of the cell's side) the neighbourhood a tile is
/// measured in reaches past its cell's walls.
pub const MARGIN: f64 = 1.0 / 8.0;

/// The cells of depth `depth` whose cube grown by [`MARGIN`] of its side
/// holds `p`: its own cell first, then up to seven neighbours (a point
/// near a wall, an edge or a corner), in a fixed order.
pub fn cells_near(grid: &Grid, p: Vec3, depth: u8) -> impl Iterator<Item = CellKey> {
    let n = 1u64 << depth;
    let rel = (p.as_dvec3() - grid.origin) / grid.size * n as f64;
    // Per axis: the own cell, then the neighbour across a near wall.
    let axis = |v: f64| -> [Option<u32>; 2] {
        let c = (v.floor().max(0.0) as u64).min(n - 1);
        let f = v - c as f64;
        let other = if f < MARGIN && c > 0 {
            Some(c - 1)
        } else if f > 1.0 - MARGIN && c + 1 < n {
            Some(c + 1)
        } else {
            None
        };
        [Some(c as u32), other.map(|o| o as u32)]
    };
    let (x, y, z) = (axis(rel.x), axis(rel.y), axis(rel.z));
    (0..8usize).filter_map(move |i| {
        Some(CellKey {
            depth,
            xyz: [x[i & 1]?, y[(i >> 1) & 1]?, z[(i >> 2) & 1]?],
        })
    })
}

/// Per slot (a cell of depth `depth`; `slot_of` maps a cell to its slot or
/// `None`): the faces of `mesh` whose centroid lies in the cell (`own`)
/// and those whose centroid lies in it grown by [`MARGIN`] (`near`), in
/// face order. Cost: `O(F)`, 4 bytes per listed face.
pub fn faces_near(
    mesh: &TriMesh,
    grid: &Grid,
    depth: u8,
    slots: usize,
    slot_of: impl Fn(CellKey) -> Option<usize>,
) -> (Vec<Vec<u32>>, Vec<Vec<u32>>) {
    let mut own = vec![Vec::new(); slots];
    let mut near = vec![Vec::new(); slots];
    for f in 0..mesh.faces.len() {
        let c = crate::octree_partition::centroid(mesh, f);
        for (i, key) in cells_near(grid, c, depth).enumerate() {
            if let Some(s) = slot_of(key) {
                if i == 0 {
                    own[s].push(f as u32);
                }
                near[s].push(f as u32);
            }
        }
    }
    (own, near)
}

/// The faces `faces` of `mesh` as a mesh of their own (positions only,
/// vertices in first-use order).
pub fn gather(mesh: &TriMesh, faces: &[u32]) -> TriMesh {
    let mut local = std::collections::HashMap::with_capacity(faces.len());
    let mut out = TriMesh::default();
    out.faces.reserve(faces.len());
    for &f in faces {
        let tri = mesh.faces[f as usize].map(|v| {
            *local.entry(v).or_insert_with(|| {
                out.positions.push(mesh.positions[v as usize]);
                (out.positions.len() - 1) as u32
            })
        });
        out.faces.push(tri);
    }
    out
}

/// `mesh` restricted to the faces whose centroid lies in `cell` grown by
/// [`MARGIN`] (positions only, vertices in first-use order). Cost: one
/// pass over `mesh`.
pub fn crop_near(mesh: &TriMesh, grid: &Grid, cell: CellKey) -> TriMesh {
    let side = grid.side(cell.depth);
    let lo = grid.corner(cell);
    let (lo, hi) = (lo - side * MARGIN, lo + side * (1.0 + MARGIN));
    let mut local = vec![u32::MAX; mesh.positions.len()];
    let mut out = TriMesh::default();
    for f in 0..mesh.faces.len() {
        let c = crate::octree_partition::centroid(mesh, f).as_dvec3();
        if c.cmplt(lo).any() || c.cmpgt(hi).any() {
            continue;
        }
        let tri = mesh.faces[f].map(|v| {
            if local[v as usize] == u32::MAX {
                local[v as usize] = out.positions.len() as u32;
                out.positions.push(mesh.positions[v as usize]);
            }
            local[v as usize]
        });
        out.faces.push(tri);
    }
    out
}

/// The error of drawing `tile` (see the module docs): the larger of
/// `tile → reference_near` and `region → drawn_near`, each the maximum
/// over the samples (object units). An empty `region` or `tile` side
/// counts 0; an empty surface to measure against, while there is
/// something to measure, is infinitely far.
pub fn measure(
    tile: &TriMesh,
    region: &TriMesh,
    reference_near: &TriMesh,
    drawn_near: &TriMesh,
) -> Result<f64> {
    let opts = CompareOptions {
        samples: Some(level_samples(tile.faces.len())),
        ..CompareOptions::default()
    };
    let one_way = |sampled: &TriMesh, target: &TriMesh| -> Result<f64> {
        if sampled.faces.is_empty() {
            return Ok(0.0);
        }
        if target.faces.is_empty() {
            return Ok(f64::INFINITY);
        }
        let index = SurfaceIndex::new(target)?;
        let st = one_sided(sampled, &index, &opts)?;
        if std::env::var_os("LODKIT_DEBUG_ERR").is_some() && st.max > 1e-3 {
            eprintln!(
                "DEBUG {} faces vs {} faces: max {} at {:?} mean {}",
                sampled.faces.len(),
                target.faces.len(),
                st.max,
                st.max_at,
                st.mean
            );
        }
        Ok(st.max)
    };
    Ok(one_way(tile, reference_near)?.max(one_way(region, drawn_near)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn a_point_near_a_corner_is_near_eight_cells() {
        let grid = Grid {
            origin: DVec3::ZERO,
            size: 4.0,
        };
        // Depth 2: cells of side 1. The centre of cell (1,1,1) is near none.
        let mid: Vec<_> = cells_near(&grid, Vec3::splat(1.5), 2).collect();
        assert_eq!(mid.len(), 1);
        assert_eq!(mid[0].xyz, [1, 1, 1]);
        // Just inside the corner shared by (1,1,1) and (2,2,2).
        let corner: Vec<_> = cells_near(&grid, Vec3::splat(1.95), 2).collect();
        assert_eq!(corner.len(), 8);
        assert_eq!(corner[0].xyz, [1, 1, 1]);
        assert!(corner.iter().any(|k| k.xyz == [2, 2, 2]));
        // The grid's outer walls have no neighbour.
        assert_eq!(cells_near(&grid, Vec3::splat(0.01), 2).count(), 1);
        assert_eq!(cells_near(&grid, Vec3::splat(3.99), 2).count(), 1);
    }
}
