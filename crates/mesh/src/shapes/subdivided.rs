//! A real scan subdivided to any size and streamed to binary PLY, never
//! held in memory: test inputs for the out-of-core simplifier with a
//! scan's shape and features, where the [blob](super::write_blob_ply)
//! only has noise.
//!
//! Each triangle is split into an `m × m` grid of `m²` triangles (`m` the
//! smallest whole number giving at least the asked count); the new points
//! are displaced along the interpolated vertex normal by fractal noise a
//! fraction of a sub-edge high, so the added detail is surface, not flat
//! facets a simplifier removes for free. Points are numbered in closed
//! form — the input's vertices, then `m − 1` per edge, then the interior
//! points of each face — so points on a shared edge are one vertex in
//! both faces and a closed input stays closed; each position depends on
//! its point alone, so the file is the same on every run.

use std::io::Write;
use std::path::Path;

use glam::Vec3;

use super::blob::fbm;
use super::blob_stream::BlobCounts;
use crate::TriMesh;
use crate::error::{Error, Result};
use crate::topology::edge_multiplicities;

/// The grid size per input triangle for about `triangles` output
/// triangles from `faces` input ones (at least 1).
fn grid(faces: u64, triangles: u64) -> u64 {
    let f = faces.max(1);
    let mut m = ((triangles as f64 / f as f64).sqrt().ceil() as u64).max(1);
    while m > 1 && f * (m - 1) * (m - 1) >= triangles {
        m -= 1;
    }
    m
}

/// Writes `mesh` subdivided to at least `triangles` triangles (`F m²`)
/// with noise `seed` to `path` as binary little-endian PLY, atomically.
/// Errors: a mesh without faces, a size past 32-bit indices, I/O.
/// Memory: the input and its edge list; time and bytes linear in the
/// output (13 B per face, 12 per vertex).
pub fn write_subdivided_ply(
    mesh: &TriMesh,
    triangles: u64,
    seed: u32,
    path: &Path,
) -> Result<BlobCounts> {
    if mesh.faces.is_empty() {
        return Err(Error::Invalid("the mesh to subdivide has no faces".into()));
    }
    let (v, f) = (mesh.positions.len() as u64, mesh.faces.len() as u64);
    let m = grid(f, triangles);
    let edges = edge_multiplicities(mesh);
    let e = edges.len() as u64;
    let per_face = (m - 1) * m.saturating_sub(2) / 2;
    let counts = BlobCounts {
        vertices: v + e * (m - 1) + f * per_face,
        triangles: f * m * m,
    };
    if counts.vertices >= u32::MAX as u64 {
        return Err(Error::Invalid(format!(
            "{} triangles subdivided to {} have more vertices than 32-bit indices address",
            f, counts.triangles
        )));
    }
    let normals = crate::normals::vertex_normals(mesh);
    let mean_edge = {
        let s: f64 = edges
            .iter()
            .map(|x| (mesh.positions[x.a as usize] - mesh.positions[x.b as usize]).length() as f64)
            .sum();
        (s / e.max(1) as f64) as f32
    };
    // Noise about one sub-edge wide and a fifth of it high.
    let sub = (mean_edge / m as f32).max(f32::MIN_POSITIVE);
    let displaced = |p: Vec3, n: Vec3| -> Vec3 {
        let n = n.normalize_or_zero();
        p + n * (0.2 * sub * fbm(p / sub, seed))
    };
    let edge_index = |a: u32, b: u32| -> u64 {
        let key = (a.min(b), a.max(b));
        edges
            .binary_search_by(|x| (x.a, x.b).cmp(&key))
            .unwrap_or(0) as u64
    };
    let m32 = m as u32;
    let interior_base = v + e * (m - 1);
    // The vertex of grid point (i, j) of face `fi` (corners c).
    let index = |fi: u64, c: [u32; 3], i: u32, j: u32| -> u32 {
        let on_edge = |p: u32, q: u32, t: u32| -> u32 {
            let base = v + edge_index(p, q) * (m - 1);
            let t = if p < q { t } else { m32 - t };
            (base + t as u64 - 1) as u32
        };
        match (i, j) {
            (0, 0) => c[0],
            (i, 0) if i == m32 => c[1],
            (0, j) if j == m32 => c[2],
            (i, 0) => on_edge(c[0], c[1], i),
            (0, j) => on_edge(c[0], c[2], j),
            (i, j) if i + j == m32 => on_edge(c[1], c[2], j),
            (i, j) => {
                // Rows i = 1..m−2, each with j = 1..m−1−i.
                let (i, j) = (i as u64, j as u64);
                let before = (i - 1) * (m - 1) - (i - 1) * i / 2;
                (interior_base + fi * per_face + before + j - 1) as u32
            }
        }
    };
    crate::io::write_atomic_with(path, |file| {
        let mut w = std::io::BufWriter::with_capacity(1 << 20, file);
        write!(
            w,
            "ply\nformat binary_little_endian 1.0\ncomment lodkit: a scan subdivided {m}x{m} per triangle, noise seed {seed}\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
            counts.vertices, counts.triangles
        )?;
        let mut put = |p: Vec3| -> std::io::Result<()> {
            for k in p.to_array() {
                w.write_all(&k.to_le_bytes())?;
            }
            Ok(())
        };
        for (p, n) in mesh.positions.iter().zip(&normals) {
            put(displaced(*p, *n))?;
        }
        for x in &edges {
            let (a, b) = (x.a as usize, x.b as usize);
            for t in 1..m {
                let s = t as f32 / m as f32;
                let p = mesh.positions[a].lerp(mesh.positions[b], s);
                put(displaced(p, normals[a].lerp(normals[b], s)))?;
            }
        }
        for face in &mesh.faces {
            let [p0, p1, p2] = face.map(|k| mesh.positions[k as usize]);
            let [n0, n1, n2] = face.map(|k| normals[k as usize]);
            for i in 1..m.saturating_sub(1) {
                for j in 1..m - i {
                    let (a, b) = (i as f32 / m as f32, j as f32 / m as f32);
                    let p = p0 + (p1 - p0) * a + (p2 - p0) * b;
                    let n = n0 * (1.0 - a - b) + n1 * a + n2 * b;
                    put(displaced(p, n))?;
                }
            }
        }
        for (fi, face) in mesh.faces.iter().enumerate() {
            let fi = fi as u64;
            let mut tri = |t: [u32; 3]| -> std::io::Result<()> {
                let mut rec = [3u8; 13];
                for (k, x) in t.iter().enumerate() {
                    rec[1 + 4 * k..5 + 4 * k].copy_from_slice(&x.to_le_bytes());
                }
                w.write_all(&rec)
            };
            for i in 0..m32 {
                for j in 0..m32 - i {
                    let at = |i, j| index(fi, *face, i, j);
                    tri([at(i, j), at(i + 1, j), at(i, j + 1)])?;
                    if i + j + 1 < m32 {
                        tri([at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)])?;
                    }
                }
            }
        }
        w.flush()
    })?;
    Ok(counts)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_closed_mesh_stays_closed_with_the_stated_counts() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.ply");
        let ico = crate::shapes::icosphere(1); // 80 triangles
        for (asked, m) in [(80u64, 1u64), (700, 3), (5_000, 8)] {
            let c = write_subdivided_ply(&ico, asked, 5, &path).unwrap();
            assert_eq!(c.triangles, 80 * m * m, "{asked}");
            let out = crate::io::load_mesh(&path).unwrap();
            assert_eq!(out.positions.len() as u64, c.vertices);
            assert_eq!(out.faces.len() as u64, c.triangles);
            let s = crate::topology::topology_stats(&out);
            assert_eq!((s.boundary_edges, s.non_manifold_edges), (0, 0), "{asked}");
            assert_eq!(
                out.positions.len() as i64 - s.edges as i64 + out.faces.len() as i64,
                2
            );
            // Near the sphere, outward (positive volume), deterministic.
            assert!(out.positions.iter().all(|p| (p.length() - 1.0).abs() < 0.2));
            let volume: f32 = out
                .faces
                .iter()
                .map(|f| {
                    let [a, b, c] = f.map(|i| out.positions[i as usize]);
                    a.dot(b.cross(c)) / 6.0
                })
                .sum();
            assert!(volume > 3.0, "{volume}");
            let again = dir.path().join("t.ply");
            write_subdivided_ply(&ico, asked, 5, &again).unwrap();
            assert_eq!(
                std::fs::read(&path).unwrap(),
                std::fs::read(&again).unwrap()
            );
        }
    }
}
