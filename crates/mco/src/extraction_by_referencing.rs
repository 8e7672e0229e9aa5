//! Run-time LOD mesh generation by referencing only (thesis §6.1–6.2.1),
//! and its birth/death form.
//!
//! **The §6.1 traversal ([`McoModel::extract_lod_traversal`]).** For LOD
//! number `k` the LOD array is walked in reverse, from `lod[k−1]`
//! down to the root: each visited node's children that are not *expanded*
//! are triangulated, and the node is marked expanded. A node is expanded at
//! LOD `k` exactly when its priority number is at most `k`, so the §6.1
//! `expanded` flag is read from the priority array instead of being set
//! and cleared in a scratch array on every call — the same traversal, with
//! no per-extraction reset.
//!
//! Every vertex of every level, crack-patched ones included, lives in the
//! model's single vertex buffer, built once. An extraction emits only an
//! index buffer: each drawn node's precomputed triangle indices are copied
//! as they are, and a node at an interface with a coarser drawn neighbour
//! gets a few indices swapped for the neighbour-specific compensation
//! points (§5.3). No floating-point operation happens here.
//!
//! **Memory layout for speed (a departure in representation only).** The
//! thesis follows pointers from each LOD-array entry to its children. Here
//! the first traversal lays the children of each LOD step out once, in
//! LOD-array order (kept in [`McoModel::traversal`]):
//!
//! - *Leaf* children (never expanded) go to one block, step after step.
//!   LOD `k` draws every leaf child of steps `1..=k`, which is a prefix of
//!   that block: one `memcpy`. Their crack patches become a list, in step
//!   order, of "while the coarse neighbour's priority number is above `k`,
//!   write vertex `v` at output position `p`" records, applied after the
//!   copy.
//! - *Inner* children go to a stream of records (priority number, triangle
//!   indices inline, crack patches with the coarse neighbour's *priority
//!   number* inline), walked in the thesis's reverse order, steps `k..1`:
//!   one contiguous prefix read backwards by step, no pointer chasing.
//!
//! The "`prio > k` ⇒ not expanded" test and the reverse traversal are the
//! thesis's; only the pointer chasing and cache misses are gone. Children
//! with no triangles are left out.
//!
//! **Birth/death tables: what [`McoModel::extract_lod`] reads.** Nodes
//! expand in priority order, so every triangle a node can draw is drawn for
//! an interval of LOD numbers: node `c` is drawn for `prio[parent] <= k <
//! prio[c]`, and its crack patch against a coarse neighbour `q` applies
//! while `k < prio[q]`. Cutting each node's interval at its neighbours'
//! priority numbers gives every *triangle version* (crack-patched ones
//! included) a life `[birth, death)`; LOD `k` draws exactly the versions
//! alive at `k`. That is the same triangle set as the traversal above,
//! tested on several shapes at many `k` (`tests/extraction.rs`), reached
//! without visiting nodes.
//!
//! The records are grouped in *death buckets* and sorted by birth inside
//! each. For a bucket whose deaths all come after `k`, every record born by
//! `k` is alive: a prefix, one `memcpy`. Buckets whose deaths all come by
//! `k` are skipped. Only the one bucket holding `k` is filtered, without
//! branches (each record is written, and the write position advances by
//! `3 · (death > k)`; skipped when the whole bucket died by `k`, as at full
//! size). Buckets are sized so that this one holds at most a sixteenth as
//! many records as the output, and there are `O(log n)` of them, so an extraction costs
//! little more than copying its output (`lodkit bench mco`). The
//! prefix ends are found through a birth table sampled every
//! [`BIRTH_STRIDE`] LOD numbers and a short binary search.
//!
//! The traversal ([`McoModel::extract_lod_traversal`]) stays: it is the
//! thesis's algorithm, the reference the tables are tested against, and
//! the view-dependent cut (`crate::view_dependent_cut`) draws nodes the
//! same way ([`McoModel::emit`]).
//!
//! By triangle count, the accumulation table gives the LOD number first
//! (a binary search over its running maximum, the choice of
//! [`crate::priority_numbering::lod_for_triangles`]).

use lodkit_mesh::TriMesh;

use crate::model::{LazyTraversal, Lifetimes, McoModel, Traversal};

/// One triangle version and the LOD numbers that draw it:
/// `birth <= k < death`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
struct Record {
    tri: [u32; 3],
    birth: u32,
    death: u32,
}

/// Width, in LOD numbers, of one entry of a death bucket's birth table: a
/// prefix lookup reads one entry pair and binary-searches the few records
/// born within this many LOD numbers.
pub(crate) const BIRTH_STRIDE: u32 = 16;

/// A death bucket holds at most `1 / BUCKET_SHARE` as many records as the
/// LOD number where it starts draws triangles (and up to `MIN_BUCKET`
/// records anyway): the one bucket an extraction filters then costs a small
/// fraction of its output, and the buckets stay few (`O(log)` of the
/// triangle count) so the copies of the others stay cheap. 16 is the knee
/// between the two (`lodkit bench mco`: smaller shares filter more, larger
/// ones copy more buckets).
const BUCKET_SHARE: u64 = 16;
const MIN_BUCKET: u64 = 512;

impl Traversal {
    /// Bytes held by the arrays.
    pub(crate) fn bytes(&self) -> usize {
        4 * (self.stream.len()
            + self.step_start.len()
            + self.leaf_block.len()
            + self.leaf_end.len()
            + 3 * self.leaf_patches.len()
            + self.leaf_patch_end.len()
            + 2 * self.leaf_pairs.len()
            + 4 * self.leaf_patches_by_coarse.len()
            + self.inner_steps.len())
    }
}

impl Lifetimes {
    fn from_records(recs: Vec<Record>, acc: &[u32]) -> Lifetimes {
        let max_lod = acc.len().saturating_sub(1);
        // Records dying at each LOD number (the others never die).
        let mut dying = vec![0u64; max_lod + 1];
        for r in &recs {
            if let Some(c) = dying.get_mut(r.death as usize) {
                *c += 1;
            }
        }
        let mut lo = Vec::new();
        let mut e = 0usize;
        while e <= max_lod {
            lo.push(e as u32);
            let cap = (acc.get(e).copied().unwrap_or(0) as u64 / BUCKET_SHARE).max(MIN_BUCKET);
            let mut held = dying[e];
            e += 1;
            while e <= max_lod && held + dying[e] <= cap {
                held += dying[e];
                e += 1;
            }
        }
        // Bucket 0 never dies; then decreasing death ranges down to 0.
        let mut death_lo = vec![(max_lod as u32).saturating_add(1)];
        death_lo.extend(lo.iter().rev());
        let buckets = death_lo.len();
        // Bucket of each death, looked up once per record (every death past
        // `max_lod` is in bucket 0).
        let last = max_lod + 1;
        let bucket_of: Vec<u32> = (0..=last)
            .map(|d| death_lo.partition_point(|&x| x > d as u32) as u32)
            .collect();
        let bucket = |d: u32| bucket_of[(d as usize).min(last)] as usize;
        // The order of a stable sort by (bucket, birth), ties in record
        // (node) order so the layout is deterministic: a counting sort by
        // bucket, then each bucket's (birth, record) keys sorted — distinct
        // keys, so an unstable sort gives exactly that order.
        let mut bucket_start = vec![0u32; buckets + 1];
        for r in &recs {
            bucket_start[bucket(r.death) + 1] += 1;
        }
        for b in 0..buckets {
            bucket_start[b + 1] += bucket_start[b];
        }
        // Two stable counting sorts (LSD): by birth, then by bucket. Records
        // enter in index order, so ties keep it: the order is that of the
        // (bucket, birth, record) keys, without a comparison sort.
        let max_birth = recs.iter().map(|r| r.birth).max().unwrap_or(0) as usize;
        let mut birth_start = vec![0u32; max_birth + 2];
        for r in &recs {
            birth_start[r.birth as usize + 1] += 1;
        }
        for k in 0..=max_birth {
            birth_start[k + 1] += birth_start[k];
        }
        let mut by_birth = vec![0u32; recs.len()];
        for (i, r) in recs.iter().enumerate() {
            let at = &mut birth_start[r.birth as usize];
            by_birth[*at as usize] = i as u32;
            *at += 1;
        }
        drop(birth_start);
        let mut fill = bucket_start.clone();
        let mut order = vec![0u64; recs.len()];
        for &i in &by_birth {
            let r = &recs[i as usize];
            let b = bucket(r.death);
            order[fill[b] as usize] = (r.birth as u64) << 32 | i as u64;
            fill[b] += 1;
        }
        drop(by_birth);
        let birth: Vec<u32> = order.iter().map(|&o| (o >> 32) as u32).collect();
        let mut tris = Vec::with_capacity(3 * recs.len());
        for &o in &order {
            tris.extend_from_slice(&recs[o as u32 as usize].tri);
        }
        let mut cut = Vec::new();
        let mut cut_start = Vec::with_capacity(buckets + 1);
        let mut death_max = Vec::with_capacity(buckets);
        for b in 0..buckets {
            let (start, end) = (bucket_start[b] as usize, bucket_start[b + 1] as usize);
            cut_start.push(cut.len() as u32);
            let entries = if end > start {
                (birth[end - 1] / BIRTH_STRIDE) as usize + 2
            } else {
                1
            };
            for i in 0..entries {
                let from = (i as u64 * BIRTH_STRIDE as u64).min(u32::MAX as u64) as u32;
                cut.push((start + birth[start..end].partition_point(|&x| x < from)) as u32);
            }
            death_max.push(
                order[start..end]
                    .iter()
                    .map(|&o| recs[o as u32 as usize].death)
                    .max()
                    .unwrap_or(0),
            );
        }
        cut_start.push(cut.len() as u32);
        Lifetimes {
            tris,
            // Bucket 0 never dies: its deaths are not kept.
            death: order[bucket_start[1] as usize..]
                .iter()
                .map(|&o| recs[o as u32 as usize].death)
                .collect(),
            birth,
            death_lo,
            death_max,
            bucket_start,
            cut,
            cut_start,
            drawn: Vec::new(),
        }
    }

    /// The end of bucket `b`'s records born at or before `k`.
    #[inline]
    fn born_by(&self, b: usize, k: u32) -> usize {
        let table = &self.cut[self.cut_start[b] as usize..self.cut_start[b + 1] as usize];
        let s = (k / BIRTH_STRIDE) as usize;
        if s + 1 >= table.len() {
            return self.bucket_start[b + 1] as usize;
        }
        let (lo, hi) = (table[s] as usize, table[s + 1] as usize);
        lo + self.birth[lo..hi].partition_point(|&x| x <= k)
    }

    /// Bytes held by the tables.
    pub(crate) fn bytes(&self) -> usize {
        4 * (self.tris.len()
            + self.birth.len()
            + self.death.len()
            + self.death_lo.len()
            + self.death_max.len()
            + self.bucket_start.len()
            + self.cut.len()
            + self.cut_start.len())
    }
}

/// True when two of node `n`'s patches substitute the same vertex (a vertex
/// on the edge between two patched faces): the first patch must win, which
/// the leaf block's unordered patch lists cannot express, so such leaves go
/// through the ordered stream.
fn patches_overlap(m: &McoModel, n: u32) -> bool {
    let nd = &m.nodes[n as usize];
    let patches = &m.patches[nd.patch_start as usize..][..nd.patch_count as usize];
    let mut seen: Vec<u32> = Vec::new();
    for p in patches {
        let subs = &m.subs[p.subs_start as usize..][..p.subs_count as usize];
        if subs.iter().any(|s| seen.contains(&s[0])) {
            return true;
        }
        seen.extend(subs.iter().map(|s| s[0]));
    }
    false
}

/// Whether a triangle has two equal indices: crack patching collapsed one
/// of its edges onto a coarse segment's end (no area, drawn as nothing).
#[inline]
fn degenerate(t: [u32; 3]) -> bool {
    t[0] == t[1] || t[1] == t[2] || t[0] == t[2]
}

/// Drops the triangles of `out[from..]` that crack patching collapsed
/// ([`degenerate`]), keeping the others in order. `O(len)`.
pub(crate) fn drop_degenerate(out: &mut Vec<u32>, from: usize) {
    let mut w = from;
    for r in (from..out.len()).step_by(3) {
        if r + 3 > out.len() {
            break;
        }
        let t = [out[r], out[r + 1], out[r + 2]];
        if !degenerate(t) {
            out[w..w + 3].copy_from_slice(&t);
            w += 3;
        }
    }
    out.truncate(w);
}

/// Record header: `meta = ntri | npatch << 8 | len << 16` (`len` in words,
/// header included).
const NTRI_MASK: u32 = 0xFF;

impl McoModel {
    /// Builds the extraction stream from the nodes, LOD array, priorities
    /// and patches (`O(n)`, a handful of allocations). Called after
    /// building and after loading.
    pub(crate) fn prepare_extraction(&mut self) {
        self.traversal = LazyTraversal::default();
        self.lifetimes = self.lifetimes();
        let mut best = 0u32;
        self.acc_max = self
            .drawn_table()
            .iter()
            .map(|&a| {
                best = best.max(a);
                best
            })
            .collect();
    }

    /// The traversal's arrays: the leaf block with its patch lists and
    /// the inner-child record stream (see the module docs).
    fn traversal_arrays(&self) -> Traversal {
        let mut stream = Vec::with_capacity(self.tris.len() / 4 + 2 * self.nodes.len());
        let mut step_start = Vec::with_capacity(self.groups.len());
        let mut leaf_block = Vec::with_capacity(self.tris.len());
        let mut leaf_end = Vec::with_capacity(self.groups.len());
        let mut leaf_patches = Vec::new();
        let mut leaf_patch_end = Vec::with_capacity(self.groups.len());
        let mut leaf_pairs = Vec::new();
        let mut inner: Vec<u32> = Vec::new();
        step_start.push(0u32);
        leaf_end.push(0u32);
        leaf_patch_end.push(0u32);
        for k in 1..self.groups.len() {
            for &n in self.group(k) {
                for c in self.children(n) {
                    let nd = self.nodes[c as usize];
                    if nd.tri_count == 0 {
                        continue;
                    }
                    let patches =
                        &self.patches[nd.patch_start as usize..][..nd.patch_count as usize];
                    if nd.child_count == 0 && !patches_overlap(self, c) {
                        // A leaf: drawn from its parent's step on, for good.
                        let base = leaf_block.len();
                        leaf_block.extend_from_slice(self.node_tris(c));
                        for p in patches {
                            let start = leaf_pairs.len() as u32;
                            for s in &self.subs[p.subs_start as usize..][..p.subs_count as usize] {
                                for (i, &v) in leaf_block[base..].iter().enumerate() {
                                    if v == s[0] {
                                        leaf_pairs.push([(base + i) as u32, s[1]]);
                                    }
                                }
                            }
                            let count = leaf_pairs.len() as u32 - start;
                            if count > 0 {
                                leaf_patches.push([self.prio[p.coarse as usize], start, count]);
                            }
                        }
                        continue;
                    }
                    inner.push(c);
                }
            }
            // Inner children by decreasing priority number: at LOD k the
            // drawn ones (prio > k) come first, so a step stops at the
            // first expanded child.
            inner.sort_by_key(|&c| std::cmp::Reverse(self.prio[c as usize]));
            for c in inner.drain(..) {
                let nd = self.nodes[c as usize];
                let patches = &self.patches[nd.patch_start as usize..][..nd.patch_count as usize];
                {
                    let head = stream.len();
                    stream.push(self.prio[c as usize]);
                    stream.push(0);
                    stream.extend_from_slice(self.node_tris(c));
                    // Patches resolved to positions in the record's output:
                    // [coarse prio, pairs, (offset, vertex)…], stored last
                    // patch first so that, applied in stream order, an
                    // earlier patch overrides a later one on a shared vertex
                    // (as sequential substitution in `emit` does).
                    let tris = self.node_tris(c);
                    for p in patches.iter().rev() {
                        stream.push(self.prio[p.coarse as usize]);
                        let count_at = stream.len();
                        stream.push(0);
                        for s in &self.subs[p.subs_start as usize..][..p.subs_count as usize] {
                            for (i, &v) in tris.iter().enumerate() {
                                if v == s[0] {
                                    stream.extend_from_slice(&[i as u32, s[1]]);
                                }
                            }
                        }
                        stream[count_at] = ((stream.len() - count_at - 1) / 2) as u32;
                    }
                    let len = (stream.len() - head) as u32;
                    debug_assert!(nd.tri_count as u32 <= NTRI_MASK && len < 1 << 16);
                    stream[head + 1] =
                        nd.tri_count as u32 | (nd.patch_count as u32) << 8 | len << 16;
                }
            }
            step_start.push(stream.len() as u32);
            leaf_end.push(leaf_block.len() as u32);
            leaf_patch_end.push(leaf_patches.len() as u32);
        }
        let mut by_coarse: Vec<[u32; 4]> = Vec::with_capacity(leaf_patches.len());
        for k in 1..leaf_patch_end.len() {
            let range = leaf_patch_end[k - 1] as usize..leaf_patch_end[k] as usize;
            for &[coarse, start, count] in &leaf_patches[range] {
                by_coarse.push([coarse, k as u32, start, count]);
            }
        }
        by_coarse.sort_by(|a, b| b[0].cmp(&a[0]).then(a[1..].cmp(&b[1..])));
        let inner_steps = (1..step_start.len())
            .filter(|&k| step_start[k] > step_start[k - 1])
            .map(|k| k as u32)
            .collect();
        Traversal {
            stream,
            step_start,
            leaf_block,
            leaf_end,
            leaf_patches,
            leaf_patch_end,
            leaf_pairs,
            leaf_patches_by_coarse: by_coarse,
            inner_steps,
        }
    }

    /// The birth/death records of every triangle version (see
    /// [`crate::model::Lifetimes`] and the module docs).
    fn lifetimes(&self) -> Lifetimes {
        let mut recs: Vec<Record> = Vec::with_capacity(self.tris.len() / 3 + self.subs.len());
        let mut cuts: Vec<u32> = Vec::new();
        let mut open: Vec<Record> = Vec::new();
        let mut now: Vec<u32> = Vec::new();
        for c in 0..self.nodes.len() as u32 {
            let nd = self.nodes[c as usize];
            if nd.tri_count == 0 {
                continue;
            }
            // Drawn while the parent is expanded and `c` is not.
            let birth = if nd.parent == u32::MAX {
                0
            } else {
                self.prio[nd.parent as usize]
            };
            let death = self.prio[c as usize];
            if birth >= death {
                continue; // never drawn (only in a malformed file)
            }
            // The node's triangles change where a patch's coarse neighbour
            // expands inside the node's life.
            let patches = &self.patches[nd.patch_start as usize..][..nd.patch_count as usize];
            cuts.clear();
            cuts.push(birth);
            cuts.extend(
                patches
                    .iter()
                    .map(|p| self.prio[p.coarse as usize])
                    .filter(|&q| birth < q && q < death),
            );
            cuts.sort_unstable();
            cuts.dedup();
            cuts.push(death);
            // One open record per triangle, extended while its version
            // stays the same from one piece of the life to the next.
            open.clear();
            for w in cuts.windows(2) {
                let (from, to) = (w[0], w[1]);
                now.clear();
                self.emit(c, &mut now, &|n: u32| self.prio[n as usize] <= from);
                for (t, tri) in now.chunks_exact(3).enumerate() {
                    let tri = [tri[0], tri[1], tri[2]];
                    match open.get_mut(t) {
                        Some(r) if r.tri == tri => r.death = to,
                        Some(r) => {
                            if !degenerate(r.tri) {
                                recs.push(*r);
                            }
                            *r = Record {
                                tri,
                                birth: from,
                                death: to,
                            };
                        }
                        None => open.push(Record {
                            tri,
                            birth: from,
                            death: to,
                        }),
                    }
                }
            }
            recs.extend(open.iter().filter(|r| !degenerate(r.tri)));
        }
        // Triangles drawn per LOD number: +1 at each birth, −1 at each death.
        let n = self.acc.len();
        let mut step = vec![0i64; n + 1];
        for r in &recs {
            step[(r.birth as usize).min(n)] += 1;
            step[(r.death as usize).min(n)] -= 1;
        }
        let mut live = 0i64;
        let drawn = step[..n]
            .iter()
            .map(|d| {
                live += d;
                live.clamp(0, u32::MAX as i64) as u32
            })
            .collect();
        let mut lt = Lifetimes::from_records(recs, &self.acc);
        lt.drawn = drawn;
        lt
    }

    /// Bytes held by the derived extraction arrays beyond the stored model:
    /// (birth/death tables, the traversal's arrays if built yet).
    pub(crate) fn extraction_bytes(&self) -> (usize, usize) {
        (
            self.lifetimes.bytes() + 4 * self.acc_max.len(),
            self.traversal.0.get().map_or(0, Traversal::bytes),
        )
    }

    /// Appends node `n`'s triangles to `out`, crack-patched against every
    /// coarse neighbour that `expanded` says is drawn unexpanded.
    #[inline(always)]
    pub(crate) fn emit<F: Fn(u32) -> bool>(&self, n: u32, out: &mut Vec<u32>, expanded: &F) {
        let nd = &self.nodes[n as usize];
        let start = out.len();
        out.extend_from_slice(&self.tris[nd.tri_start as usize..][..3 * nd.tri_count as usize]);
        if nd.patch_count == 0 {
            return;
        }
        for p in &self.patches[nd.patch_start as usize..][..nd.patch_count as usize] {
            if expanded(p.coarse) {
                continue;
            }
            let subs = &self.subs[p.subs_start as usize..][..p.subs_count as usize];
            for idx in &mut out[start..] {
                for s in subs {
                    if *idx == s[0] {
                        *idx = s[1];
                    }
                }
            }
        }
    }

    /// The cut at LOD number `k`: its index buffer into `out`.
    ///
    /// - `k`: a LOD number, clamped to [`McoModel::max_lod`]; `0` is the
    ///   root cube alone, and each step up expands one node (or the few
    ///   that must expand together) in the thesis's priority order.
    /// - `out`: cleared, then filled with exactly
    ///   [`McoModel::triangles_at_lod`]`(k)` triangles, 3 indices each,
    ///   into [`McoModel::positions`]; its allocation is reused (it grows
    ///   to at most `3 ×` [`McoModel::full_triangles`]).
    /// - Crack-free and deterministic (see the crate docs); the same
    ///   triangle set as [`McoModel::extract_lod_traversal`], in another
    ///   order.
    /// - Cost: close to a `memcpy` of the output: every death bucket
    ///   whose records all outlive `k` gives its records born by `k` in
    ///   one copy, and only the bucket holding `k` is filtered, without
    ///   branches. No floating-point operation, no allocation once `out`
    ///   is large enough.
    pub fn extract_lod(&self, k: usize, out: &mut Vec<u32>) {
        out.clear();
        let lt = &self.lifetimes;
        if lt.bucket_start.is_empty() {
            // Not prepared (a hand-made model).
            self.extract_lod_traversal(k, out);
            return;
        }
        let k = k.min(self.max_lod());
        out.reserve(3 * self.acc.get(k).copied().unwrap_or(0) as usize + 3);
        let k = k as u32;
        let immortal = lt.bucket_start[1] as usize;
        for (b, &lo) in lt.death_lo.iter().enumerate() {
            let start = lt.bucket_start[b] as usize;
            let end = lt.born_by(b, k);
            if lo > k {
                // Every record of this bucket dies after `k`.
                out.extend_from_slice(&lt.tris[3 * start..3 * end]);
                continue;
            }
            // The bucket holding `k`; the ones after it died by `k`, and so
            // may this one (at full size, all of it).
            if lt.death_max[b] <= k {
                break;
            }
            let base = out.len();
            out.resize(base + 3 * (end - start) + 3, 0);
            let dst = &mut out[base..];
            let mut w = 0;
            for (t, &d) in lt.tris[3 * start..3 * end]
                .chunks_exact(3)
                .zip(&lt.death[start - immortal..end - immortal])
            {
                dst[w..w + 3].copy_from_slice(t);
                w += 3 * usize::from(d > k);
            }
            out.truncate(base + w);
            break;
        }
    }

    /// The cut at LOD number `k` by the thesis's §6.1 reverse-order
    /// traversal of the LOD array, into `out` (cleared first; its
    /// allocation is reused): the same triangles as
    /// [`McoModel::extract_lod`], in another order, with the same bounds.
    /// The reference the birth/death tables are tested against; slower
    /// than [`McoModel::extract_lod`] at most sizes. Its arrays are built
    /// on the first call (`O(n)`, about the size of the stored triangles;
    /// thread-safe).
    pub fn extract_lod_traversal(&self, k: usize, out: &mut Vec<u32>) {
        self.traversal_with_collapsed(k, out);
        drop_degenerate(out, 0);
    }

    /// [`McoModel::extract_lod_traversal`] with the triangles crack
    /// patching collapses still in.
    fn traversal_with_collapsed(&self, k: usize, out: &mut Vec<u32>) {
        out.clear();
        if self.nodes.is_empty() {
            return;
        }
        let k = k.min(self.max_lod());
        out.reserve((3 * self.acc[k] as usize).min(self.tris.len()));
        let kk = k as u32;
        let expanded = |n: u32| self.prio[n as usize] <= kk;
        if k == 0 {
            self.emit(0, out, &expanded);
            return;
        }
        let t = self.traversal.0.get_or_init(|| self.traversal_arrays());
        // Leaves: every leaf child of steps 1..=k, in one copy, then the
        // crack patches whose coarse neighbour is still drawn coarse.
        out.extend_from_slice(&t.leaf_block[..t.leaf_end[k] as usize]);
        let by_step = &t.leaf_patches[..t.leaf_patch_end[k] as usize];
        let active = t.leaf_patches_by_coarse.partition_point(|p| p[0] > kk);
        if active < by_step.len() {
            for &[_, step, start, count] in &t.leaf_patches_by_coarse[..active] {
                if step <= kk {
                    for &[pos, v] in &t.leaf_pairs[start as usize..][..count as usize] {
                        out[pos as usize] = v;
                    }
                }
            }
        } else {
            for &[coarse, start, count] in by_step {
                if coarse > kk {
                    for &[pos, v] in &t.leaf_pairs[start as usize..][..count as usize] {
                        out[pos as usize] = v;
                    }
                }
            }
        }
        // Inner children: the reverse-order traversal of §6.1.
        let st = &t.stream[..];
        let steps = t.inner_steps.partition_point(|&s| s <= kk);
        for &step in t.inner_steps[..steps].iter().rev() {
            let step = step as usize;
            let mut p = t.step_start[step - 1] as usize;
            let end = t.step_start[step] as usize;
            while p < end {
                let prio = st[p];
                let meta = st[p + 1];
                let len = (meta >> 16) as usize;
                if prio > kk {
                    let ntri = (meta & NTRI_MASK) as usize;
                    let npatch = (meta >> 8 & 0xFF) as usize;
                    let o = out.len();
                    let tri_end = p + 2 + 3 * ntri;
                    // Records hold a few triangles: an inline copy beats a
                    // memcpy call.
                    for &x in &st[p + 2..tri_end] {
                        out.push(x);
                    }
                    let mut q = tri_end;
                    for _ in 0..npatch {
                        let coarse = st[q];
                        let ns = st[q + 1] as usize;
                        if coarse > kk {
                            for pair in st[q + 2..q + 2 + 2 * ns].chunks_exact(2) {
                                out[o + pair[0] as usize] = pair[1];
                            }
                        }
                        q += 2 + 2 * ns;
                    }
                } else {
                    break; // the rest of this step is expanded
                }
                p += len;
            }
        }
    }

    /// The cut closest to a triangle budget: the LOD number whose triangle
    /// count is nearest to `triangles` ([`McoModel::lod_for_triangles`]),
    /// extracted as by [`McoModel::extract_lod`] into `out` (cleared; its
    /// allocation reused). Returns the LOD number used.
    ///
    /// The count can miss the budget, above or below, by at most the
    /// triangles one LOD step adds (one node's expansion, or one group's);
    /// a budget above [`McoModel::full_triangles`] gives full resolution,
    /// 0 gives the root. Cost: `O(log n)` lookup plus
    /// [`McoModel::extract_lod`].
    pub fn extract_triangles(&self, triangles: usize, out: &mut Vec<u32>) -> usize {
        let k = self.lod_for_triangles(triangles);
        self.extract_lod(k, out);
        k
    }

    /// The LOD number whose triangle count is closest to `triangles` (ties
    /// to the higher one), by binary search over the running maximum of the
    /// accumulation table (which is not monotone: an expansion can lower
    /// the count). `O(log n)`. The same choice as
    /// `priority_numbering::lod_for_triangles`'s linear scan.
    pub fn lod_for_triangles(&self, triangles: usize) -> usize {
        let table = self.drawn_table();
        if self.acc_max.len() != table.len() || table.is_empty() {
            return crate::priority_numbering::lod_for_triangles(table, triangles);
        }
        let target = triangles.min(u32::MAX as usize) as u32;
        let k = self.acc_max.partition_point(|&a| a < target);
        if k == self.acc.len() {
            return k - 1;
        }
        if k == 0 {
            return 0;
        }
        let (hi, lo) = (table[k].abs_diff(target), table[k - 1].abs_diff(target));
        if lo < hi { k - 1 } else { k }
    }

    /// The plain §6.1 traversal over the nodes (no prepared arrays): the LOD
    /// array from `lod[groups[k] - 1]` back to the root, drawing each
    /// visited node's children that are not expanded. Slow; kept as the
    /// definition the prepared forms are tested against.
    #[cfg(test)]
    pub(crate) fn extract_lod_nodes(&self, k: usize, out: &mut Vec<u32>) {
        self.nodes_with_collapsed(k, out);
        drop_degenerate(out, 0);
    }

    #[cfg(test)]
    fn nodes_with_collapsed(&self, k: usize, out: &mut Vec<u32>) {
        out.clear();
        if self.nodes.is_empty() {
            return;
        }
        let k = k.min(self.max_lod());
        let kk = k as u32;
        let expanded = |n: u32| self.prio[n as usize] <= kk;
        if k == 0 {
            self.emit(0, out, &expanded);
            return;
        }
        for &n in self.lod[..self.groups[k] as usize].iter().rev() {
            for c in self.children(n) {
                if self.prio[c as usize] > kk {
                    self.emit(c, out, &expanded);
                }
            }
        }
    }

    /// The index buffer of an arbitrary balanced cut given by per-node
    /// `expanded` flags (parents of expanded nodes expanded, balance kept;
    /// see [`crate::view_dependent_cut`]), by a scan of every node: the
    /// reference `ViewCut`'s walk from the root is tested against.
    #[cfg(test)]
    pub(crate) fn extract_expanded(&self, expanded: &[bool], out: &mut Vec<u32>) {
        out.clear();
        if self.nodes.is_empty() {
            return;
        }
        let is = |n: u32| expanded[n as usize];
        if !expanded[0] {
            self.emit(0, out, &is);
            return;
        }
        for n in 0..self.nodes.len() as u32 {
            if !expanded[n as usize] {
                continue;
            }
            for c in self.children(n) {
                if !expanded[c as usize] {
                    self.emit(c, out, &is);
                }
            }
        }
    }

    /// A standalone mesh of a cut's index buffer: only the vertices it
    /// references, numbered in order of first use, with their normals and
    /// (when [`McoModel::has_colors`]) colours. Triangles with two equal
    /// indices (where crack patching moved a fine vertex onto a coarse
    /// segment's end: no area, drawn as nothing) are left out. `indices`
    /// must come from this model's cuts (every index below
    /// `positions().len()`; panics otherwise); a trailing partial triangle
    /// is ignored. `O(vertices + indices)`, one allocation per attribute.
    pub fn mesh_from_indices(&self, indices: &[u32]) -> TriMesh {
        let mut map = vec![u32::MAX; self.vertices.len()];
        let mut used: Vec<u32> = Vec::new();
        let faces = indices
            .chunks_exact(3)
            .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
            .map(|t| {
                std::array::from_fn(|k| {
                    let v = t[k] as usize;
                    if map[v] == u32::MAX {
                        map[v] = used.len() as u32;
                        used.push(v as u32);
                    }
                    map[v]
                })
            })
            .collect();
        let vb = &self.vertices;
        TriMesh {
            positions: used.iter().map(|&v| vb.positions[v as usize]).collect(),
            normals: Some(used.iter().map(|&v| vb.normals[v as usize]).collect()),
            colors: self
                .has_colors
                .then(|| used.iter().map(|&v| vb.colors[v as usize]).collect()),
            uvs: None,
            faces,
        }
    }

    /// Convenience: [`McoModel::extract_triangles`] then
    /// [`McoModel::mesh_from_indices`] (allocates every call).
    pub fn mesh_with_triangles(&self, triangles: usize) -> TriMesh {
        let mut idx = Vec::new();
        self.extract_triangles(triangles, &mut idx);
        self.mesh_from_indices(&idx)
    }

    /// Convenience: [`McoModel::extract_lod`] then
    /// [`McoModel::mesh_from_indices`] (allocates every call).
    pub fn mesh_at_lod(&self, k: usize) -> TriMesh {
        let mut idx = Vec::new();
        self.extract_lod(k, &mut idx);
        self.mesh_from_indices(&idx)
    }
}
