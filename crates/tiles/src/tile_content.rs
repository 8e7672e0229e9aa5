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
use lodkit_mesh::io::gltf::{
    GlbOptions, MAX_GRID_INDEX, QuantGrid, write_glb_on_grid, write_points_glb_on_grid,
};
use lodkit_mesh::{Aabb, PointCloud, TriMesh};

use crate::{Error, Result};

/// The grid of the tiles at `depth` of a tileset whose content lies in
/// `bounds`: `15 + depth` bits over the whole box, so a tile (about
/// `2^-depth` of it, with room to spare for skirts and vertices that
/// simplification moved past its cell) spans at most `2^16 − 1` steps of
/// its own, and each level keeps a finer grid than the one above it (at
/// most 24 bits: an `f32`'s). A small object far from the origin (a
/// box narrower than its coordinates' `f32` precision at that many bits)
/// gets the finest grid whose points are all exact `f32`s there instead:
/// its coordinates, divided by the step, stay under `2^24`.
pub fn depth_grid(bounds: &Aabb, depth: u8) -> QuantGrid {
    let mut grid = QuantGrid::covering(*bounds, 15 + u32::from(depth).min(9));
    let far = bounds.min.abs().max(bounds.max.abs()).max_element() as f64;
    while grid.step_log2 < 127 && far / 2f64.powi(grid.step_log2) >= MAX_GRID_INDEX - 2.0 {
        grid.step_log2 += 1;
        let step = 2f64.powi(grid.step_log2);
        grid.origin = Vec3::from_array(
            bounds
                .min
                .to_array()
                .map(|m| ((f64::from(m) / step).floor() * step) as f32),
        );
    }
    grid
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_small_object_far_from_the_origin_gets_an_exact_grid() {
        let mut mesh = lodkit_mesh::shapes::icosphere(2);
        for p in &mut mesh.positions {
            *p = *p * 0.001 + Vec3::splat(100.0);
        }
        mesh.normals = Some(lodkit_mesh::normals::vertex_normals(&mesh));
        let grid = depth_grid(&mesh.bbox(), 0);
        assert!(100.0 / 2f64.powi(grid.step_log2) < MAX_GRID_INDEX);
        let glb = encode_tile("far", &mesh, false, &grid).unwrap();
        let back = lodkit_mesh::io::decode(lodkit_mesh::io::Format::Glb, &glb, None).unwrap();
        let lodkit_mesh::Model::Mesh(back) = back else {
            panic!("a mesh")
        };
        assert_eq!(back.faces.len(), mesh.faces.len());
        // An ordinary box keeps the grid it always had.
        let unit = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        assert_eq!(depth_grid(&unit, 3), QuantGrid::covering(unit, 18));
    }
}
