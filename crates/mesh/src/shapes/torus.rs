//! Torus (genus 1) around the Y axis.

use glam::{Vec2, Vec3};

use crate::mesh::TriMesh;

/// Torus with major radius `major` (centre to tube centre), tube radius
/// `minor`, `seg_major × seg_minor` vertices and twice as many triangles.
/// Carries normals and UVs (which wrap at both seams).
pub fn torus(major: f32, minor: f32, seg_major: u32, seg_minor: u32) -> TriMesh {
    let (nu, nv) = (seg_major.max(3), seg_minor.max(3));
    let mut positions = Vec::with_capacity((nu * nv) as usize);
    let mut normals = Vec::with_capacity(positions.capacity());
    let mut uvs = Vec::with_capacity(positions.capacity());
    for i in 0..nu {
        let u = std::f32::consts::TAU * i as f32 / nu as f32;
        let dir = Vec3::new(u.cos(), 0.0, -u.sin());
        for j in 0..nv {
            let v = std::f32::consts::TAU * j as f32 / nv as f32;
            let n = dir * v.cos() + Vec3::Y * v.sin();
            positions.push(dir * major + n * minor);
            normals.push(n);
            uvs.push(Vec2::new(i as f32 / nu as f32, j as f32 / nv as f32));
        }
    }
    let at = |i: u32, j: u32| (i % nu) * nv + j % nv;
    let mut faces = Vec::with_capacity((2 * nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
            for f in [[a, b, c], [a, c, d]] {
                // Outward = along the tube normal at the face's first corner.
                let [p, q, r] = f.map(|k| positions[k as usize]);
                let nrm = normals[f[0] as usize];
                faces.push(if (q - p).cross(r - p).dot(nrm) >= 0.0 {
                    f
                } else {
                    [f[0], f[2], f[1]]
                });
            }
        }
    }
    TriMesh {
        positions,
        normals: Some(normals),
        colors: None,
        uvs: Some(uvs),
        faces,
    }
}
