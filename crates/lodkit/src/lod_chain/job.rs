//! What a LOD chain job reads and what it reports.
use std::path::PathBuf;

use lodkit_simplify::{Options, Target};

use crate::output::OutputOptions;
use crate::plan::OutOfCore;

/// One LOD chain: what [`super::run`] reads, writes and how.
#[derive(Debug, Clone)]
pub struct LodChainJob {
    /// Input mesh or scene (any format `lodkit_mesh::io::load` reads).
    pub input: PathBuf,
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// One target a level, each smaller than the one before
    /// ([`lodkit_simplify::halving_targets`] for a halving chain).
    pub targets: Vec<Target>,
    /// The simplifier's options (their target is not used).
    pub options: Options,
    /// Merge a scene into one mesh, dropping materials.
    pub merge: bool,
    /// The memory budget and where out-of-core blocks run.
    pub scale: OutOfCore,
    /// Samples per kind for the measured error; `None`: 4 per face of
    /// each level, within 50 000..=1 000 000.
    pub samples: Option<usize>,
    /// Normals and compression of what is written.
    pub output: OutputOptions,
    /// Send the out-of-core run's notes and each level as events (off when
    /// the caller prints `lods.json` itself and wants nothing else).
    pub notes: bool,
}

/// What [`super::run`] did: `lods.json`'s contents (also written to the
/// output folder) and the one-line summary.
pub struct LodChainReport {
    /// `lods.json` as written.
    pub json: String,
    /// The `wrote …` line.
    pub summary: String,
}
