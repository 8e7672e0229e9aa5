//! `.mco` version 1: the flat arrays (`docs/formats/mco.md`). Read for
//! files written before version 2; written only by the tests, to check
//! that it still reads.

use glam::Vec3;

use super::format::MAGIC;
use super::validate::validate;
use crate::lattice::{Grid, KEY_BITS};
use crate::marching_cubes::VertexBuffer;
use crate::model::{BuildStats, McoModel, Node, Patch};

/// The version-1 layout's number (the flat arrays), which [`encode`]
/// writes and [`decode`] still reads.
pub(crate) const VERSION: u32 = 1;
/// Bytes before the arrays.
pub(crate) const HEADER_BYTES: usize = 8 + 4 + 4 + 12 + 4 + 4 + 4 + 8 + 8 + 8 + 9 * 4;
/// Bytes per node record.
pub(crate) const NODE_BYTES: usize = 40;
/// Serialises a model as version 1 (deterministic: the same model gives
/// the same bytes). Only the tests write version 1 (to check that it
/// still reads); [`McoModel::to_bytes`] writes version 2.
#[cfg(test)]
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
#[cfg(test)]
fn put_u32(out: &mut Vec<u8>, x: u32) {
    out.extend_from_slice(&x.to_le_bytes());
}
#[cfg_attr(not(test), allow(dead_code))]
#[cfg(test)]
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

/// Parses `.mco` bytes of version 1; the error says what is wrong (no
/// path).
pub(crate) fn decode(bytes: &[u8]) -> std::result::Result<McoModel, String> {
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
