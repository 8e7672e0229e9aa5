//! Direct triangulation of an octree surface — §6.1, §6.2 and §6.3 of
//! Yemez & Schmitt.
//!
//! **Surface scanning (§6.1.1).** The paper fetches the 3×3×3 window of
//! parents around every parent cube with an ON child and lays their
//! children out in a 6×6×6 array. Departure, for speed: the window is a
//! brick of 8×8×8 cubes (the Morton-sorted cubes of one aligned block,
//! kept as bit sets, with the vertex index of a cube being its brick's
//! first index plus the ON cubes before it), widened by two cubes on every
//! side: 27 look-ups fetch 512 cubes' worth of neighbourhoods instead of 8,
//! the configuration of a neighbourhood is four row reads, and no hash
//! lookup, allocation or per-cube index array is needed. Each occupied
//! brick triangulates the neighbourhoods whose origin (lowest cube) lies in
//! it, plus those whose origin lies in an empty brick below when it is the
//! first occupied brick, in child-code order, the neighbourhood reaches —
//! the paper's back-neighbour rule, made unique. The window supplies the
//! overlapping neighbourhoods the disambiguation needs.
//!
//! **Construction rules (§6.1.3).** `C_1–C_3` give their triangle.
//! `C_4, C_5` pick the diagonal with the smaller dihedral angle, or, when
//! the particles carry normals, the one whose triangles agree best with
//! them. A planar configuration lying on a face of its neighbourhood has
//! one owner: the neighbourhood that sees it on its lower face, unless the
//! neighbourhood across that face is a solid (`C_6+`) configuration, whose
//! disc then covers the face alone. (The paper leaves this implicit;
//! without it every flat patch would be emitted twice, and a patch shared
//! with an ambiguous neighbourhood covered twice — on the bunny this rule
//! took the triangles on over-used edges from 17 % to 0.9 %.) Identical
//! triangles two solids both build on a shared face are kept once.
//!
//! **Disambiguation (§6.2).** For `C_i, i ≥ 6`, the edges of `G_i` that
//! also belong to the graph of an overlapping neighbourhood are collected;
//! if they form one Hamiltonian cycle through every ON cube, the cycle cuts
//! the hull into two discs and the one with the smaller mean dihedral angle
//! is emitted. Otherwise all of `T_i` is emitted: hole-free, non-manifold.
//! Departure: when the shared edges hold exactly one Hamiltonian cycle plus
//! edges inside one of its discs, each in the graphs of two or more
//! neighbours, the other disc is emitted — its interior edges are nobody
//! else's, and the neighbours keep the ones it leaves (see
//! `split_by_cycle`; on the bunny at R = 7 this resolves a quarter of
//! the ambiguous neighbourhoods the paper's test leaves whole, with no new
//! boundary edge). When an edge inside one disc is in one neighbour's
//! graph only, that disc is the first choice (leaving the edge would
//! risk a hole).
//!
//! **Settling (departure).** The §6.2 choice is local: a disc's interior
//! edge can still be a neighbour's rim edge (three triangles on it), and a
//! hull left whole is non-manifold by construction. So the ambiguous
//! solids — those left whole, those with a first choice on trial, and the
//! resolved ones of every class but `C_6` — are built last: each takes the
//! subset of its hull triangles that best fits what the rest of the level
//! built (no hull edge used once, every cube in a triangle, fewest surplus
//! edge uses), in scan order, two sweeps (`settle`). The whole hull is
//! always a candidate, so this opens no hole. Resolved `C_6`s (≈ 15 % of
//! neighbourhoods) are built at once: settling them too changed nothing on
//! the bunny or the armadillo and cost 8× the triangulation time. On the
//! armadillo at R = 7 (outer thinning, relaxed below 5) this took the
//! non-manifold triangles of the thinned levels from 8.1 / 5.7 / 2.9 % to
//! 0.5 / 0.2 / 0.1 % and those of the relaxed levels from 70–99 % to
//! under 1 %, with the same boundary edges on every level.
//!
//! **Decimation (§6.3, optional).** A triangle with an edge shorter than a
//! fraction of the cube size is not built and its two cubes are merged
//! (positions and colours averaged). Departure: a cube merges at most once
//! per level, so merges pair cubes instead of chaining across the surface;
//! a short edge whose cubes are already taken is kept.
//!
//! **Orientation** (not in the paper, which renders without culling):
//! [`crate::orientation`], when [`TriangulateOptions::orient`] asks.
use std::borrow::Cow;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::OnceLock;
use std::time::Instant;

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::topology::UnionFind;

use crate::decode::LevelSurface;
use crate::octree::{MortonMap, morton, unmorton};
use crate::triangulation_table::{CLASS_COUNT, Compact, Shape, Table, corner, pair, table};

/// Options of [`triangulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangulateOptions {
    /// §6.3: skip triangles with an edge shorter than this fraction of the
    /// level's cube size and merge the two cubes. `None`: no decimation.
    pub decimate: Option<f32>,
    /// Orient the triangles (see the module docs).
    pub orient: bool,
}

impl TriangulateOptions {
    /// No decimation, oriented.
    pub const DEFAULT: TriangulateOptions = TriangulateOptions {
        decimate: None,
        orient: true,
    };
}

impl Default for TriangulateOptions {
    fn default() -> Self {
        TriangulateOptions::DEFAULT
    }
}

/// Table 1's triangulation columns for one level.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct TriangulationStats {
    pub triangles: usize,
    /// Neighbourhoods of each class `C_1..C_17` (index 0 unused).
    pub configurations: Vec<u64>,
    /// Ambiguous neighbourhoods resolved by a unique Hamiltonian cycle.
    pub disambiguated: u64,
    /// Ambiguous neighbourhoods triangulated whole (the non-manifold local
    /// triangulations of Table 1).
    pub fallbacks: u64,
    pub seconds: f64,
}

impl TriangulationStats {
    /// Percentages of `C_1–3`, `C_4–5`, `C_6`, `C_>6` (Table 1).
    pub fn distribution(&self) -> [f64; 4] {
        let total: u64 = self.configurations.iter().sum();
        let t = total.max(1) as f64;
        let sum =
            |a: usize, b: usize| self.configurations[a..=b].iter().sum::<u64>() as f64 * 100.0 / t;
        [sum(1, 3), sum(4, 5), sum(6, 6), sum(7, CLASS_COUNT)]
    }
}

/// A triangulated level.
#[derive(Debug, Clone)]
pub struct Triangulation {
    pub mesh: TriMesh,
    pub stats: TriangulationStats,
}

const NONE: u32 = u32::MAX;

/// Bricks are 8×8×8 cubes of the level (`BRICK_BITS` per axis).
const BRICK_BITS: u32 = 3;
/// Dense brick grids up to this many bricks per axis (R ≤ 10), a hash map
/// above.
const DENSE_BRICKS: i64 = 128;
/// Extended window coordinate `E ∈ 0..12` (local `E − 2 ∈ −2..10`): the
/// brick it falls in (0: below, 1: this one, 2: above) and its local
/// coordinate there.
const EXT_BRICK: [usize; 12] = [0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2];
const EXT_LOCAL: [usize; 12] = [6, 7, 0, 1, 2, 3, 4, 5, 6, 7, 0, 1];
/// Extended window side.
const EXT: usize = 12;

/// The ON cubes of one brick, as bits in two orders.
#[derive(Clone, Copy)]
struct Brick {
    /// Linear order: word `z`, bit `8y + x`.
    lin: [u64; 8],
    /// Morton order of the local coordinates (eq. 1 within the brick),
    /// which is the order of the level's cubes.
    mor: [u64; 8],
    /// Vertex index of the first cube of each Morton word.
    base: [u32; 8],
}

/// An empty brick, for the empty places of a window.
static EMPTY_BRICK: Brick = Brick {
    lin: [0; 8],
    mor: [0; 8],
    base: [0; 8],
};

/// Brick coordinates → brick number.
struct BrickIndex {
    /// Bricks per axis.
    side: i64,
    dense: Vec<u32>,
    sparse: MortonMap<u32>,
}

impl BrickIndex {
    fn new(level: u8, keys: &[u64]) -> BrickIndex {
        // A u64 Morton code holds 21 bits per axis: no deeper level has cubes.
        let side = ((1i64 << level.min(21)) + (1 << BRICK_BITS) - 1) >> BRICK_BITS;
        let mut ix = BrickIndex {
            side,
            dense: Vec::new(),
            sparse: MortonMap::default(),
        };
        if side <= DENSE_BRICKS {
            ix.dense = vec![NONE; (side * side * side) as usize];
            for (i, &k) in keys.iter().enumerate() {
                let b = unmorton(k);
                ix.dense[(b[0] as i64 + side * (b[1] as i64 + side * b[2] as i64)) as usize] =
                    i as u32;
            }
        } else {
            ix.sparse.reserve(keys.len());
            for (i, &k) in keys.iter().enumerate() {
                ix.sparse.insert(k, i as u32);
            }
        }
        ix
    }

    #[inline]
    fn get(&self, b: [i64; 3]) -> u32 {
        // One unsigned compare per axis rejects both sides of the grid.
        let side = self.side as u64;
        if b[0] as u64 >= side || b[1] as u64 >= side || b[2] as u64 >= side {
            return NONE;
        }
        if self.dense.is_empty() {
            let m = morton([b[0] as u32, b[1] as u32, b[2] as u32]);
            self.sparse.get(&m).copied().unwrap_or(NONE)
        } else {
            self.dense[(b[0] + self.side * (b[1] + self.side * b[2])) as usize]
        }
    }
}

/// The ON cubes of a brick and two layers around it, as rows of bits:
/// `rows[Y + 12 Z]` bit `X` is the cube at local `(X − 2, Y − 2, Z − 2)`.
/// Neighbourhood origins lie at local `−1..8` (`1..10` extended); the rest
/// is the vicinity §6.1.1 keeps for the disambiguation.
struct Window<'a> {
    rows: [u16; EXT * EXT],
    /// The 27 bricks around (3×3×3, x fastest), NONE where empty.
    bricks: [u32; 27],
    /// The same bricks, [`EMPTY_BRICK`] where empty (read without a
    /// branch).
    around: [&'a Brick; 27],
    /// Vertex index of each ON cube a neighbourhood of the window's brick
    /// can have as a corner (extended coordinates `1..=10` per axis, x
    /// fastest; [`Window::fill_ids`]), stale elsewhere; a power of two long
    /// so that a masked index needs no bounds check.
    ids: [u32; IDS],
}

/// The four low bytes of `x` in the four 16-bit parts of a word.
#[inline]
fn spread_bytes(x: u64) -> u64 {
    let x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
    (x | (x << 8)) & 0x00ff_00ff_00ff_00ff
}

/// The scan's groups of four origin rows: first extended `y`, and a one
/// in the low bit of each row (16 bits) that is an origin row (`1..=9`).
const ROW_GROUPS: [(usize, u64); 3] = [
    (1, 0x0001_0001_0001_0001),
    (5, 0x0001_0001_0001_0001),
    (9, 1),
];

/// Length of [`Window::ids`].
const IDS: usize = 2048;

/// Extended index offset of each corner of a neighbourhood.
const CORNER_OFFSET: [usize; 8] = [
    0,
    1,
    EXT,
    EXT + 1,
    EXT * EXT,
    EXT * EXT + 1,
    EXT * EXT + EXT,
    EXT * EXT + EXT + 1,
];

/// The `(window brick, Morton word)` pairs, window brick `b` (3×3×3, x
/// fastest) other than the centre, holding cubes a neighbourhood of the
/// centre brick can reach: the top layer (local 7) of a brick below and
/// the bottom layer (local 0) of a brick above, per axis; with those
/// cubes' bits.
const REACHED: [(u8, u8, u64); 56] = {
    let mut t = [(0u8, 0u8, 0u64); 56];
    let mut n = 0;
    let mut b = 0;
    while b < 27 {
        let pos = [b % 3, (b / 3) % 3, b / 9];
        let mut w = 0;
        while b != 13 && w < 8 {
            let mut bits = 0u64;
            let mut i = 0;
            while i < 64 {
                let k = w * 64 + i;
                let l = [
                    (k & 1) | ((k >> 2) & 2) | ((k >> 4) & 4),
                    ((k >> 1) & 1) | ((k >> 3) & 2) | ((k >> 5) & 4),
                    ((k >> 2) & 1) | ((k >> 4) & 2) | ((k >> 6) & 4),
                ];
                let mut ok = true;
                let mut a = 0;
                while a < 3 {
                    ok &= match pos[a] {
                        0 => l[a] == 7,
                        1 => true,
                        _ => l[a] == 0,
                    };
                    a += 1;
                }
                if ok {
                    bits |= 1 << i;
                }
                i += 1;
            }
            if bits != 0 {
                t[n] = (b as u8, w as u8, bits);
                n += 1;
            }
            w += 1;
        }
        b += 1;
    }
    assert!(n == 56);
    t
};

/// Extended index offset of window brick `b`'s cubes from the centre
/// brick's (wrapping: negative below).
const BRICK_OFFSET: [usize; 27] = {
    let mut t = [0usize; 27];
    let mut b = 0;
    while b < 27 {
        let d = (b % 3) as isize - 1
            + EXT as isize * (((b / 3) % 3) as isize - 1)
            + (EXT * EXT) as isize * ((b / 9) as isize - 1);
        t[b] = (8 * d) as usize;
        b += 1;
    }
    t
};

impl Window<'_> {
    /// Configuration of the neighbourhood with origin `o` (extended
    /// coordinates, each in `0..10`).
    #[inline]
    fn mask(&self, o: [usize; 3]) -> u8 {
        let row = |y: usize, z: usize| ((self.rows[y + EXT * z] >> o[0]) & 3) as u8;
        row(o[1], o[2])
            | (row(o[1] + 1, o[2]) << 2)
            | (row(o[1], o[2] + 1) << 4)
            | (row(o[1] + 1, o[2] + 1) << 6)
    }

    /// Rows `i..i + 4` (four consecutive `y` of one `z`), 16 bits each,
    /// first lowest.
    #[inline]
    fn rows4(&self, i: usize) -> u64 {
        let r: &[u16; 4] = self.rows[i..i + 4].try_into().expect("four rows");
        u64::from(r[0])
            | (u64::from(r[1]) << 16)
            | (u64::from(r[2]) << 32)
            | (u64::from(r[3]) << 48)
    }

    /// Sets rows `i..i + 4` to the four 16-bit parts of `rows`, first
    /// lowest.
    #[inline]
    fn set_rows4(&mut self, i: usize, rows: u64) {
        let four = [
            rows as u16,
            (rows >> 16) as u16,
            (rows >> 32) as u16,
            (rows >> 48) as u16,
        ];
        self.rows[i..i + 4].copy_from_slice(&four);
    }

    /// The 4×4×4 cubes from `o − 1` to `o + 2` (extended coordinates), bit
    /// `x + 16y + 4z`: everything the 27 neighbourhoods around `o` see.
    /// (That order makes the four rows of a `z` one read and one mask.)
    #[inline]
    fn block(&self, o: [usize; 3]) -> u64 {
        let mut b = 0u64;
        for dz in 0..4 {
            let rows = self.rows4(o[1] - 1 + EXT * (o[2] - 1 + dz)) >> (o[0] - 1);
            b |= (rows & 0x000f_000f_000f_000f) << (4 * dz);
        }
        b
    }

    /// Fills [`Window::ids`]. The level's cubes are Morton-sorted: the
    /// centre brick's are consecutive vertices (`first..end`, `cells`
    /// their codes); a cube of a brick around is its brick word's first
    /// index plus the ON cubes before it in the word.
    fn fill_ids(&mut self, first: usize, cells: &[u64]) {
        for (i, &c) in cells.iter().enumerate() {
            self.ids[usize::from(MORTON_TO_EXT[(c & 511) as usize]) & (IDS - 1)] =
                (first + i) as u32;
        }
        for &(b, w, reached) in &REACHED {
            let (b, w) = (usize::from(b), usize::from(w));
            let brick = self.around[b];
            let all = brick.mor[w];
            let mut m = all & reached;
            while m != 0 {
                let bit = m.trailing_zeros();
                m &= m - 1;
                let e = usize::from(MORTON_TO_EXT[(w << 6) | bit as usize])
                    .wrapping_add(BRICK_OFFSET[b]);
                self.ids[e & (IDS - 1)] = brick.base[w] + (all & ((1u64 << bit) - 1)).count_ones();
            }
        }
    }

    /// Vertex of each corner of the neighbourhood with origin `o` that is
    /// ON in `mask`, NONE elsewhere: eight reads and a mask, no branch
    /// (which corners are ON is what a branch predictor cannot guess).
    #[inline]
    fn corners(&self, o: [usize; 3], mask: u8) -> [u32; 8] {
        let at = o[0] + EXT * (o[1] + EXT * o[2]);
        // One bounds check; the reads come in adjacent pairs.
        let ids = &self.ids[at..at + CORNER_OFFSET[7] + 1];
        let mut vs = CORNER_OFFSET.map(|d| ids[d]);
        for (j, v) in vs.iter_mut().enumerate() {
            // All ones where the corner is OFF.
            *v |= u32::from(mask & (1 << j) == 0).wrapping_neg();
        }
        vs
    }
}

/// Whether this brick owns the neighbourhood with origin `o` (extended)
/// lying in the bricks below it along the axes of `below`: its origin brick
/// `p` holds no ON cube, and this brick is the first, in child-code order,
/// of the occupied bricks `p + F` the neighbourhood can reach (§6.1.1's
/// back-neighbour rule at brick scale, made unique).
#[inline]
fn owns(w: &Window, o: [usize; 3], below: u8) -> bool {
    // Axes along which the neighbourhood reaches the next brick up.
    let reach =
        below | u8::from(o[0] == 9) | (u8::from(o[1] == 9) << 1) | (u8::from(o[2] == 9) << 2);
    for f in 0..below {
        if f & !reach != 0 {
            continue;
        }
        // Brick p + F = q − below + F, in the window (x fastest, centre 13).
        let d = |a: u8| 1 + i32::from((f >> a) & 1) - i32::from((below >> a) & 1);
        if w.bricks[(d(0) + 3 * d(1) + 9 * d(2)) as usize] != NONE {
            return false;
        }
    }
    true
}

/// Local Morton code `k < 512` of a brick → its linear position
/// `64 z + 8 y + x` (word `z`, bit `8 y + x` of [`Brick::lin`]).
const MORTON_TO_LINEAR: [u16; 512] = {
    let mut t = [0u16; 512];
    let mut k = 0;
    while k < 512 {
        let x = (k & 1) | ((k >> 2) & 2) | ((k >> 4) & 4);
        let y = ((k >> 1) & 1) | ((k >> 3) & 2) | ((k >> 5) & 4);
        let z = ((k >> 2) & 1) | ((k >> 4) & 2) | ((k >> 6) & 4);
        t[k] = (64 * z + 8 * y + x) as u16;
        k += 1;
    }
    t
};

/// Local Morton code `k < 512` → extended window index of the cube in the
/// centre brick, `(x + 2) + 12 (y + 2) + 144 (z + 2)`.
const MORTON_TO_EXT: [u16; 512] = {
    let mut t = [0u16; 512];
    let mut k = 0;
    while k < 512 {
        let l = MORTON_TO_LINEAR[k] as usize;
        let (x, y, z) = (l & 7, (l >> 3) & 7, l >> 6);
        t[k] = ((x + 2) + EXT * (y + 2) + EXT * EXT * (z + 2)) as u16;
        k += 1;
    }
    t
};

/// Bricks of a level (sorted Morton cells) and their keys, in Morton order.
fn bricks_of(cells: &[u64]) -> (Vec<Brick>, Vec<u64>) {
    // Room for 16 cubes a brick and more (surfaces have some 40): never
    // regrown, which copied the bricks and touched fresh pages.
    let room = cells.len() / 16 + 1;
    let mut bricks: Vec<Brick> = Vec::with_capacity(room);
    let mut keys: Vec<u64> = Vec::with_capacity(room);
    for (i, &c) in cells.iter().enumerate() {
        let key = c >> (3 * BRICK_BITS);
        if keys.last() != Some(&key) {
            keys.push(key);
            bricks.push(Brick {
                lin: [0; 8],
                mor: [0; 8],
                base: [i as u32; 8],
            });
        }
        let b = bricks.last_mut().expect("pushed above");
        let k = (c & 511) as usize;
        b.mor[k >> 6] |= 1 << (k & 63);
        let l = usize::from(MORTON_TO_LINEAR[k]);
        b.lin[l >> 6] |= 1 << (l & 63);
    }
    for b in &mut bricks {
        for w in 1..8 {
            b.base[w] = b.base[w - 1] + b.mor[w - 1].count_ones();
        }
    }
    (bricks, keys)
}

/// Triangulates one decoded level.
pub fn triangulate(s: &LevelSurface, opts: &TriangulateOptions) -> Triangulation {
    triangulate_impl(Cow::Borrowed(s), opts, None)
}

/// [`triangulate`], the mesh taking over the surface's particles instead
/// of copying them (for a level built only to be triangulated, as
/// [`crate::Decoded::into_surface`] gives it).
pub fn triangulate_owned(s: LevelSurface, opts: &TriangulateOptions) -> Triangulation {
    triangulate_impl(Cow::Owned(s), opts, None)
}

/// [`triangulate`] plus, per output triangle, the class `C_i` of the
/// neighbourhood that built it, plus 128 when that neighbourhood was an
/// ambiguous one left whole (for diagnosing non-manifold triangles).
pub fn triangulate_traced(s: &LevelSurface, opts: &TriangulateOptions) -> (Triangulation, Vec<u8>) {
    let mut classes = Vec::new();
    let t = triangulate_impl(Cow::Borrowed(s), opts, Some(&mut classes));
    (t, classes)
}

fn triangulate_impl(
    surface: Cow<'_, LevelSurface>,
    opts: &TriangulateOptions,
    mut trace: Option<&mut Vec<u8>>,
) -> Triangulation {
    // wasm32-unknown-unknown has no clock (`Instant::now` panics there):
    // the browser build reports zero seconds and times itself.
    let start = (!cfg!(target_family = "wasm")).then(Instant::now);
    let s: &LevelSurface = &surface;
    let mut stats = TriangulationStats {
        configurations: vec![0; CLASS_COUNT + 1],
        ..Default::default()
    };
    // The scan needs the cubes in strict Morton order (as decoded); a
    // caller-made surface that is not gets a sorted view.
    let sorted = s.cells.windows(2).all(|w| w[0] < w[1]);
    let (order, cells_sorted): (Option<Vec<u32>>, Vec<u64>) = if sorted {
        (None, Vec::new())
    } else {
        let mut o: Vec<u32> = (0..s.cells.len() as u32).collect();
        o.sort_by_key(|&i| s.cells[i as usize]);
        o.dedup_by_key(|i| s.cells[*i as usize]);
        let c = o.iter().map(|&i| s.cells[i as usize]).collect();
        (Some(o), c)
    };
    let cells: &[u64] = if sorted { &s.cells } else { &cells_sorted };
    // Vertex (sorted order) → vertex of `s`.
    let vid = |v: u32| order.as_ref().map_or(v, |o| o[v as usize]);
    // A closed surface has about two triangles per cube; duplicates
    // (dropped at the end) and non-manifold hulls add a few: room for
    // them, so the vector is never regrown (a copy plus fresh pages).
    let mut faces: Vec<[u32; 3]> = Vec::with_capacity(cells.len() * 2 + cells.len() / 8 + 64);
    let mut merges: Vec<(u32, u32)> = Vec::new();
    // Triangles built by solid configurations: the only ones two
    // neighbourhoods can both build (planar faces have one owner).
    let mut from_solids: Vec<u32> = Vec::new();
    // Cubes already merged (§6.3 merges pairs of nodes; chains of merges
    // would drift by more than a cube).
    let mut merged = vec![
        false;
        if opts.decimate.is_some() {
            s.cells.len()
        } else {
            0
        }
    ];
    let cube = s.frame.cube(s.level);
    let min_edge = opts.decimate.map(|f| f * cube);
    let (bricks, keys) = bricks_of(cells);
    let index = BrickIndex::new(s.level, &keys);

    let t = table();
    // Direct-mapped memo of `split_by_cycle` (1024 slots; key never 0 for
    // a solid, whose mask has four cubes or more).
    let mut cycles: Vec<(u64, Split)> = vec![(0, Split::Whole); 1 << 10];
    // Direct-mapped memo of `shared_edges` and the split it leads to,
    // keyed by the 4×4×4 cubes around the neighbourhood, which are all its
    // overlapping neighbourhoods read (key never 0 around a solid).
    let mut shared_memo: Vec<(u64, Split)> = vec![(0, Split::Whole); 1 << SHARED_MEMO_BITS];
    let mut trials: Vec<Trial> = Vec::new();
    let mut w = Window {
        rows: [0; EXT * EXT],
        bricks: [NONE; 27],
        around: [&EMPTY_BRICK; 27],
        ids: [0; IDS],
    };
    // First face each brick built (see [`settle_ranges`]).
    let mut brick_faces: Vec<u32> = Vec::with_capacity(keys.len() + 1);
    // Neighbourhoods per class (a fixed array: no bounds check per count).
    let mut configurations = [0u64; 32];
    for (qi, &q) in keys.iter().enumerate() {
        brick_faces.push(faces.len() as u32);
        let first = bricks[qi].base[0] as usize;
        let end = bricks
            .get(qi + 1)
            .map_or(cells.len(), |b| b.base[0] as usize);
        let qc = unmorton(q).map(i64::from);
        for k in 0..27 {
            w.bricks[k] = index.get([
                qc[0] + (k % 3) as i64 - 1,
                qc[1] + ((k / 3) % 3) as i64 - 1,
                qc[2] + (k / 9) as i64 - 1,
            ]);
        }
        for k in 0..27 {
            w.around[k] = match w.bricks[k] {
                NONE => &EMPTY_BRICK,
                n => &bricks[n as usize],
            };
        }
        w.fill_ids(first, &cells[first..end]);
        // Per extended z, the z-slab word of each brick of the 3×3 around
        // (a byte per row); four rows at a time, the bytes of each brick
        // along x spread to 16-bit rows and merged: the top two cubes of
        // the brick below, its eight, the bottom two of the brick above.
        for ez in 0..EXT {
            let (lz, b) = (EXT_LOCAL[ez], 9 * EXT_BRICK[ez]);
            // Bytes of extended rows `4g..4g + 4` of the bricks at `bx`.
            let bytes = |bx: usize| {
                let slab = |by: usize| w.around[b + 3 * by + bx].lin[lz];
                let (below, this, above) = (slab(0), slab(1), slab(2));
                [
                    (below >> 48) | ((this & 0xffff) << 16),
                    (this >> 16) & 0xffff_ffff,
                    (this >> 48) | ((above & 0xffff) << 16),
                ]
            };
            let (lo, mid, hi) = (bytes(0), bytes(1), bytes(2));
            for g in 0..3 {
                const TWO: u64 = 0x0003_0003_0003_0003;
                let rows = ((spread_bytes(lo[g]) >> 6) & TWO)
                    | (spread_bytes(mid[g]) << 2)
                    | ((spread_bytes(hi[g]) & TWO) << 10);
                w.set_rows4(4 * g + EXT * ez, rows);
            }
        }
        for oz in 1..10usize {
            // Origins y = −1..8 (1..10 extended) four at a time
            // (`oy0..oy0 + 4`), a row of 16 bits each ([`Window::rows4`]).
            for (oy0, lanes) in ROW_GROUPS {
                let r = [
                    w.rows4(oy0 + EXT * oz),
                    w.rows4(oy0 + 1 + EXT * oz),
                    w.rows4(oy0 + EXT * (oz + 1)),
                    w.rows4(oy0 + 1 + EXT * (oz + 1)),
                ];
                // Most rows of a window miss the surface.
                if (r[0] | r[1] | r[2] | r[3]) & (lanes * 0x7fe) == 0 {
                    continue;
                }
                // Origins x = −1..8 (1..10 extended) whose neighbourhood
                // has three ON cubes or more: a bit-sliced count of the
                // eight cubes of all origins of the four rows at once
                // (bitwise: the bit a shift moves across rows lands on
                // no origin).
                let (mut ones, mut twos, mut fours) = (0u64, 0u64, 0u64);
                for x in [
                    r[0],
                    r[0] >> 1,
                    r[1],
                    r[1] >> 1,
                    r[2],
                    r[2] >> 1,
                    r[3],
                    r[3] >> 1,
                ] {
                    let carry = ones & x;
                    ones ^= x;
                    fours |= twos & carry;
                    twos ^= carry;
                }
                let mut any = (fours | (twos & ones)) & (lanes * 0x3fe);
                // Origins in a brick below (extended 1 on an axis): only
                // those this brick owns are kept, tested first so that the
                // loop below has no test.
                let mut lower = any
                    & match (oz, oy0) {
                        (1, _) => u64::MAX,
                        (_, 1) => (lanes * 2) | 0x3fe,
                        _ => lanes * 2,
                    };
                while lower != 0 {
                    let bit = lower.trailing_zeros() as usize;
                    lower &= lower - 1;
                    let (ox, oy) = (bit & 15, oy0 + (bit >> 4));
                    let below =
                        u8::from(ox == 1) | (u8::from(oy == 1) << 1) | (u8::from(oz == 1) << 2);
                    if !owns(&w, [ox, oy, oz], below) {
                        any &= !(1 << bit);
                    }
                }
                while any != 0 {
                    let bit = any.trailing_zeros() as usize;
                    any &= any - 1;
                    let (ox, oy) = (bit & 15, oy0 + (bit >> 4));
                    let o = [ox, oy, oz];
                    // `w.mask(o)`, from the rows at hand.
                    let pair = |r: u64| ((r >> bit) & 3) as u8;
                    let mask =
                        pair(r[0]) | (pair(r[1]) << 2) | (pair(r[2]) << 4) | (pair(r[3]) << 6);
                    debug_assert_eq!(mask, w.mask(o));
                    // Three ON cubes or more (`any`): a class.
                    let c = t.compact[mask as usize];
                    debug_assert!(c.class != 0);
                    configurations[usize::from(c.class) & 31] += 1;
                    if c.face != 0 && defer_face(t, &w, o, c.face) {
                        continue;
                    }
                    let mut vs = w.corners(o, mask);
                    if order.is_some() {
                        for v in &mut vs {
                            if *v != NONE {
                                *v = vid(*v);
                            }
                        }
                    }
                    // Corners index `vs` masked: no bounds check.
                    let vertex = |j: u8| vs[usize::from(j & 7)];
                    let mut emit = |tri: [u8; 3], faces: &mut Vec<[u32; 3]>| -> bool {
                        let f = [vertex(tri[0]), vertex(tri[1]), vertex(tri[2])];
                        if let Some(min) = min_edge
                            && merge_short_edge(f, min, &s.positions, &mut merged, &mut merges)
                        {
                            return false;
                        }
                        faces.push(f);
                        true
                    };
                    // A solid left whole (no unique cycle).
                    let mut whole = false;
                    let q = c.corners;
                    if c.kind == Compact::TRIANGLE {
                        emit([q[0], q[1], q[2]], &mut faces);
                    } else if c.kind == Compact::QUAD {
                        let vq = [0, 1, 2, 3].map(|k| vertex(q[k]) as usize);
                        let pos = [0, 1, 2, 3].map(|k| s.positions[vq[k]]);
                        let nrm = s.normals.as_ref().map(|n| [0, 1, 2, 3].map(|k| n[vq[k]]));
                        let (t1, t2) = choose_quad(q, pos, nrm);
                        emit(t1, &mut faces);
                        emit(t2, &mut faces);
                    } else {
                        let cfg = &t.configs[mask as usize];
                        let Shape::Solid(tris) = &cfg.shape else {
                            unreachable!("three ON cubes or more, not planar")
                        };
                        {
                            let around = w.block(o);
                            let slot = &mut shared_memo[(around.wrapping_mul(0x9e37_79b9_7f4a_7c15)
                                >> (64 - SHARED_MEMO_BITS))
                                as usize];
                            if slot.0 != around {
                                let (shared, twice) = shared_edges(around, mask);
                                // §6.2's cycle search depends on the
                                // configuration and its shared edges only:
                                // memoised too, over all blocks.
                                let key = u64::from(shared)
                                    | (u64::from(twice) << 28)
                                    | (u64::from(mask) << 56);
                                let cycle = &mut cycles
                                    [(key.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 54) as usize];
                                if cycle.0 != key {
                                    *cycle = (key, split_by_cycle(mask, shared, twice, tris));
                                }
                                *slot = (around, cycle.1);
                            }
                            let split = slot.1;
                            // Triangles on a face of the neighbourhood (three
                            // cubes sharing a coordinate) may be built by the
                            // solid across that face too.
                            let mut solid_emit = |tri: [u8; 3], faces: &mut Vec<[u32; 3]>| {
                                if emit(tri, faces)
                                    && !((tri[0] ^ tri[1]) | (tri[0] ^ tri[2])) & 7 != 0
                                {
                                    from_solids.push(faces.len() as u32 - 1);
                                }
                            };
                            // With decimation, whose merges follow the
                            // scan, every solid is built at once; without,
                            // the choices are settled once the level is
                            // scanned (see [`settle`]).
                            let settled = opts.decimate.is_none()
                                && (cfg.class != SETTLE_SKIP_CLASS
                                    || matches!(split, Split::Holding(..) | Split::Whole));
                            let mut resolved = |keep: u16, faces: &mut Vec<[u32; 3]>| {
                                let keep = keep & all_bits(tris.len());
                                if settled {
                                    trials.push(Trial { vs, mask, keep });
                                    return;
                                }
                                stats.disambiguated += 1;
                                for (i, &tri) in tris.iter().enumerate() {
                                    if keep & (1 << i) != 0 {
                                        solid_emit(tri, faces);
                                    }
                                }
                            };
                            match split {
                                Split::Either(disc) => {
                                    // Hull corners are ON: `vs` holds their
                                    // vertices.
                                    let pos = |j: u8| s.positions[vs[usize::from(j & 7)] as usize];
                                    let keep = if smoother_disc(tris, &cfg.adjacent, disc, &pos) {
                                        disc
                                    } else {
                                        !disc
                                    };
                                    resolved(keep, &mut faces);
                                }
                                Split::Only(keep) => resolved(keep, &mut faces),
                                Split::Holding(keep, _) if settled => resolved(keep, &mut faces),
                                Split::Whole if settled => resolved(u16::MAX, &mut faces),
                                Split::Whole | Split::Holding(..) => {
                                    whole = true;
                                    stats.fallbacks += 1;
                                    for &tri in tris {
                                        solid_emit(tri, &mut faces);
                                    }
                                }
                            }
                        }
                    }
                    if let Some(tr) = trace.as_deref_mut() {
                        tr.resize(faces.len(), c.class | if whole { 0x80 } else { 0 });
                    }
                }
            }
        }
    }
    stats
        .configurations
        .copy_from_slice(&configurations[..=CLASS_COUNT]);
    // The ambiguous solids, settled against everything else built.
    brick_faces.push(faces.len() as u32);
    let ranges = if order.is_none() {
        settle_ranges(&trials, cells, &index, &brick_faces)
    } else {
        vec![(0, faces.len() as u32)]
    };
    settle(&faces, &ranges, &from_solids, &mut trials, s.cells.len());
    for t in &trials {
        let Shape::Solid(tris) = &table().configs[t.mask as usize].shape else {
            continue;
        };
        let whole = t.keep == all_bits(tris.len());
        if whole {
            stats.fallbacks += 1;
        } else {
            stats.disambiguated += 1;
        }
        for (i, tri) in tris.iter().enumerate() {
            if t.keep & (1 << i) != 0 {
                faces.push(tri.map(|j| t.vs[j as usize]));
                if on_face(tri) {
                    from_solids.push(faces.len() as u32 - 1);
                }
            }
        }
        if let Some(tr) = trace.as_deref_mut() {
            let class = table().configs[t.mask as usize].class;
            tr.resize(faces.len(), class | if whole { 0x80 } else { 0 });
        }
    }
    // A triangle whose three cubes share a coordinate lies on the face
    // between two neighbourhoods; two solid ones may both have built it:
    // keep one.
    let dropped = dedupe_face_triangles(&mut faces, &from_solids);
    if let Some(tr) = trace {
        remove_sorted(tr, &dropped);
    }
    let mut mesh = match surface {
        Cow::Borrowed(s) => s.vertices_only(),
        Cow::Owned(s) => s.into_vertices(),
    };
    if !merges.is_empty() {
        decimate_merge(&mut mesh, &mut faces, &merges);
    }
    mesh.faces = faces;
    if opts.orient {
        crate::orientation::orient(&mut mesh);
    }
    stats.triangles = mesh.faces.len();
    stats.seconds = start.map_or(0.0, |t| t.elapsed().as_secs_f64());
    Triangulation { mesh, stats }
}

/// §6.3: merges the cubes of the first edge of `f` shorter than `min`
/// whose cubes are not merged yet; whether it did (the triangle is then
/// not built). Out of line: the scan's emission stays small enough to
/// inline.
#[inline(never)]
fn merge_short_edge(
    f: [u32; 3],
    min: f32,
    positions: &[Vec3],
    merged: &mut [bool],
    merges: &mut Vec<(u32, u32)>,
) -> bool {
    for e in 0..3 {
        let (a, b) = (f[e], f[(e + 1) % 3]);
        if positions[a as usize].distance(positions[b as usize]) < min
            && !merged[a as usize]
            && !merged[b as usize]
        {
            merged[a as usize] = true;
            merged[b as usize] = true;
            merges.push((a, b));
            return true;
        }
    }
    false
}

/// Whether a planar configuration lying on a face of its neighbourhood
/// leaves that face to the neighbourhood on the other side: always when it
/// is the upper face (the other side sees it as its lower face), and when
/// the other side is a solid configuration, whose disc choice then covers
/// the face alone (two owners would cover it twice).
/// `face`: [`Compact::face`], not 0.
#[inline]
fn defer_face(t: &Table, w: &Window, o: [usize; 3], face: u8) -> bool {
    if face == 1 {
        return true;
    }
    let mut across = o;
    across[usize::from(face - 2) % 3] -= 1;
    let m = w.mask(across);
    t.solid[usize::from(m >> 6)] & (1 << (m & 63)) != 0
}

#[inline]
fn tri_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a).normalize_or_zero()
}

/// [`hull_normal`] of four triangles at once, as the `x`, `y` and `z`
/// of each: the triangles side by side in the lanes of `Vec4`s, each
/// lane's operations those of the scalar code in the same order
/// (`Vec3::cross`, `Vec3::normalize_or_zero`), so the normals have the
/// same bits.
#[inline(always)]
fn hull_normals4(tris: [[u8; 3]; 4], pos: &impl Fn(u8) -> Vec3) -> [[f32; 4]; 3] {
    use glam::Vec4;
    let mut p = [[Vec3::ZERO; 3]; 4];
    for (pt, t) in p.iter_mut().zip(tris) {
        for (v, j) in pt.iter_mut().zip(t) {
            *v = pos(j);
        }
    }
    // Corner `c` of the four triangles, coordinate `f`.
    let lane =
        |c: usize, f: fn(Vec3) -> f32| Vec4::new(f(p[0][c]), f(p[1][c]), f(p[2][c]), f(p[3][c]));
    let edge = |c: usize, f: fn(Vec3) -> f32| lane(c, f) - lane(0, f);
    let (ax, ay, az) = (edge(1, |v| v.x), edge(1, |v| v.y), edge(1, |v| v.z));
    let (bx, by, bz) = (edge(2, |v| v.x), edge(2, |v| v.y), edge(2, |v| v.z));
    let nx = ay * bz - by * az;
    let ny = az * bx - bz * ax;
    let nz = ax * by - bx * ay;
    let rcp = Vec4::ONE / ((nx * nx) + (ny * ny) + (nz * nz)).sqrt();
    let ok = rcp.is_finite_mask() & rcp.cmpgt(Vec4::ZERO);
    let unit = |n: Vec4| Vec4::select(ok, n * rcp, Vec4::ZERO).to_array();
    [unit(nx), unit(ny), unit(nz)]
}

/// Unit normal of the hull triangle `t` (corners), `pos` giving the
/// corners' positions. A function rather than a closure so that it can be
/// forced inline (LLVM had left such a closure out of line).
#[inline(always)]
fn hull_normal(t: [u8; 3], pos: &impl Fn(u8) -> Vec3) -> Vec3 {
    tri_normal(pos(t[0]), pos(t[1]), pos(t[2]))
}

/// The two triangulations of a quad `a b c d`; returns the better one.
#[inline]
fn choose_quad(q: [u8; 4], p: [Vec3; 4], n: Option<[Vec3; 4]>) -> ([u8; 3], [u8; 3]) {
    let ac = ([q[0], q[1], q[2]], [q[0], q[2], q[3]]);
    let bd = ([q[0], q[1], q[3]], [q[1], q[2], q[3]]);
    let (s_ac, s_bd) = match n {
        Some(_) => (
            quad_split_score(&p, n.as_ref(), [0, 1, 2], [0, 2, 3]),
            quad_split_score(&p, n.as_ref(), [0, 1, 3], [1, 2, 3]),
        ),
        None => quad_dihedral_scores(&p),
    };
    // Picked without a branch: the comparison waits on a square root and
    // a division, and a mispredicted guess would throw that wait away.
    let m = 0u8.wrapping_sub(u8::from(s_ac <= s_bd));
    let pick = |a: [u8; 3], b: [u8; 3]| [0, 1, 2].map(|k| (a[k] & m) | (b[k] & !m));
    (pick(ac.0, bd.0), pick(ac.1, bd.1))
}

/// [`quad_split_score`] without normals for both splits at once: the four
/// triangle normals (unnormalised) side by side in the lanes of `Vec4`s,
/// with each lane's operations those of the scalar code in the same order
/// (`Vec3::cross`, `Vec3::dot`), so the scores have the same bits.
#[inline(always)]
fn quad_dihedral_scores(p: &[Vec3; 4]) -> (f32, f32) {
    use glam::Vec4;
    // Lanes: triangles 0 1 2 and 0 2 3 (split a–c), 0 1 3 and 1 2 3 (b–d);
    // edge vectors `a = p[t1] − p[t0]`, `b = p[t2] − p[t0]`.
    let lanes = |c: fn(Vec3) -> f32| {
        let (p0, p1, p2, p3) = (c(p[0]), c(p[1]), c(p[2]), c(p[3]));
        let origin = Vec4::new(p0, p0, p0, p1);
        (
            Vec4::new(p1, p2, p1, p2) - origin,
            Vec4::new(p2, p3, p3, p3) - origin,
        )
    };
    let (ax, bx) = lanes(|v| v.x);
    let (ay, by) = lanes(|v| v.y);
    let (az, bz) = lanes(|v| v.z);
    let nx = ay * bz - by * az;
    let ny = az * bx - bz * ax;
    let nz = ax * by - bx * ay;
    // Each lane times its partner (0 with 1, 2 with 3).
    let partner = |v: Vec4| Vec4::new(v.y, v.x, v.w, v.z);
    let squared = nx * nx + ny * ny + nz * nz;
    let dots = nx * partner(nx) + ny * partner(ny) + nz * partner(nz);
    let l = (squared * partner(squared)).sqrt();
    let score = |k: usize| {
        if l[k] > 0.0 { -dots[k] / l[k] } else { 0.0 }
    };
    (score(0), score(2))
}

/// How badly the triangles `t0`, `t1` of a quad split fit: their
/// disagreement with the particle normals, or without normals their
/// dihedral angle (its cosine, negated: same order, no `acos`; one square
/// root).
#[inline(always)]
fn quad_split_score(p: &[Vec3; 4], n: Option<&[Vec3; 4]>, t0: [usize; 3], t1: [usize; 3]) -> f32 {
    let cross = |t: [usize; 3]| (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    let (m1, m2) = (cross(t0), cross(t1));
    match n {
        Some(vn) => {
            let (n1, n2) = (m1.normalize_or_zero(), m2.normalize_or_zero());
            let s1: f32 = t0.iter().map(|&i| 1.0 - n1.dot(vn[i]).abs()).sum();
            let s2: f32 = t1.iter().map(|&i| 1.0 - n2.dot(vn[i]).abs()).sum();
            s1 + s2
        }
        None => {
            let l = (m1.length_squared() * m2.length_squared()).sqrt();
            if l > 0.0 { -m1.dot(m2) / l } else { 0.0 }
        }
    }
}

/// For each of the 26 overlapping neighbourhoods `o + d` (index
/// `(dx+1) + 3(dy+1) + 9(dz+1)`): its corners that lie in this block, and
/// its corner pairs inside the overlap with the same pairs in this
/// block's numbering.
struct Overlaps {
    corners: [u8; 27],
    /// `(its pair bit, our pair bit)` for each corner pair of the overlap:
    /// six for a neighbour across a face, one across an edge (the rest
    /// zero), none across a corner.
    pairs: [[(u32, u32); 6]; 27],
    /// Per configuration, the neighbours whose overlap holds an edge of
    /// its graph `G_i` (bit `k`; never the configuration itself, 13).
    near: [u32; 256],
}

/// The neighbours across a face (a 2×2 overlap, six corner pairs), as
/// bits `k` of [`Overlaps::near`]; the others with an overlap pair are
/// across an edge (one pair).
const ACROSS_FACE: u32 = 1 << 4 | 1 << 10 | 1 << 12 | 1 << 14 | 1 << 16 | 1 << 22;

fn overlaps() -> &'static Overlaps {
    static O: OnceLock<Overlaps> = OnceLock::new();
    O.get_or_init(|| {
        let mut o = Overlaps {
            corners: [0; 27],
            pairs: [[(0, 0); 6]; 27],
            near: [0; 256],
        };
        let mut ours = [0u32; 27];
        for k in 0..27usize {
            let d = [
                (k % 3) as i32 - 1,
                ((k / 3) % 3) as i32 - 1,
                (k / 9) as i32 - 1,
            ];
            // Neighbour corner j2 sits at our local c2 + d.
            let ours_of = |j2: u8| -> Option<u8> {
                let c = corner(j2);
                let l = [c[0] + d[0], c[1] + d[1], c[2] + d[2]];
                l.iter()
                    .all(|v| (0..=1).contains(v))
                    .then(|| (l[0] + 2 * l[1] + 4 * l[2]) as u8)
            };
            for j2 in 0..8u8 {
                if ours_of(j2).is_some() {
                    o.corners[k] |= 1 << j2;
                }
            }
            let mut n = 0;
            for a2 in 0..8u8 {
                for b2 in a2 + 1..8u8 {
                    if let (Some(a), Some(b)) = (ours_of(a2), ours_of(b2))
                        && k != 13
                    {
                        o.pairs[k][n] = (1 << pair(a2, b2), 1 << pair(a, b));
                        ours[k] |= 1 << pair(a, b);
                        n += 1;
                    }
                }
            }
            debug_assert!(n == 6 || (n <= 1 && ACROSS_FACE & (1 << k) == 0));
        }
        for (mask, near) in o.near.iter_mut().enumerate() {
            let edges = table().configs[mask].edges;
            for (k, &ours) in ours.iter().enumerate() {
                if edges & ours != 0 {
                    *near |= 1 << k;
                }
            }
        }
        o
    })
}

/// Slots of the `shared_edges` memo, as a power of two: 8192 (128 KiB)
/// measured fastest on the bunny and the icosphere at R = 8 (2048 and
/// 4096 miss more, 32768 costs its fresh pages and cache).
const SHARED_MEMO_BITS: u32 = 13;

/// Edges of `G_i` (as pair bits) of the configuration `mask` also in the
/// graph of an overlapping neighbourhood, and those in the graphs of two or
/// more. `around`: the 4×4×4 cubes of [`Window::block`], all that the
/// neighbourhoods read. Without a branch on the neighbours' configurations
/// (what a branch predictor cannot guess): fixed steps per neighbour.
fn shared_edges(around: u64, mask: u8) -> (u32, u32) {
    let t = table();
    let ov = overlaps();
    let (mut shared, mut twice) = (0u32, 0u32);
    // All ones where `x` is not zero.
    let ones = |x: u32| 0u32.wrapping_sub(u32::from(x != 0));
    // Configuration of neighbour `k`, its graph's edges in the overlap
    // (none when all its cubes lie in this block: a planar patch on the
    // shared face is this block's own geometry, not outside evidence).
    let theirs = |k: usize| {
        let c = around >> (k % 3 + 16 * ((k / 3) % 3) + 4 * (k / 9));
        let m2 = ((c & 0x33) | ((c >> 14) & 0xcc)) as u8;
        t.configs[usize::from(m2)].edges & ones(u32::from(m2 & !ov.corners[k]))
    };
    let near = ov.near[usize::from(mask)];
    let mut add = |e2: u32, (their, our): (u32, u32)| {
        let bit = our & ones(e2 & their);
        twice |= shared & bit;
        shared |= bit;
    };
    let mut faces = near & ACROSS_FACE;
    while faces != 0 {
        let k = faces.trailing_zeros() as usize;
        faces &= faces - 1;
        let e2 = theirs(k);
        for p in ov.pairs[k] {
            add(e2, p);
        }
    }
    let mut edges = near & !ACROSS_FACE;
    while edges != 0 {
        let k = edges.trailing_zeros() as usize;
        edges &= edges - 1;
        add(theirs(k), ov.pairs[k][0]);
    }
    let e = t.configs[usize::from(mask)].edges;
    (shared & e, twice & e)
}

/// An ambiguous solid whose triangles are chosen once the level is
/// scanned ([`settle`]).
struct Trial {
    /// Vertex of each corner (NONE where not ON).
    vs: [u32; 8],
    mask: u8,
    /// The triangles built, as bits over the configuration's hull.
    keep: u16,
}

/// The bits of `n` triangles.
fn all_bits(n: usize) -> u16 {
    ((1u32 << n.min(16)) - 1) as u16
}

/// Hulls with more triangles than this keep their first choice: the
/// subsets tried grow as `2^n`.
const SETTLE_MAX_TRIANGLES: usize = 12;

/// Resolved neighbourhoods of this class are built at once.
const SETTLE_SKIP_CLASS: u8 = 6;

/// Sweeps over the trials; a second lets the first ones see the later.
const SETTLE_SWEEPS: usize = 2;

#[inline]
fn sorted_tri(t: [u32; 3]) -> [u32; 3] {
    let (a, b) = (t[0].min(t[1]), t[0].max(t[1]));
    [a.min(t[2]), a.max(b.min(t[2])), b.max(t[2])]
}

/// Whether the corners of a hull triangle share a coordinate: it lies on a
/// face of the neighbourhood, and the solid across may build it too.
fn on_face(tri: &[u8; 3]) -> bool {
    !((tri[0] ^ tri[1]) | (tri[0] ^ tri[2])) & 7 != 0
}

/// Hash of a triangle's vertex indices: a multiply per 32-bit word (the
/// keys are not adversarial; the default SipHash cost more than the
/// settling it served).
#[derive(Default)]
struct TriHasher(u64);

impl Hasher for TriHasher {
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 32)
    }
    fn write(&mut self, bytes: &[u8]) {
        for w in bytes.chunks(4) {
            let mut b = [0u8; 4];
            b[..w.len()].copy_from_slice(w);
            self.write_u32(u32::from_le_bytes(b));
        }
    }
    fn write_u32(&mut self, v: u32) {
        self.0 = (self.0.rotate_left(26) ^ u64::from(v)).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
    fn write_usize(&mut self, v: usize) {
        self.write_u32(v as u32);
    }
}

/// Edge and vertex use by the distinct triangles around the trials. Only
/// triangles on a neighbourhood face can be built twice (by the solids on
/// both sides; [`dedupe_face_triangles`] later keeps one copy), so only
/// those are counted by key.
struct Uses {
    face_tris: HashMap<[u32; 3], u32, BuildHasherDefault<TriHasher>>,
    /// The trials' hull edges (by key) → their slot in `edge_uses`.
    edges: MortonMap<u32>,
    edge_uses: Vec<u32>,
    vertices: Vec<u32>,
}

/// Where a triangle's edges are counted: looked up by key (a triangle of
/// the level), or the slots of a trial's hull triangle, found once.
#[derive(Clone, Copy)]
enum EdgeSlots {
    Lookup,
    Known([u32; 3]),
}

impl Uses {
    fn add(&mut self, t: [u32; 3], face: bool, slots: EdgeSlots) {
        if face {
            let n = self.face_tris.entry(sorted_tri(t)).or_insert(0);
            *n += 1;
            if *n > 1 {
                return;
            }
        }
        self.touch(t, 1, slots);
    }
    fn remove(&mut self, t: [u32; 3], face: bool, slots: EdgeSlots) {
        if face {
            let key = sorted_tri(t);
            let Some(n) = self.face_tris.get_mut(&key) else {
                return;
            };
            *n -= 1;
            if *n > 0 {
                return;
            }
            self.face_tris.remove(&key);
        }
        self.touch(t, -1, slots);
    }
    /// Whether a face triangle is built.
    fn built(&self, t: [u32; 3]) -> bool {
        self.face_tris.contains_key(&sorted_tri(t))
    }
    fn touch(&mut self, t: [u32; 3], d: i32, slots: EdgeSlots) {
        for k in 0..3 {
            let slot = match slots {
                EdgeSlots::Lookup => self.edges.get(&edge_key(t[k], t[(k + 1) % 3])).copied(),
                EdgeSlots::Known(s) => Some(s[k]),
            };
            if let Some(slot) = slot {
                let n = &mut self.edge_uses[slot as usize];
                *n = n.wrapping_add_signed(d);
            }
            let v = &mut self.vertices[t[k] as usize];
            *v = v.wrapping_add_signed(d);
        }
    }
}

/// The ranges of `faces` (increasing, disjoint) that hold every triangle
/// on a vertex of a trial. A triangle is built by the brick that scans its
/// neighbourhood: the brick of the neighbourhood's origin or, when that
/// one is empty, an occupied brick the neighbourhood reaches ([`owns`]).
/// A neighbourhood holding cube `v` has its origin in `v`'s brick or, where
/// `v` is on the brick's lower face, in the brick below; it reaches the
/// brick above only where its origin is on an upper face, i.e. where `v`
/// is on the brick's lower face (the brick of `v`) or its upper face (the
/// brick above). So the bricks `v`'s brick plus, per axis, −1 or 0 where
/// `v` is on the lower face, 0 or +1 on the upper face, 0 elsewhere, scan
/// every triangle on `v`: only their triangles, a fraction of the
/// level's, are read (`brick_faces`: the first triangle of each brick,
/// plus the end). `cells` in Morton order, vertex `i` = cell `i`.
fn settle_ranges(
    trials: &[Trial],
    cells: &[u64],
    index: &BrickIndex,
    brick_faces: &[u32],
) -> Vec<(u32, u32)> {
    let mut marked = vec![false; brick_faces.len() - 1];
    for t in trials {
        for (j, &v) in t.vs.iter().enumerate() {
            if t.mask & (1 << j) == 0 {
                continue;
            }
            let c = cells[v as usize];
            let b = unmorton(c >> (3 * BRICK_BITS)).map(i64::from);
            let local = unmorton(c & 511);
            // Per axis, the offsets of the bricks to scan.
            let offsets = local.map(|l| match l {
                0 => [-1, 0],
                7 => [0, 1],
                _ => [0, 0],
            });
            for d in 0..8 {
                let n = index.get([
                    b[0] + offsets[0][d & 1],
                    b[1] + offsets[1][(d >> 1) & 1],
                    b[2] + offsets[2][d >> 2],
                ]);
                if n != NONE {
                    marked[n as usize] = true;
                }
            }
        }
    }
    let mut ranges: Vec<(u32, u32)> = Vec::new();
    for (n, _) in marked.iter().enumerate().filter(|(_, m)| **m) {
        let (start, end) = (brick_faces[n], brick_faces[n + 1]);
        match ranges.last_mut() {
            Some(last) if last.1 == start => last.1 = end,
            _ => ranges.push((start, end)),
        }
    }
    ranges
}

/// Chooses, for each ambiguous solid (a hull §6.2 leaves whole, a disc on
/// trial, a resolved solid of a class other than `C_6`), the subset of its
/// hull triangles that best fits what the rest of the level built: in this
/// order, fewest hull edges used by one triangle (holes), fewest of its
/// cubes left in no triangle, fewest surplus uses of its hull edges
/// (non-manifold edges), its current choice, fewest triangles. The whole
/// hull leaves no hull edge used once, and a trial's choice changes the use
/// of its own hull edges only, so settling opens no hole the whole hulls
/// would not. Trials are settled in scan order, twice over: deterministic.
fn settle(
    faces: &[[u32; 3]],
    ranges: &[(u32, u32)],
    from_solids: &[u32],
    trials: &mut [Trial],
    vertices: usize,
) {
    if trials.is_empty() {
        return;
    }
    let hull = |t: &Trial| match &table().configs[t.mask as usize].shape {
        Shape::Solid(tris) => tris.as_slice(),
        _ => &[],
    };
    // Trial vertices, as a bit set (the scan below reads it for every
    // triangle of the level; bits keep it in the first-level cache).
    let mut near = vec![0u64; vertices.div_ceil(64)];
    let mut uses = Uses {
        face_tris: HashMap::default(),
        edges: MortonMap::default(),
        edge_uses: Vec::new(),
        vertices: vec![0; vertices],
    };
    // The edge slots of every hull triangle of every trial, trial by trial
    // (`first[i]`: trial `i`'s first), so that the sweeps count a trial's
    // edges without hashing.
    let mut first = Vec::with_capacity(trials.len());
    let mut hull_slots: Vec<[u32; 3]> = Vec::new();
    uses.edges.reserve(trials.len() * 12);
    for t in trials.iter() {
        first.push(hull_slots.len());
        for tri in hull(t) {
            let mut slots = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (t.vs[tri[k] as usize], t.vs[tri[(k + 1) % 3] as usize]);
                near[(a >> 6) as usize] |= 1 << (a & 63);
                let next = uses.edges.len() as u32;
                slots[k] = *uses.edges.entry(edge_key(a, b)).or_insert(next);
            }
            hull_slots.push(slots);
        }
    }
    uses.edge_uses = vec![0; uses.edges.len()];
    // Every triangle that can hold a trial vertex is tested: three bits,
    // or-ed without a branch each; whether a near one came from a solid is
    // read off the sorted `from_solids` with a cursor.
    let bit = |v: u32| (near[(v >> 6) as usize] >> (v & 63)) & 1;
    let mut solid = from_solids.iter().map(|&i| i as usize).peekable();
    for &(start, end) in ranges {
        for i in start as usize..end as usize {
            let f = faces[i];
            if bit(f[0]) | bit(f[1]) | bit(f[2]) != 0 {
                while solid.next_if(|&j| j < i).is_some() {}
                uses.add(f, solid.peek() == Some(&i), EdgeSlots::Lookup);
            }
        }
    }
    let tri_of = |t: &Trial, tri: &[u8; 3]| tri.map(|j| t.vs[j as usize]);
    for (n, t) in trials.iter().enumerate() {
        for (i, tri) in hull(t).iter().enumerate() {
            if t.keep & (1 << i) != 0 {
                let slots = EdgeSlots::Known(hull_slots[first[n] + i]);
                uses.add(tri_of(t, tri), on_face(tri), slots);
            }
        }
    }
    for _ in 0..SETTLE_SWEEPS {
        for (n, t) in trials.iter_mut().enumerate() {
            let tris = hull(t);
            if tris.len() > SETTLE_MAX_TRIANGLES {
                continue;
            }
            let slots = &hull_slots[first[n]..first[n] + tris.len()];
            for (i, tri) in tris.iter().enumerate() {
                if t.keep & (1 << i) != 0 {
                    uses.remove(tri_of(t, tri), on_face(tri), EdgeSlots::Known(slots[i]));
                }
            }
            // Hull edges (as corner pairs), their use by the others, and
            // each triangle's edges among them; face triangles the others
            // built already add nothing.
            let mut edges = [(0u8, 0u8); 18];
            let mut n_edges = 0;
            let mut base = [0u32; 18];
            let mut tri_edges = [[0usize; 3]; 16];
            let mut built = [false; 16];
            for (i, tri) in tris.iter().enumerate() {
                for k in 0..3 {
                    let (a, b) = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                    tri_edges[i][k] = match edges[..n_edges].iter().position(|&e| e == (a, b)) {
                        Some(p) => p,
                        None => {
                            base[n_edges] = uses.edge_uses[slots[i][k] as usize];
                            edges[n_edges] = (a, b);
                            n_edges += 1;
                            n_edges - 1
                        }
                    };
                }
                built[i] = on_face(tri) && uses.built(tri_of(t, tri));
            }
            // Cubes in no other triangle.
            let mut bare = 0u8;
            for j in 0..8u8 {
                if t.mask & (1 << j) != 0 && uses.vertices[t.vs[j as usize] as usize] == 0 {
                    bare |= 1 << j;
                }
            }
            let score = |sub: u16| {
                let mut count = base;
                let mut covered = 0u8;
                for (i, tri) in tris.iter().enumerate() {
                    if sub & (1 << i) == 0 {
                        continue;
                    }
                    for &j in tri {
                        covered |= 1 << j;
                    }
                    if !built[i] {
                        for &e in &tri_edges[i] {
                            count[e] += 1;
                        }
                    }
                }
                let used = &count[..n_edges];
                let holes = used.iter().filter(|&&c| c == 1).count() as u32;
                let surplus: u32 = used.iter().map(|&c| c.saturating_sub(2)).sum();
                let uncovered = (bare & !covered).count_ones();
                (holes, uncovered, surplus)
            };
            // A choice with no hole, no bare cube and no surplus use is
            // the best there is: kept without trying the others.
            if score(t.keep) != (0, 0, 0) {
                t.keep = best_subset(
                    tris,
                    &tri_edges[..tris.len()],
                    &built[..tris.len()],
                    &base[..n_edges],
                    bare,
                    t.keep,
                );
            }
            for (i, tri) in tris.iter().enumerate() {
                if t.keep & (1 << i) != 0 {
                    uses.add(tri_of(t, tri), on_face(tri), EdgeSlots::Known(slots[i]));
                }
            }
        }
    }
}

/// The subset of `tris` that [`settle`] keeps: the least, in this order,
/// hull edges used once (`base`: their use by the other triangles),
/// cubes of `bare` left in no triangle, surplus edge uses, differing from
/// `keep`, triangles, and the subset's bits. Every subset is visited in
/// Gray-code order, one triangle added or removed per step, so each costs
/// the update of three edge counts instead of a recount. Out of line: its
/// loop then keeps its state in registers (inlined in the scan, it spilled).
#[inline(never)]
fn best_subset(
    tris: &[[u8; 3]],
    tri_edges: &[[usize; 3]],
    built: &[bool],
    base: &[u32],
    bare: u8,
    keep: u16,
) -> u16 {
    // A power of two long: an edge index masked needs no bounds check.
    let mut count = [0u32; 32];
    count[..base.len()].copy_from_slice(base);
    let mut holes = base.iter().filter(|&&c| c == 1).count() as u32;
    let mut surplus: u32 = base.iter().map(|&c| c.saturating_sub(2)).sum();
    // Triangles on each corner, a 4-bit count per corner (a corner is in
    // at most `SETTLE_MAX_TRIANGLES` < 16 triangles), added and removed a
    // triangle at a time with one addition: each triangle's corners as
    // ones in their counts.
    debug_assert!(tris.len() <= SETTLE_MAX_TRIANGLES && SETTLE_MAX_TRIANGLES < 16);
    let mut corners = 0u32;
    let mut ones = [0u32; 16];
    for (n, t) in ones.iter_mut().zip(tris) {
        *n = t.iter().fold(0, |n, &j| n | (1 << (4 * j)));
    }
    // `bare` with a one in each of its corners' counts.
    let bare = (0..8).fold(0u32, |b, j| b | (u32::from((bare >> j) & 1) << (4 * j)));
    // Bare cubes in no triangle: the bare counts that are zero, summed
    // into the top count by a multiplication (at most 8: no carry).
    let uncovered = |corners: u32| {
        let some = (corners | (corners >> 1) | (corners >> 2) | (corners >> 3)) & 0x1111_1111;
        (bare & !some).wrapping_mul(0x1111_1111) >> 28
    };
    // The key, packed in a word whose order is the tuple's: holes (≤ 18),
    // bare cubes left (≤ 8), surplus (< 2^20: at most 18 edges of a few
    // dozen triangles each), differing from `keep`, triangles (≤ 16), the
    // subset. A minimum without a branch per subset, and no `count_ones`
    // (software on the baseline x86-64 target): the triangles are counted
    // as they come and go.
    let key = |sub: u16, ntri: u32, holes: u32, surplus: u32, corners: u32| {
        debug_assert!(holes < 32 && surplus < 1 << 20 && ntri < 32);
        (u64::from(holes) << 46)
            | (u64::from(uncovered(corners)) << 42)
            | (u64::from(surplus) << 22)
            | (u64::from(sub != keep) << 21)
            | (u64::from(ntri) << 16)
            | u64::from(sub)
    };
    let (mut sub, mut ntri) = (0u16, 0u32);
    let mut best = key(sub, ntri, holes, surplus, corners);
    for g in 1..=u32::from(all_bits(tris.len())) {
        let i = g.trailing_zeros() as usize;
        sub ^= 1 << i;
        let add = sub & (1 << i) != 0;
        // +1 or −1.
        let d = if add { 1 } else { u32::MAX };
        ntri = ntri.wrapping_add(d);
        corners = corners.wrapping_add(ones[i].wrapping_mul(d));
        if !built[i] {
            for &e in &tri_edges[i] {
                let e = e & 31;
                let old = count[e];
                let new = old.wrapping_add(d);
                count[e] = new;
                holes = holes + u32::from(new == 1) - u32::from(old == 1);
                surplus = surplus + new.saturating_sub(2) - old.saturating_sub(2);
            }
        }
        best = best.min(key(sub, ntri, holes, surplus, corners));
    }
    best as u16
}

/// How §6.2 resolves an ambiguous configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Split {
    /// No usable cycle: build the whole hull (hole-free, non-manifold).
    Whole,
    /// The shared edges are exactly one Hamiltonian cycle (the paper's
    /// case): either disc (bit `i`: triangle `i`; the other disc is the
    /// complement); the smoother one is built.
    Either(u16),
    /// The shared edges hold exactly one Hamiltonian cycle plus edges
    /// interior to one of its discs: the other disc is built, whose
    /// interior edges no neighbour uses.
    Only(u16),
    /// As `Only`, but a shared edge inside the other disc is in one
    /// neighbour's graph only, so leaving it would open a hole: the disc
    /// holding it is built, provided the neighbours close its rim (the
    /// cycle, second field) and no neighbour's triangle uses an edge inside
    /// the disc left out; checked once the level is scanned.
    Holding(u16, u32),
}

/// §6.2's disambiguation of the solid `tris` of configuration `mask`,
/// `shared` being the edges of `G_i` that overlapping neighbourhoods also
/// have. The paper accepts the shared edges when they form one Hamiltonian
/// cycle. Departure: when they hold exactly one Hamiltonian cycle and more
/// (the frequent failure on thinned surfaces: five of a tetrahedron's six
/// edges), the cycle still cuts the hull in two discs, and the disc whose
/// interior edges are all unshared is built: the other one, or the whole
/// hull, would put a third triangle on a shared edge.
fn split_by_cycle(mask: u8, shared: u32, twice: u32, tris: &[[u8; 3]]) -> Split {
    debug_assert!(tris.len() <= 16);
    let Some(cycle) = unique_hamiltonian_cycle(mask, shared) else {
        return Split::Whole;
    };
    let on_cycle = |a: u8, b: u8| cycle & (1 << pair(a, b)) != 0;
    // Flood the triangles without crossing the cycle.
    let mut disc = 1u16;
    let mut stack = [0u8; 16];
    let mut top = 1;
    let edge_of = |t: &[u8; 3], k: usize| (t[k], t[(k + 1) % 3]);
    while top > 0 {
        top -= 1;
        let i = stack[top] as usize;
        for k in 0..3 {
            let (a, b) = edge_of(&tris[i], k);
            if on_cycle(a, b) {
                continue;
            }
            for (j, tj) in tris.iter().enumerate() {
                if disc & (1 << j) == 0 && (0..3).any(|m| edge_of(tj, m) == (b, a)) {
                    disc |= 1 << j;
                    stack[top] = j as u8;
                    top += 1;
                }
            }
        }
    }
    let all = ((1u32 << tris.len()) - 1) as u16;
    if disc == all {
        return Split::Whole;
    }
    // The shared edges inside a disc (off the cycle).
    let interior_shared = |d: u16| {
        let mut e = 0u32;
        for (i, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = edge_of(t, k);
                if d & (1 << i) != 0 && !on_cycle(a, b) {
                    e |= shared & (1 << pair(a, b));
                }
            }
        }
        e
    };
    // A disc may be left out when the shared edges inside it keep two
    // neighbours' triangles each: leaving them to the neighbours opens no
    // hole there.
    let leave = |e: u32| e & !twice == 0;
    // Otherwise the disc holding them is built, on trial: the edges inside
    // it carry its two triangles plus the neighbours' (non-manifold, as the
    // whole hull would make them), but the rest of the hull gains none; its
    // rim, the cycle, must be closed by the neighbours, which `triangulate`
    // checks afterwards, adding the other disc where one is not.
    let other = all & !disc;
    match (interior_shared(disc), interior_shared(other)) {
        (0, 0) => Split::Either(disc),
        (0, e) if leave(e) => Split::Only(disc),
        (e, 0) if leave(e) => Split::Only(other),
        (0, _) => Split::Holding(other, cycle),
        (_, 0) => Split::Holding(disc, cycle),
        _ => Split::Whole,
    }
}

/// The Hamiltonian cycle through the ON cubes of `mask` made of `shared`
/// edges (as pair bits), if there is exactly one.
fn unique_hamiltonian_cycle(mask: u8, shared: u32) -> Option<u32> {
    let n = mask.count_ones() as usize;
    if n < 3 || (shared.count_ones() as usize) < n {
        return None;
    }
    let mut search = CycleSearch {
        mask,
        shared,
        n,
        path: [mask.trailing_zeros() as u8; 8],
        found: None,
        count: 0,
    };
    search.walk(1);
    if search.count == 1 {
        search.found
    } else {
        None
    }
}

/// Depth-first search over the simple paths of shared edges from the
/// first ON cube; each cycle is met twice (once per direction).
struct CycleSearch {
    mask: u8,
    shared: u32,
    n: usize,
    path: [u8; 8],
    found: Option<u32>,
    count: usize,
}

impl CycleSearch {
    fn has(&self, a: u8, b: u8) -> bool {
        a != b && self.shared & (1 << pair(a, b)) != 0
    }

    fn walk(&mut self, len: usize) {
        let last = self.path[len - 1];
        if len == self.n {
            if self.has(last, self.path[0]) {
                let mut c = 1u32 << pair(last, self.path[0]);
                for k in 1..self.n {
                    c |= 1 << pair(self.path[k - 1], self.path[k]);
                }
                if self.found != Some(c) {
                    self.count += 1;
                }
                self.found = Some(c);
            }
            return;
        }
        for b in 0..8u8 {
            if self.mask & (1 << b) != 0 && !self.path[..len].contains(&b) && self.has(last, b) {
                self.path[len] = b;
                self.walk(len + 1);
                if self.count > 1 {
                    return;
                }
            }
        }
    }
}

/// Whether the disc `disc` of `tris` (bit `i`: triangle `i`) has a mean
/// dihedral angle over its interior edges no larger than its complement's
/// (§6.2's choice). `adjacent` lists the hull's pairs of triangles that
/// share an edge ([`crate::triangulation_table::Config::adjacent`]); an
/// interior edge of a disc is one whose two triangles are both in it.
/// Discs with one interior edge each (`C_6`, the frequent case) compare
/// cosines, no `acos` needed.
fn smoother_disc(
    tris: &[[u8; 3]],
    adjacent: &[(u8, u8)],
    disc: u16,
    pos: &impl Fn(u8) -> Vec3,
) -> bool {
    // A tetrahedron (`C_6`, the frequent case) splits into two discs of
    // two triangles each, one interior edge apiece: the general count
    // below, with its 16-slot arrays, comes down to two dihedral cosines
    // (the same products in the same order, so the same bits).
    // (`count_ones` is a dozen instructions without the popcnt
    // extension, which the baseline x86-64 target lacks.)
    let two_bits = |d: u16| {
        let rest = d & d.wrapping_sub(1);
        (rest != 0) & (rest & rest.wrapping_sub(1) == 0)
    };
    if (tris.len() == 4) & two_bits(disc) {
        let [x, y, z] = hull_normals4([tris[0], tris[1], tris[2], tris[3]], pos);
        // `Vec3::dot`'s order.
        let cosine = |d: u16| {
            let (i, j) = (
                d.trailing_zeros() as usize & 3,
                (15 - d.leading_zeros()) as usize & 3,
            );
            ((x[i] * x[j]) + (y[i] * y[j]) + (z[i] * z[j])).clamp(-1.0, 1.0)
        };
        return cosine(disc & 15) >= cosine(!disc & 15);
    }
    let mut normals = [Vec3::ZERO; 16];
    for (i, t) in tris.iter().enumerate().take(16) {
        normals[i] = hull_normal(*t, pos);
    }
    // Cosines of the interior edges of each side.
    let mut cos = [[0.0f32; 16]; 2];
    let mut n = [0usize; 2];
    for &(i, j) in adjacent {
        let (i, j) = (usize::from(i), usize::from(j));
        let side = usize::from(disc & (1 << i) == 0);
        if usize::from(disc & (1 << j) == 0) != side || n[side] == 16 {
            continue;
        }
        cos[side][n[side]] = normals[i].dot(normals[j]).clamp(-1.0, 1.0);
        n[side] += 1;
    }
    if n == [1, 1] {
        return cos[0][0] >= cos[1][0];
    }
    let mean = |c: &[f32]| {
        if c.is_empty() {
            0.0
        } else {
            c.iter().map(|x| x.acos()).sum::<f32>() / c.len() as f32
        }
    };
    mean(&cos[0][..n[0]]) <= mean(&cos[1][..n[1]])
}

/// §6.3: merge the cubes joined by short edges (positions and attributes
/// averaged), drop the triangles that collapse.
fn decimate_merge(mesh: &mut TriMesh, faces: &mut Vec<[u32; 3]>, merges: &[(u32, u32)]) {
    let n = mesh.positions.len();
    let mut uf = UnionFind::new(n);
    for &(a, b) in merges {
        uf.union(a, b);
    }
    let root: Vec<u32> = (0..n as u32).map(|v| uf.find(v)).collect();
    let mut sum = vec![Vec3::ZERO; n];
    let mut count = vec![0u32; n];
    let mut col = vec![[0u32; 4]; n];
    for v in 0..n {
        let r = root[v] as usize;
        sum[r] += mesh.positions[v];
        count[r] += 1;
        if let Some(c) = &mesh.colors {
            for k in 0..4 {
                col[r][k] += u32::from(c[v][k]);
            }
        }
    }
    for v in 0..n {
        let r = root[v] as usize;
        mesh.positions[v] = sum[r] / count[r] as f32;
        if let Some(c) = mesh.colors.as_mut() {
            c[v] = col[r].map(|x| (x / count[r]) as u8);
        }
    }
    for f in faces.iter_mut() {
        *f = f.map(|v| root[v as usize]);
    }
    faces.retain(|f| f[0] != f[1] && f[1] != f[2] && f[0] != f[2]);
}

/// Drops the second of two identical triangles among `candidates` (solid
/// triangles on a face of their neighbourhood); returns the indices
/// dropped, in increasing order.
fn dedupe_face_triangles(faces: &mut Vec<[u32; 3]>, candidates: &[u32]) -> Vec<u32> {
    // Candidates come in increasing order (pushed as the faces grow), so
    // the first one seen of each vertex set is the lowest index: keep it,
    // drop later copies. An open-addressed set of candidates, keyed by the
    // sorted vertices, replaces a sort of all candidates; the keys are
    // gathered first, in one forward pass, so that a probe reads this
    // small array instead of a random place of `faces`.
    debug_assert!(candidates.windows(2).all(|w| w[0] < w[1]));
    let mut dropped = Vec::new();
    if candidates.len() > 1 {
        let keys: Vec<[u32; 3]> = candidates
            .iter()
            .map(|&i| sorted_tri(faces[i as usize]))
            .collect();
        let bits = (2 * candidates.len()).next_power_of_two().trailing_zeros();
        let mask = (1usize << bits) - 1;
        let mut slots = vec![NONE; mask + 1];
        for (p, k) in keys.iter().enumerate() {
            let h = (u64::from(k[0]) | (u64::from(k[1]) << 21) | (u64::from(k[2]) << 42))
                .wrapping_mul(0x9e37_79b9_7f4a_7c15);
            let mut at = (h >> (64 - bits)) as usize;
            loop {
                let q = slots[at];
                if q == NONE {
                    slots[at] = p as u32;
                    break;
                }
                if keys[q as usize] == *k {
                    dropped.push(candidates[p]);
                    break;
                }
                at = (at + 1) & mask;
            }
        }
    }
    remove_sorted(faces, &dropped);
    dropped
}

/// Removes the elements at the increasing indices `drop` from `v`: the
/// runs between them move down, those before the first stay put (a
/// `retain` tested every element, a few drops among all the faces).
fn remove_sorted<T: Copy>(v: &mut Vec<T>, drop: &[u32]) {
    let Some(&first) = drop.first() else {
        return;
    };
    let mut to = first as usize;
    for (k, &d) in drop.iter().enumerate() {
        let end = drop.get(k + 1).map_or(v.len(), |&n| n as usize);
        v.copy_within(d as usize + 1..end, to);
        to += end - d as usize - 1;
    }
    v.truncate(to);
}

fn edge_key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

/// Sorted `(edge key, triangle)` pairs of every triangle side.
fn sorted_sides(faces: &[[u32; 3]]) -> Vec<(u64, u32)> {
    let mut sides: Vec<(u64, u32)> = Vec::with_capacity(faces.len() * 3);
    for (i, f) in faces.iter().enumerate() {
        for k in 0..3 {
            sides.push((edge_key(f[k], f[(k + 1) % 3]), i as u32));
        }
    }
    sides.sort_unstable();
    sides
}

/// Triangles incident to an edge that more than two triangles use (the
/// strict count; Table 1 counts non-manifold *local triangulations*, see
/// [`TriangulationStats::fallbacks`]).
pub fn non_manifold_triangles(mesh: &TriMesh) -> usize {
    non_manifold_flags(mesh).iter().filter(|b| **b).count()
}

/// Per triangle: whether it is incident to an edge used more than twice.
pub fn non_manifold_flags(mesh: &TriMesh) -> Vec<bool> {
    let sides = sorted_sides(&mesh.faces);
    let mut bad = vec![false; mesh.faces.len()];
    let mut i = 0;
    while i < sides.len() {
        let mut j = i;
        while j < sides.len() && sides[j].0 == sides[i].0 {
            j += 1;
        }
        if j - i > 2 {
            for s in &sides[i..j] {
                bad[s.1 as usize] = true;
            }
        }
        i = j;
    }
    bad
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octree::Frame;

    /// A thin spherical shell of cubes at `level`, Morton-sorted, crossing
    /// many bricks (and the grid's lower faces when `offset` is 0).
    fn shell(level: u8, offset: f32) -> LevelSurface {
        let side = 1u32 << level;
        let c = side as f32 * 0.5 - offset;
        let r = side as f32 * 0.42;
        let mut cells = Vec::new();
        for z in 0..side {
            for y in 0..side {
                for x in 0..side {
                    let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5 - c;
                    if (p.length() - r).abs() < 0.5 {
                        cells.push(morton([x, y, z]));
                    }
                }
            }
        }
        cells.sort_unstable();
        let frame = Frame {
            origin: Vec3::ZERO,
            size: 1.0,
        };
        let positions = cells
            .iter()
            .map(|&m| frame.cell_centre(unmorton(m), u32::from(level)))
            .collect();
        LevelSurface {
            level,
            frame,
            cells,
            positions,
            colours: None,
            normals: None,
        }
    }

    /// Configuration counts by brute force: every origin next to an ON cube.
    fn brute_force_configurations(s: &LevelSurface) -> Vec<u64> {
        let on: std::collections::HashSet<[i64; 3]> = s
            .cells
            .iter()
            .map(|&m| unmorton(m).map(i64::from))
            .collect();
        let mut origins = std::collections::BTreeSet::new();
        for c in &on {
            for j in 0..8u8 {
                let k = corner(j);
                origins.insert([
                    c[0] - i64::from(k[0]),
                    c[1] - i64::from(k[1]),
                    c[2] - i64::from(k[2]),
                ]);
            }
        }
        let mut counts = vec![0u64; CLASS_COUNT + 1];
        for o in origins {
            let mut mask = 0u8;
            for j in 0..8u8 {
                let k = corner(j);
                let p = [
                    o[0] + i64::from(k[0]),
                    o[1] + i64::from(k[1]),
                    o[2] + i64::from(k[2]),
                ];
                if on.contains(&p) {
                    mask |= 1 << j;
                }
            }
            counts[table().configs[mask as usize].class as usize] += 1;
        }
        counts[0] = 0;
        counts
    }

    #[test]
    fn brick_scan_visits_every_neighbourhood_exactly_once() {
        // Shells touching the grid's lower faces and shells away from
        // them, at levels below, at and above one brick per axis.
        for (level, offset) in [(3, 0.0), (4, 0.3), (5, 0.0), (6, 1.7), (6, 0.0)] {
            let s = shell(level, offset);
            let t = triangulate(&s, &TriangulateOptions::DEFAULT);
            assert_eq!(
                t.stats.configurations,
                brute_force_configurations(&s),
                "level {level}, offset {offset}"
            );
            assert!(t.stats.triangles > 0);
        }
    }

    #[test]
    fn unsorted_cells_triangulate_like_sorted_ones() {
        let s = shell(5, 0.3);
        let opts = TriangulateOptions {
            orient: false,
            ..TriangulateOptions::DEFAULT
        };
        let sorted = triangulate(&s, &opts);
        // Reverse the cubes: vertex i becomes n − 1 − i.
        let n = s.cells.len() as u32;
        let mut rev = s.clone();
        rev.cells.reverse();
        rev.positions.reverse();
        let reversed = triangulate(&rev, &opts);
        let canon = |faces: &[[u32; 3]], map: &dyn Fn(u32) -> u32| {
            let mut f: Vec<[u32; 3]> = faces
                .iter()
                .map(|t| {
                    let mut t = t.map(map);
                    t.sort_unstable();
                    t
                })
                .collect();
            f.sort_unstable();
            f
        };
        assert_eq!(
            canon(&sorted.mesh.faces, &|v| v),
            canon(&reversed.mesh.faces, &|v| n - 1 - v)
        );
        assert_eq!(sorted.stats.configurations, reversed.stats.configurations);
    }

    #[test]
    fn tetrahedron_with_a_fifth_shared_edge_builds_the_disc_that_leaves_it_to_two_neighbours() {
        // C_6: a face triangle 0, 1, 2 and the opposite corner 7.
        let mask = 0b1000_0111u8;
        let cfg = &table().configs[mask as usize];
        assert_eq!(cfg.class, 6);
        let Shape::Solid(tris) = &cfg.shape else {
            panic!("C_6 is solid")
        };
        let e = |a: u8, b: u8| 1u32 << pair(a, b);
        let cycle = e(0, 1) | e(1, 7) | e(7, 2) | e(2, 0);
        // The paper's case: either disc, chosen by dihedral angle.
        assert!(matches!(
            split_by_cycle(mask, cycle, 0, tris),
            Split::Either(_)
        ));
        // The face diagonal 1–2 shared too, by two neighbours: build the
        // disc around the body diagonal 0–7, which no neighbour has.
        let shared = cycle | e(1, 2);
        let Split::Only(keep) = split_by_cycle(mask, shared, e(1, 2), tris) else {
            panic!("one disc left")
        };
        let built: Vec<[u8; 3]> = (0..tris.len())
            .filter(|i| keep & (1 << i) != 0)
            .map(|i| tris[i])
            .collect();
        assert_eq!(built.len(), 2);
        assert!(built.iter().all(|t| t.contains(&0) && t.contains(&7)));
        // Shared by one neighbour only: leaving it would open a hole, so
        // the disc holding it is built on trial, its rim the cycle.
        let Split::Holding(keep, rim) = split_by_cycle(mask, shared, 0, tris) else {
            panic!("the disc holding 1–2 is tried")
        };
        assert_eq!(rim, cycle);
        assert_eq!(keep.count_ones(), 2);
        assert!(
            (0..tris.len())
                .filter(|i| keep & (1 << i) != 0)
                .all(|i| tris[i].contains(&1) && tris[i].contains(&2))
        );
        // Every edge shared: several cycles, no choice.
        assert_eq!(
            split_by_cycle(mask, cfg.edges, cfg.edges, tris),
            Split::Whole
        );
    }

    #[test]
    fn face_triangle_dedupe_keeps_the_first_copy_in_any_vertex_order() {
        let mut faces = vec![
            [0, 1, 2],
            [5, 6, 7],
            [2, 0, 1],
            [1, 2, 3],
            [7, 5, 6],
            [0, 2, 1],
        ];
        // Triangle 1 is not a candidate: its copy 4 is kept.
        let dropped = dedupe_face_triangles(&mut faces, &[0, 2, 3, 4, 5]);
        assert_eq!(dropped, [2, 5]);
        assert_eq!(faces, [[0, 1, 2], [5, 6, 7], [1, 2, 3], [7, 5, 6]]);
    }

    #[test]
    fn owned_surfaces_triangulate_like_borrowed_ones() {
        use crate::{DecodeOptions, EncodeOptions, decode, encode};
        let model = lodkit_mesh::Model::Mesh(lodkit_mesh::shapes::blob(5_000));
        let opts = EncodeOptions {
            depth: Some(5),
            ..EncodeOptions::DEFAULT
        };
        let bytes = encode(&model, &opts).unwrap().bytes;
        let d = decode(&bytes, &DecodeOptions::default()).unwrap();
        // Coarse levels hold phantoms (their cells are filtered), the
        // finest none (its cells move).
        for r in [3u8, 5] {
            let s = d.surface(r).unwrap();
            let owned = d.clone().into_surface(r).unwrap();
            assert_eq!(owned.cells, s.cells, "level {r}");
            assert_eq!(owned.positions, s.positions, "level {r}");
            let t = triangulate(&s, &TriangulateOptions::DEFAULT);
            let u = triangulate_owned(owned, &TriangulateOptions::DEFAULT);
            assert!(!t.mesh.faces.is_empty());
            assert_eq!(u.mesh.faces, t.mesh.faces, "level {r}");
            assert_eq!(u.mesh.positions, t.mesh.positions, "level {r}");
        }
    }

    /// Edges used by one triangle.
    fn boundary_edges(faces: &[[u32; 3]]) -> usize {
        let sides = sorted_sides(faces);
        let mut n = 0;
        let mut i = 0;
        while i < sides.len() {
            let mut j = i;
            while j < sides.len() && sides[j].0 == sides[i].0 {
                j += 1;
            }
            n += usize::from(j - i == 1);
            i = j;
        }
        n
    }

    #[test]
    fn settled_levels_are_manifold_where_thinned_and_open_no_hole() {
        use crate::{DecodeOptions, EncodeOptions, ThinningOptions, decode, encode};
        let thinning = ThinningOptions {
            outer: true,
            relax_below: 5,
        };
        for (name, mesh) in [
            ("blob", lodkit_mesh::shapes::blob(20_000)),
            ("torus", lodkit_mesh::shapes::torus(1.0, 0.3, 96, 48)),
        ] {
            let opts = EncodeOptions {
                depth: Some(7),
                thinning,
                ..EncodeOptions::DEFAULT
            };
            let e = encode(&lodkit_mesh::Model::Mesh(mesh), &opts).unwrap();
            let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
            for r in 2..=7u8 {
                let s = d.surface(r).unwrap();
                let plain = TriangulateOptions {
                    orient: false,
                    ..TriangulateOptions::DEFAULT
                };
                let t = triangulate(&s, &plain);
                // Decimation with a zero threshold merges nothing but
                // builds every solid at scan time, ambiguous ones whole:
                // the hole-free reference of §6.2.
                let whole = triangulate(
                    &s,
                    &TriangulateOptions {
                        decimate: Some(0.0),
                        ..plain
                    },
                );
                let nm = non_manifold_triangles(&t.mesh);
                let f = t.mesh.faces.len();
                assert!(
                    boundary_edges(&t.mesh.faces) <= boundary_edges(&whole.mesh.faces),
                    "{name} r={r}: settling opened a hole"
                );
                assert!(
                    nm <= non_manifold_triangles(&whole.mesh),
                    "{name} r={r}: {nm} non-manifold triangles"
                );
                if r >= thinning.relax_below {
                    assert!(nm * 100 <= f, "{name} r={r}: {nm} of {f} non-manifold");
                    let per = f as f64 / s.cells.len() as f64;
                    assert!(
                        (1.8..=2.3).contains(&per),
                        "{name} r={r}: {per} per particle"
                    );
                }
                // Same input, same triangles.
                assert_eq!(triangulate(&s, &plain).mesh.faces, t.mesh.faces);
            }
        }
    }
}
