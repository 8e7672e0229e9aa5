//! Orientation of a triangulated level (not in the paper, which renders
//! without culling): triangles are turned to agree with the particle
//! normals when there are some, else made consistent across manifold
//! edges and each connected component turned outwards by its signed
//! volume.
//!
//! The triangulation builds triangles neighbourhood by neighbourhood with
//! no common winding, so without normals the winding is propagated over
//! the edge graph: two triangles that are the only ones on an edge must
//! traverse it opposite ways. A union-find with parity joins them into
//! components (each keeps the winding of its lowest triangle, whose
//! neighbours turn to match it, as a walk from it would), then each
//! component's signed volume decides whether it faces outwards: the same
//! windings as a depth-first walk over a table of neighbours, without the
//! table.
use lodkit_mesh::TriMesh;

/// Orients the triangles of `mesh` in place (what
/// [`TriangulateOptions::orient`](crate::TriangulateOptions::orient) does
/// after a triangulation): by the vertex normals when the mesh has them,
/// else consistently across manifold edges, each connected component
/// turned outwards by its signed volume. Deterministic; vertices are not
/// touched. Linear in the triangles apart from a sort of each vertex's
/// sides; meshes of more than 2^30 triangles are left as they are.
pub fn orient(mesh: &mut TriMesh) {
    if let Some(n) = &mesh.normals {
        for f in &mut mesh.faces {
            let [a, b, c] = f.map(|v| mesh.positions[v as usize]);
            let face_normal = (b - a).cross(c - a);
            let vn = n[f[0] as usize] + n[f[1] as usize] + n[f[2] as usize];
            if face_normal.dot(vn) < 0.0 {
                f.swap(1, 2);
            }
        }
        return;
    }
    let faces = &mut mesh.faces;
    let nf = faces.len();
    if nf > MAX_TRIANGLES {
        return;
    }
    // Windings as a union-find with parity: `link[t]` is `t`'s parent,
    // shifted left by one, and in the low bit whether `t` must turn
    // relative to it (one load for both). Each root is its component's
    // lowest triangle, which keeps its winding, as a walk from it would.
    let mut link: Vec<u32> = (0..nf as u32).map(|t| t << 1).collect();
    manifold_pairs(faces, mesh.positions.len(), |t1, t2, same_dir| {
        let (r1, p1) = find(&mut link, t1);
        let (r2, p2) = find(&mut link, t2);
        // Equal roots: the edge closes a cycle, consistent or not (a
        // non-orientable component keeps the first windings found).
        if r1 != r2 {
            let (lo, hi) = (r1.min(r2), r1.max(r2));
            link[hi as usize] = lo << 1 | (p1 ^ p2 ^ u32::from(same_dir));
        }
    });
    // Each component's signed volume with the windings made consistent
    // (untouched entries of `volume` cost no memory). A parent is never
    // above its child (roots are the lowest, halving links to a
    // grandparent), so in triangle order `t`'s parent already links to
    // the root: one step finds it (a root's link, its own, reads as its
    // root with no turn).
    let mut volume = vec![0f64; nf];
    for t in 0..nf {
        let l = link[t];
        let up = link[(l >> 1) as usize];
        let (r, p) = (up >> 1, (l ^ up) & 1);
        link[t] = r << 1 | p;
        let [a, b, c] = faces[t].map(|v| mesh.positions[v as usize].as_dvec3());
        let v = a.dot(b.cross(c));
        // `-v` when `p` is 1, by the sign bit: the branch it took was
        // mispredicted, the windings being in no pattern.
        volume[r as usize] += f64::from_bits(v.to_bits() ^ u64::from(p) << 63);
    }
    for (f, l) in faces.iter_mut().zip(link) {
        // Found above: the root and the parity to it.
        if (l & 1 == 1) != (volume[(l >> 1) as usize] < 0.0) {
            f.swap(1, 2);
        }
    }
}

/// The root of `t` and whether `t` turns relative to it (1) or not (0);
/// the triangles passed on the way are relinked to their grandparents
/// (path halving).
#[inline]
fn find(link: &mut [u32], t: u32) -> (u32, u32) {
    let (mut x, mut p) = (t as usize, 0);
    loop {
        let l = link[x];
        let up = (l >> 1) as usize;
        if up == x {
            return (x as u32, p);
        }
        // A root's turn bit is 0: `x` then keeps its parent.
        let above = link[up];
        let l = above & !1 | (l ^ above) & 1;
        link[x] = l;
        p ^= l & 1;
        x = (l >> 1) as usize;
    }
}

/// Most triangles [`orient`] turns (larger meshes, of 12 GB of faces and
/// more, are left as built): a side and a union-find link each pack a
/// triangle in 31 bits, and the sides of all triangles are counted in 32.
const MAX_TRIANGLES: usize = 1 << 30;

/// Calls `f(t1, t2, same_dir)`, `t1 < t2`, for the two triangles of every
/// edge that exactly two use, in the order of the edges' keys (lower
/// vertex, then upper); `same_dir` when both traverse it the same way
/// (their windings disagree). The sides are bucketed by lower vertex (a
/// counting pass, then a filling one), each packed in one word — upper
/// vertex, triangle, whether it runs from the lower vertex to the upper —
/// so that sorting a vertex's few sides orders them by upper vertex, then
/// triangle.
fn manifold_pairs(faces: &[[u32; 3]], vertices: usize, mut f: impl FnMut(u32, u32, bool)) {
    debug_assert!(faces.len() <= MAX_TRIANGLES);
    // No pass for the highest vertex: one at or beyond `vertices` panics
    // here as it would in [`orient`]'s volume pass.
    let n = vertices;
    // `end[v]`: one past vertex `v`'s last side; the filling pass, going
    // backwards, leaves it at the first (triangles then in order).
    let mut end = vec![0u32; n];
    for t in faces {
        for k in 0..3 {
            end[t[k].min(t[(k + 1) % 3]) as usize] += 1;
        }
    }
    let mut total = 0;
    for e in &mut end {
        total += *e;
        *e = total;
    }
    let mut sides = vec![0u64; total as usize];
    for (i, t) in faces.iter().enumerate().rev() {
        for k in (0..3).rev() {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            let slot = &mut end[a.min(b) as usize];
            *slot -= 1;
            sides[*slot as usize] = u64::from(a.max(b)) << 32 | (i as u64) << 1 | u64::from(a < b);
        }
    }
    let start = end;
    for v in 0..n {
        let to = start.get(v + 1).map_or(sides.len(), |&s| s as usize);
        let bucket = &mut sides[start[v] as usize..to];
        // Most vertices have at most 8 sides (6 on average), nearly all
        // at most 16: sorted by a network (twice, then merged), they cost
        // no mispredicted branch.
        let (small, merged);
        let bucket: &[u64] = if bucket.len() <= 8 {
            small = sort8(padded(bucket));
            &small[..bucket.len()]
        } else if let Some((low, high)) = bucket.split_first_chunk::<8>()
            && high.len() <= 8
        {
            merged = merge(sort8(*low), sort8(padded(high)));
            &merged[..bucket.len()]
        } else {
            insertion_sort(bucket);
            bucket
        };
        let mut i = 0;
        while i < bucket.len() {
            let upper = bucket[i] >> 32;
            let mut j = i + 1;
            while j < bucket.len() && bucket[j] >> 32 == upper {
                j += 1;
            }
            if j - i == 2 {
                let (s1, s2) = (bucket[i] as u32, bucket[i + 1] as u32);
                f(s1 >> 1, s2 >> 1, (s1 ^ s2) & 1 == 0);
            }
            i = j;
        }
    }
}

/// Up to 8 words, then the padding (`u64::MAX`, sorted last), copied in
/// eight fixed steps, unrolled: a copy of the slice's length
/// (`copy_from_slice`, a zip) would call `memcpy` per vertex.
#[inline]
fn padded(s: &[u64]) -> [u64; 8] {
    let mut p = [u64::MAX; 8];
    for (i, w) in p.iter_mut().enumerate() {
        if i < s.len() {
            *w = s[i];
        }
    }
    p
}

/// Sorts 8 words with Knuth's network of 19 compare-exchanges (depth 6),
/// each a min and a max without a branch: an insertion sort's inner loop
/// exit is mispredicted on the vertices of up to 8 sides.
#[inline]
fn sort8(v: [u64; 8]) -> [u64; 8] {
    let [
        mut a0,
        mut a1,
        mut a2,
        mut a3,
        mut a4,
        mut a5,
        mut a6,
        mut a7,
    ] = v;
    macro_rules! exchange {
        ($x:ident, $y:ident) => {
            ($x, $y) = ($x.min($y), $x.max($y));
        };
    }
    exchange!(a0, a2);
    exchange!(a1, a3);
    exchange!(a4, a6);
    exchange!(a5, a7);
    exchange!(a0, a4);
    exchange!(a1, a5);
    exchange!(a2, a6);
    exchange!(a3, a7);
    exchange!(a0, a1);
    exchange!(a2, a3);
    exchange!(a4, a5);
    exchange!(a6, a7);
    exchange!(a2, a4);
    exchange!(a3, a5);
    exchange!(a1, a4);
    exchange!(a3, a6);
    exchange!(a1, a2);
    exchange!(a3, a4);
    exchange!(a5, a6);
    [a0, a1, a2, a3, a4, a5, a6, a7]
}

/// Merges two sorted runs of 8 words, each step taking the lower head
/// without a branch (a run's end reads as the padding, `u64::MAX`), for
/// the vertices of 9 to 16 sides.
#[inline]
fn merge(a: [u64; 8], b: [u64; 8]) -> [u64; 16] {
    let pad = |r: [u64; 8]| {
        let mut p = [u64::MAX; 9];
        p[..8].copy_from_slice(&r);
        p
    };
    let (a, b) = (pad(a), pad(b));
    let (mut i, mut j) = (0, 0);
    let mut out = [0; 16];
    for w in &mut out {
        let (x, y) = (a[i], b[j]);
        let take_a = x <= y;
        *w = if take_a { x } else { y };
        // Both at their ends only for padding still to write.
        i = (i + usize::from(take_a)).min(8);
        j = (j + usize::from(!take_a)).min(8);
    }
    out
}

/// The vertices of more than 16 sides (rare): insertion sort beats the
/// general sort on so few.
#[inline]
fn insertion_sort(v: &mut [u64]) {
    for i in 1..v.len() {
        let x = v[i];
        let mut j = i;
        while j > 0 && v[j - 1] > x {
            v[j] = v[j - 1];
            j -= 1;
        }
        v[j] = x;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use lodkit_mesh::shapes::{blob, icosphere, torus};

    use super::*;

    /// Directed sides traversed the same way by two triangles (zero on a
    /// consistently wound manifold).
    fn same_way_sides(faces: &[[u32; 3]]) -> usize {
        let mut seen = std::collections::HashMap::new();
        for f in faces {
            for k in 0..3 {
                *seen.entry((f[k], f[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        seen.values().filter(|&&c| c > 1).count()
    }

    fn signed_volume(m: &TriMesh, faces: &[[u32; 3]]) -> f64 {
        faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| m.positions[v as usize].as_dvec3());
                a.dot(b.cross(c))
            })
            .sum()
    }

    /// Turns every triangle whose hash says so.
    fn scramble(m: &mut TriMesh) {
        for (i, f) in m.faces.iter_mut().enumerate() {
            if (i as u32).wrapping_mul(0x9e37_79b9) >> 31 == 1 {
                f.swap(1, 2);
            }
        }
    }

    #[test]
    fn scrambled_closed_surfaces_are_wound_consistently_and_outwards() {
        for mut m in [icosphere(4), torus(1.0, 0.3, 48, 24), blob(20_000)] {
            m.normals = None;
            let want = m.faces.clone();
            scramble(&mut m);
            assert!(same_way_sides(&m.faces) > 0);
            orient(&mut m);
            assert_eq!(same_way_sides(&m.faces), 0);
            assert!(signed_volume(&m, &m.faces) > 0.0);
            // The generators wind outwards: every triangle is back.
            assert_eq!(m.faces, want);
        }
    }

    #[test]
    fn each_component_is_turned_outwards_on_its_own() {
        // A sphere inside a sphere, the inner one listed first and
        // inside out: as separate components both end up facing out.
        let outer = icosphere(3);
        let mut m = icosphere(2);
        m.normals = None;
        for p in &mut m.positions {
            *p *= 0.5;
        }
        for f in &mut m.faces {
            f.swap(1, 2);
        }
        let inner = m.faces.len();
        let base = m.positions.len() as u32;
        m.positions.extend(&outer.positions);
        m.faces
            .extend(outer.faces.iter().map(|f| f.map(|v| v + base)));
        scramble(&mut m);
        orient(&mut m);
        assert_eq!(same_way_sides(&m.faces), 0);
        assert!(signed_volume(&m, &m.faces[..inner]) > 0.0);
        assert!(signed_volume(&m, &m.faces[inner..]) > 0.0);
    }

    #[test]
    fn normals_decide_when_there_are_some() {
        let mut m = icosphere(3);
        // Normals pointing inwards: every triangle faces them.
        m.normals = Some(m.positions.iter().map(|p| -p.normalize()).collect());
        scramble(&mut m);
        orient(&mut m);
        let n = m.normals.as_ref().unwrap();
        for f in &m.faces {
            let [a, b, c] = f.map(|v| m.positions[v as usize]);
            let vn: Vec3 = f.iter().map(|&v| n[v as usize]).sum();
            assert!((b - a).cross(c - a).dot(vn) > 0.0);
        }
    }

    #[test]
    fn the_networks_sort() {
        // Words of a linear congruential generator's top bits: repeats
        // included, as degenerate triangles would make.
        let mut x = 1u64;
        for n in 0..=16 {
            for _ in 0..100 {
                let v: Vec<u64> = (0..n)
                    .map(|_| {
                        x = x.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                        x >> 60
                    })
                    .collect();
                let mut want = v.clone();
                want.sort_unstable();
                let got = match v.split_first_chunk::<8>() {
                    Some((low, high)) => merge(sort8(*low), sort8(padded(high))).to_vec(),
                    None => sort8(padded(&v)).to_vec(),
                };
                assert_eq!(got[..n], want);
            }
        }
    }

    #[test]
    fn pairs_are_the_edges_two_triangles_share() {
        // Three triangles on edge 0–1 (none paired there), a fourth sharing
        // edge 1–2 with the first alone.
        let faces = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [2, 1, 5]];
        let mut got = Vec::new();
        manifold_pairs(&faces, 6, |a, b, same| got.push((a, b, same)));
        assert_eq!(got, vec![(0, 3, false)]);
        // Turned, the fourth runs along 1–2 as the first does.
        let faces = [[0, 1, 2], [1, 0, 3], [0, 1, 4], [1, 2, 5]];
        got.clear();
        manifold_pairs(&faces, 6, |a, b, same| got.push((a, b, same)));
        assert_eq!(got, vec![(0, 3, true)]);
    }
}
