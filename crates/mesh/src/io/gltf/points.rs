//! Which reader a glTF file needs, and `POINTS` primitives → one
//! [`PointCloud`] (see the module docs of `io::gltf`).

use std::borrow::Cow;
use std::path::Path;

use glam::{Mat3, Vec3};
use gltf::Semantic;
use gltf::accessor::{DataType, Dimensions};
use gltf::mesh::Mode;

use super::buffers::load_buffer;
use super::color::{linear_to_srgb8, unit8};
use super::read::{check_accessor, instances, parse_document, read_from};
use crate::error::ParseError;
use crate::mesh::{Model, PointCloud};
use crate::parse_err;

/// Reads a glTF or GLB file: its triangles as one mesh (as [`read`]) or,
/// when it has no triangle primitive but has `POINTS` primitives, its
/// points as one cloud. Compressed and quantised files are expanded first
/// (`KHR_mesh_quantization`, `EXT_meshopt_compression` /
/// `KHR_meshopt_compression` with the `meshopt` feature); Draco files are
/// a one-line error naming the extension.
pub fn read_model(bytes: &[u8], base_dir: Option<&Path>) -> Result<Model, ParseError> {
    let expanded = super::extensions::expand(bytes, base_dir)?;
    let (bytes, source) = match &expanded {
        Some((b, source)) => (b.as_slice(), *source),
        None => (bytes, bytes.len() as u64),
    };
    let (doc, _) = parse_document(bytes)?;
    let mode_in_scene =
        |want: &dyn Fn(Mode) -> bool| doc.meshes().any(|m| m.primitives().any(|p| want(p.mode())));
    let triangles =
        mode_in_scene(&|m| matches!(m, Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan));
    if !triangles && mode_in_scene(&|m| m == Mode::Points) {
        return read_points(bytes, base_dir, source).map(Model::Points);
    }
    read_from(bytes, base_dir, source).map(Model::Mesh)
}

/// Points may be instanced up to this many times what the file stores (or
/// [`super::INSTANCING_FLOOR`] points), as meshes; `stored` is capped by
/// the input's bytes (12 a point) by the caller, so aliased accessors do
/// not count twice.
fn points_cap(stored: u64) -> u64 {
    stored
        .saturating_mul(super::MAX_INSTANCING_GROWTH)
        .max(super::INSTANCING_FLOOR)
}

/// Every `POINTS` primitive of the scene, world transforms applied; an
/// attribute is kept only if every primitive has it.
fn read_points(
    bytes: &[u8],
    base_dir: Option<&Path>,
    mut source: u64,
) -> Result<PointCloud, ParseError> {
    let (doc, bin) = parse_document(bytes)?;
    let mut parts = Vec::new();
    for inst in instances(&doc)? {
        for prim in inst.mesh.primitives() {
            if prim.mode() == Mode::Points {
                parts.push((prim, inst.world));
            }
        }
    }
    if parts.is_empty() {
        return Err(ParseError::new(
            "no points: the scene has no POINTS primitives",
        ));
    }
    let all = |s: &Semantic| parts.iter().all(|(p, _)| p.get(s).is_some());
    let has_n = all(&Semantic::Normals);
    let has_c = all(&Semantic::Colors(0));
    let mut buffers: Vec<Option<Cow<[u8]>>> = vec![None; doc.buffers().len()];
    for (p, _) in &parts {
        for s in [Semantic::Positions, Semantic::Normals, Semantic::Colors(0)] {
            if let Some(v) = p.get(&s).and_then(|a| a.view()) {
                let b = v.buffer();
                let bi = b.index();
                if buffers[bi].is_none() {
                    let data = load_buffer(b, bin, base_dir)?;
                    if let Cow::Owned(d) = &data {
                        source = source.saturating_add(d.len() as u64);
                    }
                    buffers[bi] = Some(data);
                }
            }
        }
    }
    use DataType::{F32, U8, U16};
    use Dimensions::{Vec3 as D3, Vec4 as D4};
    let colour_types = [
        (U8, D3),
        (U16, D3),
        (F32, D3),
        (U8, D4),
        (U16, D4),
        (F32, D4),
    ];
    let (mut total, mut stored) = (0u64, 0u64);
    let mut seen = vec![false; doc.accessors().len()];
    for (k, (p, _)) in parts.iter().enumerate() {
        let ctx = |w: &str| format!("points primitive {k}: {w}");
        let pos = p
            .get(&Semantic::Positions)
            .ok_or_else(|| parse_err!("points primitive {k} has no POSITION"))?;
        let n = check_accessor(&pos, &ctx("POSITION"), &[(F32, D3)], &buffers)?;
        for (s, what, types) in [
            (Semantic::Normals, "NORMAL", &[(F32, D3)][..]),
            (Semantic::Colors(0), "COLOR_0", &colour_types[..]),
        ] {
            let keep = match s {
                Semantic::Normals => has_n,
                _ => has_c,
            };
            if let (true, Some(a)) = (keep, p.get(&s)) {
                let c = check_accessor(&a, &ctx(what), types, &buffers)?;
                if c != n {
                    return Err(parse_err!(
                        "points primitive {k}: {what} has {c} elements but POSITION has {n}"
                    ));
                }
            }
        }
        if !std::mem::replace(&mut seen[pos.index()], true) {
            stored += n as u64;
        }
        total += n as u64;
    }
    let stored = stored.min(source / 12);
    if total > points_cap(stored) {
        return Err(parse_err!(
            "{} POINTS instances expand {stored} stored points to {total}, over the limit of {}",
            parts.len(),
            points_cap(stored)
        ));
    }
    let mut out = PointCloud {
        positions: Vec::with_capacity(total as usize),
        normals: has_n.then(|| Vec::with_capacity(total as usize)),
        colors: has_c.then(|| Vec::with_capacity(total as usize)),
    };
    for (k, (p, world)) in parts.iter().enumerate() {
        let reader = p.reader(|b| buffers.get(b.index()).and_then(|d| d.as_deref()));
        let short = || parse_err!("points primitive {k}: accessor data ended early");
        let before = out.positions.len();
        out.positions.extend(
            reader
                .read_positions()
                .ok_or_else(short)?
                .map(|q| world.transform_point3(Vec3::from_array(q))),
        );
        let n = out.positions.len() - before;
        if let Some(dst) = out.normals.as_mut() {
            let m3 = Mat3::from_mat4(*world);
            let cof = Mat3::from_cols(
                m3.y_axis.cross(m3.z_axis),
                m3.z_axis.cross(m3.x_axis),
                m3.x_axis.cross(m3.y_axis),
            ) * if m3.determinant() < 0.0 { -1.0 } else { 1.0 };
            let identity = *world == glam::Mat4::IDENTITY;
            dst.extend(reader.read_normals().ok_or_else(short)?.map(|q| {
                let v = Vec3::from_array(q);
                if identity {
                    v
                } else {
                    (cof * v).normalize_or_zero()
                }
            }));
        }
        if let Some(dst) = out.colors.as_mut() {
            dst.extend(
                reader
                    .read_colors(0)
                    .ok_or_else(short)?
                    .into_rgba_f32()
                    .map(|c| {
                        let [r, g, b] = [c[0], c[1], c[2]].map(linear_to_srgb8);
                        [r, g, b, unit8(c[3])]
                    }),
            );
        }
        let lens = [
            out.normals.as_ref().map(Vec::len),
            out.colors.as_ref().map(Vec::len),
        ];
        if lens.iter().flatten().any(|&l| l != before + n) {
            return Err(short());
        }
    }
    out.validate()?;
    Ok(out)
}
