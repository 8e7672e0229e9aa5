//! Unit spheres: latitude/longitude ([`uv_sphere`]) and subdivided
//! icosahedron ([`icosphere`]).

use rustc_hash::FxHashMap;

use glam::{Vec2, Vec3};

use crate::mesh::TriMesh;

/// Unit UV-sphere with `segments ≥ 3` around and `rings ≥ 2` from pole to
/// pole: `segments × (rings − 1) + 2` vertices, `2 × segments × (rings − 1)`
/// triangles. Carries normals and UVs (u around, v from south to north;
/// the seam column is not duplicated, so UVs wrap there).
pub fn uv_sphere(segments: u32, rings: u32) -> TriMesh {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut positions = vec![Vec3::new(0.0, -1.0, 0.0)];
    let mut uvs = vec![Vec2::new(0.5, 0.0)];
    for r in 1..rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push(Vec3::new(
                theta.sin() * phi.cos(),
                -theta.cos(),
                -theta.sin() * phi.sin(),
            ));
            uvs.push(Vec2::new(
                s as f32 / segments as f32,
                r as f32 / rings as f32,
            ));
        }
    }
    positions.push(Vec3::Y);
    uvs.push(Vec2::new(0.5, 1.0));
    let north = positions.len() as u32 - 1;
    let at = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let mut faces = Vec::new();
    for s in 0..segments {
        faces.push([0, at(1, s), at(1, s + 1)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s + 1), at(r + 1, s));
            faces.push([a, d, c]);
            faces.push([a, c, b]);
        }
    }
    for s in 0..segments {
        faces.push([north, at(rings - 1, s + 1), at(rings - 1, s)]);
    }
    fix_winding_outward(&positions, &mut faces);
    let normals = positions.clone();
    TriMesh {
        positions,
        normals: Some(normals),
        colors: None,
        uvs: Some(uvs),
        faces,
    }
}

/// Unit icosphere: the icosahedron subdivided `level` times (each triangle
/// into four), vertices projected onto the sphere: `20 × 4^level` triangles.
pub fn icosphere(level: u32) -> TriMesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|p| Vec3::from_array(*p).normalize())
    .collect();
    let mut faces: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level.min(10) {
        let mut mid: FxHashMap<(u32, u32), u32> = FxHashMap::default();
        let mut next = Vec::with_capacity(faces.len() * 4);
        for f in &faces {
            let mut m = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                let key = (a.min(b), a.max(b));
                m[k] = *mid.entry(key).or_insert_with(|| {
                    positions
                        .push(((positions[a as usize] + positions[b as usize]) * 0.5).normalize());
                    positions.len() as u32 - 1
                });
            }
            next.extend([
                [f[0], m[0], m[2]],
                [f[1], m[1], m[0]],
                [f[2], m[2], m[1]],
                m,
            ]);
        }
        faces = next;
    }
    fix_winding_outward(&positions, &mut faces);
    let normals = positions.clone();
    TriMesh {
        positions,
        normals: Some(normals),
        colors: None,
        uvs: None,
        faces,
    }
}

/// Orients every face of a star-shaped (about the origin) closed surface
/// outward; the tables above are then correct whatever their listed order.
pub(crate) fn fix_winding_outward(positions: &[Vec3], faces: &mut [[u32; 3]]) {
    for f in faces.iter_mut() {
        let [a, b, c] = f.map(|i| positions[i as usize]);
        if (b - a).cross(c - a).dot(a + b + c) < 0.0 {
            f.swap(1, 2);
        }
    }
}
