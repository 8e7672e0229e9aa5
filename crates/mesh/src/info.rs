//! `lodkit info`: what a geometry file holds and what is wrong with it.

use serde::Serialize;

use crate::mesh::{Aabb, Model, PointCloud, RangeImage, TriMesh};
use crate::topology::{TopologyStats, topology_stats};
use crate::weld::duplicate_positions;

/// Bounding box as serialised in reports.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct BoxInfo {
    /// Smallest corner (zeros for an empty box).
    pub min: [f32; 3],
    /// Largest corner (zeros for an empty box).
    pub max: [f32; 3],
    /// Length of the diagonal, object units (0 for an empty box).
    pub diagonal: f32,
}

impl From<Aabb> for BoxInfo {
    fn from(b: Aabb) -> Self {
        if b.is_empty() {
            BoxInfo {
                min: [0.0; 3],
                max: [0.0; 3],
                diagonal: 0.0,
            }
        } else {
            BoxInfo {
                min: b.min.to_array(),
                max: b.max.to_array(),
                diagonal: b.diagonal(),
            }
        }
    }
}

/// Everything `lodkit info` reports about a mesh.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MeshInfo {
    /// Vertices, referenced or not.
    pub vertices: usize,
    /// Triangles.
    pub faces: usize,
    /// The box of every vertex.
    pub bbox: BoxInfo,
    /// Total surface area, object units squared.
    pub area: f64,
    /// Edges, boundary, non-manifold elements, components, unreferenced
    /// vertices (flattened into the JSON object).
    #[serde(flatten)]
    pub topology: TopologyStats,
    /// Faces whose corners are collinear to within f32 precision
    /// (`|AB × AC| ≤ ε · max(|AB|², |AC|²)`).
    pub degenerate_faces: usize,
    /// Vertices whose position exactly repeats an earlier vertex's.
    pub duplicate_positions: usize,
    /// The per-vertex attributes present (`normals`, `colors`, `uvs`).
    pub attributes: Vec<&'static str>,
    /// V − E + F over the referenced vertices.
    pub euler_characteristic: i64,
    /// `(2·C − χ) / 2` when the mesh is a closed 2-manifold (no boundary, no
    /// non-manifold element), else `None`.
    pub genus: Option<i64>,
}

/// `lodkit info` for point clouds and range images.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PointsInfo {
    /// Points (a range image: its valid cells).
    pub points: usize,
    /// The box of every point (a range image: posed into the world).
    pub bbox: BoxInfo,
    /// The per-point attributes present (`normals`, `colors`).
    pub attributes: Vec<&'static str>,
    /// Range images only: lattice size and whether a sensor pose is known.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub grid: Option<GridInfo>,
}

/// A range image's lattice.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct GridInfo {
    /// Lattice width.
    pub cols: usize,
    /// Lattice height.
    pub rows: usize,
    /// Cells holding a sample.
    pub valid_cells: usize,
    /// Whether the sensor-to-world pose is known.
    pub has_pose: bool,
}

/// The report for any model; serialises with a `"kind"` tag.
#[derive(Debug, Clone, PartialEq, Serialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Info {
    /// A triangle mesh.
    Mesh(MeshInfo),
    /// A point cloud.
    Points(PointsInfo),
    /// A range image (with [`PointsInfo::grid`]).
    Range(PointsInfo),
}

/// What `lodkit info` reports about any decoded model: for a mesh
/// [`mesh_info`], else [`points_info`] / [`range_info`]. Never fails;
/// defects are counted, not refused. Cost: `O(V + F log F)` for a mesh (one
/// edge sort, one vertex hash), `O(n)` for points.
pub fn model_info(model: &Model) -> Info {
    match model {
        Model::Mesh(m) => Info::Mesh(mesh_info(m)),
        Model::Points(p) => Info::Points(points_info(p)),
        Model::Range(r) => Info::Range(range_info(r)),
    }
}

/// Counts, box, area, topology ([`TopologyStats`]), degenerate faces,
/// duplicate positions, Euler characteristic and genus of a mesh.
pub fn mesh_info(m: &TriMesh) -> MeshInfo {
    let t = topology_stats(m);
    let degenerate_faces = (0..m.faces.len())
        .filter(|&f| {
            let [a, b, c] = m.triangle(f);
            let (ab, ac) = (b - a, c - a);
            ab.cross(ac).length() <= f32::EPSILON * ab.length_squared().max(ac.length_squared())
        })
        .count();
    let referenced = m.positions.len() - t.unreferenced_vertices;
    let euler = referenced as i64 - t.edges as i64 + m.faces.len() as i64;
    let closed = t.boundary_edges == 0
        && t.non_manifold_edges == 0
        && t.non_manifold_vertices == 0
        && !m.faces.is_empty();
    MeshInfo {
        vertices: m.positions.len(),
        faces: m.faces.len(),
        bbox: m.bbox().into(),
        area: m.area(),
        topology: t,
        degenerate_faces,
        duplicate_positions: duplicate_positions(&m.positions),
        attributes: m.attribute_names(),
        euler_characteristic: euler,
        genus: closed.then(|| (2 * t.components as i64 - euler) / 2),
    }
}

/// Count, box and attributes of a point cloud.
pub fn points_info(p: &PointCloud) -> PointsInfo {
    let mut attributes = Vec::new();
    if p.normals.is_some() {
        attributes.push("normals");
    }
    if p.colors.is_some() {
        attributes.push("colors");
    }
    PointsInfo {
        points: p.len(),
        bbox: p.bbox().into(),
        attributes,
        grid: None,
    }
}

/// [`points_info`] of the posed valid samples, plus the lattice.
pub fn range_info(r: &RangeImage) -> PointsInfo {
    let cloud = r.to_point_cloud();
    let mut info = points_info(&cloud);
    info.grid = Some(GridInfo {
        cols: r.cols,
        rows: r.rows,
        valid_cells: r.valid_count(),
        has_pose: r.pose.is_some(),
    });
    info
}

impl Info {
    /// Human-readable `key: value` lines (what `lodkit info` prints and
    /// `report.md` embeds).
    pub fn to_text(&self) -> String {
        let mut s = String::new();
        let bbox = |s: &mut String, b: &BoxInfo| {
            s.push_str(&format!(
                "bbox: [{:.6}, {:.6}, {:.6}] – [{:.6}, {:.6}, {:.6}] (diagonal {:.6})\n",
                b.min[0], b.min[1], b.min[2], b.max[0], b.max[1], b.max[2], b.diagonal
            ))
        };
        let attrs = |a: &[&str]| {
            if a.is_empty() {
                "none".to_string()
            } else {
                a.join(", ")
            }
        };
        match self {
            Info::Mesh(m) => {
                s.push_str(&format!(
                    "kind: mesh\nvertices: {}\nfaces: {}\n",
                    m.vertices, m.faces
                ));
                bbox(&mut s, &m.bbox);
                s.push_str(&format!(
                    "area: {:.6}\nedges: {}\nboundary: {} edges in {} loops\nnon-manifold: {} edges, {} vertices\n\
                     components: {}\ndegenerate faces: {}\nduplicate positions: {}\nunreferenced vertices: {}\n\
                     attributes: {}\neuler characteristic: {}\n",
                    m.area,
                    m.topology.edges,
                    m.topology.boundary_edges,
                    m.topology.boundary_loops,
                    m.topology.non_manifold_edges,
                    m.topology.non_manifold_vertices,
                    m.topology.components,
                    m.degenerate_faces,
                    m.duplicate_positions,
                    m.topology.unreferenced_vertices,
                    attrs(&m.attributes),
                    m.euler_characteristic
                ));
                match m.genus {
                    Some(g) => s.push_str(&format!("closed manifold, genus {g}\n")),
                    None => s.push_str("not a closed manifold\n"),
                }
            }
            Info::Points(p) | Info::Range(p) => {
                let kind = if matches!(self, Info::Range(_)) {
                    "range image"
                } else {
                    "point cloud"
                };
                s.push_str(&format!("kind: {kind}\npoints: {}\n", p.points));
                bbox(&mut s, &p.bbox);
                s.push_str(&format!("attributes: {}\n", attrs(&p.attributes)));
                if let Some(g) = &p.grid {
                    s.push_str(&format!(
                        "grid: {} cols x {} rows, {} valid cells, pose {}\n",
                        g.cols,
                        g.rows,
                        g.valid_cells,
                        if g.has_pose { "known" } else { "unknown" }
                    ));
                }
            }
        }
        s
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    #[test]
    fn torus_is_genus_one_and_sphere_genus_zero() {
        let t = mesh_info(&shapes::torus(1.0, 0.25, 16, 8));
        assert_eq!((t.euler_characteristic, t.genus), (0, Some(1)));
        let s = mesh_info(&shapes::icosphere(4));
        assert_eq!((s.euler_characteristic, s.genus), (2, Some(0)));
        assert!(
            (s.area / (4.0 * std::f64::consts::PI) - 1.0).abs() < 0.01,
            "{}",
            s.area
        );
    }

    #[test]
    fn defects_are_counted() {
        let mut m = shapes::terrain(4, 4);
        m.positions.push(m.positions[0]); // a duplicate, unreferenced
        m.positions.push(glam::Vec3::new(0.5, 0.5, 7.0));
        let n = m.positions.len() as u32;
        // A zero-area sliver: three collinear points.
        m.positions
            .extend([glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::X * 2.0]);
        m.faces.push([n, n + 1, n + 2]);
        let i = mesh_info(&m);
        assert_eq!(i.duplicate_positions, 2); // the copy, and ZERO (= terrain corner 0)
        assert_eq!(i.topology.unreferenced_vertices, 2);
        assert_eq!(i.degenerate_faces, 1);
        assert_eq!(i.topology.components, 2);
        assert_eq!(i.genus, None);
        assert_eq!(i.attributes, vec!["uvs"]);
        let text = Info::Mesh(i).to_text();
        assert!(text.contains("degenerate faces: 1"), "{text}");
    }
}
