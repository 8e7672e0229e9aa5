//! Streaming a binary STL in bounded memory: the out-of-core simplifier's
//! reader for STL inputs (a billion triangles is 50 GB of STL).
//!
//! [`StlStream::open`] checks the size against the count as the in-core
//! reader does (`84 + 50 × count`, exactly); [`StlStream::for_each_triangle`]
//! then reads the facets once, in file order, through a 1 MiB buffer,
//! refusing a non-finite coordinate like the in-core reader. STL stores
//! every corner on its own, so the stream yields triangles of positions
//! (the out-of-core path welds them bitwise per block). ASCII STL is
//! refused with a message saying so (convert it to binary with `lodkit
//! convert`, or read it in core).

use std::fs::File;
use std::io::{BufReader, Read};
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::error::{Error, ParseError, Result};
use crate::parse_err;

const HEADER: u64 = 84;
const FACET: usize = 50;

/// An opened binary STL whose facets are read on demand.
#[derive(Debug)]
pub struct StlStream {
    path: PathBuf,
    count: u64,
}

impl StlStream {
    /// Opens `path` and checks its size against its count. Errors: I/O, a
    /// file that is not a binary STL (ASCII, a count that disagrees with
    /// the size). Cost: the header only.
    pub fn open(path: &Path) -> Result<StlStream> {
        let bad = |e| Error::parse(path, e);
        let (_, len, head) = crate::io::open_head(path, HEADER)?;
        let ascii = head.trim_ascii_start().starts_with(b"solid");
        let count = head
            .get(80..84)
            .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as u64);
        match count {
            Some(n) if HEADER + FACET as u64 * n == len => Ok(StlStream {
                path: path.to_path_buf(),
                count: n,
            }),
            _ if ascii => Err(bad(ParseError::new(
                "ASCII STL cannot be streamed; convert it to binary (lodkit convert) or give a smaller file",
            ))),
            None => Err(bad(parse_err!(
                "{len} bytes: too short for a binary STL (80-byte header + 4-byte count)"
            ))),
            Some(n) => Err(bad(parse_err!(
                "binary STL header says {n} triangles ({} bytes) but the file has {len} bytes",
                HEADER + FACET as u64 * n
            ))),
        }
    }

    /// Facets in the file.
    pub fn triangles(&self) -> u64 {
        self.count
    }

    /// Calls `f` with each facet's corners in file order. Errors: I/O, a
    /// non-finite coordinate, or whatever `f` returns. Memory: the buffer.
    pub fn for_each_triangle(&self, mut f: impl FnMut([Vec3; 3]) -> Result<()>) -> Result<()> {
        let io = |e| Error::io(&self.path, e);
        let mut file = File::open(&self.path).map_err(io)?;
        let mut head = [0u8; HEADER as usize];
        file.read_exact(&mut head).map_err(io)?;
        let mut r = BufReader::with_capacity(1 << 20, file);
        let mut rec = [0u8; FACET];
        for i in 0..self.count {
            r.read_exact(&mut rec).map_err(io)?;
            let c = |o: usize| f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
            let v = |o: usize| Vec3::new(c(o), c(o + 4), c(o + 8));
            let t = [v(12), v(24), v(36)];
            if t.iter().any(|p| !p.is_finite()) {
                return Err(Error::Parse {
                    path: self.path.clone(),
                    message: format!("facet {i} has a non-finite coordinate"),
                });
            }
            f(t)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_what_the_in_core_reader_reads_and_refuses_what_it_cannot() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.stl");
        let m = crate::shapes::icosphere(2);
        crate::io::save_mesh(&path, &m, Default::default()).unwrap();
        let s = StlStream::open(&path).unwrap();
        assert_eq!(s.triangles(), m.faces.len() as u64);
        let mut tris = Vec::new();
        s.for_each_triangle(|t| {
            tris.push(t);
            Ok(())
        })
        .unwrap();
        let faces: Vec<[Vec3; 3]> = m
            .faces
            .iter()
            .map(|f| f.map(|i| m.positions[i as usize]))
            .collect();
        assert_eq!(tris, faces);
        // A count that disagrees with the size; ASCII.
        let mut bytes = std::fs::read(&path).unwrap();
        bytes.pop();
        std::fs::write(&path, &bytes).unwrap();
        let e = StlStream::open(&path).unwrap_err().to_string();
        assert!(e.contains("s.stl") && e.contains("header says"), "{e}");
        std::fs::write(&path, "solid x\nendsolid x\n").unwrap();
        let e = StlStream::open(&path).unwrap_err().to_string();
        assert!(e.contains("ASCII STL cannot be streamed"), "{e}");
    }
}
