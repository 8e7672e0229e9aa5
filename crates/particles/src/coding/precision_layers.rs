//! Precision layers — §7.2 of Yemez & Schmitt (scalable precision), with
//! the entropy mode's surface columns and height prediction (beyond the
//! paper).
//!
//! Layer `b` (`R < b ≤ N`) adds bit `b` of every particle's three 16-bit
//! grid coordinates, particles in stream order. The baseline codes every
//! bit; the entropy mode ([`code_precision`] with a [`Faces`] table) codes
//! column particles' tangential coordinates only down to their column and
//! predicts their height from their neighbours'.
//!
//! Decoding speed: nearly every particle of a later layer is a column
//! particle coding one symbol, so the loop is arranged around that case —
//! its height predictors are a fixed four-slot row read without branching
//! on how many there are, and its tangential coordinates are settled once.
use super::bit_coder::BitCoder;
use super::contexts::{COL, COLK, MAX_COLUMN_DEPTH, PREC, PRED, PRED_BINS};
use super::links::{Links, NONE};
use crate::error::{Result, stream_err};
use crate::ordering::HLevel;

/// The particles' face neighbourhood at level `R`, for the entropy mode's
/// precision layers.
#[derive(Debug, Clone, Default)]
pub struct Faces {
    /// Per particle: its [`normal_axis`] (bits 0–1) and its face
    /// neighbours along x, y, z ([`faces_per_axis`], two bits each from
    /// bit 2).
    axes: Vec<u8>,
    /// Per particle: `0`, or `1 + k` for a column particle of depth `k`
    /// (see [`code_precision`]); set by the encoder, decoded in the first
    /// precision layer.
    pub column: Vec<u8>,
    /// Per particle: `1 +` its normal axis once the first precision layer
    /// has found it a column particle, else `0` — what a neighbour's
    /// predictors are filtered on, in one byte: a particle not yet reached
    /// in the first layer reads as no column, as it must.
    column_axis: Vec<u8>,
    /// Per particle: the particles across its four tangential faces (the
    /// faces whose axis is not its normal axis), in face order, the
    /// particle's own number where there is none. From the second
    /// precision layer on, a column particle's row holds only its height
    /// predictors (the column particles among them with its normal axis).
    tangential: Vec<[u32; 4]>,
    /// Per column particle, from the second layer on: its predictors
    /// (bits 0–3) and how many of them come before it (bits 4–7).
    counts: Vec<u8>,
    /// Precision layers coded so far (the second reduces `tangential` to
    /// the predictors, row by row as it goes).
    layers: u32,
    /// Per column particle: its height (normal coordinate) as far as coded,
    /// lower bits zero — a compact copy the predictions read.
    height: Vec<u16>,
}

impl Faces {
    pub fn is_empty(&self) -> bool {
        self.axes.is_empty()
    }

    /// Particle `i`'s [`normal_axis`].
    pub fn normal_axis(&self, i: usize) -> usize {
        usize::from(self.axes[i] & 3)
    }
}

/// The face neighbourhood of every particle, by particle number, from the
/// links [`crate::coding::levels::code_level`] leaves after level `R`
/// (entropy mode); empty when `links` does not describe `leaves`.
pub fn particle_faces(links: &Links, leaves: &HLevel, particles: usize) -> Faces {
    if links.len() != leaves.cells.len() {
        return Faces::default();
    }
    let mut out = Faces {
        axes: vec![0u8; particles],
        column: vec![0u8; particles],
        column_axis: vec![0u8; particles],
        tangential: vec![[0; 4]; particles],
        counts: vec![0u8; particles],
        layers: 0,
        height: vec![0u16; particles],
    };
    let (axes, tangential) = (&mut out.axes, &mut out.tangential);
    links.for_each_row(|i, row| add_faces(axes, tangential, &leaves.particle, i, &row));
    out
}

/// [`particle_faces`] of node `i` of level `R`, `row` its links.
#[inline(always)]
fn add_faces(
    axes: &mut [u8],
    tangential: &mut [[u32; 4]],
    particle: &[u32],
    i: usize,
    row: &[u32; 6],
) {
    let particles = axes.len();
    let p = particle[i] as usize;
    if p >= particles {
        return;
    }
    let mask = (0..6).fold(0u8, |m, d| m | u8::from(row[d] != NONE) << d);
    let info = AXES[usize::from(mask)];
    axes[p] = info;
    // The four faces off the normal axis `g`, in face order — 1, 2, 4, 5
    // (g = 0), 0, 2, 3, 5 (g = 1) or 0, 1, 3, 4 (g = 2) — picked with two
    // selects each rather than indexed, so the row stays in registers.
    let g = info & 3;
    let faces = [
        if g == 0 { row[1] } else { row[0] },
        if g == 2 { row[1] } else { row[2] },
        if g == 0 { row[4] } else { row[3] },
        if g == 2 { row[4] } else { row[5] },
    ];
    // A missing neighbour reads the particle itself; one outside the
    // particle table (a hostile stream) is no neighbour either. Selects
    // rather than branches: which faces have a neighbour is data.
    tangential[p] = faces.map(|node| {
        let j = particle[if node == NONE { i } else { node as usize }];
        if j as usize >= particles { p as u32 } else { j }
    });
}

/// [`normal_axis`] and [`faces_per_axis`] of every face mask, packed.
static AXES: [u8; 64] = {
    let mut t = [0u8; 64];
    let mut m = 0;
    while m < 64 {
        t[m] = pack_axes(m as u8);
        m += 1;
    }
    t
};

/// [`normal_axis`] and [`faces_per_axis`] of a face mask in one byte.
const fn pack_axes(mask: u8) -> u8 {
    let c = faces_per_axis(mask);
    normal_axis(mask) as u8 | c[0] << 2 | c[1] << 4 | c[2] << 6
}

/// Face neighbours along each axis (0–2) of a face mask (bit `d` set when
/// the leaf across face `d` is ON, `d = a` towards `−a`, `3 + a` towards
/// `+a`).
#[inline]
pub const fn faces_per_axis(mask: u8) -> [u8; 3] {
    [
        (mask & 1) + (mask >> 3 & 1),
        (mask >> 1 & 1) + (mask >> 4 & 1),
        (mask >> 2 & 1) + (mask >> 5 & 1),
    ]
}

/// The axis a leaf's surface most likely crosses — the one with the
/// fewest face neighbours (a surface spreads across its tangent axes);
/// ties go to the later axis. Encoder and decoder derive it alike.
#[inline]
pub const fn normal_axis(mask: u8) -> usize {
    let c = faces_per_axis(mask);
    let mut g = 2;
    if c[1] < c[g] {
        g = 1;
    }
    if c[0] < c[g] {
        g = 0;
    }
    g
}

/// Precision layer for bit `b` (1-based from the most significant of the
/// 16, `R < b`): one bit per coordinate of every particle. `q` holds 16-bit
/// coordinates; the encoder's are complete, the decoder's get bit `b` set.
///
/// Baseline (`faces` empty): every bit, contexts axis, layer and the two
/// bits above (a centroid near the middle of its cube reads 0111… or
/// 1000…, so they predict this one) — ignored by the raw layer.
///
/// Entropy mode (`faces` from [`particle_faces`]; the encoder fills
/// `faces.column` where [`crate::encode::Placement::SurfaceColumn`] placed
/// the vertex): the first layer codes each particle's column state —
/// not a column, or a column of depth `k ≤` [`MAX_COLUMN_DEPTH`] (a flag,
/// then `k` in unary). A column particle's two tangential coordinates
/// (axes other than its [`normal_axis`]) code their first `k` bits below
/// `R`, then are the middle of that sub-cell (`1` then zeros), never coded
/// again; its normal coordinate is coded in every layer with a context
/// from the height its neighbours predict (`height_bin`). Other bits are
/// conditioned on the axis, the layer (first, second, later), the leaf's
/// face neighbours along the axis, whether it is the normal axis, and the
/// two bits above.
pub fn code_precision<C: BitCoder>(
    coder: &mut C,
    depth: u8,
    b: u32,
    q: &mut [[u32; 3]],
    faces: &mut Faces,
) -> Result<()> {
    let shift = 16 - b;
    let layer = (b as usize).min(16) - 1;
    if faces.is_empty() && coder.context_free() {
        // The three bits of a particle, axis 0 first, read at once.
        for v in q.iter_mut() {
            let mut bits = v
                .iter()
                .fold(0u32, |acc, &c| (acc << 1) | ((c >> shift) & 1));
            coder.bits(&mut bits, 3, PREC)?;
            for (a, c) in v.iter_mut().enumerate() {
                let bit = (bits >> (2 - a)) & 1;
                *c = (*c & !(1 << shift)) | (bit << shift);
            }
        }
        return Ok(());
    }
    if faces.is_empty() {
        for v in q.iter_mut() {
            for (a, c) in v.iter_mut().enumerate() {
                let mut bit = (*c >> shift) & 1 == 1;
                let above = ((*c >> (shift + 1)) & 3) as usize;
                coder.bit(&mut bit, PREC + (a * 16 + layer) * 4 + above)?;
                *c = (*c & !(1 << shift)) | (u32::from(bit) << shift);
            }
        }
        return Ok(());
    }
    let n = q.len();
    if faces.axes.len() != n
        || faces.column.len() != n
        || faces.column_axis.len() != n
        || faces.tangential.len() != n
        || faces.height.len() != n
        || faces.counts.len() != n
    {
        return stream_err("precision layer: face table does not match the particles");
    }
    // 1-based layer below the leaf.
    let rel = b.saturating_sub(u32::from(depth));
    if rel != faces.layers + 1 {
        return stream_err(format!(
            "precision layer {b} follows {} layers below the leaves",
            faces.layers
        ));
    }
    faces.layers = rel;
    let first_layer = rel == 1;
    // Layer bucket: the first bits below the leaf are the informative ones.
    let lb = (rel.saturating_sub(1) as usize).min(2);
    // The plain context of axis `a` without the two bits above.
    let plain = |a: usize, info: u8, g: usize| {
        let cnt = usize::from((info >> (2 + 2 * a)) & 3);
        PREC + ((((a * 3 + lb) * 3 + cnt) * 2 + usize::from(a == g)) * 4)
    };
    let above = |c: u32| ((c >> (shift + 1)) & 3) as usize;
    let pred_ctx = PRED + lb * PRED_BINS * 4;
    let Faces {
        axes,
        column,
        column_axis,
        tangential,
        height,
        counts,
        ..
    } = faces;
    for i in 0..n {
        let info = axes[i];
        let g = usize::from(info & 3);
        // A particle codes at most a column flag, two depth decisions and
        // three coordinates: one budget check covers them.
        coder.reserve(6)?;
        if first_layer {
            let col = &mut column[i];
            let mut is_column = *col != 0;
            let ctx = COL
                + usize::from(info >> 2 & 3) * 9
                + usize::from(info >> 4 & 3) * 3
                + usize::from(info >> 6);
            coder.bit_reserved(&mut is_column, ctx)?;
            if is_column {
                let want = col.saturating_sub(1);
                let mut k = 0u8;
                while k < MAX_COLUMN_DEPTH {
                    let mut deeper = want > k;
                    coder.bit_reserved(&mut deeper, COLK + k as usize)?;
                    if !deeper {
                        break;
                    }
                    k += 1;
                }
                *col = 1 + k;
                // The leaf's bits of the height are known from the structure.
                height[i] = ((q[i][g] >> (shift + 1)) << (shift + 1)) as u16;
            } else {
                *col = 0;
            }
        }
        let col = column[i];
        if col == 0 {
            for a in 0..3 {
                let c = q[i][a];
                let mut bit = (c >> shift) & 1 == 1;
                coder.bit_reserved(&mut bit, plain(a, info, g) + above(c))?;
                q[i][a] = (c & !(1 << shift)) | (u32::from(bit) << shift);
            }
            continue;
        }
        // The predictors this particle's height is read against: the
        // column particles of its tangential faces with its normal axis —
        // in the first layer only the earlier ones (the later ones are not
        // decoded yet). The second layer keeps the row reduced to them, so
        // the later layers read it as it is (the relation is symmetric:
        // each pair is seen from both sides). In the first layer the later
        // particles' and this one's `column_axis` are still `0`.
        let (pred, count) = if rel <= 2 {
            let mut p = tangential[i];
            let (mut all, mut before) = (0u8, 0u8);
            let axis = 1 + g as u8;
            for j in &mut p {
                let earlier = (*j as usize) < i;
                let keep = (column_axis[*j as usize] == axis) & (first_layer | (*j as usize != i));
                *j = if keep { *j } else { i as u32 };
                all += u8::from(keep);
                before += u8::from(keep & earlier);
            }
            let count = all | before << 4;
            if first_layer {
                column_axis[i] = axis;
            } else {
                tangential[i] = p;
                counts[i] = count;
            }
            (p, count)
        } else {
            (tangential[i], counts[i])
        };
        let k = u32::from(col - 1);
        if rel > k {
            // The common case: tangential coordinates settled (set to the
            // middle of the column's sub-cell in the layer after its last
            // coded bit), only the height is coded.
            if rel == k + 1 {
                for (a, c) in q[i].iter_mut().enumerate() {
                    if a != g {
                        *c = ((*c >> shift) | 1) << shift;
                    }
                }
            }
            let c = q[i][g];
            let bin = height_bin(height, &pred, count, i, shift);
            let mut bit = (c >> shift) & 1 == 1;
            coder.bit_reserved(&mut bit, pred_ctx + bin * 4 + above(c))?;
            let v = (c & !(1 << shift)) | (u32::from(bit) << shift);
            q[i][g] = v;
            height[i] = ((v >> shift) << shift) as u16;
            continue;
        }
        // Tangential bits still coded: all three axes, in axis order. The
        // height's context does not depend on the tangential bits, so it
        // is found first and each axis selects its context without a
        // branch on which axis is the normal one.
        let normal_ctx = pred_ctx + height_bin(height, &pred, count, i, shift) * 4;
        for a in 0..3 {
            let c = q[i][a];
            let ctx = if a == g {
                normal_ctx
            } else {
                plain(a, info, g)
            } + above(c);
            let mut bit = (c >> shift) & 1 == 1;
            coder.bit_reserved(&mut bit, ctx)?;
            q[i][a] = (c & !(1 << shift)) | (u32::from(bit) << shift);
        }
        height[i] = ((q[i][g] >> shift) << shift) as u16;
    }
    Ok(())
}

/// Where the height a column particle's neighbours predict falls relative
/// to the split of its current interval (the bit at `shift`): one of the
/// [`PRED_BINS`] — below −1, −1..−½, −½..0, 0..½, ½..1, above 1
/// half-interval, or no neighbour. The predictors share its slab along the
/// normal axis, so on a smooth surface their heights interpolate its own.
/// Each counts with what the decoder knows of it — bit `shift` decoded
/// when it comes earlier in the layer, only the bits above when later — at
/// the centre of that interval.
///
/// `pred` holds particle numbers, `i` itself in the empty slots; `count`
/// how many are predictors (bits 0–3) and how many of those come before
/// `i` (bits 4–7). `height` holds exactly the known bits of every height
/// (the bits below are zero), so the comparison of the predictors' mean
/// centre with the split, `Σ (2·h_j + 2^known_j) − n·(2·h_i + 2^(shift+1))`
/// against multiples of `n·2^shift`, divides exactly by `2^shift`:
/// `2·Σ (h_j − h_i) / 2^shift − #{j < i}` against `−2n, −n, 0, n, 2n` — an
/// empty slot (`j = i`) adds nothing to the sum, and [`BINS`] makes the
/// comparisons one lookup. Nothing branches: this runs for nearly every
/// symbol of a precision layer, so its instruction count is what counts.
#[inline(always)]
fn height_bin(height: &[u16], pred: &[u32; 4], count: u8, i: usize, shift: u32) -> usize {
    let hi = i32::from(height[i]);
    let sum: i32 = pred.iter().map(|&j| i32::from(height[j as usize])).sum();
    let d = (((sum - 4 * hi) * 2) >> shift) - i32::from(count >> 4);
    usize::from(BINS[usize::from(count & 7)][(d.clamp(-9, 8) + 9) as usize])
}

/// [`height_bin`]'s bin of `d` (clamped to `−9..=8`, offset by 9) for `n`
/// predictors: how many of `−2n, −n, 0, n, 2n` it reaches; `n = 0` is the
/// "no neighbour" bin.
///
/// Rows `5..8` (no particle has more than four predictors) are there so
/// that `count & 7` indexes the table without a bounds check.
static BINS: [[u8; 18]; 8] = {
    let mut t = [[0u8; 18]; 8];
    let mut n = 0;
    while n < 5 {
        let mut k = 0;
        while k < 18 {
            let d = k as i32 - 9;
            let n32 = n as i32;
            t[n][k] = if n == 0 {
                (PRED_BINS - 1) as u8
            } else {
                (d >= -2 * n32) as u8
                    + (d >= -n32) as u8
                    + (d >= 0) as u8
                    + (d >= n32) as u8
                    + (d >= 2 * n32) as u8
            };
            k += 1;
        }
        n += 1;
    }
    t
};

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_normal_axis_is_the_one_without_face_neighbours() {
        // A z = const sheet: neighbours at ±x and ±y.
        assert_eq!(normal_axis(0b011_011), 2);
        // An x = const sheet: neighbours at ±y, ±z.
        assert_eq!(normal_axis(0b110_110), 0);
        assert_eq!(faces_per_axis(0b100_001), [1, 0, 1]);
        // Ties go to the later axis.
        assert_eq!(normal_axis(0), 2);
        assert_eq!(normal_axis(0b000_011), 2);
    }

    /// The bin as the format defines it (docs/formats/pop.md): each
    /// predictor at the centre of what is known of its height, their mean
    /// against the split of the particle's interval, in half-intervals.
    fn bin_by_definition(height: &[u16], pred: &[u32; 4], i: usize, shift: u32) -> usize {
        let c = f64::from(height[i]);
        let split = c + f64::from(1u32 << shift);
        let mut sum = 0.0;
        let mut n = 0.0;
        for &j in pred.iter().filter(|&&j| j as usize != i) {
            let known = if (j as usize) < i { shift } else { shift + 1 };
            sum += f64::from(height[j as usize]) + f64::from(1u32 << known) / 2.0;
            n += 1.0;
        }
        if n == 0.0 {
            return PRED_BINS - 1;
        }
        let off = (sum / n - split) / f64::from(1u32 << shift) * 2.0;
        [-2.0, -1.0, 0.0, 1.0, 2.0]
            .iter()
            .filter(|&&t| off >= t)
            .count()
    }

    #[test]
    fn the_height_bin_lookup_matches_the_definition() {
        // Heights known to the bits the decoder knows at particle `i` of
        // the layer at `shift`: its own and the later ones' to `shift + 1`,
        // the earlier ones' to `shift`.
        let mut seed = 0x9e37_79b9u32;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 17;
            seed ^= seed << 5;
            seed
        };
        for _ in 0..200_000 {
            let shift = next() % 12;
            let i = 2 + (next() % 3) as usize;
            let height: Vec<u16> = (0..8usize)
                .map(|j| {
                    let known = if j < i { shift } else { shift + 1 };
                    ((next() as u16) >> known) << known
                })
                .collect();
            let mut pred = [i as u32; 4];
            let mut count = 0u8;
            for slot in &mut pred {
                if next() % 4 != 0 {
                    let j = next() % 8;
                    if j as usize != i {
                        *slot = j;
                        count += 1 + (u8::from((j as usize) < i) << 4);
                    }
                }
            }
            assert_eq!(
                height_bin(&height, &pred, count, i, shift),
                bin_by_definition(&height, &pred, i, shift),
                "height {height:?} pred {pred:?} i {i} shift {shift}"
            );
        }
    }
}
