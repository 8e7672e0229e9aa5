//! # lodkit-simplify — HQMS discrete LOD chains
//!
//! A linear-time mesh simplifier after Chen, Fahn, Tsai, Chen & Lin,
//! *Generating high-quality discrete LOD meshes for 3D computer games in
//! linear time* (Multimedia Systems, 2006): iterative full-edge collapse
//! driven by memoryless quadrics, ordered by a constant-size
//! replacement-selection heap inside a single pipeline per pass, with
//! two-stage optimal placement and hole filling. (By default the heap
//! holds one record, so each record under the pass's error threshold is
//! collapsed as soon as it is costed: see `Options::DEFAULT_HEAP_SIZE`.)
//!
//! The pipeline, one file per stage (each names its paper section and its
//! departures):
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
//! Performance and quality against meshoptimizer: `lodkit bench simplify`
//! (see the README for the table and the machine). For profiling, the
//! `simplify_loop` example runs one mesh (a file or `blob:N`) to a target
//! repeatedly and prints the best wall and thread CPU time and an output
//! hash: `cargo run --release -p lodkit-simplify --example simplify_loop --
//! MESH 1% 20`.

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
pub mod rs_heap;
mod simplifier;
mod work_mesh;

use lodkit_mesh::TriMesh;

pub use chain::{halving_targets, lod_chain};
pub use options::{AttributeWeights, Options, Target};
pub use simplifier::Simplifier;

/// Why simplification cannot start.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Error {
    #[error("face {face} has vertex index {index} but the mesh has {vertices} vertices")]
    BadIndex {
        face: usize,
        index: u32,
        vertices: usize,
    },
    #[error("vertex {0} has a non-finite coordinate")]
    NonFinite(usize),
    #[error("an attribute array does not have one entry per vertex")]
    AttributeLength,
    #[error("{0} vertices is more than 32-bit indices can address")]
    TooLarge(usize),
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
        topology: usize,
        flip: usize,
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

/// Per-level report.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelReport {
    /// The face budget asked for.
    pub target_faces: usize,
    pub triangles: usize,
    pub vertices: usize,
    /// Estimated object-space distance to the input (largest accumulated
    /// per-vertex bound, in the input's units).
    pub estimated_error: f32,
    /// Passes run since the input (cumulative over a chain).
    pub passes: u32,
    /// Edge collapses performed since the input (cumulative).
    pub collapses: usize,
    pub stop: StopReason,
    /// Wall time of this level: the whole call for `simplify`; for a chain
    /// level, from the previous level's end (the first level includes
    /// loading the input into the workspace).
    pub seconds: f64,
}

/// A simplified mesh and its report.
#[derive(Debug, Clone)]
pub struct Simplified {
    pub mesh: TriMesh,
    pub report: LevelReport,
}

/// Simplifies `mesh` with a fresh workspace; see [`Simplifier::simplify`].
pub fn simplify(mesh: &TriMesh, opts: &Options) -> Result<Simplified, Error> {
    Simplifier::new().simplify(mesh, opts)
}
