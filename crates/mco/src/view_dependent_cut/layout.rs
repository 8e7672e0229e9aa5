//! The compact layout view cuts read (built at a model's first cut, in
//! memory; the `.mco` format is unchanged): 32-byte search records and
//! closure records on inner-node ranks, the per-cut rank bitset, and the
//! triangles in node order so a run of unpatched children is one copy.

use super::*;

/// One inner node's fields the search reads, in one 32-byte record (two
/// per cache line), so that testing a node touches one record, not the
/// node, its metric, its bound and its children's records.
#[derive(Debug, Clone, Copy, Default)]
#[repr(C, align(32))]
pub(super) struct Hot {
    /// The cube's min corner, as [`McoModel::node_box`] computes it.
    pub(super) lo: [f32; 3],
    /// [`node_error`].
    pub(super) err: f32,
    /// The subtree bound ([`view_subtree_bounds`]).
    pub(super) bound: f32,
    /// The growth of the cube for the subtree's bound test (see the
    /// module docs of `view_dependent_cut`): `lo..hi` grown by `grow` on
    /// every side covers every cube of the subtree.
    pub(super) grow: f32,
    /// Rank of the first inner child (the inner children's ranks are
    /// consecutive: ranks follow node order and the children are one
    /// node range).
    pub(super) first_inner: u32,
    pub(super) level: u8,
    pub(super) child_count: u8,
    /// Bit `j`: child `first_child + j` is an inner node.
    pub(super) inner_mask: u8,
    /// Bit `j`: child `first_child + j` has crack patches (so drawing it
    /// may not be a plain copy of its triangles).
    pub(super) patch_mask: u8,
}

/// One inner node's fields the closure and the emission read, by rank.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Close {
    /// Node number of the first child.
    pub(super) first_child: u32,
    /// Its range of `ViewLayout::links`: the ranks an expanded node
    /// expands (its parent, then its balance dependencies).
    pub(super) links_start: u32,
    pub(super) links_count: u32,
    /// LOD number that expands the node (`u32::MAX`: none).
    pub(super) prio: u32,
}

/// The compact, read-only layout view-dependent cuts of a regular model
/// work on, built once per model from its arrays (`O(nodes + triangles)`;
/// about 50 bytes per inner node and 8 per node, plus a copy of the
/// triangles when the model's are not stored in node order).
///
/// Only inner nodes can be expanded, so the search, the closure and the
/// per-cut flags work on *ranks*: inner nodes numbered in node order (about
/// an eighth of the nodes: the flags are a bitset that fits a core's
/// cache). The triangles are stored in node order, so the children of a
/// node — one node range — have one triangle range, and a run of drawn
/// children without an active crack patch is emitted as one copy.
///
/// A model is regular when every node has at most 8 children after it,
/// node 0 is the root, and every node the closure can reach (parents of
/// inner nodes, balance dependencies, LOD groups) is an inner node; every
/// model the loaders accept and the pipeline builds is. Any other gets no
/// layout, and its cuts read the node arrays (same result, slower).
#[derive(Debug, Clone)]
pub(crate) struct ViewLayout {
    pub(super) hot: Vec<Hot>,
    pub(super) close: Vec<Close>,
    /// Cube edge length per level (as [`McoModel::node_size`]).
    pub(super) sizes: Vec<f32>,
    /// Per rank, at `Close::links_start`: the parent's rank (none for the
    /// root), then the balance dependencies' ranks.
    pub(super) links: Vec<u32>,
    /// The LOD array as ranks (same shape as [`McoModel::lod`]).
    pub(super) lod: Vec<u32>,
    /// Per node and one past: start of its triangles in `tris` (indices).
    pub(super) toff: Vec<u32>,
    /// The triangles in node order, or `None` when [`McoModel::tris`]
    /// already is (then `toff[i]` is node `i`'s `tri_start`).
    pub(super) tris: Option<Vec<u32>>,
    /// Per node and one past: start of its crack patches in `patches`.
    pub(super) poff: Vec<u32>,
    /// `[coarse neighbour's rank (u32::MAX: never expanded), start,
    /// count]` per patch, in node order: a range of `edits` when the node's
    /// bit in `scan` is clear, else of [`McoModel::subs`].
    pub(super) patches: Vec<[u32; 3]>,
    /// A patch prepared at build time: `[position in the node's indices,
    /// new index]`, to write over the node's copied triangles.
    pub(super) edits: Vec<[u32; 2]>,
    /// Per node, set where its patches interact (one index changed by two
    /// patches, or a patch's result changed by another), so that what a
    /// patch writes depends on which others apply: such a node's patches
    /// are applied by scanning its substitutions, in order, as
    /// [`McoModel::emit`] does. Clear for every node of a built model.
    pub(super) scan: Vec<u64>,
    /// Per rank `q` and one past: start of its range of `watchers`.
    pub(super) watch_off: Vec<u32>,
    /// The ranks whose emitted triangles depend on whether rank `q` is
    /// expanded: its parent (`q` is a child it draws or not) and every
    /// node with a child patched against `q`. A cut whose expanded set
    /// differs from the last one's only in ranks none of a node watches
    /// emits that node's triangles as the last cut did.
    pub(super) watchers: Vec<u32>,
    /// Unique per layout built (never 0): what a [`ViewCut`] keeps from
    /// the last cut applies to this layout only.
    pub(super) id: u64,
    /// Whether a kept [`ViewCut`] may update its closure incrementally
    /// (see `closure`): every link goes to a strictly coarser rank, and
    /// every LOD group is one level of ranks whose LOD number is that
    /// group's, each ranked node with a LOD number in its group once. Then
    /// the groups with the ranks outside every group, ordered by level,
    /// make the closure's links acyclic. True for every built model.
    pub(super) incremental: bool,
    /// Whether every subtree bound is finite (true for every built model):
    /// then a subtree's cubes all lie in its root's grown cube, and a
    /// camera that contains the root's sees every node (see `frontier`).
    pub(super) finite: bool,
}

impl Hot {
    /// The ranks of the node's inner children (consecutive, see
    /// `first_inner`).
    #[inline(always)]
    pub(super) fn inner_children(&self) -> std::ops::Range<u32> {
        self.first_inner..self.first_inner + self.inner_mask.count_ones()
    }
}

impl ViewLayout {
    /// The layout of `m`, or `None` when `m` is not regular (see the type
    /// docs) or its arrays do not fit `u32` offsets.
    pub(super) fn build(m: &McoModel, bounds: &[f32]) -> Option<ViewLayout> {
        let n = m.nodes.len();
        if n == 0 || n >= u32::MAX as usize || m.nodes[0].parent != u32::MAX {
            return None;
        }
        let mut rank = vec![u32::MAX; n];
        let mut inner = 0u32;
        for (i, nd) in m.nodes.iter().enumerate() {
            if nd.child_count > 0 {
                if nd.child_count > 8
                    || (nd.first_child as usize) <= i
                    || nd.first_child as usize + nd.child_count as usize > n
                {
                    return None;
                }
                rank[i] = inner;
                inner += 1;
            }
        }
        if inner > 0 && rank[0] != 0 {
            return None;
        }
        let ranked = |x: u32| rank.get(x as usize).copied().filter(|&r| r != u32::MAX);
        let mut hot = Vec::with_capacity(inner as usize);
        let mut close = Vec::with_capacity(inner as usize);
        let mut links = Vec::new();
        for (i, nd) in m.nodes.iter().enumerate() {
            if nd.child_count == 0 {
                continue;
            }
            let (lo, hi) = m.node_box(i as u32);
            let mut inner_mask = 0u8;
            let mut patch_mask = 0u8;
            let mut first_inner = u32::MAX;
            for (j, c) in m.children(i as u32).enumerate() {
                if let Some(r) = ranked(c) {
                    inner_mask |= 1 << j;
                    first_inner = first_inner.min(r);
                }
                if m.nodes[c as usize].patch_count > 0 {
                    patch_mask |= 1 << j;
                }
            }
            hot.push(Hot {
                lo: lo.to_array(),
                err: node_error(m, i as u32),
                bound: bounds[i],
                first_inner,
                grow: lo.abs().max(hi.abs()).max_element() * BOUND_GROWTH + f32::MIN_POSITIVE,
                level: nd.level,
                child_count: nd.child_count,
                inner_mask,
                patch_mask,
            });
            let links_start = u32::try_from(links.len()).ok()?;
            if nd.parent != u32::MAX {
                links.push(ranked(nd.parent)?);
            }
            let d = m
                .deps
                .get(nd.deps_start as usize..nd.deps_start as usize + nd.deps_count as usize)?;
            for &x in d {
                links.push(ranked(x)?);
            }
            let prio = m.prio.get(i).copied().unwrap_or(u32::MAX);
            if prio != u32::MAX && (prio == 0 || prio as usize >= m.groups.len()) {
                return None;
            }
            close.push(Close {
                first_child: nd.first_child,
                links_start,
                links_count: links.len() as u32 - links_start,
                prio,
            });
        }
        if m.groups.first().is_some_and(|&g| g != 0)
            || m.groups.windows(2).any(|w| w[0] > w[1])
            || m.groups.last().is_some_and(|&g| g as usize > m.lod.len())
        {
            return None;
        }
        let lod = m
            .lod
            .iter()
            .map(|&x| ranked(x))
            .collect::<Option<Vec<u32>>>()?;
        // Triangles and patches in node order.
        let mut toff = Vec::with_capacity(n + 1);
        let mut poff = Vec::with_capacity(n + 1);
        let mut patches = Vec::new();
        let mut edits = Vec::new();
        let mut scan = vec![0u64; n.div_ceil(64)];
        let mut subs: Vec<&[[u32; 2]]> = Vec::new();
        let mut writes: Vec<(usize, [u32; 2])> = Vec::new();
        let mut in_order = true;
        let mut t = 0usize;
        for (i, nd) in m.nodes.iter().enumerate() {
            let len = 3 * nd.tri_count as usize;
            if nd.tri_start as usize + len > m.tris.len() {
                return None;
            }
            in_order &= nd.tri_start as usize == t;
            toff.push(u32::try_from(t).ok()?);
            t += len;
            poff.push(u32::try_from(patches.len()).ok()?);
            let ps = m
                .patches
                .get(nd.patch_start as usize..nd.patch_start as usize + nd.patch_count as usize)?;
            if ps.is_empty() {
                continue;
            }
            subs.clear();
            for p in ps {
                subs.push(
                    m.subs.get(
                        p.subs_start as usize..p.subs_start as usize + p.subs_count as usize,
                    )?,
                );
            }
            let own = &m.tris[nd.tri_start as usize..][..len];
            if prepared_edits(own, &subs, &mut writes) {
                for (k, p) in ps.iter().enumerate() {
                    let coarse = ranked(p.coarse).unwrap_or(u32::MAX);
                    let start = u32::try_from(edits.len()).ok()?;
                    edits.extend(writes.iter().filter(|w| w.0 == k).map(|w| w.1));
                    patches.push([coarse, start, edits.len() as u32 - start]);
                }
            } else {
                scan[i >> 6] |= 1 << (i & 63);
                for p in ps {
                    let coarse = ranked(p.coarse).unwrap_or(u32::MAX);
                    patches.push([coarse, p.subs_start, p.subs_count]);
                }
            }
        }
        toff.push(u32::try_from(t).ok()?);
        poff.push(u32::try_from(patches.len()).ok()?);
        let tris = (!in_order).then(|| {
            let mut v = Vec::with_capacity(t);
            for i in 0..n as u32 {
                v.extend_from_slice(m.node_tris(i));
            }
            v
        });
        let top = m.nodes.iter().map(|nd| nd.level).max().unwrap_or(0);
        if top > 31 {
            return None;
        }
        let sizes = (0..=top as u32)
            .map(|l| m.grid.cube * (1u32 << l) as f32)
            .collect();
        let watch_off;
        let watchers;
        {
            // Pairs (watched rank, watcher rank), then a counting sort.
            let mut pairs: Vec<[u32; 2]> = Vec::new();
            for i in 0..n as u32 {
                let Some(r) = ranked(i) else { continue };
                for c in m.children(i) {
                    if let Some(q) = ranked(c) {
                        pairs.push([q, r]);
                    }
                    let c = c as usize;
                    for p in &patches[poff[c] as usize..poff[c + 1] as usize] {
                        if p[0] != u32::MAX {
                            pairs.push([p[0], r]);
                        }
                    }
                }
            }
            // A counting sort by watched rank; stable, so each rank's
            // watchers stay in increasing order and repeats are adjacent.
            let mut off = vec![0u32; inner as usize + 1];
            for p in &pairs {
                off[p[0] as usize + 1] += 1;
            }
            for q in 0..inner as usize {
                off[q + 1] += off[q];
            }
            let mut sorted = vec![0u32; pairs.len()];
            let mut at = off.clone();
            for p in &pairs {
                sorted[at[p[0] as usize] as usize] = p[1];
                at[p[0] as usize] += 1;
            }
            let mut list = Vec::with_capacity(sorted.len());
            for q in 0..inner as usize {
                let start = list.len();
                for &r in &sorted[off[q] as usize..off[q + 1] as usize] {
                    if list.len() == start || list.last() != Some(&r) {
                        list.push(r);
                    }
                }
                off[q] = start as u32;
            }
            off[inner as usize] = list.len() as u32;
            watchers = list;
            watch_off = off;
        }
        let incremental = closure_is_layered(m, &hot, &close, &links, &lod);
        let finite = hot.iter().all(|h| h.bound.is_finite());
        static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);
        Some(ViewLayout {
            id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
            incremental,
            finite,
            watch_off,
            watchers,
            hot,
            close,
            sizes,
            links,
            lod,
            toff,
            tris,
            poff,
            patches,
            edits,
            scan,
        })
    }

    /// Inner nodes (ranks).
    pub(super) fn ranks(&self) -> usize {
        self.hot.len()
    }

    /// A ranked node's cube, bit for bit [`McoModel::node_box`].
    #[inline(always)]
    pub(super) fn cube(&self, h: &Hot) -> (Vec3, Vec3) {
        let lo = Vec3::from_array(h.lo);
        (lo, lo + Vec3::splat(self.sizes[h.level as usize]))
    }

    /// [`ViewLayout::cube`] grown by the node's `grow`: a box that
    /// contains the cube of every node in its subtree.
    #[inline(always)]
    pub(super) fn grown(&self, h: &Hot, lo: Vec3, hi: Vec3) -> (Vec3, Vec3) {
        let g = Vec3::splat(h.grow);
        (lo - g, hi + g)
    }

    #[inline(always)]
    pub(super) fn tris<'a>(&'a self, m: &'a McoModel) -> &'a [u32] {
        self.tris.as_deref().unwrap_or(&m.tris)
    }
}

/// [`ViewLayout::incremental`] for the layout's records: links to
/// strictly coarser ranks, and each group one level of ranks that name it,
/// every ranked node with a LOD number in exactly one group (its own).
fn closure_is_layered(
    m: &McoModel,
    hot: &[Hot],
    close: &[Close],
    links: &[u32],
    lod: &[u32],
) -> bool {
    let coarser = close.iter().zip(hot).all(|(c, h)| {
        links[c.links_start as usize..][..c.links_count as usize]
            .iter()
            .all(|&x| hot[x as usize].level > h.level)
    });
    if !coarser {
        return false;
    }
    let mut seen = vec![false; hot.len()];
    for k in 1..m.groups.len() {
        let g = &lod[m.groups[k - 1] as usize..m.groups[k] as usize];
        let level = g.first().map(|&x| hot[x as usize].level);
        for &x in g {
            let x = x as usize;
            if close[x].prio != k as u32
                || Some(hot[x].level) != level
                || std::mem::replace(&mut seen[x], true)
            {
                return false;
            }
        }
    }
    close
        .iter()
        .zip(&seen)
        .all(|(c, &s)| c.prio == u32::MAX || s)
}

#[inline(always)]
pub(super) fn bit(bits: &[u64], r: u32) -> bool {
    bits[(r >> 6) as usize] >> (r & 63) & 1 != 0
}

/// `v` through one patch's substitutions, in order (as [`McoModel::emit`]
/// applies them).
fn substitute(subs: &[[u32; 2]], mut v: u32) -> u32 {
    for s in subs {
        if v == s[0] {
            v = s[1];
        }
    }
    v
}

/// The `(patch, [position, new index])` writes a node's patches make on
/// its indices `own`, into `writes` (cleared); false when the patches
/// interact. They do not when every index is changed by at most one patch
/// and what it becomes is left alone by every other: then, whichever
/// patches apply and in their order, each index ends as its one patch
/// makes it (or unchanged), and applying a patch is writing its list.
fn prepared_edits(own: &[u32], subs: &[&[[u32; 2]]], writes: &mut Vec<(usize, [u32; 2])>) -> bool {
    writes.clear();
    for (pos, &v) in own.iter().enumerate() {
        let mut changed = None;
        for (p, s) in subs.iter().enumerate() {
            let w = substitute(s, v);
            if w != v {
                if changed.is_some() {
                    return false;
                }
                changed = Some((p, w));
            }
        }
        if let Some((p, w)) = changed {
            let others_keep = subs
                .iter()
                .enumerate()
                .all(|(q, s)| q == p || substitute(s, w) == w);
            if !others_keep {
                return false;
            }
            writes.push((p, [pos as u32, w]));
        }
    }
    true
}
