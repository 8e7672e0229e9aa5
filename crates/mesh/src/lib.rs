//! # lodkit-mesh
//!
//! The layer every lodkit capability stands on: the geometry types
//! ([`TriMesh`], [`PointCloud`], [`RangeImage`]), their file formats
//! ([`io`]), the topology helpers the simplifier, the marching cube octree
//! and the particle coder all need ([`topology`]), synthetic test shapes
//! ([`shapes`]) and Metro-style surface distances ([`metrics`]).

/// The 48 symmetries of the cube acting on its corners, shared by the
/// marching-cubes and particle triangulation tables.
pub mod cube_symmetry;
pub mod error;
pub mod info;
pub mod io;
pub mod mesh;
pub mod metrics;
pub mod normals;
pub mod shapes;
pub mod topology;
pub mod weld;

pub use error::{Error, ParseError, Result};
pub use glam;
pub use mesh::{Aabb, Model, PointCloud, Pose, RangeImage, TriMesh};
