//! Particle attributes — §5.2, §5.4 and §5.5 of Yemez & Schmitt.
//!
//! * The **vertex** of a leaf is the mean of its samples on the 16-bit grid
//!   ([`crate::octree`]); a coarser kept node shows the vertex of the leaf
//!   that specifies it (§5.2), so vertices need no averaging.
//! * **Colour** and **normal** are averaged up the tree over the kept
//!   children only (eq. 3; phantoms carry nothing and their subtrees do not
//!   contribute). The mean is truncated to an integer and the remainder
//!   `Σ mod m` (`m ≤ 8` kept children, so 3 bits per component) is the
//!   correction of §5.5. The decoder receives the parent's value, the
//!   values of the `m − 1` new particles and the correction, and recovers
//!   the implicit child exactly by eq. (4): `c_k = m c + e − Σ_{j≠k} c_j`.
//!   Every level therefore decodes the attributes the encoder averaged,
//!   bit for bit.
//!
//! Normals are quantised to [`NORMAL_BITS`] per component as
//! `round((n + 1) · 127.5)` and averaged as integers (the mean vector,
//! renormalised for display) — §5.5 leaves the normal's bit size open.
use glam::Vec3;

use crate::coding::bit_coder::BitCoder;
use crate::coding::contexts::ATTR;
use crate::error::{Result, stream_err};
use crate::ordering::{HLevel, Hierarchy};

/// Bits per colour component (RGB888, §5.5).
pub const COLOUR_BITS: u32 = 8;
/// Bits per normal component.
pub const NORMAL_BITS: u32 = 8;

/// One attribute channel: three components of `bits` bits each.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    Colour,
    Normal,
}

impl Channel {
    pub fn bits(self) -> u32 {
        match self {
            Channel::Colour => COLOUR_BITS,
            Channel::Normal => NORMAL_BITS,
        }
    }
    fn slot(self) -> usize {
        match self {
            Channel::Colour => 0,
            Channel::Normal => 1,
        }
    }
}

/// Quantises a unit normal.
pub fn quantise_normal(n: Vec3) -> [u32; 3] {
    n.to_array()
        .map(|v| ((v.clamp(-1.0, 1.0) + 1.0) * 127.5).round() as u32)
}

/// Unit normal of quantised (possibly averaged) components.
pub fn dequantise_normal(q: [u32; 3]) -> Vec3 {
    Vec3::from_array(q.map(|v| v as f32 / 127.5 - 1.0)).normalize_or_zero()
}

/// Values of every node at every level plus the corrections of every kept
/// parent, computed bottom-up from the leaf values (eq. 3).
#[derive(Debug, Clone, Default)]
pub struct Averaged {
    pub values: Vec<Vec<[u32; 3]>>,
    pub corrections: Vec<Vec<[u32; 3]>>,
}

/// Eq. (3) with the §5.5 remainders. `leaf_values[i]` is the value of leaf
/// `i` of `h.levels[R]`.
pub fn average_up(h: &Hierarchy, leaf_values: &[[u32; 3]]) -> Averaged {
    let depth = h.depth as usize;
    let mut values = vec![Vec::new(); depth + 1];
    let mut corrections = vec![Vec::new(); depth + 1];
    values[depth] = leaf_values.to_vec();
    corrections[depth] = vec![[0; 3]; leaf_values.len()];
    for r in (0..depth).rev() {
        let n = h.levels[r].cells.len();
        let mut sum = vec![[0u64; 3]; n];
        let mut m = vec![0u64; n];
        let mut p = 0usize;
        for (i, &c) in h.levels[r + 1].cells.iter().enumerate() {
            while h.levels[r].cells[p] != c >> 3 {
                p += 1;
            }
            if h.levels[r + 1].phantom[i] {
                continue;
            }
            for k in 0..3 {
                sum[p][k] += u64::from(values[r + 1][i][k]);
            }
            m[p] += 1;
        }
        let mut v = vec![[0u32; 3]; n];
        let mut e = vec![[0u32; 3]; n];
        for i in 0..n {
            if h.levels[r].phantom[i] || m[i] == 0 {
                continue;
            }
            for k in 0..3 {
                v[i][k] = (sum[i][k] / m[i]) as u32;
                e[i][k] = (sum[i][k] % m[i]) as u32;
            }
        }
        values[r] = v;
        corrections[r] = e;
    }
    Averaged {
        values,
        corrections,
    }
}

/// Level 0: the root's value in full.
pub fn code_root<C: BitCoder>(coder: &mut C, ch: Channel, value: &mut [u32; 3]) -> Result<()> {
    for (k, v) in value.iter_mut().enumerate() {
        coder.bits(v, ch.bits(), ATTR + (ch.slot() * 3 + k) * 16)?;
    }
    Ok(())
}

/// Level `r ≥ 1` of one channel: per kept parent its correction (3 bits a
/// component), then the full values of the new particles among its
/// children; the implicit child follows from eq. (4). `values` (one per
/// node of `level`) is the truth for an encoder and filled in by a
/// decoder; `corrections` (per parent) only an encoder has.
pub fn code_level<C: BitCoder>(
    coder: &mut C,
    ch: Channel,
    parents: &HLevel,
    parent_values: &[[u32; 3]],
    level: &HLevel,
    values: &mut [[u32; 3]],
    corrections: Option<&[[u32; 3]]>,
) -> Result<()> {
    let bits = ch.bits();
    let corr_ctx = ATTR + 2 * 3 * 16 + ch.slot() * 9;
    let mut j = 0usize;
    for p in 0..parents.cells.len() {
        let start = j;
        while j < level.cells.len() && level.cells[j] >> 3 == parents.cells[p] {
            j += 1;
        }
        let kids = start..j;
        let kept_parent = !parents.phantom[p];
        let m = kids.clone().filter(|&i| !level.phantom[i]).count() as u64;
        let mut e = corrections.map(|c| c[p]).unwrap_or([0; 3]);
        if kept_parent {
            for (k, ek) in e.iter_mut().enumerate() {
                coder.bits(ek, 3, corr_ctx + k * 3)?;
                if u64::from(*ek) >= m.max(1) {
                    return stream_err("attribute correction exceeds the number of children");
                }
            }
        }
        let mut implicit = None;
        let mut sum = [0u64; 3];
        for i in kids {
            if level.phantom[i] {
                continue;
            }
            if kept_parent && level.particle[i] == parents.particle[p] {
                implicit = Some(i);
                continue;
            }
            for k in 0..3 {
                coder.bits(&mut values[i][k], bits, ATTR + (ch.slot() * 3 + k) * 16)?;
                sum[k] += u64::from(values[i][k]);
            }
        }
        if let Some(i) = implicit {
            for k in 0..3 {
                let total = m * u64::from(parent_values[p][k]) + u64::from(e[k]);
                let v = total.checked_sub(sum[k]).filter(|v| *v < (1u64 << bits));
                let Some(v) = v else {
                    return stream_err("attribute of an implicit child is out of range");
                };
                values[i][k] = v as u32;
            }
        }
    }
    Ok(())
}
