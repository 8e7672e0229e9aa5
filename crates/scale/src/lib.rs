//! # lodkit-scale — out-of-core HQMS
//!
//! Meshes larger than memory, simplified in bounded memory: the input (a
//! binary PLY or STL) is streamed twice (positions, then faces) and cut into a grid of blocks on
//! disk; each block is simplified in core with the vertices it shares with
//! other blocks locked, only as far as the final pass needs to fit the
//! budget (so the final pass, seams free, does the rest in global error
//! order, as in core); a second round on a grid shifted by half a block
//! frees the cuts of the first when the result is still too big for
//! memory; the final pass runs the ordinary in-core simplifier on the
//! whole reduced mesh, which releases every remaining lock and lands on
//! the target exactly as the in-core path does. ARCHITECTURE.md
//! ("Out of core") has the design and why.
//!
//! | item | what it does |
//! |---|---|
//! | [`simplify_file`] | a binary PLY file to a simplified [`TriMesh`](lodkit_mesh::TriMesh) in about `memory` bytes |
//! | [`lod_chain_file`] | a binary PLY file to an LOD chain in about `memory` bytes: levels too big for memory as block soups, the rest in core |
//! | [`write_soups_ply`] | a level's block soups to one welded binary PLY, streaming |
//! | [`needs_out_of_core`] | whether a file would not fit the in-core path in `memory` |
//! | [`quality_memory`] | the budget from which the result matches the in-core error |
//! | [`simplify_block`] | one block |
//! | [`Cuts`], [`Grid`] | a round's grid, and which vertices may lie on its cuts (the ones a block locks) |
//! | [`Runner`] | where the blocks run: this process's threads, or Ray tasks (`pylodkit.blocks`) |
//! | [`write_tasks`], [`read_tasks`], [`run_task`] | a round's blocks as a task file, and one task run from it (what a Ray worker does) |
//! | [`staging_dir`] | the resumable staging folder for an input, output and options |
//! | [`StagingLock`], [`remove_staging`], [`remove_abandoned`] | a staging folder held by one run at a time; removed only when no run holds it |
//! | [`finished_blocks`] | blocks an interrupted run left done in a staging folder |
//! | [`default_memory`] | the default budget: a third of `MemTotal` |

#![deny(missing_docs)]
#![forbid(unsafe_code)]

mod block;
mod level_ply;
mod partition;
mod round_manifest;
mod run;
mod runner;
pub mod soup;
mod staging;
mod tasks;

pub use block::{BlockReport, Goal, simplify_block};
pub use level_ply::write_soups_ply;
pub use partition::{Cuts, Grid};
pub use run::{ChainLevel, Event, Report, ScaleOptions, lod_chain_file, simplify_file};
pub use runner::Runner;
pub use staging::{
    LOCK_TEXT, StagingLock, default_memory, finished_blocks, remove_abandoned, remove_staging,
    staging_dir,
};
pub use tasks::{BlockTask, read_tasks, run_task, write_tasks};

/// Bytes per input face the in-core path needs, about: the file's share
/// (a face record and half a vertex, 19 B), the mesh (18 B), the
/// simplifier's workspace (68–69 B per vertex, half a vertex per face).
pub const IN_CORE_BYTES_PER_FACE: u64 = 80;

/// The final pass should hold this many times the target for the result
/// to match the in-core error: with less room the blocks take the mesh
/// most of the way to the target themselves, each in its own error order
/// and with its cuts locked (ARCHITECTURE.md, "lodkit-scale", known gap).
/// 4: every measured run at 2.6× or more was within the quality bounds
/// (mean error within 1.1× in core, max within 1.2×),
/// one at 1.9× (two block rounds) was not.
pub const QUALITY_HEADROOM: u64 = 4;

/// The smallest budget at which [`simplify_file`]'s final pass holds
/// [`QUALITY_HEADROOM`] × `target_faces`, so that the result is expected
/// to match the in-core error (mean within 1.1×, max within 1.2×). Below
/// it the output still hits the target; it is only coarser.
pub fn quality_memory(target_faces: u64) -> u64 {
    target_faces.saturating_mul(QUALITY_HEADROOM * IN_CORE_BYTES_PER_FACE)
}

/// Whether simplifying `path` (`bytes` long) in core would exceed `memory`
/// bytes, at [`IN_CORE_BYTES_PER_FACE`] per face estimated from the file's
/// size (a binary PLY triangle with its share of vertices is about 19
/// bytes; text formats are larger per face, so this overestimates them).
pub fn needs_out_of_core(bytes: u64, memory: u64) -> bool {
    in_core_bytes(bytes, PLY_BYTES_PER_FACE) > memory
}

/// Bytes per triangle of a binary PLY mesh, its share of vertices
/// included, about.
pub const PLY_BYTES_PER_FACE: u64 = 19;

/// Bytes per triangle of a binary STL (a 50-byte facet).
pub const STL_BYTES_PER_FACE: u64 = 50;

/// The in-core path's estimated memory for a file of `bytes` holding
/// `bytes_per_face` per triangle ([`PLY_BYTES_PER_FACE`],
/// [`STL_BYTES_PER_FACE`]), at [`IN_CORE_BYTES_PER_FACE`].
pub fn in_core_bytes(bytes: u64, bytes_per_face: u64) -> u64 {
    (bytes / bytes_per_face.max(1)).saturating_mul(IN_CORE_BYTES_PER_FACE)
}
