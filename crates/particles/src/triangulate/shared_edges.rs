//! Shared edges — the evidence §6.2 of Yemez & Schmitt cuts a solid's hull
//! with: the edges of a configuration's graph `G_i` that the graphs of its
//! overlapping neighbourhoods also have.
use std::sync::OnceLock;

use crate::triangulation_table::{corner, pair, table};

/// For each of the 26 overlapping neighbourhoods `o + d` (index
/// `(dx+1) + 3(dy+1) + 9(dz+1)`): its corners that lie in this block, and
/// its corner pairs inside the overlap with the same pairs in this
/// block's numbering.
pub(super) struct Overlaps {
    pub(super) corners: [u8; 27],
    /// `(its pair bit, our pair bit)` for each corner pair of the overlap:
    /// six for a neighbour across a face, one across an edge (the rest
    /// zero), none across a corner.
    pub(super) pairs: [[(u32, u32); 6]; 27],
    /// Per configuration, the neighbours whose overlap holds an edge of
    /// its graph `G_i` (bit `k`; never the configuration itself, 13).
    pub(super) near: [u32; 256],
}

/// The neighbours across a face (a 2×2 overlap, six corner pairs), as
/// bits `k` of [`Overlaps::near`]; the others with an overlap pair are
/// across an edge (one pair).
pub(super) const ACROSS_FACE: u32 = 1 << 4 | 1 << 10 | 1 << 12 | 1 << 14 | 1 << 16 | 1 << 22;

#[inline]
pub(super) fn overlaps() -> &'static Overlaps {
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
/// fits the second-level cache; fewer slots miss more, more cost fresh
/// pages (the `pop` bench decides).
pub(super) const SHARED_MEMO_BITS: u32 = 13;

/// Edges of `G_i` (as pair bits) of the configuration `mask` also in the
/// graph of an overlapping neighbourhood, and those in the graphs of two or
/// more. `around`: the 4×4×4 cubes of [`Window::block`], all that the
/// neighbourhoods read. Without a branch on the neighbours' configurations
/// (what a branch predictor cannot guess): fixed steps per neighbour.
#[inline]
pub(super) fn shared_edges(around: u64, mask: u8) -> (u32, u32) {
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
