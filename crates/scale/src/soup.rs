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
    let mut b = [0u8; MAX_FACE_BYTES];
    let k = encode(layout, t, &mut b);
    w.write_all(&b[..k])
}

/// Bytes of the largest face (every attribute).
pub(crate) const MAX_FACE_BYTES: usize = 3 * 36;

/// One face's bytes in `layout`, into `b`; returns their length.
pub(crate) fn encode(layout: Layout, t: &[Corner; 3], b: &mut [u8; MAX_FACE_BYTES]) -> usize {
    let mut k = 0;
    let mut f32s = |b: &mut [u8; MAX_FACE_BYTES], xs: &[f32]| {
        for x in xs {
            b[k..k + 4].copy_from_slice(&x.to_le_bytes());
            k += 4;
        }
    };
    for c in t {
        f32s(b, &c.position.to_array());
        if layout.normals {
            f32s(b, &c.normal.to_array());
        }
        if layout.colors {
            f32s(b, &[f32::from_bits(u32::from_le_bytes(c.color))]);
        }
        if layout.uvs {
            f32s(b, &c.uv.to_array());
        }
    }
    k
}

/// A checksum of a soup file's bytes (FNV-1a over little-endian 32-bit
/// words; a soup is always whole words): what the staging folder records
/// of each block file it writes, so that a rerun tells a file it wrote
/// from a damaged or changed one. Not a defence against a forger, who
/// can rewrite the record too; against truncation, a zeroed or swapped
/// file, a stray edit.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Sum(pub u64);

impl Sum {
    /// The checksum of no bytes.
    pub const NEW: Sum = Sum(0xcbf2_9ce4_8422_2325);

    /// Adds `bytes` (a whole number of words, but for a file's last
    /// piece, whose missing bytes count as zeros).
    pub fn add(&mut self, bytes: &[u8]) {
        for c in bytes.chunks(4) {
            let mut w = [0u8; 4];
            w[..c.len()].copy_from_slice(c);
            self.0 = (self.0 ^ u64::from(u32::from_le_bytes(w))).wrapping_mul(0x100_0000_01b3);
        }
    }

    /// The checksum of the file `path` and its length, read through a
    /// 1 MiB buffer. Errors: I/O.
    pub fn of_file(path: &Path) -> std::io::Result<(Sum, u64)> {
        let mut f = File::open(path)?;
        let mut buf = vec![0u8; 1 << 20];
        let (mut sum, mut len) = (Sum::NEW, 0u64);
        loop {
            // Fill the buffer whole (reads may be short), so words never
            // straddle two pieces.
            let mut filled = 0;
            while filled < buf.len() {
                match f.read(&mut buf[filled..]) {
                    Ok(0) => break,
                    Ok(n) => filled += n,
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => {}
                    Err(e) => return Err(e),
                }
            }
            sum.add(&buf[..filled]);
            len += filled as u64;
            if filled < buf.len() {
                return Ok((sum, len));
            }
        }
    }
}

/// The record beside a block output (`bNNNNN.sum` for `bNNNNN.out`): its
/// length and [`Sum`].
fn sum_path(path: &Path) -> std::path::PathBuf {
    path.with_extension("sum")
}

/// Whether `path` is a soup file in `layout` this staging folder wrote
/// whole: a regular file (not a link) whose length and checksum are those
/// of the record [`write_mesh`] put beside it. Cost: one read of the file.
pub fn is_intact(path: &Path, layout: Layout) -> bool {
    let Ok(meta) = std::fs::symlink_metadata(path) else {
        return false;
    };
    let record = sum_path(path);
    let recorded = std::fs::symlink_metadata(&record)
        .ok()
        .filter(|m| m.is_file() && m.len() < 64)
        .and_then(|_| std::fs::read_to_string(&record).ok())
        .and_then(|t| {
            let (len, sum) = t.trim().split_once(' ')?;
            Some((len.parse::<u64>().ok()?, u64::from_str_radix(sum, 16).ok()?))
        });
    let Some((len, sum)) = recorded else {
        return false;
    };
    meta.is_file()
        && meta.len() == len
        && len % layout.face_bytes() == 0
        && Sum::of_file(path).is_ok_and(|(s, l)| s == Sum(sum) && l == len)
}

/// Creates `path` for writing, as a new file: a file or link already
/// there (a killed run's leftover, or planted) is removed first, never
/// written through.
pub(crate) fn create_new(path: &Path) -> std::io::Result<File> {
    match std::fs::remove_file(path) {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(e),
    }
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(path)
}

/// Writes `bytes` to `path` atomically (a new temp file, synced, renamed).
pub(crate) fn write_small(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(".partial");
    let tmp = std::path::PathBuf::from(tmp);
    let mut f = create_new(&tmp)?;
    f.write_all(bytes)?;
    f.sync_all()?;
    std::fs::rename(&tmp, path)
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
/// (a new temp file, never one found there, then a rename), so a file
/// under its final name is always complete, and then its length and
/// [`Sum`] beside it (`.sum`): what lets a rerun trust it ([`is_intact`]).
pub fn write_mesh(path: &Path, layout: Layout, mesh: &TriMesh) -> std::io::Result<()> {
    let tmp = path.with_extension("partial");
    let (mut sum, mut len) = (Sum::NEW, 0u64);
    {
        let mut w = BufWriter::with_capacity(1 << 20, create_new(&tmp)?);
        let mut b = [0u8; MAX_FACE_BYTES];
        for f in &mesh.faces {
            let k = encode(layout, &f.map(|i| corner(mesh, i)), &mut b);
            sum.add(&b[..k]);
            len += k as u64;
            w.write_all(&b[..k])?;
        }
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    }
    std::fs::rename(&tmp, path)?;
    write_small(
        &sum_path(path),
        format!("{len} {:016x}\n", sum.0).as_bytes(),
    )
}
