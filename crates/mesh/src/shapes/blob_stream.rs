//! The [`blob`](super::blob) surface written straight to a binary PLY
//! file, never held in memory: test inputs for the out-of-core simplifier
//! (a billion triangles is 19 GB of PLY, more than memory).
//!
//! Same cube-sphere and noise as [`blob`](super::blob) (the same points,
//! up to vertex order), numbered without a weld: the integer lattice
//! points on the surface of the cube `[0, n]³` are ordered layer by layer
//! along z (the full bottom square, the rings of `4n` points of the
//! middle layers, the full top square), so a point's index is a closed
//! form of its coordinates and shared cube edges get one index.

use std::io::Write;
use std::path::Path;

use glam::Vec3;

use super::blob::fbm;
use crate::error::{Error, Result};

/// What [`write_blob_ply`] wrote.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlobCounts {
    /// Vertices (6 n² + 2).
    pub vertices: u64,
    /// Triangles (12 n²).
    pub triangles: u64,
}

/// The grid resolution for about `triangles` triangles (as `blob`).
fn resolution(triangles: u64) -> u32 {
    ((triangles as f64 / 12.0).sqrt().round() as u32).max(1)
}

/// The vertex and triangle counts [`write_blob_ply`] gives for `triangles`.
pub fn blob_counts(triangles: u64) -> BlobCounts {
    let n = resolution(triangles) as u64;
    BlobCounts {
        vertices: 6 * n * n + 2,
        triangles: 12 * n * n,
    }
}

/// The index of surface lattice point `(a, b, c)` of the cube `[0, n]³`.
fn index(n: u32, a: u32, b: u32, c: u32) -> u32 {
    let full = (n + 1) * (n + 1);
    if c == 0 {
        return a * (n + 1) + b;
    }
    if c == n {
        return full + (n - 1) * 4 * n + a * (n + 1) + b;
    }
    let ring = if b == 0 && a < n {
        a
    } else if a == n && b < n {
        n + b
    } else if b == n && a > 0 {
        2 * n + (n - a)
    } else {
        3 * n + (n - b)
    };
    full + (c - 1) * 4 * n + ring
}

/// The blob position of lattice point `(a, b, c)`.
fn position(n: u32, a: u32, b: u32, c: u32, seed: u32) -> Vec3 {
    let coord = |k: u32| -1.0 + 2.0 * k as f32 / n as f32;
    let p = Vec3::new(coord(a), coord(b), coord(c)).normalize();
    p * (1.0 + 0.3 * fbm(p * 1.7, seed))
}

/// Writes a blob of about `triangles` triangles (12 n², n the rounded
/// `sqrt(triangles / 12)`, at least 12; at most 2^32 − 2 vertices) and
/// noise `seed` to `path` as binary little-endian PLY, atomically (a temp
/// file renamed into place; removed on error and on Ctrl-C). Output:
/// closed genus-0 manifold, outward CCW faces, deterministic bytes.
/// Errors: I/O, or a size past 32-bit indices. Memory: one write buffer;
/// time and bytes linear in the triangles (13 B per face, 12 per vertex).
pub fn write_blob_ply(path: &Path, triangles: u64, seed: u32) -> Result<BlobCounts> {
    let counts = blob_counts(triangles);
    if counts.vertices >= u32::MAX as u64 - 1 {
        return Err(Error::Invalid(format!(
            "a {triangles}-triangle blob has more vertices than 32-bit indices address"
        )));
    }
    let n = resolution(triangles);
    crate::io::write_atomic_with(path, |w| write_body(w, n, seed, counts))?;
    Ok(counts)
}

fn write_body(w: &mut dyn Write, n: u32, seed: u32, c: BlobCounts) -> std::io::Result<()> {
    let mut w = std::io::BufWriter::with_capacity(1 << 20, w);
    write!(
        w,
        "ply\nformat binary_little_endian 1.0\ncomment lodkit blob, seed {seed}\nelement vertex {}\nproperty float x\nproperty float y\nproperty float z\nelement face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        c.vertices, c.triangles
    )?;
    let put = |w: &mut std::io::BufWriter<_>, a, b, cc| -> std::io::Result<()> {
        let p = position(n, a, b, cc, seed);
        for k in p.to_array() {
            w.write_all(&k.to_le_bytes())?;
        }
        Ok(())
    };
    // Vertices in index order (see `index`).
    for cz in 0..=n {
        if cz == 0 || cz == n {
            for a in 0..=n {
                for b in 0..=n {
                    put(&mut w, a, b, cz)?;
                }
            }
        } else {
            for a in 0..n {
                put(&mut w, a, 0, cz)?;
            }
            for b in 0..n {
                put(&mut w, n, b, cz)?;
            }
            for a in (1..=n).rev() {
                put(&mut w, a, n, cz)?;
            }
            for b in (1..=n).rev() {
                put(&mut w, 0, b, cz)?;
            }
        }
    }
    // Faces: each cube face a grid of quads; (b − a) × (c − a) points
    // along +axis, so the −side's triangles are reversed to face out.
    for axis in 0..3 {
        for side in [0u32, n] {
            let at = |i: u32, j: u32| {
                let mut p = [0u32; 3];
                p[axis] = side;
                p[(axis + 1) % 3] = i;
                p[(axis + 2) % 3] = j;
                index(n, p[0], p[1], p[2])
            };
            for i in 0..n {
                for j in 0..n {
                    let (a, b, cc, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                    for t in [[a, b, cc], [a, cc, d]] {
                        let t = if side == 0 { [t[0], t[2], t[1]] } else { t };
                        w.write_all(&[3u8])?;
                        for v in t {
                            w.write_all(&v.to_le_bytes())?;
                        }
                    }
                }
            }
        }
    }
    w.flush()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streamed_blob_is_a_closed_manifold_with_the_stated_counts() {
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("b.ply");
        let c = write_blob_ply(&p, 3000, 1).unwrap();
        let m = crate::io::load_mesh(&p).unwrap();
        assert_eq!(m.positions.len() as u64, c.vertices);
        assert_eq!(m.faces.len() as u64, c.triangles);
        let s = crate::topology::topology_stats(&m);
        assert_eq!(s.boundary_edges, 0);
        assert_eq!(s.non_manifold_edges, 0);
        // Euler characteristic 2: genus 0.
        assert_eq!(
            m.positions.len() as i64 - s.edges as i64 + m.faces.len() as i64,
            2
        );
        // Outward: positive signed volume.
        let vol: f32 = m
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|i| m.positions[i as usize]);
                a.dot(b.cross(c))
            })
            .sum();
        assert!(vol > 0.0);
        // Deterministic bytes.
        let q = dir.path().join("c.ply");
        write_blob_ply(&q, 3000, 1).unwrap();
        assert_eq!(std::fs::read(&p).unwrap(), std::fs::read(&q).unwrap());
    }
}
