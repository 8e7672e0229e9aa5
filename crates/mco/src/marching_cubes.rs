//! Marching cubes with edge ratios (thesis §4.2, Fig. 4.1) over the sparse
//! signed-distance band: the leaf level of the octree.
//!
//! A leaf cube is one whose 8 corners all lie in the band and whose signs
//! differ. A triangle vertex sits on a crossing edge `v0 → v1` at the ratio
//! `t = |d0| / (|d0| + |d1|)` from `v0` (the thesis's proportional point)
//! instead of Lorensen and Cline's midpoint. Normals and colours are
//! interpolated with the same ratio (normals renormalised), so per-vertex
//! colours of the samples are carried to the mesh.
//!
//! Each crossing edge gets one vertex, shared by the up to 4 cubes around
//! it, and the table's face rule ([`crate::marching_cubes_cases`]) makes neighbouring
//! cubes agree on every shared face: the leaf mesh is watertight wherever
//! the band is complete.

use glam::Vec3;

use crate::lattice::{BRICK, BRICK_BITS, Grid, KeyMap, pack, unpack};
use crate::marching_cubes_cases::{EDGES, TABLE};
use crate::signed_distance::SignedDistanceField;

/// Where a crossing edge's vertex sits, from `v0`: `|d0| / (|d0| + |d1|)`.
/// Both zero (never for a crossing edge) gives the midpoint.
#[inline]
pub fn edge_ratio(d0: f32, d1: f32) -> f32 {
    let (a, b) = (d0.abs(), d1.abs());
    if a + b > 0.0 { a / (a + b) } else { 0.5 }
}

/// Every vertex of every level: positions, normals and colours, built once.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct VertexBuffer {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub colors: Vec<[u8; 4]>,
}

impl VertexBuffer {
    pub fn len(&self) -> usize {
        self.positions.len()
    }
    /// Appends a vertex, returning its index.
    pub fn push(&mut self, p: Vec3, n: Vec3, c: [u8; 4]) -> u32 {
        self.positions.push(p);
        self.normals.push(n);
        self.colors.push(c);
        (self.positions.len() - 1) as u32
    }
}

/// A lattice vertex as the octree sees it at some level: its side, and the
/// band vertex whose sample's normal and colour it carries (itself, or the
/// one Fig. 5.2's rule picked). The side comes from the band's bit masks
/// ([`BandSigns`]); the normal and colour are looked up only where a vertex
/// is made ([`blend`]), so most corners cost no read of the band's slots.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Corner {
    pub inside: bool,
    /// Lattice key of the band vertex that gives the attributes.
    pub at: u64,
}

/// The sides of the band's defined vertices, from per-brick bit masks
/// ([`SignedDistanceField::brick_masks`]): 192 bytes a brick instead of the
/// 6 KB of its slots, so the octree's corner lookups stay in cache.
#[derive(Debug, Clone)]
pub struct BandSigns {
    masks: Vec<BrickMasks>,
}

impl BandSigns {
    pub fn new(field: &SignedDistanceField) -> Self {
        BandSigns {
            masks: (0..field.brick_count())
                .map(|b| field.brick_masks(b))
                .collect(),
        }
    }

    /// From every brick's masks, in brick order.
    pub fn from_masks(masks: Vec<BrickMasks>) -> Self {
        BandSigns { masks }
    }

    /// The corner of lattice vertex `v` if it is defined
    /// ([`SignedDistanceField::slot_defined`]).
    #[inline]
    pub fn corner(&self, field: &SignedDistanceField, v: u64) -> Option<Corner> {
        let [x, y, z] = unpack(v);
        let b = field.brick_of(x, y, z)?;
        let m = &self.masks[b];
        let (w, bit) = (
            (z & (BRICK - 1)) as usize,
            (x & (BRICK - 1)) | (y & (BRICK - 1)) << 3,
        );
        (m[0][w] >> bit & 1 == 1).then(|| Corner {
            inside: m[1][w] >> bit & 1 == 1,
            at: v,
        })
    }
}

/// Linear blend of two corners' normals and colours at `t` from `a`.
pub fn blend(field: &SignedDistanceField, a: &Corner, b: &Corner, t: f32) -> (Vec3, [u8; 4]) {
    let attributes = |c: &Corner| {
        let s = field.slot(c.at).expect("a corner's band vertex is defined");
        (field.sample_normal(s.sample), field.sample_color(s.sample))
    };
    blend_attributes(attributes(a), attributes(b), t)
}

/// Linear blend of two (normal, colour) pairs at `t` from `a`, the normal
/// renormalised.
pub fn blend_attributes(a: (Vec3, [u8; 4]), b: (Vec3, [u8; 4]), t: f32) -> (Vec3, [u8; 4]) {
    let n = a.0.lerp(b.0, t);
    let n = if n.length_squared() > 1e-12 {
        n.normalize()
    } else {
        a.0
    };
    // Equal colours blend to themselves (`a + 0 · t`, rounded, is `a` for
    // finite `t`): skips four roundings, the common case.
    let c = if a.1 == b.1 && t.is_finite() {
        a.1
    } else {
        std::array::from_fn(|i| (a.1[i] as f32 + (b.1[i] as f32 - a.1[i] as f32) * t).round() as u8)
    };
    (n, c)
}

/// Key of the lattice edge from vertex `v` (leaf units) along `axis`.
#[inline]
pub fn edge_key(v: u64, axis: u8) -> u64 {
    v << 2 | axis as u64
}

/// Lattice key of corner `c` of the cube at `cube` (level units) at
/// `level` (cube size `2^level` leaf cubes), in leaf units.
#[inline]
pub fn corner_key(cube: [u32; 3], level: u32, c: u8) -> u64 {
    pack(
        (cube[0] + (c & 1) as u32) << level,
        (cube[1] + (c >> 1 & 1) as u32) << level,
        (cube[2] + (c >> 2 & 1) as u32) << level,
    )
}

/// The configuration of leaf cube `cube` (bit v = corner v inside), or
/// `None` if a corner is missing from the band. Null configurations (0,
/// 255) are returned too; callers skip them.
#[cfg(test)]
pub fn leaf_config(field: &SignedDistanceField, cube: [u32; 3]) -> Option<u8> {
    let [x, y, z] = cube;
    leaf_config_in(field, field.brick_of(x, y, z)?, cube)
}

/// [`leaf_config`] for a cube whose lowest corner lies in brick `b`: the
/// corners in that brick are read directly, the others (cubes on the
/// brick's high faces) through at most one lookup per neighbour brick.
pub fn leaf_config_in(field: &SignedDistanceField, b: usize, cube: [u32; 3]) -> Option<u8> {
    let [x, y, z] = cube;
    let m = BRICK - 1;
    // Which axes step out of the brick at the high corners.
    let out = ((x & m == m) as usize) | ((y & m == m) as usize) << 1 | ((z & m == m) as usize) << 2;
    if out == 0 {
        // All 8 corners in brick `b` (two cubes in three).
        let mut cfg = 0u8;
        for c in 0..8u32 {
            let s = field.slot_in(b, x + (c & 1), y + (c >> 1 & 1), z + (c >> 2));
            if !field.slot_defined(&s) {
                return None;
            }
            cfg |= ((s.distance < 0.0) as u8) << c;
        }
        return Some(cfg);
    }
    let mut bricks = [None; 8];
    bricks[0] = Some(b);
    let mut cfg = 0u8;
    for c in 0..8u32 {
        let (dx, dy, dz) = (c & 1, c >> 1 & 1, c >> 2);
        let (vx, vy, vz) = (x + dx, y + dy, z + dz);
        let nb = c as usize & out;
        let vb = match bricks[nb] {
            Some(vb) => vb,
            None => {
                let vb = field.brick_of(vx, vy, vz)?;
                bricks[nb] = Some(vb);
                vb
            }
        };
        let s = field.slot_in(vb, vx, vy, vz);
        if !field.slot_defined(&s) {
            return None;
        }
        cfg |= ((s.distance < 0.0) as u8) << c;
    }
    Some(cfg)
}

/// Per brick (by number): its vertices' masks from
/// [`SignedDistanceField::brick_masks`] (defined, inside, reached).
pub type BrickMasks = [[u64; BRICK as usize]; 3];

/// Bits of a brick slice word (`x + 8y`) with `x = 0`, and with `y = 0`.
const COLUMN_0: u64 = 0x0101_0101_0101_0101;
const ROW_0: u64 = 0xFF;

/// The configurations of every leaf cube whose lowest corner lies in
/// brick `b`, into `out` (one byte per cube, [`crate::lattice::local_index`]
/// order; 0 where the cube has no surface or a corner outside the band),
/// from the masks of all bricks: 64 cubes (a brick slice) at a time in bit
/// operations, then one configuration byte per surface cube. The same
/// configurations as [`leaf_config_in`] cube by cube.
///
/// Returns the number of cubes (inside the lattice) with a corner some
/// sample reached — on a field filled by one add, the cubes
/// [`crate::pipeline::IncrementalBuilder::add`] would recompute — and the
/// number of surface cubes.
pub fn brick_configs(
    field: &SignedDistanceField,
    masks: &[BrickMasks],
    b: usize,
    out: &mut [u8],
) -> (usize, usize) {
    const N: usize = BRICK as usize;
    let [bx, by, bz] = field.brick_coords(b);
    // The brick and its 7 neighbours on the high sides (`o = ox | oy << 1
    // | oz << 2`); a missing one has no defined vertex.
    let none: BrickMasks = [[0; N]; 3];
    let near: [&BrickMasks; 8] = std::array::from_fn(|o| {
        let (ox, oy, oz) = (o as u32 & 1, o as u32 >> 1 & 1, o as u32 >> 2);
        if o == 0 {
            return &masks[b];
        }
        field
            .brick_of(
                (bx + ox) << BRICK_BITS,
                (by + oy) << BRICK_BITS,
                (bz + oz) << BRICK_BITS,
            )
            .map_or(&none, |nb| &masks[nb])
    });
    // Corner `c`'s bits at each cube of slice `z`: the vertex at `+dx, +dy,
    // +dz`, taken from the neighbours past the brick's high faces.
    let shifted = |which: usize, c: usize, z: usize| -> u64 {
        let (dx, dy, dz) = (c & 1, c >> 1 & 1, c >> 2);
        let (zz, oz) = if z + dz == N { (0, 4) } else { (z + dz, 0) };
        let w = |o: usize| near[o | oz][which][zz];
        let sx = |lo: u64, hi: u64| {
            if dx == 1 {
                (lo >> 1 & !(COLUMN_0 << 7)) | (hi & COLUMN_0) << 7
            } else {
                lo
            }
        };
        let row = sx(w(0), w(1));
        if dy == 1 {
            row >> 8 | (sx(w(2), w(3)) & ROW_0) << 56
        } else {
            row
        }
    };
    // Cubes past the lattice's last cell do not exist.
    let cells = field.grid.cells();
    let base = [bx << BRICK_BITS, by << BRICK_BITS, bz << BRICK_BITS];
    let mut valid_xy = 0u64;
    for ly in 0..N as u32 {
        for lx in 0..N as u32 {
            if base[0] + lx < cells && base[1] + ly < cells {
                valid_xy |= 1 << (lx + 8 * ly);
            }
        }
    }
    let (mut touched, mut surface) = (0usize, 0usize);
    for z in 0..N {
        if base[2] + z as u32 >= cells {
            break;
        }
        let mut all_defined = valid_xy;
        let mut any_reached = 0u64;
        let mut any_inside = 0u64;
        let mut all_inside = !0u64;
        let mut inside = [0u64; 8];
        for (c, ins) in inside.iter_mut().enumerate() {
            let d = shifted(0, c, z);
            *ins = shifted(1, c, z);
            all_defined &= d;
            any_reached |= shifted(2, c, z);
            any_inside |= *ins;
            all_inside &= *ins;
        }
        touched += (any_reached & valid_xy).count_ones() as usize;
        let mut m = all_defined & any_inside & !all_inside;
        surface += m.count_ones() as usize;
        while m != 0 {
            let bit = m.trailing_zeros();
            m &= m - 1;
            let cfg = (0..8).fold(0u8, |cfg, c| cfg | ((inside[c] >> bit & 1) as u8) << c);
            out[z * 64 + bit as usize] = cfg;
        }
    }
    (touched, surface)
}

/// All leaf cubes with a surface crossing: `(cube key, configuration)`,
/// sorted by key. Only cubes touching the band are examined.
#[cfg(test)]
pub fn leaf_cubes(field: &SignedDistanceField) -> Vec<(u64, u8)> {
    let cells = field.grid.cells();
    let mut out = Vec::new();
    for b in 0..field.brick_count() {
        let [bx, by, bz] = field.brick_coords(b).map(|c| c << BRICK_BITS);
        for z in bz..bz + BRICK {
            for y in by..by + BRICK {
                for x in bx..bx + BRICK {
                    if x >= cells || y >= cells || z >= cells {
                        continue;
                    }
                    if let Some(cfg) = leaf_config(field, [x, y, z])
                        && cfg != 0
                        && cfg != 255
                    {
                        out.push((pack(x, y, z), cfg));
                    }
                }
            }
        }
    }
    out.sort_unstable_by_key(|l| l.0);
    out
}

/// Creates (or finds) the vertex of every crossing edge of the given leaf
/// cubes, in cube order then edge order (so vertex numbering is
/// deterministic). Returns the edge → vertex map.
#[cfg(test)]
pub fn leaf_vertices(
    field: &SignedDistanceField,
    cubes: &[(u64, u8)],
    vb: &mut VertexBuffer,
) -> KeyMap<u32> {
    leaf_vertices_by_cube(field, cubes, vb).0
}

/// A cube's vertex per cube edge ([`NO_VERTEX`] where the edge does not
/// cross the surface): what [`node_triangles`] maps the table through.
pub type CubeEdges = [u32; 12];

/// Marks a cube edge without a crossing in [`CubeEdges`].
pub const NO_VERTEX: u32 = u32::MAX;

/// [`leaf_vertices`], also returning each cube's [`CubeEdges`] (so the
/// cubes' triangles need no map lookups).
pub fn leaf_vertices_by_cube(
    field: &SignedDistanceField,
    cubes: &[(u64, u8)],
    vb: &mut VertexBuffer,
) -> (KeyMap<u32>, Vec<CubeEdges>) {
    let g: Grid = field.grid;
    let mut by_cube = Vec::with_capacity(cubes.len());
    // About 1.3 distinct crossing edges per surface cube (each edge is
    // shared by up to 4 cubes): reserve once instead of rehashing.
    let expect = cubes.len() * 3 / 2;
    let mut edges: KeyMap<u32> = KeyMap::with_capacity_and_hasher(expect, Default::default());
    vb.positions.reserve(expect);
    vb.normals.reserve(expect);
    vb.colors.reserve(expect);
    // Cubes in key order (z slab after z slab) share an edge only within
    // the two slabs around it: the edges are found in two small maps, those
    // whose lower vertex is on the current slab's bottom plane and on its
    // top plane, which stay in cache (one map over all edges was a cache
    // miss per lookup). The whole map is filled once, from the new edges.
    let sorted = cubes.is_sorted_by_key(|c| c.0);
    let mut planes: [KeyMap<u32>; 2] = Default::default();
    let mut new_edges: Vec<(u64, u32)> = Vec::with_capacity(if sorted { expect } else { 0 });
    let mut slab = u32::MAX;
    for &(k, cfg) in cubes {
        let cube = unpack(k);
        if sorted && cube[2] != slab {
            if slab != u32::MAX && cube[2] == slab + 1 {
                planes.swap(0, 1);
                planes[1].clear();
            } else {
                planes[0].clear();
                planes[1].clear();
            }
            slab = cube[2];
        }
        let mut ce = [NO_VERTEX; 12];
        for (e, [a, b]) in EDGES.iter().enumerate() {
            if (cfg >> a & 1) == (cfg >> b & 1) {
                continue;
            }
            let (ka, kb) = (corner_key(cube, 0, *a), corner_key(cube, 0, *b));
            let key = edge_key(ka, (e / 4) as u8);
            let map = if sorted {
                &mut planes[(a >> 2) as usize]
            } else {
                &mut edges
            };
            ce[e] = *map.entry(key).or_insert_with(|| {
                let fa = field
                    .slot(ka)
                    .expect("a leaf cube's corners are in the band");
                let fb = field
                    .slot(kb)
                    .expect("a leaf cube's corners are in the band");
                let t = edge_ratio(fa.distance, fb.distance);
                let p = g.position(ka).lerp(g.position(kb), t);
                let (n, c) = blend_attributes(
                    (
                        field.sample_normal(fa.sample),
                        field.sample_color(fa.sample),
                    ),
                    (
                        field.sample_normal(fb.sample),
                        field.sample_color(fb.sample),
                    ),
                    t,
                );
                let id = vb.push(p, n, c);
                if sorted {
                    new_edges.push((key, id));
                }
                id
            });
        }
        by_cube.push(ce);
    }
    edges.extend(new_edges);
    (edges, by_cube)
}

/// Triangles of a cube of configuration `cfg` whose edge vertices are
/// `edges`: the table's edge triples mapped to vertices.
#[inline]
pub fn node_triangles(cfg: u8, edges: &CubeEdges, out: &mut Vec<u32>) {
    for t in TABLE.triangles(cfg) {
        for &e in t {
            debug_assert_ne!(
                edges[e as usize], NO_VERTEX,
                "the table uses crossing edges only"
            );
            out.push(edges[e as usize]);
        }
    }
}

/// Triangles of one cube: the table's edge triples mapped to vertices.
#[cfg(test)]
pub fn cube_triangles(
    cube: [u32; 3],
    level: u32,
    cfg: u8,
    edges: &KeyMap<u32>,
    out: &mut Vec<u32>,
) {
    for t in TABLE.triangles(cfg) {
        for &e in t {
            let [a, _] = EDGES[e as usize];
            out.push(edges[&edge_key(corner_key(cube, level, a), e / 4)]);
        }
    }
}

/// Plain (single-level) marching cubes over the band: the full-resolution
/// mesh, as positions/normals/colours and triangles.
#[cfg(test)]
pub fn march(field: &SignedDistanceField) -> (VertexBuffer, Vec<[u32; 3]>) {
    let cubes = leaf_cubes(field);
    let mut vb = VertexBuffer::default();
    let edges = leaf_vertices(field, &cubes, &mut vb);
    let mut idx = Vec::new();
    for &(k, cfg) in &cubes {
        cube_triangles(unpack(k), 0, cfg, &edges, &mut idx);
    }
    let tris = idx.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    (vb, tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::signed_distance::FieldVertex;
    use rand_xoshiro::Xoshiro256PlusPlus;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};
    use std::collections::HashMap;

    fn rng(seed: &mut Xoshiro256PlusPlus) -> f32 {
        (seed.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }

    /// A field defined on a whole `n³` vertex block from a closure.
    fn block_field(n: u32, f: impl Fn(u32, u32, u32) -> f32) -> SignedDistanceField {
        let b = lodkit_mesh::Aabb {
            min: Vec3::ZERO,
            max: Vec3::splat(n as f32),
        };
        let mut field = SignedDistanceField::new(Grid::new(b, n).unwrap());
        for x in 0..n {
            for y in 0..n {
                for z in 0..n {
                    field.set(
                        pack(x, y, z),
                        FieldVertex {
                            dist2: 0.0,
                            distance: f(x, y, z),
                            normal: Vec3::Z,
                            color: [10, 20, 30, 255],
                        },
                    );
                }
            }
        }
        field
    }

    /// Every edge strictly inside the block is used once in each direction.
    fn assert_watertight(
        vb: &VertexBuffer,
        tris: &[[u32; 3]],
        field: &SignedDistanceField,
        n: u32,
    ) {
        let g = field.grid;
        let lo = g.origin + Vec3::splat(g.cube * 1e-3);
        let hi = g.origin + Vec3::splat(g.cube * ((n - 1) as f32 - 1e-3));
        let on_border = |p: Vec3| (0..3).any(|i| p[i] < lo[i] || p[i] > hi[i]);
        let mut count: HashMap<(u32, u32), i32> = HashMap::new();
        for t in tris {
            for i in 0..3 {
                *count.entry((t[i], t[(i + 1) % 3])).or_default() += 1;
            }
        }
        for (&(a, b), &c) in &count {
            if on_border(vb.positions[a as usize]) && on_border(vb.positions[b as usize]) {
                continue;
            }
            assert_eq!(c, 1, "edge {a}->{b} used {c} times");
            assert_eq!(
                count.get(&(b, a)),
                Some(&1),
                "edge {a}->{b} has no twin (a hole)"
            );
        }
    }

    #[test]
    fn random_fields_are_watertight() {
        let mut seed = Xoshiro256PlusPlus::seed_from_u64(0x1234_5678_9abc_def1);
        for _ in 0..20 {
            let vals: Vec<f32> = (0..8 * 8 * 8).map(|_| rng(&mut seed) - 0.5).collect();
            let field = block_field(8, |x, y, z| vals[(x * 64 + y * 8 + z) as usize]);
            let (vb, tris) = march(&field);
            assert!(!tris.is_empty());
            assert_watertight(&vb, &tris, &field, 8);
        }
    }

    #[test]
    fn sphere_vertices_lie_on_the_sphere_and_normals_point_out() {
        let c = Vec3::splat(6.0);
        let field = block_field(13, |x, y, z| {
            Vec3::new(x as f32, y as f32, z as f32).distance(c) - 4.3
        });
        let (vb, tris) = march(&field);
        let g = field.grid;
        let center = g.origin + c * g.cube;
        for p in &vb.positions {
            // Linear interpolation of an exact distance field: within a few
            // per cent of a cube.
            assert!(((p.distance(center) / g.cube) - 4.3).abs() < 0.05);
        }
        for t in &tris {
            let [a, b, cc] = t.map(|i| vb.positions[i as usize]);
            let n = (b - a).cross(cc - a);
            assert!(n.dot((a + b + cc) / 3.0 - center) > 0.0, "inward triangle");
        }
        assert_watertight(&vb, &tris, &field, 13);
    }

    #[test]
    fn brick_configs_equal_cube_by_cube_configs() {
        let mut seed = Xoshiro256PlusPlus::seed_from_u64(0x51f1_5eed_0d15_ea5e);
        let mut s = lodkit_mesh::PointCloud::default();
        for _ in 0..4000 {
            let p = Vec3::new(rng(&mut seed), rng(&mut seed), rng(&mut seed));
            let n = Vec3::new(
                rng(&mut seed) - 0.5,
                rng(&mut seed) - 0.5,
                rng(&mut seed) - 0.5,
            );
            s.positions.push(p);
            s.normals
                .get_or_insert_default()
                .push(n.normalize_or(Vec3::Z));
        }
        // Resolution 20: the lattice's last cells end inside a brick; with
        // and without the tangential rule (defined ≠ reached).
        for limit in [f32::INFINITY, 0.05] {
            let mut field = SignedDistanceField::new(Grid::new(s.bbox(), 20).unwrap());
            field.tangential_limit = limit;
            field.add(&s);
            let cells = field.grid.cells();
            let masks: Vec<BrickMasks> = (0..field.brick_count())
                .map(|b| field.brick_masks(b))
                .collect();
            let (mut touched, mut surface) = (0, 0);
            for b in 0..field.brick_count() {
                let mut out = [0u8; crate::lattice::BRICK_VOLUME];
                let (t, n) = brick_configs(&field, &masks, b, &mut out);
                touched += t;
                surface += n;
                let base = field.brick_coords(b).map(|c| c << BRICK_BITS);
                let mut expect_touched = 0;
                for (li, &got) in out.iter().enumerate() {
                    let li = li as u32;
                    let cube = [
                        base[0] + (li & 7),
                        base[1] + (li >> 3 & 7),
                        base[2] + (li >> 6),
                    ];
                    if cube.iter().any(|&c| c >= cells) {
                        assert_eq!(got, 0);
                        continue;
                    }
                    let expect = match leaf_config_in(&field, b, cube) {
                        Some(cfg) if cfg != 0 && cfg != 255 => cfg,
                        _ => 0,
                    };
                    assert_eq!(got, expect, "cube {cube:?}");
                    let reached = (0..8u32).any(|c| {
                        let v = [
                            cube[0] + (c & 1),
                            cube[1] + (c >> 1 & 1),
                            cube[2] + (c >> 2),
                        ];
                        field
                            .brick_of(v[0], v[1], v[2])
                            .is_some_and(|vb| !field.slot_in(vb, v[0], v[1], v[2]).is_empty())
                    });
                    expect_touched += reached as usize;
                }
                assert_eq!(t, expect_touched);
            }
            assert!(surface > 100 && touched > surface, "{surface} {touched}");
        }
    }

    #[test]
    fn edge_ratio_is_proportional() {
        assert_eq!(edge_ratio(-1.0, 3.0), 0.25);
        assert_eq!(edge_ratio(0.0, 0.0), 0.5);
        assert_eq!(edge_ratio(2.0, -2.0), 0.5);
    }
}
