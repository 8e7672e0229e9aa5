//! The context layout: which adaptive model codes each symbol of the
//! entropy mode (the baseline's raw bits ignore contexts).
//!
//! One flat numbering for the whole stream: occupancy, phantom flags, leaf
//! paths, precision bits, column flags and depths, predicted heights, then
//! the attribute bits. The occupancy tables below turn a parent's
//! neighbourhood (coded before it, in Morton order) into a child's context
//! with table look-ups instead of branches.

/// Deepest column (tangential bits coded below `R` before the implied
/// middle) the entropy mode signals ([`super::precision_layers`]); one
/// context per step of its unary depth.
pub const MAX_COLUMN_DEPTH: u8 = 2;

pub(crate) const OCC_STATES: usize = 3 * 8 * 8 * 8 * 3;
pub(crate) const OCC: usize = 0;
pub(crate) const FLAG: usize = OCC + OCC_STATES;
pub(crate) const FLAG_STATES: usize = 2 * 8 * 4;
pub(crate) const PATH: usize = FLAG + FLAG_STATES;
pub(crate) const PATH_STATES: usize = 3 * 3 * 3 * 2;
pub(crate) const PREC: usize = PATH + PATH_STATES;
/// Entropy mode: axis × layer bucket × neighbours along it × normal axis
/// or not × 2 bits above (216); the plain layout, axis × 16 bits × 2 bits
/// above (192), fits inside.
pub(crate) const PREC_STATES: usize = 3 * 3 * 3 * 2 * 4;
/// Column flags: face neighbours along x, y, z (0–2 each).
pub(crate) const COL: usize = PREC + PREC_STATES;
pub(crate) const COL_STATES: usize = 27;
/// Column depth, unary: one context per step.
pub(crate) const COLK: usize = COL + COL_STATES;
/// Normal-axis bits of column particles: layer bucket × predicted height
/// bin × 2 bits above.
pub(crate) const PRED: usize = COLK + MAX_COLUMN_DEPTH as usize;
pub(crate) const PRED_STATES: usize = 3 * PRED_BINS * 4;
/// Bins of the height a column particle's neighbours predict
/// ([`crate::precision_coding`]).
pub(crate) const PRED_BINS: usize = 7;
/// First context of the attribute bits (see [`crate::attributes`]).
pub const ATTR: usize = PRED + PRED_STATES;
/// Contexts reserved for attributes: channel × component × 16 bit places,
/// plus correction bits.
pub const ATTR_STATES: usize = 2 * 3 * 16 + 2 * 3 * 3;
/// Total number of contexts an adaptive layer needs.
pub const NUM_CONTEXTS: usize = ATTR + ATTR_STATES;

/// The children (bit `k`: child `k`) on the upper side of their parent
/// along x, y, z.
pub(crate) const UPPER: [u8; 3] = [0xaa, 0xcc, 0xf0];

/// Per child `k` and set `known` of children below it (index `256k +
/// known`): bit `a` set when `k` is on the upper side of axis `a` and its
/// face neighbour towards −a, child `k − 2^a`, is in `known`.
pub(super) static SIBLINGS: [u8; 2048] = {
    let mut t = [0u8; 2048];
    let mut i = 0;
    while i < 2048 {
        let (k, known) = (i >> 8, i & 0xff);
        let mut a = 0;
        while a < 3 {
            let bit = 1 << a;
            if k & bit != 0 && known >> (k ^ bit) & 1 != 0 {
                t[i] |= bit as u8;
            }
            a += 1;
        }
        i += 1;
    }
    t
};

/// The part of child `k`'s occupancy context that the decisions below it
/// decide (index as [`SIBLINGS`]): its siblings behind it and how many
/// children are present so far (0, 1, 2 or more), in the layout of
/// [`code_level`]'s occupancy contexts.
pub(super) static OCC_KNOWN: [u16; 2048] = {
    let mut t = [0u16; 2048];
    let mut i = 0;
    while i < 2048 {
        let count = ((i & 0xff) as u32).count_ones();
        let count = if count > 2 { 2 } else { count };
        t[i] = SIBLINGS[i] as u16 * 24 + count as u16;
        i += 1;
    }
    t
};

/// Bit `k` of the index moved to bit `8k`: one byte per child.
pub(super) static SPREAD: [u64; 256] = {
    let mut t = [0u64; 256];
    let mut i = 0;
    while i < 256 {
        let mut k = 0;
        while k < 8 {
            t[i] |= ((i as u64 >> k) & 1) << (8 * k);
            k += 1;
        }
        i += 1;
    }
    t
};

/// Per axis `a` and children `m` of the parent's neighbour towards −a: in
/// byte `k`, bit `3 + a` set when child `k` is on the lower side of `a`
/// and its neighbour towards −a, that neighbour's child `k + 2^a`, is in
/// `m`.
pub(super) static BACK: [[u64; 256]; 3] = {
    let mut t = [[0u64; 256]; 3];
    let mut a = 0;
    while a < 3 {
        let mut m = 0;
        while m < 256 {
            let lower = !UPPER[a] as usize;
            t[a][m] = SPREAD[(m >> (1 << a)) & lower] << (3 + a);
            m += 1;
        }
        a += 1;
    }
    t
};

/// Per set of the parent's present face neighbours (bit `d`: across face
/// `d`): in byte `k`, bit `a` set when the neighbour on child `k`'s side
/// along `a` is present.
pub(super) static COARSE: [u64; 64] = {
    let mut t = [0u64; 64];
    let mut f = 0;
    while f < 64 {
        let mut a = 0;
        while a < 3 {
            let lo = if f >> a & 1 == 1 { !UPPER[a] } else { 0 };
            let hi = if f >> (a + 3) & 1 == 1 { UPPER[a] } else { 0 };
            t[f] |= SPREAD[(lo | hi) as usize] << a;
            a += 1;
        }
        f += 1;
    }
    t
};

/// The part of child `k`'s occupancy context that the parent decides,
/// index `256k + byte` with `byte` as in [`code_level`]'s `near` (state,
/// neighbours behind, parent's neighbours on its sides).
pub(super) static OCC_BASE: [u16; 2048] = {
    let mut t = [0u16; 2048];
    let mut i = 0;
    while i < 2048 {
        let (k, state, near) = (i >> 8, (i >> 6) & 3, i & 63);
        if state < 3 {
            t[i] = (OCC + ((state * 8 + k) * 64 + near) * 3) as u16;
        }
        i += 1;
    }
    t
};
