//! A noise-displaced sphere of any size: the stand-in for a dense scan in
//! benchmarks (1M+ triangles) and tests.
//!
//! Built as a cube-sphere (each cube face an `n × n` grid of quads, 12 n²
//! triangles) so triangles are near-uniform, then displaced radially by a
//! few octaves of value noise; radial displacement keeps the surface
//! star-shaped, so it stays a closed genus-0 manifold whatever the noise.

use glam::{IVec3, Vec3};

use crate::mesh::TriMesh;
use crate::weld::weld;

/// The default blob: seed 1, about `target_triangles` triangles (within a
/// few percent; never fewer than 12).
pub fn blob(target_triangles: usize) -> TriMesh {
    blob_with_seed(target_triangles, DEFAULT_NOISE_SEED)
}

/// The default noise seed of generated meshes (the blob, a subdivided
/// scan's displacement: `lodkit generate`, `pylodkit.blob`, the
/// benchmarks): 1.
pub const DEFAULT_NOISE_SEED: u32 = 1;

/// [`blob`] with a chosen noise seed.
pub fn blob_with_seed(target_triangles: usize, seed: u32) -> TriMesh {
    let n = ((target_triangles as f64 / 12.0).sqrt().round() as u32).max(1);
    let mut positions = Vec::with_capacity(6 * ((n + 1) * (n + 1)) as usize);
    let mut faces = Vec::with_capacity(12 * (n * n) as usize);
    // Grid coordinates come from the same integer expression on every cube
    // face, so shared cube edges produce bit-identical points that the exact
    // weld below merges.
    let coord = |k: u32| -1.0 + 2.0 * k as f32 / n as f32;
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let base = positions.len() as u32;
            for i in 0..=n {
                for j in 0..=n {
                    let mut p = [0.0f32; 3];
                    p[axis] = sign;
                    p[(axis + 1) % 3] = coord(i);
                    p[(axis + 2) % 3] = coord(j);
                    positions.push(Vec3::from_array(p));
                }
            }
            let at = |i: u32, j: u32| base + i * (n + 1) + j;
            for i in 0..n {
                for j in 0..n {
                    let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
                    faces.push([a, b, c]);
                    faces.push([a, c, d]);
                }
            }
        }
    }
    let (mut mesh, _) = weld(&TriMesh::new(positions, faces), 0.0);
    for p in &mut mesh.positions {
        *p = p.normalize();
    }
    super::spheres::fix_winding_outward(&mesh.positions, &mut mesh.faces);
    for p in &mut mesh.positions {
        *p *= 1.0 + 0.3 * fbm(*p * 1.7, seed);
    }
    mesh
}

/// Fractal value noise in about [-1, 1]: four octaves, gain 0.5.
pub(crate) fn fbm(p: Vec3, seed: u32) -> f32 {
    let (mut sum, mut amp, mut freq) = (0.0, 0.5, 1.0);
    for octave in 0..4 {
        sum += amp * value_noise(p * freq, seed.wrapping_add(octave * 0x9E37));
        amp *= 0.5;
        freq *= 2.03;
    }
    sum / 0.9375
}

fn value_noise(p: Vec3, seed: u32) -> f32 {
    let cell = p.floor();
    let t = p - cell;
    let s = t * t * (Vec3::splat(3.0) - 2.0 * t);
    let c = cell.as_ivec3();
    let h = |d: IVec3| lattice(c + d, seed);
    let lerp = |a: f32, b: f32, t: f32| a + (b - a) * t;
    let x00 = lerp(h(IVec3::new(0, 0, 0)), h(IVec3::new(1, 0, 0)), s.x);
    let x10 = lerp(h(IVec3::new(0, 1, 0)), h(IVec3::new(1, 1, 0)), s.x);
    let x01 = lerp(h(IVec3::new(0, 0, 1)), h(IVec3::new(1, 0, 1)), s.x);
    let x11 = lerp(h(IVec3::new(0, 1, 1)), h(IVec3::new(1, 1, 1)), s.x);
    lerp(lerp(x00, x10, s.y), lerp(x01, x11, s.y), s.z)
}

/// A hash of a lattice point to [-1, 1] (integer mixing, platform-exact).
fn lattice(c: IVec3, seed: u32) -> f32 {
    let mut h = seed.wrapping_mul(0x2C1B_3C6D);
    for v in [c.x, c.y, c.z] {
        h ^= v as u32;
        h = h.wrapping_mul(0x297A_2D39);
        h ^= h >> 15;
    }
    h = h.wrapping_mul(0x85EB_CA6B);
    h ^= h >> 13;
    (h as f32 / u32::MAX as f32) * 2.0 - 1.0
}
