//! glTF 2.0 (`.gltf` JSON and `.glb` binary): read into one [`TriMesh`],
//! write an LOD chain as one GLB.
//!
//! **Reading** takes every triangle primitive of every mesh reachable from
//! the default scene (when the file names none: from every root node; when
//! it has no nodes at all: every mesh, untransformed), with each node's world
//! transform applied. Conventions:
//! - `TRIANGLES` are read as they are; `TRIANGLE_STRIP` and `TRIANGLE_FAN`
//!   are converted to triangles (the degenerate triangles strips use as
//!   joints are dropped); points and lines are skipped;
//! - positions get the world matrix, normals its inverse transpose
//!   (renormalised; under an identity transform normals are kept exactly as
//!   stored); a mirroring transform (negative determinant) has its
//!   triangles' winding swapped so faces stay CCW seen from outside;
//! - `COLOR_0` (float, or normalised u8/u16; RGB or RGBA) is *linear* in
//!   glTF and becomes sRGB RGBA8 (alpha stays linear, RGB gets alpha 255);
//! - `TEXCOORD_0` (float or normalised u8/u16) has its V flipped:
//!   `v = 1 − v_gltf` (glTF's origin is top-left, lodkit's bottom-left);
//! - indices may be u8/u16/u32 or absent (non-indexed);
//! - an attribute is kept only if *every* primitive read has it (dropped
//!   otherwise, never filled with made-up defaults);
//! - materials, textures, skins, morph targets, cameras, animations and
//!   other texture coordinate / colour sets are ignored.
//!
//! Buffers come from the GLB `BIN` chunk, `data:` URIs (base64 only), or
//! files relative to `base_dir` (percent-decoded; `None` refuses them);
//! URLs with a scheme (`http:`, `file:`…) and absolute paths are refused.
//! Only the buffers that the primitives read actually use are resolved.
//!
//! **Guarantees on bad input**: the GLB container is parsed here, not by
//! `gltf::Glb::from_slice` (which, in gltf 1.4, subtracts 12 from the header
//! length unchecked and so panics in debug builds on a header length < 12).
//! Before `gltf`'s validation runs, every primitive's accessor indices are
//! range-checked (gltf-json 1.4's POSITION min/max check indexes the accessor
//! list without checking, and panics). Before any accessor is read through
//! `gltf`'s reader, its type, count (≥ 1), stride (≥ element size) and
//! extent (accessor inside view, view inside the buffer's real bytes, all in
//! checked arithmetic) are verified, since the reader would otherwise panic
//! (stride smaller than an element, count 0) or silently read short.
//! Sparse accessors are refused. Indices out of range, cycles in the node
//! graph and nodes with two parents are errors. All of these are one-line
//! [`ParseError`]s.
//!
//! **Writing** ([`write_glb`]): one mesh + one node per level, all nodes
//! siblings in the default scene. The node and mesh are named
//! `"{name} ({triangles} triangles)"` and the node's `extras` hold
//! `{"triangles": N, "vertices": M}`. Accessors: POSITION (f32 vec3 with
//! min/max), NORMAL (f32 vec3), COLOR_0 (normalised **u16** vec4, linear:
//! sRGB → linear in u16 is lossless for RGBA8, in u8 it is not, and
//! `write → read` must give the same colours back), TEXCOORD_0 (f32 vec2, V
//! flipped), indices u16 when every index fits below 65535 (the
//! primitive-restart value is reserved) and u32 otherwise. Each accessor has
//! its own 4-byte-aligned buffer view; the JSON chunk is padded with spaces
//! and the BIN chunk with zeros. The JSON is built with `gltf-json` types and
//! serialised with `serde_json`, whose maps are ordered: the same levels
//! always give the same bytes.

use std::borrow::Cow;
use std::collections::BTreeMap;
use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json;
use gltf::mesh::Mode;
use gltf::mesh::util::{ReadColors, ReadTexCoords};
use gltf::{Accessor, Semantic};

use crate::error::ParseError;
use crate::error::clip;
use crate::mesh::TriMesh;
use crate::parse_err;

const GLB_MAGIC: &[u8; 4] = b"glTF";
const CHUNK_JSON: &[u8; 4] = b"JSON";
const CHUNK_BIN: &[u8; 4] = b"BIN\0";

fn u32_at(b: &[u8], o: usize) -> u32 {
    u32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]])
}

/// Splits a GLB into its JSON chunk and its first BIN chunk, checking every
/// length against the bytes present.
fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), ParseError> {
    if bytes.len() < 12 {
        return Err(parse_err!(
            "GLB truncated: {} bytes, the header alone is 12",
            bytes.len()
        ));
    }
    let version = u32_at(bytes, 4);
    if version != 2 {
        return Err(parse_err!("GLB version {version} (only 2 is supported)"));
    }
    let length = u32_at(bytes, 8) as usize;
    if length < 12 || length > bytes.len() {
        return Err(parse_err!(
            "GLB header says {length} bytes but the file has {}",
            bytes.len()
        ));
    }
    let body = &bytes[..length];
    let mut at = 12usize;
    let mut json_chunk = None;
    let mut bin = None;
    while at < body.len() {
        if body.len() - at < 8 {
            return Err(parse_err!("GLB chunk header at byte {at} is truncated"));
        }
        let len = u32_at(body, at) as usize;
        let ty = &body[at + 4..at + 8];
        let start = at + 8;
        if len > body.len() - start {
            return Err(parse_err!(
                "GLB chunk at byte {at} says {len} bytes but only {} remain",
                body.len() - start
            ));
        }
        let data = &body[start..start + len];
        match (json_chunk.is_none(), ty) {
            (true, t) if t == CHUNK_JSON => json_chunk = Some(data),
            (true, _) => return Err(ParseError::new("GLB's first chunk is not JSON")),
            (false, t) if t == CHUNK_BIN && bin.is_none() => bin = Some(data),
            _ => {} // unknown chunk types are ignored, as the spec asks
        }
        at = start + len;
    }
    let json_chunk = json_chunk.ok_or_else(|| ParseError::new("GLB has no JSON chunk"))?;
    Ok((json_chunk, bin))
}

/// Decodes standard base64 (`+/`, `=` padding optional, no whitespace),
/// as glTF data URIs use it.
fn decode_base64(s: &str) -> Result<Vec<u8>, String> {
    use base64::Engine as _;
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    const ENGINE: GeneralPurpose = GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        GeneralPurposeConfig::new().with_decode_padding_mode(DecodePaddingMode::Indifferent),
    );
    ENGINE.decode(s).map_err(|e| e.to_string())
}

/// Decodes `%XX` escapes in a relative URI.
fn percent_decode(s: &str) -> Result<String, ParseError> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hex = b
                .get(i + 1..i + 3)
                .and_then(|h| std::str::from_utf8(h).ok())
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| parse_err!("buffer URI '{}' has a bad %-escape", clip(s, 48)))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| parse_err!("buffer URI '{}' is not UTF-8", clip(s, 48)))
}

/// The bytes of buffer `buffer` (see the module docs for what is accepted).
fn load_buffer<'a>(
    buffer: gltf::Buffer<'_>,
    bin: Option<&'a [u8]>,
    base_dir: Option<&Path>,
) -> Result<Cow<'a, [u8]>, ParseError> {
    let i = buffer.index();
    let uri = match buffer.source() {
        gltf::buffer::Source::Bin => {
            return bin
                .map(Cow::Borrowed)
                .ok_or_else(|| parse_err!("buffer {i} has no uri and there is no GLB BIN chunk"));
        }
        gltf::buffer::Source::Uri(u) => u,
    };
    if let Some(rest) = uri.strip_prefix("data:") {
        let (meta, data) = rest
            .split_once(',')
            .ok_or_else(|| parse_err!("buffer {i}: data URI has no ','"))?;
        if !meta.ends_with(";base64") {
            return Err(parse_err!(
                "buffer {i}: data URI is not base64 ('{}')",
                clip(meta, 48)
            ));
        }
        return decode_base64(data)
            .map(Cow::Owned)
            .map_err(|e| parse_err!("buffer {i}: data URI is not valid base64: {e}"));
    }
    let has_scheme = uri.split_once(':').is_some_and(|(s, _)| {
        !s.is_empty()
            && s.bytes()
                .all(|c| c.is_ascii_alphanumeric() || b"+.-".contains(&c))
    });
    if has_scheme || uri.starts_with('/') || uri.starts_with('\\') {
        return Err(parse_err!(
            "buffer {i}: '{}' is not a relative path (URLs and absolute paths are refused)",
            clip(uri, 48)
        ));
    }
    let rel = percent_decode(uri)?;
    let dir = base_dir.ok_or_else(|| {
        parse_err!(
            "buffer {i}: external file '{}' but no directory to resolve it against",
            clip(&rel, 48)
        )
    })?;
    let path = dir.join(&rel);
    let meta = std::fs::metadata(&path)
        .map_err(|e| parse_err!("buffer {i}: cannot open '{}': {e}", clip(&rel, 48)))?;
    if !meta.is_file() || meta.len() > super::MAX_FILE_BYTES {
        return Err(parse_err!(
            "buffer {i}: '{}' is not a regular file within the size limit",
            clip(&rel, 48)
        ));
    }
    std::fs::read(&path)
        .map(Cow::Owned)
        .map_err(|e| parse_err!("buffer {i}: cannot read '{}': {e}", clip(&rel, 48)))
}

/// Checks what gltf-json's validation indexes without checking.
fn precheck(root: &json::Root) -> Result<(), ParseError> {
    let n = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let bad = prim
                .attributes
                .values()
                .chain(prim.indices.iter())
                .map(|a| a.value())
                .find(|&a| a >= n);
            if let Some(a) = bad {
                return Err(parse_err!(
                    "mesh {m} primitive {p} uses accessor {a} but there are {n} accessors"
                ));
            }
        }
    }
    Ok(())
}

/// Parses and validates the document; returns it with the GLB BIN chunk.
fn parse_document(bytes: &[u8]) -> Result<(gltf::Document, Option<&[u8]>), ParseError> {
    if bytes.is_empty() {
        return Err(ParseError::new("empty file"));
    }
    // A UTF-8 byte-order mark is not allowed by the spec but is tolerated.
    let unbom = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let (json_bytes, bin) = if bytes.starts_with(GLB_MAGIC) {
        split_glb(bytes)?
    } else if unbom.trim_ascii_start().starts_with(b"{") {
        (unbom, None)
    } else {
        let head = &bytes[..bytes.len().min(4)];
        return Err(parse_err!(
            "neither GLB (magic 'glTF') nor glTF JSON (starts with '{{'): starts with '{}'",
            head.escape_ascii()
        ));
    };
    let root: json::Root =
        json::deserialize::from_slice(json_bytes).map_err(|e| parse_err!("glTF JSON: {e}"))?;
    precheck(&root)?;
    let doc = gltf::Document::from_json(root).map_err(|e| match e {
        gltf::Error::Validation(errs) => {
            let more = match errs.len() {
                0 | 1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            match errs.first() {
                Some((path, err)) => parse_err!("invalid glTF: {path}: {err}{more}"),
                None => ParseError::new("invalid glTF"),
            }
        }
        other => parse_err!("glTF: {other}"),
    })?;
    Ok((doc, bin))
}

/// One mesh placed in the world by a node.
struct Instance<'a> {
    mesh: gltf::Mesh<'a>,
    world: Mat4,
}

/// The meshes to read, with world transforms (see the module docs).
fn instances(doc: &gltf::Document) -> Result<Vec<Instance<'_>>, ParseError> {
    if doc.nodes().len() == 0 {
        return Ok(doc
            .meshes()
            .map(|mesh| Instance {
                mesh,
                world: Mat4::IDENTITY,
            })
            .collect());
    }
    let roots: Vec<gltf::Node> = match doc.default_scene() {
        Some(s) => s.nodes().collect(),
        None => {
            let mut is_child = vec![false; doc.nodes().len()];
            for n in doc.nodes() {
                for c in n.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut seen = vec![false; doc.nodes().len()];
    let mut stack: Vec<(gltf::Node, Mat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, Mat4::IDENTITY))
        .collect();
    let mut out = Vec::new();
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut seen[node.index()], true) {
            return Err(parse_err!(
                "node {} is reached twice: the node graph has a cycle or a node with two parents",
                node.index()
            ));
        }
        let world = parent * Mat4::from_cols_array_2d(&node.transform().matrix());
        if let Some(mesh) = node.mesh() {
            out.push(Instance { mesh, world });
        }
        let children: Vec<gltf::Node> = node.children().collect();
        stack.extend(children.into_iter().rev().map(|c| (c, world)));
    }
    Ok(out)
}

/// Verifies an accessor so that `gltf`'s reader can read all `count`
/// elements without panicking or coming up short; returns the count.
fn check_accessor(
    acc: &Accessor<'_>,
    what: &str,
    allowed: &[(DataType, Dimensions)],
    buffers: &[Option<Cow<'_, [u8]>>],
) -> Result<usize, ParseError> {
    let i = acc.index();
    if acc.sparse().is_some() {
        return Err(parse_err!(
            "accessor {i} ({what}) is sparse, which is not supported"
        ));
    }
    let ty = (acc.data_type(), acc.dimensions());
    if !allowed.contains(&ty) {
        return Err(parse_err!(
            "accessor {i} ({what}) has type {:?} {:?}, which is not allowed there",
            ty.0,
            ty.1
        ));
    }
    let count = acc.count();
    if count == 0 {
        return Err(parse_err!("accessor {i} ({what}) is empty (count 0)"));
    }
    let view = acc
        .view()
        .ok_or_else(|| parse_err!("accessor {i} ({what}) has no bufferView"))?;
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(parse_err!(
            "buffer view {} has stride {stride}, less than accessor {i}'s element size {elem}",
            view.index()
        ));
    }
    let end = (count as u64 - 1)
        .checked_mul(stride as u64)
        .and_then(|x| x.checked_add(elem as u64))
        .and_then(|x| x.checked_add(acc.offset() as u64));
    match end {
        Some(e) if e <= view.length() as u64 => {}
        _ => {
            return Err(parse_err!(
                "accessor {i} ({what}): {count} elements from offset {} do not fit in buffer view {} ({} bytes)",
                acc.offset(),
                view.index(),
                view.length()
            ));
        }
    }
    let b = view.buffer().index();
    let have = buffers
        .get(b)
        .and_then(|d| d.as_ref())
        .map_or(0, |d| d.len()) as u64;
    let view_end = (view.offset() as u64).checked_add(view.length() as u64);
    if view_end.is_none_or(|e| e > have) {
        return Err(parse_err!(
            "buffer view {} (bytes {}..+{}) is outside buffer {b}, which has {have} bytes",
            view.index(),
            view.offset(),
            view.length()
        ));
    }
    Ok(count)
}

/// A primitive to read, from an [`Instance`].
struct Part<'a> {
    prim: gltf::Primitive<'a>,
    world: Mat4,
    mesh: usize,
}

/// glTF linear [0, 1] → sRGB byte.
fn linear_to_srgb8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let s = if x <= 0.003_130_8 {
        x * 12.92
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    };
    (s * 255.0).round().clamp(0.0, 255.0) as u8
}

/// sRGB byte → linear [0, 1].
fn srgb8_to_linear(c: u8) -> f32 {
    let s = c as f32 / 255.0;
    if s <= 0.040_45 {
        s / 12.92
    } else {
        ((s + 0.055) / 1.055).powf(2.4)
    }
}

fn unit8(x: f32) -> u8 {
    let x = if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    (x * 255.0).round() as u8
}

/// Reads a glTF or GLB file into one mesh (see the module docs).
pub fn read(bytes: &[u8], base_dir: Option<&Path>) -> Result<TriMesh, ParseError> {
    let (doc, bin) = parse_document(bytes)?;
    let mut parts = Vec::new();
    for inst in instances(&doc)? {
        for prim in inst.mesh.primitives() {
            if matches!(
                prim.mode(),
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                parts.push(Part {
                    prim,
                    world: inst.world,
                    mesh: inst.mesh.index(),
                });
            }
        }
    }
    if parts.is_empty() {
        return Err(ParseError::new(
            "no triangles: the scene has no triangle primitives",
        ));
    }
    let all = |s: &Semantic| parts.iter().all(|p| p.prim.get(s).is_some());
    let has_n = all(&Semantic::Normals);
    let has_c = all(&Semantic::Colors(0));
    let has_uv = all(&Semantic::TexCoords(0));

    // Resolve exactly the buffers the accessors to read live in.
    let mut buffers: Vec<Option<Cow<[u8]>>> = vec![None; doc.buffers().len()];
    for p in &parts {
        let mut accs: Vec<Accessor> = vec![];
        accs.extend(p.prim.get(&Semantic::Positions));
        accs.extend(p.prim.indices());
        if has_n {
            accs.extend(p.prim.get(&Semantic::Normals));
        }
        if has_c {
            accs.extend(p.prim.get(&Semantic::Colors(0)));
        }
        if has_uv {
            accs.extend(p.prim.get(&Semantic::TexCoords(0)));
        }
        for a in accs {
            if let Some(v) = a.view() {
                let b = v.buffer();
                let bi = b.index();
                if buffers[bi].is_none() {
                    buffers[bi] = Some(load_buffer(b, bin, base_dir)?);
                }
            }
        }
    }

    use DataType::{F32, U8, U16, U32};
    use Dimensions::{Scalar, Vec2 as D2, Vec3 as D3, Vec4 as D4};
    // Check every accessor and count the output before allocating it.
    let mut total = 0u64;
    for (k, p) in parts.iter().enumerate() {
        let ctx = |w: &str| format!("mesh {} primitive {k}: {w}", p.mesh);
        let pos = p
            .prim
            .get(&Semantic::Positions)
            .ok_or_else(|| parse_err!("mesh {} primitive {k} has no POSITION", p.mesh))?;
        let n = check_accessor(&pos, &ctx("POSITION"), &[(F32, D3)], &buffers)?;
        let same = |a: Option<Accessor>, w: &str, t: &[(DataType, Dimensions)]| {
            if let Some(a) = a {
                let c = check_accessor(&a, &ctx(w), t, &buffers)?;
                if c != n {
                    return Err(parse_err!(
                        "mesh {} primitive {k}: {w} has {c} elements but POSITION has {n}",
                        p.mesh
                    ));
                }
            }
            Ok(())
        };
        if has_n {
            same(p.prim.get(&Semantic::Normals), "NORMAL", &[(F32, D3)])?;
        }
        if has_c {
            let t = [
                (U8, D3),
                (U16, D3),
                (F32, D3),
                (U8, D4),
                (U16, D4),
                (F32, D4),
            ];
            same(p.prim.get(&Semantic::Colors(0)), "COLOR_0", &t)?;
        }
        if has_uv {
            let t = [(U8, D2), (U16, D2), (F32, D2)];
            same(p.prim.get(&Semantic::TexCoords(0)), "TEXCOORD_0", &t)?;
        }
        if let Some(ix) = p.prim.indices() {
            check_accessor(
                &ix,
                &ctx("indices"),
                &[(U8, Scalar), (U16, Scalar), (U32, Scalar)],
                &buffers,
            )?;
        }
        total += n as u64;
    }
    if total > u32::MAX as u64 {
        return Err(parse_err!(
            "{total} vertices once instanced: more than 32-bit indices can address"
        ));
    }

    let mut out = TriMesh {
        positions: Vec::with_capacity(total as usize),
        normals: has_n.then(|| Vec::with_capacity(total as usize)),
        colors: has_c.then(|| Vec::with_capacity(total as usize)),
        uvs: has_uv.then(|| Vec::with_capacity(total as usize)),
        faces: Vec::new(),
    };
    for (k, p) in parts.iter().enumerate() {
        let reader = p
            .prim
            .reader(|b| buffers.get(b.index()).and_then(|d| d.as_deref()));
        let base = out.positions.len() as u32;
        let short = || parse_err!("mesh {} primitive {k}: accessor data ended early", p.mesh);
        let pos: Vec<[f32; 3]> = reader.read_positions().ok_or_else(short)?.collect();
        let n = pos.len();
        let m3 = Mat3::from_mat4(p.world);
        let det = m3.determinant();
        // Cofactor matrix = det × inverse transpose: defined even when the
        // matrix is singular, and the sign fix keeps its direction right.
        let cof = Mat3::from_cols(
            m3.y_axis.cross(m3.z_axis),
            m3.z_axis.cross(m3.x_axis),
            m3.x_axis.cross(m3.y_axis),
        ) * if det < 0.0 { -1.0 } else { 1.0 };
        out.positions.extend(
            pos.iter()
                .map(|q| p.world.transform_point3(Vec3::from_array(*q))),
        );
        if let Some(dst) = out.normals.as_mut() {
            let src: Vec<[f32; 3]> = reader.read_normals().ok_or_else(short)?.collect();
            if p.world == Mat4::IDENTITY {
                dst.extend(src.iter().map(|q| Vec3::from_array(*q)));
            } else {
                dst.extend(
                    src.iter()
                        .map(|q| (cof * Vec3::from_array(*q)).normalize_or_zero()),
                );
            }
        }
        if let Some(dst) = out.colors.as_mut() {
            let lin = |c: [f32; 3]| c.map(linear_to_srgb8);
            match reader.read_colors(0).ok_or_else(short)? {
                ReadColors::RgbU8(it) => dst.extend(it.map(|c| {
                    let [r, g, b] = lin(c.map(|x| x as f32 / 255.0));
                    [r, g, b, 255]
                })),
                ReadColors::RgbU16(it) => dst.extend(it.map(|c| {
                    let [r, g, b] = lin(c.map(|x| x as f32 / 65535.0));
                    [r, g, b, 255]
                })),
                ReadColors::RgbF32(it) => dst.extend(it.map(|c| {
                    let [r, g, b] = lin(c);
                    [r, g, b, 255]
                })),
                ReadColors::RgbaU8(it) => dst.extend(it.map(|c| {
                    let [r, g, b] = lin([c[0], c[1], c[2]].map(|x| x as f32 / 255.0));
                    [r, g, b, c[3]]
                })),
                ReadColors::RgbaU16(it) => dst.extend(it.map(|c| {
                    let [r, g, b] = lin([c[0], c[1], c[2]].map(|x| x as f32 / 65535.0));
                    [r, g, b, unit8(c[3] as f32 / 65535.0)]
                })),
                ReadColors::RgbaF32(it) => dst.extend(it.map(|c| {
                    let [r, g, b] = lin([c[0], c[1], c[2]]);
                    [r, g, b, unit8(c[3])]
                })),
            }
        }
        if let Some(dst) = out.uvs.as_mut() {
            let it: ReadTexCoords = reader.read_tex_coords(0).ok_or_else(short)?;
            dst.extend(it.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)));
        }
        if [
            out.normals.as_ref().map(Vec::len),
            out.colors.as_ref().map(Vec::len),
            out.uvs.as_ref().map(Vec::len),
        ]
        .iter()
        .flatten()
        .any(|&l| l != out.positions.len())
        {
            return Err(short());
        }
        let idx: Vec<u32> = match reader.read_indices() {
            Some(r) => r.into_u32().collect(),
            None => (0..n as u32).collect(),
        };
        if let Some(&bad) = idx.iter().find(|&&i| i as usize >= n) {
            return Err(parse_err!(
                "mesh {} primitive {k}: index {bad} out of range ({n} vertices)",
                p.mesh
            ));
        }
        let mirrored = det < 0.0;
        let mut push = |a: u32, b: u32, c: u32| {
            let f = if mirrored { [a, c, b] } else { [a, b, c] };
            out.faces.push(f.map(|i| base + i));
        };
        match p.prim.mode() {
            Mode::Triangles => {
                if !idx.len().is_multiple_of(3) {
                    return Err(parse_err!(
                        "mesh {} primitive {k}: {} indices is not a whole number of triangles",
                        p.mesh,
                        idx.len()
                    ));
                }
                for t in idx.chunks_exact(3) {
                    push(t[0], t[1], t[2]);
                }
            }
            Mode::TriangleStrip => {
                for i in 0..idx.len().saturating_sub(2) {
                    let (a, b, c) = if i % 2 == 0 {
                        (idx[i], idx[i + 1], idx[i + 2])
                    } else {
                        (idx[i], idx[i + 2], idx[i + 1])
                    };
                    if a != b && b != c && a != c {
                        push(a, b, c);
                    }
                }
            }
            Mode::TriangleFan => {
                for i in 1..idx.len().saturating_sub(1) {
                    let (a, b, c) = (idx[i], idx[i + 1], idx[0]);
                    if a != b && b != c && a != c {
                        push(a, b, c);
                    }
                }
            }
            _ => {}
        }
    }
    if out.faces.is_empty() {
        return Err(ParseError::new("no triangles"));
    }
    Ok(out)
}

// ---------------------------------------------------------------- writing

/// Builds the BIN chunk and the JSON objects that point into it.
struct Builder {
    bin: Vec<u8>,
    root: json::Root,
}

impl Builder {
    /// Appends `bytes` as a new 4-byte-aligned buffer view and an accessor
    /// over it; returns the accessor's index.
    #[allow(clippy::too_many_arguments)]
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        component: json::accessor::ComponentType,
        ty: json::accessor::Type,
        normalized: bool,
        target: json::buffer::Target,
        min_max: Option<(json::Value, json::Value)>,
    ) -> json::Index<json::Accessor> {
        debug_assert!(self.bin.len().is_multiple_of(4));
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let view = self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: bytes.len().into(),
            byte_offset: Some(offset.into()),
            byte_stride: None,
            name: None,
            target: Some(json::validation::Checked::Valid(target)),
            extensions: None,
            extras: None,
        });
        let (min, max) = match min_max {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: count.into(),
            component_type: json::validation::Checked::Valid(json::accessor::GenericComponentType(
                component,
            )),
            extensions: None,
            extras: None,
            type_: json::validation::Checked::Valid(ty),
            min,
            max,
            name: None,
            normalized,
            sparse: None,
        })
    }
}

fn le_bytes<const N: usize, T: Copy>(items: &[T], f: impl Fn(T) -> [u8; N]) -> Vec<u8> {
    let mut v = Vec::with_capacity(items.len() * N);
    for &x in items {
        v.extend_from_slice(&f(x));
    }
    v
}

fn vec3_bytes(v: &[Vec3]) -> Vec<u8> {
    let mut out = Vec::with_capacity(v.len() * 12);
    for p in v {
        for c in p.to_array() {
            out.extend_from_slice(&c.to_le_bytes());
        }
    }
    out
}

/// Writes the levels as one GLB (see the module docs for the layout).
///
/// Errors: no levels, a level with no faces, a level that breaks the
/// [`TriMesh`] invariant (index out of range, attribute length, non-finite
/// value), or more data than a GLB can hold (4 GiB).
pub fn write_glb(levels: &[(&str, &TriMesh)]) -> Result<Vec<u8>, ParseError> {
    use json::accessor::{ComponentType as C, Type as T};
    use json::buffer::Target::{ArrayBuffer, ElementArrayBuffer};
    use json::validation::Checked::Valid;

    if levels.is_empty() {
        return Err(ParseError::new("GLB: no levels to write"));
    }
    let mut b = Builder {
        bin: Vec::new(),
        root: json::Root {
            asset: json::Asset {
                generator: Some(format!("lodkit {}", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        },
    };
    let mut nodes = Vec::new();
    for (name, m) in levels {
        m.validate()
            .map_err(|e| parse_err!("GLB level '{name}': {e}"))?;
        if m.faces.is_empty() {
            return Err(parse_err!("GLB level '{name}' has no faces"));
        }
        let n = m.positions.len();
        let bbox = m.bbox();
        let mut attributes = BTreeMap::new();
        let pos = b.accessor(
            &vec3_bytes(&m.positions),
            n,
            C::F32,
            T::Vec3,
            false,
            ArrayBuffer,
            Some((
                json::Value::from(bbox.min.to_array().to_vec()),
                json::Value::from(bbox.max.to_array().to_vec()),
            )),
        );
        attributes.insert(Valid(json::mesh::Semantic::Positions), pos);
        if let Some(normals) = &m.normals {
            let a = b.accessor(
                &vec3_bytes(normals),
                n,
                C::F32,
                T::Vec3,
                false,
                ArrayBuffer,
                None,
            );
            attributes.insert(Valid(json::mesh::Semantic::Normals), a);
        }
        if let Some(colors) = &m.colors {
            let q = |c: u8| ((srgb8_to_linear(c) * 65535.0).round() as u16).to_le_bytes();
            let bytes = le_bytes(colors, |c: [u8; 4]| {
                let [r0, r1] = q(c[0]);
                let [g0, g1] = q(c[1]);
                let [b0, b1] = q(c[2]);
                let [a0, a1] = (c[3] as u16 * 257).to_le_bytes();
                [r0, r1, g0, g1, b0, b1, a0, a1]
            });
            let a = b.accessor(&bytes, n, C::U16, T::Vec4, true, ArrayBuffer, None);
            attributes.insert(Valid(json::mesh::Semantic::Colors(0)), a);
        }
        if let Some(uvs) = &m.uvs {
            let bytes = le_bytes(uvs, |t: Vec2| {
                let [u0, u1, u2, u3] = t.x.to_le_bytes();
                let [v0, v1, v2, v3] = (1.0 - t.y).to_le_bytes();
                [u0, u1, u2, u3, v0, v1, v2, v3]
            });
            let a = b.accessor(&bytes, n, C::F32, T::Vec2, false, ArrayBuffer, None);
            attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), a);
        }
        let flat: Vec<u32> = m.faces.iter().flatten().copied().collect();
        let indices = if n < u16::MAX as usize {
            let bytes = le_bytes(&flat, |i: u32| (i as u16).to_le_bytes());
            b.accessor(
                &bytes,
                flat.len(),
                C::U16,
                T::Scalar,
                false,
                ElementArrayBuffer,
                None,
            )
        } else {
            let bytes = le_bytes(&flat, |i: u32| i.to_le_bytes());
            b.accessor(
                &bytes,
                flat.len(),
                C::U32,
                T::Scalar,
                false,
                ElementArrayBuffer,
                None,
            )
        };
        let label = format!("{name} ({} triangles)", m.faces.len());
        let mesh = b.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: Some(label.clone()),
            primitives: vec![json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(indices),
                material: None,
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            }],
            weights: None,
        });
        let extras = serde_json::value::to_raw_value(&serde_json::json!({
            "triangles": m.faces.len(),
            "vertices": n,
        }))
        .map_err(|e| parse_err!("GLB: {e}"))?;
        nodes.push(b.root.push(json::Node {
            camera: None,
            children: None,
            extensions: None,
            extras: Some(extras),
            matrix: None,
            mesh: Some(mesh),
            name: Some(label),
            rotation: None,
            scale: None,
            translation: None,
            skin: None,
            weights: None,
        }));
    }
    let bin_len = b.bin.len();
    if bin_len > u32::MAX as usize - 1024 {
        return Err(parse_err!(
            "GLB: {bin_len} bytes of geometry, over the 4 GiB GLB limit"
        ));
    }
    b.root.push(json::Buffer {
        byte_length: bin_len.into(),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });
    let scene = b.root.push(json::Scene {
        extensions: None,
        extras: None,
        name: None,
        nodes,
    });
    b.root.scene = Some(scene);

    let mut js = serde_json::to_vec(&b.root).map_err(|e| parse_err!("GLB: {e}"))?;
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let total = 12 + 8 + js.len() + 8 + bin_len;
    let total32 = u32::try_from(total)
        .map_err(|_| parse_err!("GLB: {total} bytes, over the 4 GiB GLB limit"))?;
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(GLB_MAGIC);
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&total32.to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(CHUNK_JSON);
    out.extend_from_slice(&js);
    out.extend_from_slice(&(bin_len as u32).to_le_bytes());
    out.extend_from_slice(CHUNK_BIN);
    out.extend_from_slice(&b.bin);
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn b64(data: &[u8]) -> String {
        use base64::Engine as _;
        base64::engine::general_purpose::STANDARD.encode(data)
    }

    /// The bytes behind [`BODY`]: a unit quad's positions (0..48), u8
    /// indices (48..54), normalised u8 RGB colours (56..68) and normalised
    /// u16 UVs (68..84).
    fn quad_bin() -> Vec<u8> {
        let mut v = vec3_bytes(&[Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]);
        v.extend_from_slice(&[0, 1, 2, 0, 2, 3, 0, 0]);
        v.extend_from_slice(&[255, 0, 0, 0, 0, 0, 128, 128, 128, 0, 255, 0]);
        for uv in [[0u16, 0], [65535, 0], [65535, 65535], [0, 65535]] {
            for c in uv {
                v.extend_from_slice(&c.to_le_bytes());
            }
        }
        v
    }

    const BODY: &str = r#""bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":6},{"buffer":0,"byteOffset":56,"byteLength":12},{"buffer":0,"byteOffset":68,"byteLength":16}],
"accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
{"bufferView":1,"componentType":5121,"count":6,"type":"SCALAR"},
{"bufferView":2,"componentType":5121,"normalized":true,"count":4,"type":"VEC3"},
{"bufferView":3,"componentType":5123,"normalized":true,"count":4,"type":"VEC2"}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0,"COLOR_0":2,"TEXCOORD_0":3},"indices":1}]}],
"nodes":[{"mesh":0,"translation":[10,0,0],"scale":[-1,1,1]}],
"scenes":[{"nodes":[0]}],"scene":0"#;

    /// A glTF JSON document with `body` and the quad's bytes as a data URI.
    fn doc(body: &str) -> String {
        let bin = quad_bin();
        format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],{body}}}"#,
            bin.len(),
            b64(&bin)
        )
    }

    fn sample() -> TriMesh {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1.0, -1.0e-7),
            Vec3::new(0.0, 1.0, 3.5),
        ];
        TriMesh {
            normals: Some(
                positions
                    .iter()
                    .map(|p| (*p - Vec3::splat(0.4)).normalize())
                    .collect(),
            ),
            colors: Some(vec![
                [0, 0, 0, 0],
                [255, 255, 255, 255],
                [1, 2, 3, 4],
                [188, 60, 250, 128],
            ]),
            uvs: Some(vec![
                Vec2::ZERO,
                Vec2::new(1.0, 0.25),
                Vec2::new(0.3, 0.7),
                Vec2::ONE,
            ]),
            faces: vec![[0, 1, 2], [0, 2, 3]],
            positions,
        }
    }

    #[test]
    fn glb_round_trips_with_every_attribute_subset() {
        for mask in 0..8 {
            let mut m = sample();
            if mask & 1 == 0 {
                m.normals = None;
            }
            if mask & 2 == 0 {
                m.colors = None;
            }
            if mask & 4 == 0 {
                m.uvs = None;
            }
            let glb = write_glb(&[("LOD0", &m)]).unwrap();
            let back = read(&glb, None).unwrap();
            assert_eq!(back, m, "mask {mask}");
            assert_eq!(write_glb(&[("LOD0", &m)]).unwrap(), glb, "deterministic");
        }
    }

    #[test]
    fn every_rgba8_colour_survives_the_linear_encoding() {
        for c in 0..=255u8 {
            let lin = (srgb8_to_linear(c) * 65535.0).round() as u16;
            assert_eq!(linear_to_srgb8(lin as f32 / 65535.0), c);
            assert_eq!(unit8((c as u16 * 257) as f32 / 65535.0), c);
        }
    }

    /// Checks the container and JSON of a GLB; returns the parsed JSON.
    fn check_glb_structure(glb: &[u8]) -> serde_json::Value {
        assert_eq!(&glb[..4], b"glTF");
        assert_eq!(u32_at(glb, 4), 2);
        assert_eq!(u32_at(glb, 8) as usize, glb.len());
        let jl = u32_at(glb, 12) as usize;
        assert_eq!(&glb[16..20], b"JSON");
        assert_eq!(jl % 4, 0);
        let js = &glb[20..20 + jl];
        let bl = u32_at(glb, 20 + jl) as usize;
        assert_eq!(&glb[24 + jl..28 + jl], b"BIN\0");
        assert_eq!((28 + jl) % 4, 0);
        assert_eq!(bl % 4, 0);
        assert_eq!(28 + jl + bl, glb.len());
        let v: serde_json::Value = serde_json::from_slice(js).unwrap();
        assert!(js.ends_with(b"}") || js.ends_with(b" "));
        assert_eq!(v["buffers"][0]["byteLength"].as_u64().unwrap() as usize, bl);
        for view in v["bufferViews"].as_array().unwrap() {
            let o = view["byteOffset"].as_u64().unwrap();
            let l = view["byteLength"].as_u64().unwrap();
            assert_eq!(o % 4, 0);
            assert!(o + l <= bl as u64);
        }
        v
    }

    #[test]
    fn glb_levels_structure_names_and_extras() {
        let small = sample();
        // 70000 vertices: needs u32 indices.
        let n = 70_000u32;
        let big = TriMesh::new(
            (0..n)
                .map(|i| Vec3::new(i as f32, (i % 7) as f32, 0.0))
                .collect(),
            (0..n - 2).map(|i| [i, i + 1, i + 2]).collect(),
        );
        let glb = write_glb(&[("LOD0", &big), ("LOD1", &small)]).unwrap();
        let v = check_glb_structure(&glb);
        assert_eq!(v["scene"], 0);
        assert_eq!(v["scenes"][0]["nodes"], serde_json::json!([0, 1]));
        assert_eq!(v["nodes"][0]["name"], "LOD0 (69998 triangles)");
        assert_eq!(v["meshes"][1]["name"], "LOD1 (2 triangles)");
        assert_eq!(
            v["nodes"][1]["extras"],
            serde_json::json!({"triangles": 2, "vertices": 4})
        );
        let acc = &v["accessors"];
        assert_eq!(acc[0]["min"], serde_json::json!([0.0, 0.0, 0.0]));
        assert_eq!(acc[0]["max"], serde_json::json!([69999.0, 6.0, 0.0]));
        assert_eq!(acc[1]["componentType"], 5125); // u32 indices
        let small_idx = v["meshes"][1]["primitives"][0]["indices"].as_u64().unwrap() as usize;
        assert_eq!(acc[small_idx]["componentType"], 5123); // u16 indices
        assert_eq!(v["meshes"][1]["primitives"][0]["attributes"]["COLOR_0"], 4);
        assert_eq!(acc[4]["normalized"], true);
        // Reading merges all levels into one mesh.
        let back = read(&glb, None).unwrap();
        assert_eq!(back.faces.len(), 69_998 + 2);
        assert_eq!(back.positions[n as usize..], small.positions[..]);
    }

    #[test]
    fn json_gltf_with_transform_u8_indices_and_normalised_attributes() {
        let m = read(doc(BODY).as_bytes(), None).unwrap();
        assert_eq!(
            m.positions,
            vec![
                Vec3::new(10.0, 0.0, 0.0),
                Vec3::new(9.0, 0.0, 0.0),
                Vec3::new(9.0, 1.0, 0.0),
                Vec3::new(10.0, 1.0, 0.0)
            ]
        );
        // The mirror (scale x = -1) flips the winding back to CCW.
        assert_eq!(m.faces, vec![[0, 2, 1], [0, 3, 2]]);
        let c = m.colors.unwrap();
        assert_eq!(c[0], [255, 0, 0, 255]);
        assert_eq!(c[2], [linear_to_srgb8(128.0 / 255.0), 188, 188, 255]);
        assert_eq!(
            m.uvs.unwrap(),
            vec![Vec2::Y, Vec2::ONE, Vec2::X, Vec2::ZERO]
        );
    }

    #[test]
    fn strips_fans_and_normals_under_rotation() {
        let strip = BODY.replace(r#","indices":1"#, r#","mode":5"#).replace(
            r#""translation":[10,0,0],"scale":[-1,1,1]"#,
            r#""rotation":[0,0,0.7071068,0.7071068]"#,
        );
        let m = read(doc(&strip).as_bytes(), None).unwrap();
        assert_eq!(m.faces, vec![[0, 1, 2], [1, 3, 2]]);
        assert!((m.positions[1] - Vec3::Y).length() < 1e-6);
        let fan = strip.replace(r#""mode":5"#, r#""mode":6"#);
        let m = read(doc(&fan).as_bytes(), None).unwrap();
        assert_eq!(m.faces, vec![[1, 2, 0], [2, 3, 0]]);
        // Normals: a non-uniform scale uses the inverse transpose.
        let mut s = sample();
        s.colors = None;
        s.uvs = None;
        s.normals = Some(vec![Vec3::new(1.0, 1.0, 0.0).normalize(); 4]);
        let glb = write_glb(&[("n", &s)]).unwrap();
        let v = check_glb_structure(&glb);
        let mut root = v.clone();
        root["nodes"][0]["scale"] = serde_json::json!([2.0, 1.0, 1.0]);
        let js = serde_json::to_vec(&root).unwrap();
        let bin = &glb[28 + u32_at(&glb, 12) as usize..];
        let mut re = Vec::new();
        re.extend_from_slice(b"glTF");
        re.extend_from_slice(&2u32.to_le_bytes());
        let pad = (4 - js.len() % 4) % 4;
        re.extend_from_slice(&((28 + js.len() + pad + bin.len()) as u32).to_le_bytes());
        re.extend_from_slice(&((js.len() + pad) as u32).to_le_bytes());
        re.extend_from_slice(b"JSON");
        re.extend_from_slice(&js);
        re.extend(std::iter::repeat_n(b' ', pad));
        re.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        re.extend_from_slice(b"BIN\0");
        re.extend_from_slice(bin);
        let m = read(&re, None).unwrap();
        let want = Vec3::new(0.5, 1.0, 0.0).normalize();
        assert!((m.normals.unwrap()[0] - want).length() < 1e-6);
        assert_eq!(m.positions[1], Vec3::new(2.0, 0.0, 0.0));
    }

    #[test]
    fn attribute_missing_from_one_primitive_is_dropped() {
        let two = BODY.replace(
            r#"{"attributes":{"POSITION":0,"COLOR_0":2,"TEXCOORD_0":3},"indices":1}"#,
            r#"{"attributes":{"POSITION":0,"COLOR_0":2,"TEXCOORD_0":3},"indices":1},{"attributes":{"POSITION":0,"COLOR_0":2},"indices":1}"#,
        );
        let m = read(doc(&two).as_bytes(), None).unwrap();
        assert_eq!(m.positions.len(), 8);
        assert!(m.colors.is_some() && m.uvs.is_none());
    }

    #[test]
    fn external_buffer_resolved_against_base_dir() {
        let dir = tempfile::tempdir().unwrap();
        std::fs::write(dir.path().join("quad data.bin"), quad_bin()).unwrap();
        let body = format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":84,"uri":"quad%20data.bin"}}],{BODY}}}"#
        );
        let m = read(body.as_bytes(), Some(dir.path())).unwrap();
        assert_eq!(m.faces.len(), 2);
        let e = read(body.as_bytes(), None).unwrap_err().to_string();
        assert!(e.contains("no directory to resolve it"), "{e}");
        let http = body.replace("quad%20data.bin", "http://example.invalid/q.bin");
        let e = read(http.as_bytes(), Some(dir.path()))
            .unwrap_err()
            .to_string();
        assert!(e.contains("not a relative path"), "{e}");
    }

    #[test]
    fn bad_input_is_a_one_line_error() {
        let glb = write_glb(&[("x", &sample())]).unwrap();
        let mut short_len = glb.clone();
        short_len[8..12].copy_from_slice(&3u32.to_le_bytes());
        let mut long_chunk = glb.clone();
        long_chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
        let s = |x: &str| x.as_bytes().to_vec();
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (vec![], "empty file"),
            (s("glTX...."), "neither GLB"),
            (glb[..10].to_vec(), "GLB truncated"),
            (glb[..glb.len() - 4].to_vec(), "GLB header says"),
            (short_len, "GLB header says 3 bytes"),
            (long_chunk, "chunk at byte 12 says 4294967295 bytes"),
            (s("{ not json"), "glTF JSON"),
            (s(&doc(&BODY.replace(r#""byteLength":16"#, r#""byteLength":64"#))), "outside buffer 0"),
            (s(&doc(&BODY.replace(r#""count":4,"type":"VEC2""#, r#""count":5,"type":"VEC2""#))), "do not fit in buffer view 3"),
            (s(&doc(&BODY.replace(r#""count":6"#, r#""count":0"#))), "empty (count 0)"),
            (s(&doc(&BODY.replace("[0, 1, 2, 0, 2, 3", "x").replace(r#""POSITION":0"#, r#""POSITION":9"#))), "uses accessor 9 but there are 4"),
            (s(&doc(&BODY.replace(r#""componentType":5121,"count":6"#, r#""componentType":5126,"count":1"#))), "not allowed there"),
            (s(&doc(&BODY.replace(r#""byteOffset":0,"byteLength":48"#, r#""byteOffset":0,"byteLength":48,"byteStride":8"#))), "stride 8"),
            (s(&doc(&BODY.replace(r#""scenes":[{"nodes":[0]}]"#, r#""scenes":[{"nodes":[0,0]}]"#))), "reached twice"),
            (s(&doc(&BODY.replace(r#""mesh":0,"#, r#""mesh":0,"children":[0],"#))), "reached twice"),
            (s(&doc(&BODY.replace(r#""bufferView":1,"#, r#""sparse":{"count":1,"indices":{"bufferView":1,"componentType":5121},"values":{"bufferView":1}},"bufferView":1,"#))), "sparse"),
            (s(&doc(BODY).replace(";base64,", ",")), "data URI is not base64"),
            (s(&doc(BODY).replace(";base64,", ";base64,%%")), "not valid base64"),
            (s(&(BODY.replace(r#""bufferViews""#, r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":84}],"bufferViews""#) + "}")), "no GLB BIN chunk"),
            (s(&doc(&BODY.replace(r#""mode""#, "x").replace(r#""indices":1"#, r#""indices":1,"mode":1"#))), "no triangle primitives"),
            (s(&doc(&BODY.replace(r#""max":[1,1,0]"#, r#""max":[1,1]"#))), "invalid glTF"),
        ];
        for (input, want) in cases {
            let e = read(&input, None).unwrap_err().to_string();
            assert!(e.contains(want), "{e:?} should contain {want:?}");
            assert!(!e.contains('\n'), "{e:?}");
        }
        // Index out of range.
        let mut bin = quad_bin();
        bin[50] = 7;
        let d = format!(
            r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":84,"uri":"data:application/octet-stream;base64,{}"}}],{BODY}}}"#,
            b64(&bin)
        );
        let e = read(d.as_bytes(), None).unwrap_err().to_string();
        assert!(e.contains("index 7 out of range (4 vertices)"), "{e}");
    }

    #[test]
    fn json_with_a_byte_order_mark_is_read() {
        let with_bom = [b"\xEF\xBB\xBF".as_slice(), doc(BODY).as_bytes()].concat();
        assert_eq!(read(&with_bom, None).unwrap().faces.len(), 2);
    }

    #[test]
    fn base64_decoder() {
        for n in 0..20u8 {
            let data: Vec<u8> = (0..n).map(|i| i.wrapping_mul(37)).collect();
            assert_eq!(decode_base64(&b64(&data)).unwrap(), data);
        }
        assert!(decode_base64("A").is_err());
        assert!(decode_base64("AB=C").is_err());
        assert!(decode_base64("A=").is_err());
    }
}
