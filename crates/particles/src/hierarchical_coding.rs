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
//! Precision layer `b` (bits `R + 1 ..= N`, §7.2): one bit per coordinate
//! of every particle, in stream order.
use crate::error::{Result, stream_err};
use crate::octree::{MortonMap, morton, unmorton};
use crate::ordering::{HLevel, NO_PARTICLE};

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
}

// Context layout (the baseline ignores contexts).
const OCC_STATES: usize = 3 * 8 * 8 * 8 * 3;
const OCC: usize = 0;
const FLAG: usize = OCC + OCC_STATES;
const FLAG_STATES: usize = 2 * 8 * 4;
const PATH: usize = FLAG + FLAG_STATES;
const PATH_STATES: usize = 3 * 3 * 3 * 2;
const PREC: usize = PATH + PATH_STATES;
const PREC_STATES: usize = 3 * 16 * 4;
/// First context of the attribute bits (see [`crate::attributes`]).
pub const ATTR: usize = PREC + PREC_STATES;
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
    /// Index of the parents by Morton code (entropy contexts).
    pub parent_index: &'a MortonMap<u32>,
    /// Refuse to build more nodes than this (decoder guard).
    pub max_nodes: usize,
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

/// Codes level `r` and returns it; new particles' leaves are appended to
/// `leaves` (their index is their particle number).
pub fn code_level<C: BitCoder>(
    coder: &mut C,
    inp: &LevelInput,
    leaves: &mut Vec<[u32; 3]>,
    truth: Option<&Truth>,
) -> Result<HLevel> {
    let depth = u32::from(inp.depth);
    let r = u32::from(inp.r);
    let parents = inp.parents;
    let mut out = HLevel::default();
    // Level-r nodes coded so far (value: phantom), for neighbour contexts.
    let mut fine: MortonMap<bool> = MortonMap::default();
    let side_parent = 1i64 << (r - 1);
    let mut t = 0usize;
    for p in 0..parents.cells.len() {
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
        let pxyz = unmorton(pc);
        let mut coarse = 0usize;
        if inp.entropy {
            // Parent's face neighbours on the far side of each child half.
            for a in 0..3 {
                for (dir, bit) in [(-1i64, 0usize), (1, 1)] {
                    let v = pxyz[a] as i64 + dir;
                    if v < 0 || v >= side_parent {
                        continue;
                    }
                    let mut n = pxyz;
                    n[a] = v as u32;
                    if inp.parent_index.contains_key(&morton(n)) {
                        coarse |= 1 << (2 * a + bit);
                    }
                }
            }
        }
        // 1. Occupancy.
        let mut count = 0usize;
        for k in 0..8usize {
            let cell = (pc << 3) | k as u64;
            if Some(k) == implicit {
                present[k] = true;
                phantom[k] = false;
            } else {
                let ctx = if inp.entropy {
                    let state = match implicit {
                        None => 0,
                        Some(i) if k < i => 1,
                        Some(_) => 2,
                    };
                    let c = unmorton(cell);
                    let mut fine_bits = 0usize;
                    let mut coarse_bits = 0usize;
                    for a in 0..3 {
                        if c[a] > 0 {
                            let mut n = c;
                            n[a] -= 1;
                            if fine.contains_key(&morton(n)) {
                                fine_bits |= 1 << a;
                            }
                        }
                        let half = (k >> a) & 1;
                        if coarse & (1 << (2 * a + half)) != 0 {
                            coarse_bits |= 1 << a;
                        }
                    }
                    OCC + (((state * 8 + k) * 8 + fine_bits) * 8 + coarse_bits) * 3 + count.min(2)
                } else {
                    OCC
                };
                coder.bit(&mut present[k], ctx)?;
            }
            if present[k] {
                count += 1;
                if inp.entropy {
                    fine.insert(cell, false);
                }
            }
        }
        if count == 0 {
            return stream_err(format!("level {r}: a phantom node has no child"));
        }
        // 2. Phantom flags.
        for k in 0..8usize {
            if !present[k] || Some(k) == implicit {
                continue;
            }
            if r == depth {
                phantom[k] = false;
                continue;
            }
            if inp.entropy && implicit.is_some_and(|i| k < i) {
                phantom[k] = true;
            } else {
                let ctx = if inp.entropy {
                    let c = unmorton((pc << 3) | k as u64);
                    let mut nb = 0usize;
                    for a in 0..3 {
                        if c[a] > 0 {
                            let mut n = c;
                            n[a] -= 1;
                            if fine.get(&morton(n)) == Some(&true) {
                                nb |= 1 << a;
                            }
                        }
                    }
                    FLAG + ((usize::from(phantom_parent) * 8 + nb) * 4) + (count - 1).min(3)
                } else {
                    FLAG
                };
                coder.bit(&mut phantom[k], ctx)?;
            }
            if phantom[k] && inp.entropy {
                fine.insert((pc << 3) | k as u64, true);
            }
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
                if inp.entropy {
                    for a in 0..3 {
                        ext[a] = ((coarse >> (2 * a)) & 1) + ((coarse >> (2 * a + 1)) & 1);
                        if c[a] > 0 {
                            let mut n = c;
                            n[a] -= 1;
                            back[a] = usize::from(fine.contains_key(&morton(n)));
                        }
                    }
                }
                for d in (r + 1)..=depth {
                    let s = depth - d;
                    let step = (d - r).min(3) as usize - 1;
                    for (a, l) in leaf.iter_mut().enumerate() {
                        let mut b = (want[a] >> s) & 1 == 1;
                        let ctx = if inp.entropy {
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
    Ok(out)
}

/// Precision layer for bit `b` (1-based from the most significant of the
/// 16): one bit per coordinate of every particle. `q` holds 16-bit
/// coordinates; the encoder's are complete, the decoder's get bit `b` set.
pub fn code_precision<C: BitCoder>(coder: &mut C, b: u32, q: &mut [[u32; 3]]) -> Result<()> {
    let shift = 16 - b;
    let layer = (b as usize).min(16) - 1;
    for v in q.iter_mut() {
        for (a, c) in v.iter_mut().enumerate() {
            let mut bit = (*c >> shift) & 1 == 1;
            // The two bits above: a centroid near the middle of its cube
            // reads 0111… or 1000…, so they predict this one.
            let above = ((*c >> (shift + 1)) & 3) as usize;
            coder.bit(&mut bit, PREC + (a * 16 + layer) * 4 + above)?;
            *c = (*c & !(1 << shift)) | (u32::from(bit) << shift);
        }
    }
    Ok(())
}

/// Morton index of a level, for neighbour lookups.
pub fn index_of(level: &HLevel) -> MortonMap<u32> {
    let mut m = MortonMap::default();
    m.reserve(level.cells.len());
    for (i, &c) in level.cells.iter().enumerate() {
        m.insert(c, i as u32);
    }
    m
}
