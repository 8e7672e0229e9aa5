//! `.mco` files: the public load/save entry points, and the version-1
//! layout (flat arrays). Byte layouts are specified in
//! `docs/formats/mco.md`. [`save`] and [`McoModel::to_bytes`] write
//! version 2 ([`crate::model_file_v2`], the compact, streamable layout);
//! [`decode`] and [`load`] read both versions.
//!
//! Reading is defensive: the file size must equal the size the header's
//! counts imply (checked in 64-bit arithmetic before anything is
//! allocated), the CRC-32 must match, every index the extractor will
//! follow is range-checked, and every table is checked against the others
//! ([`validate`], for both versions): the nodes form one octree, the LOD
//! array, priority numbers and balance dependencies agree, and the
//! accumulation table is the triangle count the nodes give at every LOD
//! number. So a loaded model can never make extraction panic, read out of
//! bounds, or size an allocation by a table that disagrees with the data.
//! Each array is one allocation — there is no per-node allocation. Any
//! problem is one error line naming the file.

use std::path::Path;

use glam::Vec3;

use crate::lattice::{Grid, KEY_BITS};
use crate::marching_cubes::VertexBuffer;
use crate::model::{BuildStats, McoModel, Node, Patch};
use crate::model_file_v2::{ChunkInfo, PartialModel};
use crate::{Error, Result};

/// File signature.
pub(crate) const MAGIC: [u8; 8] = *b"LODKMCO\0";
/// The version-1 layout's number (the flat arrays), which [`encode`]
/// writes and [`decode`] still reads.
pub(crate) const VERSION: u32 = 1;
/// The `.mco` format version this crate writes ([`McoModel::to_bytes`],
/// `docs/formats/mco.md`); it reads this one and version 1.
pub const FORMAT_VERSION: u32 = crate::model_file_v2::VERSION;
/// Bytes before the arrays.
pub(crate) const HEADER_BYTES: usize = 8 + 4 + 4 + 12 + 4 + 4 + 4 + 8 + 8 + 8 + 9 * 4;
/// Bytes per node record.
pub(crate) const NODE_BYTES: usize = 40;
/// Most triangles a node can have (the table's maximum is 12; the margin
/// keeps extraction records far below their 16-bit length field).
pub(crate) const MAX_NODE_TRIANGLES: usize = 16;
/// Most substitutions one patch can hold (a face has at most 4 crossing
/// edges per fine node).
pub(crate) const MAX_PATCH_SUBS: usize = 16;
/// Files larger than this are refused before reading.
pub(crate) const MAX_FILE_BYTES: u64 = 16 << 30;

/// Serialises a model as version 1 (deterministic: the same model gives
/// the same bytes). Only the tests write version 1 now (to check that it
/// still reads); [`McoModel::to_bytes`] writes version 2.
#[cfg_attr(not(test), allow(dead_code))]
pub(crate) fn encode(m: &McoModel) -> Vec<u8> {
    let v = m.vertices.len();
    let n = m.nodes.len();
    let mut out = Vec::with_capacity(
        HEADER_BYTES + v * 28 + n * (NODE_BYTES + 8) + 4 * (m.tris.len() + m.lod.len()),
    );
    out.extend_from_slice(&MAGIC);
    put_u32(&mut out, VERSION);
    put_u32(&mut out, m.has_colors as u32);
    for c in m.grid.origin.to_array() {
        put_f32(&mut out, c);
    }
    put_f32(&mut out, m.grid.cube);
    put_u32(&mut out, m.grid.depth);
    put_u32(&mut out, m.grid.resolution);
    out.extend_from_slice(&m.stats.input_samples.to_le_bytes());
    // Offset 48, reserved: always 0, so that the same model gives the same
    // bytes (files before it held the build's wall time; readers skip it).
    out.extend_from_slice(&0u64.to_le_bytes());
    out.extend_from_slice(&m.stats.unpatched.to_le_bytes());
    for count in [
        v,
        n,
        m.tris.len(),
        m.lod.len(),
        m.groups.len(),
        m.acc.len(),
        m.patches.len(),
        m.subs.len(),
        m.deps.len(),
    ] {
        put_u32(&mut out, count as u32);
    }
    debug_assert_eq!(out.len(), HEADER_BYTES);
    for p in &m.vertices.positions {
        p.to_array().iter().for_each(|&c| put_f32(&mut out, c));
    }
    for p in &m.vertices.normals {
        p.to_array().iter().for_each(|&c| put_f32(&mut out, c));
    }
    for c in &m.vertices.colors {
        out.extend_from_slice(c);
    }
    for nd in &m.nodes {
        for c in nd.coord {
            put_u32(&mut out, c);
        }
        for x in [
            nd.parent,
            nd.first_child,
            nd.tri_start,
            nd.patch_start,
            nd.deps_start,
        ] {
            put_u32(&mut out, x);
        }
        out.extend_from_slice(&nd.tri_count.to_le_bytes());
        out.extend_from_slice(&nd.deps_count.to_le_bytes());
        out.extend_from_slice(&[nd.child_count, nd.level, nd.patch_count, nd.config]);
    }
    m.metric.iter().for_each(|&x| put_f32(&mut out, x));
    for arr in [&m.prio, &m.tris, &m.lod, &m.groups, &m.acc] {
        arr.iter().for_each(|&x| put_u32(&mut out, x));
    }
    for p in &m.patches {
        put_u32(&mut out, p.coarse);
        put_u32(&mut out, p.subs_start);
        put_u32(&mut out, p.subs_count);
    }
    for s in &m.subs {
        put_u32(&mut out, s[0]);
        put_u32(&mut out, s[1]);
    }
    m.deps.iter().for_each(|&x| put_u32(&mut out, x));
    let crc = crc32fast::hash(&out);
    put_u32(&mut out, crc);
    out
}

#[cfg_attr(not(test), allow(dead_code))]
fn put_u32(out: &mut Vec<u8>, x: u32) {
    out.extend_from_slice(&x.to_le_bytes());
}
#[cfg_attr(not(test), allow(dead_code))]
fn put_f32(out: &mut Vec<u8>, x: f32) {
    out.extend_from_slice(&x.to_le_bytes());
}

/// A bounds-checked little-endian cursor.
struct Reader<'a> {
    b: &'a [u8],
    at: usize,
}

impl Reader<'_> {
    fn take(&mut self, n: usize) -> std::result::Result<&[u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.b.len());
        let Some(end) = end else {
            return Err(format!("truncated at byte {}", self.at));
        };
        let s = &self.b[self.at..end];
        self.at = end;
        Ok(s)
    }
    fn u32(&mut self) -> std::result::Result<u32, String> {
        Ok(u32::from_le_bytes(
            self.take(4)?.try_into().expect("4 bytes"),
        ))
    }
    fn u16(&mut self) -> std::result::Result<u16, String> {
        Ok(u16::from_le_bytes(
            self.take(2)?.try_into().expect("2 bytes"),
        ))
    }
    fn u8(&mut self) -> std::result::Result<u8, String> {
        Ok(self.take(1)?[0])
    }
    fn u64(&mut self) -> std::result::Result<u64, String> {
        Ok(u64::from_le_bytes(
            self.take(8)?.try_into().expect("8 bytes"),
        ))
    }
    fn f32(&mut self) -> std::result::Result<f32, String> {
        Ok(f32::from_bits(self.u32()?))
    }
    fn vec3(&mut self) -> std::result::Result<Vec3, String> {
        Ok(Vec3::new(self.f32()?, self.f32()?, self.f32()?))
    }
    fn u32s(&mut self, n: usize) -> std::result::Result<Vec<u32>, String> {
        let raw = self.take(n * 4)?;
        Ok(raw
            .chunks_exact(4)
            .map(|c| u32::from_le_bytes(c.try_into().expect("4 bytes")))
            .collect())
    }
}

/// Parses `.mco` bytes of version 1 or 2; the error says what is wrong
/// (no path).
pub(crate) fn decode(bytes: &[u8]) -> std::result::Result<McoModel, String> {
    match crate::model_file_v2::file_version(bytes) {
        Some(crate::model_file_v2::VERSION) => return crate::model_file_v2::decode(bytes),
        Some(v) if v != VERSION => {
            return Err(format!(
                "unsupported .mco version {v} (this lodkit reads versions 1 and 2)"
            ));
        }
        _ => {}
    }
    if bytes.len() < HEADER_BYTES + 4 {
        return Err(format!(
            "not an .mco file: {} bytes, shorter than the {}-byte header",
            bytes.len(),
            HEADER_BYTES + 4
        ));
    }
    if bytes[..8] != MAGIC {
        return Err("not an .mco file: bad signature".into());
    }
    let mut r = Reader { b: bytes, at: 8 };
    let version = r.u32()?;
    if version != VERSION {
        return Err(format!(
            "unsupported .mco version {version} (this lodkit reads versions 1 and 2)"
        ));
    }
    let flags = r.u32()?;
    if flags > 1 {
        return Err(format!("unknown flags {flags:#x}"));
    }
    let origin = r.vec3()?;
    let cube = r.f32()?;
    let depth = r.u32()?;
    let resolution = r.u32()?;
    if !(origin.is_finite() && cube.is_finite() && cube > 0.0) || depth > KEY_BITS - 1 {
        return Err("invalid lattice (origin, cube size or depth)".into());
    }
    let stats = BuildStats {
        input_samples: r.u64()?,
        unpatched: {
            r.u64()?; // reserved (an old file's build time): skipped
            r.u64()?
        },
    };
    let mut c = [0usize; 9];
    for x in &mut c {
        *x = r.u32()? as usize;
    }
    let [v, n, t, l, g, a, p, s, d] = c;
    // Exact size from the counts, in u64 (no overflow on 32-bit counts).
    let expect: u64 = HEADER_BYTES as u64
        + 28 * v as u64
        + (NODE_BYTES as u64 + 8) * n as u64
        + 4 * (t + l + g + a + d) as u64
        + 12 * p as u64
        + 8 * s as u64
        + 4;
    if expect != bytes.len() as u64 {
        return Err(format!(
            "size mismatch: the header's counts need {expect} bytes, the file has {}",
            bytes.len()
        ));
    }
    let body = &bytes[..bytes.len() - 4];
    let stored = u32::from_le_bytes(bytes[bytes.len() - 4..].try_into().expect("4 bytes"));
    if crc32fast::hash(body) != stored {
        return Err("checksum mismatch: the file is corrupted".into());
    }
    let mut vb = VertexBuffer {
        positions: Vec::with_capacity(v),
        normals: Vec::with_capacity(v),
        colors: Vec::with_capacity(v),
    };
    for _ in 0..v {
        vb.positions.push(r.vec3()?);
    }
    for _ in 0..v {
        vb.normals.push(r.vec3()?);
    }
    for _ in 0..v {
        vb.colors.push(r.take(4)?.try_into().expect("4 bytes"));
    }
    let mut nodes = Vec::with_capacity(n);
    for _ in 0..n {
        let coord = [r.u32()?, r.u32()?, r.u32()?];
        nodes.push(Node {
            coord,
            parent: r.u32()?,
            first_child: r.u32()?,
            tri_start: r.u32()?,
            patch_start: r.u32()?,
            deps_start: r.u32()?,
            tri_count: r.u16()?,
            deps_count: r.u16()?,
            child_count: r.u8()?,
            level: r.u8()?,
            patch_count: r.u8()?,
            config: r.u8()?,
        });
    }
    let metric = (0..n)
        .map(|_| r.f32())
        .collect::<std::result::Result<Vec<_>, _>>()?;
    let prio = r.u32s(n)?;
    let tris = r.u32s(t)?;
    let lod = r.u32s(l)?;
    let groups = r.u32s(g)?;
    let acc = r.u32s(a)?;
    let mut patches = Vec::with_capacity(p);
    for _ in 0..p {
        patches.push(Patch {
            coarse: r.u32()?,
            subs_start: r.u32()?,
            subs_count: r.u32()?,
        });
    }
    let mut subs = Vec::with_capacity(s);
    for _ in 0..s {
        subs.push([r.u32()?, r.u32()?]);
    }
    let deps = r.u32s(d)?;
    let m = McoModel {
        grid: Grid {
            origin,
            cube,
            depth,
            resolution,
        },
        has_colors: flags & 1 == 1,
        vertices: vb,
        nodes,
        tris,
        metric,
        prio,
        lod,
        groups,
        acc,
        patches,
        subs,
        deps,
        stats,
        ..Default::default()
    };
    validate(&m)?;
    let mut m = m;
    m.prepare_extraction();
    Ok(m)
}

/// Every index extraction follows must be in range, and the tables must
/// agree with each other (the tree, the LOD tables, finite positions,
/// normals and metrics). `O(size)`.
pub(crate) fn validate(m: &McoModel) -> std::result::Result<(), String> {
    let (v, n) = (m.vertices.len() as u64, m.nodes.len() as u64);
    if n == 0 {
        return Err("the model has no nodes".into());
    }
    if let Some(i) = m.tris.iter().position(|&x| x as u64 >= v) {
        return Err(format!("triangle index {i} points past the {v} vertices"));
    }
    if !m.tris.len().is_multiple_of(3) {
        return Err("the triangle index count is not a multiple of 3".into());
    }
    for (i, nd) in m.nodes.iter().enumerate() {
        let bad = |what: &str| Err(format!("node {i}: {what} out of range"));
        if (nd.parent != u32::MAX && nd.parent as u64 >= n) || (i == 0) != (nd.parent == u32::MAX) {
            return bad("parent");
        }
        if nd.first_child as u64 + nd.child_count as u64 > n
            || (nd.child_count > 0 && nd.first_child as usize <= i)
        {
            return bad("children");
        }
        if nd.tri_start as u64 + 3 * nd.tri_count as u64 > m.tris.len() as u64
            || nd.tri_count as usize > MAX_NODE_TRIANGLES
        {
            return bad("triangles");
        }
        if nd.patch_start as u64 + nd.patch_count as u64 > m.patches.len() as u64
            || nd.patch_count > 6
        {
            return bad("patches");
        }
        if nd.deps_start as u64 + nd.deps_count as u64 > m.deps.len() as u64 {
            return bad("balance dependencies");
        }
        if nd.level as u32 > m.grid.depth {
            return bad("level");
        }
    }
    for (i, p) in m.patches.iter().enumerate() {
        if p.coarse as u64 >= n
            || p.subs_start as u64 + p.subs_count as u64 > m.subs.len() as u64
            || p.subs_count as usize > MAX_PATCH_SUBS
        {
            return Err(format!("patch {i} out of range"));
        }
    }
    if m.subs.iter().any(|s| s[0] as u64 >= v || s[1] as u64 >= v) {
        return Err("a crack-patch vertex is out of range".into());
    }
    if m.deps.iter().any(|&x| x as u64 >= n) || m.lod.iter().any(|&x| x as u64 >= n) {
        return Err("a node reference is out of range".into());
    }
    if m.groups.first() != Some(&0)
        || m.groups.windows(2).any(|w| w[0] > w[1])
        || *m.groups.last().expect("non-empty") as usize > m.lod.len()
    {
        return Err("the LOD groups are not an increasing prefix of the LOD array".into());
    }
    if m.acc.len() != m.groups.len() {
        return Err("the accumulation table does not match the LOD numbers".into());
    }
    if m.prio.len() != m.nodes.len() || m.metric.len() != m.nodes.len() {
        return Err("per-node arrays do not match the node count".into());
    }
    if m.prio
        .iter()
        .any(|&k| k != u32::MAX && (k == 0 || k as usize >= m.groups.len()))
    {
        return Err("a priority number is out of range".into());
    }
    if m.vertices.normals.len() != m.vertices.positions.len()
        || m.vertices.colors.len() != m.vertices.positions.len()
    {
        return Err("vertex arrays differ in length".into());
    }
    if let Some(i) = (m.vertices.positions.iter().zip(&m.vertices.normals))
        .position(|(p, n)| !(p.is_finite() && n.is_finite()))
    {
        return Err(format!("vertex {i}: position or normal is not finite"));
    }
    if let Some(i) = m.metric.iter().position(|x| !x.is_finite()) {
        return Err(format!("node {i}: LOD metric is not finite"));
    }
    validate_tree(m)?;
    validate_lod_tables(m)
}

/// The nodes form one tree: each node's children follow it, name it as
/// their parent, and are octants of its cube one level down; every node
/// but the root is listed as a child exactly once. (Run after
/// [`validate`]'s range checks.)
fn validate_tree(m: &McoModel) -> std::result::Result<(), String> {
    let mut listed = 0u64;
    for (i, nd) in m.nodes.iter().enumerate() {
        for c in m.children(i as u32) {
            let cn = &m.nodes[c as usize];
            if cn.parent != i as u32 {
                return Err(format!(
                    "node {c}: its parent is {}, but node {i} lists it as a child",
                    cn.parent
                ));
            }
            if cn.level as u32 + 1 != nd.level as u32
                || (0..3).any(|a| cn.coord[a] >> 1 != nd.coord[a])
            {
                return Err(format!(
                    "node {c}: not an octant of its parent {i}'s cube one level down"
                ));
            }
        }
        listed += nd.child_count as u64;
    }
    if listed != m.nodes.len() as u64 - 1 {
        return Err(format!(
            "the nodes are not one tree: {listed} are children, {} expected",
            m.nodes.len() - 1
        ));
    }
    Ok(())
}

/// The LOD array, priority numbers, balance dependencies and the
/// accumulation table agree with each other and with the tree: LOD number
/// `k` expands `lod[groups[k-1]..groups[k]]` (at least one node), those
/// nodes and no others have priority number `k`, each has children, was
/// drawn before (its parent expanded at an earlier LOD number) and has its
/// balance dependencies expanded by then; and `acc[k]` is the triangle
/// count those expansions give, recomputed from the nodes' own counts.
/// (Run after [`validate`]'s range checks and [`validate_tree`].)
fn validate_lod_tables(m: &McoModel) -> std::result::Result<(), String> {
    let last = *m.groups.last().expect("non-empty") as usize;
    if last != m.lod.len() {
        return Err(format!(
            "the LOD groups cover {last} of the LOD array's {} entries",
            m.lod.len()
        ));
    }
    let numbered = m.prio.iter().filter(|&&k| k != u32::MAX).count();
    if numbered != m.lod.len() {
        return Err(format!(
            "{numbered} nodes have a priority number, the LOD array has {} entries",
            m.lod.len()
        ));
    }
    let mut tris = m.nodes[0].tri_count as u64;
    if m.acc[0] as u64 != tris {
        return Err(format!(
            "the triangle table gives {} triangles at LOD 0, the root has {tris}",
            m.acc[0]
        ));
    }
    for k in 1..m.groups.len() {
        if m.groups[k] == m.groups[k - 1] {
            return Err(format!("LOD {k} expands no node"));
        }
        for &n in m.group(k) {
            let nd = &m.nodes[n as usize];
            if m.prio[n as usize] != k as u32 {
                return Err(format!(
                    "LOD {k}: node {n} has priority number {}",
                    m.prio[n as usize]
                ));
            }
            if nd.child_count == 0 {
                return Err(format!("LOD {k}: node {n} has no children to expand"));
            }
            if nd.parent != u32::MAX && m.prio[nd.parent as usize] >= k as u32 {
                return Err(format!(
                    "LOD {k}: node {n} expands before its parent {}",
                    nd.parent
                ));
            }
            let deps = &m.deps[nd.deps_start as usize..][..nd.deps_count as usize];
            if let Some(d) = deps.iter().find(|&&d| m.prio[d as usize] > k as u32) {
                return Err(format!(
                    "LOD {k}: node {n} expands before its balance dependency {d}"
                ));
            }
            // `n` is drawn until now (parent expanded earlier, itself not).
            tris = tris.saturating_sub(nd.tri_count as u64);
            tris += m
                .children(n)
                .map(|c| m.nodes[c as usize].tri_count as u64)
                .sum::<u64>();
        }
        if m.acc[k] as u64 != tris {
            return Err(format!(
                "the triangle table gives {} triangles at LOD {k}, its nodes draw {tris}",
                m.acc[k]
            ));
        }
    }
    Ok(())
}

impl McoModel {
    /// The model as `.mco` bytes (`docs/formats/mco.md`, version
    /// [`FORMAT_VERSION`]: LOD-ordered, deflated chunks, so any prefix
    /// serves a coarse cut): deterministic — the same model always gives
    /// the same bytes (no time stamps, no paths). Lossless for a built model
    /// (or one read from version 2): [`McoModel::from_bytes`] gives a model whose every cut
    /// is this one's, bit for bit (positions, normals, colours; vertices
    /// renumbered). No larger than the model's binary PLY on the shipped
    /// bunny. `O(size)`.
    pub fn to_bytes(&self) -> Vec<u8> {
        crate::model_file_v2::encode(self)
    }

    /// Reads a model from `.mco` bytes (a file's contents, or an
    /// in-memory buffer such as a download).
    ///
    /// Reads versions 1 and 2. Errors ([`Error::Format`], one line):
    /// wrong signature or version,
    /// a size that differs from what the header's counts imply, a
    /// checksum mismatch, any index out of range, or tables that disagree
    /// (the octree, the LOD array and priority numbers, the per-LOD
    /// triangle counts against the nodes' triangles). Every check runs
    /// before the model is used, so a model that loads can never make a
    /// cut panic or read out of bounds; untrusted bytes are safe. Memory
    /// is allocated only after the size check: at most a small multiple
    /// of `bytes.len()`. Cost: `O(size)`, plus building the extraction
    /// tables (`O(n log n)` in the triangles).
    pub fn from_bytes(bytes: &[u8]) -> Result<McoModel> {
        decode(bytes).map_err(Error::Format)
    }

    /// Writes the model to `path` as `.mco` bytes ([`McoModel::to_bytes`]),
    /// atomically: a failed write leaves no partial file. Errors name the
    /// file.
    pub fn save(&self, path: &Path) -> Result<()> {
        save(path, self)
    }

    /// Reads a `.mco` file ([`McoModel::from_bytes`]); files over 16 GiB
    /// are refused before reading. Errors ([`Error::File`]) name the file
    /// and say what is wrong, one line.
    pub fn load(path: &Path) -> Result<McoModel> {
        load(path)
    }

    /// The `.mco` format version `bytes` declare (1 or 2), or `None` when
    /// they are too short or lack the signature. Reads 12 bytes; checks
    /// nothing else.
    pub fn file_version(bytes: &[u8]) -> Option<u32> {
        crate::model_file_v2::file_version(bytes)
    }

    /// The chunk table of version-2 bytes, in file order: a prefix through
    /// chunk `c` serves LOD numbers `0..=last_lod` of that chunk. Errors
    /// ([`Error::Format`], one line) as [`McoModel::from_bytes`], and for
    /// version-1 bytes (which have no chunks). Cost: `O(size)` (each chunk
    /// is inflated and checked).
    pub fn chunk_table(bytes: &[u8]) -> Result<Vec<ChunkInfo>> {
        crate::model_file_v2::chunk_table(bytes).map_err(Error::Format)
    }

    /// Reads a prefix of version-2 bytes (a partial download) as far as its
    /// complete chunks go: the model serves every LOD number up to
    /// [`PartialModel::max_lod`] exactly as the whole file would. Errors
    /// ([`Error::Format`], one line) on a bad header or chunk, or a prefix
    /// without one complete chunk; the checks of [`McoModel::from_bytes`]
    /// run on what was read. Cost: `O(prefix)`. For bytes arriving in
    /// pieces, [`McoStream`](crate::McoStream) reads each chunk once.
    pub fn from_prefix(bytes: &[u8]) -> Result<PartialModel> {
        crate::model_file_v2::decode_prefix(bytes).map_err(Error::Format)
    }
}

/// Writes `model` to `path` atomically, as version 2
/// ([`McoModel::to_bytes`]).
fn save(path: &Path, model: &McoModel) -> Result<()> {
    lodkit_mesh::io::write_atomic(path, &model.to_bytes())?;
    Ok(())
}

/// Reads a `.mco` file; errors name the file.
fn load(path: &Path) -> Result<McoModel> {
    let named = |message: String| Error::File {
        path: path.display().to_string(),
        message,
    };
    let meta = std::fs::metadata(path).map_err(|e| named(e.to_string()))?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(named(format!(
            "{} bytes is larger than the {MAX_FILE_BYTES}-byte limit",
            meta.len()
        )));
    }
    let bytes = std::fs::read(path).map_err(|e| named(e.to_string()))?;
    decode(&bytes).map_err(named)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::{Options, build_from_mesh};
    use rand_xoshiro::Xoshiro256PlusPlus;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};

    fn model() -> McoModel {
        build_from_mesh(
            &lodkit_mesh::shapes::icosphere(3),
            &Options {
                resolution: Some(12),
            },
        )
        .unwrap()
    }

    #[test]
    fn round_trip_is_exact_and_deterministic() {
        let m = model();
        let bytes = encode(&m);
        assert_eq!(bytes, encode(&m));
        let back = decode(&bytes).unwrap();
        assert_eq!(back, m);
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("s.mco");
        std::fs::write(&path, &bytes).unwrap();
        assert_eq!(load(&path).unwrap(), m);
    }

    #[test]
    fn truncated_and_corrupted_files_are_clear_errors() {
        let bytes = encode(&model());
        for cut in [0, 7, 8, 40, HEADER_BYTES, bytes.len() / 2, bytes.len() - 1] {
            let e = decode(&bytes[..cut]).unwrap_err();
            assert!(!e.contains('\n'));
            assert!(
                e.contains("shorter") || e.contains("size mismatch") || e.contains("signature"),
                "{cut}: {e}"
            );
        }
        let mut flipped = bytes.clone();
        let at = bytes.len() / 3;
        flipped[at] ^= 0x10;
        assert!(decode(&flipped).unwrap_err().contains("checksum"));
        let mut version = bytes.clone();
        version[8] = 9;
        assert!(decode(&version).unwrap_err().contains("version 9"));
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.mco");
        std::fs::write(&path, &bytes[..100]).unwrap();
        let msg = load(&path).unwrap_err().to_string();
        assert!(msg.starts_with(&path.display().to_string()), "{msg}");
    }

    /// Mutations with a re-computed checksum reach the semantic checks:
    /// none may panic, and every accepted model must extract safely.
    #[test]
    fn mutated_files_never_panic() {
        let m = model();
        let bytes = encode(&m);
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x2545_f491_4f6c_dd1d);
        let mut next = || rng.next_u64();
        let mut idx = Vec::new();
        for _ in 0..3000 {
            let mut b = bytes.clone();
            let body = b.len() - 4;
            for _ in 0..1 + next() % 4 {
                let at = (next() as usize) % body;
                b[at] = next() as u8;
            }
            let crc = crc32fast::hash(&b[..body]);
            b[body..].copy_from_slice(&crc.to_le_bytes());
            if let Ok(back) = decode(&b) {
                for k in [0, 1, back.max_lod() / 2, back.max_lod()] {
                    back.extract_lod(k, &mut idx);
                }
                back.extract_triangles(100, &mut idx);
                let cam = crate::Camera::looking_at(Vec3::new(0.0, 0.0, 5.0), Vec3::ZERO);
                back.extract_view(&cam, 1.0, &mut idx);
            }
        }
    }
}
