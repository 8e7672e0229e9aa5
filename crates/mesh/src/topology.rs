//! Connectivity helpers shared by the simplifier, the marching cube octree
//! and the particle coder: vertex→face rings, edge multiplicities, boundary
//! and non-manifold detection, connected components.
//!
//! All functions are O(V + F) or O(F log F) (edge sort) and allocate only
//! what they return.

use crate::mesh::TriMesh;

/// Vertex→face incidence in compressed-row form: the faces around vertex
/// `v` are `faces[offsets[v]..offsets[v + 1]]`, in increasing face order.
/// This is the "vertex ring" of HQMS §3.1 built in one pass over the faces.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct VertexRings {
    /// `V + 1` row starts into `faces`.
    pub offsets: Vec<u32>,
    /// Face indices, vertex by vertex.
    pub faces: Vec<u32>,
}

impl VertexRings {
    /// The rings of every vertex, `O(V + F)`. Face indices must be
    /// `< positions.len()` (the [`TriMesh`] invariant; panics otherwise).
    pub fn build(mesh: &TriMesh) -> VertexRings {
        let n = mesh.positions.len();
        let mut offsets = vec![0u32; n + 1];
        for f in &mesh.faces {
            for &v in f {
                offsets[v as usize + 1] += 1;
            }
        }
        for i in 0..n {
            offsets[i + 1] += offsets[i];
        }
        let mut fill = offsets.clone();
        let mut faces = vec![0u32; offsets[n] as usize];
        for (fi, f) in mesh.faces.iter().enumerate() {
            for &v in f {
                let slot = &mut fill[v as usize];
                faces[*slot as usize] = fi as u32;
                *slot += 1;
            }
        }
        VertexRings { offsets, faces }
    }
    /// The faces around `v`, in increasing face order.
    #[inline]
    pub fn ring(&self, v: u32) -> &[u32] {
        &self.faces[self.offsets[v as usize] as usize..self.offsets[v as usize + 1] as usize]
    }
    /// The number of faces around `v`.
    pub fn valence(&self, v: u32) -> usize {
        self.ring(v).len()
    }
}

/// An undirected edge `(a, b)` with `a < b` and the number of faces using it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct EdgeUse {
    /// The smaller endpoint.
    pub a: u32,
    /// The larger endpoint.
    pub b: u32,
    /// How many face sides use the edge.
    pub count: u32,
}

/// The key of undirected edge `{a, b}`: `min << 32 | max`, so sorting keys
/// sorts edges by `(min, max)`.
#[inline]
fn edge_key(a: u32, b: u32) -> u64 {
    let (a, b) = if a < b { (a, b) } else { (b, a) };
    ((a as u64) << 32) | b as u64
}

/// Every distinct undirected edge with its face multiplicity, sorted by
/// `(a, b)`. Multiplicity 1 = boundary, 2 = manifold interior, > 2 =
/// non-manifold. Cost: one sort of `3F` keys.
pub fn edge_multiplicities(mesh: &TriMesh) -> Vec<EdgeUse> {
    let mut keys: Vec<u64> = Vec::with_capacity(mesh.faces.len() * 3);
    for f in &mesh.faces {
        for k in 0..3 {
            keys.push(edge_key(f[k], f[(k + 1) % 3]));
        }
    }
    keys.sort_unstable();
    let mut out: Vec<EdgeUse> = Vec::with_capacity(keys.len() / 2 + 1);
    for k in keys {
        let (a, b) = ((k >> 32) as u32, k as u32);
        match out.last_mut() {
            Some(e) if e.a == a && e.b == b => e.count += 1,
            _ => out.push(EdgeUse { a, b, count: 1 }),
        }
    }
    out
}

/// The number of non-manifold edges: edges that more than two faces use.
/// This is the count `info` reports ([`TopologyStats::non_manifold_edges`]).
pub fn non_manifold_edge_count(mesh: &TriMesh) -> usize {
    edge_multiplicities(mesh)
        .iter()
        .filter(|e| e.count > 2)
        .count()
}

/// Per face: whether it uses a non-manifold edge (one that more than two
/// faces use). A face repeating an index counts its degenerate side like
/// any other. Cost: one sort of `3F` (edge, face) pairs.
pub fn non_manifold_faces(mesh: &TriMesh) -> Vec<bool> {
    let mut sides: Vec<(u64, u32)> = Vec::with_capacity(mesh.faces.len() * 3);
    for (i, f) in mesh.faces.iter().enumerate() {
        for k in 0..3 {
            sides.push((edge_key(f[k], f[(k + 1) % 3]), i as u32));
        }
    }
    sides.sort_unstable();
    let mut bad = vec![false; mesh.faces.len()];
    for run in sides.chunk_by(|x, y| x.0 == y.0) {
        if run.len() > 2 {
            for s in run {
                bad[s.1 as usize] = true;
            }
        }
    }
    bad
}

/// The number of faces that use a non-manifold edge (see
/// [`non_manifold_faces`]).
pub fn non_manifold_face_count(mesh: &TriMesh) -> usize {
    non_manifold_faces(mesh).iter().filter(|b| **b).count()
}

/// Disjoint-set forest over `0..n` with path halving and union by index:
/// the smaller root wins, so **every set's root is its smallest member**
/// whatever order the unions came in. Results are therefore deterministic,
/// and a caller can number classes by their root (the simplifier's
/// component pruning, the info report's components and boundary loops, the
/// marching cube octree's LOD groups all rely on this).
///
/// Cost: `find` and `union` run in amortised near-constant time (path
/// halving alone gives `O(log n)` amortised; with union by index in
/// practice a few steps). Memory: 4 bytes per element. Panics if an
/// element is `>= n`.
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    /// `n` singleton sets `{0}, {1}, …, {n − 1}` (`n ≤ 2³²`).
    pub fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }

    /// Back to `n` singletons, keeping the allocation.
    pub fn reset(&mut self, n: usize) {
        self.parent.clear();
        self.parent.extend(0..n as u32);
    }

    /// The number of elements.
    pub fn len(&self) -> usize {
        self.parent.len()
    }

    /// Whether there are no elements.
    pub fn is_empty(&self) -> bool {
        self.parent.is_empty()
    }

    /// The root (smallest member) of `x`'s set; halves the path on the way.
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = p;
            x = p;
        }
        x
    }

    /// Joins the sets of `a` and `b`; the smaller of the two roots becomes
    /// the root of the union.
    pub fn union(&mut self, a: u32, b: u32) {
        let (ra, rb) = (self.find(a), self.find(b));
        if ra != rb {
            let (lo, hi) = if ra < rb { (ra, rb) } else { (rb, ra) };
            self.parent[hi as usize] = lo;
        }
    }
}

/// Summary of a mesh's connectivity.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize)]
pub struct TopologyStats {
    /// Distinct undirected edges.
    pub edges: usize,
    /// Edges that one face uses.
    pub boundary_edges: usize,
    /// Connected components of the boundary-edge graph: one per hole or
    /// open rim for a manifold boundary.
    pub boundary_loops: usize,
    /// Edges that more than two faces use ([`non_manifold_edge_count`]).
    pub non_manifold_edges: usize,
    /// Vertices whose incident faces form more than one edge-connected fan
    /// (a "bow-tie" vertex); vertices on non-manifold edges are not counted
    /// again here.
    pub non_manifold_vertices: usize,
    /// Face-connected components (faces sharing a vertex are connected).
    pub components: usize,
    /// Vertices no face uses.
    pub unreferenced_vertices: usize,
}

/// Computes [`TopologyStats`] in O(F log F).
pub fn topology_stats(mesh: &TriMesh) -> TopologyStats {
    let n = mesh.positions.len();
    let edges = edge_multiplicities(mesh);
    let mut s = TopologyStats {
        edges: edges.len(),
        ..Default::default()
    };

    let mut boundary_uf = UnionFind::new(n);
    let mut on_boundary = vec![false; n];
    let mut on_nm_edge = vec![false; n];
    for e in &edges {
        if e.count == 1 {
            s.boundary_edges += 1;
            boundary_uf.union(e.a, e.b);
            on_boundary[e.a as usize] = true;
            on_boundary[e.b as usize] = true;
        } else if e.count > 2 {
            s.non_manifold_edges += 1;
            on_nm_edge[e.a as usize] = true;
            on_nm_edge[e.b as usize] = true;
        }
    }
    s.boundary_loops = (0..n as u32)
        .filter(|&v| on_boundary[v as usize] && boundary_uf.find(v) == v)
        .count();

    let mut comp = UnionFind::new(n);
    let mut referenced = vec![false; n];
    for f in &mesh.faces {
        comp.union(f[0], f[1]);
        comp.union(f[1], f[2]);
        for &v in f {
            referenced[v as usize] = true;
        }
    }
    s.components = (0..n as u32)
        .filter(|&v| referenced[v as usize] && comp.find(v) == v)
        .count();
    s.unreferenced_vertices = referenced.iter().filter(|r| !**r).count();

    // Fans around each vertex: faces of the ring are joined when they share
    // an edge incident to the vertex.
    let rings = VertexRings::build(mesh);
    let mut local: Vec<(u32, usize)> = Vec::new();
    let mut fan_uf = UnionFind::new(0);
    for v in 0..n as u32 {
        let ring = rings.ring(v);
        if ring.len() < 2 || on_nm_edge[v as usize] {
            continue;
        }
        // (other vertex, ring slot) pairs; faces sharing "other" share an edge with v.
        local.clear();
        for (slot, &f) in ring.iter().enumerate() {
            for &w in &mesh.faces[f as usize] {
                if w != v {
                    local.push((w, slot));
                }
            }
        }
        local.sort_unstable();
        fan_uf.reset(ring.len());
        for pair in local.windows(2) {
            if pair[0].0 == pair[1].0 {
                fan_uf.union(pair[0].1 as u32, pair[1].1 as u32);
            }
        }
        let fans = (0..ring.len() as u32)
            .filter(|&i| fan_uf.find(i) == i)
            .count();
        if fans > 1 {
            s.non_manifold_vertices += 1;
        }
    }
    s
}

/// Face-connected component id per face (ids dense, ordered by first face)
/// and the number of components.
pub fn face_components(mesh: &TriMesh) -> (Vec<u32>, usize) {
    let mut uf = UnionFind::new(mesh.positions.len());
    for f in &mesh.faces {
        uf.union(f[0], f[1]);
        uf.union(f[1], f[2]);
    }
    let mut id_of_root = rustc_hash::FxHashMap::default();
    let ids = mesh
        .faces
        .iter()
        .map(|f| {
            let r = uf.find(f[0]);
            let next = id_of_root.len() as u32;
            *id_of_root.entry(r).or_insert(next)
        })
        .collect();
    (ids, id_of_root.len())
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn tetra() -> TriMesh {
        let p = vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        TriMesh::new(p, vec![[0, 2, 1], [0, 1, 3], [1, 2, 3], [0, 3, 2]])
    }

    #[test]
    fn closed_tetrahedron_has_no_boundary() {
        let s = topology_stats(&tetra());
        assert_eq!(s.edges, 6);
        assert_eq!(s.boundary_edges, 0);
        assert_eq!(s.boundary_loops, 0);
        assert_eq!(s.non_manifold_edges, 0);
        assert_eq!(s.non_manifold_vertices, 0);
        assert_eq!(s.components, 1);
    }

    #[test]
    fn open_tetrahedron_has_one_loop_of_three_edges() {
        let mut m = tetra();
        m.faces.pop();
        let s = topology_stats(&m);
        assert_eq!((s.boundary_edges, s.boundary_loops), (3, 1));
    }

    #[test]
    fn fin_edge_and_bowtie_vertex_are_non_manifold() {
        // Three triangles on edge 0-1 (a fin), plus two triangles touching at vertex 5 only.
        let p = vec![
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            Vec3::NEG_Y,
            Vec3::new(5.0, 0.0, 0.0),
            Vec3::new(6.0, 0.0, 0.0),
            Vec3::new(6.0, 1.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(4.0, -1.0, 0.0),
        ];
        let faces = vec![[0, 1, 2], [1, 0, 3], [0, 1, 4], [5, 6, 7], [5, 8, 9]];
        let m = TriMesh::new(p, faces);
        let s = topology_stats(&m);
        assert_eq!(s.non_manifold_edges, 1);
        assert_eq!(s.non_manifold_vertices, 1);
        assert_eq!(s.components, 2);
        assert_eq!(non_manifold_edge_count(&m), 1);
        assert_eq!(non_manifold_faces(&m), [true, true, true, false, false]);
        assert_eq!(non_manifold_face_count(&m), 3);
        let (ids, n) = face_components(&m);
        assert_eq!((ids, n), (vec![0, 0, 0, 1, 1], 2));
    }

    #[test]
    fn rings_list_incident_faces_in_order() {
        let r = VertexRings::build(&tetra());
        assert_eq!(r.ring(0), &[0, 1, 3]);
        assert_eq!(r.valence(3), 3);
    }
}
