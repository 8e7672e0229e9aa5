//! Writing PLY: a header naming exactly the attributes present, then the
//! body in binary little-endian or ASCII.
//!
//! Layout (each line only when the attribute is present):
//! ```text
//! element vertex N
//! property float x / y / z
//! property float nx / ny / nz
//! property uchar red / green / blue / alpha
//! property float s / t
//! element face F                       (meshes only)
//! property list uchar int vertex_indices
//! ```
//! These are the names MeshLab and most tools read, and the ones our reader
//! maps back. ASCII floats use Rust's shortest round-trip formatting, so
//! reading the file back gives the same `f32` values bit for bit. The
//! output holds no timestamp or path: the same model gives the same bytes.

use std::io::{self, Write};

use glam::{Vec2, Vec3};

use crate::mesh::{PointCloud, TriMesh};

/// Appends `m` as a PLY file to `out`: binary little-endian, or ASCII when
/// `ascii`. Fails (writing nothing) when an attribute's length differs from
/// the vertex count, a face index is not below the vertex count, or the
/// vertex count does not fit PLY's `int` indices.
pub fn write_mesh(out: &mut Vec<u8>, m: &TriMesh, ascii: bool) -> io::Result<()> {
    let v = Vertices {
        positions: &m.positions,
        normals: m.normals.as_deref(),
        colors: m.colors.as_deref(),
        uvs: m.uvs.as_deref(),
    };
    v.check()?;
    if let Some((i, f)) = m
        .faces
        .iter()
        .enumerate()
        .find(|(_, f)| f.iter().any(|&x| x as usize >= m.positions.len()))
    {
        return Err(invalid(format!(
            "face {i} has index {} but the mesh has {} vertices",
            f.iter().max().copied().unwrap_or(0),
            m.positions.len()
        )));
    }
    write(out, &v, Some(&m.faces), ascii)
}

/// Appends `p` as a PLY point cloud (a `vertex` element only) to `out`:
/// binary little-endian, or ASCII when `ascii`. Fails (writing nothing)
/// when an attribute's length differs from the point count.
pub fn write_points(out: &mut Vec<u8>, p: &PointCloud, ascii: bool) -> io::Result<()> {
    let v = Vertices {
        positions: &p.positions,
        normals: p.normals.as_deref(),
        colors: p.colors.as_deref(),
        uvs: None,
    };
    v.check()?;
    write(out, &v, None, ascii)
}

struct Vertices<'a> {
    positions: &'a [Vec3],
    normals: Option<&'a [Vec3]>,
    colors: Option<&'a [[u8; 4]]>,
    uvs: Option<&'a [Vec2]>,
}

impl Vertices<'_> {
    fn check(&self) -> io::Result<()> {
        let n = self.positions.len();
        if i32::try_from(n).is_err() {
            return Err(invalid(format!(
                "{n} vertices is more than PLY int indices can address"
            )));
        }
        let lens = [
            ("normals", self.normals.map(<[_]>::len)),
            ("colors", self.colors.map(<[_]>::len)),
            ("uvs", self.uvs.map(<[_]>::len)),
        ];
        for (name, len) in lens {
            if let Some(l) = len.filter(|&l| l != n) {
                return Err(invalid(format!("{name} has {l} entries for {n} vertices")));
            }
        }
        Ok(())
    }

    /// Bytes per binary vertex record.
    fn stride(&self) -> usize {
        12 + self.normals.map_or(0, |_| 12)
            + self.colors.map_or(0, |_| 4)
            + self.uvs.map_or(0, |_| 8)
    }
}

fn invalid(msg: String) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidInput, msg)
}

fn write(
    out: &mut Vec<u8>,
    v: &Vertices<'_>,
    faces: Option<&[[u32; 3]]>,
    ascii: bool,
) -> io::Result<()> {
    let format = if ascii {
        "ascii"
    } else {
        "binary_little_endian"
    };
    writeln!(out, "ply\nformat {format} 1.0\ncomment written by lodkit")?;
    writeln!(out, "element vertex {}", v.positions.len())?;
    out.extend_from_slice(b"property float x\nproperty float y\nproperty float z\n");
    if v.normals.is_some() {
        out.extend_from_slice(b"property float nx\nproperty float ny\nproperty float nz\n");
    }
    if v.colors.is_some() {
        out.extend_from_slice(
            b"property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n",
        );
    }
    if v.uvs.is_some() {
        out.extend_from_slice(b"property float s\nproperty float t\n");
    }
    if let Some(faces) = faces {
        writeln!(out, "element face {}", faces.len())?;
        out.extend_from_slice(b"property list uchar int vertex_indices\n");
    }
    out.extend_from_slice(b"end_header\n");
    if ascii {
        write_ascii_body(out, v, faces)
    } else {
        write_binary_body(out, v, faces);
        Ok(())
    }
}

fn write_binary_body(out: &mut Vec<u8>, v: &Vertices<'_>, faces: Option<&[[u32; 3]]>) {
    let faces = faces.unwrap_or_default();
    out.reserve(v.positions.len() * v.stride() + faces.len() * 13);
    let put3 = |out: &mut Vec<u8>, p: Vec3| {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    };
    for (i, &p) in v.positions.iter().enumerate() {
        put3(out, p);
        if let Some(n) = v.normals.and_then(|n| n.get(i)) {
            put3(out, *n);
        }
        if let Some(c) = v.colors.and_then(|c| c.get(i)) {
            out.extend_from_slice(c);
        }
        if let Some(t) = v.uvs.and_then(|t| t.get(i)) {
            out.extend_from_slice(&t.x.to_le_bytes());
            out.extend_from_slice(&t.y.to_le_bytes());
        }
    }
    for f in faces {
        out.push(3);
        for &i in f {
            // `check` bounded every index by the vertex count, itself ≤ i32::MAX.
            out.extend_from_slice(&i.to_le_bytes());
        }
    }
}

fn write_ascii_body(
    out: &mut Vec<u8>,
    v: &Vertices<'_>,
    faces: Option<&[[u32; 3]]>,
) -> io::Result<()> {
    for (i, p) in v.positions.iter().enumerate() {
        write!(out, "{} {} {}", p.x, p.y, p.z)?;
        if let Some(n) = v.normals.and_then(|n| n.get(i)) {
            write!(out, " {} {} {}", n.x, n.y, n.z)?;
        }
        if let Some([r, g, b, a]) = v.colors.and_then(|c| c.get(i)) {
            write!(out, " {r} {g} {b} {a}")?;
        }
        if let Some(t) = v.uvs.and_then(|t| t.get(i)) {
            write!(out, " {} {}", t.x, t.y)?;
        }
        out.push(b'\n');
    }
    for [a, b, c] in faces.unwrap_or_default() {
        writeln!(out, "3 {a} {b} {c}")?;
    }
    Ok(())
}
