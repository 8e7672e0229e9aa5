//! The octree every level of a tileset is cut by: cells split while they
//! hold more than the leaf budget of input triangles (by centroid).
//!
//! The root cell is the cube around the input's bounding box (its largest
//! extent on every axis, centred), so cells are cubes and a cell at depth
//! `d` is `(x, y, z)` in a `2^d` grid. A face belongs to the one cell that
//! holds its centroid (clamped into the grid), so the cells of one depth
//! split any mesh of the object into disjoint tiles whose union is the
//! mesh.

use glam::{DVec3, Vec3};
use lodkit_mesh::{Aabb, TriMesh};

/// Deepest octree level: 2^20 cells per axis resolve a millionth of the
/// object, far below any leaf budget; it also bounds the recursion when
/// many centroids coincide (such a leaf may then exceed the budget).
pub const MAX_DEPTH: u8 = 20;

/// A cell: its depth and integer coordinates in the `2^depth` grid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct CellKey {
    /// Depth (0: the root).
    pub depth: u8,
    /// Grid coordinates, each in `0..2^depth`.
    pub xyz: [u32; 3],
}

impl CellKey {
    /// The root cell.
    pub const ROOT: CellKey = CellKey {
        depth: 0,
        xyz: [0, 0, 0],
    };

    /// The `i`-th child (`i` in `0..8`, bit 0: x, bit 1: y, bit 2: z).
    pub fn child(self, i: usize) -> CellKey {
        let b = |k: usize| ((i >> k) & 1) as u32;
        CellKey {
            depth: self.depth + 1,
            xyz: [
                self.xyz[0] * 2 + b(0),
                self.xyz[1] * 2 + b(1),
                self.xyz[2] * 2 + b(2),
            ],
        }
    }

    /// The file stem of its tile: `DEPTH-X-Y-Z`.
    pub fn name(self) -> String {
        format!(
            "{}-{}-{}-{}",
            self.depth, self.xyz[0], self.xyz[1], self.xyz[2]
        )
    }
}

/// The root cube and the cell lookups in it.
#[derive(Clone, Copy, Debug)]
pub struct Grid {
    /// The cube's lowest corner.
    pub origin: DVec3,
    /// The cube's edge length (> 0).
    pub size: f64,
}

impl Grid {
    /// The cube around `bbox` (a little larger, so no point sits on its
    /// far faces; a flat or point-like box gets a unit-free positive size).
    pub fn around(bbox: &Aabb) -> Grid {
        let (lo, hi) = (bbox.min.as_dvec3(), bbox.max.as_dvec3());
        let extent = (hi - lo).max_element();
        let size = if extent > 0.0 {
            extent * (1.0 + 1e-6)
        } else {
            1.0
        };
        let centre = (lo + hi) * 0.5;
        Grid {
            origin: centre - DVec3::splat(size * 0.5),
            size,
        }
    }

    /// The edge length of a cell of depth `depth`.
    pub fn side(&self, depth: u8) -> f64 {
        self.size / (1u64 << depth) as f64
    }

    /// Cell `key`'s lowest corner.
    pub fn corner(&self, key: CellKey) -> DVec3 {
        self.origin + DVec3::from_array(key.xyz.map(f64::from)) * self.side(key.depth)
    }

    /// The cell of depth `depth` that holds `p` (clamped into the grid).
    pub fn cell_of(&self, p: Vec3, depth: u8) -> CellKey {
        let n = 1u64 << depth;
        let rel = (p.as_dvec3() - self.origin) / self.size * n as f64;
        let c = |v: f64| (v.floor().max(0.0) as u64).min(n - 1) as u32;
        CellKey {
            depth,
            xyz: [c(rel.x), c(rel.y), c(rel.z)],
        }
    }
}

/// A face's centroid.
pub fn centroid(mesh: &TriMesh, f: usize) -> Vec3 {
    let [a, b, c] = mesh.triangle(f);
    (a + b + c) / 3.0
}

/// One node of the octree.
#[derive(Clone, Debug)]
pub struct Node {
    /// Its cell.
    pub key: CellKey,
    /// Indices of its children in [`Octree::nodes`] (empty: a leaf).
    pub children: Vec<usize>,
    /// Input faces whose centroid lies in the cell.
    pub input_faces: usize,
}

/// The octree of an input: nodes in breadth-first order (the root first,
/// each node's children in octant order), so every walk over it is
/// deterministic.
#[derive(Clone, Debug)]
pub struct Octree {
    /// The root cube.
    pub grid: Grid,
    /// The nodes.
    pub nodes: Vec<Node>,
    /// Leaf node index of each input face.
    pub leaf_of_face: Vec<u32>,
    /// Deepest node's depth.
    pub depth: u8,
}

impl Octree {
    /// Splits cells of `mesh` while they hold more than `leaf_faces`
    /// faces (and are above [`MAX_DEPTH`]). Cost: `O(F × depth)` time,
    /// 12 bytes per face.
    pub fn build(mesh: &TriMesh, leaf_faces: usize) -> Octree {
        let grid = Grid::around(&mesh.bbox());
        let centroids: Vec<Vec3> = (0..mesh.faces.len()).map(|f| centroid(mesh, f)).collect();
        let mut nodes = vec![Node {
            key: CellKey::ROOT,
            children: Vec::new(),
            input_faces: mesh.faces.len(),
        }];
        let mut leaf_of_face = vec![0u32; mesh.faces.len()];
        // Face lists of the nodes still to split, in breadth-first order.
        let mut queue = std::collections::VecDeque::new();
        queue.push_back((0usize, (0..mesh.faces.len() as u32).collect::<Vec<u32>>()));
        let mut depth = 0;
        while let Some((n, faces)) = queue.pop_front() {
            let key = nodes[n].key;
            depth = depth.max(key.depth);
            if faces.len() <= leaf_faces || key.depth >= MAX_DEPTH {
                for &f in &faces {
                    leaf_of_face[f as usize] = n as u32;
                }
                continue;
            }
            let mut parts: [Vec<u32>; 8] = Default::default();
            for &f in &faces {
                let c = grid.cell_of(centroids[f as usize], key.depth + 1);
                let i = (c.xyz[0] & 1) | ((c.xyz[1] & 1) << 1) | ((c.xyz[2] & 1) << 2);
                parts[i as usize].push(f);
            }
            drop(faces);
            for (i, part) in parts.into_iter().enumerate() {
                if part.is_empty() {
                    continue;
                }
                let id = nodes.len();
                nodes.push(Node {
                    key: key.child(i),
                    children: Vec::new(),
                    input_faces: part.len(),
                });
                nodes[n].children.push(id);
                queue.push_back((id, part));
            }
        }
        Octree {
            grid,
            nodes,
            leaf_of_face,
            depth,
        }
    }

    /// Index of the node with `key`, if any (a descent from the root).
    pub fn find(&self, key: CellKey) -> Option<usize> {
        let mut n = 0;
        while self.nodes[n].key.depth < key.depth {
            let shift = key.depth - self.nodes[n].key.depth - 1;
            let want = CellKey {
                depth: self.nodes[n].key.depth + 1,
                xyz: key.xyz.map(|v| v >> shift),
            };
            n = *self.nodes[n]
                .children
                .iter()
                .find(|&&c| self.nodes[c].key == want)?;
        }
        Some(n)
    }

    /// Index of the leaf whose cell holds cell `key` (a leaf of depth at
    /// most `key.depth`), if any: `None` when `key` lies in an internal
    /// node of its depth or in a cell the input left empty.
    pub fn leaf_holding(&self, key: CellKey) -> Option<usize> {
        let mut n = 0;
        loop {
            let node = &self.nodes[n];
            if node.children.is_empty() {
                return Some(n);
            }
            if node.key.depth >= key.depth {
                return None;
            }
            let shift = key.depth - node.key.depth - 1;
            let want = CellKey {
                depth: node.key.depth + 1,
                xyz: key.xyz.map(|v| v >> shift),
            };
            n = *node.children.iter().find(|&&c| self.nodes[c].key == want)?;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lodkit_mesh::shapes::icosphere;

    #[test]
    fn leaves_hold_at_most_the_budget_and_cover_every_face() {
        let m = icosphere(5);
        let t = Octree::build(&m, 1000);
        let mut counts = vec![0usize; t.nodes.len()];
        for &l in &t.leaf_of_face {
            counts[l as usize] += 1;
            assert!(t.nodes[l as usize].children.is_empty());
        }
        for (n, node) in t.nodes.iter().enumerate() {
            if node.children.is_empty() {
                assert_eq!(counts[n], node.input_faces);
                assert!(node.input_faces <= 1000);
            } else {
                let s: usize = node.children.iter().map(|&c| t.nodes[c].input_faces).sum();
                assert_eq!(s, node.input_faces);
            }
            assert_eq!(t.find(node.key), Some(n));
            let deeper = CellKey {
                depth: node.key.depth + 2,
                xyz: node.key.xyz.map(|v| v * 4 + 1),
            };
            let holding = node.children.is_empty().then_some(n);
            assert_eq!(t.leaf_holding(node.key), holding);
            if holding.is_some() {
                assert_eq!(t.leaf_holding(deeper), holding);
            }
        }
    }
}
