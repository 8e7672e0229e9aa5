//! The arrays a model keeps for its view-dependent cuts, built at its
//! first cut (see `layout` for how): plain data, so that the model can hold
//! them without depending on the cut.

use std::sync::OnceLock;

/// The derived arrays of a model's view-dependent cuts once built (see
/// [`ViewData`]). Derived from the other fields, so it never makes two
/// models differ: every value compares equal.
#[derive(Debug, Clone, Default)]
pub(crate) struct LazyViewBounds(pub(super) OnceLock<ViewData>);

impl PartialEq for LazyViewBounds {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// What a model's view-dependent cuts read beyond the model: the compact
/// layout of a regular model ([`ViewLayout`], every model a loader or the
/// pipeline makes), or only the subtree bounds of any other (a hand-made
/// model; its cuts read the node arrays directly, with the same result).
#[derive(Debug, Clone)]
pub(super) enum ViewData {
    Layout(Box<ViewLayout>),
    Bounds(Vec<f32>),
}

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
