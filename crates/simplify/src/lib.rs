//! # lodkit-simplify — HQMS discrete LOD chains
//!
//! A linear-time mesh simplifier after Chen, Fahn, Tsai, Chen & Lin,
//! *Generating high-quality discrete LOD meshes for 3D computer games in
//! linear time* (Multimedia Systems 11(5), 2006): iterative full-edge
//! collapse driven by memoryless quadrics, ordered by a constant-size
//! replacement-selection heap inside a single pipeline per pass, with
//! two-stage optimal placement and hole filling. (By default the heap
//! holds one record, so each record under the pass's error threshold is
//! collapsed as soon as it is costed: see [`Options::DEFAULT_HEAP_SIZE`].)
//!
//! ## Entry points
//!
//! | item | what it does |
//! |---|---|
//! | [`simplify`] | one mesh to one budget (`Options::target`) |
//! | [`lod_chain`] | one mesh to several budgets, each level from the previous |
//! | [`halving_targets`] | the targets 1/2, 1/4, … for [`lod_chain`] |
//! | [`Simplifier`] | the same two calls on a reusable workspace (no allocation once warm); `simplify_grouped` / `lod_chain_grouped` keep vertex groups (materials) apart like seams |
//! | [`scene::simplify_scene`], [`scene::scene_lod_chain`] | every mesh of a [`lodkit_mesh::Scene`], materials kept, no crack at material borders |
//! | [`Options`], [`Target`], [`AttributeWeights`] | every knob, with named defaults |
//! | [`Simplified`], [`LevelReport`], [`StopReason`] | the output mesh and why it stopped where it did |
//! | [`Error`] | why simplification could not start |
//!
//! ## Contract (all entry points)
//!
//! - **Input**: any [`TriMesh`]: positions in any unit (errors are reported
//!   in the same unit), CCW faces, optional normals / RGBA8 colours / UVs.
//!   Duplicate positions are welded exactly (bitwise) before simplifying;
//!   corners that differ in an attribute become wedges, so attribute seams
//!   are kept, never torn. Degenerate, non-manifold and unwelded input is
//!   accepted.
//! - **Output size**: at most the target's face count when
//!   [`StopReason::Reached`], and at most one or two faces under it (the
//!   last collapse removes one or two). Otherwise the report says why it
//!   stopped short ([`StopReason`]): the error bound, no valid collapse
//!   left, or the pass limit. A lone triangle is never erased; a target
//!   above the input's face count returns the (welded, compacted) input.
//! - **Guarantees**: a collapse that would flip a face, create a
//!   non-manifold edge or tear a seam is refused; a closed manifold stays
//!   closed and keeps its genus; with
//!   `lock_border` border vertices do not move; vertices are compacted (no
//!   unreferenced vertex) and attributes are interpolated at the placed
//!   vertex. **Deterministic**: the same input and options give the same
//!   output, bit for bit (single-threaded, no hashing order, no clock in
//!   the result).
//! - **Errors** ([`Error`]): an index out of range, a non-finite position,
//!   an attribute array of the wrong length, more than 2³² − 2 vertices or
//!   2³⁰ faces. Never a panic on any input.
//! - **Cost**: `O(V + F)` time per pass (ring table, costing and collapse
//!   are linear, the heap is constant-size); each pass removes up to about
//!   half the vertices, so a level takes a handful of passes. Memory: about
//!   the input's size again, reported exactly by
//!   [`Simplifier::peak_bytes`].
//!
//! ## Stages, one file each (each names its paper section and departures)
//!
//! | stage | file | paper |
//! |---|---|---|
//! | input: weld positions, wedges for attribute seams | `work_mesh.rs` | (§4 input) |
//! | prune small components | `prune.rs` | — |
//! | vertex rings + null/valid/dirty flags | `ring_table.rs` | §4.2, Table 1 |
//! | memoryless (and attribute-extended) quadrics | `quadric.rs` | §3.4 |
//! | cost computation + hole filling | `cost.rs` | §4.3.2 |
//! | replacement-selection heap | `rs_heap.rs` | §3.5 |
//! | full edge collapse, dependency check, placement | `collapse.rs` | §3.3, §4.3.1, §4.3.3 |
//! | one pass (the single pipeline) | `pass.rs` | §4.1, §4.3 |
//! | output / compaction | `output.rs` | §4.4 |
//! | the pass loop, reusable workspace | `simplifier.rs` | §4.1 |
//! | LOD chain | `chain.rs` | §4.4 |
//!
//! ```
//! use lodkit_simplify::{simplify, Options};
//! let sphere = lodkit_mesh::shapes::icosphere(4); // 5,120 triangles
//! let lod = simplify(&sphere, &Options::faces(500)).unwrap();
//! assert!(lod.mesh.faces.len() <= 500 && lod.mesh.faces.len() >= 497);
//! ```
//!
//! Speed and quality against meshoptimizer: `lodkit bench simplify` (the
//! README has the table and the machine). The example `budget` simplifies
//! a file to a face budget; the profiling driver is the bench crate's
//! `simplify_loop` example.

#![deny(missing_docs)]
#![forbid(unsafe_code)]
// `!(x > 0.0)` is how this crate says "not positive, or NaN": the negated
// comparisons are deliberate, so NaN never passes a test meant for numbers.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

mod chain;
mod collapse;
mod cost;
mod options;
mod output;
mod pass;
mod prune;
mod quadric;
mod ring_table;
mod rs_heap;
pub mod scene;
mod simplifier;
mod work_mesh;

use lodkit_mesh::TriMesh;

pub use chain::{halving_targets, lod_chain};
pub use options::{AttributeWeights, Options, Target};
pub use simplifier::Simplifier;

/// Why simplification cannot start (checked before any work is done).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    /// A face refers to a vertex that does not exist.
    #[error("face {face} has vertex index {index} but the mesh has {vertices} vertices")]
    BadIndex {
        /// The face's index.
        face: usize,
        /// The offending vertex index.
        index: u32,
        /// The mesh's vertex count.
        vertices: usize,
    },
    /// This vertex has a NaN or infinite coordinate.
    #[error("vertex {0} has a non-finite coordinate")]
    NonFinite(usize),
    /// `normals`, `colors` or `uvs` is not `positions.len()` long.
    #[error("an attribute array does not have one entry per vertex")]
    AttributeLength,
    /// More vertices than 32-bit indices (minus two reserved values) address.
    #[error("{0} vertices is more than 32-bit indices can address")]
    TooLarge(usize),
    /// More faces than the ring table's 30-bit face numbers address.
    #[error("{0} triangles is more than the ring table can address (2^30)")]
    TooManyFaces(usize),
}

/// Why a level stopped where it did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StopReason {
    /// The face target was reached.
    Reached,
    /// Every remaining collapse would exceed `max_error`.
    MaxError,
    /// No valid collapse is left: every candidate would break the
    /// topology, flip a face or tear a seam (counts from the last pass).
    Blocked {
        /// Collapses refused because they would break the topology.
        topology: usize,
        /// Collapses refused because they would flip a face.
        flip: usize,
        /// Collapses refused because they would tear an attribute seam.
        seam: usize,
    },
    /// `max_passes` passes ran without reaching the target.
    PassLimit,
}

impl std::fmt::Display for StopReason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            StopReason::Reached => write!(f, "reached the target"),
            StopReason::MaxError => write!(
                f,
                "stopped short: the next collapse would exceed --max-error"
            ),
            StopReason::Blocked {
                topology,
                flip,
                seam,
            } => write!(
                f,
                "stopped short: no valid collapse left ({topology} would break the topology, {flip} would flip a face, {seam} would tear an attribute seam)"
            ),
            StopReason::PassLimit => write!(f, "stopped short: pass limit reached"),
        }
    }
}

/// What one level (or one [`simplify`] call) did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelReport {
    /// The face budget asked for.
    pub target_faces: usize,
    /// Triangles in the output.
    pub triangles: usize,
    /// Vertices in the output (wedges count once per attribute value).
    pub vertices: usize,
    /// Estimated object-space distance to the input (largest accumulated
    /// per-vertex bound, in the input's units).
    pub estimated_error: f32,
    /// Passes run since the input (cumulative over a chain).
    pub passes: u32,
    /// Edge collapses performed since the input (cumulative).
    pub collapses: usize,
    /// Why the level stopped where it did.
    pub stop: StopReason,
    /// Set on the last level of an LOD chain that ended before its targets
    /// did ([`lod_chain`]): why the next target could not remove a single
    /// triangle from this level (`Reached` when that target asked for no
    /// fewer triangles than this level has). `None` on every other level
    /// and from [`simplify`].
    pub chain_end: Option<StopReason>,
    /// Wall time of this level: the whole call for `simplify`; for a chain
    /// level, from the previous level's end (the first level includes
    /// loading the input into the workspace).
    pub seconds: f64,
}

/// A simplified mesh and its report.
#[derive(Debug, Clone)]
pub struct Simplified {
    /// The output: compacted, with the input's attributes interpolated.
    pub mesh: TriMesh,
    /// What the call did and why it stopped.
    pub report: LevelReport,
}

/// Simplifies `mesh` to `opts.target` faces (and `opts.max_error`) with a
/// fresh workspace: see the crate docs for the contract (output size,
/// guarantees, errors, cost). To simplify many meshes, keep a
/// [`Simplifier`] and call [`Simplifier::simplify`]: same result, no
/// allocation once its buffers are large enough.
pub fn simplify(mesh: &TriMesh, opts: &Options) -> Result<Simplified, Error> {
    Simplifier::new().simplify(mesh, opts)
}
