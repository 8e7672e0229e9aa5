//! The cloud read in passes and its points staged: one reader over a
//! vertex-only binary PLY or a LAS/LAZ file ([`Source`]), the fixed-size
//! record a staged point takes ([`Layout`]), and the buffered files of
//! the spill pass ([`Spill`]).

use std::io::Write;
use std::path::{Path, PathBuf};

use glam::Vec3;
use lodkit_mesh::PointCloud;
use lodkit_mesh::io::ply::stream::PlyStream;

use crate::{Error, Result};

/// One streamed point; attributes the source lacks are zero.
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct Point {
    pub(super) position: Vec3,
    pub(super) normal: Vec3,
    pub(super) color: [u8; 4],
}

/// A cloud read in passes.
pub(super) enum Source {
    Ply(Box<PlyStream>),
    Las(lodkit_mesh::io::LasStream),
}

impl Source {
    pub(super) fn open(path: &Path) -> Result<Source> {
        use lodkit_mesh::io::Format;
        match Format::from_path(path) {
            Some(Format::Ply) => {
                let s = PlyStream::open_points(path)?;
                if s.face_records() > 0 {
                    return Err(Error::Input(format!(
                        "{}: has faces; a point tileset out of core reads a vertex-only PLY",
                        path.display()
                    )));
                }
                Ok(Source::Ply(Box::new(s)))
            }
            Some(Format::Las) => Ok(Source::Las(lodkit_mesh::io::LasStream::open(path)?)),
            _ => Err(Error::Input(format!(
                "{}: a point tileset out of core reads a vertex-only binary PLY, LAS or LAZ",
                path.display()
            ))),
        }
    }

    /// Points the header declares.
    pub(super) fn len(&self) -> u64 {
        match self {
            Source::Ply(s) => s.vertex_count(),
            Source::Las(s) => s.len(),
        }
    }

    pub(super) fn layout(&self) -> Layout {
        match self {
            Source::Ply(s) => Layout {
                normals: s.attributes().normals,
                colors: s.attributes().colors,
            },
            Source::Las(s) => Layout {
                normals: false,
                colors: s.has_colors(),
            },
        }
    }

    pub(super) fn origin(&self) -> Option<[f64; 3]> {
        match self {
            Source::Ply(_) => None,
            Source::Las(s) => Some(s.origin()),
        }
    }

    /// Calls `f` with every point and its input index, in input order;
    /// with positions only (the rest zero) unless `attributes`.
    pub(super) fn for_each(
        &self,
        attributes: bool,
        f: &mut dyn FnMut(u32, &Point) -> Result<()>,
    ) -> Result<()> {
        let mut failed = None;
        let mut i = 0u32;
        match self {
            Source::Ply(s) => {
                let mut each = |p: &Point| {
                    if failed.is_none() {
                        if let Err(e) = f(i, p) {
                            failed = Some(e);
                        }
                        i = i.wrapping_add(1);
                    }
                };
                if attributes {
                    s.for_each_vertex(|v| {
                        each(&Point {
                            position: v.position,
                            normal: v.normal,
                            color: v.color,
                        })
                    })?;
                } else {
                    s.for_each_position(|position| {
                        each(&Point {
                            position,
                            ..Point::default()
                        })
                    })?;
                }
                // A vertex-only file ends with its last vertex, as the
                // in-core reader requires.
                s.for_each_face(|_| Ok(()))?;
            }
            Source::Las(s) => s.for_each(|position, color| {
                if failed.is_none() {
                    // z-up to the y-up frame of tile contents, as the job
                    // turns an in-core LAS cloud: (x, y, z) ↦ (x, z, −y).
                    let p = Point {
                        position: Vec3::new(position.x, position.z, -position.y),
                        normal: Vec3::ZERO,
                        color,
                    };
                    if let Err(e) = f(i, &p) {
                        failed = Some(e);
                    }
                    i = i.wrapping_add(1);
                }
            })?,
        }
        failed.map_or(Ok(()), Err)
    }
}

/// The raw record of a staged point: position, then the normal and the
/// colour when the cloud has them (little-endian `f32` bits, RGBA8).
#[derive(Clone, Copy, Debug)]
pub(super) struct Layout {
    pub(super) normals: bool,
    pub(super) colors: bool,
}

impl Layout {
    pub(super) fn size(self) -> usize {
        12 + if self.normals { 12 } else { 0 } + if self.colors { 4 } else { 0 }
    }

    pub(super) fn put(self, p: &Point, out: &mut Vec<u8>) {
        for v in p.position.to_array() {
            out.extend_from_slice(&v.to_le_bytes());
        }
        if self.normals {
            for v in p.normal.to_array() {
                out.extend_from_slice(&v.to_le_bytes());
            }
        }
        if self.colors {
            out.extend_from_slice(&p.color);
        }
    }

    /// The cloud of a staged file (none: empty), or of the byte range
    /// `at` of it.
    pub(super) fn read(self, path: &Path, at: Option<(u64, u64)>) -> Result<PointCloud> {
        let bytes = match at {
            None => match std::fs::read(path) {
                Ok(b) => b,
                Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
                Err(source) => {
                    return Err(Error::Io {
                        path: path.to_path_buf(),
                        source,
                    });
                }
            },
            Some((start, len)) => {
                use std::io::{Read, Seek, SeekFrom};
                let mut f = std::fs::File::open(path).map_err(io_err(path))?;
                f.seek(SeekFrom::Start(start)).map_err(io_err(path))?;
                let mut b = Vec::new();
                f.take(len).read_to_end(&mut b).map_err(io_err(path))?;
                b
            }
        };
        let n = bytes.len() / self.size();
        let mut c = PointCloud {
            positions: Vec::with_capacity(n),
            normals: self.normals.then(|| Vec::with_capacity(n)),
            colors: self.colors.then(|| Vec::with_capacity(n)),
        };
        let f = |b: &[u8], k: usize| f32::from_le_bytes([b[k], b[k + 1], b[k + 2], b[k + 3]]);
        for r in bytes.chunks_exact(self.size()) {
            c.positions.push(Vec3::new(f(r, 0), f(r, 4), f(r, 8)));
            let mut at = 12;
            if let Some(ns) = &mut c.normals {
                ns.push(Vec3::new(f(r, 12), f(r, 16), f(r, 20)));
                at = 24;
            }
            if let Some(cs) = &mut c.colors {
                cs.push([r[at], r[at + 1], r[at + 2], r[at + 3]]);
            }
        }
        Ok(c)
    }

    /// Appends `cloud` to `out`.
    pub(super) fn append(self, cloud: &PointCloud, out: &mut Vec<u8>) {
        out.reserve(cloud.positions.len() * self.size());
        for (i, &position) in cloud.positions.iter().enumerate() {
            let p = Point {
                position,
                normal: cloud.normals.as_ref().map_or(Vec3::ZERO, |n| n[i]),
                color: cloud.colors.as_ref().map_or([0; 4], |c| c[i]),
            };
            self.put(&p, out);
        }
    }
}

pub(super) fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// Files of raw points, one per slot, appended through buffers that are
/// written out together whenever they hold more than `cap` bytes (one
/// open file at a time, however many slots).
pub(super) struct Spill {
    pub(super) dir: PathBuf,
    pub(super) bufs: Vec<Vec<u8>>,
    pub(super) held: usize,
    pub(super) cap: usize,
}

impl Spill {
    pub(super) fn new(dir: &Path, slots: usize, cap: usize) -> Result<Spill> {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        Ok(Spill {
            dir: dir.to_path_buf(),
            bufs: vec![Vec::new(); slots],
            held: 0,
            cap,
        })
    }

    pub(super) fn file(dir: &Path, slot: usize) -> PathBuf {
        dir.join(format!("{slot}.pts"))
    }

    /// Appends `records` (whole staged records) to the file of `slot`.
    pub(super) fn put_bytes(&mut self, slot: usize, records: &[u8]) -> Result<()> {
        self.bufs[slot].extend_from_slice(records);
        self.held += records.len();
        if self.held > self.cap {
            self.flush()?;
        }
        Ok(())
    }

    pub(super) fn flush(&mut self) -> Result<()> {
        for (slot, buf) in self.bufs.iter_mut().enumerate() {
            if buf.is_empty() {
                continue;
            }
            let path = Self::file(&self.dir, slot);
            let mut f = std::fs::OpenOptions::new()
                .create(true)
                .append(true)
                .open(&path)
                .map_err(io_err(&path))?;
            f.write_all(buf).map_err(io_err(&path))?;
            *buf = Vec::new();
        }
        self.held = 0;
        Ok(())
    }
}
