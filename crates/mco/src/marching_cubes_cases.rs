//! The 256-case marching cubes table, generated in code.
//!
//! Follows the thesis's §2.2.1 and §4.2 (Lorensen and Cline's marching
//! cubes: a cube's 8 vertex signs pick a case, the case lists triangles
//! over the cube's 12 edges). Nothing is typed in by hand: the table is
//! derived from
//!
//! 1. **A face rule.** On each of the cube's 6 faces the sign pattern alone
//!    decides the iso-segments drawn across that face. On an *ambiguous*
//!    face (signs alternate around it) the rule always separates the two
//!    positive (outside) corners and joins the two negative (inside) ones.
//!    Because the decision depends only on the 4 signs of the face, the two
//!    cubes sharing a face draw the same segments on it, so adjacent cubes
//!    never leave a hole — the consistency the thesis's 15 Lorensen cases
//!    lack (their complementary cases disagree on ambiguous faces).
//! 2. **Base cases.** The 256 sign configurations fall into 22 classes under
//!    the 48 symmetries of the cube (24 rotations × reflection); complement
//!    is deliberately *not* a symmetry, because it would flip the face rule.
//!    For the representative of each class (its smallest configuration
//!    number) the face segments are chained into closed loops around the
//!    cube and each loop is fanned into triangles.
//! 3. **Symmetries.** Every other configuration takes its class
//!    representative's triangles mapped through the symmetry that carries
//!    the representative onto it (edges permuted, winding reversed for the
//!    reflections).
//!
//! Conventions (used everywhere in the crate):
//! - cube vertex `v` has offset `(v & 1, v >> 1 & 1, v >> 2 & 1)`;
//! - edge `axis * 4 + k` joins the `k`-th vertex (in increasing order)
//!   whose `axis` bit is 0 to the vertex with that bit set;
//! - configuration bit `v` is set when vertex `v` is *inside* (negative
//!   signed distance);
//! - triangles wind counter-clockwise seen from outside: their normal
//!   points from the inside (negative) corners towards the outside.
//!
//! The tests check every configuration's triangles against the face rule
//! directly, the class count, the symmetry closure, and watertightness on
//! random fields.

use std::sync::LazyLock;

/// Edge index → its two cube vertices (lower vertex first).
pub const EDGES: [[u8; 2]; 12] = edge_list();

const fn edge_list() -> [[u8; 2]; 12] {
    let mut out = [[0u8; 2]; 12];
    let mut axis = 0;
    while axis < 3 {
        let mut k = 0;
        let mut v = 0u8;
        while v < 8 {
            if v & (1 << axis) == 0 {
                out[axis * 4 + k] = [v, v | (1 << axis)];
                k += 1;
            }
            v += 1;
        }
        axis += 1;
    }
    out
}

/// The edge joining cube vertices `a` and `b`, if they are adjacent.
pub fn edge_between(a: u8, b: u8) -> Option<u8> {
    EDGES
        .iter()
        .position(|e| (e[0] == a && e[1] == b) || (e[0] == b && e[1] == a))
        .map(|i| i as u8)
}

/// A face: `axis` (0 x, 1 y, 2 z) and `side` (0 low, 1 high).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Face {
    pub axis: u8,
    pub side: u8,
}

/// The 6 faces in a fixed order: `axis * 2 + side`.
pub const FACES: [Face; 6] = [
    Face { axis: 0, side: 0 },
    Face { axis: 0, side: 1 },
    Face { axis: 1, side: 0 },
    Face { axis: 1, side: 1 },
    Face { axis: 2, side: 0 },
    Face { axis: 2, side: 1 },
];

/// The face's 4 vertices, counter-clockwise seen from outside the cube.
pub const fn face_vertices(f: Face) -> [u8; 4] {
    let a = f.axis as u32;
    let (u, w) = ((a + 1) % 3, (a + 2) % 3);
    let base = f.side << a;
    let (du, dw) = (1u8 << u, 1u8 << w);
    if f.side == 1 {
        // u × w = axis: (0,0) (1,0) (1,1) (0,1) turns around +axis.
        [base, base | du, base | du | dw, base | dw]
    } else {
        [base, base | dw, base | du | dw, base | du]
    }
}

/// The edge joining cube vertices `a` and `b` (which must be adjacent),
/// for the const tables.
const fn edge_between_const(a: u8, b: u8) -> u8 {
    let mut i = 0;
    while i < 12 {
        let e = EDGES[i];
        if (e[0] == a && e[1] == b) || (e[0] == b && e[1] == a) {
            return i as u8;
        }
        i += 1;
    }
    panic!("face edges are cube edges")
}

/// [`face_edges`] of every face, by `axis * 2 + side`.
const FACE_EDGES: [[u8; 4]; 6] = {
    let mut out = [[0u8; 4]; 6];
    let mut f = 0;
    while f < 6 {
        let v = face_vertices(FACES[f]);
        let mut i = 0;
        while i < 4 {
            out[f][i] = edge_between_const(v[i], v[(i + 1) % 4]);
            i += 1;
        }
        f += 1;
    }
    out
};

/// The face's 4 edges in the same cyclic order: edge `i` joins vertex `i`
/// and vertex `i + 1` of [`face_vertices`].
#[inline]
pub fn face_edges(f: Face) -> [u8; 4] {
    FACE_EDGES[(f.axis * 2 + f.side) as usize]
}

/// The oriented iso-segments the face rule draws on face `f` for cube
/// configuration `config`: pairs `(from_edge, to_edge)` of cube edges.
/// Oriented so that, seen from outside the cube, the inside corners lie to
/// the right of the segment. 0, 1 or 2 segments.
pub fn face_segments(config: u8, f: Face) -> Vec<[u8; 2]> {
    face_segments_fixed(config, f).to_vec()
}

/// [`face_segments`] without allocating: a slice of a table made once by
/// [`face_segments_derived`].
#[inline]
pub fn face_segments_fixed(config: u8, f: Face) -> &'static [[u8; 2]] {
    let (n, segs) = &FACE_SEGMENTS[config as usize][(f.axis * 2 + f.side) as usize];
    &segs[..*n as usize]
}

/// One face's segments: how many (0–2), then the segments.
type FaceSegments = (u8, [[u8; 2]; 2]);

/// Every configuration's face segments, by face, derived once.
static FACE_SEGMENTS: LazyLock<Vec<[FaceSegments; 6]>> = LazyLock::new(|| {
    (0..=255u8)
        .map(|config| {
            FACES.map(|f| {
                let list = face_segments_derived(config, f);
                let mut segs = [[0u8; 2]; 2];
                segs[..list.len()].copy_from_slice(&list);
                (list.len() as u8, segs)
            })
        })
        .collect()
});

/// The face rule itself (see the module docs): the segments of
/// [`face_segments`], derived from the face's 4 signs.
pub fn face_segments_derived(config: u8, f: Face) -> Vec<[u8; 2]> {
    let v = face_vertices(f);
    let e = face_edges(f);
    let inside = |i: usize| config & (1 << v[i % 4]) != 0;
    let crossing: Vec<usize> = (0..4).filter(|&i| inside(i) != inside(i + 1)).collect();
    match crossing.len() {
        0 => Vec::new(),
        2 => {
            let (a, b) = (crossing[0], crossing[1]);
            // Walking counter-clockwise from edge a to edge b passes vertices
            // a+1..=b, which then lie to the right of the segment a → b.
            if inside(a + 1) {
                vec![[e[a], e[b]]]
            } else {
                vec![[e[b], e[a]]]
            }
        }
        4 => {
            // Ambiguous: cut off each outside corner on its own. Outside
            // vertex i sits between edges i-1 and i; the segment i → i-1
            // keeps it on the left (outside on the left, inside right).
            (0..4)
                .filter(|&i| !inside(i))
                .map(|i| [e[i], e[(i + 3) % 4]])
                .collect()
        }
        _ => unreachable!("a closed square has an even number of sign changes"),
    }
}

/// Traces the configuration's closed iso-polygons directly from the face
/// rule: loops of edge indices, each wound counter-clockwise seen from
/// outside the surface.
pub fn trace_loops(config: u8) -> Vec<Vec<u8>> {
    let mut next = [u8::MAX; 12];
    for f in FACES {
        for &[a, b] in face_segments_derived(config, f).iter() {
            debug_assert_eq!(next[a as usize], u8::MAX, "edge leaves twice");
            next[a as usize] = b;
        }
    }
    let mut used = [false; 12];
    let mut loops = Vec::new();
    for start in 0..12u8 {
        if next[start as usize] == u8::MAX || used[start as usize] {
            continue;
        }
        let mut lp = Vec::new();
        let mut e = start;
        while !used[e as usize] {
            used[e as usize] = true;
            lp.push(e);
            e = next[e as usize];
        }
        debug_assert_eq!(e, start, "face segments form closed loops");
        loops.push(lp);
    }
    loops
}

/// True when cube edges `a` and `b` lie on a common face.
fn share_face(a: u8, b: u8) -> bool {
    FACES.iter().any(|&f| {
        let e = face_edges(f);
        e.contains(&a) && e.contains(&b)
    })
}

/// A loop's polygon as triangles: a fan. With the inside corners to the
/// right of every segment seen from outside the cube, the loop turns
/// counter-clockwise around the direction pointing away from the inside
/// corners, so the fan keeps the loop's order. The fan starts at the first
/// loop vertex whose diagonals all cross the cube's interior: a diagonal
/// between two vertices of one face would lie in that face, where the
/// neighbouring cube's polygon may draw the very same diagonal (two
/// surfaces through one line).
fn fan(lp: &[u8], out: &mut Vec<[u8; 3]>) {
    let n = lp.len();
    let start = (0..n)
        .find(|&s| (2..n - 1).all(|i| !share_face(lp[s], lp[(s + i) % n])))
        .unwrap_or(0);
    for i in 1..n - 1 {
        out.push([lp[start], lp[(start + i) % n], lp[(start + i + 1) % n]]);
    }
}

/// The 48 symmetries of the cube, shared with the particles' table.
pub use lodkit_mesh::cube_symmetry::CubeSymmetry as Symmetry;

/// Image of edge `e` under the symmetry `g`.
pub fn symmetry_edge(g: &Symmetry, e: u8) -> u8 {
    let [a, b] = EDGES[e as usize];
    edge_between(g.vertex(a), g.vertex(b)).expect("symmetries keep edges")
}

/// The generated table: for each configuration, its triangles as edge
/// index triples, plus the class bookkeeping the tests inspect.
pub struct McTable {
    offsets: [u16; 257],
    tris: Vec<[u8; 3]>,
    /// Smallest configuration of each configuration's symmetry class.
    pub representative: [u8; 256],
}

impl McTable {
    fn generate() -> McTable {
        let syms = Symmetry::all();
        let mut representative = [0u8; 256];
        let mut via = [0usize; 256];
        for c in 0..=255u8 {
            let (rep, g) = syms
                .iter()
                .enumerate()
                .map(|(gi, g)| (g.config(c), gi))
                .min()
                .expect("48 symmetries");
            representative[c as usize] = rep;
            // g maps c to rep; we need the symmetry mapping rep to c.
            via[c as usize] = inverse_index(&syms, g);
        }
        let mut offsets = [0u16; 257];
        let mut tris = Vec::new();
        for c in 0..=255u8 {
            let rep = representative[c as usize];
            let mut base = Vec::new();
            for lp in trace_loops(rep) {
                fan(&lp, &mut base);
            }
            let g = syms[via[c as usize]];
            debug_assert_eq!(g.config(rep), c);
            for t in base {
                let m = t.map(|e| symmetry_edge(&g, e));
                tris.push(if g.reverses() { [m[0], m[2], m[1]] } else { m });
            }
            offsets[c as usize + 1] = tris.len() as u16;
        }
        McTable {
            offsets,
            tris,
            representative,
        }
    }

    /// Triangles of configuration `config` (edge index triples).
    #[inline]
    pub fn triangles(&self, config: u8) -> &[[u8; 3]] {
        let c = config as usize;
        &self.tris[self.offsets[c] as usize..self.offsets[c + 1] as usize]
    }

    /// The largest number of triangles any configuration produces.
    pub fn max_triangles(&self) -> usize {
        (0..256)
            .map(|c| (self.offsets[c + 1] - self.offsets[c]) as usize)
            .max()
            .unwrap_or(0)
    }
}

fn inverse_index(syms: &[Symmetry], g: usize) -> usize {
    let s = syms[g];
    syms.iter()
        .position(|h| (0..8).all(|v| h.vertex(s.vertex(v)) == v))
        .expect("the group is closed under inverses")
}

/// The table, generated on first use.
pub static TABLE: LazyLock<McTable> = LazyLock::new(McTable::generate);

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::BTreeMap;

    /// Directed boundary edges of a triangle set: (edge, edge) pairs used in
    /// one direction and not cancelled by the opposite direction.
    fn boundary(tris: &[[u8; 3]]) -> BTreeMap<(u8, u8), i32> {
        let mut m: BTreeMap<(u8, u8), i32> = BTreeMap::new();
        for t in tris {
            for i in 0..3 {
                let (a, b) = (t[i], t[(i + 1) % 3]);
                if let Some(c) = m.get_mut(&(b, a)) {
                    *c -= 1;
                    if *c == 0 {
                        m.remove(&(b, a));
                    }
                } else {
                    *m.entry((a, b)).or_default() += 1;
                }
            }
        }
        m
    }

    #[test]
    fn edges_and_faces_are_consistent() {
        for (i, [a, b]) in EDGES.iter().enumerate() {
            assert_eq!((a ^ b).count_ones(), 1, "edge {i}");
            assert_eq!(edge_between(*a, *b), Some(i as u8));
        }
        for f in FACES {
            let v = face_vertices(f);
            // Counter-clockwise around the outward normal.
            let p =
                |v: u8| glam::Vec3::new((v & 1) as f32, (v >> 1 & 1) as f32, (v >> 2 & 1) as f32);
            let n = (p(v[1]) - p(v[0])).cross(p(v[2]) - p(v[1]));
            let mut out = glam::Vec3::ZERO;
            out[f.axis as usize] = if f.side == 1 { 1.0 } else { -1.0 };
            assert!(n.dot(out) > 0.0, "face {f:?} winds clockwise");
        }
    }

    #[test]
    fn generated_table_is_the_one_the_mco_files_were_built_with() {
        // FNV-1a of every configuration's triangles and representative:
        // a change to the generator (or to the cube symmetries it uses,
        // `lodkit_mesh::cube_symmetry`) must not move a single triangle.
        let mut h = 0xcbf2_9ce4_8422_2325u64;
        let mut eat = |b: u8| h = (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3);
        for c in 0..=255u8 {
            let tris = TABLE.triangles(c);
            eat(tris.len() as u8);
            for t in tris {
                t.iter().for_each(|&e| eat(e));
            }
            eat(TABLE.representative[c as usize]);
        }
        assert_eq!(h, 0x5387_c82d_bca8_c23c);
    }

    #[test]
    fn twenty_two_classes_under_the_48_symmetries() {
        let reps: std::collections::BTreeSet<u8> = TABLE.representative.iter().copied().collect();
        assert_eq!(reps.len(), 22);
        assert_eq!(Symmetry::all().len(), 48);
        // The group acts faithfully: 48 distinct vertex permutations.
        let perms: std::collections::BTreeSet<[u8; 8]> = Symmetry::all()
            .iter()
            .map(|g| std::array::from_fn(|v| g.vertex(v as u8)))
            .collect();
        assert_eq!(perms.len(), 48);
    }

    #[test]
    fn face_tables_match_their_derivation() {
        for f in FACES {
            let v = face_vertices(f);
            let e: [u8; 4] = std::array::from_fn(|i| edge_between(v[i], v[(i + 1) % 4]).unwrap());
            assert_eq!(face_edges(f), e, "{f:?}");
            for c in 0..=255u8 {
                assert_eq!(
                    face_segments(c, f),
                    face_segments_derived(c, f),
                    "{c} {f:?}"
                );
            }
        }
    }

    #[test]
    fn every_configuration_matches_the_face_rule() {
        for c in 0..=255u8 {
            let tris = TABLE.triangles(c);
            // Every crossing edge is used, no other edge is.
            let crossing: Vec<u8> = (0..12u8)
                .filter(|&e| {
                    let [a, b] = EDGES[e as usize];
                    (c >> a & 1) != (c >> b & 1)
                })
                .collect();
            let mut used: Vec<u8> = tris.iter().flatten().copied().collect();
            used.sort_unstable();
            used.dedup();
            assert_eq!(used, crossing, "config {c}");
            // The polygon boundaries are exactly the face rule's segments,
            // in the same direction.
            let mut expect: BTreeMap<(u8, u8), i32> = BTreeMap::new();
            for f in FACES {
                for [a, b] in face_segments(c, f) {
                    *expect.entry((a, b)).or_default() += 1;
                }
            }
            assert_eq!(boundary(tris), expect, "config {c}");
        }
        assert_eq!(TABLE.triangles(0).len(), 0);
        assert_eq!(TABLE.triangles(255).len(), 0);
        assert!(TABLE.max_triangles() <= 12);
    }

    #[test]
    fn no_triangle_edge_lies_in_a_cube_face_unless_it_is_a_face_segment() {
        for c in 0..=255u8 {
            let segs: Vec<[u8; 2]> = FACES.iter().flat_map(|&f| face_segments(c, f)).collect();
            for t in TABLE.triangles(c) {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    if share_face(a, b) {
                        assert!(
                            segs.contains(&[a, b]) || segs.contains(&[b, a]),
                            "config {c}: diagonal {a}-{b} lies in a face"
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn table_is_closed_under_symmetry() {
        for g in Symmetry::all() {
            for c in 0..=255u8 {
                let mut mapped: Vec<[u8; 3]> = TABLE
                    .triangles(c)
                    .iter()
                    .map(|t| {
                        let m = t.map(|e| symmetry_edge(&g, e));
                        if g.reverses() { [m[0], m[2], m[1]] } else { m }
                    })
                    .collect();
                let image = TABLE.triangles(g.config(c));
                // Same polygons (boundaries) whatever the fan's start.
                assert_eq!(boundary(&mapped), boundary(image), "g {g:?} config {c}");
                mapped.clear();
            }
        }
    }

    #[test]
    fn single_inside_corner_normal_points_away_from_it() {
        let tris = TABLE.triangles(1);
        assert_eq!(tris.len(), 1);
        let mid = |e: u8| {
            let [a, b] = EDGES[e as usize];
            let p =
                |v: u8| glam::Vec3::new((v & 1) as f32, (v >> 1 & 1) as f32, (v >> 2 & 1) as f32);
            (p(a) + p(b)) * 0.5
        };
        let [a, b, c] = tris[0].map(mid);
        let n = (b - a).cross(c - a);
        assert!(n.dot(glam::Vec3::ONE) > 0.0, "normal {n}");
    }
}
