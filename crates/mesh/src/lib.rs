//! # lodkit-mesh
//!
//! The layer every lodkit capability stands on: the geometry types
//! ([`TriMesh`], [`PointCloud`], [`RangeImage`], one [`Model`] for any of
//! them), their file formats ([`io`]), the topology helpers the
//! simplifier, the marching cube octree and the particle coder share
//! ([`topology`]), welding ([`weld`]), normals ([`normals`]), synthetic test
//! shapes ([`shapes`]), Metro-style surface distances ([`metrics`], after
//! Cignoni, Rocchini and Scopigno, *Metro: measuring error on simplified
//! surfaces*, Computer Graphics Forum 17(2), 1998) and the `lodkit info`
//! report ([`info`]).
//!
//! ## Entry points
//!
//! | item | contract |
//! |---|---|
//! | [`io::load`], [`io::load_mesh`], [`io::decode`] | file or bytes → model; one-line errors naming the file, never a panic |
//! | [`io::save`], [`io::save_mesh`], [`io::encode`], [`io::write_atomic`] | model → bytes → file, atomic and deterministic |
//! | [`TriMesh`], [`PointCloud`], [`RangeImage`], [`Model`], [`Aabb`], [`Pose`] | the types and their invariants (`validate`) |
//! | [`Scene`], [`io::load_scene`], [`io::save_scene`] | meshes with per-face materials, nodes, textures and images (kept as bytes) beside `TriMesh` ([`scene`]) |
//! | [`metrics::compare`], [`metrics::one_sided`] | symmetric / one-sided Metro distance, deterministic for a seed |
//! | [`info::model_info`] | counts, topology defects, genus |
//! | [`topology::UnionFind`], [`topology::edge_multiplicities`], [`topology::non_manifold_faces`], [`topology::topology_stats`] | shared connectivity primitives |
//! | [`weld::weld`], [`normals::vertex_normals`], [`shapes`] | welding, normals, test shapes |
//! | [`Intrinsics`] | pinhole intrinsics (COLMAP's convention), shared by the renderer's cameras and the silhouette calibration's lens |
//! | `image::decode_rgba`, `image::image_size` (feature `images`) | the one PNG/JPEG decoder, for photographs and textures; sizes bounded from the header before any pixel is allocated |
//!
//! Conventions for every crate (see [`TriMesh`]): positions are `f32`
//! object units, never rescaled; faces are CCW seen from outside; colours
//! are straight sRGB RGBA8; UVs have a bottom-left origin. Errors:
//! [`ParseError`] (what is wrong) inside decoders, [`Error`] (which file)
//! at the `io` boundary.
//!
//! ```
//! use lodkit_mesh::metrics::{compare, CompareOptions};
//! let fine = lodkit_mesh::shapes::icosphere(4);
//! let coarse = lodkit_mesh::shapes::icosphere(2);
//! let opts = CompareOptions { samples: Some(10_000), ..Default::default() };
//! let r = compare(&fine, &coarse, &opts).unwrap();
//! assert!(r.symmetric.max > 0.0 && r.symmetric.max < 0.05);
//! ```

#![deny(missing_docs)]
#![forbid(unsafe_code)]

/// The 48 symmetries of the cube acting on its corners, shared by the
/// marching-cubes and particle triangulation tables.
pub mod cube_symmetry;
mod error;
#[cfg(feature = "images")]
pub mod image;
pub mod info;
mod intrinsics;
pub mod io;
mod mesh;
pub mod metrics;
pub mod normals;
pub mod scene;
pub mod shapes;
pub mod topology;
pub mod weld;

pub use error::{Error, ParseError, Result, escape};
pub use glam;
pub use intrinsics::Intrinsics;
pub use mesh::{Aabb, Model, PointCloud, Pose, RangeImage, TriMesh};
pub use scene::{Scene, SceneMesh};
