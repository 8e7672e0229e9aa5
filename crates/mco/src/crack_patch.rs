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
//! vertices `P3` stick out. Each is moved to its compensation point `R`,
//! the foot of the perpendicular from `P3` to the coarse segment `P1P2`
//! (Fig. 5.6; clamped to the segment, and onto the nearest segment when
//! the face has two).
//!
//! Every compensation point is stored once in the shared vertex buffer
//! (keyed by the fine vertex and `q`), and node `n` gets a patch record
//! "while `q` is not expanded, draw these vertices as those": extraction
//! only swaps indices.
//!
//! **Normals (§5.4.4).** The thesis's formula is garbled in the text; what
//! survives is a sum of the normals of the moved fine triangles `A`, `B` and
//! twice the coarse triangle `C` that the compensation point lies on, over
//! 4. Reconstructed as `n(R) = normalize(mean(n̂_fine) + n̂_C)`: the fine
//! triangles around `R` (with `R` in place of `P3`) and the coarse triangle
//! weigh half each, which is the thesis's `(n_A + n_B + 2 n_C) / 4` when two
//! fine triangles meet at `R`. Without a coarse triangle (none holds both
//! segment ends) the fine mean is used.
//!
//! Not patchable this way: a face the coarse side crosses nowhere while the
//! fine side does, an ambiguous coarse face whose four crossings the fine
//! side joins the other way round (the armadillo has some), a closed fine
//! loop inside a face, and a coarse edge whose fine crossings are not its
//! own crossing. [`expand_together`] finds the nodes around such faces and
//! edges and the priority numbering expands them in one LOD step, so these
//! interfaces never appear in an extraction (fine vertices met there are
//! only counted, in `BuildStats::unpatched`).

use std::collections::HashMap;

use glam::Vec3;

use crate::marching_cubes::{corner_key, edge_key};
use crate::mc_table::{EDGES, FACES, Face, face_edges, face_segments};
use crate::model::{McoModel, Patch};
use crate::octree_build::Tree;
use crate::signed_distance::{pack, unpack};

fn closest_on_segment(p: Vec3, a: Vec3, b: Vec3) -> Vec3 {
    let ab = b - a;
    let len2 = ab.length_squared();
    if len2 <= 0.0 {
        return a;
    }
    a + ab * ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
}

fn unit_normal(p: [Vec3; 3]) -> Vec3 {
    (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero()
}

/// Vertex of cube edge `e` of the level-`l` node at `cube`.
fn edge_vertex(tree: &Tree, l: usize, cube: [u32; 3], e: u8) -> u32 {
    let [a, _] = EDGES[e as usize];
    tree.levels[l].edges[&edge_key(corner_key(cube, l as u32, a), e / 4)]
}

/// Segment `[e0, e1]` of face edges of the level-`l` cube `cube` as a
/// vertex pair, smaller index first.
fn segment_vertices(tree: &Tree, l: usize, cube: [u32; 3], s: [u8; 2]) -> [u32; 2] {
    let a = edge_vertex(tree, l, cube, s[0]);
    let b = edge_vertex(tree, l, cube, s[1]);
    [a.min(b), a.max(b)]
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
fn face_patchable(tree: &Tree, l: usize, pc: [u32; 3], mc: [u32; 3], f: Face) -> bool {
    let lv = &tree.levels[l];
    let below = &tree.levels[l - 1];
    let axis = f.axis as usize;
    let cfg = lv.configs[lv.index[&pack(pc[0], pc[1], pc[2])] as usize];
    let mut coarse: Vec<[u32; 2]> = face_segments(cfg, f)
        .into_iter()
        .map(|s| segment_vertices(tree, l, pc, s))
        .collect();
    coarse.sort_unstable();
    let mut fine: Vec<[u32; 2]> = Vec::new();
    for oct in 0..8u32 {
        let high = oct >> axis & 1 == 1;
        // Children of `pc` on its high face, children of `mc` on its low face.
        let (base, face) = if high {
            (pc, f)
        } else {
            (
                mc,
                Face {
                    axis: f.axis,
                    side: 0,
                },
            )
        };
        let c = [
            base[0] * 2 + (oct & 1),
            base[1] * 2 + (oct >> 1 & 1),
            base[2] * 2 + (oct >> 2 & 1),
        ];
        if let Some(&ci) = below.index.get(&pack(c[0], c[1], c[2])) {
            fine.extend(
                face_segments(below.configs[ci as usize], face)
                    .into_iter()
                    .map(|s| segment_vertices(tree, l - 1, c, s)),
            );
        }
    }
    fine.sort_unstable();
    fine.dedup();
    if fine.is_empty() || coarse.is_empty() {
        return fine.is_empty() && coarse.is_empty();
    }
    // Chain the fine segments; a vertex on more than two of them cannot be
    // told apart, so the face counts as unpatchable.
    let mut degree: HashMap<u32, u32> = HashMap::new();
    for s in &fine {
        for v in s {
            *degree.entry(*v).or_default() += 1;
        }
    }
    if degree.values().any(|&d| d > 2) {
        return false;
    }
    let mut ends: Vec<u32> = degree.iter().filter(|e| *e.1 == 1).map(|e| *e.0).collect();
    ends.sort_unstable();
    let mut used = vec![false; fine.len()];
    let mut pairs: Vec<[u32; 2]> = Vec::new();
    for &start in &ends {
        if fine
            .iter()
            .zip(&used)
            .all(|(s, &u)| u || !s.contains(&start))
        {
            continue; // reached as the far end of an earlier chain
        }
        let mut at = start;
        while let Some(k) = (0..fine.len()).find(|&k| !used[k] && fine[k].contains(&at)) {
            used[k] = true;
            at = if fine[k][0] == at {
                fine[k][1]
            } else {
                fine[k][0]
            };
        }
        pairs.push([start.min(at), start.max(at)]);
    }
    if used.iter().any(|&u| !u) {
        return false; // a closed loop
    }
    pairs.sort_unstable();
    pairs == coarse
}

/// Same-level node pairs whose shared face cannot be crack-patched (see
/// `face_patchable`), and the nodes around unpatchable edges: they must
/// expand in the same LOD step (see [`crate::priority`]). Call after
/// [`crate::octree_build::assemble`].
pub fn expand_together(tree: &Tree) -> Vec<(u32, u32)> {
    let mut out = Vec::new();
    for l in 1..tree.levels.len() {
        let lv = &tree.levels[l];
        let below = &tree.levels[l - 1];
        for (i, &k) in lv.keys.iter().enumerate() {
            let pc = unpack(k);
            for axis in 0..3u8 {
                let f = Face { axis, side: 1 };
                let mut mc = pc;
                mc[axis as usize] += 1;
                let Some(&j) = lv.index.get(&pack(mc[0], mc[1], mc[2])) else {
                    continue;
                };
                if !face_patchable(tree, l, pc, mc, f) {
                    out.push((tree.node_id[l][i], tree.node_id[l][j as usize]));
                }
            }
            // Edges whose fine crossings are not exactly the coarse one (two
            // fine crossings and none coarse, or a coarse fallback vertex):
            // every node around the edge expands together.
            for (e, [a, _]) in EDGES.iter().enumerate() {
                let axis = e / 4;
                let va = corner_key(pc, l as u32, *a);
                let coarse = lv.edges.get(&edge_key(va, axis as u8)).copied();
                let [x, y, z] = unpack(va);
                let mut vm = [x, y, z];
                vm[axis] += 1 << (l - 1);
                let fine: Vec<u32> = [va, pack(vm[0], vm[1], vm[2])]
                    .iter()
                    .filter_map(|&h| below.edges.get(&edge_key(h, axis as u8)).copied())
                    .collect();
                if fine.is_empty() || (fine.len() == 1 && Some(fine[0]) == coarse) {
                    continue;
                }
                let (u, w) = ((axis + 1) % 3, (axis + 2) % 3);
                let base = [x >> l, y >> l, z >> l];
                let mut around = Vec::new();
                for du in 0..2u32 {
                    for dw in 0..2u32 {
                        let mut c = base;
                        if c[u] < du || c[w] < dw {
                            continue;
                        }
                        c[u] -= du;
                        c[w] -= dw;
                        if let Some(&j) = lv.index.get(&pack(c[0], c[1], c[2])) {
                            around.push(tree.node_id[l][j as usize]);
                        }
                    }
                }
                for pair in around.windows(2) {
                    out.push((pair[0], pair[1]));
                }
            }
        }
    }
    out
}

/// Computes every node's crack patches and appends the compensation points
/// to the tree's vertex buffer. Call after [`crate::octree_build::assemble`].
pub fn patch(tree: &mut Tree, model: &mut McoModel) {
    let depth = tree.levels.len() - 1;
    let mut point_of: HashMap<(u32, u32), u32> = HashMap::new();
    // Per compensation point: (sum of fine unit normals, count, coarse normal).
    let mut normal_acc: Vec<(Vec3, u32, Vec3)> = Vec::new();
    let mut unpatched = 0u64;
    let mut patches: Vec<Vec<Patch>> = vec![Vec::new(); model.nodes.len()];
    let mut subs: Vec<[u32; 2]> = Vec::new();
    for l in 0..depth {
        for i in 0..tree.levels[l].keys.len() {
            let id = tree.node_id[l][i];
            let cube = unpack(tree.levels[l].keys[i]);
            let cfg = tree.levels[l].configs[i];
            if cfg == 0 || cfg == 255 {
                continue;
            }
            let pc = [cube[0] >> 1, cube[1] >> 1, cube[2] >> 1];
            for f in FACES {
                let a = f.axis as usize;
                if cube[a] & 1 != f.side as u32 {
                    continue; // the face is inside the parent
                }
                let mut qc = pc;
                if f.side == 1 {
                    qc[a] += 1;
                } else if qc[a] == 0 {
                    continue;
                } else {
                    qc[a] -= 1;
                }
                let Some(&qi) = tree.levels[l + 1].index.get(&pack(qc[0], qc[1], qc[2])) else {
                    continue;
                };
                let q = tree.node_id[l + 1][qi as usize];
                let qcfg = tree.levels[l + 1].configs[qi as usize];
                let opposite = Face {
                    axis: f.axis,
                    side: 1 - f.side,
                };
                let segs: Vec<[u32; 2]> = face_segments(qcfg, opposite)
                    .into_iter()
                    .map(|[e0, e1]| {
                        [
                            edge_vertex(tree, l + 1, qc, e0),
                            edge_vertex(tree, l + 1, qc, e1),
                        ]
                    })
                    .collect();
                let mut fine: Vec<u32> = face_edges(f)
                    .iter()
                    .filter(|&&e| {
                        let [x, y] = EDGES[e as usize];
                        (cfg >> x & 1) != (cfg >> y & 1)
                    })
                    .map(|&e| edge_vertex(tree, l, cube, e))
                    .filter(|v| !segs.iter().any(|s| s.contains(v)))
                    .collect();
                fine.sort_unstable();
                fine.dedup();
                if fine.is_empty() {
                    continue;
                }
                if segs.is_empty() {
                    unpatched += fine.len() as u64;
                    continue;
                }
                let start = subs.len();
                for x in fine {
                    let px = tree.vertices.positions[x as usize];
                    let (seg, r) = segs
                        .iter()
                        .map(|s| {
                            let (a, b) = (
                                tree.vertices.positions[s[0] as usize],
                                tree.vertices.positions[s[1] as usize],
                            );
                            (*s, closest_on_segment(px, a, b))
                        })
                        .min_by(|a, b| {
                            a.1.distance_squared(px)
                                .total_cmp(&b.1.distance_squared(px))
                        })
                        .expect("segments is not empty");
                    let new = *point_of.entry((x, q)).or_insert_with(|| {
                        let n = tree.vertices.normals[x as usize];
                        let c = tree.vertices.colors[x as usize];
                        let coarse = model
                            .node_tris(q)
                            .chunks_exact(3)
                            .find(|t| t.contains(&seg[0]) && t.contains(&seg[1]))
                            .map(|t| {
                                unit_normal(
                                    [0, 1, 2].map(|k| tree.vertices.positions[t[k] as usize]),
                                )
                            })
                            .unwrap_or(Vec3::ZERO);
                        normal_acc.push((Vec3::ZERO, 0, coarse));
                        tree.vertices.push(r, n, c)
                    });
                    // Fine triangles of this node around the moved vertex.
                    let slot = new as usize - (tree.vertices.len() - normal_acc.len());
                    for t in model.node_tris(id).chunks_exact(3) {
                        if t.contains(&x) {
                            let pts = [0, 1, 2].map(|k| {
                                if t[k] == x {
                                    r
                                } else {
                                    tree.vertices.positions[t[k] as usize]
                                }
                            });
                            let un = unit_normal(pts);
                            if un != Vec3::ZERO {
                                normal_acc[slot].0 += un;
                                normal_acc[slot].1 += 1;
                            }
                        }
                    }
                    subs.push([x, new]);
                }
                patches[id as usize].push(Patch {
                    coarse: q,
                    subs_start: start as u32,
                    subs_count: (subs.len() - start) as u32,
                });
            }
        }
    }
    // §5.4.4: recompute the compensation points' normals.
    let base = tree.vertices.len() - normal_acc.len();
    for (k, (sum, count, coarse)) in normal_acc.iter().enumerate() {
        let fine = if *count > 0 {
            (*sum / *count as f32).normalize_or_zero()
        } else {
            Vec3::ZERO
        };
        let n = (fine + *coarse).normalize_or_zero();
        if n != Vec3::ZERO {
            tree.vertices.normals[base + k] = n;
        }
    }
    model.subs = subs;
    for (id, list) in patches.into_iter().enumerate() {
        model.nodes[id].patch_start = model.patches.len() as u32;
        model.nodes[id].patch_count = list.len() as u8;
        model.patches.extend(list);
    }
    model.stats.unpatched = unpatched;
}
