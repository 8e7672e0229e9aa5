//! The geometry types every lodkit stage consumes and produces.
//!
//! Conventions (shared by all crates):
//! - positions are `f32` object-space units, whatever the file used;
//! - faces are counter-clockwise seen from outside (right-handed normal);
//! - colours are straight (non-premultiplied) sRGB RGBA8;
//! - UVs have their origin at the bottom-left (OpenGL / OBJ / PLY
//!   convention). glTF's top-left origin is flipped on read and write.

use glam::{Quat, Vec2, Vec3};

use crate::error::ParseError;

/// Axis-aligned bounding box. `Aabb::EMPTY` has `min > max`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// The smallest corner.
    pub min: Vec3,
    /// The largest corner.
    pub max: Vec3,
}

impl Aabb {
    /// The box of no points (`min = +∞`, `max = −∞`): the identity of
    /// [`Aabb::union`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// The smallest box holding every point ([`Aabb::EMPTY`] for none).
    pub fn from_points<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Aabb {
        let mut b = Aabb::EMPTY;
        for p in points {
            b.min = b.min.min(*p);
            b.max = b.max.max(*p);
        }
        b
    }
    /// Whether the box holds no point.
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x
    }
    /// `max − min`; zero for an empty box.
    pub fn size(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }
    /// Length of the diagonal; 0 for an empty box.
    pub fn diagonal(&self) -> f32 {
        self.size().length()
    }
    /// The midpoint of the box (meaningless for an empty box).
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }
    /// The smallest box holding both boxes.
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }
}

/// An indexed triangle mesh with optional per-vertex attributes.
///
/// Invariant (checked by [`TriMesh::validate`], which every reader calls):
/// every face index is `< positions.len()`, no face repeats an index, every
/// coordinate is finite, and each present attribute has one entry per vertex.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct TriMesh {
    /// Vertex positions, object-space units.
    pub positions: Vec<Vec3>,
    /// Per-vertex unit normals, when the mesh has them.
    pub normals: Option<Vec<Vec3>>,
    /// Per-vertex sRGB RGBA8 colours, when the mesh has them.
    pub colors: Option<Vec<[u8; 4]>>,
    /// Per-vertex texture coordinates (origin bottom-left), when present.
    pub uvs: Option<Vec<Vec2>>,
    /// Triangles as vertex indices, counter-clockwise seen from outside.
    pub faces: Vec<[u32; 3]>,
}

impl TriMesh {
    /// A mesh of positions and faces, no attributes (not validated).
    pub fn new(positions: Vec<Vec3>, faces: Vec<[u32; 3]>) -> Self {
        TriMesh {
            positions,
            faces,
            ..Default::default()
        }
    }
    /// `positions.len()`.
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }
    /// `faces.len()`.
    pub fn face_count(&self) -> usize {
        self.faces.len()
    }
    /// The box of every position (referenced or not).
    pub fn bbox(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
    /// The three corner positions of face `f`.
    #[inline]
    pub fn triangle(&self, f: usize) -> [Vec3; 3] {
        let [a, b, c] = self.faces[f];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }
    /// Total surface area in double precision, for sizing decisions (a
    /// lattice, an octree depth): each triangle's area computed in `f64`,
    /// faces with an index out of range and non-finite areas skipped, so
    /// it never panics on unchecked input. Cost: one pass over the faces.
    pub fn area_f64(&self) -> f64 {
        self.faces
            .iter()
            .filter(|f| f.iter().all(|&i| (i as usize) < self.positions.len()))
            .map(|f| {
                let [a, b, c] = f.map(|i| self.positions[i as usize].as_dvec3());
                0.5 * (b - a).cross(c - a).length()
            })
            .filter(|x| x.is_finite())
            .sum()
    }
    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.faces.len())
            .map(|f| triangle_area(self.triangle(f)) as f64)
            .sum()
    }
    /// Names of the attributes present, in a fixed order (for reports).
    pub fn attribute_names(&self) -> Vec<&'static str> {
        let mut v = Vec::new();
        if self.normals.is_some() {
            v.push("normals");
        }
        if self.colors.is_some() {
            v.push("colors");
        }
        if self.uvs.is_some() {
            v.push("uvs");
        }
        v
    }

    /// Checks the type invariant; the message names the first offending
    /// element. Readers turn this into a per-file error.
    pub fn validate(&self) -> Result<(), ParseError> {
        let n = self.positions.len();
        check_finite(&self.positions, "vertex")?;
        check_attr_len(n, self.normals.as_ref().map(Vec::len), "normals")?;
        check_attr_len(n, self.colors.as_ref().map(Vec::len), "colors")?;
        check_attr_len(n, self.uvs.as_ref().map(Vec::len), "uvs")?;
        if let Some(normals) = &self.normals {
            check_finite(normals, "normal")?;
        }
        if let Some(uvs) = &self.uvs
            && let Some(i) = uvs.iter().position(|t| !t.is_finite())
        {
            return Err(crate::parse_err!("uv {i} is not finite ({:?})", uvs[i]));
        }
        for (i, f) in self.faces.iter().enumerate() {
            for &v in f {
                if v as usize >= n {
                    return Err(crate::parse_err!(
                        "face {i} has index {v} but the mesh has {n} vertices"
                    ));
                }
            }
            if f[0] == f[1] || f[1] == f[2] || f[0] == f[2] {
                return Err(crate::parse_err!(
                    "face {i} repeats a vertex index ({} {} {})",
                    f[0],
                    f[1],
                    f[2]
                ));
            }
        }
        Ok(())
    }
}

/// A point cloud with optional per-point normals and colours.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PointCloud {
    /// Point positions, object-space units.
    pub positions: Vec<Vec3>,
    /// Per-point unit normals, when known.
    pub normals: Option<Vec<Vec3>>,
    /// Per-point sRGB RGBA8 colours, when known.
    pub colors: Option<Vec<[u8; 4]>>,
}

impl PointCloud {
    /// The number of points.
    pub fn len(&self) -> usize {
        self.positions.len()
    }
    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }
    /// The box of every point.
    pub fn bbox(&self) -> Aabb {
        Aabb::from_points(&self.positions)
    }
    /// Checks that every coordinate is finite and each attribute has one
    /// entry per point; the message names the first offending element.
    pub fn validate(&self) -> Result<(), ParseError> {
        let n = self.positions.len();
        check_finite(&self.positions, "point")?;
        check_attr_len(n, self.normals.as_ref().map(Vec::len), "normals")?;
        check_attr_len(n, self.colors.as_ref().map(Vec::len), "colors")?;
        if let Some(normals) = &self.normals {
            check_finite(normals, "normal")?;
        }
        Ok(())
    }
}

/// A rigid transform `world = rotation * local + translation`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pose {
    /// Unit quaternion, applied first.
    pub rotation: Quat,
    /// Added after the rotation.
    pub translation: Vec3,
}

impl Pose {
    /// No rotation, no translation.
    pub const IDENTITY: Pose = Pose {
        rotation: Quat::IDENTITY,
        translation: Vec3::ZERO,
    };
    /// A point from the local frame to the world.
    #[inline]
    pub fn apply(&self, p: Vec3) -> Vec3 {
        self.rotation * p + self.translation
    }
    /// A direction from the local frame to the world (no translation).
    #[inline]
    pub fn apply_vector(&self, v: Vec3) -> Vec3 {
        self.rotation * v
    }
}

/// A range image: a `rows × cols` lattice of scanner samples in row-major
/// order (cell = row × cols + col). Cells without a sample have
/// `valid[cell] == false`; their `points` entry is meaningless (zero).
/// Lattice neighbours are scan neighbours, which is what range-image
/// triangulation and normal estimation rely on.
#[derive(Debug, Clone, PartialEq)]
pub struct RangeImage {
    /// Lattice width.
    pub cols: usize,
    /// Lattice height.
    pub rows: usize,
    /// `rows * cols` points in the sensor's frame.
    pub points: Vec<Vec3>,
    /// `rows * cols` flags: whether the cell holds a sample.
    pub valid: Vec<bool>,
    /// `rows * cols` sRGB RGBA8 colours, when the scan has them.
    pub colors: Option<Vec<[u8; 4]>>,
    /// Sensor-to-world transform, when known (e.g. from a `.conf` file).
    pub pose: Option<Pose>,
}

impl RangeImage {
    /// The number of cells holding a sample.
    pub fn valid_count(&self) -> usize {
        self.valid.iter().filter(|v| **v).count()
    }
    /// The sample at `(row, col)` in the sensor's frame, if there is one.
    /// Panics outside the lattice.
    #[inline]
    pub fn cell(&self, row: usize, col: usize) -> Option<Vec3> {
        let i = row * self.cols + col;
        if self.valid[i] {
            Some(self.points[i])
        } else {
            None
        }
    }
    /// The valid samples as a point cloud in world space (pose applied).
    pub fn to_point_cloud(&self) -> PointCloud {
        let pose = self.pose.unwrap_or(Pose::IDENTITY);
        let idx: Vec<usize> = (0..self.points.len()).filter(|&i| self.valid[i]).collect();
        PointCloud {
            positions: idx.iter().map(|&i| pose.apply(self.points[i])).collect(),
            normals: None,
            colors: self
                .colors
                .as_ref()
                .map(|c| idx.iter().map(|&i| c[i]).collect()),
        }
    }
    /// Checks the lattice size, that valid cells are finite and that the
    /// colours have one entry per cell.
    pub fn validate(&self) -> Result<(), ParseError> {
        let n = self
            .rows
            .checked_mul(self.cols)
            .ok_or_else(|| ParseError::new("range grid size overflows"))?;
        if self.points.len() != n || self.valid.len() != n {
            return Err(crate::parse_err!(
                "range grid is {}x{} but has {} cells",
                self.cols,
                self.rows,
                self.points.len()
            ));
        }
        check_attr_len(n, self.colors.as_ref().map(Vec::len), "colors")?;
        for i in 0..n {
            if self.valid[i] && !self.points[i].is_finite() {
                return Err(crate::parse_err!(
                    "range cell {i} is not finite ({:?})",
                    self.points[i]
                ));
            }
        }
        Ok(())
    }
}

/// What a geometry file holds once decoded.
#[derive(Debug, Clone, PartialEq)]
pub enum Model {
    /// A triangle mesh (the file has faces).
    Mesh(TriMesh),
    /// Points with no connectivity.
    Points(PointCloud),
    /// One scanner's range image (a PLY `range_grid`).
    Range(RangeImage),
}

impl Model {
    /// `"mesh"`, `"point cloud"` or `"range image"` (for messages).
    pub fn kind(&self) -> &'static str {
        match self {
            Model::Mesh(_) => "mesh",
            Model::Points(_) => "point cloud",
            Model::Range(_) => "range image",
        }
    }
}

/// Area of a triangle.
#[inline]
pub fn triangle_area([a, b, c]: [Vec3; 3]) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

fn check_finite(v: &[Vec3], what: &str) -> Result<(), ParseError> {
    match v.iter().position(|p| !p.is_finite()) {
        Some(i) => Err(crate::parse_err!(
            "{what} {i} is not finite ({}, {}, {})",
            v[i].x,
            v[i].y,
            v[i].z
        )),
        None => Ok(()),
    }
}

fn check_attr_len(n: usize, len: Option<usize>, what: &str) -> Result<(), ParseError> {
    match len {
        Some(l) if l != n => Err(crate::parse_err!("{what} has {l} entries for {n} vertices")),
        _ => Ok(()),
    }
}
