//! Decimation — §6.3 of Yemez & Schmitt (optional).
//!
//! A triangle with an edge shorter than a fraction of the cube size is not
//! built and its two cubes are merged (positions and colours averaged).
//! Departure: a cube merges at most once per level, so merges pair cubes
//! instead of chaining across the surface; a short edge whose cubes are
//! already taken is kept.
use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::topology::UnionFind;

/// §6.3: merges the cubes of the first edge of `f` shorter than `min`
/// whose cubes are not merged yet; whether it did (the triangle is then
/// not built). Out of line: the scan's emission stays small enough to
/// inline.
#[inline(never)]
pub(super) fn merge_short_edge(
    f: [u32; 3],
    min: f32,
    positions: &[Vec3],
    merged: &mut [bool],
    merges: &mut Vec<(u32, u32)>,
) -> bool {
    for e in 0..3 {
        let (a, b) = (f[e], f[(e + 1) % 3]);
        if positions[a as usize].distance(positions[b as usize]) < min
            && !merged[a as usize]
            && !merged[b as usize]
        {
            merged[a as usize] = true;
            merged[b as usize] = true;
            merges.push((a, b));
            return true;
        }
    }
    false
}

/// §6.3: merge the cubes joined by short edges (positions and attributes
/// averaged), drop the triangles that collapse.
#[inline]
pub(super) fn decimate_merge(mesh: &mut TriMesh, faces: &mut Vec<[u32; 3]>, merges: &[(u32, u32)]) {
    let n = mesh.positions.len();
    let mut uf = UnionFind::new(n);
    for &(a, b) in merges {
        uf.union(a, b);
    }
    let root: Vec<u32> = (0..n as u32).map(|v| uf.find(v)).collect();
    let mut sum = vec![Vec3::ZERO; n];
    let mut count = vec![0u32; n];
    let mut col = vec![[0u32; 4]; n];
    for v in 0..n {
        let r = root[v] as usize;
        sum[r] += mesh.positions[v];
        count[r] += 1;
        if let Some(c) = &mesh.colors {
            for k in 0..4 {
                col[r][k] += u32::from(c[v][k]);
            }
        }
    }
    for v in 0..n {
        let r = root[v] as usize;
        mesh.positions[v] = sum[r] / count[r] as f32;
        if let Some(c) = mesh.colors.as_mut() {
            c[v] = col[r].map(|x| (x / count[r]) as u8);
        }
    }
    for f in faces.iter_mut() {
        *f = f.map(|v| root[v as usize]);
    }
    faces.retain(|f| f[0] != f[1] && f[1] != f[2] && f[0] != f[2]);
}
