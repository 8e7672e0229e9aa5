//! Triangle soups on disk: the blocks' exchange format. A face is its
//! three corners, each a position and the attributes of the staging
//! folder's [`Layout`] (normal, RGBA8 colour, texture coordinates), all
//! little-endian, with no header, so a block file needs no global vertex
//! numbering and blocks can be written and read independently (on one
//! machine or on Ray workers sharing a folder). Vertices are recovered by
//! an exact (bitwise) weld over the position and every attribute: the
//! simplifier never moves a locked vertex, so a vertex shared by two
//! blocks has the same bits in both, and corners that differ in an
//! attribute stay apart, as the in-core simplifier's wedges do.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

use glam::{Vec2, Vec3};
use lodkit_mesh::TriMesh;
use lodkit_mesh::io::ply::stream::StreamVertex;
use rustc_hash::FxHashMap;

/// One corner of a soup face: a position and its attributes (those the
/// layout does not carry are zero).
pub type Corner = StreamVertex;

/// The attributes every corner of a staging folder's soups carries.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Layout {
    /// A normal (3 × f32).
    pub normals: bool,
    /// An RGBA8 colour.
    pub colors: bool,
    /// Texture coordinates (2 × f32).
    pub uvs: bool,
}

impl Layout {
    /// Bytes per corner.
    pub fn corner_bytes(self) -> usize {
        12 + 12 * self.normals as usize + 4 * self.colors as usize + 8 * self.uvs as usize
    }

    /// Bytes per face.
    pub fn face_bytes(self) -> u64 {
        3 * self.corner_bytes() as u64
    }

    /// The layout's name in a manifest: `n`, `c`, `u` for each attribute,
    /// `-` for none.
    pub fn tag(self) -> String {
        let s: String = [(self.normals, 'n'), (self.colors, 'c'), (self.uvs, 'u')]
            .iter()
            .filter(|x| x.0)
            .map(|x| x.1)
            .collect();
        if s.is_empty() { "-".into() } else { s }
    }

    /// The layout named `tag` ([`tag`](Self::tag)); None for anything else.
    pub fn from_tag(tag: &str) -> Option<Layout> {
        if tag == "-" {
            return Some(Layout::default());
        }
        if tag.is_empty() || !tag.chars().all(|c| "ncu".contains(c)) {
            return None;
        }
        Some(Layout {
            normals: tag.contains('n'),
            colors: tag.contains('c'),
            uvs: tag.contains('u'),
        })
    }

    /// The corner's bits in this layout (zeros for absent attributes):
    /// the weld key.
    pub(crate) fn key(self, c: &Corner) -> [u32; 9] {
        let p = c.position.to_array().map(f32::to_bits);
        let n = if self.normals {
            c.normal.to_array().map(f32::to_bits)
        } else {
            [0; 3]
        };
        let col = if self.colors {
            u32::from_le_bytes(c.color)
        } else {
            0
        };
        let uv = if self.uvs {
            c.uv.to_array().map(f32::to_bits)
        } else {
            [0; 2]
        };
        [p[0], p[1], p[2], n[0], n[1], n[2], col, uv[0], uv[1]]
    }
}

/// Appends one face to `w`.
pub fn put(w: &mut impl Write, layout: Layout, t: &[Corner; 3]) -> std::io::Result<()> {
    let mut b = [0u8; 3 * 36];
    let mut k = 0;
    let mut f32s = |b: &mut [u8], xs: &[f32]| {
        for x in xs {
            b[k..k + 4].copy_from_slice(&x.to_le_bytes());
            k += 4;
        }
    };
    for c in t {
        f32s(&mut b, &c.position.to_array());
        if layout.normals {
            f32s(&mut b, &c.normal.to_array());
        }
        if layout.colors {
            f32s(&mut b, &[f32::from_bits(u32::from_le_bytes(c.color))]);
        }
        if layout.uvs {
            f32s(&mut b, &c.uv.to_array());
        }
    }
    w.write_all(&b[..k])
}

/// Calls `f` with each face of the soup file `path` (in `layout`).
/// Errors: I/O, or a length that is not a whole number of faces.
pub fn for_each(
    path: &Path,
    layout: Layout,
    mut f: impl FnMut(&[Corner; 3]),
) -> std::io::Result<()> {
    let file = File::open(path)?;
    let fb = layout.face_bytes();
    if file.metadata()?.len() % fb != 0 {
        return Err(std::io::Error::other(format!(
            "{}: not a whole number of {fb}-byte faces",
            path.display()
        )));
    }
    let mut r = BufReader::with_capacity(1 << 20, file);
    let mut b = vec![0u8; fb as usize];
    let mut t = [Corner::default(); 3];
    loop {
        match r.read_exact(&mut b) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(e),
        }
        let mut k = 0;
        let mut next = || {
            let x = u32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
            k += 4;
            x
        };
        for c in &mut t {
            let v3 = |next: &mut dyn FnMut() -> u32| {
                Vec3::new(
                    f32::from_bits(next()),
                    f32::from_bits(next()),
                    f32::from_bits(next()),
                )
            };
            c.position = v3(&mut next);
            if layout.normals {
                c.normal = v3(&mut next);
            }
            if layout.colors {
                c.color = next().to_le_bytes();
            }
            if layout.uvs {
                let u = f32::from_bits(next());
                c.uv = Vec2::new(u, f32::from_bits(next()));
            }
        }
        f(&t);
    }
}

/// Faces in the soup file `path` (from its length).
pub fn faces_in(path: &Path, layout: Layout) -> std::io::Result<u64> {
    Ok(std::fs::metadata(path)?.len() / layout.face_bytes())
}

/// Welds soup faces into an indexed mesh with the layout's attributes,
/// vertices numbered in order of first appearance (deterministic).
/// Corners equal bit for bit (position and attributes) merge; `-0.0` and
/// `0.0` stay apart, as in the in-core weld.
pub struct Welder {
    layout: Layout,
    map: WeldMap,
    mesh: TriMesh,
}

/// The weld's map: positions alone (the common case of a huge scan) hash
/// and compare 12 bytes, not the 36 of the full key (the full key cost
/// a third of a 10 M-face out-of-core run in hashing and `memcmp`).
enum WeldMap {
    Positions(FxHashMap<[u32; 3], u32>),
    Attributes(FxHashMap<[u32; 9], u32>),
}

impl Welder {
    /// An empty welder for `layout`.
    pub fn new(layout: Layout) -> Welder {
        let mut mesh = TriMesh::default();
        if layout.normals {
            mesh.normals = Some(Vec::new());
        }
        if layout.colors {
            mesh.colors = Some(Vec::new());
        }
        if layout.uvs {
            mesh.uvs = Some(Vec::new());
        }
        let map = if layout == Layout::default() {
            WeldMap::Positions(FxHashMap::default())
        } else {
            WeldMap::Attributes(FxHashMap::default())
        };
        Welder { layout, map, mesh }
    }

    /// Adds one face.
    pub fn add(&mut self, t: &[Corner; 3]) {
        let mut f = [0u32; 3];
        for (k, c) in t.iter().enumerate() {
            let next = self.mesh.positions.len() as u32;
            f[k] = match &mut self.map {
                WeldMap::Positions(m) => *m
                    .entry(c.position.to_array().map(f32::to_bits))
                    .or_insert(next),
                WeldMap::Attributes(m) => *m.entry(self.layout.key(c)).or_insert(next),
            };
            if f[k] == next {
                push_vertex(&mut self.mesh, c);
            }
        }
        self.mesh.faces.push(f);
    }

    /// The welded mesh.
    pub fn finish(self) -> TriMesh {
        self.mesh
    }
}

/// Appends `c` as a vertex of `mesh`, with the attributes `mesh` has.
pub fn push_vertex(mesh: &mut TriMesh, c: &Corner) {
    mesh.positions.push(c.position);
    if let Some(n) = mesh.normals.as_mut() {
        n.push(c.normal);
    }
    if let Some(col) = mesh.colors.as_mut() {
        col.push(c.color);
    }
    if let Some(uv) = mesh.uvs.as_mut() {
        uv.push(c.uv);
    }
}

/// Corner `i` of `mesh` (attributes the mesh lacks are zero).
pub fn corner(mesh: &TriMesh, i: u32) -> Corner {
    let i = i as usize;
    Corner {
        position: mesh.positions[i],
        normal: mesh.normals.as_ref().map_or(Vec3::ZERO, |n| n[i]),
        color: mesh.colors.as_ref().map_or([0; 4], |c| c[i]),
        uv: mesh.uvs.as_ref().map_or(Vec2::ZERO, |u| u[i]),
    }
}

/// Writes `mesh`'s faces to `path` as a soup in `layout`, atomically
/// (temp file then rename), so a file under its final name is always
/// complete: that is what lets a rerun trust it.
pub fn write_mesh(path: &Path, layout: Layout, mesh: &TriMesh) -> std::io::Result<()> {
    let tmp = path.with_extension("partial");
    {
        let mut w = BufWriter::with_capacity(1 << 20, File::create(&tmp)?);
        for f in &mesh.faces {
            put(&mut w, layout, &f.map(|i| corner(mesh, i)))?;
        }
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}
