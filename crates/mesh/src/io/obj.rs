//! Wavefront OBJ, read through [`tobj`] and written by hand.
//!
//! **Reading**: [`tobj::load_obj_buf`] with `triangulate` and `single_index`,
//! so a corner whose `v/vt/vn` triple differs (an attribute seam) becomes its
//! own vertex. Polygons are fanned from their first corner. All objects and
//! groups are merged into one [`TriMesh`]; vertices come out in order of
//! first use by a face, and `v` lines no face uses are dropped. Materials are
//! ignored here (a missing or broken `.mtl` is not an error; `io::mtl`
//! reads them into a scene); `l` (polyline) and
//! `p` (point) elements are skipped. Attributes:
//! - UVs (`vt`) are kept as stored: OBJ's origin is bottom-left, like lodkit's;
//! - normals (`vn`) are kept as stored (not renormalised);
//! - vertex colours `v x y z r g b` become RGBA8 with alpha 255; values are
//!   taken as `0..1` unless one exceeds 1, in which case the file's colours
//!   are taken as `0..255`; both are clamped and rounded.
//!
//! An attribute is kept only when *every* corner of every face has it;
//! otherwise it is dropped for the whole mesh (a half-textured mesh comes out
//! untextured rather than misaligned), and dropped before vertices are split
//! by it, so no seam remains where the dropped attribute alone differed.
//!
//! **Guarantees on bad input**: before `tobj` sees the text, `prescan`
//! checks every line `tobj` would act on: UTF-8, numbers on `v`/`vt`/`vn`
//! lines, the same colour layout on every `v` line, faces with at least 3
//! corners, and every face index (1-based, or negative = relative) in range
//! of the elements defined *before* the face. This matters: given a face
//! index far out of range, `tobj` 4.0 computes `index * 2 + 1` with
//! unchecked arithmetic and panics on overflow in debug builds (and reads a
//! wrong element after wrap-around in release builds); and given `v` lines
//! with colours on some lines only, it silently pairs colours with the wrong
//! vertices. With the prescan, every such file is a one-line [`ParseError`]
//! naming the line, and `tobj` only ever sees input it handles correctly.
//! Faces that repeat a vertex and non-finite coordinates are refused by
//! [`TriMesh::validate`], which `io::decode` runs on every mesh.
//!
//! **Writing**: `v x y z [r g b]` (colours as `0..1`), `vt u v`, `vn x y z`,
//! then `f` lines in the form that matches the attributes present (`a`,
//! `a/a`, `a//a` or `a/a/a`), 1-based. Floats use Rust's shortest
//! round-trip `f32` formatting; an RGBA8 colour survives `write → read`
//! exactly (alpha is not stored by OBJ and reads back as 255).

use std::borrow::Cow;
use std::io::Write;

use glam::{Vec2, Vec3};

use crate::error::ParseError;
use crate::error::clip;
use crate::mesh::TriMesh;
use crate::parse_err;

/// What the prescan learned about the file.
#[derive(Debug, Default)]
pub(super) struct Scan {
    /// The file has `l` lines, which must be hidden from `tobj` (it turns an
    /// `l` with 3 or more points into a face).
    has_polylines: bool,
    /// Face corners in the file, and how many of them name a texture
    /// coordinate / a normal.
    corners: usize,
    with_uv: usize,
    with_normal: usize,
}

impl Scan {
    /// Texture coordinates are dropped: some corners lack one.
    fn drops_uvs(&self) -> bool {
        self.with_uv > 0 && self.with_uv < self.corners
    }
    /// Normals are dropped: some corners lack one.
    fn drops_normals(&self) -> bool {
        self.with_normal > 0 && self.with_normal < self.corners
    }
}

fn check_floats<'a>(
    words: impl Iterator<Item = &'a str>,
    line: usize,
    what: &str,
) -> Result<(), ParseError> {
    for w in words {
        if w.parse::<f32>().is_err() {
            return Err(parse_err!(
                "line {line}: {what} '{}' is not a number",
                clip(w, 32)
            ));
        }
    }
    Ok(())
}

/// Resolves one face index (1-based, or negative = relative to the `count`
/// elements defined so far) to a 0-based index, or says why it cannot.
fn resolve(tok: &str, count: usize, what: &str, line: usize) -> Result<usize, ParseError> {
    let x: i64 = tok.parse().map_err(|_| {
        parse_err!(
            "line {line}: face {what} index '{}' is not an integer",
            clip(tok, 32)
        )
    })?;
    let count_i = count as i64;
    let r = if x > 0 {
        x - 1
    } else if x < 0 {
        count_i + x
    } else {
        return Err(parse_err!(
            "line {line}: face {what} index 0 (OBJ indices start at 1)"
        ));
    };
    if r < 0 || r >= count_i {
        return Err(parse_err!(
            "line {line}: face {what} index {x} is out of range: {count} {} defined so far",
            match (what, count == 1) {
                (_, true) => what,
                ("vertex", false) => "vertices",
                ("normal", false) => "normals",
                _ => "texture coordinates",
            }
        ));
    }
    Ok(r as usize)
}

/// Checks every line `tobj` acts on (see the module docs); line numbers are
/// 1-based.
pub(super) fn prescan(text: &str) -> Result<Scan, ParseError> {
    let mut scan = Scan::default();
    let (mut nv, mut nvt, mut nvn) = (0usize, 0usize, 0usize);
    // First line of a `v` with colours, and of one without.
    let (mut colored_at, mut plain_at) = (None, None);
    for (i, raw) in text.split('\n').enumerate() {
        let line = i + 1;
        let mut words = raw.split_whitespace();
        match words.next() {
            Some("v") => {
                let rest: Vec<&str> = words.collect();
                match rest.len() {
                    3 | 4 => {
                        plain_at.get_or_insert(line);
                    }
                    6 => {
                        colored_at.get_or_insert(line);
                    }
                    n => {
                        return Err(parse_err!(
                            "line {line}: 'v' with {n} numbers (expected x y z, x y z w or x y z r g b)"
                        ));
                    }
                }
                check_floats(rest.iter().copied(), line, "vertex value")?;
                if let (Some(c), Some(p)) = (colored_at, plain_at) {
                    return Err(parse_err!(
                        "line {}: vertex colours on some 'v' lines (line {c}) but not on others (line {p})",
                        c.max(p)
                    ));
                }
                nv += 1;
            }
            Some("vt") => {
                let rest: Vec<&str> = words.take(3).collect();
                if rest.len() < 2 {
                    return Err(parse_err!("line {line}: 'vt' needs at least u and v"));
                }
                check_floats(rest.iter().copied(), line, "texture coordinate")?;
                nvt += 1;
            }
            Some("vn") => {
                let rest: Vec<&str> = words.collect();
                if rest.len() != 3 {
                    return Err(parse_err!(
                        "line {line}: 'vn' with {} numbers (expected 3)",
                        rest.len()
                    ));
                }
                check_floats(rest.iter().copied(), line, "normal component")?;
                nvn += 1;
            }
            Some("f") => {
                let mut corners = 0usize;
                for w in words {
                    corners += 1;
                    let mut parts = w.split('/');
                    let v = parts.next().unwrap_or("");
                    if v.is_empty() {
                        return Err(parse_err!(
                            "line {line}: face corner '{}' has no vertex index",
                            clip(w, 32)
                        ));
                    }
                    resolve(v, nv, "vertex", line)?;
                    if let Some(t) = parts.next().filter(|t| !t.is_empty()) {
                        resolve(t, nvt, "texture coordinate", line)?;
                        scan.with_uv += 1;
                    }
                    if let Some(n) = parts.next().filter(|n| !n.is_empty()) {
                        resolve(n, nvn, "normal", line)?;
                        scan.with_normal += 1;
                    }
                    if parts.next().is_some() {
                        return Err(parse_err!(
                            "line {line}: face corner '{}' has more than v/vt/vn",
                            clip(w, 32)
                        ));
                    }
                }
                scan.corners += corners;
                if corners < 3 {
                    return Err(parse_err!(
                        "line {line}: face with {corners} corner{} (a face needs at least 3)",
                        if corners == 1 { "" } else { "s" }
                    ));
                }
            }
            Some("l") => scan.has_polylines = true,
            Some("usemtl") if words.next().is_none() => {
                return Err(parse_err!("line {line}: 'usemtl' without a material name"));
            }
            _ => {}
        }
    }
    Ok(scan)
}

/// `text` as `tobj` may see it: `l` lines blanked, and the texture
/// coordinate or normal index taken out of every face corner when that
/// attribute is dropped (some corners lack it). `tobj` splits a vertex for
/// every distinct `v/vt/vn` triple; an index it never sees cannot split
/// one, so a quad textured on one half stays one connected quad once its
/// UVs are dropped. Line count and numbering are kept.
pub(super) fn rewritten<'a>(text: &'a str, scan: &Scan) -> Cow<'a, str> {
    let (drop_uv, drop_n) = (scan.drops_uvs(), scan.drops_normals());
    if !scan.has_polylines && !drop_uv && !drop_n {
        return Cow::Borrowed(text);
    }
    let mut out = String::with_capacity(text.len());
    for (i, line) in text.split('\n').enumerate() {
        if i > 0 {
            out.push('\n');
        }
        let mut words = line.split_whitespace();
        match words.next() {
            Some("l") => {}
            Some("f") if drop_uv || drop_n => {
                out.push('f');
                for w in words {
                    let mut parts = w.split('/');
                    let v = parts.next().unwrap_or("");
                    let t = parts.next().filter(|t| !t.is_empty() && !drop_uv);
                    let n = parts.next().filter(|n| !n.is_empty() && !drop_n);
                    out.push(' ');
                    out.push_str(v);
                    match (t, n) {
                        (Some(t), Some(n)) => {
                            out.push('/');
                            out.push_str(t);
                            out.push('/');
                            out.push_str(n);
                        }
                        (Some(t), None) => {
                            out.push('/');
                            out.push_str(t);
                        }
                        (None, Some(n)) => {
                            out.push_str("//");
                            out.push_str(n);
                        }
                        (None, None) => {}
                    }
                }
            }
            _ => out.push_str(line),
        }
    }
    Cow::Owned(out)
}

/// Reads an OBJ file into one triangle mesh (see the module docs).
///
/// Errors: invalid UTF-8, any problem `prescan` finds (with its line),
/// anything else `tobj` refuses, and a file with no faces.
pub fn read(bytes: &[u8]) -> Result<TriMesh, ParseError> {
    let bytes = crate::io::input::strip_bom(bytes);
    let text = std::str::from_utf8(bytes)
        .map_err(|e| parse_err!("not a text file: invalid UTF-8 at byte {}", e.valid_up_to()))?;
    let scan = prescan(text)?;
    let text = rewritten(text, &scan);
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |_| {
        Err(tobj::LoadError::OpenFileFailed)
    })
    .map_err(|e| parse_err!("OBJ: {e}"))?;
    merge(&models)
}

/// Merges `tobj` models into one mesh, keeping an attribute only when every
/// model with vertices has it for all of its vertices.
pub(super) fn merge(models: &[tobj::Model]) -> Result<TriMesh, ParseError> {
    let used: Vec<&tobj::Mesh> = models
        .iter()
        .map(|m| &m.mesh)
        .filter(|m| !m.positions.is_empty())
        .collect();
    let total: usize = used.iter().map(|m| m.positions.len() / 3).sum();
    if used.iter().all(|m| m.indices.is_empty()) {
        return Err(ParseError::new("no faces"));
    }
    let all = |f: &dyn Fn(&tobj::Mesh) -> bool| used.iter().all(|m| f(m));
    let has_uv =
        all(&|m| m.texcoords.len() / 2 == m.positions.len() / 3 && m.texcoords.len() % 2 == 0);
    let has_n = all(&|m| m.normals.len() == m.positions.len());
    let has_c = all(&|m| m.vertex_color.len() == m.positions.len());
    let scale = if has_c
        && used
            .iter()
            .flat_map(|m| m.vertex_color.iter())
            .any(|&c| c > 1.0)
    {
        1.0
    } else {
        255.0
    };
    let mut out = TriMesh {
        positions: Vec::with_capacity(total),
        normals: has_n.then(|| Vec::with_capacity(total)),
        colors: has_c.then(|| Vec::with_capacity(total)),
        uvs: has_uv.then(|| Vec::with_capacity(total)),
        faces: Vec::new(),
    };
    for m in used {
        let base = u32::try_from(out.positions.len())
            .map_err(|_| ParseError::new("more vertices than 32-bit indices can address"))?;
        let n = m.positions.len() / 3;
        out.positions.extend(
            m.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if let Some(v) = out.normals.as_mut() {
            v.extend(
                m.normals
                    .chunks_exact(3)
                    .map(|p| Vec3::new(p[0], p[1], p[2])),
            );
        }
        if let Some(v) = out.uvs.as_mut() {
            v.extend(m.texcoords.chunks_exact(2).map(|p| Vec2::new(p[0], p[1])));
        }
        if let Some(v) = out.colors.as_mut() {
            let q = |c: f32| (c * scale).clamp(0.0, 255.0).round() as u8;
            v.extend(
                m.vertex_color
                    .chunks_exact(3)
                    .map(|c| [q(c[0]), q(c[1]), q(c[2]), 255]),
            );
        }
        if m.indices.len() % 3 != 0 {
            return Err(ParseError::new(
                "OBJ: triangulation left a partial triangle",
            ));
        }
        for t in m.indices.chunks_exact(3) {
            if t.iter().any(|&i| i as usize >= n) {
                return Err(ParseError::new("OBJ: face index out of range"));
            }
            out.faces.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    if out.positions.len() > u32::MAX as usize {
        return Err(ParseError::new(
            "more vertices than 32-bit indices can address",
        ));
    }
    Ok(out)
}

/// Writes `m` as OBJ (see the module docs). Face indices must be in range
/// (the [`TriMesh`] invariant).
pub fn write(out: &mut Vec<u8>, m: &TriMesh) -> std::io::Result<()> {
    writeln!(
        out,
        "# lodkit OBJ: {} vertices, {} faces",
        m.positions.len(),
        m.faces.len()
    )?;
    for (i, p) in m.positions.iter().enumerate() {
        write!(out, "v {} {} {}", p.x, p.y, p.z)?;
        if let Some(c) = &m.colors {
            let c = c[i];
            let f = |x: u8| x as f32 / 255.0;
            write!(out, " {} {} {}", f(c[0]), f(c[1]), f(c[2]))?;
        }
        out.push(b'\n');
    }
    if let Some(uvs) = &m.uvs {
        for t in uvs {
            writeln!(out, "vt {} {}", t.x, t.y)?;
        }
    }
    if let Some(normals) = &m.normals {
        for n in normals {
            writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
        }
    }
    let (uv, nrm) = (m.uvs.is_some(), m.normals.is_some());
    for f in &m.faces {
        out.push(b'f');
        for &i in f {
            let i = i as u64 + 1;
            match (uv, nrm) {
                (false, false) => write!(out, " {i}")?,
                (true, false) => write!(out, " {i}/{i}")?,
                (false, true) => write!(out, " {i}//{i}")?,
                (true, true) => write!(out, " {i}/{i}/{i}")?,
            }
        }
        out.push(b'\n');
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square pyramid with vertices in first-use order, all attributes.
    fn pyramid() -> TriMesh {
        let positions = vec![
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.5, 0.5, 1.0e-7),
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
        ];
        TriMesh {
            normals: Some(
                positions
                    .iter()
                    .map(|p| (*p - Vec3::splat(0.3)).normalize())
                    .collect(),
            ),
            colors: Some(vec![
                [0, 0, 0, 255],
                [255, 1, 2, 255],
                [128, 127, 129, 255],
                [3, 254, 17, 255],
                [9, 99, 199, 255],
            ]),
            uvs: Some(
                positions
                    .iter()
                    .map(|p| Vec2::new(p.x, 1.0 - p.y / 3.0))
                    .collect(),
            ),
            faces: vec![[0, 1, 2], [1, 3, 2], [3, 4, 2], [4, 0, 2]],
            positions,
        }
    }

    fn round_trip(m: &TriMesh) -> TriMesh {
        let mut out = Vec::new();
        write(&mut out, m).unwrap();
        read(&out).unwrap()
    }

    #[test]
    fn round_trips_every_attribute_combination() {
        for mask in 0..8 {
            let mut m = pyramid();
            if mask & 1 == 0 {
                m.normals = None;
            }
            if mask & 2 == 0 {
                m.colors = None;
            }
            if mask & 4 == 0 {
                m.uvs = None;
            }
            assert_eq!(round_trip(&m), m, "mask {mask}");
        }
    }

    #[test]
    fn every_u8_colour_survives() {
        let n = 256;
        let positions: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(i as f32, (i * i) as f32, 0.0))
            .collect();
        let m = TriMesh {
            colors: Some(
                (0..n)
                    .map(|i| [i as u8, 255 - i as u8, (i * 7 % 256) as u8, 255])
                    .collect(),
            ),
            faces: (0..n as u32 - 2)
                .step_by(3)
                .map(|i| [i, i + 1, i + 2])
                .collect(),
            positions,
            ..Default::default()
        };
        // Vertex 255 is used by no face and is dropped.
        let back = round_trip(&m);
        assert_eq!(back.colors.unwrap()[..255], m.colors.unwrap()[..255]);
    }

    #[test]
    fn seams_quads_objects_and_relative_indices() {
        let text = "mtllib missing.mtl\no a\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nvt 0.5 0.5\n\
                    usemtl nowhere\nf 1/1 2/2 3/3 4/4\ng b\nf -4/5 -2/3 -1/4\nl 1 2 3\n";
        let m = read(text.as_bytes()).unwrap();
        // The quad is fanned; group `b` is merged after `a` with its own
        // vertices, the first of which, (v1, vt5), is a UV seam copy of v1.
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [4, 5, 6]]);
        assert_eq!(m.positions.len(), 7);
        assert_eq!(m.positions[4], Vec3::ZERO);
        assert_eq!(m.uvs.as_ref().unwrap()[4], Vec2::splat(0.5));
        assert!(m.normals.is_none() && m.colors.is_none());
    }

    #[test]
    fn attributes_missing_on_some_corners_are_dropped() {
        let text =
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 1\nvt 0 0\nvn 0 0 1\nf 1/1/1 2/1/1 3/1/1\nf 2 4 3\n";
        let m = read(text.as_bytes()).unwrap();
        assert_eq!(m.faces.len(), 2);
        assert!(m.uvs.is_none() && m.normals.is_none());
        // The dropped attributes split no vertex: 4 positions, 4 vertices.
        assert_eq!(m.positions.len(), 4);
    }

    /// A quad with UVs on one of its two triangles: the UVs are dropped,
    /// and the vertex split they made is not kept, so the quad stays one
    /// connected component (two triangles sharing an edge).
    #[test]
    fn a_quad_textured_on_one_half_stays_one_component() {
        let text = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 1 1\n\
                    vn 0 0 1\nf 1/1/1 2/2/1 3/3/1\nf 1//1 3//1 4//1\n";
        let m = read(text.as_bytes()).unwrap();
        assert!(m.uvs.is_none());
        assert!(m.normals.is_some(), "normals are on every corner and stay");
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3]]);
        let stats = crate::topology::topology_stats(&m);
        assert_eq!(
            (stats.components, stats.boundary_edges),
            (1, 4),
            "{stats:?}"
        );
    }

    #[test]
    fn colours_in_0_255_and_w_coordinate() {
        let m = read(b"v 0 0 0 255 0 128\nv 2 0 0 2 0 0\nv 0 2 0 0 0 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.colors.unwrap()[0], [255, 0, 128, 255]);
        let m = read(b"v 0 0 0\nv 2 0 0 2\nv 0 2 0\nf 1 2 3\n").unwrap();
        assert_eq!(m.positions[1], Vec3::X);
    }

    #[test]
    fn bad_input_is_a_line_numbered_error() {
        let tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
        let cases: Vec<(String, &str)> = vec![
            (String::new(), "no faces"),
            (tri.to_string(), "no faces"),
            (
                format!("{tri}f 1 2 4\n"),
                "line 4: face vertex index 4 is out of range: 3 vertices",
            ),
            (format!("{tri}f 0 1 2\n"), "line 4: face vertex index 0"),
            (format!("{tri}f -1 -2 -4\n"), "index -4 is out of range"),
            (
                format!("{tri}vt 0 0\nf 1/1 2/-9223372036854775807 3/1\n"),
                "texture coordinate index -9223372036854775807",
            ),
            (
                format!("{tri}vn 0 0 1\nf 1//1 2//9223372036854775807 3//1\n"),
                "normal index 9223372036854775807",
            ),
            (
                format!("{tri}f 1 2 99999999999999999999999\n"),
                "not an integer",
            ),
            (format!("{tri}f 1 2\n"), "line 4: face with 2 corners"),
            (format!("{tri}f 1\n"), "face with 1 corner "),
            (format!("{tri}f 1/// 2 3\n"), "more than v/vt/vn"),
            (format!("{tri}f /1 2 3\n"), "no vertex index"),
            (
                "v 0 0 zero\n".to_string(),
                "line 1: vertex value 'zero' is not a number",
            ),
            ("v 0 0\n".to_string(), "'v' with 2 numbers"),
            (
                format!("{tri}v 1 1 1 0.5 0.5 0.5\nf 1 2 4\n"),
                "line 4: vertex colours on some 'v' lines",
            ),
            (format!("{tri}vt x 0\n"), "texture coordinate 'x'"),
            (format!("{tri}vn 0 1\n"), "'vn' with 2 numbers"),
            (format!("{tri}f 1 1 2\n"), "repeats"),
            (format!("{tri}v nan 0 0\nf 1 2 4\n"), "not finite"),
            (format!("{tri}f 1 2 3\nusemtl\n"), "'usemtl' without"),
        ];
        for (input, want) in cases {
            let e = read(input.as_bytes())
                .and_then(|m| m.validate().map(|_| m))
                .unwrap_err()
                .to_string();
            assert!(e.contains(want), "{e:?} should contain {want:?}");
            assert!(!e.contains('\n'), "{e:?}");
        }
        let e = read(b"v 0 0 0\n\xff\n").unwrap_err().to_string();
        assert!(e.contains("invalid UTF-8"), "{e}");
    }
}
