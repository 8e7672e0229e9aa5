//! Crack patching at level-1 interfaces, precomputed (thesis §5.3,
//! Fig. 5.6, §5.4.4).
//!
//! The balance constraint leaves only one kind of interface: a drawn node
//! `n` at level `L` whose face lies on its parent's face, across which the
//! coarse neighbour `q` (level `L + 1`) is drawn instead of its children.
//! On the shared plane the coarse side draws straight segments between
//! crossings of `q`'s face edges; the fine side draws a polyline through
//! extra crossings on the inner half-edges. Because parent edges reference
//! the vertex of the child half-edge ([`crate::octree_build`]), the polyline
//! and the segment already share their end points; only the extra fine
//! vertices `P3` stick out. The thesis moves each to its compensation
//! point `R`, the foot of the perpendicular from `P3` to the coarse segment
//! `P1P2` (Fig. 5.6). That closes the gap in space but leaves a T-junction:
//! the coarse side draws the edge `P1P2`, the fine side `P1R` and `RP2`, so
//! no edge is shared, a rasteriser leaves pinholes along the seam, and the
//! cut has boundary edges the full-resolution surface lacks. Here `P3` is
//! moved to the end of `P1P2` nearer its foot `R` instead: the fine
//! polyline collapses onto the coarse segment itself (the fine triangle on
//! the collapsed edge gets two equal indices and no area; the others keep
//! their orientation), both sides draw the same edge `P1P2`, and the cut is
//! watertight in its indices. The move is at most half a fine cube's edge,
//! well inside the coarse side's own error. When the face has two coarse
//! segments, `P3` goes onto the one joining the ends of its own fine
//! polyline, not the nearer one: the fine polylines across the parent's
//! face are chained, and each polyline's ends are one coarse segment's
//! ends (what `face_patchable` checks). On a curved surface the other
//! segment can be nearer, and a point moved there leaves the gap between
//! its polyline and its segment open.
//!
//! No vertex is added: node `n` gets a patch record "while `q` is not
//! expanded, draw these vertices as those", and extraction only swaps
//! indices. Triangles that a patch makes degenerate stay in the index
//! buffers (a cut keeps its precomputed triangle count; a GPU draws
//! nothing for them) and [`McoModel::mesh_from_indices`] leaves them out.
//!
//! Not patchable this way: a face the coarse side crosses nowhere while the
//! fine side does, an ambiguous coarse face whose four crossings the fine
//! side joins the other way round (the armadillo has some), a closed fine
//! loop inside a face, and a coarse edge whose fine crossings are not its
//! own crossing. [`expand_together`] finds the nodes around such faces and
//! edges and the priority numbering expands them in one LOD step, so these
//! interfaces never appear in an extraction (fine vertices met there are
//! only counted, in `BuildStats::unpatched`).

use glam::Vec3;

use crate::lattice::{KEY_BITS, pack, unpack};
use crate::marching_cubes::{CubeEdges, NO_VERTEX, corner_key, edge_key};
use crate::marching_cubes_cases::{EDGES, FACES, Face, face_edges, face_segments_fixed};
use crate::model::{McoModel, Patch};
use crate::neighbours::{FaceNeighbours, NO_NODE};
use crate::octree_build::{Level, Tree};

fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= 0.0 {
        return a;
    }
    a + ab * ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
}

/// Whether the face `f` shared by the level-`l` nodes at `pc` and `mc`
/// (`mc` on `f`'s side of `pc`) can be crack-patched when one side is drawn
/// one level finer than the other: the fine polylines on the face (from the
/// level below, both sides' children) must join exactly the crossing pairs
/// the coarse face's segments join, with no closed loop. Then every extra
/// fine vertex lies on a polyline whose ends are its coarse segment's ends,
/// and moving it onto that segment closes the gap (Fig. 5.6).
///
/// Three things break this: a face the coarse level crosses nowhere while
/// the finer one does; a closed fine loop inside the face; and an
/// *ambiguous* coarse face (two opposite corners inside) that the face rule
/// cuts one way while the finer level, knowing the face's centre, joins the
/// same four crossings the other way. In the last case the fine polyline
/// runs across the coarse face from one coarse segment to the other: no
/// choice of compensation points can close that gap.
fn face_patchable(tree: &Tree, l: usize, i: usize, mc: usize, f: Face) -> bool {
    let lv = &tree.levels[l];
    let below = &tree.levels[l - 1];
    let axis = f.axis as usize;
    // At most 2 coarse segments, and 8 children with at most 2 each.
    let mut coarse = [[0u32; 2]; 2];
    let mut nc = 0;
    for s in face_segments_fixed(lv.configs[i], f) {
        coarse[nc] = ordered(&lv.node_edges[i], *s);
        nc += 1;
    }
    coarse[..nc].sort_unstable();
    // Children of `pc` on its high face, children of `mc` on its low face
    // (the order does not matter: the segments are sorted below).
    let mut fine = [[0u32; 2]; 16];
    let mut nf = 0;
    for (node, face) in [
        (i, f),
        (
            mc,
            Face {
                axis: f.axis,
                side: 0,
            },
        ),
    ] {
        for &ci in tree.kids(l, node) {
            let ci = ci as usize;
            if below.keys[ci] >> (axis as u32 * KEY_BITS) & 1 != face.side as u64 {
                continue;
            }
            for s in face_segments_fixed(below.configs[ci], face) {
                fine[nf] = ordered(&below.node_edges[ci], *s);
                nf += 1;
            }
        }
    }
    let fine = &mut fine[..nf];
    fine.sort_unstable();
    let nf = dedup_sorted(fine);
    let fine = &fine[..nf];
    let coarse = &coarse[..nc];
    if fine.is_empty() || coarse.is_empty() {
        return fine.is_empty() && coarse.is_empty();
    }
    // Chain the fine segments; a vertex on more than two of them cannot be
    // told apart, so the face counts as unpatchable.
    let mut ends_all = [0u32; 32];
    for (k, s) in fine.iter().enumerate() {
        ends_all[2 * k] = s[0];
        ends_all[2 * k + 1] = s[1];
    }
    let ends_all = &mut ends_all[..2 * nf];
    ends_all.sort_unstable();
    // Vertices on exactly one segment, increasing.
    let mut ends = [0u32; 32];
    let mut ne = 0;
    let mut k = 0;
    while k < ends_all.len() {
        let mut run = 1;
        while k + run < ends_all.len() && ends_all[k + run] == ends_all[k] {
            run += 1;
        }
        if run > 2 {
            return false;
        }
        if run == 1 {
            ends[ne] = ends_all[k];
            ne += 1;
        }
        k += run;
    }
    let mut used = [false; 16];
    let used = &mut used[..nf];
    let mut pairs = [[0u32; 2]; 16];
    let mut np = 0;
    for &start in &ends[..ne] {
        if fine
            .iter()
            .zip(used.iter())
            .all(|(s, &u)| u || !s.contains(&start))
        {
            continue; // reached as the far end of an earlier chain
        }
        let mut at = start;
        while let Some(k) = (0..nf).find(|&k| !used[k] && fine[k].contains(&at)) {
            used[k] = true;
            at = if fine[k][0] == at {
                fine[k][1]
            } else {
                fine[k][0]
            };
        }
        pairs[np] = [start.min(at), start.max(at)];
        np += 1;
    }
    if used.iter().any(|&u| !u) {
        return false; // a closed loop
    }
    let pairs = &mut pairs[..np];
    pairs.sort_unstable();
    pairs == coarse
}

/// Segment `[e0, e1]` of a node's face edges as a vertex pair, smaller
/// index first.
#[inline]
fn ordered(edges: &CubeEdges, s: [u8; 2]) -> [u32; 2] {
    let (a, b) = (edges[s[0] as usize], edges[s[1] as usize]);
    [a.min(b), a.max(b)]
}

/// Removes adjacent duplicates of a sorted slice in place; returns the
/// length kept.
fn dedup_sorted<T: PartialEq + Copy>(v: &mut [T]) -> usize {
    if v.is_empty() {
        return 0;
    }
    let mut w = 1;
    for r in 1..v.len() {
        if v[r] != v[w - 1] {
            v[w] = v[r];
            w += 1;
        }
    }
    w
}

/// The fine segments on face `f` of a node whose children are `kids`
/// (indices into the level below, `below`): those of the children whose
/// face `f` lies on the node's, as vertex pairs, smaller index first. At
/// most 4 children, 2 segments each.
fn fine_face_segments(below: &Level, kids: &[u32], f: Face, out: &mut [[u32; 2]; 8]) -> usize {
    let axis = f.axis as u32;
    let mut n = 0;
    for &ci in kids {
        let ci = ci as usize;
        if below.keys[ci] >> (axis * KEY_BITS) & 1 != f.side as u64 {
            continue;
        }
        for s in face_segments_fixed(below.configs[ci], f) {
            out[n] = ordered(&below.node_edges[ci], *s);
            n += 1;
        }
    }
    n
}

/// The two ends of the fine polyline through vertex `x` among the
/// segments `fine`, smaller first; `None` when `x` is on no segment, on a
/// closed loop, or where the polyline branches (a vertex on more than two
/// segments).
fn chain_ends(fine: &[[u32; 2]], x: u32) -> Option<[u32; 2]> {
    let mut used = [false; 8];
    let mut ends = [x; 2];
    let mut side = 0;
    for start in 0..fine.len() {
        if !fine[start].contains(&x) {
            continue;
        }
        if side == 2 {
            return None; // `x` on three segments
        }
        // Walk away from `x` through `start`.
        used[start] = true;
        let mut at = if fine[start][0] == x {
            fine[start][1]
        } else {
            fine[start][0]
        };
        loop {
            if at == x {
                return None; // a closed loop
            }
            let mut next = None;
            for k in 0..fine.len() {
                if !used[k] && fine[k].contains(&at) {
                    if next.is_some() {
                        return None; // a branch
                    }
                    next = Some(k);
                }
            }
            let Some(k) = next else { break };
            used[k] = true;
            at = if fine[k][0] == at {
                fine[k][1]
            } else {
                fine[k][0]
            };
        }
        ends[side] = at;
        side += 1;
    }
    (side > 0).then(|| [ends[0].min(ends[1]), ends[0].max(ends[1])])
}

/// The level-`lv` node at offset `ou` along axis `u` and `ow` along axis
/// `w` (each in `-1..=1`) from node `i` at `pc`, through the face
/// neighbour table `nbr`, and a binary search for a diagonal neighbour
/// whose two paths through face neighbours both cross empty cells.
#[inline]
fn near(
    lv: &Level,
    nbr: &[FaceNeighbours],
    i: usize,
    pc: [u32; 3],
    (u, ou): (usize, i32),
    (w, ow): (usize, i32),
) -> Option<u32> {
    let step = |n: u32, axis: usize, o: i32| -> u32 {
        match o {
            0 => n,
            _ if n == NO_NODE => NO_NODE,
            _ => nbr[n as usize][2 * axis + (o > 0) as usize],
        }
    };
    let i = i as u32;
    let via_u = step(step(i, u, ou), w, ow);
    if via_u != NO_NODE {
        return Some(via_u);
    }
    if ou == 0 || ow == 0 {
        return None;
    }
    let via_w = step(step(i, w, ow), u, ou);
    if via_w != NO_NODE {
        return Some(via_w);
    }
    let mut c = pc;
    for (axis, o) in [(u, ou), (w, ow)] {
        c[axis] = c[axis].checked_add_signed(o)?;
    }
    crate::neighbours::find(&lv.keys, c)
}

/// Whether the leaf lattice edge from `v` along `axis` joins two defined
/// band vertices on opposite sides (a leaf vertex can sit only on such an
/// edge).
#[inline]
fn leaf_edge_crosses(tree: &Tree, v: u64, axis: usize) -> bool {
    let mut far = unpack(v);
    far[axis] += 1;
    match (
        tree.signs.corner(tree.field, v),
        tree.signs.corner(tree.field, pack(far[0], far[1], far[2])),
    ) {
        (Some(a), Some(b)) => a.inside != b.inside,
        _ => false,
    }
}

/// Same-level node pairs whose shared face cannot be crack-patched (see
/// `face_patchable`), and the nodes around unpatchable edges: they must
/// expand in the same LOD step (see [`crate::priority_numbering`]). Call after
/// [`crate::octree_build::assemble`].
pub fn expand_together(tree: &Tree) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for l in 1..tree.levels.len() {
        let lv = &tree.levels[l];
        let below = &tree.levels[l - 1];
        let nbr = &tree.face_neighbours[l];
        for (i, &k) in lv.keys.iter().enumerate() {
            let pc = unpack(k);
            for axis in 0..3u8 {
                let f = Face { axis, side: 1 };
                let j = nbr[i][2 * axis as usize + 1];
                if j == NO_NODE {
                    continue;
                }
                if !face_patchable(tree, l, i, j as usize, f) {
                    out.push((tree.node_id[l][i], tree.node_id[l][j as usize]));
                }
            }
            // Edges whose fine crossings are not exactly the coarse one (two
            // fine crossings and none coarse, or a coarse fallback vertex):
            // every node around the edge expands together.
            const NONE: u32 = u32::MAX;
            let mut by_octant = [NONE; 8];
            for &ci in tree.kids(l, i) {
                let [x, y, z] = unpack(below.keys[ci as usize]);
                by_octant[(x & 1 | (y & 1) << 1 | (z & 1) << 2) as usize] = ci;
            }
            for (e, [a, b]) in EDGES.iter().enumerate() {
                let axis = e / 4;
                let va = corner_key(pc, l as u32, *a);
                // The level's crossings agree between the nodes around an
                // edge, so this node's own edge vertex is the map's.
                let coarse = Some(lv.node_edges[i][e]).filter(|&v| v != NO_VERTEX);
                let [x, y, z] = unpack(va);
                let mut vm = [x, y, z];
                vm[axis] += 1 << (l - 1);
                // The halves are edge `e` of the children in octants `a`
                // and `b`; a child that exists knows its crossing (the same
                // as the level's map), otherwise look the half up.
                let mut fine = [0u32; 2];
                let mut nf = 0;
                for (h, oct) in [(va, *a), (pack(vm[0], vm[1], vm[2]), *b)] {
                    let v = match by_octant[oct as usize] {
                        // A leaf edge has a vertex only if its ends are in
                        // the band on opposite sides: checked in the band's
                        // bit masks first, which saves most lookups in the
                        // large leaf edge map.
                        NONE if l == 1 && !leaf_edge_crosses(tree, h, axis) => None,
                        NONE => below.edges.get(&edge_key(h, axis as u8)).copied(),
                        ci => Some(below.node_edges[ci as usize][e]).filter(|&v| v != NO_VERTEX),
                    };
                    if let Some(v) = v {
                        fine[nf] = v;
                        nf += 1;
                    }
                }
                if nf == 0 || (nf == 1 && Some(fine[0]) == coarse) {
                    continue;
                }
                let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                // The 4 cubes around the edge are this node and its
                // neighbours at offsets `(a_u − du, a_w − dw)` along `u`
                // and `w` (`a_u`, `a_w`: corner `a`'s offsets).
                let (au, aw) = ((*a >> u & 1) as i32, (*a >> w & 1) as i32);
                let mut around = [0u32; 4];
                let mut na = 0;
                for du in 0..2i32 {
                    for dw in 0..2i32 {
                        if let Some(j) = near(lv, nbr, i, pc, (u, au - du), (w, aw - dw)) {
                            around[na] = tree.node_id[l][j as usize];
                            na += 1;
                        }
                    }
                }
                for pair in around[..na].windows(2) {
                    out.push((pair[0], pair[1]));
                }
            }
        }
    }
    out
}

/// Computes every node's crack patches (vertex substitutions into the
/// tree's vertex buffer, which stays as it is). Call after
/// [`crate::octree_build::assemble`].
pub fn patch(tree: &Tree, model: &mut McoModel) {
    let depth = tree.levels.len() - 1;
    let levels = &tree.levels;
    let node_id = &tree.node_id;
    let vertices = &tree.vertices;
    let mut unpatched = 0u64;
    // Each node is visited once and its patches pushed together: per node,
    // the start and count of its run in `found`.
    let mut runs: Vec<(u32, u8)> = vec![(0, 0); model.nodes.len()];
    let mut found: Vec<Patch> = Vec::new();
    let mut subs: Vec<[u32; 2]> = Vec::new();
    for l in 0..depth {
        let (lv, up) = (&levels[l], &levels[l + 1]);
        let (parent, up_nbr) = (&tree.parent[l], &tree.face_neighbours[l + 1]);
        for i in 0..lv.keys.len() {
            let cfg = lv.configs[i];
            if cfg == 0 || cfg == 255 {
                continue;
            }
            let id = node_id[l][i];
            let cube = unpack(lv.keys[i]);
            let ne = &lv.node_edges[i];
            let run_start = found.len();
            for f in FACES {
                let a = f.axis as usize;
                if cube[a] & 1 != f.side as u32 {
                    continue; // the face is inside the parent
                }
                if face_segments_fixed(cfg, f).is_empty() {
                    continue; // no crossing on the face: nothing to move
                }
                // The coarse neighbour: across the parent's face.
                let qi = up_nbr[parent[i] as usize][2 * a + f.side as usize];
                if qi == NO_NODE {
                    continue;
                }
                let qi = qi as usize;
                let q = node_id[l + 1][qi];
                let opposite = Face {
                    axis: f.axis,
                    side: 1 - f.side,
                };
                let qne = &up.node_edges[qi];
                let mut seg_buf = [[0u32; 2]; 2];
                let mut ns = 0;
                for &[e0, e1] in face_segments_fixed(up.configs[qi], opposite) {
                    seg_buf[ns] = [qne[e0 as usize], qne[e1 as usize]];
                    ns += 1;
                }
                let segs = &seg_buf[..ns];
                let mut fine_buf = [0u32; 4];
                let mut nf = 0;
                for &e in face_edges(f).iter() {
                    let [x, y] = EDGES[e as usize];
                    if (cfg >> x & 1) == (cfg >> y & 1) {
                        continue;
                    }
                    let v = ne[e as usize];
                    if !segs.iter().any(|s| s.contains(&v)) {
                        fine_buf[nf] = v;
                        nf += 1;
                    }
                }
                let fine = &mut fine_buf[..nf];
                fine.sort_unstable();
                let nf = dedup_sorted(fine);
                if nf == 0 {
                    continue;
                }
                if segs.is_empty() {
                    unpatched += nf as u64;
                    continue;
                }
                // The fine polylines on the parent's face: each extra
                // vertex goes onto the coarse segment joining its
                // polyline's ends (see the module docs); the nearest
                // segment only where the face is not patchable (its nodes
                // expand together, so that patch is never drawn).
                let mut on_face = [[0u32; 2]; 8];
                let (start_of, list) = &tree.children[l + 1];
                let p = parent[i] as usize;
                let kids = &list[start_of[p] as usize..start_of[p + 1] as usize];
                let n_on_face = fine_face_segments(lv, kids, f, &mut on_face);
                let on_face = &on_face[..n_on_face];
                let start = subs.len();
                for &x in &fine_buf[..nf] {
                    let px = vertices.positions[x as usize];
                    let own = chain_ends(on_face, x)
                        .and_then(|e| segs.iter().find(|s| [s[0].min(s[1]), s[0].max(s[1])] == e));
                    let (_, end) = segs
                        .iter()
                        .filter(|s| own.is_none_or(|o| o == *s))
                        .map(|s| {
                            let (a, b) = (
                                vertices.positions[s[0] as usize],
                                vertices.positions[s[1] as usize],
                            );
                            let r = closest_on_segment(px, a, b);
                            // The end of the segment nearer the foot `r`.
                            let end = if r.distance_squared(a) <= r.distance_squared(b) {
                                s[0]
                            } else {
                                s[1]
                            };
                            (r.distance_squared(px), end)
                        })
                        .min_by(|a, b| a.0.total_cmp(&b.0))
                        .expect("segments is not empty");
                    subs.push([x, end]);
                }
                found.push(Patch {
                    coarse: q,
                    subs_start: start as u32,
                    subs_count: (subs.len() - start) as u32,
                });
            }
            runs[id as usize] = (run_start as u32, (found.len() - run_start) as u8);
        }
    }
    model.subs = subs;
    model.patches.reserve(found.len());
    for (id, &(start, count)) in runs.iter().enumerate() {
        model.nodes[id].patch_start = model.patches.len() as u32;
        model.nodes[id].patch_count = count;
        model
            .patches
            .extend_from_slice(&found[start as usize..][..count as usize]);
    }
    model.stats.unpatched = unpatched;
}
