//! Run-time LOD mesh generation by referencing only (thesis §6.1–6.2.1).
//!
//! For LOD number `k` the LOD array is walked in reverse, from `lod[k−1]`
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
//! [`McoModel::prepare_extraction`] lays the children of each LOD step out
//! once, in LOD-array order:
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
//! By triangle count, the accumulation table gives the LOD number first
//! ([`crate::priority::lod_for_triangles`]).

use lodkit_mesh::TriMesh;

use crate::model::McoModel;

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

/// Record header: `meta = ntri | npatch << 8 | len << 16` (`len` in words,
/// header included).
const NTRI_MASK: u32 = 0xFF;

impl McoModel {
    /// Builds the extraction stream from the nodes, LOD array, priorities
    /// and patches (`O(n)`, a handful of allocations). Called after
    /// building and after loading.
    pub fn prepare_extraction(&mut self) {
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
        self.stream = stream;
        self.step_start = step_start;
        self.leaf_block = leaf_block;
        self.leaf_end = leaf_end;
        self.leaf_patches = leaf_patches;
        self.leaf_patch_end = leaf_patch_end;
        self.leaf_pairs = leaf_pairs;
        let mut by_coarse: Vec<[u32; 4]> = Vec::with_capacity(self.leaf_patches.len());
        for k in 1..self.leaf_patch_end.len() {
            let range = self.leaf_patch_end[k - 1] as usize..self.leaf_patch_end[k] as usize;
            for &[coarse, start, count] in &self.leaf_patches[range] {
                by_coarse.push([coarse, k as u32, start, count]);
            }
        }
        by_coarse.sort_by(|a, b| b[0].cmp(&a[0]).then(a[1..].cmp(&b[1..])));
        self.leaf_patches_by_coarse = by_coarse;
        self.inner_steps = (1..self.step_start.len())
            .filter(|&k| self.step_start[k] > self.step_start[k - 1])
            .map(|k| k as u32)
            .collect();
    }

    /// Appends node `n`'s triangles to `out`, crack-patched against every
    /// coarse neighbour that `expanded` says is drawn unexpanded.
    #[inline(always)]
    fn emit<F: Fn(u32) -> bool>(&self, n: u32, out: &mut Vec<u32>, expanded: &F) {
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

    /// The index buffer of LOD number `k` (clamped to [`McoModel::max_lod`])
    /// into `out` (cleared first; its allocation is reused). Emits exactly
    /// `acc[k]` triangles.
    pub fn extract_lod(&self, k: usize, out: &mut Vec<u32>) {
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
        if self.step_start.len() != self.groups.len() {
            // Not prepared (a hand-made model): follow the nodes instead.
            for &n in self.lod[..self.groups[k] as usize].iter().rev() {
                for c in self.children(n) {
                    if self.prio[c as usize] > kk {
                        self.emit(c, out, &expanded);
                    }
                }
            }
            return;
        }
        // Leaves: every leaf child of steps 1..=k, in one copy, then the
        // crack patches whose coarse neighbour is still drawn coarse.
        out.extend_from_slice(&self.leaf_block[..self.leaf_end[k] as usize]);
        let by_step = &self.leaf_patches[..self.leaf_patch_end[k] as usize];
        let active = self.leaf_patches_by_coarse.partition_point(|p| p[0] > kk);
        if active < by_step.len() {
            for &[_, step, start, count] in &self.leaf_patches_by_coarse[..active] {
                if step <= kk {
                    for &[pos, v] in &self.leaf_pairs[start as usize..][..count as usize] {
                        out[pos as usize] = v;
                    }
                }
            }
        } else {
            for &[coarse, start, count] in by_step {
                if coarse > kk {
                    for &[pos, v] in &self.leaf_pairs[start as usize..][..count as usize] {
                        out[pos as usize] = v;
                    }
                }
            }
        }
        // Inner children: the reverse-order traversal of §6.1.
        let st = &self.stream[..];
        let steps = self.inner_steps.partition_point(|&s| s <= kk);
        for &step in self.inner_steps[..steps].iter().rev() {
            let step = step as usize;
            let mut p = self.step_start[step - 1] as usize;
            let end = self.step_start[step] as usize;
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

    /// The index buffer closest to `triangles` triangles; returns the LOD
    /// number used.
    pub fn extract_triangles(&self, triangles: usize, out: &mut Vec<u32>) -> usize {
        let k = crate::priority::lod_for_triangles(&self.acc, triangles);
        self.extract_lod(k, out);
        k
    }

    /// The index buffer of an arbitrary balanced cut given by per-node
    /// `expanded` flags (parents of expanded nodes expanded, balance kept;
    /// see [`crate::view_dependent`]).
    pub fn extract_expanded(&self, expanded: &[bool], out: &mut Vec<u32>) {
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

    /// A standalone mesh of an index buffer: only the referenced vertices,
    /// numbered in order of first use, with normals and (if the input had
    /// them) colours.
    pub fn mesh_from_indices(&self, indices: &[u32]) -> TriMesh {
        let mut map = vec![u32::MAX; self.vertices.len()];
        let mut used: Vec<u32> = Vec::new();
        let faces = indices
            .chunks_exact(3)
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

    /// Convenience: the mesh closest to `triangles` triangles.
    pub fn mesh_with_triangles(&self, triangles: usize) -> TriMesh {
        let mut idx = Vec::new();
        self.extract_triangles(triangles, &mut idx);
        self.mesh_from_indices(&idx)
    }

    /// Convenience: the mesh at LOD number `k`.
    pub fn mesh_at_lod(&self, k: usize) -> TriMesh {
        let mut idx = Vec::new();
        self.extract_lod(k, &mut idx);
        self.mesh_from_indices(&idx)
    }
}
