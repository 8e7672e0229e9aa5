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
pub struct Node {
    /// Cube coordinates in units of this node's size.
    pub coord: [u32; 3],
    pub parent: u32,
    pub first_child: u32,
    pub tri_start: u32,
    pub patch_start: u32,
    pub deps_start: u32,
    pub tri_count: u16,
    pub deps_count: u16,
    pub child_count: u8,
    /// 0 for leaf cubes; the root has the octree depth.
    pub level: u8,
    pub patch_count: u8,
    /// Marching cubes configuration (bit v = corner v inside).
    pub config: u8,
}

/// Crack patch of one node against one coarse neighbour.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Patch {
    /// The coarse neighbour: the patch applies while it is not expanded.
    pub coarse: u32,
    pub subs_start: u32,
    pub subs_count: u32,
}

/// Figures about the build, saved with the model.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct BuildStats {
    pub input_samples: u64,
    pub build_seconds: f64,
    /// Fine vertices on an interface whose coarse side had no segment to
    /// project onto (left unpatched).
    pub unpatched: u64,
}

/// A marching cube octree ready for extraction.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct McoModel {
    pub grid: Grid,
    pub has_colors: bool,
    pub vertices: VertexBuffer,
    pub nodes: Vec<Node>,
    pub tris: Vec<u32>,
    pub metric: Vec<f32>,
    pub prio: Vec<u32>,
    pub lod: Vec<u32>,
    /// LOD number `k` expands `lod[..groups[k]]` (`groups[0] == 0`).
    pub groups: Vec<u32>,
    pub acc: Vec<u32>,
    pub patches: Vec<Patch>,
    pub subs: Vec<[u32; 2]>,
    pub deps: Vec<u32>,
    pub stats: BuildStats,
    /// The §6.1 traversal's arrays (derived, not saved), built on the
    /// first [`McoModel::extract_lod_traversal`]: extraction by LOD number
    /// does not need them.
    pub traversal: LazyTraversal,
    /// Every drawable triangle version with its life interval, for
    /// extraction by LOD number (derived; see [`crate::extraction_by_referencing`]).
    pub lifetimes: Lifetimes,
    /// Running maximum of `acc` (derived): the triangle-count lookup is a
    /// binary search over it.
    pub acc_max: Vec<u32>,
}

/// The traversal's arrays once built. Derived from the other fields, so
/// it never makes two models differ: every `LazyTraversal` compares equal.
#[derive(Debug, Clone, Default)]
pub struct LazyTraversal(pub std::sync::OnceLock<Traversal>);

impl PartialEq for LazyTraversal {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The §6.1 traversal's prepared arrays (see [`crate::extraction_by_referencing`]).
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Traversal {
    /// Records of inner children, step after step.
    pub stream: Vec<u32>,
    /// LOD number `k`'s records are `stream[step_start[k-1]..step_start[k]]`.
    pub step_start: Vec<u32>,
    /// Leaf children's triangles in LOD-step order.
    pub leaf_block: Vec<u32>,
    /// LOD number `k` draws `leaf_block[..leaf_end[k]]`.
    pub leaf_end: Vec<u32>,
    /// Leaf crack patches in LOD-step order: `[coarse prio, pairs start,
    /// pairs count]`.
    pub leaf_patches: Vec<[u32; 3]>,
    /// LOD number `k`'s leaves have `leaf_patches[..leaf_patch_end[k]]`.
    pub leaf_patch_end: Vec<u32>,
    /// `[position in leaf_block, compensation vertex]`.
    pub leaf_pairs: Vec<[u32; 2]>,
    /// The leaf patches again as `[coarse prio, step, pairs start, pairs
    /// count]`, by decreasing coarse priority: for a high `k` the
    /// active ones are a short prefix.
    pub leaf_patches_by_coarse: Vec<[u32; 4]>,
    /// LOD steps that have inner-child records, increasing.
    pub inner_steps: Vec<u32>,
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
pub struct Lifetimes {
    pub tris: Vec<u32>,
    pub birth: Vec<u32>,
    pub death: Vec<u32>,
    pub death_lo: Vec<u32>,
    /// The last death in each bucket (0 when empty).
    pub death_max: Vec<u32>,
    pub bucket_start: Vec<u32>,
    pub cut: Vec<u32>,
    pub cut_start: Vec<u32>,
}

impl McoModel {
    /// Children of node `n`.
    #[inline]
    pub fn children(&self, n: u32) -> std::ops::Range<u32> {
        let nd = &self.nodes[n as usize];
        nd.first_child..nd.first_child + nd.child_count as u32
    }

    /// Triangle indices of node `n`.
    #[inline]
    pub fn node_tris(&self, n: u32) -> &[u32] {
        let nd = &self.nodes[n as usize];
        &self.tris[nd.tri_start as usize..nd.tri_start as usize + 3 * nd.tri_count as usize]
    }

    /// The highest LOD number (every leaf drawn).
    pub fn max_lod(&self) -> usize {
        self.groups.len().saturating_sub(1)
    }

    /// The nodes LOD number `k` (1-based) expands.
    pub fn group(&self, k: usize) -> &[u32] {
        &self.lod[self.groups[k - 1] as usize..self.groups[k] as usize]
    }

    /// Triangles at full resolution.
    pub fn full_triangles(&self) -> usize {
        self.acc.last().copied().unwrap_or(0) as usize
    }

    /// Per-level (node count, triangles of the nodes of that level),
    /// index = level (0 = leaf cubes).
    pub fn level_table(&self) -> Vec<(usize, usize)> {
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
    pub fn node_size(&self, n: u32) -> f32 {
        self.grid.cube * (1u32 << self.nodes[n as usize].level) as f32
    }

    /// A node's cube as (min corner, max corner).
    pub fn node_box(&self, n: u32) -> (Vec3, Vec3) {
        let nd = &self.nodes[n as usize];
        let s = self.node_size(n);
        let min = self.grid.origin
            + Vec3::new(nd.coord[0] as f32, nd.coord[1] as f32, nd.coord[2] as f32) * s;
        (min, min + Vec3::splat(s))
    }
}
