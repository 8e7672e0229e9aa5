//! Shapes with the defects real scans have: an open rim, small holes,
//! non-manifold edges and vertices.

use glam::{Vec2, Vec3};

use crate::mesh::TriMesh;

/// An open height field over `[0, 1]²` with `nx × ny` quads (`2 nx ny`
/// triangles), one boundary loop, gentle hills, UVs = grid coordinates.
pub fn terrain(nx: u32, ny: u32) -> TriMesh {
    let (nx, ny) = (nx.max(1), ny.max(1));
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=ny {
        for i in 0..=nx {
            let (u, v) = (i as f32 / nx as f32, j as f32 / ny as f32);
            let h = 0.1 * (u * 7.0).sin() * (v * 5.0).cos() + 0.05 * (u * 13.0 + v * 11.0).sin();
            positions.push(Vec3::new(u, v, h));
            uvs.push(Vec2::new(u, v));
        }
    }
    let at = |i: u32, j: u32| j * (nx + 1) + i;
    let mut faces = Vec::new();
    for j in 0..ny {
        for i in 0..nx {
            faces.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            faces.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
        }
    }
    TriMesh {
        positions,
        normals: None,
        colors: None,
        uvs: Some(uvs),
        faces,
    }
}

/// An [`icosphere`](super::icosphere) of the given level with `holes` small
/// holes, each made by removing the fan of faces around one vertex (vertices
/// spread over the sphere, far enough apart that holes never merge).
pub fn holey_sphere(level: u32, holes: usize) -> TriMesh {
    let mut m = super::icosphere(level.max(2));
    // The 12 original icosahedron vertices are indices 0..12 and never adjacent after subdivision.
    let centres: Vec<u32> = (0..holes.min(12) as u32).collect();
    m.faces.retain(|f| !f.iter().any(|v| centres.contains(v)));
    m.normals = None;
    m
}

/// A small mesh with both kinds of non-manifold elements: a "fin" (three
/// triangles on one edge) and two fans meeting at a single "bow-tie" vertex.
pub fn non_manifold() -> TriMesh {
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(0.5, 1.0, 0.0),
        Vec3::new(0.5, -1.0, 0.0),
        Vec3::new(0.5, 0.0, 1.0),
        // Bow-tie centred at vertex 5.
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::new(4.0, 1.0, 0.0),
        Vec3::new(4.0, -1.0, 0.0),
        Vec3::new(2.0, 1.0, 0.0),
        Vec3::new(2.0, -1.0, 0.0),
    ];
    let faces = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [5, 7, 6], [5, 8, 9]];
    TriMesh::new(positions, faces)
}
