//! Streaming a binary PLY mesh in bounded memory: the out-of-core
//! simplifier's reader (inputs far larger than memory, past
//! [`MAX_FILE_BYTES`](crate::io::MAX_FILE_BYTES)).
//!
//! [`PlyStream::open`] reads and checks the header only; the vertex
//! positions and the faces are then read once each, in file order, through
//! a fixed 1 MiB buffer ([`PlyStream::for_each_position`] or
//! [`PlyStream::for_each_vertex`] with the attributes, then
//! [`PlyStream::for_each_face`]). Normals, colours and texture
//! coordinates are found and converted as the in-core reader does
//! (its property names, colour scaling). The same checks as the in-core
//! reader, through the same code: the header's ([`header::parse`], the
//! declared counts must fit in the file at their smallest record size),
//! the faces' (`read::checked_fan`: at least 3 indices, each below the
//! vertex count, no triangle repeating a corner) and the end's (no byte
//! after the last declared element, `read::check_end`); coordinates must
//! be finite and within range. Every problem is a one-line error naming
//! the file. Supported layout: binary (either endianness), a `vertex`
//! element whose properties are all scalars with float or double `x y z`,
//! alone (a point cloud, through [`PlyStream::open_points`]) or followed
//! by a `face` element whose only list holds the indices (any integer
//! types; polygons are fanned like the in-core reader); other scalar face
//! properties are skipped, elements after `face` must have fixed-size
//! records (they are skipped). Anything else is refused with a message
//! that says so (the in-core reader handles every layout).

use std::fs::File;
use std::io::{BufReader, Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

use super::header::{self, Encoding, PropertyKind, ScalarType};
use super::read::{VertexPlan, check_end, checked_fan, color_channel, to_index, vertex_plan};
use crate::error::{Error, ParseError, Result};
use crate::parse_err;

/// Bytes read ahead per `read` call.
const BUFFER: usize = 1 << 20;
/// The most header bytes read while looking for `end_header`.
const MAX_HEADER: usize = 1 << 20;

/// Which vertex attributes a streamed file carries besides positions.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct StreamAttributes {
    /// `nx ny nz`.
    pub normals: bool,
    /// `red green blue [alpha]` (or `diffuse_*`).
    pub colors: bool,
    /// `u v`, `s t`, `texture_u texture_v` or `texture_s texture_t`.
    pub uvs: bool,
}

/// One vertex of [`PlyStream::for_each_vertex`]: attributes the file does
/// not carry are zero.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StreamVertex {
    /// Position, object units.
    pub position: Vec3,
    /// Normal as stored (not renormalised).
    pub normal: Vec3,
    /// sRGB RGBA8 (alpha 255 when the file has none).
    pub color: [u8; 4],
    /// Texture coordinates.
    pub uv: Vec2,
}

/// An opened binary PLY mesh whose body is read on demand.
#[derive(Debug)]
pub struct PlyStream {
    path: PathBuf,
    big_endian: bool,
    body_start: u64,
    vertex_count: u64,
    vertex_stride: usize,
    /// Where each attribute sits in a vertex record.
    plan: VertexPlan,
    face_count: u64,
    /// Per face record: scalar bytes before the list, the list's count and
    /// item types, scalar bytes after it.
    face_layout: (usize, ScalarType, ScalarType, usize),
    /// Bytes of the (fixed-size) elements after `face`.
    tail_bytes: u64,
    file_len: u64,
}

impl PlyStream {
    /// Opens `path` and checks its header (see the module docs).
    /// Errors: I/O, a malformed header, a layout this reader does not
    /// stream, counts that cannot fit in the file. Cost: the header only.
    pub fn open(path: &Path) -> Result<PlyStream> {
        Self::open_with(path, false)
    }

    /// [`open`](Self::open) that also takes a point cloud: a file whose
    /// only element is `vertex` (then [`face_records`](Self::face_records)
    /// is 0 and [`for_each_face`](Self::for_each_face) only checks the
    /// file's end). The mesh readers use `open`, which refuses such a
    /// file, so a cloud never reaches them as a mesh of no faces.
    pub fn open_points(path: &Path) -> Result<PlyStream> {
        Self::open_with(path, true)
    }

    fn open_with(path: &Path, points: bool) -> Result<PlyStream> {
        let bad = |e| Error::parse(path, e);
        let (_, file_len, head) = crate::io::open_head(path, MAX_HEADER as u64)?;
        let h = header::parse(&head).map_err(bad)?;
        let body_len = file_len - h.body_start as u64;
        // check_counts takes usize; on 64-bit targets the cast is exact.
        h.check_counts(usize::try_from(body_len).unwrap_or(usize::MAX))
            .map_err(bad)?;
        let big_endian = match h.encoding {
            Encoding::Ascii => {
                return Err(bad(ParseError::new(
                    "ASCII PLY cannot be streamed; convert it to binary (lodkit convert) or give a smaller file",
                )));
            }
            Encoding::BinaryLittleEndian => false,
            Encoding::BinaryBigEndian => true,
        };
        let Some(v) = h.elements.first().filter(|v| v.name == "vertex") else {
            return Err(bad(ParseError::new(
                "streaming needs the vertex element first and the face element second",
            )));
        };
        // A point cloud: the vertex element alone.
        let fe = match h.elements.get(1) {
            None if points => None,
            None => {
                return Err(bad(ParseError::new(
                    "streaming needs a vertex element followed by a face element",
                )));
            }
            Some(fe) if fe.name == "face" => Some(fe),
            Some(_) => {
                return Err(bad(ParseError::new(
                    "streaming needs the vertex element first and the face element second",
                )));
            }
        };
        let vertex_stride = v.fixed_stride().ok_or_else(|| {
            bad(ParseError::new(
                "streaming needs vertex records of fixed size (no list property)",
            ))
        })?;
        let plan = vertex_plan(v).map_err(bad)?;
        for (name, slot) in ["x", "y", "z"].iter().zip(plan.position) {
            if !matches!(slot.ty, ScalarType::F32 | ScalarType::F64) {
                return Err(bad(parse_err!(
                    "vertex property '{name}' is {}, streaming reads float or double",
                    slot.ty.name()
                )));
            }
        }
        let Some(fe) = fe else {
            return Ok(PlyStream {
                path: path.to_path_buf(),
                big_endian,
                body_start: h.body_start as u64,
                vertex_count: v.count,
                vertex_stride,
                plan,
                face_count: 0,
                face_layout: (0, ScalarType::U8, ScalarType::U32, 0),
                tail_bytes: 0,
                file_len,
            });
        };
        let lists: Vec<usize> = (0..fe.properties.len())
            .filter(|&i| matches!(fe.properties[i].kind, PropertyKind::List { .. }))
            .collect();
        let [li] = lists[..] else {
            return Err(bad(ParseError::new(
                "streaming needs exactly one list property (the indices) in the face element",
            )));
        };
        let PropertyKind::List { count, item } = fe.properties[li].kind else {
            unreachable!("filtered to lists above")
        };
        if !item.is_integer() {
            return Err(bad(ParseError::new("face indices are not integers")));
        }
        let scalar_bytes = |ps: &[header::Property]| -> usize {
            ps.iter()
                .map(|p| match p.kind {
                    PropertyKind::Scalar(t) => t.size(),
                    PropertyKind::List { .. } => 0,
                })
                .sum()
        };
        let before = scalar_bytes(&fe.properties[..li]);
        let after = scalar_bytes(&fe.properties[li + 1..]);
        // Elements after the faces are skipped, but must end the file
        // exactly, as the in-core reader requires: fixed-size records only.
        let mut tail_bytes = 0u64;
        for e in &h.elements[2..] {
            let stride = e.fixed_stride().ok_or_else(|| {
                bad(parse_err!(
                    "streaming needs fixed-size records after the face element ({} has a list)",
                    e.name
                ))
            })?;
            // check_counts bounded every count by the file's size.
            tail_bytes = tail_bytes.saturating_add(e.count.saturating_mul(stride as u64));
        }
        Ok(PlyStream {
            path: path.to_path_buf(),
            big_endian,
            body_start: h.body_start as u64,
            vertex_count: v.count,
            vertex_stride,
            plan,
            face_count: fe.count,
            face_layout: (before, count, item, after),
            tail_bytes,
            file_len,
        })
    }

    /// The vertex attributes the file carries besides positions.
    pub fn attributes(&self) -> StreamAttributes {
        StreamAttributes {
            normals: self.plan.normal.is_some(),
            colors: self.plan.color.is_some(),
            uvs: self.plan.uv.is_some(),
        }
    }

    /// Vertices declared in the header.
    pub fn vertex_count(&self) -> u64 {
        self.vertex_count
    }

    /// Face records declared in the header (a polygon gives several
    /// triangles, a list under 3 none).
    pub fn face_records(&self) -> u64 {
        self.face_count
    }

    /// The file's size in bytes.
    pub fn file_len(&self) -> u64 {
        self.file_len
    }

    fn parse_error(&self, e: ParseError) -> Error {
        Error::parse(&self.path, e)
    }

    fn reader(&self, at: u64) -> Result<Reader> {
        let io = |e| Error::io(&self.path, e);
        let mut f = File::open(&self.path).map_err(io)?;
        f.seek(SeekFrom::Start(at)).map_err(io)?;
        Ok(Reader {
            inner: BufReader::with_capacity(BUFFER, f),
        })
    }

    fn truncated(&self, what: &str) -> Error {
        self.parse_error(parse_err!("file ends inside the {what} records"))
    }

    /// Calls `f` with each vertex position in file order. Errors: I/O, a
    /// truncated file, a non-finite coordinate or one past
    /// [`MAX_COORDINATE`](crate::io::MAX_COORDINATE). Memory: the buffer.
    pub fn for_each_position(&self, mut f: impl FnMut(Vec3)) -> Result<()> {
        self.vertices(false, |v| f(v.position))
    }

    /// [`for_each_position`](Self::for_each_position) with the attributes
    /// of [`attributes`](Self::attributes) (the others are zero), each
    /// converted as the in-core reader converts it.
    pub fn for_each_vertex(&self, f: impl FnMut(&StreamVertex)) -> Result<()> {
        self.vertices(true, f)
    }

    fn vertices(&self, attributes: bool, mut f: impl FnMut(&StreamVertex)) -> Result<()> {
        let mut r = self.reader(self.body_start)?;
        let mut rec = vec![0u8; self.vertex_stride];
        let big = self.big_endian;
        let mut v = StreamVertex::default();
        for i in 0..self.vertex_count {
            if !r.fill(&mut rec) {
                return Err(self.truncated("vertex"));
            }
            decode_vertex(&self.plan, &rec, big, attributes, &mut v);
            if !v
                .position
                .to_array()
                .iter()
                .all(|c| c.is_finite() && c.abs() <= crate::io::MAX_COORDINATE)
            {
                return Err(self.parse_error(parse_err!(
                    "vertex {i} has a non-finite or out-of-range coordinate"
                )));
            }
            f(&v);
        }
        Ok(())
    }

    /// Random access to the vertices through a cache of about
    /// `cache_bytes` (pages of 4 KiB, or of the whole cache when smaller;
    /// at least one vertex record): what the
    /// out-of-core partition uses instead of a table of every vertex, so
    /// its memory does not grow with the input. Pages of whole vertex
    /// records, direct-mapped; scans write vertices and faces in scan
    /// order, so a face's vertices are nearly always in the last pages
    /// read, and any order is still correct (a miss reads one page).
    /// Read [`for_each_vertex`](Self::for_each_vertex) first: this reader
    /// does not check coordinates again. Errors: I/O (when opened or on a
    /// miss).
    pub fn vertex_reader(&self, cache_bytes: usize) -> Result<VertexReader<'_>> {
        let per_page = (VERTEX_PAGE.min(cache_bytes) / self.vertex_stride.max(1)).max(1);
        let page_bytes = per_page * self.vertex_stride;
        let slots = (cache_bytes / page_bytes.max(1)).clamp(1, 1 << 16);
        let file = File::open(&self.path).map_err(|e| Error::Io {
            path: self.path.clone(),
            source: e,
        })?;
        Ok(VertexReader {
            s: self,
            file,
            per_page: per_page as u64,
            tags: vec![u64::MAX; slots],
            pages: vec![0u8; slots * page_bytes],
            page_bytes,
        })
    }

    /// Calls `f` with each triangle in file order (polygons fanned from
    /// their first corner), each face checked as the in-core reader checks
    /// it; then checks that the file ends where the header says. Errors:
    /// I/O, a truncated file, a face the in-core reader refuses (under 3
    /// indices, an index past the vertex count, a repeated corner), bytes
    /// after the last element, or whatever `f` returns. Memory: the buffer.
    pub fn for_each_face(&self, mut f: impl FnMut([u32; 3]) -> Result<()>) -> Result<()> {
        let start = self.body_start + self.vertex_count * self.vertex_stride as u64;
        let mut r = self.reader(start)?;
        let (before, count_t, item_t, after) = self.face_layout;
        let mut skip = vec![0u8; before.max(after)];
        let mut buf = [0u8; 8];
        let mut poly: Vec<u32> = Vec::new();
        let mut read = 0u64;
        let face = |fi: u64, msg: String| self.parse_error(parse_err!("face {fi}: {msg}"));
        for fi in 0..self.face_count {
            if !r.fill(&mut skip[..before]) || !r.fill(&mut buf[..count_t.size()]) {
                return Err(self.truncated("face"));
            }
            let n = read_scalar(&buf, count_t, self.big_endian);
            if !(0.0..=1e6).contains(&n) {
                return Err(face(fi, format!("lists {n} indices")));
            }
            poly.clear();
            for _ in 0..n as usize {
                if !r.fill(&mut buf[..item_t.size()]) {
                    return Err(self.truncated("face"));
                }
                let ix = read_scalar(&buf, item_t, self.big_endian);
                poly.push(to_index(ix).map_err(|m| face(fi, m))?);
            }
            if !r.fill(&mut skip[..after]) {
                return Err(self.truncated("face"));
            }
            read += (before + count_t.size() + poly.len() * item_t.size() + after) as u64;
            let fan = checked_fan(&poly, Some(self.vertex_count)).map_err(|m| face(fi, m))?;
            for t in fan {
                f(t)?;
            }
        }
        let end = start.saturating_add(read).saturating_add(self.tail_bytes);
        if end > self.file_len {
            return Err(self.truncated("last element's"));
        }
        check_end(self.file_len - end).map_err(|e| self.parse_error(e))
    }
}

/// Bytes of vertex records per page of a [`VertexReader`] (rounded down
/// to whole records). Small pages keep many regions of the file at once:
/// a face order that sweeps across rows of vertices (the streamed blob's
/// sides: one vertex from each of thousands of rows in turn) then holds
/// one page per row; with 1 MiB pages the same sweep missed on nearly
/// every corner and a 100 M-face partition took 274 s instead of 20.
const VERTEX_PAGE: usize = 4 << 10;

/// Random access to a [`PlyStream`]'s vertices ([`PlyStream::vertex_reader`]).
pub struct VertexReader<'a> {
    s: &'a PlyStream,
    file: File,
    per_page: u64,
    /// The page held by each slot (`u64::MAX`: none).
    tags: Vec<u64>,
    pages: Vec<u8>,
    page_bytes: usize,
}

impl VertexReader<'_> {
    /// Vertex `i` with the attributes of [`PlyStream::attributes`].
    /// Errors: an index past the vertex count, I/O.
    pub fn get(&mut self, i: u32) -> Result<StreamVertex> {
        let s = self.s;
        if i as u64 >= s.vertex_count {
            return Err(s.parse_error(parse_err!(
                "vertex index {i} but the file has {} vertices",
                s.vertex_count
            )));
        }
        let page = i as u64 / self.per_page;
        let slot = (page % self.tags.len() as u64) as usize;
        let base = slot * self.page_bytes;
        if self.tags[slot] != page {
            let first = page * self.per_page;
            let n = self.per_page.min(s.vertex_count - first) as usize * s.vertex_stride;
            let at = s.body_start + first * s.vertex_stride as u64;
            let io = |e| Error::io(&s.path, e);
            self.file.seek(SeekFrom::Start(at)).map_err(io)?;
            self.file
                .read_exact(&mut self.pages[base..base + n])
                .map_err(io)?;
            self.tags[slot] = page;
        }
        let off = base + (i as u64 % self.per_page) as usize * s.vertex_stride;
        let mut v = StreamVertex::default();
        decode_vertex(
            &s.plan,
            &self.pages[off..off + s.vertex_stride],
            s.big_endian,
            true,
            &mut v,
        );
        Ok(v)
    }
}

/// Decodes the vertex record `rec` with `plan` into `v` (the attributes
/// too when `attributes`), as the in-core reader converts them.
fn decode_vertex(plan: &VertexPlan, rec: &[u8], big: bool, attributes: bool, v: &mut StreamVertex) {
    let get = |s: super::read::Slot| read_scalar(&rec[s.offset..], s.ty, big);
    let vec3 =
        |s: [super::read::Slot; 3]| Vec3::new(get(s[0]) as f32, get(s[1]) as f32, get(s[2]) as f32);
    v.position = vec3(plan.position);
    if !attributes {
        return;
    }
    if let Some(s) = plan.normal {
        v.normal = vec3(s);
    }
    if let Some((rgb, alpha)) = plan.color {
        let [r, g, b] = rgb.map(|s| color_channel(get(s), s.ty));
        let a = alpha.map_or(255, |s| color_channel(get(s), s.ty));
        v.color = [r, g, b, a];
    }
    if let Some([s, t]) = plan.uv {
        v.uv = Vec2::new(get(s) as f32, get(t) as f32);
    }
}

struct Reader {
    inner: BufReader<File>,
}

impl Reader {
    /// Fills `out`; false at end of file (or an I/O error, reported as a
    /// truncation: the file changed or is unreadable under us).
    fn fill(&mut self, out: &mut [u8]) -> bool {
        self.inner.read_exact(out).is_ok()
    }
}

/// One scalar of type `t` at the start of `b`, as f64 (exact for every
/// PLY integer type and for floats), decoded by the in-core reader's
/// [`super::sources::decode_scalar`]. A `b` too short gives NaN, which
/// every caller refuses (coordinates must be finite, counts and indices
/// in range); callers pass buffers of the scalar's size anyway.
fn read_scalar(b: &[u8], t: ScalarType, big: bool) -> f64 {
    super::sources::decode_scalar(b, t, big).unwrap_or(f64::NAN)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The vertex reader gives every vertex as the sequential pass does,
    /// in any order, with a cache far smaller than the vertices (every
    /// page missed and read again), attributes included.
    #[test]
    fn random_access_through_a_tiny_cache_matches_the_sequential_pass() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.ply");
        let mut m = crate::shapes::blob_with_seed(2_000, 3);
        m.colors = Some(
            (0..m.positions.len())
                .map(|i| [i as u8, 7, 9, 255])
                .collect(),
        );
        m.uvs = Some(
            m.positions
                .iter()
                .map(|p| glam::Vec2::new(p.x, p.z))
                .collect(),
        );
        crate::io::save_mesh(&path, &m, Default::default()).unwrap();
        let s = PlyStream::open(&path).unwrap();
        assert!(s.attributes().colors && s.attributes().uvs && !s.attributes().normals);
        let mut all = Vec::new();
        s.for_each_vertex(|v| all.push(*v)).unwrap();
        assert_eq!(all.len(), m.positions.len());
        assert_eq!(all[5].color, [5, 7, 9, 255]);
        // 100 bytes: pages of 4 records of 24 bytes, one slot.
        let mut r = s.vertex_reader(100).unwrap();
        let n = all.len() as u32;
        for k in 0..3 * n {
            let i = (k.wrapping_mul(2_654_435_761)) % n;
            assert_eq!(r.get(i).unwrap(), all[i as usize], "vertex {i}");
        }
        assert!(r.get(n).is_err());
    }

    /// A vertex-only file streams as a cloud through `open_points` only;
    /// `open` (the mesh readers') refuses it.
    #[test]
    fn a_cloud_opens_as_points_not_as_a_mesh() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("c.ply");
        let c = crate::PointCloud {
            positions: vec![glam::Vec3::X, glam::Vec3::Y, glam::Vec3::Z],
            normals: None,
            colors: Some(vec![[1, 2, 3, 255]; 3]),
        };
        crate::io::save(&path, &crate::Model::Points(c), Default::default()).unwrap();
        let e = PlyStream::open(&path).unwrap_err().to_string();
        assert!(e.contains("followed by a face element"), "{e}");
        let s = PlyStream::open_points(&path).unwrap();
        assert_eq!((s.vertex_count(), s.face_records()), (3, 0));
        let mut colors = Vec::new();
        s.for_each_vertex(|v| colors.push(v.color)).unwrap();
        assert_eq!(colors, [[1, 2, 3, 255]; 3]);
        s.for_each_face(|_| panic!("no faces")).unwrap();
    }
}
