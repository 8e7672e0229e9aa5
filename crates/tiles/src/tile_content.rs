//! A tile's glTF content (GLB bytes), its positions on the quantisation
//! grid of its depth.
//!
//! Neighbouring tiles of one depth are cut from one mesh and share their
//! border vertices; quantised on a grid of their own (as `gltfpack -cc`
//! does per file) those vertices round differently on each side, which
//! both 3D Tiles clients show as pinholes. Every tile of a depth is
//! written on one [`QuantGrid`] ([`depth_grid`]), so a border vertex
//! dequantises to the same `f32` in every tile that holds it.

use lodkit_mesh::glam::Vec3;
use lodkit_mesh::io::gltf::{GlbOptions, QuantGrid, write_glb_on_grid, write_points_glb_on_grid};
use lodkit_mesh::{Aabb, PointCloud, TriMesh};

use crate::{Error, Result};

/// The grid of the tiles at `depth` of a tileset whose content lies in
/// `bounds`: `15 + depth` bits over the whole box, so a tile (about
/// `2^-depth` of it, with room to spare for skirts and vertices that
/// simplification moved past its cell) spans at most `2^16 − 1` steps of
/// its own, and each level keeps a finer grid than the one above it (at
/// most 24 bits: an `f32`'s).
pub fn depth_grid(bounds: &Aabb, depth: u8) -> QuantGrid {
    QuantGrid::covering(*bounds, 15 + u32::from(depth).min(9))
}

/// The farthest [`depth_grid`] moves a point: half a step along each
/// axis, `step · √3 / 2` (object units).
pub fn rounding(grid: &QuantGrid) -> f64 {
    2f64.powi(grid.step_log2) * 3f64.sqrt() / 2.0
}

/// Adds each tile's rounding to its `geometricError` (a tile is at least
/// that far from what it stands for, full-resolution leaves included) and
/// to its bounding box (half a step each way: a rounded vertex may leave
/// the box of the unrounded ones). `info[0].bbox` must already hold every
/// tile's content; `depth` gives a node's depth. Errors and boxes stay
/// nested (a coarser depth rounds more).
pub fn add_rounding(info: &mut [crate::tileset_json::NodeInfo], depth: impl Fn(usize) -> u8) {
    let bounds = info.first().map_or(Aabb::EMPTY, |i| i.bbox);
    for (i, node) in info.iter_mut().enumerate() {
        let grid = depth_grid(&bounds, depth(i));
        node.error = node.error.max(rounding(&grid));
        if node.bbox.min.x <= node.bbox.max.x {
            let half = Vec3::splat(2f32.powi(grid.step_log2 - 1));
            node.bbox = Aabb {
                min: node.bbox.min - half,
                max: node.bbox.max + half,
            };
        }
    }
}

/// Encodes one tile's mesh (y-up, object units, with normals) as a GLB
/// named `name`, positions on `grid` (`compress`: meshoptimizer codecs
/// too).
///
/// Errors: the writer's (an invalid mesh, a tile the grid cannot hold,
/// `compress` without the `meshopt` feature), naming the tile.
pub fn encode_tile(
    name: &str,
    mesh: &TriMesh,
    compress: bool,
    grid: &QuantGrid,
) -> Result<Vec<u8>> {
    write_glb_on_grid(&[(name, mesh)], &GlbOptions { compress }, grid)
        .map_err(|e| Error::Encode(format!("tile {name}: {e}")))
}

/// [`encode_tile`] for a tile of points (glTF `POINTS`, colours and
/// normals kept).
pub fn encode_point_tile(
    name: &str,
    cloud: &PointCloud,
    compress: bool,
    grid: &QuantGrid,
) -> Result<Vec<u8>> {
    write_points_glb_on_grid(name, cloud, &GlbOptions { compress }, grid)
        .map_err(|e| Error::Encode(format!("tile {name}: {e}")))
}
