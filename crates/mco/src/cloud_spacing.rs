//! A point cloud's sample spacing: the distance from sampled query points
//! to their `k`-th nearest neighbour, found in a uniform grid.
//!
//! The spacing needs only ~20k queries, but each against every point: a
//! kd-tree over the whole cloud (sorting it) cost a tenth of a 1M-point
//! build. A grid of about twelve cells per point, filled by one counting
//! sort, answers the same queries exactly: every point within the searched
//! block of cells is measured, and the block grows until the `k`-th
//! distance is closer than any cell outside it can be. Distances are
//! summed in axis order as `kiddo`'s squared Euclidean metric sums them,
//! so the values (and the median of them) are the same bit for bit.
//!
//! The grid assumes surface-like data (a few points per occupied cell). If
//! a cell holds too many points (e.g. samples along a curve) it gives up
//! and the caller uses a kd-tree.

use glam::Vec3;

/// Most points one cell may hold before the grid gives up.
/// (`shapes::blob` at 1M points crowds up to ~70 into one; points along a
/// curve would put thousands in each, and every query would measure
/// dozens of such cells.)
const MAX_CELL_POINTS: u32 = 512;

/// `dist[k]` from every `step`-th point of `points` (from the first) to its
/// `k`-th nearest other point (the query itself is its 0-th neighbour;
/// duplicates count as neighbours at distance 0), or `None` if the grid
/// does not suit the data (non-finite coordinates, crowded cells, fewer
/// than `k + 1` points).
pub fn kth_neighbour_distances(points: &[Vec3], step: usize, k: usize) -> Option<Vec<f32>> {
    let n = points.len();
    if n < k + 1 || step == 0 || !points.iter().all(|p| p.is_finite()) {
        return None;
    }
    let (lo, hi) = points.iter().fold((points[0], points[0]), |(lo, hi), &p| {
        (lo.min(p), hi.max(p))
    });
    let longest = (hi - lo).max_element();
    if longest <= 0.0 {
        return Some(vec![0.0; n.div_ceil(step)]);
    }
    // About 12n cells in the bounding cube of the longest side: on a
    // surface, a few points per occupied cell (far fewer cells make long
    // cell lists, far more make many empty cells to scan).
    let per_axis = ((12.0 * n as f64).cbrt().ceil() as u32).max(1);
    let h = longest / per_axis as f32;
    let inv = 1.0 / h;
    let dims = ((hi - lo) * inv).to_array().map(|e| e as u32 + 1);
    let cell_of = |p: Vec3| -> [u32; 3] {
        let c = ((p - lo) * inv).to_array();
        [0, 1, 2].map(|a| (c[a] as u32).min(dims[a] - 1))
    };
    let index = |c: [u32; 3]| {
        (c[2] as usize * dims[1] as usize + c[1] as usize) * dims[0] as usize + c[0] as usize
    };
    let cells = dims.iter().map(|&d| d as usize).product::<usize>();
    // Counting sort of the points by cell: `start[c]..start[c + 1]`.
    let mut start = vec![0u32; cells + 1];
    let mut cell = Vec::with_capacity(n);
    for &p in points {
        let c = index(cell_of(p));
        start[c + 1] += 1;
        if start[c + 1] > MAX_CELL_POINTS {
            return None;
        }
        cell.push(c as u32);
    }
    for c in 0..cells {
        start[c + 1] += start[c];
    }
    let mut next = start.clone();
    let mut sorted = vec![Vec3::ZERO; n];
    for (&p, &c) in points.iter().zip(&cell) {
        let slot = &mut next[c as usize];
        sorted[*slot as usize] = p;
        *slot += 1;
    }
    drop(cell);
    drop(next);
    let mut out = Vec::with_capacity(n.div_ceil(step));
    // The k + 1 smallest squared distances so far, ascending.
    let mut best = vec![f32::INFINITY; k + 1];
    for &q in points.iter().step_by(step) {
        let qc = cell_of(q);
        let mut r = 1u32;
        loop {
            // The block of cells within Chebyshev distance r of q's cell,
            // from scratch (a wider block is rarely needed): each of its
            // x-rows is one run of consecutive cells, one slice of points.
            best.fill(f32::INFINITY);
            let span = |a: usize| qc[a].saturating_sub(r)..=(qc[a] + r).min(dims[a] - 1);
            let (x0, x1) = (qc[0].saturating_sub(r), (qc[0] + r).min(dims[0] - 1));
            for z in span(2) {
                for y in span(1) {
                    let run =
                        start[index([x0, y, z])] as usize..start[index([x1, y, z]) + 1] as usize;
                    for &p in &sorted[run] {
                        let d = q - p;
                        let d2 = d.x * d.x + d.y * d.y + d.z * d.z;
                        if d2 < best[k] {
                            let mut i = k;
                            while i > 0 && best[i - 1] > d2 {
                                best[i] = best[i - 1];
                                i -= 1;
                            }
                            best[i] = d2;
                        }
                    }
                }
            }
            // Points outside the searched block are at least r·h away
            // (shrunk a little for rounding in the cell computation).
            let reach = r as f32 * h * 0.999;
            let covered = (0..3).all(|a| qc[a] <= r && qc[a] + r >= dims[a] - 1);
            if covered || best[k] <= reach * reach {
                break;
            }
            r += 1;
        }
        out.push(best[k].sqrt());
    }
    Some(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_xoshiro::Xoshiro256PlusPlus;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};

    /// The k-th distances as sorting all distances finds them.
    fn brute(points: &[Vec3], step: usize, k: usize) -> Vec<f32> {
        points
            .iter()
            .step_by(step)
            .map(|&q| {
                let mut d: Vec<f32> = points
                    .iter()
                    .map(|&p| {
                        let d = q - p;
                        d.x * d.x + d.y * d.y + d.z * d.z
                    })
                    .collect();
                d.sort_by(f32::total_cmp);
                d[k].sqrt()
            })
            .collect()
    }

    /// The k-th distances as the `kiddo` kd-tree finds them.
    fn kd_tree(points: &[Vec3], step: usize, k: usize) -> Vec<f32> {
        use kiddo::{ImmutableKdTree, SquaredEuclidean};
        let pts: Vec<[f32; 3]> = points.iter().map(|v| v.to_array()).collect();
        let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&pts).unwrap();
        let n = std::num::NonZero::new(k + 1).unwrap();
        pts.iter()
            .step_by(step)
            .map(|q| {
                let r = tree
                    .query(q)
                    .nearest_n::<SquaredEuclidean<f32>>(n)
                    .execute();
                r[k].distance.sqrt()
            })
            .collect()
    }

    #[test]
    fn grid_neighbours_equal_brute_force_and_the_kd_tree() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x9e37_79b9_7f4a_7c15);
        let mut next = || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        // A sphere's surface, a flat square with duplicates, and a few
        // scattered points (large rings).
        let sphere: Vec<Vec3> = (0..1200)
            .map(|_| Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or_zero())
            .collect();
        let mut flat: Vec<Vec3> = (0..1000).map(|_| Vec3::new(next(), next(), 0.0)).collect();
        flat.extend_from_within(..50);
        let sparse: Vec<Vec3> = (0..7)
            .map(|_| Vec3::new(next(), next(), next()) * 10.0)
            .collect();
        for (name, pts) in [("sphere", sphere), ("flat", flat), ("sparse", sparse)] {
            for (step, k) in [(1, 1), (7, 4), (3, 6)] {
                let grid = kth_neighbour_distances(&pts, step, k);
                assert_eq!(
                    grid,
                    Some(brute(&pts, step, k)),
                    "{name}, step {step}, k {k}"
                );
                assert_eq!(
                    grid,
                    Some(kd_tree(&pts, step, k)),
                    "{name}, step {step}, k {k}"
                );
            }
        }
        assert_eq!(kth_neighbour_distances(&[Vec3::ZERO; 3], 1, 4), None);
        assert_eq!(
            kth_neighbour_distances(&[Vec3::ONE; 6], 2, 4),
            Some(vec![0.0; 3])
        );
    }
}
