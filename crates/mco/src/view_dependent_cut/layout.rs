//! The compact layout view cuts read (built at a model's first cut, in
//! memory; the `.mco` format is unchanged): 32-byte search records and
//! closure records on inner-node ranks, the per-cut rank bitset, and the
//! triangles in node order so a run of unpatched children is one copy.

use super::*;

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
