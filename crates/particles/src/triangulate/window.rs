//! Bricks and windows — the data of §6.1.1's surface scan.
//!
//! The paper fetches the 3×3×3 window of parents around every parent cube
//! with an ON child and lays their children out in a 6×6×6 array.
//! Departure, for speed: the window is a brick of 8×8×8 cubes (the
//! Morton-sorted cubes of one aligned block, kept as bit sets, with the
//! vertex index of a cube being its brick's first index plus the ON cubes
//! before it), widened by two cubes on every side: 27 look-ups fetch 512
//! cubes' worth of neighbourhoods instead of 8, the configuration of a
//! neighbourhood is four row reads, and no hash lookup, allocation or
//! per-cube index array is needed.
use super::NONE;
use crate::octree::{MortonMap, morton, unmorton};

/// Bricks are 8×8×8 cubes of the level (`BRICK_BITS` per axis).
pub(super) const BRICK_BITS: u32 = 3;
/// Dense brick grids up to this many bricks per axis (R ≤ 10), a hash map
/// above.
pub(super) const DENSE_BRICKS: i64 = 128;
/// Extended window coordinate `E ∈ 0..12` (local `E − 2 ∈ −2..10`): the
/// brick it falls in (0: below, 1: this one, 2: above) and its local
/// coordinate there.
pub(super) const EXT_BRICK: [usize; 12] = [0, 0, 1, 1, 1, 1, 1, 1, 1, 1, 2, 2];
pub(super) const EXT_LOCAL: [usize; 12] = [6, 7, 0, 1, 2, 3, 4, 5, 6, 7, 0, 1];
/// Extended window side.
pub(super) const EXT: usize = 12;

/// The ON cubes of one brick, as bits in two orders.
#[derive(Clone, Copy)]
pub(super) struct Brick {
    /// Linear order: word `z`, bit `8y + x`.
    pub(super) lin: [u64; 8],
    /// Morton order of the local coordinates (eq. 1 within the brick),
    /// which is the order of the level's cubes.
    pub(super) mor: [u64; 8],
    /// Vertex index of the first cube of each Morton word.
    pub(super) base: [u32; 8],
}

/// An empty brick, for the empty places of a window.
pub(super) static EMPTY_BRICK: Brick = Brick {
    lin: [0; 8],
    mor: [0; 8],
    base: [0; 8],
};

/// Brick coordinates → brick number.
pub(super) struct BrickIndex {
    /// Bricks per axis.
    pub(super) side: i64,
    pub(super) dense: Vec<u32>,
    pub(super) sparse: MortonMap<u32>,
}

impl BrickIndex {
    #[inline]
    pub(super) fn new(level: u8, keys: &[u64]) -> BrickIndex {
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
    pub(super) fn get(&self, b: [i64; 3]) -> u32 {
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
pub(super) struct Window<'a> {
    pub(super) rows: [u16; EXT * EXT],
    /// The 27 bricks around (3×3×3, x fastest), NONE where empty.
    pub(super) bricks: [u32; 27],
    /// The same bricks, [`EMPTY_BRICK`] where empty (read without a
    /// branch).
    pub(super) around: [&'a Brick; 27],
    /// Vertex index of each ON cube a neighbourhood of the window's brick
    /// can have as a corner (extended coordinates `1..=10` per axis, x
    /// fastest; [`Window::fill_ids`]), stale elsewhere; a power of two long
    /// so that a masked index needs no bounds check.
    pub(super) ids: [u32; IDS],
}

/// The four low bytes of `x` in the four 16-bit parts of a word.
#[inline]
pub(super) fn spread_bytes(x: u64) -> u64 {
    let x = (x | (x << 16)) & 0x0000_ffff_0000_ffff;
    (x | (x << 8)) & 0x00ff_00ff_00ff_00ff
}

/// The scan's groups of four origin rows: first extended `y`, and a one
/// in the low bit of each row (16 bits) that is an origin row (`1..=9`).
pub(super) const ROW_GROUPS: [(usize, u64); 3] = [
    (1, 0x0001_0001_0001_0001),
    (5, 0x0001_0001_0001_0001),
    (9, 1),
];

/// Length of [`Window::ids`].
pub(super) const IDS: usize = 2048;

/// Extended index offset of each corner of a neighbourhood.
pub(super) const CORNER_OFFSET: [usize; 8] = [
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
pub(super) const REACHED: [(u8, u8, u64); 56] = {
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
pub(super) const BRICK_OFFSET: [usize; 27] = {
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

impl<'a> Window<'a> {
    /// An empty window.
    pub(super) fn new() -> Window<'a> {
        Window {
            rows: [0; EXT * EXT],
            bricks: [NONE; 27],
            around: [&EMPTY_BRICK; 27],
            ids: [0; IDS],
        }
    }

    /// Loads the brick `q` (brick key; its cubes `cells`, vertices from
    /// `first`) and the 26 around it: their bricks, the ids of every cube a
    /// neighbourhood of `q` can have as a corner, and the rows of bits.
    #[inline]
    pub(super) fn load(
        &mut self,
        q: u64,
        bricks: &'a [Brick],
        index: &BrickIndex,
        first: usize,
        cells: &[u64],
    ) {
        let qc = unmorton(q).map(i64::from);
        for k in 0..27 {
            self.bricks[k] = index.get([
                qc[0] + (k % 3) as i64 - 1,
                qc[1] + ((k / 3) % 3) as i64 - 1,
                qc[2] + (k / 9) as i64 - 1,
            ]);
        }
        for k in 0..27 {
            self.around[k] = match self.bricks[k] {
                NONE => &EMPTY_BRICK,
                n => &bricks[n as usize],
            };
        }
        self.fill_ids(first, cells);
        // Per extended z, the z-slab word of each brick of the 3×3 around
        // (a byte per row); four rows at a time, the bytes of each brick
        // along x spread to 16-bit rows and merged: the top two cubes of
        // the brick below, its eight, the bottom two of the brick above.
        for ez in 0..EXT {
            let (lz, b) = (EXT_LOCAL[ez], 9 * EXT_BRICK[ez]);
            // Bytes of extended rows `4g..4g + 4` of the bricks at `bx`.
            let bytes = |bx: usize| {
                let slab = |by: usize| self.around[b + 3 * by + bx].lin[lz];
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
                self.set_rows4(4 * g + EXT * ez, rows);
            }
        }
    }

    /// Configuration of the neighbourhood with origin `o` (extended
    /// coordinates, each in `0..10`).
    #[inline]
    pub(super) fn mask(&self, o: [usize; 3]) -> u8 {
        let row = |y: usize, z: usize| ((self.rows[y + EXT * z] >> o[0]) & 3) as u8;
        row(o[1], o[2])
            | (row(o[1] + 1, o[2]) << 2)
            | (row(o[1], o[2] + 1) << 4)
            | (row(o[1] + 1, o[2] + 1) << 6)
    }

    /// Rows `i..i + 4` (four consecutive `y` of one `z`), 16 bits each,
    /// first lowest.
    #[inline]
    pub(super) fn rows4(&self, i: usize) -> u64 {
        let r: &[u16; 4] = self.rows[i..i + 4].try_into().expect("four rows");
        u64::from(r[0])
            | (u64::from(r[1]) << 16)
            | (u64::from(r[2]) << 32)
            | (u64::from(r[3]) << 48)
    }

    /// Sets rows `i..i + 4` to the four 16-bit parts of `rows`, first
    /// lowest.
    #[inline]
    pub(super) fn set_rows4(&mut self, i: usize, rows: u64) {
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
    pub(super) fn block(&self, o: [usize; 3]) -> u64 {
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
    #[inline]
    pub(super) fn fill_ids(&mut self, first: usize, cells: &[u64]) {
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
    pub(super) fn corners(&self, o: [usize; 3], mask: u8) -> [u32; 8] {
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
pub(super) fn owns(w: &Window, o: [usize; 3], below: u8) -> bool {
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
pub(super) const MORTON_TO_LINEAR: [u16; 512] = {
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
pub(super) const MORTON_TO_EXT: [u16; 512] = {
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
#[inline]
pub(super) fn bricks_of(cells: &[u64]) -> (Vec<Brick>, Vec<u64>) {
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

/// The occupied bricks of a level, in Morton order, and their index.
pub(super) struct Bricks {
    pub(super) bricks: Vec<Brick>,
    /// Brick keys (cell code without its low `3 · BRICK_BITS` bits).
    pub(super) keys: Vec<u64>,
    pub(super) index: BrickIndex,
}

impl Bricks {
    /// The bricks of level `level`'s cells (strictly increasing Morton
    /// codes).
    #[inline]
    pub(super) fn of(level: u8, cells: &[u64]) -> Bricks {
        let (bricks, keys) = bricks_of(cells);
        let index = BrickIndex::new(level, &keys);
        Bricks {
            bricks,
            keys,
            index,
        }
    }
}
