//! The cube lattice and the sparse band of signed distances at its vertices.
//!
//! Follows the thesis's §4.2 (after Hoppe et al. 1992): the signed distance
//! of a cube vertex `v` is its distance to the tangent plane of the closest
//! sample, `f(v) = (v − oᵢ) · nᵢ`, with `oᵢ` the sample and `nᵢ` its normal.
//!
//! Departures, and why:
//! - **Sign convention.** The thesis calls inside `+1`; here a vertex is
//!   *inside* when `f(v) < 0` (normals point outwards, the usual convention
//!   of meshes and scanners). Only the naming differs.
//! - **Sparse band, no search structure.** Each sample *stamps* the 4×4×4
//!   lattice vertices of its cube and the 26 cubes around it, and a vertex
//!   keeps the closest sample seen, so the field is a band about two cubes
//!   wide around the data (never a dense n³ grid). Stamping only the
//!   sample's own cube (8 corners) was tried first: a cube the surface
//!   merely clips often holds no sample, misses a corner and leaves a hole
//!   (half the edges of a sphere at resolution 24 were on holes). Every
//!   sample within one cube size of a vertex is a candidate — the only ones
//!   the thesis's "closest range point" can sensibly be for a vertex that
//!   marching cubes will use. Stamping needs no kd-tree and makes adding a
//!   new range image touch only the cubes around its samples (the
//!   incremental API).
//! - **Ties** (two samples at exactly the same distance) keep the sample
//!   added first, so the field does not depend on hash order and adding
//!   scans one at a time gives the same field as adding them together.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

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

/// A multiply-shift hasher for the packed integer keys (the std SipHash is
/// several times slower on the build's hot maps and buys nothing here:
/// keys come from geometry, not from an adversary choosing hash inputs).
#[derive(Default, Clone, Copy)]
pub struct KeyHasher(u64);

impl Hasher for KeyHasher {
    #[inline]
    fn finish(&self) -> u64 {
        self.0
    }
    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.write_u64(b as u64);
        }
    }
    #[inline]
    fn write_u64(&mut self, k: u64) {
        self.0 = (self.0 ^ k)
            .wrapping_mul(0x9E37_79B9_7F4A_7C15)
            .rotate_left(29);
    }
}

/// A `HashMap` keyed by packed lattice keys.
pub type KeyMap<V> = HashMap<u64, V, BuildHasherDefault<KeyHasher>>;

/// The cube lattice: leaf cubes of edge `cube` from `origin`, `2^depth`
/// along each axis (the octree root covers all of them).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    pub origin: Vec3,
    /// Leaf cube edge length (object units).
    pub cube: f32,
    /// Octree depth: the root is `2^depth` leaf cubes wide.
    pub depth: u32,
    /// Requested cubes along the longest axis of the input's box.
    pub resolution: u32,
}

impl Grid {
    /// The lattice for data inside `bbox` with `resolution` cubes along its
    /// longest axis, plus a margin of one and a half cubes on every side so
    /// that the band around the outermost samples is complete.
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

    /// World position of lattice vertex `key` (leaf units).
    #[inline]
    pub fn position(&self, key: u64) -> Vec3 {
        let [x, y, z] = unpack(key);
        self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.cube
    }

    /// The leaf cube containing `p`, clamped into the lattice.
    #[inline]
    pub fn cell_of(&self, p: Vec3) -> [u32; 3] {
        let max = (self.cells() - 1) as f32;
        let c = ((p - self.origin) / self.cube).floor();
        [
            c.x.clamp(0.0, max) as u32,
            c.y.clamp(0.0, max) as u32,
            c.z.clamp(0.0, max) as u32,
        ]
    }
}

/// Oriented samples: positions with unit normals, optional colours.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Samples {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub colors: Option<Vec<[u8; 4]>>,
}

impl Samples {
    pub fn len(&self) -> usize {
        self.positions.len()
    }
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
    pub fn bbox(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
    /// Appends `o`'s samples (colours kept only if both have them).
    pub fn append(&mut self, o: &Samples) {
        let had = !self.positions.is_empty();
        self.colors = match (self.colors.take(), &o.colors) {
            (Some(mut a), Some(b)) => {
                a.extend_from_slice(b);
                Some(a)
            }
            (None, Some(b)) if !had => Some(b.clone()),
            _ => None,
        };
        self.positions.extend_from_slice(&o.positions);
        self.normals.extend_from_slice(&o.normals);
    }
}

/// One lattice vertex of the band: its closest sample's data.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FieldVertex {
    /// Squared distance to the closest sample (selection key).
    pub dist2: f32,
    /// Signed distance to that sample's tangent plane (negative = inside).
    pub distance: f32,
    /// The closest sample's normal.
    pub normal: Vec3,
    /// The closest sample's colour (opaque grey without colours).
    pub color: [u8; 4],
}

/// Largest offset along the tangent plane, in cubes, for a band vertex to
/// be defined when the rule is on (see [`SignedDistanceField::get`]). The
/// default cube is twice the sample spacing, so on continuous data some
/// sample is always within half a cube tangentially; 1.5 leaves room for
/// irregular sampling. Measured on the bunny from its 10 real scans: the
/// symmetric mean error drops from 0.178 mm to 0.124 mm (spurious sheets
/// past the scans' edges are gone). On closed meshes the rule opens holes
/// at thin features (the closed bunny: 52 boundary edges instead of 14 at
/// full resolution), so mesh inputs build without it.
pub const TANGENTIAL_LIMIT: f32 = 1.5;

/// Neutral colour for inputs without colours.
pub const NO_COLOR: [u8; 4] = [200, 200, 200, 255];

/// The sparse signed-distance band.
#[derive(Debug, Clone)]
pub struct SignedDistanceField {
    pub grid: Grid,
    pub values: KeyMap<FieldVertex>,
    /// Hoppe's tangential rule in object units (`f32::INFINITY` = off).
    pub tangential_limit: f32,
}

impl SignedDistanceField {
    pub fn new(grid: Grid) -> Self {
        SignedDistanceField {
            grid,
            values: KeyMap::default(),
            tangential_limit: f32::INFINITY,
        }
    }

    /// Stamps `samples` into the band; returns the keys of the lattice
    /// vertices whose value changed (sorted, unique). Samples outside the
    /// lattice are clamped into its border cubes. Non-finite samples are
    /// skipped.
    pub fn add(&mut self, samples: &Samples) -> Vec<u64> {
        let mut changed = Vec::new();
        let g = self.grid;
        for (i, (&p, &n)) in samples.positions.iter().zip(&samples.normals).enumerate() {
            if !p.is_finite() || !n.is_finite() {
                continue;
            }
            let color = samples.colors.as_ref().map_or(NO_COLOR, |c| c[i]);
            let [cx, cy, cz] = g.cell_of(p);
            // The 4×4×4 vertices of the sample's cube and its 26 neighbours.
            for corner in 0..64u32 {
                let (dx, dy, dz) = (corner & 3, corner >> 2 & 3, corner >> 4);
                if cx + dx < 1 || cy + dy < 1 || cz + dz < 1 {
                    continue;
                }
                let key = pack(cx + dx - 1, cy + dy - 1, cz + dz - 1);
                let v = g.position(key);
                let d2 = v.distance_squared(p);
                let fv = FieldVertex {
                    dist2: d2,
                    distance: (v - p).dot(n),
                    normal: n,
                    color,
                };
                match self.values.entry(key) {
                    std::collections::hash_map::Entry::Vacant(e) => {
                        e.insert(fv);
                        changed.push(key);
                    }
                    std::collections::hash_map::Entry::Occupied(mut e) => {
                        if d2 < e.get().dist2 {
                            e.insert(fv);
                            changed.push(key);
                        }
                    }
                }
            }
        }
        changed.sort_unstable();
        changed.dedup();
        changed
    }

    /// The value of lattice vertex `key`, if it is defined: in the band,
    /// and (when the rule is on, for scan data) its closest sample's tangent
    /// plane is a fair estimate there — Hoppe et al.'s rule: the vertex's offset *along* the tangent plane
    /// from the sample is at most [`TANGENTIAL_LIMIT`] cubes. Beyond that
    /// the vertex is beside the data (past a scan's edge, or across a thin
    /// feature) rather than above or below it, and its sign is a guess
    /// that would draw a spurious sheet.
    #[inline]
    pub fn get(&self, key: u64) -> Option<&FieldVertex> {
        let v = self.values.get(&key)?;
        let limit = self.tangential_limit;
        (limit == f32::INFINITY || v.dist2 - v.distance * v.distance <= limit * limit).then_some(v)
    }

    /// Number of lattice vertices in the band.
    pub fn len(&self) -> usize {
        self.values.len()
    }
    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }
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

    #[test]
    fn plane_samples_give_signed_distances_to_the_plane() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let g = Grid::new(b, 10).unwrap();
        let mut s = Samples::default();
        for i in 0..30 {
            for j in 0..30 {
                s.positions
                    .push(Vec3::new(i as f32 / 29.0, j as f32 / 29.0, 0.53));
                s.normals.push(Vec3::Z);
            }
        }
        let mut f = SignedDistanceField::new(g);
        let changed = f.add(&s);
        assert_eq!(changed.len(), f.len());
        for (&k, v) in &f.values {
            let p = g.position(k);
            assert!((v.distance - (p.z - 0.53)).abs() < 1e-5);
        }
        // Adding the same samples again changes nothing.
        assert!(f.add(&s).is_empty());
    }
}
