//! Direct triangulation of an octree surface — §6.1, §6.2 and §6.3 of
//! Yemez & Schmitt.
//!
//! **Surface scanning (§6.1.1).** Around every parent cube of level `r − 1`
//! that has an ON child, the 3×3×3 window of parents is fetched (27
//! look-ups) and their children laid out in a local 6×6×6 array; the 2×2×2
//! neighbourhoods whose origin lies in the window's centre (plus the
//! back-neighbours of Fig. 6) are triangulated from it, and the same array
//! supplies the overlapping neighbourhoods the disambiguation needs.
//! Each neighbourhood is visited exactly once: it belongs to the parent of
//! the first of its eight cubes (in child-code order) whose parent has an
//! ON child — the paper's back-neighbour rule, made unique.
//!
//! **Construction rules (§6.1.3).** `C_1–C_3` give their triangle.
//! `C_4, C_5` pick the diagonal with the smaller dihedral angle, or, when
//! the particles carry normals, the one whose triangles agree best with
//! them. A planar configuration lying on a face of its neighbourhood has
//! one owner: the neighbourhood that sees it on its lower face, unless the
//! neighbourhood across that face is a solid (`C_6+`) configuration, whose
//! disc then covers the face alone. (The paper leaves this implicit;
//! without it every flat patch would be emitted twice, and a patch shared
//! with an ambiguous neighbourhood covered twice — on the bunny this rule
//! took the triangles on over-used edges from 17 % to 0.9 %.) Identical
//! triangles two solids both build on a shared face are kept once.
//!
//! **Disambiguation (§6.2).** For `C_i, i ≥ 6`, the edges of `G_i` that
//! also belong to the graph of an overlapping neighbourhood are collected;
//! if they form one Hamiltonian cycle through every ON cube, the cycle cuts
//! the hull into two discs and the one with the smaller mean dihedral angle
//! is emitted. Otherwise all of `T_i` is emitted: hole-free, non-manifold.
//!
//! **Decimation (§6.3, optional).** A triangle with an edge shorter than a
//! fraction of the cube size is not built and its two cubes are merged
//! (positions and colours averaged). Departure: a cube merges at most once
//! per level, so merges pair cubes instead of chaining across the surface;
//! a short edge whose cubes are already taken is kept.
//!
//! **Orientation** (not in the paper, which renders without culling):
//! triangles are turned to agree with the particle normals when there are
//! some, else made consistent across manifold edges and each component
//! turned outwards by its signed volume.
use std::time::Instant;

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::topology::UnionFind;

use crate::decode::LevelSurface;
use crate::octree::{MortonMap, morton, unmorton};
use crate::triangulation_table::{CLASS_COUNT, Shape, corner, pair, table};

/// Options of [`triangulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangulateOptions {
    /// §6.3: skip triangles with an edge shorter than this fraction of the
    /// level's cube size and merge the two cubes. `None`: no decimation.
    pub decimate: Option<f32>,
    /// Orient the triangles (see the module docs).
    pub orient: bool,
}

impl TriangulateOptions {
    /// No decimation, oriented.
    pub const DEFAULT: TriangulateOptions = TriangulateOptions {
        decimate: None,
        orient: true,
    };
}

impl Default for TriangulateOptions {
    fn default() -> Self {
        TriangulateOptions::DEFAULT
    }
}

/// Table 1's triangulation columns for one level.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct TriangulationStats {
    pub triangles: usize,
    /// Neighbourhoods of each class `C_1..C_17` (index 0 unused).
    pub configurations: Vec<u64>,
    /// Ambiguous neighbourhoods resolved by a unique Hamiltonian cycle.
    pub disambiguated: u64,
    /// Ambiguous neighbourhoods triangulated whole (the non-manifold local
    /// triangulations of Table 1).
    pub fallbacks: u64,
    pub seconds: f64,
}

impl TriangulationStats {
    /// Percentages of `C_1–3`, `C_4–5`, `C_6`, `C_>6` (Table 1).
    pub fn distribution(&self) -> [f64; 4] {
        let total: u64 = self.configurations.iter().sum();
        let t = total.max(1) as f64;
        let sum =
            |a: usize, b: usize| self.configurations[a..=b].iter().sum::<u64>() as f64 * 100.0 / t;
        [sum(1, 3), sum(4, 5), sum(6, 6), sum(7, CLASS_COUNT)]
    }
}

/// A triangulated level.
#[derive(Debug, Clone)]
pub struct Triangulation {
    pub mesh: TriMesh,
    pub stats: TriangulationStats,
}

const NONE: u32 = u32::MAX;

struct Window {
    /// Vertex index of the child at local (x, y, z) ∈ [0, 6)³, or NONE.
    cell: [u32; 216],
    /// Whether each of the 27 parents has an ON child.
    parent: [bool; 27],
}

impl Window {
    #[inline]
    fn at(&self, x: usize, y: usize, z: usize) -> u32 {
        self.cell[x + 6 * y + 36 * z]
    }
    fn mask(&self, o: [usize; 3]) -> u8 {
        let mut m = 0u8;
        for j in 0..8u8 {
            let c = corner(j);
            if self.at(
                o[0] + c[0] as usize,
                o[1] + c[1] as usize,
                o[2] + c[2] as usize,
            ) != NONE
            {
                m |= 1 << j;
            }
        }
        m
    }
}

/// Triangulates one decoded level.
pub fn triangulate(s: &LevelSurface, opts: &TriangulateOptions) -> Triangulation {
    let start = Instant::now();
    let mut stats = TriangulationStats {
        configurations: vec![0; CLASS_COUNT + 1],
        ..Default::default()
    };
    let mut faces: Vec<[u32; 3]> = Vec::with_capacity(s.cells.len() * 2);
    let mut merges: Vec<(u32, u32)> = Vec::new();
    // Triangles built by solid configurations: the only ones two
    // neighbourhoods can both build (planar faces have one owner).
    let mut from_solids: Vec<u32> = Vec::new();
    // Cubes already merged (§6.3 merges pairs of nodes; chains of merges
    // would drift by more than a cube).
    let mut merged = vec![
        false;
        if opts.decimate.is_some() {
            s.cells.len()
        } else {
            0
        }
    ];
    let cube = s.frame.cube(s.level);
    let min_edge = opts.decimate.map(|f| f * cube);
    if s.level >= 1 {
        // Parents with their child masks and first child index.
        let mut parents: Vec<(u64, u8, u32)> = Vec::new();
        for (i, &c) in s.cells.iter().enumerate() {
            let p = c >> 3;
            match parents.last_mut() {
                Some(last) if last.0 == p => last.1 |= 1 << (c & 7),
                _ => parents.push((p, 1 << (c & 7), i as u32)),
            }
        }
        // Parents grouped by their own parent (a 2×2×2 block of parents):
        // the 3×3×3 window spans at most 2×2×2 such blocks, so 8 look-ups
        // fetch its 27 parents instead of 27.
        let mut index: MortonMap<[u32; 8]> = MortonMap::default();
        index.reserve(parents.len() / 2);
        for (i, p) in parents.iter().enumerate() {
            index.entry(p.0 >> 3).or_insert([NONE; 8])[(p.0 & 7) as usize] = i as u32;
        }
        let mut blocks: [Option<[u32; 8]>; 8] = [None; 8];
        let side = 1i64 << (s.level - 1);
        let t = table();
        let mut w = Window {
            cell: [NONE; 216],
            parent: [false; 27],
        };
        for &(pm, _, _) in &parents {
            let pc = unmorton(pm);
            w.cell = [NONE; 216];
            w.parent = [false; 27];
            // Block coordinates of the window's lowest parent (may be -1).
            let base = pc.map(|v| (v as i64 - 1).div_euclid(2));
            for (b, slot) in blocks.iter_mut().enumerate() {
                let g = [
                    base[0] + (b & 1) as i64,
                    base[1] + ((b >> 1) & 1) as i64,
                    base[2] + (b >> 2) as i64,
                ];
                *slot = if g.iter().all(|&v| v >= 0 && v < (side + 1) / 2) {
                    index
                        .get(&morton([g[0] as u32, g[1] as u32, g[2] as u32]))
                        .copied()
                } else {
                    None
                };
            }
            for dz in 0..3usize {
                for dy in 0..3usize {
                    for dx in 0..3usize {
                        let q = [
                            pc[0] as i64 + dx as i64 - 1,
                            pc[1] as i64 + dy as i64 - 1,
                            pc[2] as i64 + dz as i64 - 1,
                        ];
                        if q.iter().any(|&v| v < 0 || v >= side) {
                            continue;
                        }
                        let b = (q[0].div_euclid(2) - base[0])
                            | ((q[1].div_euclid(2) - base[1]) << 1)
                            | ((q[2].div_euclid(2) - base[2]) << 2);
                        let Some(block) = blocks[b as usize] else {
                            continue;
                        };
                        let pi =
                            block[((q[0] & 1) | ((q[1] & 1) << 1) | ((q[2] & 1) << 2)) as usize];
                        if pi == NONE {
                            continue;
                        }
                        let (_, mask, first) = parents[pi as usize];
                        w.parent[dx + 3 * dy + 9 * dz] = true;
                        let mut next = first;
                        for k in 0..8u8 {
                            if mask & (1 << k) != 0 {
                                let c = corner(k);
                                let (x, y, z) = (
                                    2 * dx + c[0] as usize,
                                    2 * dy + c[1] as usize,
                                    2 * dz + c[2] as usize,
                                );
                                w.cell[x + 6 * y + 36 * z] = next;
                                next += 1;
                            }
                        }
                    }
                }
            }
            for oz in 1..4usize {
                for oy in 1..4usize {
                    for ox in 1..4usize {
                        let o = [ox, oy, oz];
                        // Owner: parent of the first cube whose parent has ON children.
                        let owner = (0..8usize).find_map(|j| {
                            let k = ((ox + (j & 1)) / 2)
                                + 3 * ((oy + ((j >> 1) & 1)) / 2)
                                + 9 * ((oz + (j >> 2)) / 2);
                            w.parent[k].then_some(k)
                        });
                        // 13 is the window's centre parent.
                        if owner != Some(13) {
                            continue;
                        }
                        let mask = w.mask(o);
                        let cfg = &t.configs[mask as usize];
                        if cfg.class == 0 {
                            continue;
                        }
                        stats.configurations[cfg.class as usize] += 1;
                        let v = |j: u8| {
                            let c = corner(j);
                            w.at(ox + c[0] as usize, oy + c[1] as usize, oz + c[2] as usize)
                        };
                        let mut emit = |tri: [u8; 3], faces: &mut Vec<[u32; 3]>| {
                            let f = tri.map(v);
                            if let Some(min) = min_edge {
                                for e in 0..3 {
                                    let (a, b) = (f[e], f[(e + 1) % 3]);
                                    if s.positions[a as usize].distance(s.positions[b as usize])
                                        < min
                                        && !merged[a as usize]
                                        && !merged[b as usize]
                                    {
                                        merged[a as usize] = true;
                                        merged[b as usize] = true;
                                        merges.push((a, b));
                                        return;
                                    }
                                }
                            }
                            faces.push(f);
                        };
                        match &cfg.shape {
                            Shape::None => {}
                            Shape::Triangle(tri) => {
                                if defer_face(&w, o, cfg.face) {
                                    continue;
                                }
                                emit(*tri, &mut faces);
                            }
                            Shape::Quad(q) => {
                                if defer_face(&w, o, cfg.face) {
                                    continue;
                                }
                                let pos = q.map(|j| s.positions[v(j) as usize]);
                                let nrm = s.normals.as_ref().map(|n| q.map(|j| n[v(j) as usize]));
                                let (t1, t2) = choose_quad(*q, pos, nrm);
                                emit(t1, &mut faces);
                                emit(t2, &mut faces);
                            }
                            Shape::Solid(tris) => {
                                let shared = shared_edges(&w, o, mask, cfg.edges);
                                match split_by_cycle(mask, shared, tris) {
                                    Some((a, b)) => {
                                        stats.disambiguated += 1;
                                        let pos = |j: u8| s.positions[v(j) as usize];
                                        let pick =
                                            if mean_dihedral(&a, &pos) <= mean_dihedral(&b, &pos) {
                                                a
                                            } else {
                                                b
                                            };
                                        let first = faces.len();
                                        for tri in pick {
                                            emit(tri, &mut faces);
                                        }
                                        from_solids.extend(first as u32..faces.len() as u32);
                                    }
                                    None => {
                                        stats.fallbacks += 1;
                                        let first = faces.len();
                                        for &tri in tris {
                                            emit(tri, &mut faces);
                                        }
                                        from_solids.extend(first as u32..faces.len() as u32);
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
    }
    // A triangle whose three cubes share a coordinate lies on the face
    // between two neighbourhoods; two solid ones may both have built it:
    // keep one.
    dedupe_face_triangles(&s.cells, &mut faces, &from_solids);
    let mut mesh = s.vertices_only();
    if !merges.is_empty() {
        decimate_merge(&mut mesh, &mut faces, &merges);
    }
    mesh.faces = faces;
    if opts.orient {
        orient(&mut mesh);
    }
    stats.triangles = mesh.faces.len();
    stats.seconds = start.elapsed().as_secs_f64();
    Triangulation { mesh, stats }
}

/// Whether a planar configuration lying on a face of its neighbourhood
/// leaves that face to the neighbourhood on the other side: always when it
/// is the upper face (the other side sees it as its lower face), and when
/// the other side is a solid configuration, whose disc choice then covers
/// the face alone (two owners would cover it twice).
fn defer_face(w: &Window, o: [usize; 3], face: Option<(u8, u8)>) -> bool {
    let Some((axis, side)) = face else {
        return false;
    };
    if side == 1 {
        return true;
    }
    let mut across = o;
    across[axis as usize] -= 1;
    matches!(
        table().configs[w.mask(across) as usize].shape,
        Shape::Solid(_)
    )
}

fn tri_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a).normalize_or_zero()
}

/// The two triangulations of a quad `a b c d`; returns the better one.
fn choose_quad(q: [u8; 4], p: [Vec3; 4], n: Option<[Vec3; 4]>) -> ([u8; 3], [u8; 3]) {
    let ac = ([q[0], q[1], q[2]], [q[0], q[2], q[3]]);
    let bd = ([q[0], q[1], q[3]], [q[1], q[2], q[3]]);
    let score = |t: ([usize; 3], [usize; 3])| -> f32 {
        let n1 = tri_normal(p[t.0[0]], p[t.0[1]], p[t.0[2]]);
        let n2 = tri_normal(p[t.1[0]], p[t.1[1]], p[t.1[2]]);
        match n {
            // Disagreement with the particle normals.
            Some(vn) => {
                let s1: f32 = t.0.iter().map(|&i| 1.0 - n1.dot(vn[i]).abs()).sum();
                let s2: f32 = t.1.iter().map(|&i| 1.0 - n2.dot(vn[i]).abs()).sum();
                s1 + s2
            }
            // Dihedral angle between the two triangles (its cosine,
            // negated: same order, no acos).
            None => -n1.dot(n2),
        }
    };
    let s_ac = score(([0, 1, 2], [0, 2, 3]));
    let s_bd = score(([0, 1, 3], [1, 2, 3]));
    if s_ac <= s_bd { ac } else { bd }
}

/// Edges of `G_i` (as pair bits) also in the graph of an overlapping
/// neighbourhood of the window.
fn shared_edges(w: &Window, o: [usize; 3], mask: u8, edges: u32) -> u32 {
    let t = table();
    let mut shared = 0u32;
    let ns: Vec<u8> = (0..8).filter(|j| mask & (1 << j) != 0).collect();
    for (i, &a) in ns.iter().enumerate() {
        for &b in &ns[i + 1..] {
            let bit = 1u32 << pair(a, b);
            if edges & bit == 0 {
                continue;
            }
            let (ca, cb) = (corner(a), corner(b));
            'nb: for dz in -1i32..=1 {
                for dy in -1i32..=1 {
                    for dx in -1i32..=1 {
                        if (dx, dy, dz) == (0, 0, 0) {
                            continue;
                        }
                        let d = [dx, dy, dz];
                        // Corners of a and b inside the neighbour block o + d.
                        let la = [ca[0] - d[0], ca[1] - d[1], ca[2] - d[2]];
                        let lb = [cb[0] - d[0], cb[1] - d[1], cb[2] - d[2]];
                        if la.iter().chain(lb.iter()).any(|&v| !(0..=1).contains(&v)) {
                            continue;
                        }
                        let o2 = [
                            (o[0] as i32 + dx) as usize,
                            (o[1] as i32 + dy) as usize,
                            (o[2] as i32 + dz) as usize,
                        ];
                        let m2 = w.mask(o2);
                        // A neighbour whose cubes all lie in this block
                        // (a planar patch on the shared face) is this
                        // block's own geometry, not outside evidence.
                        let inside = (0..8u8).filter(|j| m2 & (1 << j) != 0).all(|j| {
                            let c = corner(j);
                            (0..3).all(|k| (0..=1).contains(&(c[k] + d[k])))
                        });
                        if inside {
                            continue;
                        }
                        let cfg = &t.configs[m2 as usize];
                        let ja = (la[0] + 2 * la[1] + 4 * la[2]) as u8;
                        let jb = (lb[0] + 2 * lb[1] + 4 * lb[2]) as u8;
                        if cfg.edges & (1 << pair(ja, jb)) != 0 {
                            shared |= bit;
                            break 'nb;
                        }
                    }
                }
            }
        }
    }
    shared
}

/// If `shared` is one Hamiltonian cycle through the ON cubes of `mask`,
/// the two discs of hull triangles it separates.
/// Two discs of triangles.
type Discs = (Vec<[u8; 3]>, Vec<[u8; 3]>);

fn split_by_cycle(mask: u8, shared: u32, tris: &[[u8; 3]]) -> Option<Discs> {
    let ns: Vec<u8> = (0..8).filter(|j| mask & (1 << j) != 0).collect();
    if shared.count_ones() as usize != ns.len() {
        return None;
    }
    let has = |a: u8, b: u8| shared & (1 << pair(a, b)) != 0;
    for &a in &ns {
        if ns.iter().filter(|&&b| b != a && has(a, b)).count() != 2 {
            return None;
        }
    }
    // Walk the cycle: it must visit every node before closing.
    let (mut prev, mut cur) = (ns[0], *ns.iter().find(|&&b| b != ns[0] && has(ns[0], b))?);
    let mut steps = 1;
    while cur != ns[0] {
        let next = *ns.iter().find(|&&b| b != cur && b != prev && has(cur, b))?;
        prev = cur;
        cur = next;
        steps += 1;
        if steps > ns.len() {
            return None;
        }
    }
    if steps != ns.len() {
        return None;
    }
    // Flood the triangles without crossing the cycle.
    let mut side = vec![u8::MAX; tris.len()];
    side[0] = 0;
    let mut stack = vec![0usize];
    let edge_of = |t: &[u8; 3], k: usize| (t[k], t[(k + 1) % 3]);
    while let Some(i) = stack.pop() {
        for k in 0..3 {
            let (a, b) = edge_of(&tris[i], k);
            if has(a, b) {
                continue;
            }
            for (j, tj) in tris.iter().enumerate() {
                if side[j] == u8::MAX && (0..3).any(|m| edge_of(tj, m) == (b, a)) {
                    side[j] = 0;
                    stack.push(j);
                }
            }
        }
    }
    let a: Vec<[u8; 3]> = tris
        .iter()
        .zip(&side)
        .filter(|(_, s)| **s == 0)
        .map(|(t, _)| *t)
        .collect();
    let b: Vec<[u8; 3]> = tris
        .iter()
        .zip(&side)
        .filter(|(_, s)| **s != 0)
        .map(|(t, _)| *t)
        .collect();
    if a.is_empty() || b.is_empty() {
        return None;
    }
    Some((a, b))
}

/// Mean dihedral angle over the interior edges of a disc of triangles.
fn mean_dihedral(tris: &[[u8; 3]], pos: &impl Fn(u8) -> Vec3) -> f32 {
    let mut sum = 0.0;
    let mut n = 0;
    for (i, ti) in tris.iter().enumerate() {
        for tj in &tris[i + 1..] {
            let shared = ti.iter().filter(|v| tj.contains(v)).count();
            if shared == 2 {
                let ni = tri_normal(pos(ti[0]), pos(ti[1]), pos(ti[2]));
                let nj = tri_normal(pos(tj[0]), pos(tj[1]), pos(tj[2]));
                sum += ni.dot(nj).clamp(-1.0, 1.0).acos();
                n += 1;
            }
        }
    }
    if n == 0 { 0.0 } else { sum / n as f32 }
}

/// §6.3: merge the cubes joined by short edges (positions and attributes
/// averaged), drop the triangles that collapse.
fn decimate_merge(mesh: &mut TriMesh, faces: &mut Vec<[u32; 3]>, merges: &[(u32, u32)]) {
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

fn dedupe_face_triangles(cells: &[u64], faces: &mut Vec<[u32; 3]>, candidates: &[u32]) {
    let mut keyed: Vec<([u32; 3], u32)> = Vec::new();
    for &i in candidates {
        let f = &faces[i as usize];
        let c = f.map(|v| unmorton(cells[v as usize]));
        if (0..3).any(|a| c[0][a] == c[1][a] && c[1][a] == c[2][a]) {
            let mut k = *f;
            k.sort_unstable();
            keyed.push((k, i));
        }
    }
    keyed.sort_unstable();
    let mut drop = vec![false; faces.len()];
    for w in keyed.windows(2) {
        if w[0].0 == w[1].0 {
            drop[w[1].1 as usize] = true;
        }
    }
    let mut i = 0;
    faces.retain(|_| {
        i += 1;
        !drop[i - 1]
    });
}

fn edge_key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}

/// Sorted `(edge key, triangle)` pairs of every triangle side.
fn sorted_sides(faces: &[[u32; 3]]) -> Vec<(u64, u32)> {
    let mut sides: Vec<(u64, u32)> = Vec::with_capacity(faces.len() * 3);
    for (i, f) in faces.iter().enumerate() {
        for k in 0..3 {
            sides.push((edge_key(f[k], f[(k + 1) % 3]), i as u32));
        }
    }
    sides.sort_unstable();
    sides
}

/// Triangles incident to an edge that more than two triangles use (the
/// strict count; Table 1 counts non-manifold *local triangulations*, see
/// [`TriangulationStats::fallbacks`]).
pub fn non_manifold_triangles(mesh: &TriMesh) -> usize {
    let sides = sorted_sides(&mesh.faces);
    let mut bad = vec![false; mesh.faces.len()];
    let mut i = 0;
    while i < sides.len() {
        let mut j = i;
        while j < sides.len() && sides[j].0 == sides[i].0 {
            j += 1;
        }
        if j - i > 2 {
            for s in &sides[i..j] {
                bad[s.1 as usize] = true;
            }
        }
        i = j;
    }
    bad.iter().filter(|b| **b).count()
}

/// See the module docs, "Orientation".
fn orient(mesh: &mut TriMesh) {
    if let Some(n) = &mesh.normals {
        for f in &mut mesh.faces {
            let [a, b, c] = f.map(|v| mesh.positions[v as usize]);
            let fn_ = (b - a).cross(c - a);
            let vn = n[f[0] as usize] + n[f[1] as usize] + n[f[2] as usize];
            if fn_.dot(vn) < 0.0 {
                f.swap(1, 2);
            }
        }
        return;
    }
    // Triangle → its neighbours across manifold edges.
    let sides = sorted_sides(&mesh.faces);
    let nf = mesh.faces.len();
    let mut across = vec![[u32::MAX; 3]; nf];
    let mut i = 0;
    while i < sides.len() {
        let mut j = i;
        while j < sides.len() && sides[j].0 == sides[i].0 {
            j += 1;
        }
        if j - i == 2 {
            let (t1, t2) = (sides[i].1, sides[i + 1].1);
            for (t, o) in [(t1, t2), (t2, t1)] {
                if let Some(slot) = across[t as usize].iter_mut().find(|x| **x == u32::MAX) {
                    *slot = o;
                }
            }
        }
        i = j;
    }
    let mut done = vec![false; nf];
    let mut stack = Vec::new();
    let mut component = Vec::new();
    for seed in 0..nf {
        if done[seed] {
            continue;
        }
        done[seed] = true;
        stack.push(seed);
        component.clear();
        while let Some(i) = stack.pop() {
            component.push(i);
            let f = mesh.faces[i];
            for &j in &across[i] {
                if j == u32::MAX || done[j as usize] {
                    continue;
                }
                let j = j as usize;
                // Consistent neighbours traverse their shared edge in
                // opposite directions.
                let g = mesh.faces[j];
                let same_dir = (0..3)
                    .any(|k| (0..3).any(|m| g[m] == f[k] && g[(m + 1) % 3] == f[(k + 1) % 3]));
                if same_dir {
                    mesh.faces[j].swap(1, 2);
                }
                done[j] = true;
                stack.push(j);
            }
        }
        let volume: f64 = component
            .iter()
            .map(|&i| {
                let [a, b, c] = mesh.faces[i].map(|v| mesh.positions[v as usize].as_dvec3());
                a.dot(b.cross(c))
            })
            .sum();
        if volume < 0.0 {
            for &i in &component {
                mesh.faces[i].swap(1, 2);
            }
        }
    }
}
