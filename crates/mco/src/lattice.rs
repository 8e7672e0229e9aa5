//! The cube lattice the whole build works on: packed integer keys of
//! lattice points, the lattice itself ([`Grid`]: origin, cube size, octree
//! depth), the 8³-vertex bricks the signed-distance band is stored in, and
//! the hash map keyed by packed keys ([`KeyMap`]).
//!
//! A lattice point `(x, y, z)` (a cube vertex, or a cube by its lowest
//! corner, in units of some level's cube size) packs into one `u64` as
//! `x | y << 20 | z << 40`: every coordinate stays below 2²⁰, which
//! [`MAX_RESOLUTION`] and the octree depth guarantee.

use std::collections::HashMap;

use glam::Vec3;
use lodkit_mesh::Aabb;

use crate::{Error, Result};

/// Bits per lattice coordinate in a packed key.
pub const KEY_BITS: u32 = 20;
const KEY_MASK: u64 = (1 << KEY_BITS) - 1;

/// The finest resolution accepted (cubes along the longest axis). 4096³
/// leaf cubes is far beyond what fits in memory as a surface band of a
/// real scan; the cap keeps every lattice coordinate inside a packed key.
pub const MAX_RESOLUTION: u32 = 4096;

/// Packs lattice coordinates (each below 2²⁰) into one key.
#[inline]
pub fn pack(x: u32, y: u32, z: u32) -> u64 {
    x as u64 | (y as u64) << KEY_BITS | (z as u64) << (2 * KEY_BITS)
}

/// Inverse of [`pack`].
#[inline]
pub fn unpack(k: u64) -> [u32; 3] {
    [
        (k & KEY_MASK) as u32,
        (k >> KEY_BITS & KEY_MASK) as u32,
        (k >> (2 * KEY_BITS) & KEY_MASK) as u32,
    ]
}

/// A `HashMap` keyed by packed lattice keys, with `rustc-hash`'s
/// multiply-rotate hasher: the std SipHash is several times slower on the
/// build's hot maps and buys nothing here (keys come from geometry, not
/// from an adversary choosing hash inputs). The build only looks keys up,
/// never iterates a map, so outputs do not depend on the hasher.
pub type KeyMap<V> = HashMap<u64, V, rustc_hash::FxBuildHasher>;

/// The cube lattice a model is built on: leaf cubes of edge
/// [`Grid::cube`] from [`Grid::origin`], `2^depth` along each axis (the
/// octree root covers all of them). Made by [`Grid::new`] or
/// [`crate::grid_for`], which validate it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    pub(crate) origin: Vec3,
    /// Leaf cube edge length (object units).
    pub(crate) cube: f32,
    /// Octree depth: the root is `2^depth` leaf cubes wide.
    pub(crate) depth: u32,
    /// Requested cubes along the longest axis of the input's box.
    pub(crate) resolution: u32,
}

/// A placeholder lattice (unit cubes at the origin, depth 0), for models
/// built by hand.
impl Default for Grid {
    fn default() -> Self {
        Grid {
            origin: Vec3::ZERO,
            cube: 1.0,
            depth: 0,
            resolution: 2,
        }
    }
}

impl Grid {
    /// The lattice for data inside `bbox` (object units) with `resolution`
    /// cubes along its longest axis, plus a margin of one and a half cubes
    /// on every side so that the band around the outermost samples is
    /// complete. Errors ([`Error::Input`]): an empty or non-finite box, a
    /// box without extent, `resolution` outside `2..=`[`MAX_RESOLUTION`].
    pub fn new(bbox: Aabb, resolution: u32) -> Result<Grid> {
        if bbox.is_empty() || !bbox.min.is_finite() || !bbox.max.is_finite() {
            return Err(Error::Input("the input has no finite samples".into()));
        }
        if !(2..=MAX_RESOLUTION).contains(&resolution) {
            return Err(Error::Input(format!(
                "resolution {resolution} is outside 2..={MAX_RESOLUTION}"
            )));
        }
        let size = bbox.size();
        let longest = size.max_element();
        if longest <= 0.0 {
            return Err(Error::Input(
                "the input's bounding box has no extent".into(),
            ));
        }
        let cube = longest / resolution as f32;
        let origin = bbox.min - Vec3::splat(1.5 * cube);
        let cells = (size.max_element() / cube).ceil() as u32 + 4;
        let depth = 32 - (cells.max(2) - 1).leading_zeros();
        Ok(Grid {
            origin,
            cube,
            depth,
            resolution,
        })
    }

    /// Leaf cubes along each axis (`2^depth`).
    pub fn cells(&self) -> u32 {
        1 << self.depth
    }

    /// The lattice's lowest corner (object units).
    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    /// Leaf cube edge length (object units).
    pub fn cube(&self) -> f32 {
        self.cube
    }

    /// Octree depth: the root is `2^depth` leaf cubes wide.
    pub fn depth(&self) -> u32 {
        self.depth
    }

    /// Cubes along the longest axis of the inputs' box, as requested.
    pub fn resolution(&self) -> u32 {
        self.resolution
    }

    /// World position of lattice vertex `key` (leaf units).
    #[inline]
    pub(crate) fn position(&self, key: u64) -> Vec3 {
        let [x, y, z] = unpack(key);
        self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.cube
    }

    /// The leaf cube containing `p`, clamped into the lattice.
    #[inline]
    pub(crate) fn cell_of(&self, p: Vec3) -> [u32; 3] {
        let max = self.cells() - 1;
        let c = (p - self.origin) / self.cube;
        // `as u32` truncates, saturates and maps NaN to 0: for c ≥ 0 that is
        // the floor, and anything below 0 clamps to 0 either way (no
        // libm `floor` call on CPUs without SSE4.1's `roundps`).
        [
            (c.x as u32).min(max),
            (c.y as u32).min(max),
            (c.z as u32).min(max),
        ]
    }
}

/// Lattice vertices along each axis of a brick (`2^BRICK_BITS`).
pub const BRICK_BITS: u32 = 3;
/// Vertices per brick edge.
pub const BRICK: u32 = 1 << BRICK_BITS;
/// Vertices per brick (`BRICK³` = 512).
pub const BRICK_VOLUME: usize = 1 << (3 * BRICK_BITS);
/// `BRICK - 1`: masks a lattice coordinate to its offset inside its brick.
pub const LOCAL_MASK: u32 = BRICK - 1;

/// Index of lattice vertex `(x, y, z)` inside its brick (x fastest).
#[inline]
pub fn local_index(x: u32, y: u32, z: u32) -> usize {
    ((x & LOCAL_MASK) | (y & LOCAL_MASK) << BRICK_BITS | (z & LOCAL_MASK) << (2 * BRICK_BITS))
        as usize
}

/// Key of the brick holding lattice vertex `(x, y, z)`.
#[inline]
pub fn brick_key(x: u32, y: u32, z: u32) -> u64 {
    pack(x >> BRICK_BITS, y >> BRICK_BITS, z >> BRICK_BITS)
}

/// Leaf cubes of at least this and at most [`MAX_PLAIN_CUBE`] (object
/// units) are built as they are; outside, the build runs in a frame
/// scaled by a power of two (see [`normalising_scale`]).
const MIN_PLAIN_CUBE: f32 = 1.0 / (1u32 << 24) as f32;
/// See [`MIN_PLAIN_CUBE`].
const MAX_PLAIN_CUBE: f32 = (1u32 << 16) as f32;

/// The power of two `2^k` that brings a leaf cube of `cube` object units to
/// about `2^-8` (a unit box at resolution 256), or 1 when `cube` lies in
/// `MIN_PLAIN_CUBE..=MAX_PLAIN_CUBE`. The build's squared distances, areas
/// and tolerances overflow `f32` for cubes around 1e18 and lose their
/// meaning (subnormal) around 1e-12; scaled, every input builds in the same
/// frame and gives the same model at any scale within float precision.
/// Multiplying by a power of two is exact (no rounding), and the model is
/// mapped back exactly, so lattices of ordinary size build bit for bit as
/// they always did.
pub(crate) fn normalising_scale(cube: f32) -> f32 {
    if !(cube.is_finite() && cube > 0.0) || (MIN_PLAIN_CUBE..=MAX_PLAIN_CUBE).contains(&cube) {
        return 1.0;
    }
    let k = -8 - cube.log2().round() as i32;
    2f32.powi(k.clamp(-126, 126))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pack_round_trips() {
        for c in [[0, 0, 0], [1, 2, 3], [KEY_MASK as u32; 3]] {
            assert_eq!(unpack(pack(c[0], c[1], c[2])), c);
        }
    }

    #[test]
    fn grid_covers_the_box_with_margin() {
        let b = Aabb {
            min: Vec3::new(-1.0, 0.0, 0.0),
            max: Vec3::new(1.0, 0.5, 0.25),
        };
        let g = Grid::new(b, 20).unwrap();
        assert!((g.cube - 0.1).abs() < 1e-6);
        assert!(g.cells() >= 24);
        let [x, _, _] = g.cell_of(b.max);
        assert!(x + 1 < g.cells());
        assert!(Grid::new(b, 1).is_err());
        assert!(Grid::new(Aabb::EMPTY, 8).is_err());
    }
}
