//! Triangle soups on disk: the blocks' exchange format. A face is its
//! three corner positions, nine little-endian `f32` (36 bytes), with no
//! header, so a block file needs no global vertex numbering and blocks can
//! be written and read independently (on one machine or on Ray workers
//! sharing a folder). Vertices are recovered by an exact (bitwise) weld:
//! the simplifier never moves a locked vertex, so a vertex shared by two
//! blocks has the same bits in both.

use std::fs::File;
use std::io::{BufReader, BufWriter, Read, Write};
use std::path::Path;

use glam::Vec3;
use lodkit_mesh::TriMesh;
use rustc_hash::FxHashMap;

/// Bytes per face in a soup file.
pub const FACE_BYTES: u64 = 36;

/// Appends one face to `w`.
pub fn put(w: &mut impl Write, t: [Vec3; 3]) -> std::io::Result<()> {
    let mut b = [0u8; FACE_BYTES as usize];
    for (k, c) in t.iter().flat_map(|p| p.to_array()).enumerate() {
        b[4 * k..4 * k + 4].copy_from_slice(&c.to_le_bytes());
    }
    w.write_all(&b)
}

/// Calls `f` with each face of the soup file `path`. Errors: I/O, or a
/// length that is not a whole number of faces.
pub fn for_each(path: &Path, mut f: impl FnMut([Vec3; 3])) -> std::io::Result<()> {
    let file = File::open(path)?;
    if file.metadata()?.len() % FACE_BYTES != 0 {
        return Err(std::io::Error::other(format!(
            "{}: not a whole number of 36-byte faces",
            path.display()
        )));
    }
    let mut r = BufReader::with_capacity(1 << 20, file);
    let mut b = [0u8; FACE_BYTES as usize];
    loop {
        match r.read_exact(&mut b) {
            Ok(()) => {}
            Err(e) if e.kind() == std::io::ErrorKind::UnexpectedEof => return Ok(()),
            Err(e) => return Err(e),
        }
        let c = |k: usize| f32::from_le_bytes([b[4 * k], b[4 * k + 1], b[4 * k + 2], b[4 * k + 3]]);
        f([
            Vec3::new(c(0), c(1), c(2)),
            Vec3::new(c(3), c(4), c(5)),
            Vec3::new(c(6), c(7), c(8)),
        ]);
    }
}

/// Faces in the soup file `path` (from its length).
pub fn faces_in(path: &Path) -> std::io::Result<u64> {
    Ok(std::fs::metadata(path)?.len() / FACE_BYTES)
}

/// Welds soup faces into an indexed mesh, vertices numbered in order of
/// first appearance (deterministic). Positions equal bit for bit merge;
/// `-0.0` and `0.0` stay apart, as in the in-core weld.
#[derive(Default)]
pub struct Welder {
    map: FxHashMap<[u32; 3], u32>,
    mesh: TriMesh,
}

impl Welder {
    /// Adds one face.
    pub fn add(&mut self, t: [Vec3; 3]) {
        let mut f = [0u32; 3];
        for (k, p) in t.iter().enumerate() {
            let key = p.to_array().map(f32::to_bits);
            let next = self.mesh.positions.len() as u32;
            f[k] = *self.map.entry(key).or_insert(next);
            if f[k] == next {
                self.mesh.positions.push(*p);
            }
        }
        self.mesh.faces.push(f);
    }

    /// The welded mesh.
    pub fn finish(self) -> TriMesh {
        self.mesh
    }
}

/// Writes `mesh`'s faces to `path` as a soup, atomically (temp file then
/// rename), so a file under its final name is always complete: that is
/// what lets a rerun trust it.
pub fn write_mesh(path: &Path, mesh: &TriMesh) -> std::io::Result<()> {
    let tmp = path.with_extension("partial");
    {
        let mut w = BufWriter::with_capacity(1 << 20, File::create(&tmp)?);
        for f in &mesh.faces {
            put(&mut w, f.map(|i| mesh.positions[i as usize]))?;
        }
        w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
    }
    std::fs::rename(&tmp, path)
}
