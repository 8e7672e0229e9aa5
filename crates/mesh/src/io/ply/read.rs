//! Stage 2 of reading a PLY file: decoding the body into a [`Model`].
//!
//! The header is first turned into a [`Plan`]: which element is the vertex
//! list, the faces or the range grid, and for each attribute lodkit keeps,
//! the index (and, for binary fixed-size records, the byte offset and type)
//! of the property that holds it. Everything else is skipped.
//!
//! Three decoding paths share the plan:
//! - **columns** (binary, elements without lists): records are fixed-size,
//!   so each attribute is gathered with `chunks_exact(stride)`; the common
//!   `float x, y, z` little-endian layout uses `from_le_bytes` on fixed-size
//!   arrays, which the compiler vectorises;
//! - **triangles** (binary little-endian faces that hold only a `uchar`
//!   count and `int`/`uint` indices, and every count is 3): 13-byte records
//!   decoded in one pass; any other count falls back to the general path;
//! - **general** (everything else, ASCII included): record by record through
//!   a [`Source`], which bounds-checks every read.

use glam::{Vec2, Vec3};

use super::header::{self, Element, Encoding, Header, PropertyKind, ScalarType};
use super::sources::{AsciiSource, BinarySource, Source, decode_scalar};
use crate::error::ParseError;
use crate::mesh::{Model, PointCloud, RangeImage, TriMesh};
use crate::parse_err;

/// Decodes a whole PLY file; see the module docs of [`super`] for what is
/// accepted. Never panics; every allocation is bounded by the file size.
pub fn read(bytes: &[u8]) -> Result<Model, ParseError> {
    let bytes = crate::io::input::strip_bom(bytes);
    let header = header::parse(bytes)?;
    let body = bytes.get(header.body_start..).unwrap_or_default();
    header.check_counts(body.len())?;
    let plan = Plan::new(&header)?;
    let mut data = Decoded::default();
    match header.encoding {
        Encoding::Ascii => {
            // Line numbers count from the file's first line.
            let header_lines = bytes[..header.body_start.min(bytes.len())]
                .iter()
                .filter(|&&b| b == b'\n')
                .count();
            let mut src = AsciiSource::new(body, header_lines + 1);
            for (el, role) in header.elements.iter().zip(&plan.roles) {
                decode_general(&mut src, el, role, plan.vertices, &mut data)?;
            }
            src.finish()?;
        }
        Encoding::BinaryLittleEndian | Encoding::BinaryBigEndian => {
            let big = header.encoding == Encoding::BinaryBigEndian;
            let mut src = BinarySource {
                data: body,
                pos: 0,
                big,
            };
            for (el, role) in header.elements.iter().zip(&plan.roles) {
                decode_binary(&mut src, el, role, plan.vertices, &mut data)?;
            }
            check_end(body.len() as u64 - src.pos as u64)?;
        }
    }
    plan.assemble(data)
}

// ---------------------------------------------------------------------------
// Plan
// ---------------------------------------------------------------------------

/// A scalar property to read: its index in the element, type, and byte
/// offset in a binary record (meaningful only for fixed-size records).
#[derive(Debug, Clone, Copy)]
pub(super) struct Slot {
    index: usize,
    pub(super) ty: ScalarType,
    pub(super) offset: usize,
}

#[derive(Debug, Clone)]
pub(super) struct VertexPlan {
    pub(super) position: [Slot; 3],
    pub(super) normal: Option<[Slot; 3]>,
    /// `red green blue` and the optional `alpha`.
    pub(super) color: Option<([Slot; 3], Option<Slot>)>,
    pub(super) uv: Option<[Slot; 2]>,
}

/// What to do with each element, in file order.
#[derive(Debug, Clone)]
enum Role {
    Vertex(Box<VertexPlan>),
    /// Faces: index of the index-list property.
    Face(usize),
    /// Range grid: index of the index-list property.
    RangeGrid(usize),
    Skip,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Mesh,
    Range { cols: usize, rows: usize },
    Points,
}

struct Plan {
    roles: Vec<Role>,
    kind: Kind,
    has_vertex: bool,
    /// The header's vertex count, against which face indices are checked
    /// ([`checked_fan`]); `None` without a vertex element (refused by
    /// `assemble`).
    vertices: Option<u64>,
}

/// Colour property name sets, tried in order; the fourth is the alpha.
const COLOR_NAMES: [[&str; 4]; 2] = [
    ["red", "green", "blue", "alpha"],
    [
        "diffuse_red",
        "diffuse_green",
        "diffuse_blue",
        "diffuse_alpha",
    ],
];
/// Texture coordinate property name pairs, tried in order.
const UV_NAMES: [[&str; 2]; 4] = [
    ["u", "v"],
    ["s", "t"],
    ["texture_u", "texture_v"],
    ["texture_s", "texture_t"],
];
/// Names of the index list in `face` and `range_grid` elements.
const INDEX_LIST_NAMES: [&str; 2] = ["vertex_indices", "vertex_index"];

impl Plan {
    fn new(header: &Header) -> Result<Plan, ParseError> {
        let has_faces = header.element("face").is_some_and(|e| e.count > 0);
        let kind = if has_faces {
            Kind::Mesh
        } else if let Some(grid) = header.element("range_grid") {
            range_shape(header, grid)?
        } else {
            Kind::Points
        };
        let roles = header
            .elements
            .iter()
            .map(|el| {
                Ok(match (el.name.as_str(), kind) {
                    ("vertex", _) => Role::Vertex(Box::new(vertex_plan(el)?)),
                    ("face", Kind::Mesh) => Role::Face(index_list(el)?),
                    ("range_grid", Kind::Range { .. }) => Role::RangeGrid(index_list(el)?),
                    _ => Role::Skip,
                })
            })
            .collect::<Result<Vec<_>, ParseError>>()?;
        let has_vertex = header.element("vertex").is_some();
        Ok(Plan {
            roles,
            kind,
            has_vertex,
            vertices: header.element("vertex").map(|e| e.count),
        })
    }

    /// Builds the model from what the body held. Range-grid indices are
    /// checked here (nothing downstream would); face indices are left to
    /// `validate()`, which `io::decode` runs next.
    fn assemble(&self, d: Decoded) -> Result<Model, ParseError> {
        if !self.has_vertex {
            return Err(ParseError::new("file has no vertex element"));
        }
        Ok(match self.kind {
            Kind::Mesh => Model::Mesh(TriMesh {
                positions: d.positions,
                normals: d.normals,
                colors: d.colors,
                uvs: d.uvs,
                faces: d.faces,
            }),
            Kind::Points => Model::Points(PointCloud {
                positions: d.positions,
                normals: d.normals,
                colors: d.colors,
            }),
            Kind::Range { cols, rows } => {
                // `range_shape` checked rows × cols against the element
                // count, which `check_counts` bounded by the file size.
                let n = d.cells.len();
                if n != rows.saturating_mul(cols) {
                    return Err(parse_err!(
                        "range_grid holds {n} cells but obj_info says {cols} × {rows}"
                    ));
                }
                let mut points = vec![Vec3::ZERO; n];
                let mut valid = vec![false; n];
                let mut colors = d.colors.as_ref().map(|_| vec![[0u8; 4]; n]);
                let nv = d.positions.len();
                for (cell, entry) in d.cells.iter().enumerate() {
                    let Some(v) = *entry else { continue };
                    let Some(p) = d.positions.get(v as usize) else {
                        return Err(parse_err!(
                            "range_grid cell {cell} refers to vertex {v} but there are {nv} vertices"
                        ));
                    };
                    points[cell] = *p;
                    valid[cell] = true;
                    if let (Some(out), Some(c)) = (
                        colors.as_mut(),
                        d.colors.as_ref().and_then(|c| c.get(v as usize)),
                    ) {
                        out[cell] = *c;
                    }
                }
                Model::Range(RangeImage {
                    cols,
                    rows,
                    points,
                    valid,
                    colors,
                    pose: None,
                })
            }
        })
    }
}

/// The grid shape from `obj_info num_cols` / `num_rows`, checked against
/// the `range_grid` element's count.
fn range_shape(header: &Header, grid: &Element) -> Result<Kind, ParseError> {
    let dim = |key: &str| -> Result<usize, ParseError> {
        let v = header
            .obj_info(key)
            .ok_or_else(|| parse_err!("range_grid element needs 'obj_info {key}' in the header"))?;
        v.parse()
            .map_err(|_| parse_err!("obj_info {key} is not a count: '{v}'"))
    };
    let (cols, rows) = (dim("num_cols")?, dim("num_rows")?);
    if cols.checked_mul(rows).map(|n| n as u64) != Some(grid.count) {
        return Err(parse_err!(
            "range_grid has {} cells but obj_info says num_cols {cols} × num_rows {rows}",
            grid.count
        ));
    }
    Ok(Kind::Range { cols, rows })
}

/// The scalar property called `name`, if present; a list of that name is an
/// error (it cannot hold one attribute value per record).
fn scalar_slot(el: &Element, name: &str) -> Result<Option<Slot>, ParseError> {
    let Some(index) = el.property(name) else {
        return Ok(None);
    };
    match el.properties[index].kind {
        PropertyKind::Scalar(ty) => Ok(Some(Slot {
            index,
            ty,
            offset: el.offset_of(index).unwrap_or(0),
        })),
        PropertyKind::List { .. } => Err(parse_err!(
            "{} property {name} is a list, expected a single value",
            el.name
        )),
    }
}

/// All of `names` as slots when every one is present, else `None`.
fn slots<const N: usize>(el: &Element, names: [&str; N]) -> Result<Option<[Slot; N]>, ParseError> {
    let mut out = [Slot {
        index: 0,
        ty: ScalarType::U8,
        offset: 0,
    }; N];
    for (o, name) in out.iter_mut().zip(names) {
        match scalar_slot(el, name)? {
            Some(s) => *o = s,
            None => return Ok(None),
        }
    }
    Ok(Some(out))
}

pub(super) fn vertex_plan(el: &Element) -> Result<VertexPlan, ParseError> {
    let Some(position) = slots(el, ["x", "y", "z"])? else {
        return Err(ParseError::new(
            "vertex element lacks one of the x, y, z properties",
        ));
    };
    let normal = slots(el, ["nx", "ny", "nz"])?;
    let mut color = None;
    for [r, g, b, a] in COLOR_NAMES {
        if let Some(rgb) = slots(el, [r, g, b])? {
            color = Some((rgb, scalar_slot(el, a)?));
            break;
        }
    }
    let mut uv = None;
    for names in UV_NAMES {
        if let Some(s) = slots(el, names)? {
            uv = Some(s);
            break;
        }
    }
    Ok(VertexPlan {
        position,
        normal,
        color,
        uv,
    })
}

/// The index list of a `face` or `range_grid` element: `vertex_indices`,
/// `vertex_index`, or failing those the element's only list property.
fn index_list(el: &Element) -> Result<usize, ParseError> {
    let found = INDEX_LIST_NAMES
        .iter()
        .find_map(|n| el.property(n))
        .or_else(|| {
            let mut lists = el
                .properties
                .iter()
                .enumerate()
                .filter(|(_, p)| matches!(p.kind, PropertyKind::List { .. }));
            match (lists.next(), lists.next()) {
                (Some((i, _)), None) => Some(i),
                _ => None,
            }
        });
    let Some(index) = found else {
        return Err(parse_err!(
            "{} element has no vertex_indices list property",
            el.name
        ));
    };
    match el.properties[index].kind {
        PropertyKind::List { item, .. } if item.is_integer() => Ok(index),
        PropertyKind::List { item, .. } => Err(parse_err!(
            "{} {} has non-integer index type {}",
            el.name,
            el.properties[index].name,
            item.name()
        )),
        PropertyKind::Scalar(_) => Err(parse_err!(
            "{} property {} is a single value, expected a list",
            el.name,
            el.properties[index].name
        )),
    }
}

// ---------------------------------------------------------------------------
// Decoded data
// ---------------------------------------------------------------------------

#[derive(Default)]
struct Decoded {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    colors: Option<Vec<[u8; 4]>>,
    uvs: Option<Vec<Vec2>>,
    faces: Vec<[u32; 3]>,
    /// Range-grid cells: the first listed vertex, or `None` for an empty cell.
    cells: Vec<Option<u32>>,
}

impl Decoded {
    /// Allocates the vertex attributes the plan reads. `count` must have
    /// passed `Header::check_counts`.
    fn start_vertices(&mut self, plan: &VertexPlan, count: usize) {
        self.positions = Vec::with_capacity(count);
        self.normals = plan.normal.map(|_| Vec::with_capacity(count));
        self.colors = plan.color.map(|_| Vec::with_capacity(count));
        self.uvs = plan.uv.map(|_| Vec::with_capacity(count));
    }

    /// Appends one vertex whose scalar values (by property index) are
    /// `vals` (indices in `plan` are always `< vals.len()`).
    fn push_vertex(&mut self, plan: &VertexPlan, vals: &[f64]) {
        let get = |s: Slot| vals.get(s.index).copied().unwrap_or(f64::NAN);
        let vec3 = |s: [Slot; 3]| Vec3::new(get(s[0]) as f32, get(s[1]) as f32, get(s[2]) as f32);
        self.positions.push(vec3(plan.position));
        if let (Some(out), Some(s)) = (self.normals.as_mut(), plan.normal) {
            out.push(vec3(s));
        }
        if let (Some(out), Some((rgb, alpha))) = (self.colors.as_mut(), plan.color) {
            let [r, g, b] = rgb.map(|s| color_channel(get(s), s.ty));
            let a = alpha.map_or(255, |s| color_channel(get(s), s.ty));
            out.push([r, g, b, a]);
        }
        if let (Some(out), Some([u, v])) = (self.uvs.as_mut(), plan.uv) {
            out.push(Vec2::new(get(u) as f32, get(v) as f32));
        }
    }
}

/// Converts a colour value of type `ty` to 8 bits: floats are in [0, 1],
/// `ushort` in [0, 65535], every other integer type in [0, 255] (clamped).
pub(super) fn color_channel(v: f64, ty: ScalarType) -> u8 {
    let scaled = match ty {
        ScalarType::F32 | ScalarType::F64 => v * 255.0,
        ScalarType::U16 => v / 257.0,
        _ => v,
    };
    // `as` saturates and maps NaN to 0.
    scaled.round().clamp(0.0, 255.0) as u8
}

/// The face checks of both PLY readers (this one and the streaming
/// [`super::stream`]), so that they accept the same files: a polygon's
/// triangles `(p0, pi, pi+1)` (a fan), once the polygon has at least 3
/// corners (as in OBJ), every index is below `vertices` (the header's
/// count; `None`: not checked here) and no triangle repeats a corner.
/// Errors are phrases for the caller to prefix with the face's record.
pub(super) fn checked_fan(
    poly: &[u32],
    vertices: Option<u64>,
) -> Result<impl Iterator<Item = [u32; 3]> + '_, String> {
    let [first, rest @ ..] = poly else {
        return Err("has no vertex indices (a face needs at least 3)".into());
    };
    if rest.len() < 2 {
        return Err(format!(
            "has {} vertex indices (a face needs at least 3)",
            poly.len()
        ));
    }
    if let Some(n) = vertices
        && let Some(&v) = poly.iter().find(|&&v| u64::from(v) >= n)
    {
        return Err(format!(
            "has vertex index {v} but the file has {n} vertices"
        ));
    }
    let fan = rest.windows(2).map(|w| [*first, w[0], w[1]]);
    for t in fan.clone() {
        check_triangle(t)?;
    }
    Ok(fan)
}

/// A triangle must have three distinct corners.
pub(super) fn check_triangle([a, b, c]: [u32; 3]) -> Result<(), String> {
    if a == b || b == c || a == c {
        return Err(format!("repeats a vertex index ({a} {b} {c})"));
    }
    Ok(())
}

/// The end of a binary body, in both readers: bytes after the last element
/// the header declares mean a wrong count in the header or a damaged file,
/// so they are refused rather than ignored. `left`: bytes after the last
/// record.
pub(super) fn check_end(left: u64) -> Result<(), ParseError> {
    if left > 0 {
        return Err(parse_err!(
            "{left} bytes follow the last element the header declares (a wrong element \
             count in the header, or a damaged file)"
        ));
    }
    Ok(())
}

/// Converts a decoded list item to a vertex index.
pub(super) fn to_index(v: f64) -> Result<u32, String> {
    if v >= 0.0 && v <= u32::MAX as f64 {
        Ok(v as u32)
    } else {
        Err(format!("has invalid vertex index {v}"))
    }
}

// ---------------------------------------------------------------------------
// Element decoders
// ---------------------------------------------------------------------------

/// Prefixes a source error with the line (ASCII), element and record it
/// happened in.
fn at(el: &Element, record: u64, line: Option<usize>, msg: String) -> ParseError {
    match line {
        Some(l) => parse_err!("line {l}: {} {record}: {msg}", el.name),
        None => parse_err!("{} {record}: {msg}", el.name),
    }
}

/// Decodes a binary element, through the fast paths where the layout
/// allows and the general path otherwise.
fn decode_binary(
    src: &mut BinarySource<'_>,
    el: &Element,
    role: &Role,
    vertices: Option<u64>,
    out: &mut Decoded,
) -> Result<(), ParseError> {
    let stride = el.fixed_stride().filter(|&s| s > 0);
    match (role, stride) {
        (Role::Vertex(plan), Some(stride)) => {
            let records = src.take_records(el, stride)?;
            vertex_columns(records, stride, plan, src.big, out);
            Ok(())
        }
        (Role::Face(_), _) if !src.big && is_triangle_layout(el) => {
            if let Some(records) = src.peek(el.count.saturating_mul(13))
                && let Some(faces) = triangles_le(records)
            {
                for (i, f) in faces.iter().enumerate() {
                    // A fan of one triangle: the same checks as every face.
                    checked_fan(f, vertices)
                        .map(drop)
                        .map_err(|m| at(el, i as u64, None, m))?;
                }
                src.pos += records.len();
                out.faces = faces;
                return Ok(());
            }
            decode_general(src, el, role, vertices, out)
        }
        (Role::Skip, Some(stride)) => src.take_records(el, stride).map(drop),
        _ => decode_general(src, el, role, vertices, out),
    }
}

/// Gathers the vertex attributes from fixed-size binary records, one
/// attribute at a time. Slot offsets are inside the record by construction
/// (a short read would yield NaN, which `validate()` reports).
fn vertex_columns(records: &[u8], stride: usize, plan: &VertexPlan, big: bool, out: &mut Decoded) {
    let at = |r: &[u8], s: Slot| {
        r.get(s.offset..)
            .and_then(|b| decode_scalar(b, s.ty, big))
            .unwrap_or(f64::NAN)
    };
    let rows = || records.chunks_exact(stride);
    let vec3 = |r: &[u8], s: [Slot; 3]| {
        Vec3::new(at(r, s[0]) as f32, at(r, s[1]) as f32, at(r, s[2]) as f32)
    };

    let [x, y, z] = plan.position;
    let packed_f32 = !big
        && [x.ty, y.ty, z.ty] == [ScalarType::F32; 3]
        && y.offset == x.offset + 4
        && z.offset == x.offset + 8;
    out.positions = if packed_f32 && stride == 12 {
        // The plain `float x, y, z` record: a straight conversion.
        records.as_chunks::<12>().0.iter().map(le_vec3).collect()
    } else if packed_f32 {
        rows()
            .map(
                |r| match r.get(x.offset..).and_then(|b| b.first_chunk::<12>()) {
                    Some(c) => le_vec3(c),
                    None => Vec3::NAN,
                },
            )
            .collect()
    } else {
        rows().map(|r| vec3(r, plan.position)).collect()
    };
    out.normals = plan.normal.map(|s| rows().map(|r| vec3(r, s)).collect());
    out.colors = plan.color.map(|(rgb, alpha)| {
        rows()
            .map(|r| {
                let [red, green, blue] = rgb.map(|s| color_channel(at(r, s), s.ty));
                let a = alpha.map_or(255, |s| color_channel(at(r, s), s.ty));
                [red, green, blue, a]
            })
            .collect()
    });
    out.uvs = plan.uv.map(|[u, v]| {
        rows()
            .map(|r| Vec2::new(at(r, u) as f32, at(r, v) as f32))
            .collect()
    });
}

#[inline(always)]
fn le_vec3(c: &[u8; 12]) -> Vec3 {
    Vec3::new(
        f32::from_le_bytes([c[0], c[1], c[2], c[3]]),
        f32::from_le_bytes([c[4], c[5], c[6], c[7]]),
        f32::from_le_bytes([c[8], c[9], c[10], c[11]]),
    )
}

/// Whether the face element is exactly `property list uchar int|uint …`.
fn is_triangle_layout(el: &Element) -> bool {
    matches!(
        el.properties.as_slice(),
        [p] if matches!(
            p.kind,
            PropertyKind::List {
                count: ScalarType::U8,
                item: ScalarType::I32 | ScalarType::U32
            }
        )
    )
}

/// Decodes 13-byte `3 a b c` little-endian face records; `None` as soon as
/// a record's count is not 3 (the caller then takes the general path).
/// Indices are reinterpreted as `u32`: a negative `int` becomes ≥ 2³¹,
/// which `validate()` reports as out of range.
fn triangles_le(records: &[u8]) -> Option<Vec<[u32; 3]>> {
    let (recs, _) = records.as_chunks::<13>();
    let mut all_triangles = true;
    let faces: Vec<[u32; 3]> = recs
        .iter()
        .map(|r| {
            all_triangles &= r[0] == 3;
            [
                u32::from_le_bytes([r[1], r[2], r[3], r[4]]),
                u32::from_le_bytes([r[5], r[6], r[7], r[8]]),
                u32::from_le_bytes([r[9], r[10], r[11], r[12]]),
            ]
        })
        .collect();
    all_triangles.then_some(faces)
}

/// Decodes an element record by record, bounds-checking every value.
fn decode_general<S: Source>(
    src: &mut S,
    el: &Element,
    role: &Role,
    vertices: Option<u64>,
    out: &mut Decoded,
) -> Result<(), ParseError> {
    if el.properties.is_empty() {
        // Records of nothing: the count (unbounded by the file) is moot.
        return Ok(());
    }
    // `check_counts` bounded the count by the file size.
    let count = usize::try_from(el.count)
        .map_err(|_| parse_err!("{} element count {} is too large", el.name, el.count))?;
    let list_index = match role {
        Role::Face(i) | Role::RangeGrid(i) => Some(*i),
        Role::Vertex(_) | Role::Skip => None,
    };
    match role {
        Role::Vertex(plan) => out.start_vertices(plan, count),
        Role::Face(_) => out.faces = Vec::with_capacity(count),
        Role::RangeGrid(_) => out.cells = Vec::with_capacity(count),
        Role::Skip => {}
    }
    let mut vals = vec![0.0f64; el.properties.len()];
    let mut poly: Vec<u32> = Vec::new();
    for record in 0..el.count {
        let mut one = || -> Result<(), String> {
            src.begin_record()?;
            for (i, (p, val)) in el.properties.iter().zip(vals.iter_mut()).enumerate() {
                match p.kind {
                    PropertyKind::Scalar(ty) => *val = src.scalar(ty)?,
                    PropertyKind::List { count, item } => {
                        let n = src.list_len(count, item)?;
                        if Some(i) == list_index {
                            poly.clear();
                            for _ in 0..n {
                                poly.push(to_index(src.scalar(item)?)?);
                            }
                        } else {
                            src.skip(n, item)?;
                        }
                    }
                }
            }
            match role {
                Role::Vertex(plan) => out.push_vertex(plan, &vals),
                Role::Face(_) => out.faces.extend(checked_fan(&poly, vertices)?),
                Role::RangeGrid(_) => out.cells.push(poly.first().copied()),
                Role::Skip => {}
            }
            src.end_record()
        };
        // The line is read before `one`'s error is mapped; `end_record`
        // only advances it on success.
        if let Err(msg) = one() {
            return Err(at(el, record, src.line(), msg));
        }
    }
    Ok(())
}
