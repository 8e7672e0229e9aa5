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
use super::bit_coder::BitCoder;
use super::contexts::{BACK, COARSE, FLAG, OCC, OCC_BASE, OCC_KNOWN, PATH, SIBLINGS};
use super::links::{Links, NONE, Pending, RANK, child_links};
use crate::error::{Result, stream_err};
use crate::octree::unmorton;
use crate::ordering::{HLevel, NO_PARTICLE};

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
/// `leaves` (their index is their particle number). In entropy mode
/// `links` holds the links of level `r − 1` on entry and those of level
/// `r` on return (those of level `R` serve
/// [`crate::coding::precision_layers::particle_faces`]); the
/// baseline leaves it alone.
pub fn code_level<C: BitCoder>(
    coder: &mut C,
    inp: &LevelInput,
    links: &mut Links,
    leaves: &mut Vec<[u32; 3]>,
    truth: Option<&Truth>,
) -> Result<HLevel> {
    // One loop per mode, so neither carries the other's dead work.
    if inp.entropy {
        code_level_in::<C, true>(coder, inp, links, leaves, truth)
    } else {
        code_level_in::<C, false>(coder, inp, links, leaves, truth)
    }
}

/// The children below child `k` (`k ≤ 8`).
#[inline(always)]
fn below(k: u32) -> u32 {
    (1 << k) - 1
}

/// [`code_level`] for one mode: `ENTROPY` selects the entropy mode's
/// contexts and inferences.
///
/// Per parent the children are bit masks (bit `k`: child `k`), and every
/// decision a decoded bit feeds (contexts, counts, which children exist)
/// is computed from the masks rather than branched on: decoded bits are
/// data, and a branch on each cost about a mispredicted branch per
/// symbol.
fn code_level_in<C: BitCoder, const ENTROPY: bool>(
    coder: &mut C,
    inp: &LevelInput,
    links: &mut Links,
    leaves: &mut Vec<[u32; 3]>,
    truth: Option<&Truth>,
) -> Result<HLevel> {
    let depth = u32::from(inp.depth);
    let r = u32::from(inp.r);
    let parents = inp.parents;
    if ENTROPY {
        links.materialise();
        if links.nb.len() != parents.cells.len() {
            return stream_err(format!(
                "level {r}: neighbour links do not match level {}",
                r - 1
            ));
        }
    }
    let expected = inp.max_nodes.min(8 * parents.cells.len());
    // The level's nodes are written by index, `n` so far, into room for
    // all of them plus one parent's eight children: every child slot of a
    // parent is written and the count advanced by whether the child exists
    // (no branch on a decoded bit); the room is cut to `n` at the end. The
    // `max_nodes` check after each parent keeps `n + 8` within it.
    let room = expected + 8;
    let mut cells = vec![0u64; room];
    let mut phantoms_out = vec![false; room];
    let mut particles = vec![0u32; room];
    let mut n = 0usize;
    let finest = r == depth;
    // New particles are among the level's nodes: room for all of them at
    // once (unused room is never touched) rather than doubling copies; at
    // `R` they are written by index like the nodes, into room for the
    // nodes but the implicit children (one per parent that is not a
    // phantom), checked before each parent.
    let leaves_start = leaves.len();
    if finest {
        let inherited = parents.phantom.iter().filter(|&&p| !p).count();
        leaves.resize(
            leaves_start + expected.saturating_sub(inherited) + 8,
            [0; 3],
        );
    } else {
        leaves.reserve_exact(expected);
    }
    let mut n_leaves = leaves_start;
    // Per parent: its children (bit k: child k present), which of them are
    // phantoms, and the index of its first child in the level. The masks
    // have an empty sentinel past the parents, which a missing neighbour
    // reads (see below).
    let n_parents = parents.cells.len();
    let (mut masks, mut phantoms, mut firsts) = if ENTROPY {
        (
            vec![0u8; n_parents + 1],
            vec![0u8; n_parents + 1],
            vec![0u32; n_parents],
        )
    } else {
        (Vec::new(), Vec::new(), Vec::new())
    };
    // Bits of each new particle's path: three per level below `r`.
    let path_symbols = u64::from(3 * (depth - r));
    let s = depth - r;
    let mut t = 0usize;
    for p in 0..n_parents {
        let pc = parents.cells[p];
        let phantom_parent = parents.phantom[p];
        // The children (bit `k`: child `k`) and which of them are phantoms:
        // the truth for an encoder, decided below for a decoder.
        let mut own = 0u32;
        let mut phantom = 0u32;
        if let Some(tr) = truth {
            while t < tr.level.cells.len() && tr.level.cells[t] >> 3 == pc {
                let k = (tr.level.cells[t] & 7) as u32;
                own |= 1 << k;
                phantom |= u32::from(tr.level.phantom[t]) << k;
                t += 1;
            }
        }
        // The implicit child (the one holding the parent's particle leaf;
        // 8, none, under a phantom). A phantom reads the root's leaf, so the
        // look-up needs no branch.
        let leaf =
            leaves[(parents.particle[p] & u32::from(!phantom_parent).wrapping_neg()) as usize];
        let i = (leaf[0] >> s) & 1 | ((leaf[1] >> s) & 1) << 1 | ((leaf[2] >> s) & 1) << 2;
        let implicit = if phantom_parent { 8 } else { i };
        let implicit_bit = (1 << implicit) & 0xff;
        own |= implicit_bit;
        phantom &= !implicit_bit;
        // Per child `k`, in byte `k` of `near`, what its occupancy context
        // takes from the parent ([`OCC_BASE`]): the parent's state (bits
        // 6–7: under a phantom 0, before the implicit child 1, after it 2),
        // which of the child's neighbours towards −x, −y, −z are children
        // of the parent's neighbours (bits 3–5; [`BACK`]), and which of the
        // parent's neighbours on the child's sides are present (bits 0–2;
        // [`COARSE`]) — all coded before this parent (smaller Morton
        // codes). `phantom_near`, bits 0–2: those neighbours that are
        // phantoms. `faces`, bit `d`: the parent's neighbour across face
        // `d` is present.
        let mut near = 0u64;
        let mut phantom_near = 0u64;
        let mut faces = 0u32;
        if ENTROPY {
            let nb = &links.nb[p];
            for (d, &q) in nb.iter().enumerate() {
                faces |= u32::from(q != NONE) << d;
            }
            near = COARSE[faces as usize];
            for a in 0..3 {
                // A missing neighbour (`NONE`) reads the empty sentinel: a
                // mask applied after the look-up compiles to a branch
                // around it, mispredicted on the data.
                let q = (nb[a] as usize).min(n_parents);
                near |= BACK[a][usize::from(masks[q])];
                phantom_near |= BACK[a][usize::from(phantoms[q])] >> 3;
            }
            // +1 for every child, +1 more above the implicit one (its own
            // byte is never read); nothing under a phantom.
            const ONES: u64 = 0x0101_0101_0101_0101;
            let state = ONES + ((ONES << (8 * (implicit & 7))) << 8);
            near |= (state & u64::from(!phantom_parent).wrapping_neg()) << 6;
        }
        // 1. Occupancy: every child but the implicit one.
        let todo = 0xff & !implicit_bit;
        if ENTROPY {
            coder.bits_chained(&mut own, todo, |k, known| {
                let parent_part = OCC_BASE[(k << 8 | (near >> (8 * k)) as u32 & 0xff) as usize];
                usize::from(parent_part) + usize::from(OCC_KNOWN[(k << 8 | known) as usize])
            })?;
        } else {
            coder.bits_chained(&mut own, todo, |_, _| OCC)?;
        }
        if own == 0 {
            return stream_err(format!("level {r}: a phantom node has no child"));
        }
        // 2. Phantom flags of the signalled children, below `R`. The
        // entropy mode infers those before the implicit child: the path
        // rule would have picked them if they were kept.
        if r == depth {
            phantom = 0;
        } else {
            let inferred = if ENTROPY && !phantom_parent {
                own & below(implicit)
            } else {
                0
            };
            let coded = own & !implicit_bit & !inferred;
            phantom = (phantom & coded) | inferred;
            if ENTROPY {
                let pp = u32::from(phantom_parent);
                let count = (own.count_ones() - 1).min(3);
                let base = FLAG as u32 + pp * 32 + count;
                coder.bits_chained(&mut phantom, coded, |k, known| {
                    let near = (phantom_near >> (8 * k)) as u32 & 7;
                    let nb = near | u32::from(SIBLINGS[(k << 8 | known) as usize]);
                    (base + nb * 4) as usize
                })?;
            } else {
                coder.bits_chained(&mut phantom, coded, |_, _| FLAG)?;
            }
        }
        if ENTROPY {
            masks[p] = own as u8;
            phantoms[p] = phantom as u8;
            firsts[p] = n as u32;
        }
        // 3. Leaf paths of the new particles, then the nodes.
        let parent_at = unmorton(pc);
        if finest {
            // No phantoms and no path bits at `R`: every child of the
            // parent is written, kept when it exists, and brings a new
            // particle unless it is the implicit child — whose particle,
            // the parent's, is set after the loop (a select in the loop
            // compiles to a branch on the decoded bits).
            if n_leaves + 8 > leaves.len() {
                // More new particles than the declared nodes leave room for.
                return stream_err(format!(
                    "level {r} holds more nodes than its chunk declares"
                ));
            }
            let first = n;
            let base = parent_at.map(|c| c << 1);
            for k in 0..8 {
                cells[n] = (pc << 3) | u64::from(k);
                particles[n] = n_leaves as u32;
                leaves[n_leaves] = [base[0] | (k & 1), base[1] | (k >> 1 & 1), base[2] | k >> 2];
                let exists = (own >> k & 1) as usize;
                n += exists;
                n_leaves += exists & usize::from(k != implicit);
            }
            // Under a phantom (no implicit child) the slot is rewritten as
            // it is.
            let at = first + usize::from(RANK[(own << 3 | (implicit & 7)) as usize]);
            let keep = u32::from(!phantom_parent).wrapping_neg();
            particles[at] = (parents.particle[p] & keep) | (particles[at] & !keep);
        } else {
            // The new particles (kept children but the implicit one), in
            // child order: their leaf paths.
            let fresh = own & !phantom & !implicit_bit;
            let first_id = leaves.len();
            let mut rest = fresh;
            while rest != 0 {
                let k = rest.trailing_zeros();
                rest &= rest - 1;
                let mut leaf = [0, 1, 2].map(|a| ((parent_at[a] << 1) | (k >> a & 1)) << s);
                let id = leaves.len();
                let want = truth.map(|tr| tr.leaves[id]).unwrap_or([0; 3]);
                coder.reserve(path_symbols)?;
                // Path contexts: per axis, how many of the parent's two
                // neighbours along it are present (the surface's extent
                // predicts which path bits the lexicographic rule fixes),
                // and whether the child's neighbour behind it is present.
                let ext = [0, 1, 2].map(|a| (faces >> a & 1) + (faces >> (a + 3) & 1));
                let behind = (near >> (8 * k + 3)) as u32 & 7
                    | u32::from(SIBLINGS[(k << 8 | own & below(k)) as usize]);
                // Raw bits: the three axes of a depth, read at once.
                let together = !ENTROPY && coder.context_free();
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
                    let step = (d - r).min(3) - 1;
                    for (a, l) in leaf.iter_mut().enumerate() {
                        let mut b = (want[a] >> s) & 1 == 1;
                        let ctx = if ENTROPY {
                            let back = behind >> a & 1;
                            PATH + (((step * 3 + a as u32) * 3 + ext[a]) * 2 + back) as usize
                        } else {
                            PATH
                        };
                        coder.bit_reserved(&mut b, ctx)?;
                        *l |= u32::from(b) << s;
                    }
                }
                leaves.push(leaf);
            }
            // The nodes, as at `R`: every child slot written, kept when the
            // child exists; the particle selected with masks.
            let window = "the room holds a parent's eight children";
            let cells8: &mut [u64; 8] = (&mut cells[n..n + 8]).try_into().expect(window);
            let phantoms8: &mut [bool; 8] = (&mut phantoms_out[n..n + 8]).try_into().expect(window);
            let particles8: &mut [u32; 8] = (&mut particles[n..n + 8]).try_into().expect(window);
            let mut count = 0usize;
            for k in 0..8 {
                let id = first_id as u32 + u32::from(RANK[(fresh << 3 | k) as usize]);
                let inherited = u32::from(k == implicit).wrapping_neg();
                let none = NO_PARTICLE & (phantom >> k & 1).wrapping_neg();
                cells8[count & 7] = (pc << 3) | u64::from(k);
                phantoms8[count & 7] = phantom >> k & 1 == 1;
                particles8[count & 7] =
                    (id & !inherited) | (parents.particle[p] & inherited) | none;
                count += (own >> k & 1) as usize;
            }
            n += count;
        }
        if n > inp.max_nodes {
            return stream_err(format!(
                "level {r} holds more nodes than its chunk declares"
            ));
        }
    }
    if ENTROPY {
        masks.truncate(n_parents);
        *links = if r == depth {
            Links {
                nb: Vec::new(),
                pending: Some(Pending {
                    parent_nb: std::mem::take(&mut links.nb),
                    masks,
                    firsts,
                    n,
                }),
            }
        } else {
            child_links(&links.nb, &masks, &firsts, n)
        };
    }
    cells.truncate(n);
    phantoms_out.truncate(n);
    particles.truncate(n);
    if finest {
        leaves.truncate(n_leaves);
    }
    Ok(HLevel {
        cells,
        phantom: phantoms_out,
        particle: particles,
    })
}

#[cfg(test)]
mod tests {
    use std::collections::HashMap;

    use super::*;
    use crate::coding::raw_bits::BitWriter;
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

    #[test]
    fn garbage_level_payloads_decode_without_panicking() {
        // The decoder writes a level's nodes by index into room sized from
        // the chunk's node count: hostile payloads, whatever node counts
        // they declare, must end in a level or an error, never a panic.
        use crate::coding::range_coder::EntropyReader;
        let model = lodkit_mesh::Model::Mesh(lodkit_mesh::shapes::icosphere(2));
        let mut tree = Octree::build(
            &model,
            &BuildOptions {
                depth: Some(5),
                ..BuildOptions::default()
            },
        )
        .unwrap();
        thin(&mut tree, &ThinningOptions::DEFAULT);
        let (h, _) = Hierarchy::from_thinned(&tree).unwrap();
        let depth = h.depth;
        let leaves: Vec<[u32; 3]> = h
            .particle_leaf
            .iter()
            .map(|&l| unmorton(h.levels[depth as usize].cells[l as usize]))
            .collect();
        let mut outcomes = [0usize; 2];
        for r in 1..=depth {
            // The true links and leaves of the levels above `r`.
            let mut links = Links::root();
            let mut coded = vec![leaves[0]];
            for q in 1..r {
                let inp = LevelInput {
                    depth,
                    r: q,
                    entropy: true,
                    parents: &h.levels[q as usize - 1],
                    max_nodes: usize::MAX,
                };
                let truth = Truth {
                    level: &h.levels[q as usize],
                    leaves: &leaves,
                };
                let mut w = crate::coding::range_coder::EntropyWriter::new();
                code_level(&mut w, &inp, &mut links, &mut coded, Some(&truth)).unwrap();
            }
            let nodes = h.levels[r as usize].cells.len();
            for seed in 0..24u32 {
                let bytes: Vec<u8> = (0..(16 + seed as usize * 13))
                    .map(|i| {
                        ((i as u32).wrapping_mul(2_654_435_761) ^ seed.wrapping_mul(40_503)) as u8
                    })
                    .collect();
                for max_nodes in [0, 1, nodes / 2, nodes, 8 * nodes, usize::MAX] {
                    let Ok(mut c) = EntropyReader::new(&bytes) else {
                        continue;
                    };
                    let inp = LevelInput {
                        depth,
                        r,
                        entropy: true,
                        parents: &h.levels[r as usize - 1],
                        max_nodes,
                    };
                    let mut l = links.clone();
                    let mut got = coded.clone();
                    let ok = code_level(&mut c, &inp, &mut l, &mut got, None).is_ok();
                    outcomes[usize::from(ok)] += 1;
                }
            }
        }
        assert!(outcomes[0] > 0, "{outcomes:?}");
    }
}
