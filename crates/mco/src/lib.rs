//! The marching cube octree (MCO): continuous level of detail for dense 3D
//! scans, after the thesis "Marching cube octree" (modified marching cubes
//! with edge ratios, a bottom-up octree, node priority numbering, crack
//! patching and LOD mesh generation by referencing only; full citation in
//! `docs/references.md`), chapters 4–6, plus a view-dependent cut from its
//! future work (§8.2).
//!
//! # Using it
//!
//! Build a model once — [`build_from_mesh`], [`build_from_points`],
//! [`build_from_range_images`], [`build_from_conf`], [`build_from_models`],
//! or scan by scan with [`IncrementalBuilder`] —, keep it as a `.mco` file
//! ([`McoModel::save`] / [`McoModel::load`], or [`McoModel::to_bytes`] /
//! [`McoModel::from_bytes`] for an in-memory buffer), then cut it as often
//! as needed. The file is LOD-ordered (`.mco` version 2, deflated chunks)
//! and lossless: the model read back cuts exactly as the model built. Any
//! prefix of it serves every cut up to some LOD number, read with [`McoModel::from_prefix`], or with [`McoStream`] as
//! the bytes arrive; [`McoModel::chunk_table`] lists what each chunk adds.
//! Cuts:
//!
//! - by triangle budget: [`McoModel::extract_triangles`];
//! - by LOD number: [`McoModel::extract_lod`] (`0` = the root cube,
//!   [`McoModel::max_lod`] = every leaf cube);
//! - for a camera, within a pixel error: [`McoModel::extract_view`], or
//!   frame after frame through a [`ViewCut`] (the same cut, its scratch
//!   space kept; each cut costs in proportion to its size, not the
//!   model's).
//!
//! A cut is an index buffer (3 `u32` per triangle, counter-clockwise seen
//! from outside) into the model's one vertex buffer ([`McoModel::positions`],
//! [`McoModel::normals`], [`McoModel::colors`]), which a renderer uploads
//! once. Cuts write into a caller-owned `Vec<u32>`: it is cleared, and its
//! allocation is kept, so a buffer reused from frame to frame allocates
//! only when it grows. [`McoModel::mesh_from_indices`] turns a cut into a
//! standalone [`lodkit_mesh::TriMesh`]. [`McoModel::info`] gives the
//! model's sizes.
//!
//! # Guarantees
//!
//! - **Deterministic.** The same inputs and [`Options`] give the same
//!   model, the same `.mco` bytes and the same index buffers, on every run
//!   and every platform with IEEE `f32` (the build reads no clock, uses no
//!   threads and no randomness).
//! - **Crack-free.** Every cut — any budget, LOD number or camera — joins
//!   the octree levels it mixes without gaps: a finer node's vertices on
//!   the interface with a coarser drawn neighbour are replaced by points on
//!   that neighbour's edges (§5.3), and the nodes whose interface cannot
//!   be patched that way are expanded together. Boundary edges remain only
//!   where the reconstructed surface itself is open (past a scan's edge).
//! - **Bounded.** A cut at LOD number `k` has exactly
//!   [`McoModel::triangles_at_lod`]`(k)` triangles, never more than
//!   [`McoModel::full_triangles`]; every index is below
//!   `positions().len()`.
//! - **No panics on bad data.** Malformed inputs and `.mco` bytes are one
//!   line of [`Error`]; a model that loads extracts safely.
//!
//! # The pipeline, one file per stage
//!
//! | stage | file | thesis |
//! |---|---|---|
//! | oriented samples from range images, meshes, point clouds | `normals_estimation.rs` (`cloud_spacing.rs`: a cloud's spacing) | §4.2, Fig. 4.2, §4.3.1 |
//! | the cube lattice: packed keys, grid, bricks, key map | `lattice.rs` | §4.2 |
//! | sparse signed-distance band | `signed_distance.rs` | §4.2 |
//! | the 256 marching-cubes cases, generated | `marching_cubes_cases.rs` | §2.2.1, §4.2 |
//! | edge-ratio marching cubes (leaves) | `marching_cubes.rs` | §4.2, Fig. 4.1 |
//! | octree, bottom-up four-case rule | `octree_build.rs` (`neighbours.rs`: face neighbours) | §5.1, Fig. 5.2 |
//! | priority numbering, LOD array, accumulation table | `priority_numbering.rs` | §5.2, §5.4.3, §6.1 |
//! | crack patching | `crack_patch.rs` | §5.3, Fig. 5.6, §5.4.4 |
//! | extraction by referencing: §6.1 traversal, birth/death tables | `extraction_by_referencing.rs` | §6.1, §6.2.1 |
//! | view-dependent cut | `view_dependent_cut.rs` | §8.2 (future work) |
//! | the model's arrays, its info | `model.rs` | Fig. 6.1 |
//! | `.mco` files: load, save, shared limits, checks | `mco_file.rs`, `mco_file/{format,validate}.rs` | — (`docs/formats/mco.md`) |
//! | `.mco` version 1 (flat arrays, read) / version 2 (LOD-ordered chunks, prefix reader) | `mco_file/v1.rs` / `mco_file/v2.rs` | — (`docs/formats/mco.md`) |
//! | entry points, incremental builder | `pipeline.rs` | §4.4 |
//! | virtual range scanner | `scanner.rs` | §4.4 (the experiment) |
//!
//! Speed: extraction by LOD number runs at about the speed of a `memcpy`
//! of its output (`lodkit bench mco`); the build's throughput by input
//! size is the `mco_build` criterion bench (`cargo bench -p lodkit-bench
//! --bench mco`); figures in `docs/benchmarks.md`.
//!
//! ```no_run
//! use lodkit_mco::{Camera, McoModel, Options, build_from_mesh};
//! let bunny = lodkit_mesh::io::load_mesh("bunny.ply".as_ref())?;
//! let model = build_from_mesh(&bunny, &Options::default())?;
//! model.save("bunny.mco".as_ref())?;
//! let model = McoModel::load("bunny.mco".as_ref())?;
//! let mut indices = Vec::new(); // reused by every cut
//! model.extract_triangles(10_000, &mut indices);
//! let camera = Camera::looking_at([0.0, 0.1, 0.4].into(), [0.0, 0.1, 0.0].into());
//! model.extract_view(&camera, 1.0, &mut indices);
//! let mesh = model.mesh_from_indices(&indices); // a standalone mesh
//! # Ok::<(), lodkit_mco::Error>(())
//! ```

#![deny(missing_docs)]
// The one `unsafe` block is the SSE2 stamping of the signed-distance band
// (`signed_distance.rs`), allowed there alone; its scalar twin is what
// every other target runs, and a test runs both on the same input.
#![deny(unsafe_code)]

mod band_edge_pruning;
mod cloud_spacing;
mod crack_patch;
mod extraction_by_referencing;
mod lattice;
mod marching_cubes;
// The table's generator keeps a few accessors only its tests read (the case
// each configuration maps to, the face rule derived plainly); the file is
// shared with the cube-symmetry move to lodkit-mesh, so they are allowed
// here rather than gated there.
#[cfg_attr(not(test), allow(dead_code))]
mod marching_cubes_cases;
mod mco_file;
mod model;
mod neighbours;
mod normals_estimation;
mod octree_build;
mod pipeline;
mod priority_numbering;
mod scanner;
mod signed_distance;
mod view_dependent_cut;

#[cfg(test)]
mod tests;

pub use lattice::{Grid, MAX_RESOLUTION};
pub use mco_file::{ChunkInfo, FORMAT_VERSION, Header as McoHeader, McoStream, PartialModel};
pub use model::{LevelInfo, McoModel, ModelInfo};
pub use pipeline::{
    AddReport, IncrementalBuilder, MAX_BUILD_BYTES, Options, all_closed_meshes, build_from_conf,
    build_from_mesh, build_from_models, build_from_points, build_from_range_images, densify_meshes,
    estimate_build_bytes, grid_for, mesh_resolution, samples_of,
};
pub use scanner::{ScanOptions, scan_mesh, write_scans};
pub use view_dependent_cut::{Camera, ViewCut};

/// Errors of the continuous-LOD crate; `Display` is one line.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The input cannot be reconstructed (no samples, no surface, bad option).
    #[error("{0}")]
    Input(String),
    /// `.mco` bytes are malformed (what is wrong, one line).
    #[error("{0}")]
    Format(String),
    /// A `.mco` file cannot be read or is malformed; names the file.
    #[error("{path}: {message}")]
    File {
        /// The file, as given.
        path: String,
        /// What is wrong with it.
        message: String,
    },
    /// Reading or writing geometry failed.
    #[error(transparent)]
    Mesh(#[from] lodkit_mesh::Error),
}

/// `Result` with this crate's [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
