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
    pub offsets: Vec<u32>,
    pub faces: Vec<u32>,
}

impl VertexRings {
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
    #[inline]
    pub fn ring(&self, v: u32) -> &[u32] {
        &self.faces[self.offsets[v as usize] as usize..self.offsets[v as usize + 1] as usize]
    }
    pub fn valence(&self, v: u32) -> usize {
        self.ring(v).len()
    }
}

/// An undirected edge `(a, b)` with `a < b` and the number of faces using it.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub struct EdgeUse {
    pub a: u32,
    pub b: u32,
    pub count: u32,
}

/// Every distinct undirected edge with its face multiplicity, sorted by
/// `(a, b)`. Multiplicity 1 = boundary, 2 = manifold interior, > 2 =
/// non-manifold.
pub fn edge_multiplicities(mesh: &TriMesh) -> Vec<EdgeUse> {
    let mut keys: Vec<u64> = Vec::with_capacity(mesh.faces.len() * 3);
    for f in &mesh.faces {
        for k in 0..3 {
            let (a, b) = (f[k], f[(k + 1) % 3]);
            let (a, b) = if a < b { (a, b) } else { (b, a) };
            keys.push(((a as u64) << 32) | b as u64);
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

/// Disjoint-set forest with path halving and union by index (the smaller
/// root wins, which keeps results deterministic).
#[derive(Debug, Clone)]
pub struct UnionFind {
    parent: Vec<u32>,
}

impl UnionFind {
    pub fn new(n: usize) -> Self {
        UnionFind {
            parent: (0..n as u32).collect(),
        }
    }
    pub fn find(&mut self, mut x: u32) -> u32 {
        while self.parent[x as usize] != x {
            let p = self.parent[self.parent[x as usize] as usize];
            self.parent[x as usize] = p;
            x = p;
        }
        x
    }
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
    pub edges: usize,
    pub boundary_edges: usize,
    /// Connected components of the boundary-edge graph: one per hole or
    /// open rim for a manifold boundary.
    pub boundary_loops: usize,
    pub non_manifold_edges: usize,
    /// Vertices whose incident faces form more than one edge-connected fan
    /// (a "bow-tie" vertex); vertices on non-manifold edges are not counted
    /// again here.
    pub non_manifold_vertices: usize,
    /// Face-connected components (faces sharing a vertex are connected).
    pub components: usize,
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
        fan_uf.parent.clear();
        fan_uf.parent.extend(0..ring.len() as u32);
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
    let mut id_of_root = std::collections::HashMap::new();
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
