//! Shared checks for the integration tests.
#![allow(dead_code)]

use std::collections::HashMap;

use lodkit_mesh::TriMesh;
use lodkit_mesh::glam::{DVec3, Vec3};

/// Closest point on triangle `abc` to `p` (Ericson, Real-Time Collision
/// Detection §5.1.5, written from the region description). Computed in
/// f64: the region tests subtract products, and in f32 a sliver triangle
/// (crack patching makes some) sent points lying on its edge to a wrong
/// region, reporting gaps of 6e-2 where the true distance was 4e-7.
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    closest_on_triangle_f64(p.as_dvec3(), a.as_dvec3(), b.as_dvec3(), c.as_dvec3()).as_vec3()
}

fn closest_on_triangle_f64(p: DVec3, a: DVec3, b: DVec3, c: DVec3) -> DVec3 {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(ap);
    let d2 = ac.dot(ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return a;
    }
    let bp = p - b;
    let d3 = ab.dot(bp);
    let d4 = ac.dot(bp);
    if d3 >= 0.0 && d4 <= d3 {
        return b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return a + ab * (d1 / (d1 - d3));
    }
    let cp = p - c;
    let d5 = ab.dot(cp);
    let d6 = ac.dot(cp);
    if d6 >= 0.0 && d5 <= d6 {
        return c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return a + ac * (d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    let denom = 1.0 / (va + vb + vc);
    let v = vb * denom;
    let w = vc * denom;
    a + ab * v + ac * w
}

/// Boundary edges (used by one face) that do not lie on another face within
/// `tol`: sampled at 5 points each. Returns (boundary edges, gap edges).
pub fn gap_edges(m: &TriMesh, tol: f32) -> (usize, usize) {
    let mut count: HashMap<(u32, u32), (u32, usize)> = HashMap::new();
    for (fi, f) in m.faces.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let key = (a.min(b), a.max(b));
            let e = count.entry(key).or_insert((0, fi));
            e.0 += 1;
        }
    }
    let boundary: Vec<((u32, u32), usize)> = count
        .iter()
        .filter(|(_, v)| v.0 == 1)
        .map(|(k, v)| (*k, v.1))
        .collect();
    if boundary.is_empty() {
        return (0, 0);
    }
    // Spatial hash of faces by their bbox cells.
    let bb = m.bbox();
    let cell = (bb.diagonal() / 64.0).max(1e-9);
    let key = |p: Vec3| {
        let q = ((p - bb.min) / cell).floor();
        (q.x as i32, q.y as i32, q.z as i32)
    };
    let mut grid: HashMap<(i32, i32, i32), Vec<usize>> = HashMap::new();
    for (fi, f) in m.faces.iter().enumerate() {
        let ps = f.map(|i| m.positions[i as usize]);
        let lo = key(ps[0].min(ps[1]).min(ps[2]) - Vec3::splat(tol));
        let hi = key(ps[0].max(ps[1]).max(ps[2]) + Vec3::splat(tol));
        for x in lo.0..=hi.0 {
            for y in lo.1..=hi.1 {
                for z in lo.2..=hi.2 {
                    grid.entry((x, y, z)).or_default().push(fi);
                }
            }
        }
    }
    let mut gaps = 0;
    for ((a, b), owner) in &boundary {
        let (pa, pb) = (m.positions[*a as usize], m.positions[*b as usize]);
        let ok = [0.0f32, 0.25, 0.5, 0.75, 1.0].iter().all(|&t| {
            let p = pa.lerp(pb, t);
            grid.get(&key(p)).is_some_and(|faces| {
                faces.iter().any(|&fi| {
                    if fi == *owner {
                        return false;
                    }
                    let [x, y, z] = m.faces[fi].map(|i| m.positions[i as usize]);
                    closest_on_triangle(p, x, y, z).distance(p) <= tol
                })
            })
        });
        if !ok {
            gaps += 1;
        }
    }
    (boundary.len(), gaps)
}
