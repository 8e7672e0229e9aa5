//! The out-of-core tiler's files in its staging folder: faces spilled by
//! cell (one soup file per octree node, written through buffers of
//! bounded size, so a level of any size is distributed with a few files
//! open at a time), and each finished tile (welded, refitted, with
//! normals and its cut edges) kept until the tileset is written.
//!
//! Both are lodkit's own staging files, read back by the same build or by
//! a rerun that resumes it; every length is checked against the file's
//! size before anything is allocated, so a damaged file is an error, not
//! a huge allocation.

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_scale::soup::{self, Corner, Layout};

use crate::{Error, Result};

/// Faces of one level distributed into per-node soup files under `dir`
/// (`N.soup` for node `N`). Faces wait in per-node buffers; when all the
/// buffers together pass `cap` bytes every buffer is appended to its file
/// and emptied, so memory stays at `cap` whatever the level's size.
pub struct Spill {
    dir: PathBuf,
    layout: Layout,
    bufs: Vec<Vec<u8>>,
    buffered: usize,
    cap: usize,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

impl Spill {
    /// A spill into `dir` (emptied first: files an interrupted run left
    /// are partial) for `nodes` nodes, buffering up to `cap` bytes.
    pub fn new(dir: &Path, layout: Layout, nodes: usize, cap: usize) -> Result<Spill> {
        if dir.exists() {
            std::fs::remove_dir_all(dir).map_err(io(dir))?;
        }
        std::fs::create_dir_all(dir).map_err(io(dir))?;
        Ok(Spill {
            dir: dir.to_path_buf(),
            layout,
            bufs: vec![Vec::new(); nodes],
            buffered: 0,
            cap: cap.max(1 << 16),
        })
    }

    /// The soup file of node `node` in `dir`.
    pub fn file(dir: &Path, node: usize) -> PathBuf {
        dir.join(format!("{node}.soup"))
    }

    /// Adds one face to node `node`'s file.
    pub fn put(&mut self, node: usize, t: &[Corner; 3]) -> Result<()> {
        let b = &mut self.bufs[node];
        let before = b.len();
        soup::put(b, self.layout, t).map_err(io(&self.dir))?;
        self.buffered += b.len() - before;
        if self.buffered >= self.cap {
            self.flush()?;
        }
        Ok(())
    }

    /// Appends every buffer to its file.
    fn flush(&mut self) -> Result<()> {
        for (node, b) in self.bufs.iter_mut().enumerate() {
            if b.is_empty() {
                continue;
            }
            let path = Self::file(&self.dir, node);
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&path)
                .map_err(io(&path))?;
            f.write_all(b).map_err(io(&path))?;
            b.clear();
        }
        self.buffered = 0;
        Ok(())
    }

    /// Flushes the last buffers and marks the spill complete (`done`, a
    /// file beside the folder), so a rerun reuses it.
    pub fn finish(mut self, done: &Path) -> Result<()> {
        self.flush()?;
        lodkit_mesh::io::write_atomic(done, b"spilled\n")?;
        Ok(())
    }

    /// The faces spilled to `node` in `dir`, welded (attributes of
    /// `layout`, vertices in order of first appearance); an empty mesh
    /// when none were.
    pub fn read(dir: &Path, node: usize, layout: Layout) -> Result<TriMesh> {
        let path = Self::file(dir, node);
        if !path.exists() {
            return Ok(TriMesh::default());
        }
        let mut w = soup::Welder::new(layout);
        soup::for_each(&path, layout, |t| w.add(t)).map_err(io(&path))?;
        Ok(w.finish())
    }
}

/// A finished tile in the staging folder: its mesh (positions, normals,
/// colours) and its cut edges (vertex index pairs).
pub struct StagedTile {
    /// The tile's triangles, skirts not yet hung.
    pub mesh: TriMesh,
    /// Its cut edges, in the direction their face walks them.
    pub cuts: Vec<[u32; 2]>,
}

const MAGIC: &[u8; 8] = b"lktile1\n";

impl StagedTile {
    /// Writes the tile to `path` atomically.
    pub fn write(&self, path: &Path) -> Result<()> {
        let m = &self.mesh;
        let mut b: Vec<u8> = Vec::with_capacity(16 + m.positions.len() * 28 + m.faces.len() * 12);
        b.extend_from_slice(MAGIC);
        let flags = m.normals.is_some() as u8 | (m.colors.is_some() as u8) << 1;
        b.push(flags);
        for n in [m.positions.len(), m.faces.len(), self.cuts.len()] {
            b.extend_from_slice(&(n as u32).to_le_bytes());
        }
        let v3 = |b: &mut Vec<u8>, v: &[Vec3]| {
            for p in v {
                for x in p.to_array() {
                    b.extend_from_slice(&x.to_le_bytes());
                }
            }
        };
        v3(&mut b, &m.positions);
        if let Some(n) = &m.normals {
            v3(&mut b, n);
        }
        if let Some(c) = &m.colors {
            for c in c {
                b.extend_from_slice(c);
            }
        }
        for f in &m.faces {
            for i in f {
                b.extend_from_slice(&i.to_le_bytes());
            }
        }
        for e in &self.cuts {
            for i in e {
                b.extend_from_slice(&i.to_le_bytes());
            }
        }
        lodkit_mesh::io::write_atomic(path, &b)?;
        Ok(())
    }

    /// Reads a tile [`write`](Self::write) wrote. Errors: I/O, or a file
    /// whose lengths do not add up (named).
    pub fn read(path: &Path) -> Result<StagedTile> {
        let b = std::fs::read(path).map_err(io(path))?;
        let bad = || Error::Input(format!("{}: not a whole staged tile", path.display()));
        if b.len() < 21 || &b[..8] != MAGIC {
            return Err(bad());
        }
        let flags = b[8];
        let u = |k: usize| u32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
        let (nv, nf, nc) = (u(9) as usize, u(13) as usize, u(17) as usize);
        let per_vertex = 12 + 12 * (flags & 1) as usize + 4 * ((flags >> 1) & 1) as usize;
        let want = 21u64 + nv as u64 * per_vertex as u64 + nf as u64 * 12 + nc as u64 * 8;
        if want != b.len() as u64 {
            return Err(bad());
        }
        let mut k = 21;
        let mut f32s = |n: usize| -> Vec<Vec3> {
            let v = (0..n)
                .map(|i| {
                    let o = k + 12 * i;
                    Vec3::new(
                        f32::from_bits(u(o)),
                        f32::from_bits(u(o + 4)),
                        f32::from_bits(u(o + 8)),
                    )
                })
                .collect();
            k += 12 * n;
            v
        };
        let positions = f32s(nv);
        let normals = (flags & 1 != 0).then(|| f32s(nv));
        let colors = (flags & 2 != 0).then(|| {
            let c = (0..nv)
                .map(|i| {
                    [
                        b[k + 4 * i],
                        b[k + 4 * i + 1],
                        b[k + 4 * i + 2],
                        b[k + 4 * i + 3],
                    ]
                })
                .collect();
            k += 4 * nv;
            c
        });
        let mut idx = |n: usize, per: usize| -> Vec<u32> {
            let v = (0..n * per).map(|i| u(k + 4 * i)).collect();
            k += 4 * n * per;
            v
        };
        let faces: Vec<[u32; 3]> = idx(nf, 3)
            .chunks_exact(3)
            .map(|c| [c[0], c[1], c[2]])
            .collect();
        let cuts: Vec<[u32; 2]> = idx(nc, 2).chunks_exact(2).map(|c| [c[0], c[1]]).collect();
        let mesh = TriMesh {
            positions,
            normals,
            colors,
            uvs: None,
            faces,
        };
        if mesh.validate().is_err() || cuts.iter().flatten().any(|&i| i as usize >= nv) {
            return Err(bad());
        }
        Ok(StagedTile { mesh, cuts })
    }
}
