//! The built marching cube octree: flat arrays that extraction only reads
//! (Fig. 6.1's "final data structure", without pointers).
//!
//! - `vertices`: every vertex of every level, crack-patched copies
//!   included, built once (a GPU keeps them resident);
//! - `nodes`: breadth-first from the root; a node's children are
//!   contiguous (`first_child .. first_child + child_count`);
//! - `tris`: each node's triangles as 3 vertex indices each, at
//!   `tri_start .. tri_start + 3 * tri_count`;
//! - `lod`: the LOD array (§5.2), nodes in expansion order; LOD number `k`
//!   has expanded `lod[..groups[k]]` — one node per LOD number, except the
//!   few nodes that must expand together (see [`crate::priority_numbering`]);
//!   `prio[n]` is the LOD number that expands `n` (`u32::MAX` for
//!   leaves); `acc[k]` is the accumulation table (§6.1): triangles emitted
//!   at LOD number `k`;
//! - `patches` / `subs`: crack patching (§5.3): when node `n` is drawn
//!   while its coarse neighbour `q` is not expanded, `n`'s vertices listed
//!   in the patch are replaced by their compensation points;
//! - `deps`: balance constraint (§5.2): the nodes that must be expanded
//!   before `n` may be (the parents of `n`'s same-level neighbours).

use glam::Vec3;

use crate::lattice::Grid;
use crate::marching_cubes::VertexBuffer;

/// One octree node (a marching cube at some level).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Node {
    /// Cube coordinates in units of this node's size.
    pub(crate) coord: [u32; 3],
    pub(crate) parent: u32,
    pub(crate) first_child: u32,
    pub(crate) tri_start: u32,
    pub(crate) patch_start: u32,
    pub(crate) deps_start: u32,
    pub(crate) tri_count: u16,
    pub(crate) deps_count: u16,
    pub(crate) child_count: u8,
    /// 0 for leaf cubes; the root has the octree depth.
    pub(crate) level: u8,
    pub(crate) patch_count: u8,
    /// Marching cubes configuration (bit v = corner v inside).
    pub(crate) config: u8,
}

/// Crack patch of one node against one coarse neighbour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub(crate) struct Patch {
    /// The coarse neighbour: the patch applies while it is not expanded.
    pub(crate) coarse: u32,
    pub(crate) subs_start: u32,
    pub(crate) subs_count: u32,
}

/// Figures about the build, saved with the model.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub(crate) struct BuildStats {
    pub(crate) input_samples: u64,
    /// Fine vertices on an interface whose coarse side had no segment to
    /// project onto (left unpatched).
    pub(crate) unpatched: u64,
}

/// A built marching cube octree, ready for extraction: flat arrays that
/// cuts only read (see the module docs of the crate for the entry points).
///
/// `Clone` copies every array; `PartialEq` compares every array (the
/// traversal arrays built lazily by [`McoModel::extract_lod_traversal`]
/// always compare equal: they are a function of the others). The
/// `Default` model is empty: every cut of it is empty.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct McoModel {
    pub(crate) grid: Grid,
    pub(crate) has_colors: bool,
    pub(crate) vertices: VertexBuffer,
    pub(crate) nodes: Vec<Node>,
    pub(crate) tris: Vec<u32>,
    pub(crate) metric: Vec<f32>,
    pub(crate) prio: Vec<u32>,
    pub(crate) lod: Vec<u32>,
    /// LOD number `k` expands `lod[..groups[k]]` (`groups[0] == 0`).
    pub(crate) groups: Vec<u32>,
    pub(crate) acc: Vec<u32>,
    pub(crate) patches: Vec<Patch>,
    pub(crate) subs: Vec<[u32; 2]>,
    pub(crate) deps: Vec<u32>,
    pub(crate) stats: BuildStats,
    /// The §6.1 traversal's arrays (derived, not saved), built on the
    /// first [`McoModel::extract_lod_traversal`]: extraction by LOD number
    /// does not need them.
    pub(crate) traversal: LazyTraversal,
    /// Every drawable triangle version with its life interval, for
    /// extraction by LOD number (derived; see [`crate::extraction_by_referencing`]).
    pub(crate) lifetimes: Lifetimes,
    /// Running maximum of `acc` (derived): the triangle-count lookup is a
    /// binary search over it.
    pub(crate) acc_max: Vec<u32>,
    /// Per node, the largest error in its subtree (derived, built on the
    /// first view-dependent cut; see [`crate::view_dependent_cut`]).
    pub(crate) view_bounds: crate::view_dependent_cut::view_data::LazyViewBounds,
}

/// The traversal's arrays once built. Derived from the other fields, so
/// it never makes two models differ: every `LazyTraversal` compares equal.
#[derive(Debug, Clone, Default)]
pub(crate) struct LazyTraversal(pub std::sync::OnceLock<Traversal>);

impl PartialEq for LazyTraversal {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The §6.1 traversal's prepared arrays (see [`crate::extraction_by_referencing`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Traversal {
    /// Records of inner children, step after step.
    pub(crate) stream: Vec<u32>,
    /// LOD number `k`'s records are `stream[step_start[k-1]..step_start[k]]`.
    pub(crate) step_start: Vec<u32>,
    /// Leaf children's triangles in LOD-step order.
    pub(crate) leaf_block: Vec<u32>,
    /// LOD number `k` draws `leaf_block[..leaf_end[k]]`.
    pub(crate) leaf_end: Vec<u32>,
    /// Leaf crack patches in LOD-step order: `[coarse prio, pairs start,
    /// pairs count]`.
    pub(crate) leaf_patches: Vec<[u32; 3]>,
    /// LOD number `k`'s leaves have `leaf_patches[..leaf_patch_end[k]]`.
    pub(crate) leaf_patch_end: Vec<u32>,
    /// `[position in leaf_block, compensation vertex]`.
    pub(crate) leaf_pairs: Vec<[u32; 2]>,
    /// The leaf patches again as `[coarse prio, step, pairs start, pairs
    /// count]`, by decreasing coarse priority: for a high `k` the
    /// active ones are a short prefix.
    pub(crate) leaf_patches_by_coarse: Vec<[u32; 4]>,
    /// LOD steps that have inner-child records, increasing.
    pub(crate) inner_steps: Vec<u32>,
}

/// The birth/death form of the LOD array (derived, not saved; built by
/// [`McoModel::prepare_extraction`]).
///
/// Record `r` is one triangle, `tris[3r..3r + 3]`, as LOD numbers
/// `birth[r] <= k < death[r]` draw it (crack-patch variants are records of
/// their own). Records are grouped in *death buckets*: bucket `b` holds the
/// records with `death` in `[death_lo[b], death_lo[b - 1])` (bucket 0:
/// never dies), at `bucket_start[b]..bucket_start[b + 1]`, sorted by birth.
/// `cut[cut_start[b] + s]` is the first record of bucket `b` born at or
/// after `s * BIRTH_STRIDE`. `death` starts at bucket 1 (record
/// `bucket_start[1]`): bucket 0's records never die.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Lifetimes {
    pub(crate) tris: Vec<u32>,
    pub(crate) birth: Vec<u32>,
    pub(crate) death: Vec<u32>,
    pub(crate) death_lo: Vec<u32>,
    /// The last death in each bucket (0 when empty).
    pub(crate) death_max: Vec<u32>,
    pub(crate) bucket_start: Vec<u32>,
    pub(crate) cut: Vec<u32>,
    pub(crate) cut_start: Vec<u32>,
    /// Triangles drawn at each LOD number, those crack patching collapses
    /// (two equal indices) left out: what [`McoModel::extract_lod`] gives.
    pub(crate) drawn: Vec<u32>,
}

impl McoModel {
    /// Children of node `n`.
    #[inline]
    pub(crate) fn children(&self, n: u32) -> std::ops::Range<u32> {
        let nd = &self.nodes[n as usize];
        nd.first_child..nd.first_child + nd.child_count as u32
    }

    /// Triangle indices of node `n`.
    #[inline]
    pub(crate) fn node_tris(&self, n: u32) -> &[u32] {
        let nd = &self.nodes[n as usize];
        &self.tris[nd.tri_start as usize..nd.tri_start as usize + 3 * nd.tri_count as usize]
    }

    /// The highest LOD number: every leaf cube drawn (full resolution).
    /// LOD numbers run `0..=max_lod()`; `0` draws the root cube alone.
    /// `O(1)`.
    pub fn max_lod(&self) -> usize {
        self.groups.len().saturating_sub(1)
    }

    /// The nodes LOD number `k` (1-based) expands.
    pub(crate) fn group(&self, k: usize) -> &[u32] {
        &self.lod[self.groups[k - 1] as usize..self.groups[k] as usize]
    }

    /// Triangles at full resolution (LOD number [`McoModel::max_lod`]).
    /// `O(1)`.
    pub fn full_triangles(&self) -> usize {
        self.acc.last().copied().unwrap_or(0) as usize
    }

    /// Per-level (node count, triangles of the nodes of that level),
    /// index = level (0 = leaf cubes).
    pub(crate) fn level_table(&self) -> Vec<(usize, usize)> {
        let levels = self.grid.depth as usize + 1;
        let mut t = vec![(0usize, 0usize); levels];
        for n in &self.nodes {
            let e = &mut t[n.level as usize];
            e.0 += 1;
            e.1 += n.tri_count as usize;
        }
        t
    }

    /// Edge length of a node's cube.
    pub(crate) fn node_size(&self, n: u32) -> f32 {
        self.grid.cube * (1u32 << self.nodes[n as usize].level) as f32
    }

    /// A node's cube as (min corner, max corner).
    pub(crate) fn node_box(&self, n: u32) -> (Vec3, Vec3) {
        let nd = &self.nodes[n as usize];
        let s = self.node_size(n);
        let min = self.grid.origin
            + Vec3::new(nd.coord[0] as f32, nd.coord[1] as f32, nd.coord[2] as f32) * s;
        (min, min + Vec3::splat(s))
    }
}

/// Sizes of one octree level.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LevelInfo {
    /// Nodes (marching cubes) of the level.
    pub nodes: usize,
    /// Triangles of those nodes (all drawn when the level is the cut).
    pub triangles: usize,
}

/// What a built model holds (see [`McoModel::info`]); every count is
/// exact.
#[derive(Debug, Clone, PartialEq)]
pub struct ModelInfo {
    /// The lattice the model was built on.
    pub grid: Grid,
    /// Whether [`McoModel::colors`] carries the input's colours (otherwise
    /// every vertex is opaque grey).
    pub has_colors: bool,
    /// Vertices of every level, crack-patch compensation points included.
    pub vertices: usize,
    /// Octree nodes.
    pub nodes: usize,
    /// Entries of the LOD array (the expandable nodes).
    pub lod_array: usize,
    /// The highest LOD number ([`McoModel::max_lod`]).
    pub lod_numbers: usize,
    /// Triangles at full resolution ([`McoModel::full_triangles`]).
    pub full_triangles: usize,
    /// Crack-patch substitutions (fine vertex → compensation point).
    pub crack_patches: usize,
    /// Oriented samples the model was built from.
    pub input_samples: u64,
    /// Per level, index 0 = the leaf cubes, last = the root.
    pub levels: Vec<LevelInfo>,
    /// Bytes of the arrays extraction by LOD number reads beyond the
    /// stored model (the birth/death tables), built at build or load time.
    pub extraction_table_bytes: usize,
    /// Death buckets of the birth/death tables (`O(log n)` of the
    /// triangle count).
    pub death_buckets: usize,
    /// Bytes of the §6.1 traversal's arrays if built yet (built on the
    /// first [`McoModel::extract_lod_traversal`]; 0 before).
    pub traversal_bytes: usize,
    /// Bytes of the stored triangles (every node's index triples).
    pub stored_triangle_bytes: usize,
}

impl McoModel {
    /// The model's sizes. `O(nodes)`.
    pub fn info(&self) -> ModelInfo {
        let (extraction_table_bytes, traversal_bytes) = self.extraction_bytes();
        ModelInfo {
            grid: self.grid,
            has_colors: self.has_colors,
            vertices: self.vertices.len(),
            nodes: self.nodes.len(),
            lod_array: self.lod.len(),
            lod_numbers: self.max_lod(),
            full_triangles: self.full_triangles(),
            crack_patches: self.subs.len(),
            input_samples: self.stats.input_samples,
            levels: self
                .level_table()
                .into_iter()
                .map(|(nodes, triangles)| LevelInfo { nodes, triangles })
                .collect(),
            extraction_table_bytes,
            death_buckets: self.lifetimes.death_lo.len(),
            traversal_bytes,
            stored_triangle_bytes: 4 * self.tris.len(),
        }
    }

    /// The lattice the model was built on (leaf cube size, origin, depth).
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// The model's bounding cube (the octree root) as (min corner, max
    /// corner), object units; both zero for an empty model.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        if self.nodes.is_empty() {
            return (Vec3::ZERO, Vec3::ZERO);
        }
        self.node_box(0)
    }

    /// Vertex positions (object units): the one vertex buffer every cut
    /// indexes, every level and every crack-patch point included.
    pub fn positions(&self) -> &[Vec3] {
        &self.vertices.positions
    }

    /// Unit vertex normals, one per position (outward).
    pub fn normals(&self) -> &[Vec3] {
        &self.vertices.normals
    }

    /// Vertex colours (RGBA8), one per position: the input's colours when
    /// [`McoModel::has_colors`], else opaque grey.
    pub fn colors(&self) -> &[[u8; 4]] {
        &self.vertices.colors
    }

    /// Whether the input had colours ([`McoModel::colors`] carries them).
    pub fn has_colors(&self) -> bool {
        self.has_colors
    }

    /// Triangles a cut at LOD number `k` has (clamped to
    /// [`McoModel::max_lod`]; 0 for an empty model): the accumulation
    /// table (§6.1) less the triangles crack patching collapses. An index
    /// buffer for it needs `3 ×` this many `u32`.
    /// `O(1)`.
    pub fn triangles_at_lod(&self, k: usize) -> usize {
        let table = self.drawn_table();
        match table.len() {
            0 => 0,
            n => table[k.min(n - 1)] as usize,
        }
    }

    /// Triangles drawn per LOD number: without the ones crack patching
    /// collapses once extraction is prepared, else the stored accumulation
    /// table.
    pub(crate) fn drawn_table(&self) -> &[u32] {
        if self.lifetimes.drawn.len() == self.acc.len() {
            &self.lifetimes.drawn
        } else {
            &self.acc
        }
    }
}
