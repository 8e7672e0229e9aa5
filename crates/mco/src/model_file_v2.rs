//! `.mco` version 2: the marching cube octree laid out in LOD-number order,
//! compact, and readable from any prefix (`docs/formats/mco.md`).
//!
//! **Layout.** A 104-byte header (lattice, totals, its own CRC), then
//! chunks, each `[u32 stored length][u32 CRC-32][u32 payload length]`
//! and the payload, deflated (`miniz_oxide`) or stored as it is.
//! Chunk `c` carries the LOD steps `K[c-1] + 1 ..= K[c]` (chunk 0 also the
//! root, LOD number 0): for each step, the nodes it expands (their metric,
//! balance dependencies and child count) and the records of the children
//! that expansion makes drawable (octant, configuration, triangles, crack
//! patches), then the vertices those records reference first. After chunks
//! `0..=c` every LOD number up to `K[c]` is served with exactly the
//! triangles the whole file gives it.
//!
//! **Numbering.** The file fixes one numbering of nodes and vertices, the
//! order in which they appear in the stream: the root is node 0, and the
//! children of each expanded node are numbered when it expands, in LOD-array
//! order; a vertex is numbered when a record first references it. A built
//! model is renumbered that way when written ([`encode`]), so the indices an
//! extraction returns from a read file are a renumbering of the in-memory
//! model's; the triangles are the same. Writing a read file again gives the
//! same bytes.
//!
//! **Prefixes.** [`McoStream`] takes bytes as they arrive and, after each
//! complete chunk, [`McoStream::model`] is a regular [`McoModel`] truncated
//! to the LOD numbers covered: nodes not yet expanded are leaves there
//! (`prio = u32::MAX`, no children), and a crack patch whose coarse
//! neighbour has not yet appeared points at its own node (a neighbour that
//! has not appeared is not expanded at any covered LOD number, so the patch
//! applies whenever the node is drawn, as in the whole model). Every
//! extraction (by LOD number, by budget, by view) works on it unchanged; a
//! view-dependent cut equals the whole model's whenever that cut expands
//! only covered LOD numbers.
//!
//! **Compactness.** Positions are quantised on the lattice box with
//! [`position_bits`] bits per axis (error at most a 1024th of a leaf cube,
//! [`position_error`]), normals octahedral with 2 × 16 bits, colours stored
//! only when meaningful, indices as LEB128 varints relative to the running
//! vertex count (0 = a new vertex), node records 3 bytes plus their
//! triangles and patches; each payload then deflated (a quarter smaller on
//! the bunny). The accumulation table is not stored: it is
//! recomputed from the triangle counts, so it always agrees with them.
//!
//! **Reading is defensive.** Every count is checked against the bytes left
//! in its chunk before anything is allocated (each element costs at least
//! one byte), every index against the tables read so far and the header's
//! totals, so memory grows with the bytes present and a hostile file cannot
//! make extraction allocate more than its triangles need. Errors are one
//! line, without the path ([`crate::model_file::load`] adds it).

use glam::Vec3;

use crate::lattice::{Grid, KEY_BITS};
use crate::model::{BuildStats, McoModel, Node, Patch};
use crate::model_file::{MAGIC, MAX_NODE_TRIANGLES, MAX_PATCH_SUBS};
use crate::signed_distance::NO_COLOR;

/// The format version this module writes and reads.
pub const VERSION: u32 = 2;
/// Bytes of the header, its CRC included.
pub const HEADER_BYTES: usize = 104;
/// Bytes before each chunk's payload (stored length, CRC, raw length).
pub const CHUNK_HEAD_BYTES: usize = 12;
/// A deflated payload may expand to at most this many times its stored
/// length (plus [`EXPANSION_SLACK`]): memory stays proportional to the
/// file. The writer stores a payload uncompressed when it would deflate
/// further than that.
pub const MAX_EXPANSION: u64 = 16;
/// See [`MAX_EXPANSION`].
pub const EXPANSION_SLACK: u64 = 4096;
/// Deflate level of the payloads.
const DEFLATE_LEVEL: u8 = 6;
/// Target size of chunk 0; chunk `c` aims at `FIRST_CHUNK_BYTES << c`,
/// capped at [`MAX_CHUNK_TARGET`]. A chunk closes after the first LOD step
/// that reaches its target, so it can be larger by one step.
pub const FIRST_CHUNK_BYTES: usize = 4096;
/// Largest chunk target.
pub const MAX_CHUNK_TARGET: usize = 1 << 20;
/// Bits per octahedral normal component.
pub const NORMAL_BITS: u32 = 16;
/// Header flag: vertex colours are meaningful (stored).
const FLAG_COLORS: u32 = 1;
/// Node record byte 0: the cube coordinates and level are written out
/// instead of derived from the parent (octant in bits 0–2).
const EXPLICIT: u8 = 1 << 3;

/// Bits per quantised position axis for an octree of depth `depth`: the
/// root box is `2^depth` leaf cubes wide, and each leaf cube gets at least
/// `2^9` steps (at least 16 bits in all).
pub fn position_bits(depth: u32) -> u32 {
    (depth + 9).max(16)
}

/// Largest error, per axis, of a quantised position inside the lattice box
/// (half a quantisation step), in object units: `cube / 2^(b - depth + 1)`,
/// at most `cube / 1024` (plus the `f32` rounding of the coordinate).
// The bound the tests check quantisation against; documented with the layout.
#[cfg_attr(not(test), allow(dead_code))]
pub fn position_error(grid: &Grid) -> f32 {
    let b = position_bits(grid.depth);
    grid.cube / (1u64 << (b - grid.depth + 1)) as f32
}

/// The version field of `.mco` bytes (`None`: too short or not `.mco`).
pub fn file_version(bytes: &[u8]) -> Option<u32> {
    (bytes.len() >= 12 && bytes[..8] == MAGIC)
        .then(|| u32::from_le_bytes(bytes[8..12].try_into().expect("4 bytes")))
}

// ---------------------------------------------------------------- writing

fn put_u32(out: &mut Vec<u8>, x: u32) {
    out.extend_from_slice(&x.to_le_bytes());
}

fn put_var(out: &mut Vec<u8>, mut x: u32) {
    while x >= 0x80 {
        out.push(x as u8 | 0x80);
        x >>= 7;
    }
    out.push(x as u8);
}

fn zigzag(x: i64) -> u32 {
    ((x << 1) ^ (x >> 63)) as u32
}

fn unzigzag(x: u32) -> i64 {
    (x >> 1) as i64 ^ -((x & 1) as i64)
}

/// LSB-first bit packer.
#[derive(Default)]
struct Bits {
    out: Vec<u8>,
    acc: u64,
    n: u32,
}

impl Bits {
    fn put(&mut self, x: u32, bits: u32) {
        self.acc |= (x as u64) << self.n;
        self.n += bits;
        while self.n >= 8 {
            self.out.push(self.acc as u8);
            self.acc >>= 8;
            self.n -= 8;
        }
    }
    fn finish(mut self) -> Vec<u8> {
        if self.n > 0 {
            self.out.push(self.acc as u8);
        }
        self.out
    }
}

/// Quantised position of `p` on the lattice box.
fn quantise(grid: &Grid, bits: u32, p: Vec3) -> [u32; 3] {
    let scale = (1u64 << (bits - grid.depth)) as f64 / grid.cube as f64;
    let top = ((1u64 << bits) - 1) as f64;
    let o = grid.origin.to_array();
    let p = p.to_array();
    std::array::from_fn(|a| {
        let q = ((p[a] as f64 - o[a] as f64) * scale).round();
        if q.is_nan() {
            0
        } else {
            q.clamp(0.0, top) as u32
        }
    })
}

fn dequantise(grid: &Grid, bits: u32, q: [u32; 3]) -> Vec3 {
    let step = grid.cube as f64 / (1u64 << (bits - grid.depth)) as f64;
    let o = grid.origin.to_array();
    Vec3::from_array(std::array::from_fn(|a| {
        (o[a] as f64 + q[a] as f64 * step) as f32
    }))
}

const NORMAL_MAX: f32 = ((1u32 << (NORMAL_BITS - 1)) - 1) as f32;

/// Octahedral normal, two signed 16-bit components (as `u16`).
/// Octahedral normal, two signed 16-bit components (as `u16`). Of the
/// rounded code and its eight neighbours, the one that decodes closest to
/// `n` (ties to the smaller code); repeated from that code's own normal
/// until it picks itself, so that a decoded normal encodes to its own code
/// and a read file writes back the same bytes.
fn oct_encode(n: Vec3) -> [u16; 2] {
    let mut e = oct_nearest(n);
    for _ in 0..4 {
        let again = oct_nearest(oct_decode(e));
        if again == e {
            break;
        }
        e = again;
    }
    e
}

fn oct_nearest(n: Vec3) -> [u16; 2] {
    let s = n.x.abs() + n.y.abs() + n.z.abs();
    if !(s > 0.0 && s.is_finite()) {
        return [0, 0];
    }
    let (mut x, mut y) = (n.x / s, n.y / s);
    if n.z < 0.0 {
        let (ox, oy) = (x, y);
        x = (1.0 - oy.abs()) * if ox >= 0.0 { 1.0 } else { -1.0 };
        y = (1.0 - ox.abs()) * if oy >= 0.0 { 1.0 } else { -1.0 };
    }
    let lim = NORMAL_MAX as i32;
    let q = |v: f32| ((v.clamp(-1.0, 1.0) * NORMAL_MAX).round() as i32).clamp(-lim, lim);
    let (qx, qy) = (q(x), q(y));
    let n = n / n.length();
    let mut best = ((qx, qy), f32::INFINITY);
    for dy in -1..=1 {
        for dx in -1..=1 {
            let c = ((qx + dx).clamp(-lim, lim), (qy + dy).clamp(-lim, lim));
            // The distance, not the cosine: near 1 a cosine cannot tell
            // neighbouring codes apart in `f32`.
            let d = oct_decode([c.0 as i16 as u16, c.1 as i16 as u16]).distance_squared(n);
            if d < best.1 || (d == best.1 && c < best.0) {
                best = (c, d);
            }
        }
    }
    [best.0.0 as i16 as u16, best.0.1 as i16 as u16]
}

fn oct_decode(e: [u16; 2]) -> Vec3 {
    let x = (e[0] as i16 as f32 / NORMAL_MAX).clamp(-1.0, 1.0);
    let y = (e[1] as i16 as f32 / NORMAL_MAX).clamp(-1.0, 1.0);
    let z = 1.0 - x.abs() - y.abs();
    let (x, y) = if z < 0.0 {
        (
            (1.0 - y.abs()) * if x >= 0.0 { 1.0 } else { -1.0 },
            (1.0 - x.abs()) * if y >= 0.0 { 1.0 } else { -1.0 },
        )
    } else {
        (x, y)
    };
    Vec3::new(x, y, z).normalize_or(Vec3::Z)
}

/// Bytes of the vertex section of a chunk with `n` new vertices.
fn vertex_section_bytes(n: u64, bits: u32, colors: bool) -> u64 {
    (3 * bits as u64 * n).div_ceil(8) + 4 * n + if colors { 4 * n } else { 0 }
}

/// The stream order of a model: node numbering (old → new) and, per LOD
/// step, the nodes it expands (old numbers), unreachable nodes left out.
struct Order {
    new_node: Vec<u32>,
    steps: Vec<Vec<u32>>,
    nodes: u32,
}

fn stream_order(m: &McoModel) -> Order {
    let n = m.nodes.len();
    let mut new_node = vec![u32::MAX; n];
    let mut expanded = vec![false; n];
    let mut next = 0u32;
    if n > 0 {
        new_node[0] = 0;
        next = 1;
    }
    let mut steps = Vec::with_capacity(m.groups.len().saturating_sub(1));
    for k in 1..m.groups.len() {
        let mut step = Vec::new();
        let (a, b) = (m.groups[k - 1] as usize, m.groups[k] as usize);
        for &x in m.lod.get(a..b).unwrap_or(&[]) {
            let x = x as usize;
            // Only a node that has appeared, has children and is not yet
            // expanded can expand (always so in a built model).
            if x >= n || new_node[x] == u32::MAX || expanded[x] || m.nodes[x].child_count == 0 {
                continue;
            }
            expanded[x] = true;
            for c in m.children(x as u32) {
                if (c as usize) < n && new_node[c as usize] == u32::MAX {
                    new_node[c as usize] = next;
                    next += 1;
                }
            }
            step.push(x as u32);
        }
        steps.push(step);
    }
    Order {
        new_node,
        steps,
        nodes: next,
    }
}

struct Writer<'a> {
    m: &'a McoModel,
    order: &'a Order,
    /// Old vertex → new number.
    new_vert: Vec<u32>,
    next_vert: u32,
    /// Old numbers of the vertices first referenced in the open chunk.
    chunk_verts: Vec<u32>,
    totals: [u64; 4], // triangle indices, patches, subs, deps
}

impl Writer<'_> {
    fn vertex(&mut self, out: &mut Vec<u8>, v: u32) {
        let id = &mut self.new_vert[v as usize];
        if *id == u32::MAX {
            *id = self.next_vert;
            self.next_vert += 1;
            self.chunk_verts.push(v);
            put_var(out, 0);
        } else {
            put_var(out, self.next_vert - *id);
        }
    }

    /// Record of node `c` becoming drawable (the child of `parent`).
    fn appear(&mut self, out: &mut Vec<u8>, c: u32, parent: Option<u32>) {
        let m = self.m;
        let nd = m.nodes[c as usize];
        let derived = parent.and_then(|p| {
            let pn = &m.nodes[p as usize];
            let oct: [u32; 3] =
                std::array::from_fn(|a| nd.coord[a].wrapping_sub(pn.coord[a].wrapping_mul(2)));
            (oct.iter().all(|&o| o < 2)
                && pn.coord.iter().all(|&x| x < 1 << 31)
                && pn.level >= 1
                && nd.level == pn.level - 1)
                .then(|| (oct[0] | oct[1] << 1 | oct[2] << 2) as u8)
        });
        let patch_count = nd.patch_count.min(6);
        let tri_count = (nd.tri_count as usize).min(MAX_NODE_TRIANGLES) as u8;
        out.push(derived.unwrap_or(EXPLICIT) | patch_count << 4);
        out.push(nd.config);
        out.push(tri_count);
        if derived.is_none() {
            nd.coord.iter().for_each(|&x| put_var(out, x));
            out.push(nd.level);
        }
        let tris = &m.tris[nd.tri_start as usize..][..3 * tri_count as usize];
        for &v in tris {
            self.vertex(out, v);
        }
        self.totals[0] += tris.len() as u64;
        let me = self.order.new_node[c as usize];
        for p in &m.patches[nd.patch_start as usize..][..patch_count as usize] {
            // A coarse neighbour that never appears is never expanded: the
            // node itself stands for it (the patch applies whenever drawn).
            let q = match self.order.new_node[p.coarse as usize] {
                u32::MAX => me,
                q => q,
            };
            put_var(out, zigzag(me as i64 - q as i64));
            let subs =
                &m.subs[p.subs_start as usize..][..(p.subs_count as usize).min(MAX_PATCH_SUBS)];
            put_var(out, subs.len() as u32);
            for s in subs {
                self.vertex(out, s[0]);
                self.vertex(out, s[1]);
            }
            self.totals[1] += 1;
            self.totals[2] += subs.len() as u64;
        }
    }

    fn vertex_section(&mut self, out: &mut Vec<u8>, bits: u32) {
        let vb = &self.m.vertices;
        let mut packed = Bits::default();
        for &v in &self.chunk_verts {
            for q in quantise(&self.m.grid, bits, vb.positions[v as usize]) {
                packed.put(q, bits);
            }
        }
        out.extend_from_slice(&packed.finish());
        for &v in &self.chunk_verts {
            let e = oct_encode(vb.normals.get(v as usize).copied().unwrap_or(Vec3::Z));
            out.extend_from_slice(&e[0].to_le_bytes());
            out.extend_from_slice(&e[1].to_le_bytes());
        }
        if self.m.has_colors {
            for &v in &self.chunk_verts {
                out.extend_from_slice(&vb.colors.get(v as usize).copied().unwrap_or(NO_COLOR));
            }
        }
        self.chunk_verts.clear();
    }
}

/// Appends a chunk: the payload deflated (raw length recorded), or stored
/// as it is (raw length 0) when deflating does not help or would expand
/// past [`MAX_EXPANSION`] on reading.
fn close_chunk(file: &mut Vec<u8>, payload: &[u8]) {
    let packed = miniz_oxide::deflate::compress_to_vec(payload, DEFLATE_LEVEL);
    let fits = (payload.len() as u64) <= MAX_EXPANSION * packed.len() as u64 + EXPANSION_SLACK;
    let (stored, raw) = if packed.len() < payload.len() && fits {
        (&packed[..], payload.len() as u32)
    } else {
        (payload, 0)
    };
    put_u32(file, stored.len() as u32);
    put_u32(file, crc32fast::hash(stored));
    put_u32(file, raw);
    file.extend_from_slice(stored);
}

/// Serialises a model as version 2 (deterministic: the same model gives
/// the same bytes; no time is stored). Positions and normals are quantised
/// (see the module docs); nodes and vertices are renumbered in stream
/// order, and nodes no LOD step reaches are left out. A model with no nodes
/// gives a file with no chunks, which [`decode`] refuses. Cost: `O(size)`.
pub fn encode(m: &McoModel) -> Vec<u8> {
    encode_numbered(m).0
}

/// [`encode`], and the new number of each of `m`'s vertices (`u32::MAX`:
/// left out, no record references it).
fn encode_numbered(m: &McoModel) -> (Vec<u8>, Vec<u32>) {
    let order = stream_order(m);
    let bits = position_bits(m.grid.depth.min(KEY_BITS - 1));
    let mut w = Writer {
        m,
        order: &order,
        new_vert: vec![u32::MAX; m.vertices.len()],
        next_vert: 0,
        chunk_verts: Vec::new(),
        totals: [0; 4],
    };
    let mut chunks = Vec::new();
    let mut chunk_count = 0u32;
    let mut payload = Vec::new();
    let mut records = Vec::new();
    let mut steps_in_chunk = 0u32;
    let max_lod = order.steps.len();
    if !m.nodes.is_empty() {
        w.appear(&mut records, 0, None);
        for (i, step) in order.steps.iter().enumerate() {
            put_var(&mut records, step.len() as u32);
            for &x in step {
                let nd = m.nodes[x as usize];
                put_var(&mut records, order.new_node[x as usize]);
                records.extend_from_slice(
                    &m.metric
                        .get(x as usize)
                        .copied()
                        .unwrap_or(0.0)
                        .to_le_bytes(),
                );
                records.push(nd.child_count);
                let me = order.new_node[x as usize] as i64;
                let deps: Vec<u32> = m.deps[nd.deps_start as usize..][..nd.deps_count as usize]
                    .iter()
                    .filter_map(|&d| match order.new_node.get(d as usize) {
                        Some(&q) if q != u32::MAX => Some(q),
                        _ => None,
                    })
                    .collect();
                put_var(&mut records, deps.len() as u32);
                for d in &deps {
                    put_var(&mut records, zigzag(me - *d as i64));
                }
                w.totals[3] += deps.len() as u64;
                for c in m.children(x) {
                    w.appear(&mut records, c, Some(x));
                }
            }
            steps_in_chunk += 1;
            let target = (FIRST_CHUNK_BYTES << chunk_count.min(16)).min(MAX_CHUNK_TARGET);
            let size = records.len()
                + vertex_section_bytes(w.chunk_verts.len() as u64, bits, m.has_colors) as usize;
            if size >= target || i + 1 == max_lod {
                payload.clear();
                put_var(&mut payload, steps_in_chunk);
                payload.append(&mut records);
                w.vertex_section(&mut payload, bits);
                close_chunk(&mut chunks, &payload);
                chunk_count += 1;
                steps_in_chunk = 0;
            }
        }
        if max_lod == 0 {
            payload.clear();
            put_var(&mut payload, 0);
            payload.append(&mut records);
            w.vertex_section(&mut payload, bits);
            close_chunk(&mut chunks, &payload);
            chunk_count += 1;
        }
    }
    let mut out = Vec::with_capacity(HEADER_BYTES + chunks.len());
    out.extend_from_slice(&MAGIC);
    put_u32(&mut out, VERSION);
    put_u32(&mut out, if m.has_colors { FLAG_COLORS } else { 0 });
    for c in m.grid.origin.to_array() {
        out.extend_from_slice(&c.to_le_bytes());
    }
    out.extend_from_slice(&m.grid.cube.to_le_bytes());
    put_u32(&mut out, m.grid.depth);
    put_u32(&mut out, m.grid.resolution);
    out.extend_from_slice(&m.stats.input_samples.to_le_bytes());
    out.extend_from_slice(&m.stats.unpatched.to_le_bytes());
    put_u32(&mut out, bits);
    for t in [
        w.next_vert as u64,
        order.nodes as u64,
        max_lod as u64,
        w.totals[0],
        w.totals[1],
        w.totals[2],
        w.totals[3],
        chunk_count as u64,
    ] {
        put_u32(&mut out, t as u32);
    }
    out.extend_from_slice(&((HEADER_BYTES + chunks.len()) as u64).to_le_bytes());
    let crc = crc32fast::hash(&out);
    put_u32(&mut out, crc);
    debug_assert_eq!(out.len(), HEADER_BYTES);
    out.extend_from_slice(&chunks);
    (out, w.new_vert)
}

// ---------------------------------------------------------------- reading

type Res<T> = std::result::Result<T, String>;

/// The fixed header of a version-2 file.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Header {
    /// Whether the vertices carry the input's colours.
    pub has_colors: bool,
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

fn le32(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("4 bytes"))
}
fn le64(b: &[u8], at: usize) -> u64 {
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
    if flags & !FLAG_COLORS != 0 {
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
struct Cursor<'a> {
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
        crate::model_file::validate(&m)?;
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
fn inflate(stored: &[u8], raw: u32) -> Res<Vec<u8>> {
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

fn check_totals(h: &Header, m: &McoModel, end: u64) -> Res<()> {
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
fn vertex_ref(r: &mut Cursor, vertices: &mut u32, limit: u32) -> Res<u32> {
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
fn read_node(
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
fn read_chunk(h: &Header, m: &mut McoModel, vertices: &mut u32, b: &[u8], first: bool) -> Res<()> {
    let mut r = Cursor { b, at: 0 };
    let steps = r.count(1, "LOD step")?;
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
    let first_new_vertex = *vertices;
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
    if vertex_section_bytes(new, bits, h.has_colors) != r.left() as u64 {
        return Err(format!(
            "{} bytes left for {new} new vertices (expected {})",
            r.left(),
            vertex_section_bytes(new, bits, h.has_colors)
        ));
    }
    let rest = &b[r.at..];
    let new = new as usize;
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
            normals[4 * new..]
                .chunks_exact(4)
                .map(|c| [c[0], c[1], c[2], c[3]]),
        );
    } else {
        vb.colors.resize(vb.positions.len(), NO_COLOR);
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
/// incomplete, or on any bad byte in what is complete.
pub fn decode_prefix(bytes: &[u8]) -> Res<PartialModel> {
    let mut s = McoStream::new();
    s.push_bytes(bytes)?;
    if s.header().is_none() {
        return Err(format!(
            "{} bytes, shorter than the {HEADER_BYTES}-byte header",
            bytes.len()
        ));
    }
    s.partial()
        .ok_or_else(|| "no complete chunk yet (chunk 0 serves LOD 0)".into())
}

/// The chunk table of a whole version-2 file (for `lodkit mco info`).
pub fn chunk_table(bytes: &[u8]) -> Res<Vec<ChunkInfo>> {
    let mut s = McoStream::new();
    s.push_bytes(bytes)?;
    Ok(s.chunks().to_vec())
}

#[cfg(test)]
mod tests;
