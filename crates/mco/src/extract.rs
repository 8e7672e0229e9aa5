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
//! By triangle count, the accumulation table gives the LOD number first
//! ([`crate::priority::lod_for_triangles`]).

use lodkit_mesh::TriMesh;

use crate::model::McoModel;

impl McoModel {
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
        for &n in self.lod[..self.groups[k] as usize].iter().rev() {
            for c in self.children(n) {
                if self.prio[c as usize] > kk {
                    self.emit(c, out, &expanded);
                }
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
