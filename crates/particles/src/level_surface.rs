//! One decoded octree level's particles, the surface `S^r` that
//! triangulation and display read: below both the decoder that makes it
//! and the triangulation that meshes it.

use glam::Vec3;
use lodkit_mesh::{PointCloud, TriMesh};

use crate::octree::Frame;

/// One decoded octree surface `S^r` ready for triangulation or display.
#[derive(Debug, Clone)]
pub struct LevelSurface {
    /// Octree level `r` (cubes of side `frame.size / 2^r`).
    pub level: u8,
    /// The octree cube, as in the header.
    pub frame: Frame,
    /// Kept cells, sorted Morton codes.
    pub cells: Vec<u64>,
    /// One vertex per cell (its particle), in model units.
    pub positions: Vec<Vec3>,
    /// RGBA8 colours per vertex, when the stream has them.
    pub colours: Option<Vec<[u8; 4]>>,
    /// Unit normals per vertex, when the stream has them.
    pub normals: Option<Vec<Vec3>>,
}

impl LevelSurface {
    /// The particles as a point cloud.
    pub fn to_point_cloud(&self) -> PointCloud {
        PointCloud {
            positions: self.positions.clone(),
            normals: self.normals.clone(),
            colors: self.colours.clone(),
        }
    }

    /// Empty mesh carrying the particles as vertices (faces added by
    /// triangulation).
    pub fn vertices_only(&self) -> TriMesh {
        TriMesh {
            positions: self.positions.clone(),
            normals: self.normals.clone(),
            colors: self.colours.clone(),
            uvs: None,
            faces: Vec::new(),
        }
    }

    /// [`vertices_only`](Self::vertices_only), moving the particles.
    pub fn into_vertices(self) -> TriMesh {
        TriMesh {
            positions: self.positions,
            normals: self.normals,
            colors: self.colours,
            uvs: None,
            faces: Vec::new(),
        }
    }
}
