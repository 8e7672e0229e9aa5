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
//! The pipeline reads top to bottom in the file names:
//! [`octree`] → [`thinning`] → [`ordering`] → [`attributes`] →
//! [`hierarchical_coding`] (levels) and [`precision_coding`] (precision
//! layers) over [`encode_baseline`] or [`encode_entropy`] → [`container`];
//! and back: [`decode`](mod@decode) → [`triangulate`](mod@triangulate)
//! (with [`triangulation_table`], then [`orientation`]) → [`stats`].
//!
//! ## What to expect (release build, shared 2-core machine)
//!
//! | input | R | particles | baseline structure bits/particle (paper: 5.1) | entropy structure | all bits/particle at N = 12, entropy |
//! |---|---|---|---|---|---|
//! | Stanford bunny (35,947 vertices) | 7 | 33,712 | 4.72 | 2.08 | 8.68 |
//! | Armadillo (CGAL 26k) | 7 | 23,353 | 4.82 | 2.42 | 9.78 |
//! | Stanford bunny, dense, R = N = 10 | 10 | 2,118,241 | 4.78 | 1.49 | 1.49 |
//!
//! The entropy mode's vertices sit on their samples' plane at their
//! leaf's middle column ([`encode::Placement`]), so the precision layers
//! code little more than the coordinate across the surface. Triangles ≈
//! 2.0–2.1 × particles per level; decode + triangulate of the finest level
//! (criterion, 2-core machine at load < 1, `cargo bench -p lodkit-bench
//! --bench pop`) 15–18 M triangles/s in the baseline mode and 8.6–9.6 M in
//! the entropy mode, whose decoder makes about 12 binary decisions per
//! particle at R = 8 (per stage: `cargo run --release -p lodkit-particles
//! --example pop_profile -- icosphere6:8:12`; decoding alone: `cargo run
//! --release -p lodkit-particles --example pop_decode_time`);
//! `lodkit pop stats FILE` prints the paper's Table 1 for any stream.
//!
//! ```no_run
//! use lodkit_particles::{encode, EncodeOptions, decode, DecodeOptions, triangulate, TriangulateOptions};
//! let bunny = lodkit_mesh::io::load(std::path::Path::new("bunny.ply")).unwrap();
//! let pop = encode(&bunny, &EncodeOptions::DEFAULT).unwrap();
//! let dec = decode(&pop.bytes, &DecodeOptions::default()).unwrap();
//! let level = dec.surface(6).unwrap();
//! let mesh = triangulate(&level, &TriangulateOptions::DEFAULT).mesh;
//! ```
// Octree code walks parallel per-node arrays (cells, labels, particles)
// by index; iterator chains over three of them read worse.
#![allow(clippy::needless_range_loop)]

pub mod attributes;
pub mod coding;
pub mod container;
pub mod decode;
pub mod encode;
pub mod error;
pub mod octree;
pub mod ordering;
pub mod orientation;
pub mod stats;
pub mod thinning;
pub mod triangulate;
pub mod triangulation_table;

pub use container::Mode;
pub use decode::{DecodeOptions, Decoded, LevelSurface, decode};
pub use encode::{EncodeOptions, EncodeReport, Encoded, LevelReport, Placement, encode};
pub use error::{Error, Result};
pub use octree::Sidedness;
pub use stats::{
    LevelStats, ProgressiveLevel, StreamStats, non_manifold_flags, non_manifold_triangles,
    progressive_levels, stream_stats,
};
pub use thinning::ThinningOptions;
pub use triangulate::{TriangulateOptions, Triangulation, TriangulationStats, triangulate};
