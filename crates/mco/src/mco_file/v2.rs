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
//! patches), then the vertices those records reference first (chunk 0's
//! include the root's). After chunks
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
//! **Exactness.** A model read from its file cuts exactly as the model
//! written, bit for bit: positions are quantised on the lattice box with
//! [`position_bits`] bits per axis (within a 1024th of a leaf cube:
//! half a step, `cube / 2^(bits - depth + 1)`) and each coordinate's residual follows (header flag
//! `FLAG_EXACT_POSITIONS`), so crack patching's compensation points stay on
//! the coarse segments they close; a build puts its marching-cubes vertices
//! on that grid ([`snapped_position`]), so most residuals are 0. Normals
//! are octahedral with 2 × 16 bits, and a build keeps the normals those
//! codes decode to ([`stored_normal`]).
//!
//! **Compactness.** Colours are stored only when meaningful, indices as LEB128 varints relative to the running
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
//! line, without the path (the loader in `mco_file` adds it).

use glam::Vec3;

use super::format::{MAGIC, MAX_NODE_TRIANGLES, MAX_PATCH_SUBS};
use crate::lattice::{Grid, KEY_BITS};
use crate::model::{BuildStats, McoModel, Node, Patch};
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
/// Header flag: each vertex section ends with the positions' residuals, so
/// positions read back bit for bit (every file lodkit writes sets it).
const FLAG_EXACT_POSITIONS: u32 = 2;
/// Node record byte 0: the cube coordinates and level are written out
/// instead of derived from the parent (octant in bits 0–2).
const EXPLICIT: u8 = 1 << 3;

/// Bits per quantised position axis for an octree of depth `depth`: the
/// root box is `2^depth` leaf cubes wide, and each leaf cube gets at least
/// `2^9` steps (at least 16 bits in all).
pub fn position_bits(depth: u32) -> u32 {
    (depth + 9).max(16)
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

/// The normal a model stores for `n`: the octahedral code's own normal,
/// which encodes back to the same code. A build keeps these normals, so a
/// model and the model read from its file have the same normals, bit for
/// bit. A zero or non-finite `n` stores +z.
pub(crate) fn stored_normal(n: Vec3) -> Vec3 {
    oct_decode(oct_encode(n))
}

/// `p` moved onto the position grid a file of a model on `grid` stores
/// (the quantised position, read back), when that is within
/// half a quantisation step (it is for every point of the lattice box); else `p`.
/// A model whose vertices are snapped costs one byte per coordinate of
/// residual, which deflates away. The grid scales with a power-of-two
/// scaling of `grid`, exactly.
pub(crate) fn snapped_position(grid: &Grid, p: Vec3) -> Vec3 {
    let bits = position_bits(grid.depth.min(KEY_BITS - 1));
    let d = dequantise(grid, bits, quantise(grid, bits, p));
    let err = grid.cube / (1u64 << (bits - grid.depth.min(KEY_BITS - 1) + 1)) as f32;
    if (d - p).abs().max_element() <= 1.5 * err {
        d
    } else {
        p
    }
}

/// Bytes of the fixed-size part of the vertex section of a chunk with `n`
/// new vertices (positions' residuals, when present, follow it: at least
/// `3n` more bytes).
fn vertex_section_bytes(n: u64, bits: u32, colors: bool) -> u64 {
    (3 * bits as u64 * n).div_ceil(8) + 4 * n + if colors { 4 * n } else { 0 }
}

/// `f32` bits in an order that follows the values (negative below
/// positive): consecutive floats are consecutive integers.
fn ordered(x: f32) -> u32 {
    let b = x.to_bits();
    if b & 0x8000_0000 != 0 {
        !b
    } else {
        b | 0x8000_0000
    }
}

fn unordered(o: u32) -> f32 {
    f32::from_bits(if o & 0x8000_0000 != 0 {
        o & 0x7FFF_FFFF
    } else {
        !o
    })
}

/// The residual of `p` against its quantised position `q`, per axis, as
/// `zigzag(ordered(p) − ordered(dequantised))` (a few units of the last
/// place on a built model: usually one byte as a varint).
fn residuals(grid: &Grid, bits: u32, p: Vec3, q: [u32; 3]) -> [u64; 3] {
    let d = dequantise(grid, bits, q).to_array();
    let p = p.to_array();
    std::array::from_fn(|a| {
        let x = ordered(p[a]) as i64 - ordered(d[a]) as i64;
        ((x << 1) ^ (x >> 63)) as u64
    })
}

fn put_var64(out: &mut Vec<u8>, mut x: u64) {
    while x >= 0x80 {
        out.push(x as u8 | 0x80);
        x >>= 7;
    }
    out.push(x as u8);
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
        let grid = &self.m.grid;
        let mut packed = Bits::default();
        let mut residual = Vec::with_capacity(3 * self.chunk_verts.len());
        for &v in &self.chunk_verts {
            let p = vb.positions[v as usize];
            let q = quantise(grid, bits, p);
            for x in q {
                packed.put(x, bits);
            }
            for r in residuals(grid, bits, p, q) {
                put_var64(&mut residual, r);
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
        out.extend_from_slice(&residual);
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
                + vertex_section_bytes(w.chunk_verts.len() as u64, bits, m.has_colors) as usize
                + 3 * w.chunk_verts.len();
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
    put_u32(
        &mut out,
        FLAG_EXACT_POSITIONS | if m.has_colors { FLAG_COLORS } else { 0 },
    );
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

mod read;
#[cfg(test)]
use read::*;
pub use read::{ChunkInfo, Header, McoStream, PartialModel, chunk_table, decode, decode_prefix};

#[cfg(test)]
mod tests;
