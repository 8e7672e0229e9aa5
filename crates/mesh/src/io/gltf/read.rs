//! Reading: document → instances (nodes with world transforms) → checked
//! accessors → one [`TriMesh`].

use std::borrow::Cow;
use std::path::Path;

use glam::{Mat3, Mat4, Vec2, Vec3};
use gltf::accessor::{DataType, Dimensions};
use gltf::json;
use gltf::mesh::Mode;
use gltf::mesh::util::{ReadColors, ReadTexCoords};
use gltf::{Accessor, Semantic};

use super::buffers::load_buffer;
use super::color::{linear_to_srgb8, unit8};
use super::glb::{GLB_MAGIC, split_glb};
use crate::error::ParseError;
use crate::mesh::TriMesh;
use crate::parse_err;
use crate::scene::{NO_MATERIAL, Node, Scene, SceneMesh, Transform};

/// Checks what gltf-json's validation indexes without checking, what the
/// `gltf` crate unwraps (an image's source), and the material factors,
/// which must be finite and inside glTF's ranges (a factor of `1e39` reads
/// as infinity and could not be written back as JSON).
fn precheck(root: &json::Root) -> Result<(), ParseError> {
    for (i, img) in root.images.iter().enumerate() {
        match (&img.buffer_view, &img.uri) {
            (None, None) => {
                return Err(parse_err!("image {i} has neither a uri nor a bufferView"));
            }
            (Some(_), Some(_)) => {
                return Err(parse_err!("image {i} has both a uri and a bufferView"));
            }
            (Some(v), None) => {
                if v.value() >= root.buffer_views.len() {
                    return Err(parse_err!(
                        "image {i} uses buffer view {} but there are {} buffer views",
                        v.value(),
                        root.buffer_views.len()
                    ));
                }
                if img.mime_type.is_none() {
                    return Err(parse_err!(
                        "image {i} is stored in a bufferView but has no mimeType"
                    ));
                }
            }
            (None, Some(_)) => {}
        }
    }
    for (i, m) in root.materials.iter().enumerate() {
        let pbr = &m.pbr_metallic_roughness;
        let unit = |x: f32| x.is_finite() && (0.0..=1.0).contains(&x);
        let bad = |what: &str, v: &[f32], range: &str| {
            Err(parse_err!(
                "material {i}: {what} {v:?} is not a finite number {range}"
            ))
        };
        if !pbr.base_color_factor.0.iter().all(|&x| unit(x)) {
            return bad("baseColorFactor", &pbr.base_color_factor.0, "in [0, 1]");
        }
        for (what, v) in [
            ("metallicFactor", pbr.metallic_factor.0),
            ("roughnessFactor", pbr.roughness_factor.0),
        ]
        .into_iter()
        .chain(
            m.occlusion_texture
                .as_ref()
                .map(|o| ("occlusionTexture strength", o.strength.0)),
        ) {
            if !unit(v) {
                return bad(what, &[v], "in [0, 1]");
            }
        }
        if !m.emissive_factor.0.iter().all(|&x| unit(x)) {
            return bad("emissiveFactor", &m.emissive_factor.0, "in [0, 1]");
        }
        if let Some(n) = &m.normal_texture
            && !(n.scale.is_finite() && n.scale.abs() <= 1e6)
        {
            return bad("normalTexture scale", &[n.scale], "of at most 1e6");
        }
        if let Some(c) = &m.alpha_cutoff
            && !(c.0.is_finite() && c.0 >= 0.0 && c.0 <= 1e6)
        {
            return bad("alphaCutoff", &[c.0], "in [0, 1e6]");
        }
    }
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
pub(super) fn parse_document(bytes: &[u8]) -> Result<(gltf::Document, Option<&[u8]>), ParseError> {
    if bytes.is_empty() {
        return Err(ParseError::new("empty file"));
    }
    // A UTF-8 byte-order mark is not allowed by the spec but is tolerated.
    let unbom = crate::io::input::strip_bom(bytes);
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
pub(super) struct Instance<'a> {
    pub(super) mesh: gltf::Mesh<'a>,
    pub(super) world: Mat4,
}

/// The meshes to read, with world transforms (see the module docs).
pub(super) fn instances(doc: &gltf::Document) -> Result<Vec<Instance<'_>>, ParseError> {
    if doc.nodes().len() == 0 {
        return Ok(doc
            .meshes()
            .map(|mesh| Instance {
                mesh,
                world: Mat4::IDENTITY,
            })
            .collect());
    }
    let roots = root_nodes(doc);
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

/// The default scene's nodes; when the file names none, every node that
/// is no other node's child.
fn root_nodes(doc: &gltf::Document) -> Vec<gltf::Node<'_>> {
    match doc.default_scene() {
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
    }
}

/// Verifies an accessor so that `gltf`'s reader can read all `count`
/// elements without panicking or coming up short; returns the count.
pub(super) fn check_accessor(
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

/// Instancing may multiply what the file stores by at most this factor
/// (vertices and indices counted separately, each accessor once however
/// many nodes use it)…
pub const MAX_INSTANCING_GROWTH: u64 = 16;
/// …or reach this many vertices (and indices), whichever is larger. So a
/// scene may place a small mesh many times (a million-vertex forest from
/// one tree) while the memory of the expanded mesh stays proportional to
/// the file: a 4 MB file can never ask for gigabytes. Beyond the limit the
/// file is refused before anything is allocated.
pub const INSTANCING_FLOOR: u64 = 1 << 22;

/// What one read has decoded so far, against the bytes it was given.
///
/// "Stored" counts each accessor once (however many nodes or meshes use
/// it) and is capped by the input's bytes (`source`: the file and the
/// external buffers it names) — at least 12 bytes a stored vertex (an
/// `f32` VEC3 position) and 1 byte a stored index — so accessors that
/// alias one buffer view cannot inflate it. The totals are summed over
/// every primitive read in this run (every mesh of a scene), and checked
/// before each allocation.
pub(super) struct Budget {
    source: u64,
    seen_pos: Vec<bool>,
    seen_ix: Vec<bool>,
    stored_vertices: u64,
    stored_indices: u64,
    vertices: u64,
    indices: u64,
}

impl Budget {
    /// A budget for a document of `n_accessors` accessors read from
    /// `source` bytes (the file, and any external buffers read while
    /// expanding it).
    pub(super) fn new(source: u64, n_accessors: usize) -> Budget {
        Budget {
            source,
            seen_pos: vec![false; n_accessors],
            seen_ix: vec![false; n_accessors],
            stored_vertices: 0,
            stored_indices: 0,
            vertices: 0,
            indices: 0,
        }
    }

    /// Counts an external buffer's bytes as input.
    pub(super) fn add_source(&mut self, bytes: usize) {
        self.source = self.source.saturating_add(bytes as u64);
    }
}

/// Refuses a scene whose instancing expands the stored vertices or indices
/// past `max(MAX_INSTANCING_GROWTH × stored, INSTANCING_FLOOR)`, or past
/// what 32-bit indices address.
fn check_instancing(
    parts: &[Part<'_>],
    vertices: u64,
    stored_vertices: u64,
    indices: u64,
    stored_indices: u64,
) -> Result<(), ParseError> {
    if vertices > u32::MAX as u64 {
        return Err(parse_err!(
            "{vertices} vertices once instanced: more than 32-bit indices can address"
        ));
    }
    let cap = |stored: u64| (stored.saturating_mul(MAX_INSTANCING_GROWTH)).max(INSTANCING_FLOOR);
    for (what, expanded, stored) in [
        ("vertices", vertices, stored_vertices),
        ("indices", indices, stored_indices),
    ] {
        if expanded > cap(stored) {
            return Err(parse_err!(
                "{} primitive instances expand {stored} stored {what} to {expanded}, over the limit of \
                 {} ({MAX_INSTANCING_GROWTH}x what the file stores, at least {INSTANCING_FLOOR})",
                parts.len(),
                cap(stored)
            ));
        }
    }
    Ok(())
}

/// A primitive to read, from an [`Instance`].
struct Part<'a> {
    prim: gltf::Primitive<'a>,
    world: Mat4,
    mesh: usize,
}

/// Reads a glTF or GLB file into one mesh (see the module docs).
pub fn read(bytes: &[u8], base_dir: Option<&Path>) -> Result<TriMesh, ParseError> {
    read_from(bytes, base_dir, bytes.len() as u64)
}

/// [`read`] of `bytes` that came from `source` bytes of input (more than
/// `bytes.len()` when an expanded file's external buffers were read, less
/// when compressed views were decoded): the budget of [`Budget`].
pub(super) fn read_from(
    bytes: &[u8],
    base_dir: Option<&Path>,
    source: u64,
) -> Result<TriMesh, ParseError> {
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
    let mut budget = Budget::new(source, doc.accessors().len());
    read_parts(&parts, bin, base_dir, doc.buffers().len(), &mut budget).map(|(mesh, _)| mesh)
}

/// Reads `parts` (each with its world transform) into one mesh; also
/// returns each part's face count, in order. `n_buffers` is the
/// document's count; `budget` what this run has read so far.
fn read_parts(
    parts: &[Part<'_>],
    bin: Option<&[u8]>,
    base_dir: Option<&Path>,
    n_buffers: usize,
    budget: &mut Budget,
) -> Result<(TriMesh, Vec<usize>), ParseError> {
    let all = |s: &Semantic| parts.iter().all(|p| p.prim.get(s).is_some());
    let has_n = all(&Semantic::Normals);
    let has_c = all(&Semantic::Colors(0));
    // UVs are kept when any part has them: a writer leaves TEXCOORD_0 off
    // an untextured primitive (lodkit's scene writer does), and the other
    // parts' texture mapping must survive that. A part without them reads
    // as (0, 0).
    let has_uv = parts
        .iter()
        .any(|p| p.prim.get(&Semantic::TexCoords(0)).is_some());

    // Resolve exactly the buffers the accessors to read live in.
    let mut buffers: Vec<Option<Cow<[u8]>>> = vec![None; n_buffers];
    for p in parts {
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
                    let data = load_buffer(b, bin, base_dir)?;
                    if let Cow::Owned(d) = &data {
                        budget.add_source(d.len());
                    }
                    buffers[bi] = Some(data);
                }
            }
        }
    }

    use DataType::{F32, U8, U16, U32};
    use Dimensions::{Scalar, Vec2 as D2, Vec3 as D3, Vec4 as D4};
    // Check every accessor and count the output before allocating it.
    let mut total = 0u64;
    let mut total_indices = 0u64;
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
        let indices = match p.prim.indices() {
            Some(ix) => {
                let c = check_accessor(
                    &ix,
                    &ctx("indices"),
                    &[(U8, Scalar), (U16, Scalar), (U32, Scalar)],
                    &buffers,
                )?;
                if !std::mem::replace(&mut budget.seen_ix[ix.index()], true) {
                    budget.stored_indices += c as u64;
                }
                c
            }
            None => {
                if !std::mem::replace(&mut budget.seen_ix[pos.index()], true) {
                    budget.stored_indices += n as u64;
                }
                n
            }
        };
        if !std::mem::replace(&mut budget.seen_pos[pos.index()], true) {
            budget.stored_vertices += n as u64;
        }
        total += n as u64;
        total_indices += indices as u64;
    }
    budget.vertices += total;
    budget.indices += total_indices;
    check_instancing(
        parts,
        budget.vertices,
        budget.stored_vertices.min(budget.source / 12),
        budget.indices,
        budget.stored_indices.min(budget.source),
    )?;

    let mut out = TriMesh {
        positions: Vec::with_capacity(total as usize),
        normals: has_n.then(|| Vec::with_capacity(total as usize)),
        colors: has_c.then(|| Vec::with_capacity(total as usize)),
        uvs: has_uv.then(|| Vec::with_capacity(total as usize)),
        // A triangle takes at least one index (strips and fans) and at
        // most three; checked against the cap above.
        faces: Vec::with_capacity((total_indices / 3) as usize),
    };
    let mut part_faces = Vec::with_capacity(parts.len());
    for (k, p) in parts.iter().enumerate() {
        let faces_before = out.faces.len();
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
            if p.prim.get(&Semantic::TexCoords(0)).is_some() {
                let it: ReadTexCoords = reader.read_tex_coords(0).ok_or_else(short)?;
                dst.extend(it.into_f32().map(|[u, v]| Vec2::new(u, 1.0 - v)));
            } else {
                let n = out.positions.len() - dst.len();
                dst.resize(dst.len() + n, Vec2::ZERO);
            }
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
        part_faces.push(out.faces.len() - faces_before);
    }
    if out.faces.is_empty() {
        return Err(ParseError::new("no triangles"));
    }
    Ok((out, part_faces))
}

/// Reads a glTF or GLB file as a [`Scene`] (see the module docs): each
/// mesh with triangle primitives that a node of the default scene places
/// (every mesh when the file has no nodes) becomes one [`SceneMesh`] in its own
/// frame (its primitives' faces in order, each face tagged with its
/// primitive's material), the nodes reachable from the default scene keep
/// their names, local transforms and hierarchy (renumbered depth first),
/// and the material, texture, sampler and image tables are read
/// (`materials_read`). Compressed and quantised files are expanded first,
/// as by `read_model`. Same checks and errors as [`read`];
/// instances are not expanded (a node refers to its mesh).
pub fn read_scene(bytes: &[u8], base_dir: Option<&Path>) -> Result<Scene, ParseError> {
    let expanded = super::extensions::expand(bytes, base_dir)?;
    let (bytes, source) = match &expanded {
        Some((b, source)) => (b.as_slice(), *source),
        None => (bytes, bytes.len() as u64),
    };
    let (doc, bin) = parse_document(bytes)?;
    let mut budget = Budget::new(source, doc.accessors().len());
    // Checks the node graph (no cycle, one parent per node).
    instances(&doc)?;
    // Only the meshes the default scene's nodes place (an MSFT_lod chain's
    // other levels sit outside the scene); with no nodes at all, every mesh.
    let mut placed = vec![doc.nodes().len() == 0; doc.meshes().len()];
    let mut stack: Vec<gltf::Node> = root_nodes(&doc);
    while let Some(n) = stack.pop() {
        if let Some(m) = n.mesh() {
            placed[m.index()] = true;
        }
        stack.extend(n.children());
    }
    let mut scene = Scene::default();
    let mut mesh_map = vec![None; doc.meshes().len()];
    for mesh in doc.meshes().filter(|m| placed[m.index()]) {
        let parts: Vec<Part> = mesh
            .primitives()
            .filter(|p| {
                matches!(
                    p.mode(),
                    Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
                )
            })
            .map(|prim| Part {
                prim,
                world: Mat4::IDENTITY,
                mesh: mesh.index(),
            })
            .collect();
        if parts.is_empty() {
            continue;
        }
        let (tm, counts) = read_parts(&parts, bin, base_dir, doc.buffers().len(), &mut budget)?;
        let mut face_materials = Vec::with_capacity(tm.faces.len());
        for (p, c) in parts.iter().zip(counts) {
            let id = p.prim.material().index().map_or(NO_MATERIAL, |i| i as u32);
            face_materials.extend(std::iter::repeat_n(id, c));
        }
        mesh_map[mesh.index()] = Some(scene.meshes.len());
        scene.meshes.push(SceneMesh {
            name: mesh.name().map(str::to_owned),
            mesh: tm,
            face_materials,
        });
    }
    if scene.meshes.is_empty() {
        return Err(ParseError::new(
            "no triangles: the scene has no triangle primitives",
        ));
    }
    if doc.nodes().len() == 0 {
        for m in 0..scene.meshes.len() {
            scene.nodes.push(Node {
                mesh: Some(m),
                ..Default::default()
            });
            scene.roots.push(m);
        }
    } else {
        let roots = root_nodes(&doc);
        let mut new_id = vec![usize::MAX; doc.nodes().len()];
        let mut order = Vec::new();
        let mut stack: Vec<gltf::Node> = roots.iter().rev().cloned().collect();
        while let Some(n) = stack.pop() {
            new_id[n.index()] = order.len();
            let children: Vec<gltf::Node> = n.children().collect();
            stack.extend(children.into_iter().rev());
            order.push(n);
        }
        for n in &order {
            scene.nodes.push(Node {
                name: n.name().map(str::to_owned),
                transform: match n.transform() {
                    gltf::scene::Transform::Matrix { matrix } => {
                        Transform::Matrix(Mat4::from_cols_array_2d(&matrix).to_cols_array())
                    }
                    gltf::scene::Transform::Decomposed {
                        translation,
                        rotation,
                        scale,
                    } => Transform::Trs {
                        translation,
                        rotation,
                        scale,
                    },
                },
                mesh: n.mesh().and_then(|m| mesh_map[m.index()]),
                children: n.children().map(|c| new_id[c.index()]).collect(),
            });
        }
        scene.roots = roots.iter().map(|r| new_id[r.index()]).collect();
    }
    super::materials_read::read_tables(&doc, bin, base_dir, budget.source, &mut scene)?;
    scene.validate()?;
    Ok(scene)
}
