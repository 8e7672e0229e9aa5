//! Hierarchical particle coding — §7.1 and §7.2 of Yemez & Schmitt; the
//! symbol sequence both bit layers share.
//!
//! One traversal serves the encoder and the decoder: every symbol goes
//! through [`BitCoder::bit`] with a `&mut bool` that the encoder has filled
//! from the truth and the decoder fills from the stream, so the two can
//! never disagree about what comes next.
//!
//! Level `r ≥ 1`, parents at `r − 1` in Morton (lexicographic) order; for
//! each parent:
//! 1. child occupancy: 7 bits when the parent has a particle (its child
//!    containing the particle's leaf is implicit and always kept), 8 bits
//!    under a phantom;
//! 2. below level `R`, one phantom flag per signalled child (the implicit
//!    child is never a phantom);
//! 3. for each new particle (a kept, non-implicit child), the path of its
//!    leaf below `r`: `R − r` bits per coordinate, coded as one 3-bit child
//!    code per level (the same count as §7.1's `N − r` bits at `N = R`).
//!
//! The paper interleaves nothing specific; we code per parent so a
//! decoder needs no buffering. The entropy mode also skips the phantom
//! flag of a child whose code is below the implicit child's (the path rule
//! makes it a phantom) — the baseline codes every flag, as §7.1 counts.
//!
//! Precision layers (bits `R + 1 ..= N`, §7.2) are the next stage,
//! [`crate::precision_coding`]; the context layout below serves both.
use crate::error::{Result, stream_err};
use crate::octree::unmorton;
use crate::ordering::{HLevel, NO_PARTICLE};
use crate::precision_coding::MAX_COLUMN_DEPTH;

/// One binary symbol at a time, with a context for adaptive layers.
pub trait BitCoder {
    /// Writes `*b` (encoder) or reads it into `*b` (decoder).
    fn bit(&mut self, b: &mut bool, ctx: usize) -> Result<()>;
    /// Symbols coded so far.
    fn symbols(&self) -> u64;
    /// `n ≤ 32` bits of `*v`, most significant first, context `ctx + i`
    /// for bit `i` (from the top).
    fn bits(&mut self, v: &mut u32, n: u32, ctx: usize) -> Result<()> {
        let mut out = 0u32;
        for i in 0..n {
            let mut b = (*v >> (n - 1 - i)) & 1 == 1;
            self.bit(&mut b, ctx + i as usize)?;
            out = (out << 1) | u32::from(b);
        }
        *v = out;
        Ok(())
    }
    /// Whether the contexts are ignored (the baseline's raw bits): symbols
    /// with different contexts may then be coded together with
    /// [`BitCoder::bits`], which a raw reader does with one shift.
    fn context_free(&self) -> bool {
        false
    }
}

// Context layout (the baseline ignores contexts).
const OCC_STATES: usize = 3 * 8 * 8 * 8 * 3;
const OCC: usize = 0;
const FLAG: usize = OCC + OCC_STATES;
const FLAG_STATES: usize = 2 * 8 * 4;
const PATH: usize = FLAG + FLAG_STATES;
const PATH_STATES: usize = 3 * 3 * 3 * 2;
pub(crate) const PREC: usize = PATH + PATH_STATES;
/// Entropy mode: axis × layer bucket × neighbours along it × normal axis
/// or not × 2 bits above (216); the plain layout, axis × 16 bits × 2 bits
/// above (192), fits inside.
const PREC_STATES: usize = 3 * 3 * 3 * 2 * 4;
/// Column flags: face neighbours along x, y, z (0–2 each).
pub(crate) const COL: usize = PREC + PREC_STATES;
const COL_STATES: usize = 27;
/// Column depth, unary: one context per step.
pub(crate) const COLK: usize = COL + COL_STATES;
/// Normal-axis bits of column particles: layer bucket × predicted height
/// bin × 2 bits above.
pub(crate) const PRED: usize = COLK + MAX_COLUMN_DEPTH as usize;
const PRED_STATES: usize = 3 * PRED_BINS * 4;
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

/// What a level coder needs besides the bits.
pub struct LevelInput<'a> {
    /// Octree resolution `R`.
    pub depth: u8,
    /// The level being coded, `1..=R`.
    pub r: u8,
    /// Use the entropy mode's contexts and inferences.
    pub entropy: bool,
    /// Nodes at level `r − 1`.
    pub parents: &'a HLevel,
    /// Refuse to build more nodes than this (decoder guard).
    pub max_nodes: usize,
}

/// No node across this face.
const NONE: u32 = u32::MAX;

/// The children (bit `k`: child `k`) on the upper side of their parent
/// along x, y, z.
const UPPER: [u8; 3] = [0xaa, 0xcc, 0xf0];

/// Per child `k`: the children that have `k` behind them along x, y, z
/// (`k` + e_a for `k` on the lower side of axis `a`), one byte per axis.
const BEHIND_OF: [u32; 8] = {
    let mut t = [0u32; 8];
    let mut k = 0;
    while k < 8 {
        let mut a = 0;
        while a < 3 {
            let bit = 1usize << a;
            if k & bit == 0 {
                t[k] |= 1 << ((k | bit) + 8 * a);
            }
            a += 1;
        }
        k += 1;
    }
    t
};

/// Bits `k`, `8 + k` and `16 + k` of `m` as bits 0, 1, 2.
#[inline(always)]
fn axes_of(m: u32, k: usize) -> usize {
    let x = (m >> k) & 0x01_01_01;
    ((x | x >> 7 | x >> 14) & 7) as usize
}

/// Face-neighbour links of one level, for the entropy contexts: `nb[i][d]`
/// is the index of the node across face `d` of node `i` (`d = a` towards
/// `−a`, `d = 3 + a` towards `+a`) or `NONE`. Built from the parent
/// level's links while the level is coded (a child's neighbour is a
/// sibling or a child of its parent's neighbour), so no context needs a
/// hash or a search: the coder of level `r` reads only arrays.
///
/// The links of level `R` serve only
/// [`crate::precision_coding::particle_faces`], which reads each
/// once: [`code_level`] leaves them unbuilt there (`pending`), and they are
/// derived on the fly from what builds them.
#[derive(Debug, Clone, Default)]
pub struct Links {
    nb: Vec<[u32; 6]>,
    pending: Option<Pending>,
}

/// What [`child_links`] builds a level's links from.
#[derive(Debug, Clone)]
struct Pending {
    parent_nb: Vec<[u32; 6]>,
    masks: Vec<u8>,
    firsts: Vec<u32>,
    n: usize,
}

impl Links {
    /// The links of level 0: the root has no neighbour.
    pub fn root() -> Links {
        Links {
            nb: vec![[NONE; 6]],
            pending: None,
        }
    }

    /// Nodes the links describe.
    pub(crate) fn len(&self) -> usize {
        self.pending.as_ref().map_or(self.nb.len(), |p| p.n)
    }

    /// Calls `f(i, links of node i)` for every node in order, deriving
    /// pending links on the fly.
    pub(crate) fn for_each_row(&self, mut f: impl FnMut(usize, [u32; 6])) {
        match &self.pending {
            Some(p) => each_child_links(&p.parent_nb, &p.masks, &p.firsts, f),
            None => {
                for (i, row) in self.nb.iter().enumerate() {
                    f(i, *row);
                }
            }
        }
    }

    /// Builds links left pending.
    fn materialise(&mut self) {
        if let Some(p) = self.pending.take() {
            self.nb = Vec::with_capacity(p.n);
            each_child_links(&p.parent_nb, &p.masks, &p.firsts, |_, row| {
                self.nb.push(row)
            });
        }
    }
}

/// The truth an encoder codes from.
pub struct Truth<'a> {
    pub level: &'a HLevel,
    /// Leaf coordinates (`R` bits) of every particle, in stream order.
    pub leaves: &'a [[u32; 3]],
}

/// Level 0: the root's particle leaf, `3R` bits.
pub fn code_root<C: BitCoder>(
    coder: &mut C,
    depth: u8,
    truth: Option<[u32; 3]>,
) -> Result<[u32; 3]> {
    let mut leaf = truth.unwrap_or([0; 3]);
    for v in &mut leaf {
        coder.bits(v, u32::from(depth), PATH)?;
    }
    Ok(leaf)
}

/// Index of child `j` of the node whose children are `mask`, the first at
/// `first`, if that child exists.
#[inline]
fn child_index(mask: u8, first: u32, j: usize) -> Option<u32> {
    (mask >> j & 1 == 1).then(|| first + (mask & ((1u8 << j) - 1)).count_ones())
}

/// Codes level `r` and returns it; new particles' leaves are appended to
/// `leaves` (their index is their particle number). In entropy mode
/// `links` holds the links of level `r − 1` on entry and those of level
/// `r` on return (those of level `R` serve
/// [`crate::precision_coding::particle_faces`]); the
/// baseline leaves it alone.
pub fn code_level<C: BitCoder>(
    coder: &mut C,
    inp: &LevelInput,
    links: &mut Links,
    leaves: &mut Vec<[u32; 3]>,
    truth: Option<&Truth>,
) -> Result<HLevel> {
    let depth = u32::from(inp.depth);
    let r = u32::from(inp.r);
    let parents = inp.parents;
    let entropy = inp.entropy;
    if entropy {
        links.materialise();
    }
    if entropy && links.nb.len() != parents.cells.len() {
        return stream_err(format!(
            "level {r}: neighbour links do not match level {}",
            r - 1
        ));
    }
    let mut out = HLevel::default();
    let expected = inp.max_nodes.min(8 * parents.cells.len());
    out.cells.reserve(expected);
    out.phantom.reserve(expected);
    out.particle.reserve(expected);
    // New particles are among the level's nodes: room for all of them at
    // once (unused room is never touched) rather than doubling copies.
    leaves.reserve_exact(expected);
    // Per parent: its children (bit k: child k present), which of them are
    // phantoms, and the index of its first child in `out`.
    let n_parents = parents.cells.len();
    let (mut masks, mut phantoms, mut firsts) = if entropy {
        (
            vec![0u8; n_parents],
            vec![0u8; n_parents],
            vec![0u32; n_parents],
        )
    } else {
        (Vec::new(), Vec::new(), Vec::new())
    };
    let mut t = 0usize;
    for p in 0..n_parents {
        let pc = parents.cells[p];
        let phantom_parent = parents.phantom[p];
        let mut present = [false; 8];
        let mut phantom = [false; 8];
        if let Some(tr) = truth {
            while t < tr.level.cells.len() && tr.level.cells[t] >> 3 == pc {
                let k = (tr.level.cells[t] & 7) as usize;
                present[k] = true;
                phantom[k] = tr.level.phantom[t];
                t += 1;
            }
        }
        let implicit = if phantom_parent {
            None
        } else {
            let leaf = leaves[parents.particle[p] as usize];
            let s = depth - r;
            Some(
                ((leaf[0] >> s) & 1 | ((leaf[1] >> s) & 1) << 1 | ((leaf[2] >> s) & 1) << 2)
                    as usize,
            )
        };
        // The parent's face neighbours (`coarse`, bit 2a: towards −a, bit
        // 2a + 1: towards +a) and the children masks of those towards −a,
        // all coded before this parent (their Morton codes are smaller).
        let mut coarse = 0usize;
        let mut back_mask = [0u8; 3];
        let mut back_phantom = [0u8; 3];
        if entropy {
            let nb = &links.nb[p];
            for a in 0..3 {
                if nb[a] != NONE {
                    coarse |= 1 << (2 * a);
                    back_mask[a] = masks[nb[a] as usize];
                    back_phantom[a] = phantoms[nb[a] as usize];
                }
                if nb[3 + a] != NONE {
                    coarse |= 1 << (2 * a + 1);
                }
            }
        }
        // Neighbour sets over the children, one byte per axis (x in bits
        // 0–7, y in 8–15, z in 16–23): bit `k` of byte `a` of
        // `behind(back)` is whether the node at child `k` − e_a is among
        // the children of the neighbour towards −a (child `k | bit`, for
        // `k` on the lower side); [`BEHIND_OF`] adds this parent's own
        // children as they are decided (child `k` − e_a is child `k ^
        // bit` < `k` for `k` on the upper side).
        let behind = |back: &[u8; 3]| -> u32 {
            (0..3).fold(0u32, |f, a| {
                f | u32::from((back[a] >> (1u32 << a)) & !UPPER[a]) << (8 * a)
            })
        };
        // Bit `k` of byte `a`: whether the parent's neighbour on child
        // `k`'s side along `a` is present.
        let coarse_at = (0..3).fold(0u32, |f, a| {
            let lo = if coarse >> (2 * a) & 1 == 1 {
                !UPPER[a]
            } else {
                0
            };
            let hi = if coarse >> (2 * a + 1) & 1 == 1 {
                UPPER[a]
            } else {
                0
            };
            f | u32::from(lo | hi) << (8 * a)
        });
        let mut fine = if entropy { behind(&back_mask) } else { 0 };
        // 1. Occupancy.
        let mut count = 0usize;
        let mut own = 0u8;
        for k in 0..8usize {
            if Some(k) == implicit {
                present[k] = true;
                phantom[k] = false;
            } else {
                let ctx = if entropy {
                    let state = match implicit {
                        None => 0,
                        Some(i) if k < i => 1,
                        Some(_) => 2,
                    };
                    let fine_bits = axes_of(fine, k);
                    let coarse_bits = axes_of(coarse_at, k);
                    OCC + (((state * 8 + k) * 8 + fine_bits) * 8 + coarse_bits) * 3 + count.min(2)
                } else {
                    OCC
                };
                coder.bit(&mut present[k], ctx)?;
            }
            if present[k] {
                count += 1;
                own |= 1 << k;
                fine |= BEHIND_OF[k];
            }
        }
        if count == 0 {
            return stream_err(format!("level {r}: a phantom node has no child"));
        }
        // 2. Phantom flags.
        let mut own_phantom = 0u8;
        let mut fine_phantom = if entropy { behind(&back_phantom) } else { 0 };
        for k in 0..8usize {
            if !present[k] || Some(k) == implicit {
                continue;
            }
            if r == depth {
                phantom[k] = false;
                continue;
            }
            if entropy && implicit.is_some_and(|i| k < i) {
                phantom[k] = true;
            } else {
                let ctx = if entropy {
                    let nb = axes_of(fine_phantom, k);
                    FLAG + ((usize::from(phantom_parent) * 8 + nb) * 4) + (count - 1).min(3)
                } else {
                    FLAG
                };
                coder.bit(&mut phantom[k], ctx)?;
            }
            if phantom[k] {
                own_phantom |= 1 << k;
                fine_phantom |= BEHIND_OF[k];
            }
        }
        if entropy {
            masks[p] = own;
            phantoms[p] = own_phantom;
            firsts[p] = out.cells.len() as u32;
        }
        // 3. Leaf paths of the new particles, then the nodes.
        for k in 0..8usize {
            if !present[k] {
                continue;
            }
            let cell = (pc << 3) | k as u64;
            let particle = if phantom[k] {
                NO_PARTICLE
            } else if Some(k) == implicit {
                parents.particle[p]
            } else {
                let id = leaves.len();
                let want = truth.map(|tr| tr.leaves[id]).unwrap_or([0; 3]);
                let c = unmorton(cell);
                let mut leaf = c.map(|v| v << (depth - r));
                // Context: the surface's extent along each axis (how many
                // of the parent's two neighbours on that axis are present)
                // predicts which path bits the lexicographic rule fixes.
                let mut ext = [0usize; 3];
                let mut back = [0usize; 3];
                if entropy {
                    for a in 0..3 {
                        ext[a] = ((coarse >> (2 * a)) & 1) + ((coarse >> (2 * a + 1)) & 1);
                        back[a] = (fine >> (8 * a + k) & 1) as usize;
                    }
                }
                // Raw bits: the three axes of a depth, read at once.
                let together = !entropy && coder.context_free();
                for d in (r + 1)..=depth {
                    let s = depth - d;
                    if together {
                        let mut bits = want
                            .iter()
                            .fold(0u32, |acc, &w| (acc << 1) | ((w >> s) & 1));
                        coder.bits(&mut bits, 3, PATH)?;
                        for (a, l) in leaf.iter_mut().enumerate() {
                            *l |= ((bits >> (2 - a)) & 1) << s;
                        }
                        continue;
                    }
                    let step = (d - r).min(3) as usize - 1;
                    for (a, l) in leaf.iter_mut().enumerate() {
                        let mut b = (want[a] >> s) & 1 == 1;
                        let ctx = if entropy {
                            PATH + ((step * 3 + a) * 3 + ext[a]) * 2 + back[a]
                        } else {
                            PATH
                        };
                        coder.bit(&mut b, ctx)?;
                        *l |= u32::from(b) << s;
                    }
                }
                leaves.push(leaf);
                id as u32
            };
            out.cells.push(cell);
            out.phantom.push(phantom[k]);
            out.particle.push(particle);
        }
        if out.cells.len() > inp.max_nodes {
            return stream_err(format!(
                "level {r} holds more nodes than its chunk declares"
            ));
        }
    }
    if entropy {
        *links = if r == depth {
            Links {
                nb: Vec::new(),
                pending: Some(Pending {
                    parent_nb: std::mem::take(&mut links.nb),
                    masks,
                    firsts,
                    n: out.cells.len(),
                }),
            }
        } else {
            child_links(&links.nb, &masks, &firsts, out.cells.len())
        };
    }
    Ok(out)
}

/// The links of the children level: a child's neighbour across a face is
/// a sibling, or a child of the parent's neighbour across that face.
fn child_links(parent_nb: &[[u32; 6]], masks: &[u8], firsts: &[u32], n: usize) -> Links {
    let mut nb = Vec::with_capacity(n);
    each_child_links(parent_nb, masks, firsts, |_, row| nb.push(row));
    debug_assert_eq!(nb.len(), n);
    Links { nb, pending: None }
}

/// Calls `f(i, links of child i)` for the children level's nodes in order.
#[inline]
fn each_child_links(
    parent_nb: &[[u32; 6]],
    masks: &[u8],
    firsts: &[u32],
    mut f: impl FnMut(usize, [u32; 6]),
) {
    let mut i = 0;
    for p in 0..masks.len() {
        let m = masks[p];
        if m == 0 {
            continue;
        }
        // Children masks and first indices of the parent's face neighbours.
        let mut nm = [0u8; 6];
        let mut nf = [0u32; 6];
        for d in 0..6 {
            let q = parent_nb[p][d];
            if q != NONE {
                nm[d] = masks[q as usize];
                nf[d] = firsts[q as usize];
            }
        }
        let mut rest = m;
        while rest != 0 {
            let k = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let mut row = [NONE; 6];
            for d in 0..6 {
                let bit = 1usize << (d % 3);
                let towards_plus = d >= 3;
                let inside = (k & bit != 0) != towards_plus;
                let (qm, qf) = if inside {
                    (m, firsts[p])
                } else {
                    (nm[d], nf[d])
                };
                if let Some(j) = child_index(qm, qf, k ^ bit) {
                    row[d] = j;
                }
            }
            f(i, row);
            i += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;
    use crate::encode_baseline::BitWriter;
    use crate::octree::{BuildOptions, Octree, morton, offset};
    use crate::ordering::Hierarchy;
    use crate::thinning::{ThinningOptions, thin};

    #[test]
    fn propagated_links_are_the_face_neighbours_a_hash_lookup_finds() {
        let model = lodkit_mesh::Model::Mesh(lodkit_mesh::shapes::icosphere(3));
        let mut tree = Octree::build(&model, &BuildOptions::default()).unwrap();
        thin(&mut tree, &ThinningOptions::DEFAULT);
        let (h, _) = Hierarchy::from_thinned(&tree).unwrap();
        let leaves: Vec<[u32; 3]> = h
            .particle_leaf
            .iter()
            .map(|&l| unmorton(h.levels[h.depth as usize].cells[l as usize]))
            .collect();
        let mut coded = vec![leaves[0]];
        let mut links = Links::root();
        let mut checked = 0;
        for r in 1..=h.depth as usize {
            let inp = LevelInput {
                depth: h.depth,
                r: r as u8,
                entropy: true,
                parents: &h.levels[r - 1],
                max_nodes: usize::MAX,
            };
            let truth = Truth {
                level: &h.levels[r],
                leaves: &leaves,
            };
            let mut w = BitWriter::new();
            let got = code_level(&mut w, &inp, &mut links, &mut coded, Some(&truth)).unwrap();
            assert_eq!(got, h.levels[r]);
            links.materialise();
            let index: HashMap<u64, u32> = got
                .cells
                .iter()
                .enumerate()
                .map(|(i, &c)| (c, i as u32))
                .collect();
            for (i, &c) in got.cells.iter().enumerate() {
                for d in 0..6 {
                    let mut step = [0i32; 3];
                    step[d % 3] = if d < 3 { -1 } else { 1 };
                    let want = offset(unmorton(c), step, 1 << r)
                        .and_then(|n| index.get(&morton(n)).copied())
                        .unwrap_or(NONE);
                    assert_eq!(links.nb[i][d], want, "level {r} node {i} face {d}");
                    checked += usize::from(want != NONE);
                }
            }
        }
        assert!(checked > 1000, "{checked} links checked");
    }
}
