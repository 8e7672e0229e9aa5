//! # lodkit-particles
//!
//! Progressive octree particles after Yemez & Schmitt, "Multilevel
//! representation and transmission of real objects with progressive octree
//! particles" (IEEE TVCG 2003): a dense surface becomes an octree (§4),
//! thinned (§4.3) and ordered so that each level adds one difference set
//! of ON leaves (§4.4); each leaf is a particle with a vertex and averaged
//! attributes (§5); the octree is coded hierarchically with scalable vertex
//! precision (§7), and a viewer triangulates each decoded level directly
//! from a 256-case table (§6).
//!
//! ## Entry points
//!
//! | call | does |
//! |---|---|
//! | [`encode`] | mesh, points or range image → `.pop` bytes ([`EncodeOptions`]) |
//! | [`read_header`], [`ChunkReader`] | parse the container: header, then chunks |
//! | [`decode`] | a whole stream, or a prefix of whole chunks, up to a level / precision ([`DecodeOptions`]); strict |
//! | [`decode_prefix`] | what has arrived: every complete chunk of a byte prefix, and where it stopped ([`Decoded::cut`]) |
//! | [`PrefixDecoder`] | the same for bytes still arriving, each chunk decoded once over all reads |
//! | [`Decoded::surface`], [`Decoded::triangulate`] | one level's particles, or its oriented mesh |
//! | [`triangulate`], [`triangulate_owned`] | a level's particles → [`lodkit_mesh::TriMesh`] ([`TriangulateOptions`]) |
//! | [`orient`] | turns a mesh's triangles outwards |
//! | [`stream_stats`], [`progressive_levels`] | Table 1 per level; every level's mesh with the bytes it needs |
//!
//! Every call is deterministic (same input and options, same bytes or
//! triangles), and no byte sequence makes a decoder panic or allocate more
//! than its counts, checked against the bytes present, allow (the decoder
//! is fuzzed: `crates/particles/fuzz`). Errors are [`Error`]: bad input
//! to the encoder, or an invalid stream with the chunk and the reason.
//!
//! ## Pipeline
//!
//! Octree and labels (`octree.rs`) → thinning (`thinning.rs`) →
//! progressive ordering (`ordering.rs`) → attributes (`attributes.rs`) →
//! coding (`coding/`: `levels.rs` and `precision_layers.rs` over the
//! symbol interface `bit_coder.rs`, with `raw_bits.rs` or `range_coder.rs`
//! and the entropy mode's `contexts.rs` and `links.rs`) → container
//! (`container.rs`); and back: `decode.rs` → `level_surface.rs` (one level's particles) → `triangulate/` (the 256
//! cases in `triangulation_table.rs`, then `orientation.rs`) → `stats.rs`.
//!
//! ## What to expect
//!
//! About 5 structure bits per particle in the baseline mode (the paper's
//! 5.1) and about half that in the entropy mode; triangles ≈ 2 × particles
//! per level. Figures and the commands that reproduce them:
//! `docs/benchmarks.md` (`cargo bench -p lodkit-bench --bench pop`);
//! `lodkit pop stats FILE` prints Table 1 for any stream.
//!
//! ```no_run
//! use lodkit_particles::{DecodeOptions, EncodeOptions, TriangulateOptions, decode_prefix, encode};
//! let bunny = lodkit_mesh::io::load(std::path::Path::new("bunny.ply")).unwrap();
//! let pop = encode(&bunny, &EncodeOptions::DEFAULT).unwrap();
//! // The first half of the stream, as a viewer receiving it has it.
//! let arrived = &pop.bytes[..pop.bytes.len() / 2];
//! let d = decode_prefix(arrived, &DecodeOptions::default()).unwrap();
//! let mesh = d.triangulate(d.finest_level(), &TriangulateOptions::DEFAULT).unwrap().mesh;
//! ```
// Octree code walks parallel per-node arrays (cells, labels, particles)
// by index; iterator chains over three of them read worse.
#![allow(clippy::needless_range_loop)]
// Every public item is documented; the unstable `internals` (bench only)
// re-export stages that are not.
#![cfg_attr(not(feature = "internals"), deny(missing_docs))]
#![forbid(unsafe_code)]

pub(crate) mod attributes;
pub(crate) mod coding;
pub(crate) mod container;
pub(crate) mod decode;
pub(crate) mod decode_stream;
pub(crate) mod encode;
pub(crate) mod error;
pub(crate) mod level_surface;
pub(crate) mod octree;
pub(crate) mod ordering;
pub(crate) mod orientation;
#[cfg(test)]
mod progressive_tests;
#[cfg(feature = "silhouettes")]
pub mod silhouette;
pub(crate) mod stats;
pub(crate) mod thinning;
pub(crate) mod triangulate;
pub(crate) mod triangulation_table;

pub use container::{
    CHUNK_HEADER_LEN, Chunk, ChunkKind, ChunkReader, HEADER_LEN, Header, MAGIC, Mode, VERSION,
    read_header,
};
pub use decode::{Cut, DecodeOptions, Decoded, decode, decode_prefix};
pub use decode_stream::PrefixDecoder;
pub use encode::{
    DEFAULT_PRECISION, EncodeOptions, EncodeReport, Encoded, LevelReport, Placement, encode,
};
pub use error::{Error, Result};
pub use level_surface::LevelSurface;
pub use octree::{Frame, Sidedness};
pub use ordering::HLevel;
pub use orientation::orient;
pub use stats::{
    LevelStats, ProgressiveLevel, StreamStats, non_manifold_triangles, progressive_levels,
    stream_stats,
};
pub use thinning::ThinningOptions;
pub use triangulate::{
    TriangulateOptions, Triangulation, TriangulationStats, triangulate, triangulate_owned,
    triangulate_traced,
};

/// The pipeline's stages, for the bench crate's profiling drivers and the
/// range coder's benchmark only (feature `internals`): no stability
/// promise, not part of the contract above.
#[cfg(feature = "internals")]
#[doc(hidden)]
#[allow(missing_docs)]
pub mod internals {
    pub use crate::coding::bit_coder::BitCoder;
    pub use crate::coding::range_coder::{EntropyReader, EntropyWriter, PRECISION, model};
    pub use crate::octree::{BuildOptions, FACES, Label, Octree, morton, unmorton};
    pub use crate::thinning::thin;
}
