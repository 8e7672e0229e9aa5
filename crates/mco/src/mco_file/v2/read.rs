//! Reading `.mco` version 2: the header, the chunk cursor and inflation,
//! each chunk's nodes, triangles, vertices and patches validated against
//! the tables read so far, and the prefix reader ([`McoStream`]).

use super::*;
pub(super) type Res<T> = std::result::Result<T, String>;

/// The fixed header of a version-2 file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// Whether the vertices carry the input's colours.
    pub has_colors: bool,
    /// Whether each vertex section ends with the positions' residuals
    /// (positions exact; set in every file lodkit writes). Without them
    /// positions are the quantised ones.
    pub exact_positions: bool,
    /// The lattice the model was built on.
    pub grid: Grid,
    /// Oriented samples the model was built from.
    pub input_samples: u64,
    /// Cracks the build left unpatched.
    pub unpatched: u64,
    /// Bits per quantised position axis.
    pub position_bits: u32,
    /// Vertices of the whole model.
    pub vertices: u32,
    /// Octree nodes of the whole model.
    pub nodes: u32,
    /// The highest LOD number of the whole model.
    pub max_lod: u32,
    /// Stored triangle indices of the whole model.
    pub triangle_indices: u32,
    /// Crack patches of the whole model.
    pub patches: u32,
    /// Crack-patch substitutions of the whole model.
    pub subs: u32,
    /// Dependency entries of the whole model.
    pub deps: u32,
    /// Chunks in the file.
    pub chunks: u32,
    /// Bytes of the whole file.
    pub file_bytes: u64,
}

impl Header {
    /// Bytes of the header at the start of a file: a prefix this long
    /// gives [`McoStream::header`].
    pub const BYTES: usize = HEADER_BYTES;
}

pub(super) fn le32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
pub(super) fn le64(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("8 bytes"))
}

/// Parses the header (the first [`HEADER_BYTES`] bytes).
pub fn parse_header(b: &[u8]) -> Res<Header> {
    if b.len() < HEADER_BYTES {
        return Err(format!(
            "not an .mco file: {} bytes, shorter than the {HEADER_BYTES}-byte header",
            b.len()
        ));
    }
    if b[..8] != MAGIC {
        return Err("not an .mco file: bad signature".into());
    }
    let version = le32(b, 8);
    if version != VERSION {
        return Err(format!(
            "unsupported .mco version {version} (this reader reads versions 1 and {VERSION})"
        ));
    }
    if crc32fast::hash(&b[..HEADER_BYTES - 4]) != le32(b, HEADER_BYTES - 4) {
        return Err("header checksum mismatch (corrupted file)".into());
    }
    let flags = le32(b, 12);
    if flags & !(FLAG_COLORS | FLAG_EXACT_POSITIONS) != 0 {
        return Err(format!("unknown flags {flags:#x}"));
    }
    let f = |at| f32::from_bits(le32(b, at));
    let grid = Grid {
        origin: Vec3::new(f(16), f(20), f(24)),
        cube: f(28),
        depth: le32(b, 32),
        resolution: le32(b, 36),
    };
    if !(grid.origin.is_finite() && grid.cube.is_finite() && grid.cube > 0.0)
        || grid.depth > KEY_BITS - 1
    {
        return Err("invalid lattice (origin, cube size or depth)".into());
    }
    let h = Header {
        has_colors: flags & FLAG_COLORS != 0,
        exact_positions: flags & FLAG_EXACT_POSITIONS != 0,
        grid,
        input_samples: le64(b, 40),
        unpatched: le64(b, 48),
        position_bits: le32(b, 56),
        vertices: le32(b, 60),
        nodes: le32(b, 64),
        max_lod: le32(b, 68),
        triangle_indices: le32(b, 72),
        patches: le32(b, 76),
        subs: le32(b, 80),
        deps: le32(b, 84),
        chunks: le32(b, 88),
        file_bytes: le64(b, 92),
    };
    if h.position_bits != position_bits(grid.depth) {
        return Err(format!(
            "{} position bits for octree depth {} (expected {})",
            h.position_bits,
            grid.depth,
            position_bits(grid.depth)
        ));
    }
    if h.nodes == 0 || h.chunks == 0 {
        return Err("the model has no nodes".into());
    }
    // Every chunk holds at least one byte per LOD step and one chunk head.
    let min_bytes = HEADER_BYTES as u64 + (CHUNK_HEAD_BYTES as u64 + 1) * h.chunks as u64;
    if h.file_bytes < min_bytes || h.max_lod as u64 > h.file_bytes {
        return Err("header counts do not fit the file size".into());
    }
    Ok(h)
}

/// A bounds-checked cursor over one chunk's payload.
pub(super) struct Cursor<'a> {
    b: &'a [u8],
    at: usize,
}

impl Cursor<'_> {
    fn left(&self) -> usize {
        self.b.len() - self.at
    }
    fn u8(&mut self) -> Res<u8> {
        let x = *self.b.get(self.at).ok_or("record truncated")?;
        self.at += 1;
        Ok(x)
    }
    fn f32(&mut self) -> Res<f32> {
        let s = self.b.get(self.at..self.at + 4).ok_or("record truncated")?;
        self.at += 4;
        Ok(f32::from_le_bytes(s.try_into().expect("4 bytes")))
    }
    /// A varint of at most 10 bytes (below 2^64).
    fn var64(&mut self) -> Res<u64> {
        let mut x = 0u64;
        for i in 0..10 {
            let b = self.u8()?;
            if i == 9 && b > 1 {
                break;
            }
            x |= ((b & 0x7F) as u64) << (7 * i);
            if b & 0x80 == 0 {
                return Ok(x);
            }
        }
        Err("varint overflows 64 bits".into())
    }
    fn var(&mut self) -> Res<u32> {
        let mut x = 0u64;
        for i in 0..5 {
            let b = self.u8()?;
            x |= ((b & 0x7F) as u64) << (7 * i);
            if b & 0x80 == 0 {
                return u32::try_from(x).map_err(|_| "varint overflows 32 bits".into());
            }
        }
        Err("varint longer than 5 bytes".into())
    }
    /// A count of elements that each take at least `min_bytes` more bytes.
    fn count(&mut self, min_bytes: usize, what: &str) -> Res<usize> {
        let n = self.var()? as usize;
        if n.saturating_mul(min_bytes) > self.left() {
            return Err(format!("{what} count {n} exceeds the chunk"));
        }
        Ok(n)
    }
}

/// One chunk of a version-2 file, as `lodkit mco info` lists it.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ChunkInfo {
    /// Byte offset of the chunk head in the file.
    pub offset: u64,
    /// Bytes of the chunk, head included.
    pub bytes: u64,
    /// Bytes of its payload once inflated.
    pub payload_bytes: u64,
    /// The LOD numbers it completes: `first_lod..=last_lod`.
    pub first_lod: u32,
    /// The last LOD number it completes (a prefix through this chunk
    /// serves LOD numbers `0..=last_lod`).
    pub last_lod: u32,
    /// Nodes the model holds after this chunk.
    pub nodes: u32,
    /// Vertices the model holds after this chunk.
    pub vertices: u32,
    /// Triangle indices the model holds after this chunk.
    pub triangle_indices: u32,
}

/// A prefix of a version-2 file, read as far as its complete chunks go.
#[derive(Debug, Clone)]
pub struct PartialModel {
    /// The highest LOD number served (the model's `max_lod()`).
    pub max_lod: usize,
    /// True when every chunk was present (the model is the whole file's).
    pub complete: bool,
    /// Complete chunks read.
    pub chunks: usize,
    /// The model of those chunks: every cut up to `max_lod` is the whole
    /// file's cut.
    pub model: McoModel,
}

/// Incremental reader of a version-2 file: push bytes as they arrive, and
/// take [`McoStream::model`] after any push that completed a chunk.
///
/// Memory is the bytes of the one incomplete chunk plus the model read so
/// far. After an error the stream stays failed (every later push returns
/// the same error).
#[derive(Debug, Default)]
pub struct McoStream {
    pending: Vec<u8>,
    /// File offset of `pending[0]`.
    offset: u64,
    header: Option<Header>,
    model: McoModel,
    vertices: u32,
    chunks: Vec<ChunkInfo>,
    failed: Option<String>,
}

impl McoStream {
    /// An empty stream, waiting for the header.
    pub fn new() -> McoStream {
        McoStream::default()
    }

    /// The header, once its bytes have arrived.
    pub fn header(&self) -> Option<&Header> {
        self.header.as_ref()
    }

    /// Complete chunks read so far, in file order.
    pub fn chunks(&self) -> &[ChunkInfo] {
        &self.chunks
    }

    /// The highest LOD number served so far (`None` before chunk 0).
    pub fn max_lod(&self) -> Option<usize> {
        self.chunks.last().map(|c| c.last_lod as usize)
    }

    /// True once every chunk the header announces has been read.
    pub fn is_complete(&self) -> bool {
        self.header
            .is_some_and(|h| self.chunks.len() == h.chunks as usize)
    }

    /// Bytes consumed so far (header and complete chunks).
    pub fn bytes_read(&self) -> u64 {
        self.offset
    }

    /// Appends `bytes` and reads every chunk they complete. Returns whether
    /// at least one chunk was completed (a new model is available). Errors
    /// (one line) on a bad header or chunk, or bytes past the file's end.
    /// Cost: linear in the bytes pushed.
    pub fn push(&mut self, bytes: &[u8]) -> crate::Result<bool> {
        self.push_bytes(bytes).map_err(crate::Error::Format)
    }

    /// [`McoStream::push`] with the message alone (the whole-file readers
    /// below feed their bytes through it).
    fn push_bytes(&mut self, bytes: &[u8]) -> Res<bool> {
        if let Some(e) = &self.failed {
            return Err(e.clone());
        }
        self.pending.extend_from_slice(bytes);
        let r = self.drain();
        if let Err(e) = &r {
            self.failed = Some(e.clone());
            self.pending = Vec::new();
        }
        r
    }

    fn drain(&mut self) -> Res<bool> {
        let mut progressed = false;
        let mut used = 0usize;
        if self.header.is_none() {
            if self.pending.len() < HEADER_BYTES {
                if self.pending.len() >= 12 && self.pending[..8] == MAGIC {
                    // Refuse another version as soon as it shows.
                    let v = le32(&self.pending, 8);
                    if v != VERSION {
                        return Err(format!(
                            "unsupported .mco version {v} for streaming (only version {VERSION} streams)"
                        ));
                    }
                } else if self.pending.len() >= 8 && self.pending[..8] != MAGIC {
                    return Err("not an .mco file: bad signature".into());
                }
                return Ok(false);
            }
            self.header = Some(parse_header(&self.pending)?);
            used = HEADER_BYTES;
            self.offset = HEADER_BYTES as u64;
        }
        let h = self.header.expect("set above");
        loop {
            let rest = &self.pending[used..];
            if self.chunks.len() == h.chunks as usize {
                if !rest.is_empty() {
                    return Err(format!(
                        "{} bytes after the last chunk (the file should end at byte {})",
                        rest.len(),
                        h.file_bytes
                    ));
                }
                break;
            }
            if rest.len() < CHUNK_HEAD_BYTES {
                break;
            }
            let len = le32(rest, 0) as u64;
            if self.offset + CHUNK_HEAD_BYTES as u64 + len > h.file_bytes {
                return Err(format!(
                    "chunk {} at byte {} runs past the file's {} bytes",
                    self.chunks.len(),
                    self.offset,
                    h.file_bytes
                ));
            }
            if (rest.len() as u64) < CHUNK_HEAD_BYTES as u64 + len {
                break;
            }
            let total = CHUNK_HEAD_BYTES + len as usize;
            let stored = &rest[CHUNK_HEAD_BYTES..total];
            if crc32fast::hash(stored) != le32(rest, 4) {
                return Err(format!(
                    "chunk {} at byte {}: checksum mismatch (corrupted file)",
                    self.chunks.len(),
                    self.offset
                ));
            }
            let payload = inflate(stored, le32(rest, 8))
                .map_err(|e| format!("chunk {} at byte {}: {e}", self.chunks.len(), self.offset))?;
            let first_lod = self.model.groups.len() as u32;
            read_chunk(
                &h,
                &mut self.model,
                &mut self.vertices,
                &payload,
                self.chunks.is_empty(),
            )
            .map_err(|e| format!("chunk {} at byte {}: {e}", self.chunks.len(), self.offset))?;
            self.chunks.push(ChunkInfo {
                offset: self.offset,
                bytes: total as u64,
                payload_bytes: payload.len() as u64,
                first_lod: if self.chunks.is_empty() { 0 } else { first_lod },
                last_lod: self.model.groups.len() as u32 - 1,
                nodes: self.model.nodes.len() as u32,
                vertices: self.vertices,
                triangle_indices: self.model.tris.len() as u32,
            });
            self.offset += total as u64;
            used += total;
            progressed = true;
            if self.chunks.len() == h.chunks as usize {
                check_totals(&h, &self.model, self.offset)?;
            }
        }
        self.pending.drain(..used);
        Ok(progressed)
    }

    /// The model truncated to the LOD numbers read so far (see the module
    /// docs), prepared for extraction; `None` before chunk 0 is complete.
    /// Cost: a copy of the arrays read, and building the extraction tables
    /// (`O(n log n)` in the triangles).
    pub fn model(&self) -> Option<McoModel> {
        self.snapshot().ok()
    }

    fn snapshot(&self) -> Res<McoModel> {
        if self.chunks.is_empty() {
            return Err("no complete chunk yet (chunk 0 serves LOD 0)".into());
        }
        let mut m = self.model.clone();
        let n = m.nodes.len() as u32;
        for (i, nd) in m.nodes.iter().enumerate() {
            for p in &mut m.patches[nd.patch_start as usize..][..nd.patch_count as usize] {
                if p.coarse >= n {
                    p.coarse = i as u32;
                }
            }
        }
        crate::mco_file::validate::validate(&m)?;
        m.prepare_extraction();
        Ok(m)
    }

    /// The stream's state as a [`PartialModel`] (`None` before chunk 0).
    pub fn partial(&self) -> Option<PartialModel> {
        let model = self.model()?;
        Some(PartialModel {
            max_lod: model.max_lod(),
            complete: self.is_complete(),
            chunks: self.chunks.len(),
            model,
        })
    }
}

/// A chunk's payload from its stored bytes: deflated when `raw > 0`
/// (then exactly `raw` bytes, at most [`MAX_EXPANSION`] times the stored
/// ones), else stored as it is.
pub(super) fn inflate(stored: &[u8], raw: u32) -> Res<Vec<u8>> {
    if raw == 0 {
        return Ok(stored.to_vec());
    }
    if raw as u64 > MAX_EXPANSION * stored.len() as u64 + EXPANSION_SLACK {
        return Err(format!(
            "{raw} bytes deflated into {} (more than {MAX_EXPANSION} times)",
            stored.len()
        ));
    }
    let out = miniz_oxide::inflate::decompress_to_vec_with_limit(stored, raw as usize)
        .map_err(|_| format!("bad deflate stream (or more than {raw} bytes)"))?;
    if out.len() != raw as usize {
        return Err(format!("inflates to {} bytes, not {raw}", out.len()));
    }
    Ok(out)
}

pub(super) fn check_totals(h: &Header, m: &McoModel, end: u64) -> Res<()> {
    let got = [
        m.vertices.len() as u64,
        m.nodes.len() as u64,
        m.max_lod() as u64,
        m.tris.len() as u64,
        m.patches.len() as u64,
        m.subs.len() as u64,
        m.deps.len() as u64,
        end,
    ];
    let want = [
        h.vertices as u64,
        h.nodes as u64,
        h.max_lod as u64,
        h.triangle_indices as u64,
        h.patches as u64,
        h.subs as u64,
        h.deps as u64,
        h.file_bytes,
    ];
    if got != want {
        return Err("the chunks do not add up to the header's totals".into());
    }
    Ok(())
}

/// Reads one vertex reference: 0 = the next new vertex, `d` = `d` before it.
pub(super) fn vertex_ref(r: &mut Cursor, vertices: &mut u32, limit: u32) -> Res<u32> {
    let d = r.var()?;
    if d == 0 {
        if *vertices >= limit {
            return Err("more vertices than the header announces".into());
        }
        *vertices += 1;
        return Ok(*vertices - 1);
    }
    if d > *vertices {
        return Err(format!(
            "vertex reference {d} back from {} vertices",
            *vertices
        ));
    }
    Ok(*vertices - d)
}

/// Reads a node record (the node becoming drawable) and appends the node.
pub(super) fn read_node(
    h: &Header,
    m: &mut McoModel,
    vertices: &mut u32,
    r: &mut Cursor,
    parent: Option<u32>,
) -> Res<()> {
    let me = m.nodes.len() as u32;
    if me >= h.nodes {
        return Err("more nodes than the header announces".into());
    }
    let head = r.u8()?;
    let config = r.u8()?;
    let tri_count = r.u8()? as usize;
    let patch_count = (head >> 4) as usize;
    if head & 0x80 != 0 || patch_count > 6 {
        return Err(format!("node {me}: bad record head {head:#x}"));
    }
    if tri_count > MAX_NODE_TRIANGLES {
        return Err(format!(
            "node {me}: {tri_count} triangles (at most {MAX_NODE_TRIANGLES})"
        ));
    }
    let (coord, level) = if head & EXPLICIT != 0 {
        let c = [r.var()?, r.var()?, r.var()?];
        (c, r.u8()?)
    } else {
        let Some(p) = parent else {
            return Err("the root's coordinates are missing".into());
        };
        let pn = &m.nodes[p as usize];
        let oct = head & 7;
        if pn.coord.iter().any(|&x| x >= 1 << 31) {
            return Err(format!("node {me}: coordinates overflow"));
        }
        let c = std::array::from_fn(|a| 2 * pn.coord[a] + (oct as u32 >> a & 1));
        (c, pn.level - 1)
    };
    if level as u32 > h.grid.depth {
        return Err(format!("node {me}: level {level} above the octree depth"));
    }
    let tri_start = m.tris.len() as u32;
    if tri_count * 3 > r.left() {
        return Err(format!("node {me}: triangles run past the chunk"));
    }
    for _ in 0..3 * tri_count {
        let v = vertex_ref(r, vertices, h.vertices)?;
        m.tris.push(v);
    }
    let patch_start = m.patches.len() as u32;
    for _ in 0..patch_count {
        let d = unzigzag(r.var()?);
        let q = me as i64 - d;
        if q < 0 || q >= h.nodes as i64 {
            return Err(format!("node {me}: crack-patch neighbour {q} out of range"));
        }
        let subs = r.count(2, "substitution")?;
        if subs > MAX_PATCH_SUBS {
            return Err(format!("node {me}: {subs} substitutions in one patch"));
        }
        let subs_start = m.subs.len() as u32;
        for _ in 0..subs {
            let a = vertex_ref(r, vertices, h.vertices)?;
            let b = vertex_ref(r, vertices, h.vertices)?;
            m.subs.push([a, b]);
        }
        m.patches.push(Patch {
            coarse: q as u32,
            subs_start,
            subs_count: subs as u32,
        });
    }
    m.nodes.push(Node {
        coord,
        parent: parent.unwrap_or(u32::MAX),
        first_child: 0,
        tri_start,
        patch_start,
        deps_start: 0,
        tri_count: tri_count as u16,
        deps_count: 0,
        child_count: 0,
        level,
        patch_count: patch_count as u8,
        config,
    });
    m.metric.push(0.0);
    m.prio.push(u32::MAX);
    Ok(())
}

/// Reads one chunk's payload into `m` (the model read so far).
pub(super) fn read_chunk(
    h: &Header,
    m: &mut McoModel,
    vertices: &mut u32,
    b: &[u8],
    first: bool,
) -> Res<()> {
    let mut r = Cursor { b, at: 0 };
    let steps = r.count(1, "LOD step")?;
    // The vertex section holds every vertex this chunk's records introduce,
    // the root's (chunk 0) included.
    let first_new_vertex = *vertices;
    if first {
        m.grid = h.grid;
        m.has_colors = h.has_colors;
        m.stats = BuildStats {
            input_samples: h.input_samples,
            unpatched: h.unpatched,
        };
        read_node(h, m, vertices, &mut r, None)?;
        m.groups.push(0);
        m.acc.push(m.nodes[0].tri_count as u32);
    } else if steps == 0 {
        return Err("a chunk after the first serves no LOD number".into());
    }
    if m.groups.len() as u64 + steps as u64 > h.max_lod as u64 + 1 {
        return Err("more LOD numbers than the header announces".into());
    }
    for _ in 0..steps {
        let k = m.groups.len() as u32;
        let expand = r.count(7, "expanded node")?;
        let mut acc = *m.acc.last().expect("chunk 0 pushed acc[0]") as u64;
        for _ in 0..expand {
            let n = r.var()?;
            let Some(nd) = m.nodes.get(n as usize).copied() else {
                return Err(format!("LOD {k}: node {n} has not appeared"));
            };
            if m.prio[n as usize] != u32::MAX || nd.level == 0 {
                return Err(format!("LOD {k}: node {n} cannot expand"));
            }
            let metric = r.f32()?;
            let children = r.u8()?;
            if !(1..=8).contains(&children) {
                return Err(format!("LOD {k}: node {n} has {children} children"));
            }
            let deps = r.count(1, "dependency")?;
            if deps > u16::MAX as usize {
                return Err(format!("LOD {k}: node {n} has {deps} dependencies"));
            }
            let deps_start = m.deps.len() as u32;
            for _ in 0..deps {
                let q = n as i64 - unzigzag(r.var()?);
                if q < 0 || q >= m.nodes.len() as i64 {
                    return Err(format!("LOD {k}: node {n}'s dependency {q} out of range"));
                }
                m.deps.push(q as u32);
            }
            let first_child = m.nodes.len() as u32;
            {
                let x = &mut m.nodes[n as usize];
                x.first_child = first_child;
                x.child_count = children;
                x.deps_start = deps_start;
                x.deps_count = deps as u16;
            }
            m.metric[n as usize] = metric;
            m.prio[n as usize] = k;
            m.lod.push(n);
            acc = acc.saturating_sub(nd.tri_count as u64);
            for _ in 0..children {
                read_node(h, m, vertices, &mut r, Some(n))?;
                acc += m.nodes.last().expect("pushed").tri_count as u64;
            }
        }
        m.groups.push(m.lod.len() as u32);
        m.acc.push(acc as u32);
    }
    let new = (*vertices - first_new_vertex) as u64;
    let bits = h.position_bits;
    // Fixed-size part, then (exact positions) one varint of at least one
    // byte per coordinate.
    let fixed = vertex_section_bytes(new, bits, h.has_colors);
    let least = fixed + if h.exact_positions { 3 * new } else { 0 };
    let left = r.left() as u64;
    if left < least || (!h.exact_positions && left != fixed) {
        return Err(format!(
            "{left} bytes left for {new} new vertices (expected {}{least})",
            if h.exact_positions { "at least " } else { "" }
        ));
    }
    let rest = &b[r.at..];
    let new = new as usize;
    let start = m.vertices.positions.len();
    let vb = &mut m.vertices;
    vb.positions.reserve(new);
    let (mut acc, mut nbits, mut at) = (0u64, 0u32, 0usize);
    for _ in 0..new {
        let q: [u32; 3] = std::array::from_fn(|_| {
            while nbits < bits {
                acc |= (rest[at] as u64) << nbits;
                at += 1;
                nbits += 8;
            }
            let x = (acc & ((1u64 << bits) - 1)) as u32;
            acc >>= bits;
            nbits -= bits;
            x
        });
        vb.positions.push(dequantise(&h.grid, bits, q));
    }
    let normals = &rest[(3 * bits as usize * new).div_ceil(8)..];
    vb.normals
        .extend(normals[..4 * new].chunks_exact(4).map(|c| {
            oct_decode([
                u16::from_le_bytes([c[0], c[1]]),
                u16::from_le_bytes([c[2], c[3]]),
            ])
        }));
    if h.has_colors {
        vb.colors.extend(
            normals[4 * new..8 * new]
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]]),
        );
    } else {
        vb.colors.resize(vb.positions.len(), NO_COLOR);
    }
    r.at += fixed as usize;
    if h.exact_positions {
        for (i, p) in vb.positions[start..].iter_mut().enumerate() {
            let mut xyz = p.to_array();
            for x in &mut xyz {
                let z = r.var64()?;
                let d = (z >> 1) as i128 ^ -((z & 1) as i128);
                let o = ordered(*x) as i128 + d;
                if !(0..=u32::MAX as i128).contains(&o) {
                    return Err(format!(
                        "vertex {}: position residual out of range",
                        first_new_vertex as usize + i
                    ));
                }
                *x = unordered(o as u32);
            }
            *p = Vec3::from_array(xyz);
        }
        if r.left() != 0 {
            return Err(format!("{} bytes after the vertex section", r.left()));
        }
    }
    Ok(())
}

/// Parses a whole version-2 file; every chunk must be present. The error
/// says what is wrong (no path).
pub fn decode(bytes: &[u8]) -> Res<McoModel> {
    let h = parse_header(bytes)?;
    if bytes.len() as u64 != h.file_bytes {
        return Err(format!(
            "size mismatch: {} bytes, the header says {} (truncated or padded file)",
            bytes.len(),
            h.file_bytes
        ));
    }
    let mut s = McoStream::new();
    s.push_bytes(bytes)?;
    if !s.is_complete() {
        return Err("the file ends inside a chunk".into());
    }
    s.snapshot()
}

/// Reads a prefix of a version-2 file: the model of its complete chunks
/// (a chunk cut short is ignored). Errors when the header or chunk 0 is
/// incomplete, or on any bad byte or table in what is complete.
pub fn decode_prefix(bytes: &[u8]) -> Res<PartialModel> {
    let mut s = McoStream::new();
    s.push_bytes(bytes)?;
    if s.header().is_none() {
        return Err(format!(
            "{} bytes, shorter than the {HEADER_BYTES}-byte header",
            bytes.len()
        ));
    }
    let model = s.snapshot()?;
    Ok(PartialModel {
        max_lod: model.max_lod(),
        complete: s.is_complete(),
        chunks: s.chunks.len(),
        model,
    })
}

/// The chunk table of a whole version-2 file (for `lodkit mco info`).
pub fn chunk_table(bytes: &[u8]) -> Res<Vec<ChunkInfo>> {
    let mut s = McoStream::new();
    s.push_bytes(bytes)?;
    Ok(s.chunks().to_vec())
}
