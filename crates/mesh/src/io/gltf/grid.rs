//! A position quantisation grid shared by many GLB files (the tiles of a
//! tileset), so that a vertex at the same position in two files is stored
//! on the same grid point and dequantises to the same `f32`, bit for bit.
//! A grid per file (what [`super::GlbOptions::compress`] alone gives, and
//! what `gltfpack -cc` does) rounds a border vertex differently on each
//! side of a tile border, which shows as pinholes.
//!
//! **How the floats stay equal.** The grid's step is a power of two and
//! its origin a multiple of the step, so every grid point `origin + i ×
//! step` with `|origin / step + i| < 2^24` is an exact `f32`. Each file
//! stores its positions as `u16` offsets from its own lowest grid point
//! (so a tile needs 16 bits over its own extent, not over the whole
//! tileset's), and its node's translation is that lowest point and its
//! scale the step — both exact — so `translation + scale × q` is exact in
//! `f32` arithmetic and equal in every file that holds the point.

use glam::Vec3;

use super::write::{Builder, GlbOptions, Quantise, counts};
use crate::error::ParseError;
use crate::mesh::{Aabb, PointCloud, TriMesh};
use crate::parse_err;
use crate::scene::Scene;

/// The largest grid index magnitude (`2^24`): beyond it grid points are
/// not all exact `f32`s.
pub const MAX_GRID_INDEX: f64 = (1u64 << 24) as f64;

/// A quantisation grid for positions, shared by every file written on it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuantGrid {
    /// The grid point of index 0, in the positions' frame and units; a
    /// multiple of the step on each axis.
    pub origin: Vec3,
    /// The step is `2^step_log2` (in the positions' units).
    pub step_log2: i32,
}

impl QuantGrid {
    /// The finest grid on which `bbox` spans at most `2^bits − 1` steps
    /// on every axis: the step is the smallest power of two at or above
    /// `extent / (2^bits − 2)` (one step is kept for the origin's
    /// rounding), the origin the grid point at or below the box's minimum.
    /// `bits` is clamped to `2..=24`; so a file on it whose positions lie
    /// in the box fits 16-bit positions when `bits ≤ 16`. A box of zero
    /// extent gets a step of 1.
    pub fn covering(bbox: Aabb, bits: u32) -> QuantGrid {
        let bits = bits.clamp(2, 24);
        let extent = (bbox.max - bbox.min).max_element() as f64;
        let ideal = extent / ((1u64 << bits) - 2) as f64;
        let step_log2 = if ideal > 0.0 && ideal.is_finite() {
            (ideal.log2().ceil() as i32).clamp(-126, 127)
        } else {
            0
        };
        let step = 2f64.powi(step_log2);
        let origin = Vec3::from_array(
            bbox.min
                .to_array()
                .map(|m| ((m as f64 / step).floor() * step) as f32),
        );
        QuantGrid { origin, step_log2 }
    }

    /// The step, `2^step_log2`.
    pub fn step(&self) -> f64 {
        2f64.powi(self.step_log2)
    }

    /// The grid index of `p` (nearest grid point), in `f64`.
    pub fn index(&self, p: Vec3) -> [f64; 3] {
        let s = self.step();
        std::array::from_fn(|k| ((p[k] as f64 - self.origin[k] as f64) / s).round())
    }

    /// The grid point of index `i`, as the `f32` a client computes.
    pub fn point(&self, i: [f64; 3]) -> Vec3 {
        let s = self.step();
        Vec3::from_array(std::array::from_fn(|k| {
            (self.origin[k] as f64 + i[k] * s) as f32
        }))
    }

    /// Checks the grid (finite, normal step, origin on the grid and
    /// exact) and resolves it for one file whose positions are `sets`:
    /// the file's lowest grid point (its node translation) and the step.
    /// Errors: a bad grid, a position off the grid's exact range, or a
    /// file spanning more than 65,535 steps on an axis.
    pub(super) fn resolve<'a>(
        &self,
        sets: impl Iterator<Item = &'a [Vec3]>,
    ) -> Result<Quantise, ParseError> {
        let s = self.step();
        if !(-126..=127).contains(&self.step_log2) {
            return Err(parse_err!(
                "GLB grid: step 2^{} is not a normal f32",
                self.step_log2
            ));
        }
        let base: [f64; 3] = std::array::from_fn(|k| self.origin[k] as f64 / s);
        if base
            .iter()
            .any(|b| !b.is_finite() || b.fract() != 0.0 || b.abs() >= MAX_GRID_INDEX)
        {
            return Err(parse_err!(
                "GLB grid: origin {:?} is not a multiple of the step 2^{} within 2^24 steps",
                self.origin.to_array(),
                self.step_log2
            ));
        }
        let mut lo = [f64::INFINITY; 3];
        let mut hi = [f64::NEG_INFINITY; 3];
        for p in sets.flatten() {
            let i = self.index(*p);
            for k in 0..3 {
                lo[k] = lo[k].min(i[k]);
                hi[k] = hi[k].max(i[k]);
            }
        }
        if lo[0] > hi[0] {
            lo = [0.0; 3];
            hi = [0.0; 3];
        }
        for k in 0..3 {
            if (base[k] + lo[k]).abs() >= MAX_GRID_INDEX
                || (base[k] + hi[k]).abs() >= MAX_GRID_INDEX
            {
                return Err(parse_err!(
                    "GLB grid: positions lie more than 2^24 steps from the grid's zero on axis {k} \
                     (use a coarser grid)"
                ));
            }
            if hi[k] - lo[k] > u16::MAX as f64 {
                return Err(parse_err!(
                    "GLB grid: positions span {} grid steps on axis {k}, more than the 65,535 a \
                     16-bit position holds (use a coarser grid or a smaller tile)",
                    hi[k] - lo[k]
                ));
            }
        }
        Ok(Quantise {
            origin: self.point(lo),
            step: s as f32,
            shared: true,
        })
    }
}

fn on_grid<'a>(
    opts: &GlbOptions,
    grid: &QuantGrid,
    sets: impl Iterator<Item = &'a [Vec3]>,
) -> Result<Builder, ParseError> {
    let q = grid.resolve(sets)?;
    let mut b = Builder::new(opts, None)?;
    b.quantise = Some(q);
    Ok(b)
}

/// [`super::write_glb_with`] with positions on `grid` (a grid shared with
/// other files: see the module docs): `KHR_mesh_quantization` 16-bit
/// positions whether or not `opts.compress` is set (compressing adds
/// `EXT_meshopt_compression` and octahedral 8-bit normals, as always).
///
/// Errors: those of [`super::write_glb_with`], and those of a grid that
/// does not fit (a bad grid; a level spanning more than 65,535 steps; a
/// position over 2^24 steps from the grid's zero).
pub fn write_glb_on_grid(
    levels: &[(&str, &TriMesh)],
    opts: &GlbOptions,
    grid: &QuantGrid,
) -> Result<Vec<u8>, ParseError> {
    if levels.is_empty() {
        return Err(ParseError::new("GLB: no levels to write"));
    }
    let mut b = on_grid(
        opts,
        grid,
        levels.iter().map(|(_, m)| m.positions.as_slice()),
    )?;
    let mut nodes = Vec::new();
    for (name, m) in levels {
        let prim = b.primitive(name, m)?;
        let label = format!("{name} ({} triangles)", m.faces.len());
        nodes.push(b.node(&label, prim, counts(m))?);
    }
    b.finish(nodes, Vec::new())
}

/// [`super::write_points_glb`] with positions on `grid`, as
/// [`write_glb_on_grid`]: one `POINTS` node with POSITION (16-bit on the
/// grid), NORMAL and COLOR_0 when the cloud has them. Errors: those of
/// [`super::write_points_glb`] and of the grid.
pub fn write_points_glb_on_grid(
    name: &str,
    cloud: &PointCloud,
    opts: &GlbOptions,
    grid: &QuantGrid,
) -> Result<Vec<u8>, ParseError> {
    let mut b = on_grid(opts, grid, std::iter::once(cloud.positions.as_slice()))?;
    let prim = b.points_primitive(cloud)?;
    let mut extras = serde_json::Map::new();
    extras.insert("points".into(), cloud.positions.len().into());
    let node = b.node(name, prim, extras)?;
    b.finish(vec![node], Vec::new())
}

/// [`super::write_scene_glb_with`] with every mesh's positions on `grid`,
/// as [`write_glb_on_grid`] (materials, textures and node transforms as
/// that writes them). Errors: those of [`super::write_scene_glb_with`]
/// and of the grid.
pub fn write_scene_glb_on_grid(
    scene: &Scene,
    opts: &GlbOptions,
    grid: &QuantGrid,
) -> Result<Vec<u8>, ParseError> {
    let q = grid.resolve(scene.meshes.iter().map(|m| m.mesh.positions.as_slice()))?;
    super::materials_write::write_scene_with_quantise(scene, opts, Some(q))
}
