//! Particle attributes of a carved octree — §8.1.1 of Yemez & Schmitt.
//!
//! - **Vertex**: the centre of gravity of the hull's surface points in the
//!   leaf. The surface points are the midpoints of the leaf's refinement
//!   lattice edges ([`super::carve::SUB`]³ points) whose ends fall on
//!   either side of the hull; a leaf with no such edge keeps its centre.
//! - **Normal**: from the octree neighbourhood: minus the gradient of the
//!   occupancy over the 5×5×5 leaves around it (IN 1, OUT 0, an ON leaf
//!   the fraction of its refinement points in the hull), weighted by
//!   `1/|d|²`.
//! - **Colour**: from the views that see the vertex, best aligned with
//!   the normal first: at most [`BLEND_VIEWS`] views with
//!   `cos(normal, view) ≥` [`MIN_COSINE`] whose ray from the vertex to the
//!   camera meets no occupied cube of the carved volume (a DDA march
//!   through an occupancy grid of level `min(R, 8)`, from
//!   [`RAY_START`] cubes off the vertex), blended with weights `cos²`;
//!   bilinear samples of the images. Where no view passes, the best
//!   aligned view is used as it is.
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::octree::{Label, Octree, QBITS, morton, unmorton};
use crate::silhouette::carve::{Carved, SUB};
use crate::silhouette::images::ViewImage;
use lodkit_mesh::io::cameras::View;

/// Views blended into a particle's colour.
pub const BLEND_VIEWS: usize = 3;
/// Least cosine between normal and view direction a colour view needs.
pub const MIN_COSINE: f64 = 0.2;
/// Where the visibility march starts, in cubes of the occupancy grid: the
/// vertex's own surface band is occupied.
pub const RAY_START: f64 = 2.5;
/// Deepest level of the visibility grid (256³ bytes = 16 MiB).
const GRID_LEVEL: u8 = 8;

/// Vertices (16-bit grid) and outward normals of the ON leaves, in the
/// order of `carved.leaves` (= the tree's level `R`); a leaf with
/// `kept[i]` false (eliminated by thinning, never coded) gets its centre
/// and a zero normal.
pub fn vertices_and_normals(
    tree: &Octree,
    carved: &Carved,
    kept: &[bool],
) -> (Vec<[u32; 3]>, Vec<Vec3>) {
    let r = tree.depth;
    let s = QBITS - u32::from(r);
    let fraction: crate::octree::MortonMap<f64> = carved
        .leaves
        .iter()
        .zip(&carved.inside)
        .map(|(&m, &b)| (m, f64::from(b.count_ones()) / (SUB * SUB * SUB) as f64))
        .collect();
    carved
        .leaves
        .par_iter()
        .zip(&carved.inside)
        .zip(kept)
        .map(|((&m, &bits), &keep)| {
            let c = unmorton(m);
            if !keep {
                let half = 1u32 << (s - 1).min(15);
                return (
                    c.map(|v| (v << s) + if s == 0 { 0 } else { half }),
                    Vec3::ZERO,
                );
            }
            // Vertex.
            let at = |i: usize, j: usize, k: usize| bits >> (i + SUB * j + SUB * SUB * k) & 1 == 1;
            let mut sum = DVec3::ZERO;
            let mut n = 0u32;
            for k in 0..SUB {
                for j in 0..SUB {
                    for i in 0..SUB {
                        let here = at(i, j, k);
                        let p = DVec3::new(i as f64, j as f64, k as f64) + 0.5;
                        for (a, nb) in [
                            (i + 1, (i + 1, j, k)),
                            (j + 1, (i, j + 1, k)),
                            (k + 1, (i, j, k + 1)),
                        ]
                        .iter()
                        .enumerate()
                        .map(|(axis, (lim, nb))| ((axis, *lim), *nb))
                        {
                            if a.1 < SUB && at(nb.0, nb.1, nb.2) != here {
                                let mut q = p;
                                q[a.0] += 0.5;
                                sum += q;
                                n += 1;
                            }
                        }
                    }
                }
            }
            let local = if n > 0 {
                sum / f64::from(n) / SUB as f64
            } else {
                DVec3::splat(0.5)
            };
            let unit = f64::from(1u32 << s);
            let mut q = [0u32; 3];
            for a in 0..3 {
                let lo = c[a] << s;
                let v = (f64::from(lo) + local[a] * unit).floor() as u32;
                q[a] = v.clamp(lo, lo + (1 << s) - 1);
            }
            // Normal.
            let side = 1i64 << r;
            let mut g = DVec3::ZERO;
            for dz in -2i64..=2 {
                for dy in -2i64..=2 {
                    for dx in -2i64..=2 {
                        if dx == 0 && dy == 0 && dz == 0 {
                            continue;
                        }
                        let p = [c[0] as i64 + dx, c[1] as i64 + dy, c[2] as i64 + dz];
                        let occ = if p.iter().any(|&v| v < 0 || v >= side) {
                            0.0
                        } else {
                            let pm = morton([p[0] as u32, p[1] as u32, p[2] as u32]);
                            match fraction.get(&pm) {
                                Some(&f) => f,
                                None => {
                                    match tree.label(r, [p[0] as u32, p[1] as u32, p[2] as u32]) {
                                        Label::In => 1.0,
                                        _ => 0.0,
                                    }
                                }
                            }
                        };
                        let d = DVec3::new(dx as f64, dy as f64, dz as f64);
                        g += d * (occ / d.length_squared());
                    }
                }
            }
            (q, (-g).normalize_or_zero().as_vec3())
        })
        .unzip()
}

/// Occupancy grid of level `min(R, GRID_LEVEL)`: a cell is occupied when
/// it holds a kept (ON) or IN cube.
struct Grid {
    level: u8,
    side: usize,
    occupied: Vec<bool>,
}

impl Grid {
    fn new(tree: &Octree) -> Grid {
        let level = tree.depth.min(GRID_LEVEL);
        let side = 1usize << level;
        let mut occupied = vec![false; side * side * side];
        let idx = |c: [u32; 3]| (c[2] as usize * side + c[1] as usize) * side + c[0] as usize;
        // Cells of level `level` with ON descendants.
        for &m in &tree.levels[level as usize].cells {
            occupied[idx(unmorton(m))] = true;
        }
        // IN band cells at levels up to `level` fill their block.
        for r in 1..=level as usize {
            let sh = level as usize - r;
            for (&m, &l) in &tree.levels[r].band {
                if l != Label::In {
                    continue;
                }
                let c = unmorton(m);
                let n = 1u32 << sh;
                for z in 0..n {
                    for y in 0..n {
                        for x in 0..n {
                            occupied[idx([(c[0] << sh) + x, (c[1] << sh) + y, (c[2] << sh) + z])] =
                                true;
                        }
                    }
                }
            }
        }
        Grid {
            level,
            side,
            occupied,
        }
    }

    /// Whether the segment from `p` (grid units) towards `target` meets an
    /// occupied cell beyond [`RAY_START`] cells.
    fn occluded(&self, p: DVec3, target: DVec3) -> bool {
        let dir = target - p;
        let len = dir.length();
        if len <= RAY_START {
            return false;
        }
        let d = dir / len;
        let side = self.side as f64;
        // Clip the segment [RAY_START, len] to the grid box.
        let (mut t0, mut t1) = (RAY_START, len);
        for a in 0..3 {
            if d[a].abs() < 1e-12 {
                if p[a] < 0.0 || p[a] >= side {
                    return false;
                }
            } else {
                let (ta, tb) = ((0.0 - p[a]) / d[a], (side - p[a]) / d[a]);
                t0 = t0.max(ta.min(tb));
                t1 = t1.min(ta.max(tb));
            }
        }
        if t0 >= t1 {
            return false;
        }
        // Amanatides–Woo traversal.
        let start = p + d * (t0 + 1e-9);
        let mut cell = [0i64; 3];
        let mut step = [0i64; 3];
        let mut next = [f64::INFINITY; 3];
        let mut delta = [f64::INFINITY; 3];
        for a in 0..3 {
            cell[a] = (start[a].floor() as i64).clamp(0, self.side as i64 - 1);
            if d[a] > 0.0 {
                step[a] = 1;
                delta[a] = 1.0 / d[a];
                next[a] = t0 + ((cell[a] + 1) as f64 - start[a]) / d[a];
            } else if d[a] < 0.0 {
                step[a] = -1;
                delta[a] = -1.0 / d[a];
                next[a] = t0 + (cell[a] as f64 - start[a]) / d[a];
            }
        }
        let n = self.side as i64;
        for _ in 0..4 * self.side {
            let i =
                (cell[2] as usize * self.side + cell[1] as usize) * self.side + cell[0] as usize;
            if self.occupied[i] {
                return true;
            }
            let a = if next[0] < next[1] {
                if next[0] < next[2] { 0 } else { 2 }
            } else if next[1] < next[2] {
                1
            } else {
                2
            };
            if next[a] > t1 {
                return false;
            }
            cell[a] += step[a];
            if cell[a] < 0 || cell[a] >= n {
                return false;
            }
            next[a] += delta[a];
        }
        false
    }
}

fn bilinear(img: &ViewImage, u: f64, v: f64) -> Option<DVec3> {
    let (w, h) = (img.width as i64, img.height as i64);
    let (x, y) = (u - 0.5, v - 0.5);
    if !(x.is_finite() && y.is_finite())
        || x < -0.5
        || y < -0.5
        || x > w as f64 - 0.5
        || y > h as f64 - 0.5
    {
        return None;
    }
    let (x0, y0) = (x.floor() as i64, y.floor() as i64);
    let (fx, fy) = (x - x0 as f64, y - y0 as f64);
    let px = |i: i64, j: i64| {
        let (i, j) = (i.clamp(0, w - 1) as usize, j.clamp(0, h - 1) as usize);
        let k = (j * img.width as usize + i) * 3;
        DVec3::new(
            f64::from(img.rgb[k]),
            f64::from(img.rgb[k + 1]),
            f64::from(img.rgb[k + 2]),
        )
    };
    Some(
        px(x0, y0) * (1.0 - fx) * (1.0 - fy)
            + px(x0 + 1, y0) * fx * (1.0 - fy)
            + px(x0, y0 + 1) * (1.0 - fx) * fy
            + px(x0 + 1, y0 + 1) * fx * fy,
    )
}

/// Colours of the particles at world positions `points` with normals
/// `normals`; `kept[i]` false skips particle `i` (eliminated by
/// thinning: black, never coded).
pub fn colours(
    tree: &Octree,
    views: &[View],
    images: &[ViewImage],
    points: &[DVec3],
    normals: &[Vec3],
    kept: &[bool],
) -> Vec<[u8; 3]> {
    let grid = Grid::new(tree);
    let cell = f64::from(tree.frame.size) / (1u64 << grid.level) as f64;
    let origin = tree.frame.origin.as_dvec3();
    let to_grid = |p: DVec3| (p - origin) / cell;
    let centres: Vec<DVec3> = views.iter().map(View::centre).collect();
    (0..points.len())
        .into_par_iter()
        .map(|i| {
            if !kept[i] {
                return [0, 0, 0];
            }
            let p = points[i];
            let n = normals[i].as_dvec3();
            let mut order: Vec<(f64, usize)> = centres
                .iter()
                .enumerate()
                .map(|(k, c)| ((*c - p).normalize_or_zero().dot(n), k))
                .collect();
            // Best aligned first; ties by view index (deterministic).
            order.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let gp = to_grid(p);
            let mut sum = DVec3::ZERO;
            let mut wsum = 0.0;
            let mut used = 0;
            for &(cos, k) in &order {
                if cos < MIN_COSINE || used == BLEND_VIEWS {
                    break;
                }
                if grid.occluded(gp, to_grid(centres[k])) {
                    continue;
                }
                let Some((u, v)) = views[k].project(p) else {
                    continue;
                };
                if let Some(c) = bilinear(&images[k], u, v) {
                    sum += c * cos * cos;
                    wsum += cos * cos;
                    used += 1;
                }
            }
            if wsum == 0.0 {
                for &(_, k) in &order {
                    if let Some((u, v)) = views[k].project(p)
                        && let Some(c) = bilinear(&images[k], u, v)
                    {
                        sum = c;
                        wsum = 1.0;
                        break;
                    }
                }
            }
            if wsum == 0.0 {
                return [128, 128, 128];
            }
            let c = sum / wsum;
            [c.x, c.y, c.z].map(|v| v.round().clamp(0.0, 255.0) as u8)
        })
        .collect()
}
