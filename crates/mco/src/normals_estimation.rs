//! Oriented samples from every kind of input (thesis §4.2, §4.3.1).
//!
//! - **Range images** (Fig. 4.2): a lattice point's normal is the average
//!   of the normals of the 4 triangles it forms with its 4 lattice
//!   neighbours (right–up, up–left, left–down, down–right). Triangles with
//!   a missing neighbour are skipped; a point with none is dropped. The
//!   thesis does not say how the normal's side is chosen: the lattice's
//!   winding gives every normal of one scan the same side, and the whole
//!   scan is flipped if most normals face away from the sensor (+z in the
//!   sensor frame, the Stanford scans' and lodkit's scanner's convention).
//!   Normals are computed in the sensor frame and then rotated by the
//!   pose.
//! - **Meshes** (§4.3.1): vertices with area-weighted vertex normals
//!   (`lodkit_mesh::normals`); unreferenced vertices are dropped.
//! - **Bare point clouds** (beyond the thesis, which assumes range data):
//!   PCA over the k nearest neighbours (a `kiddo` kd-tree) gives the
//!   tangent plane, and Hoppe et al.'s propagation over the k-NN graph
//!   (Prim's order, weight `1 − |nᵢ·nⱼ|`) orients the normals
//!   consistently, seeded by the highest point whose normal is set to
//!   point up (+z).

use std::collections::BinaryHeap;
use std::num::NonZero;

use glam::{Mat3, Vec3};
use kiddo::{ImmutableKdTree, SquaredEuclidean};
use lodkit_mesh::{PointCloud, RangeImage, TriMesh};

use crate::{Error, Result};

/// Neighbours used by the PCA normal estimate (Hoppe et al. use 10–20).
pub const PCA_NEIGHBOURS: usize = 12;

/// Oriented samples of a range image (Fig. 4.2), in world space.
pub fn range_image_samples(r: &RangeImage) -> PointCloud {
    let (rows, cols) = (r.rows, r.cols);
    let at = |row: isize, col: isize| -> Option<Vec3> {
        if row < 0 || col < 0 || row as usize >= rows || col as usize >= cols {
            return None;
        }
        r.cell(row as usize, col as usize)
    };
    let mut raw: Vec<(usize, Vec3)> = Vec::new();
    for row in 0..rows as isize {
        for col in 0..cols as isize {
            let Some(p) = at(row, col) else { continue };
            // Neighbours counter-clockwise in (col, row): right, up, left, down.
            let nb = [
                at(row, col + 1),
                at(row + 1, col),
                at(row, col - 1),
                at(row - 1, col),
            ];
            let mut sum = Vec3::ZERO;
            for i in 0..4 {
                if let (Some(a), Some(b)) = (nb[i], nb[(i + 1) % 4]) {
                    let n = (a - p).cross(b - p);
                    let len = n.length();
                    if len > 0.0 && len.is_finite() {
                        sum += n / len;
                    }
                }
            }
            if sum.length_squared() > 0.0 {
                raw.push((row as usize * cols + col as usize, sum.normalize()));
            }
        }
    }
    let facing = raw.iter().filter(|(_, n)| n.z > 0.0).count();
    let flip = if facing * 2 < raw.len() { -1.0 } else { 1.0 };
    let pose = r.pose.unwrap_or(lodkit_mesh::Pose::IDENTITY);
    PointCloud {
        positions: raw.iter().map(|&(i, _)| pose.apply(r.points[i])).collect(),
        normals: Some(
            raw.iter()
                .map(|&(_, n)| pose.apply_vector(n * flip).normalize())
                .collect(),
        ),
        colors: r
            .colors
            .as_ref()
            .map(|c| raw.iter().map(|&(i, _)| c[i]).collect()),
    }
}

/// Oriented samples of a mesh: referenced vertices with area-weighted
/// normals. Vertices whose normal is zero (only degenerate faces) are
/// dropped.
pub fn mesh_samples(m: &TriMesh) -> PointCloud {
    mesh_samples_with(m, &vertex_normals(m))
}

/// The mesh's area-weighted vertex normals, computed at any scale: a mesh
/// whose extent is far from 1 (cross products overflow `f32` around 1e19,
/// go subnormal around 1e-19) has them computed on a copy scaled by a
/// power of two, which gives the same directions; other meshes as
/// `lodkit_mesh::normals::vertex_normals` does.
pub(crate) fn vertex_normals(m: &TriMesh) -> Vec<Vec3> {
    let extent = m.bbox().size().max_element();
    let s = crate::lattice::normalising_scale(extent / 256.0);
    if s == 1.0 {
        return lodkit_mesh::normals::vertex_normals(m);
    }
    let scaled = TriMesh {
        positions: m.positions.iter().map(|&p| p * s).collect(),
        normals: None,
        colors: None,
        uvs: None,
        faces: m.faces.clone(),
    };
    lodkit_mesh::normals::vertex_normals(&scaled)
}

/// [`mesh_samples`] with the mesh's vertex normals already computed.
pub(crate) fn mesh_samples_with(m: &TriMesh, normals: &[Vec3]) -> PointCloud {
    let mut used = vec![false; m.positions.len()];
    for f in &m.faces {
        for &i in f {
            if let Some(u) = used.get_mut(i as usize) {
                *u = true;
            }
        }
    }
    let keep: Vec<usize> = (0..m.positions.len())
        .filter(|&i| used[i] && normals[i].length_squared() > 0.5 && m.positions[i].is_finite())
        .collect();
    PointCloud {
        positions: keep.iter().map(|&i| m.positions[i]).collect(),
        normals: Some(keep.iter().map(|&i| normals[i]).collect()),
        colors: m
            .colors
            .as_ref()
            .map(|c| keep.iter().map(|&i| c[i]).collect()),
    }
}

/// Makes `s`, the [`mesh_samples`] of `m`, dense enough for cube `cube`
/// ([`densify_mesh_samples`]), computing the vertex normals once more only
/// if some triangle needs them.
pub fn densify_mesh_samples_of(m: &TriMesh, cube: f32, s: &mut PointCloud) {
    if long_edged_faces(m, cube).next().is_none() {
        return;
    }
    densify_mesh_samples(m, &vertex_normals(m), cube, s);
}

/// Faces of `m` (valid indices) with an edge longer than `cube`, with their
/// corner positions and that edge length; a face on the same three
/// vertices as an earlier one (in any order) is left out: it would add the
/// same samples again, so a mesh of one triangle repeated a million times
/// is densified once, not a million times.
pub(crate) fn long_edged_faces(
    m: &TriMesh,
    cube: f32,
) -> impl Iterator<Item = (&[u32; 3], [Vec3; 3], f32)> {
    let nv = m.positions.len();
    let ok = cube > 0.0 && cube.is_finite();
    let mut seen: rustc_hash::FxHashSet<[u32; 3]> = Default::default();
    m.faces.iter().filter_map(move |f| {
        if !ok || f.iter().any(|&i| i as usize >= nv) {
            return None;
        }
        let [a, b, c] = f.map(|i| m.positions[i as usize]);
        // One square root: it is monotone, so the longest edge is the root
        // of the largest squared length (NaNs are skipped by `max` alike).
        let mut longest = a
            .distance_squared(b)
            .max(b.distance_squared(c))
            .max(c.distance_squared(a))
            .sqrt();
        if longest.is_infinite() {
            // Squared lengths past f32's range (coordinates around 1e19):
            // the length itself may still fit.
            let [a, b, c] = [a, b, c].map(|p| p.as_dvec3());
            longest = (a.distance(b).max(b.distance(c)).max(c.distance(a))) as f32;
        }
        if !(longest > cube && longest.is_finite()) {
            return None;
        }
        let mut key = *f;
        key.sort_unstable();
        seen.insert(key).then_some((f, [a, b, c], longest))
    })
}

/// Subdivisions per side of a long-edged face's sample grid: half-cube
/// spacing, at most [`MAX_SUBDIVISIONS`] (bounded work per face).
fn subdivisions(longest: f32, cube: f32) -> usize {
    ((2.0 * longest / cube).ceil() as usize).min(MAX_SUBDIVISIONS)
}

/// Most subdivisions per side of one face's densification grid.
const MAX_SUBDIVISIONS: usize = 64;

/// At most how many samples [`densify_mesh_samples`] adds to `m`'s for cube
/// `cube` (exact but for the samples whose interpolated normal is zero),
/// without making them: the figure the build's memory estimate uses.
/// `O(faces)`.
pub(crate) fn densify_count(m: &TriMesh, cube: f32) -> u64 {
    long_edged_faces(m, cube)
        .map(|(_, _, longest)| {
            let n = subdivisions(longest, cube) as u64;
            // The grid's points less its three corners.
            (n + 1) * (n + 2) / 2 - 3
        })
        .sum()
}

/// Makes mesh samples `s` dense enough for a lattice of cube `cube`: to
/// the vertices (as [`mesh_samples`]) it appends, on every triangle with an edge longer than a
/// cube, points on a barycentric grid of half a cube, with normals
/// interpolated from the area-weighted vertex normals. Beyond the thesis
/// (which samples vertices only): a mesh with long edges would otherwise
/// leave cubes the surface crosses with no sample near, hence holes.
/// `normals` are the mesh's vertex normals.
pub(crate) fn densify_mesh_samples(m: &TriMesh, normals: &[Vec3], cube: f32, s: &mut PointCloud) {
    let out_normals = s.normals.get_or_insert_default();
    for (f, [a, b, c], longest) in long_edged_faces(m, cube) {
        let [na, nb, nc] = f.map(|i| normals[i as usize]);
        let n = subdivisions(longest, cube);
        let color = m.colors.as_ref().map(|cs| cs[f[0] as usize]);
        for i in 0..=n {
            for j in 0..=n - i {
                let k = n - i - j;
                if i == n || j == n || k == n {
                    continue; // the corners are vertex samples already
                }
                let (u, v, w) = (
                    i as f32 / n as f32,
                    j as f32 / n as f32,
                    k as f32 / n as f32,
                );
                let nrm = (na * u + nb * v + nc * w).normalize_or_zero();
                if nrm == Vec3::ZERO {
                    continue;
                }
                s.positions.push(a * u + b * v + c * w);
                out_normals.push(nrm);
                if let (Some(cs), Some(col)) = (s.colors.as_mut(), color) {
                    cs.push(col);
                }
            }
        }
    }
}

/// Oriented samples of a point cloud: its own normals when it has them,
/// else PCA normals oriented consistently (see the module docs).
pub fn point_cloud_samples(pc: &PointCloud) -> Result<PointCloud> {
    let normals = match &pc.normals {
        Some(n) => n.iter().map(|v| v.normalize_or_zero()).collect(),
        None => estimate_normals(&pc.positions, PCA_NEIGHBOURS)?,
    };
    let keep: Vec<usize> = (0..pc.positions.len())
        .filter(|&i| normals[i].length_squared() > 0.5 && pc.positions[i].is_finite())
        .collect();
    Ok(PointCloud {
        positions: keep.iter().map(|&i| pc.positions[i]).collect(),
        normals: Some(keep.iter().map(|&i| normals[i]).collect()),
        colors: pc
            .colors
            .as_ref()
            .map(|c| keep.iter().map(|&i| c[i]).collect()),
    })
}

/// PCA normals over `k` nearest neighbours, consistently oriented.
/// Errors if there are fewer than 3 points.
pub fn estimate_normals(points: &[Vec3], k: usize) -> Result<Vec<Vec3>> {
    if points.len() < 3 {
        return Err(Error::Input(format!(
            "{} points are too few to estimate normals",
            points.len()
        )));
    }
    let k = k.clamp(3, points.len());
    let entries: Vec<[f32; 3]> = points.iter().map(|p| p.to_array()).collect();
    let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&entries)
        .map_err(|e| Error::Input(format!("cannot index the points: {e:?}")))?;
    let kk = NonZero::new(k).expect("k >= 3");
    let mut neighbours: Vec<Vec<u32>> = Vec::with_capacity(points.len());
    let mut normals = Vec::with_capacity(points.len());
    for p in &entries {
        let found = tree
            .query(p)
            .nearest_n::<SquaredEuclidean<f32>>(kk)
            .execute();
        let mut idx: Vec<u32> = found.iter().map(|r| r.item).collect();
        idx.sort_unstable();
        let centroid = idx.iter().map(|&i| points[i as usize]).sum::<Vec3>() / idx.len() as f32;
        let mut cov = Mat3::ZERO;
        for &i in &idx {
            let d = points[i as usize] - centroid;
            cov += Mat3::from_cols(d * d.x, d * d.y, d * d.z);
        }
        normals.push(smallest_eigenvector(cov));
        neighbours.push(idx);
    }
    orient(points, &neighbours, &mut normals);
    Ok(normals)
}

/// Unit eigenvector of the smallest eigenvalue of a symmetric 3×3 matrix
/// (cyclic Jacobi rotations; converges in a handful of sweeps).
pub fn smallest_eigenvector(m: Mat3) -> Vec3 {
    let mut a = [[0f64; 3]; 3];
    for (c, col) in [m.x_axis, m.y_axis, m.z_axis].iter().enumerate() {
        for r in 0..3 {
            a[r][c] = col[r] as f64;
        }
    }
    let mut v = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0f64]];
    for _ in 0..32 {
        let off = a[0][1].abs() + a[0][2].abs() + a[1][2].abs();
        if off < 1e-30 {
            break;
        }
        for (p, q) in [(0, 1), (0, 2), (1, 2)] {
            if a[p][q].abs() < 1e-300 {
                continue;
            }
            let theta = (a[q][q] - a[p][p]) / (2.0 * a[p][q]);
            let t = theta.signum() / (theta.abs() + (theta * theta + 1.0).sqrt());
            let t = if theta == 0.0 { 1.0 } else { t };
            let c = 1.0 / (t * t + 1.0).sqrt();
            let s = t * c;
            for row in &mut a {
                let (akp, akq) = (row[p], row[q]);
                row[p] = c * akp - s * akq;
                row[q] = s * akp + c * akq;
            }
            let (rp, rq) = (a[p], a[q]);
            for k in 0..3 {
                a[p][k] = c * rp[k] - s * rq[k];
                a[q][k] = s * rp[k] + c * rq[k];
            }
            for row in &mut v {
                let (vp, vq) = (row[p], row[q]);
                row[p] = c * vp - s * vq;
                row[q] = s * vp + c * vq;
            }
        }
    }
    let i = (0..3)
        .min_by(|&x, &y| a[x][x].total_cmp(&a[y][y]))
        .expect("3 eigenvalues");
    Vec3::new(v[0][i] as f32, v[1][i] as f32, v[2][i] as f32).normalize_or_zero()
}

/// Hoppe's orientation propagation over the k-NN graph (made symmetric),
/// in Prim's order of the weight `1 − |nᵢ·nⱼ|`, one seed per component:
/// its highest point, turned to face +z.
fn orient(points: &[Vec3], nb: &[Vec<u32>], normals: &mut [Vec3]) {
    let n = points.len();
    let mut adj: Vec<Vec<u32>> = nb.to_vec();
    for (i, list) in nb.iter().enumerate() {
        for &j in list {
            if j as usize != i {
                adj[j as usize].push(i as u32);
            }
        }
    }
    for a in &mut adj {
        a.sort_unstable();
        a.dedup();
    }
    let mut done = vec![false; n];
    let mut order: Vec<usize> = (0..n).collect();
    order.sort_by(|&a, &b| points[b].z.total_cmp(&points[a].z).then(a.cmp(&b)));
    for &seed in &order {
        if done[seed] {
            continue;
        }
        if normals[seed].z < 0.0 {
            normals[seed] = -normals[seed];
        }
        done[seed] = true;
        // Max-heap on (similarity, Reverse(index)): the most parallel edge first.
        let mut heap = BinaryHeap::new();
        let push = |heap: &mut BinaryHeap<(u32, std::cmp::Reverse<u32>, u32)>,
                    normals: &[Vec3],
                    from: usize| {
            for &j in &adj[from] {
                let sim = normals[from].dot(normals[j as usize]).abs();
                heap.push(((sim * 1e6) as u32, std::cmp::Reverse(j), from as u32));
            }
        };
        push(&mut heap, normals, seed);
        while let Some((_, std::cmp::Reverse(j), from)) = heap.pop() {
            let j = j as usize;
            if done[j] {
                continue;
            }
            if normals[j].dot(normals[from as usize]) < 0.0 {
                normals[j] = -normals[j];
            }
            done[j] = true;
            push(&mut heap, normals, j);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn range_image_of_a_plane_has_normals_facing_the_sensor() {
        let (rows, cols) = (5, 6);
        let mut points = Vec::new();
        for r in 0..rows {
            for c in 0..cols {
                points.push(Vec3::new(c as f32, r as f32, -3.0));
            }
        }
        let mut valid = vec![true; rows * cols];
        valid[7] = false;
        let img = RangeImage {
            cols,
            rows,
            points,
            valid,
            colors: None,
            pose: None,
        };
        let s = range_image_samples(&img);
        // The hole's 4 neighbours keep their normals except where both
        // neighbours of every triangle touch the hole or the border: the
        // corner cell (1, 0) and (0, 1) lose all 4 triangles.
        assert!(
            s.len() >= rows * cols - 3 && s.len() < rows * cols,
            "{}",
            s.len()
        );
        for n in s.normals.as_deref().unwrap() {
            assert!((n.z - 1.0).abs() < 1e-5, "{n}");
        }
    }

    #[test]
    fn pca_normals_on_a_sphere_point_outwards() {
        let m = lodkit_mesh::shapes::icosphere(3);
        let n = estimate_normals(&m.positions, PCA_NEIGHBOURS).unwrap();
        for (p, n) in m.positions.iter().zip(&n) {
            assert!(p.normalize().dot(*n) > 0.95, "{p} {n}");
        }
    }

    #[test]
    fn smallest_eigenvector_of_a_diagonal_matrix() {
        let m = Mat3::from_diagonal(Vec3::new(3.0, 0.5, 2.0));
        let v = smallest_eigenvector(m);
        assert!(v.y.abs() > 0.999);
    }

    #[test]
    fn too_few_points_is_an_error() {
        assert!(estimate_normals(&[Vec3::ZERO, Vec3::X], 12).is_err());
    }
}
