//! STL, ASCII and binary.
//!
//! **Detection**: a file is binary when it is at least 84 bytes long and its
//! size is exactly `84 + 50 × count` (count = the `u32` at byte 80), whatever
//! its first bytes say (many binary exporters start the header with
//! `solid`). Otherwise a file starting with `solid` is parsed as ASCII;
//! anything else is refused with the size arithmetic in the message.
//!
//! **Reading**: STL stores every triangle corner separately, so the corners
//! are welded exactly ([`crate::weld::weld`], tolerance 0: bitwise-equal
//! coordinates, `-0 == 0`); vertices are numbered in order of first
//! appearance. Triangles that become degenerate (two equal corners) are
//! dropped. Facet normals are parsed and ignored (they are per face; lodkit
//! normals are per vertex); the binary attribute word (sometimes a colour) is
//! ignored. Winding is kept as stored (STL is CCW seen from outside).
//!
//! **Writing**: attributes are dropped (STL holds geometry only); each facet
//! gets the unit normal of its corners (zero for a degenerate triangle).
//! Binary files use the header `lodkit binary STL` padded with zeros (so they
//! never start with `solid`); ASCII floats use `{:e}` (shortest round-trip
//! scientific notation), so `write → read` gives back the same `f32`s.
//!
//! **Bad input** (empty, shorter than a header, a count that disagrees with
//! the size, malformed ASCII: a missing keyword, a non-number, a facet with
//! other than 3 vertices, a missing `endsolid`; non-finite coordinates; no
//! triangle left) is a one-line [`ParseError`]; nothing panics and nothing
//! is allocated from the header count before the size has confirmed it.

use std::io::Write;
use std::str::SplitWhitespace;

use glam::Vec3;

use crate::error::ParseError;
use crate::error::clip;
use crate::mesh::TriMesh;
use crate::parse_err;

const HEADER: usize = 80;
const FACET_BYTES: u64 = 50;

/// The triangle count from a binary header, if the file has one.
fn binary_count(bytes: &[u8]) -> Option<u32> {
    let c = bytes.get(HEADER..HEADER + 4)?;
    Some(u32::from_le_bytes([c[0], c[1], c[2], c[3]]))
}

/// `true` when the size matches `84 + 50 × count` exactly.
pub fn is_binary(bytes: &[u8]) -> bool {
    binary_count(bytes)
        .is_some_and(|n| (HEADER as u64 + 4) + FACET_BYTES * n as u64 == bytes.len() as u64)
}

/// Reads an ASCII or binary STL (see the module docs) into a welded mesh.
pub fn read(bytes: &[u8]) -> Result<TriMesh, ParseError> {
    if bytes.is_empty() {
        return Err(ParseError::new("empty file"));
    }
    let corners = if is_binary(bytes) {
        read_binary(bytes)?
    } else if crate::io::input::strip_bom(bytes)
        .trim_ascii_start()
        .starts_with(b"solid")
    {
        match read_ascii(crate::io::input::strip_bom(bytes)) {
            Ok(c) => c,
            // A binary file whose size disagrees with its count, but whose
            // header happens to start with `solid`: say what is really wrong.
            Err(e) if bytes.len() >= HEADER + 4 && bytes.contains(&0) => {
                return Err(size_mismatch(bytes).unwrap_or(e));
            }
            Err(e) => return Err(e),
        }
    } else if bytes.len() < HEADER + 4 {
        return Err(parse_err!(
            "{} bytes: too short for a binary STL (80-byte header + 4-byte count) and not ASCII (no 'solid')",
            bytes.len()
        ));
    } else {
        return Err(size_mismatch(bytes).unwrap_or_else(|| ParseError::new("not an STL file")));
    };
    soup_to_mesh(corners)
}

fn size_mismatch(bytes: &[u8]) -> Option<ParseError> {
    let n = binary_count(bytes)?;
    Some(parse_err!(
        "binary STL header says {n} triangles ({} bytes) but the file has {} bytes",
        (HEADER as u64 + 4) + FACET_BYTES * n as u64,
        bytes.len()
    ))
}

/// Corners of a binary STL whose size has been checked by [`is_binary`].
fn read_binary(bytes: &[u8]) -> Result<Vec<[Vec3; 3]>, ParseError> {
    let body = &bytes[HEADER + 4..];
    let f = |b: &[u8], o: usize| f32::from_le_bytes([b[o], b[o + 1], b[o + 2], b[o + 3]]);
    let v = |b: &[u8], o: usize| Vec3::new(f(b, o), f(b, o + 4), f(b, o + 8));
    // `chunks_exact` bounds everything by the real size: the count was
    // checked against it, and no allocation uses the count itself.
    let mut out = Vec::with_capacity(body.len() / FACET_BYTES as usize);
    for rec in body.chunks_exact(FACET_BYTES as usize) {
        out.push([v(rec, 12), v(rec, 24), v(rec, 36)]);
    }
    Ok(out)
}

/// Whitespace tokens with their 1-based line numbers.
struct Tokens<'a> {
    lines: std::iter::Enumerate<std::str::Split<'a, char>>,
    words: SplitWhitespace<'a>,
    line: usize,
}

impl<'a> Tokens<'a> {
    fn new(text: &'a str) -> Self {
        Tokens {
            lines: text.split('\n').enumerate(),
            words: "".split_whitespace(),
            line: 0,
        }
    }
    fn next(&mut self) -> Option<&'a str> {
        loop {
            if let Some(w) = self.words.next() {
                return Some(w);
            }
            let (i, l) = self.lines.next()?;
            self.line = i + 1;
            self.words = l.split_whitespace();
        }
    }
    /// Drops what is left of the current line (a solid's name).
    fn skip_line(&mut self) {
        self.words = "".split_whitespace();
    }
    /// Consumes `word`, the next keyword of facet `facet`.
    fn expect(&mut self, word: &str, facet: usize) -> Result<(), ParseError> {
        match self.next() {
            Some(w) if w == word => Ok(()),
            Some(w) => Err(parse_err!(
                "line {}: expected '{word}' in facet {facet}, found '{}'",
                self.line,
                clip(w, 32)
            )),
            None => Err(parse_err!(
                "unexpected end of file: expected '{word}' in facet {facet}"
            )),
        }
    }
    fn float(&mut self, what: &str) -> Result<f32, ParseError> {
        match self.next() {
            Some(w) => w.parse().map_err(|_| {
                parse_err!(
                    "line {}: {what} '{}' is not a number",
                    self.line,
                    clip(w, 32)
                )
            }),
            None => Err(parse_err!("unexpected end of file: expected a {what}")),
        }
    }
    fn vec3(&mut self, what: &str) -> Result<Vec3, ParseError> {
        Ok(Vec3::new(
            self.float(what)?,
            self.float(what)?,
            self.float(what)?,
        ))
    }
}

/// Corners of an ASCII STL: one or more `solid … endsolid` blocks.
fn read_ascii(bytes: &[u8]) -> Result<Vec<[Vec3; 3]>, ParseError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        parse_err!(
            "ASCII STL with invalid UTF-8 at byte {} (and not a binary STL: header count does not match the size)",
            e.valid_up_to()
        )
    })?;
    let mut t = Tokens::new(text);
    let mut out = Vec::new();
    while let Some(w) = t.next() {
        if w != "solid" {
            return Err(parse_err!(
                "line {}: expected 'solid', found '{}'",
                t.line,
                clip(w, 32)
            ));
        }
        t.skip_line();
        loop {
            match t.next() {
                Some("facet") => {}
                Some("endsolid") => {
                    t.skip_line();
                    break;
                }
                Some(w) => {
                    return Err(parse_err!(
                        "line {}: expected 'facet' or 'endsolid', found '{}'",
                        t.line,
                        clip(w, 32)
                    ));
                }
                None => {
                    return Err(ParseError::new(
                        "unexpected end of file: missing 'endsolid'",
                    ));
                }
            }
            let facet = out.len();
            t.expect("normal", facet)?;
            t.vec3("normal component")?;
            t.expect("outer", facet)?;
            t.expect("loop", facet)?;
            let mut corners = [Vec3::ZERO; 3];
            let mut n = 0usize;
            loop {
                match t.next() {
                    Some("vertex") => {
                        let v = t.vec3("coordinate")?;
                        if n < 3 {
                            corners[n] = v;
                        }
                        n += 1;
                    }
                    Some("endloop") => break,
                    Some(w) => {
                        return Err(parse_err!(
                            "line {}: expected 'vertex' or 'endloop' in facet {facet}, found '{}'",
                            t.line,
                            clip(w, 32)
                        ));
                    }
                    None => {
                        return Err(parse_err!(
                            "unexpected end of file in facet {facet}: missing 'endloop'"
                        ));
                    }
                }
            }
            if n != 3 {
                return Err(parse_err!(
                    "line {}: facet {facet} has {n} vertices, STL facets need 3",
                    t.line
                ));
            }
            t.expect("endfacet", facet)?;
            out.push(corners);
        }
    }
    if out.is_empty() && !text.contains("solid") {
        return Err(ParseError::new("not an ASCII STL: no 'solid'"));
    }
    Ok(out)
}

/// Checks corners, then welds the soup exactly.
fn soup_to_mesh(corners: Vec<[Vec3; 3]>) -> Result<TriMesh, ParseError> {
    if let Some(i) = corners
        .iter()
        .position(|c| c.iter().any(|v| !v.is_finite()))
    {
        let c = corners[i];
        return Err(parse_err!(
            "facet {i} has a non-finite coordinate ({} {} {} / {} {} {} / {} {} {})",
            c[0].x,
            c[0].y,
            c[0].z,
            c[1].x,
            c[1].y,
            c[1].z,
            c[2].x,
            c[2].y,
            c[2].z
        ));
    }
    if corners.len() > (u32::MAX / 3) as usize {
        return Err(parse_err!(
            "{} triangles: more corners than 32-bit indices can address",
            corners.len()
        ));
    }
    let n = corners.len();
    let soup = TriMesh::new(
        corners.into_iter().flatten().collect(),
        (0..n as u32)
            .map(|f| [3 * f, 3 * f + 1, 3 * f + 2])
            .collect(),
    );
    let (mesh, dropped) = crate::weld::weld(&soup, 0.0);
    if mesh.faces.is_empty() {
        return Err(if n == 0 {
            ParseError::new("no triangles")
        } else {
            parse_err!("no triangles left: all {dropped} are degenerate (repeated corners)")
        });
    }
    Ok(mesh)
}

/// Unit normal of a triangle, or zero when it is degenerate.
fn facet_normal([a, b, c]: [Vec3; 3]) -> Vec3 {
    let n = (b - a).cross(c - a);
    let len = n.length();
    if len > 0.0 && len.is_finite() {
        n / len
    } else {
        Vec3::ZERO
    }
}

/// Writes `m` as STL, binary (default) or ASCII. Attributes are dropped.
///
/// Fails (`InvalidInput`) only when the mesh has more than `u32::MAX` faces,
/// which a binary STL cannot count. Face indices must be in range (the
/// [`TriMesh`] invariant).
pub fn write(out: &mut Vec<u8>, m: &TriMesh, ascii: bool) -> std::io::Result<()> {
    if ascii {
        out.extend_from_slice(b"solid lodkit\n");
        for f in 0..m.faces.len() {
            let t = m.triangle(f);
            let n = facet_normal(t);
            writeln!(out, "  facet normal {:e} {:e} {:e}", n.x, n.y, n.z)?;
            out.extend_from_slice(b"    outer loop\n");
            for v in t {
                writeln!(out, "      vertex {:e} {:e} {:e}", v.x, v.y, v.z)?;
            }
            out.extend_from_slice(b"    endloop\n  endfacet\n");
        }
        out.extend_from_slice(b"endsolid lodkit\n");
        return Ok(());
    }
    let count = u32::try_from(m.faces.len()).map_err(|_| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidInput,
            "binary STL holds at most 4294967295 triangles",
        )
    })?;
    let mut header = [0u8; HEADER];
    let tag = b"lodkit binary STL";
    header[..tag.len()].copy_from_slice(tag);
    out.reserve(HEADER + 4 + 50 * m.faces.len());
    out.extend_from_slice(&header);
    out.extend_from_slice(&count.to_le_bytes());
    for f in 0..m.faces.len() {
        let t = m.triangle(f);
        for v in std::iter::once(facet_normal(t)).chain(t) {
            for c in v.to_array() {
                out.extend_from_slice(&c.to_le_bytes());
            }
        }
        out.extend_from_slice(&[0, 0]);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tetrahedron whose vertices appear in first-use order (what a
    /// welded STL read gives back).
    fn tetra() -> TriMesh {
        TriMesh::new(
            vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.1, 0.2, 1.0e-3),
            ],
            vec![[0, 1, 2], [0, 2, 3], [2, 1, 3], [1, 0, 3]],
        )
    }

    fn write_vec(m: &TriMesh, ascii: bool) -> Vec<u8> {
        let mut out = Vec::new();
        write(&mut out, m, ascii).unwrap();
        out
    }

    #[test]
    fn binary_and_ascii_round_trip_exactly() {
        let mut m = tetra();
        m.normals = Some(vec![Vec3::Z; 4]); // dropped by STL
        for ascii in [false, true] {
            let back = read(&write_vec(&m, ascii)).unwrap();
            assert_eq!(back, tetra(), "ascii = {ascii}");
        }
    }

    #[test]
    fn binary_layout_and_normals() {
        let b = write_vec(&tetra(), false);
        assert_eq!(b.len(), 84 + 50 * 4);
        assert!(!b.starts_with(b"solid"));
        assert_eq!(binary_count(&b), Some(4));
        // Facet 0 = (origin, +Y, +X): normal -Z.
        let nz = f32::from_le_bytes([b[92], b[93], b[94], b[95]]);
        assert_eq!(nz, -1.0);
    }

    #[test]
    fn binary_starting_with_solid_is_detected_by_size() {
        let mut b = write_vec(&tetra(), false);
        b[..5].copy_from_slice(b"solid");
        assert_eq!(read(&b).unwrap(), tetra());
    }

    #[test]
    fn weld_merges_corners_and_drops_degenerate_facets() {
        let mut soup = TriMesh::new(
            vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Y, Vec3::X, Vec3::ONE],
            vec![[0, 1, 2], [3, 4, 5]],
        );
        let b = write_vec(&soup, false);
        let m = read(&b).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.faces, vec![[0, 1, 2], [2, 1, 3]]);
        // A facet with two equal corners disappears.
        soup.positions[5] = Vec3::X;
        let m = read(&write_vec(&soup, true)).unwrap();
        assert_eq!(m.faces.len(), 1);
    }

    #[test]
    fn ascii_accepts_several_solids_and_odd_spacing() {
        let text = "solid a b c\nfacet normal 0 0 1\n outer loop\nvertex 0 0 0\nvertex 1 0 0 vertex 0 1 0\nendloop endfacet\nendsolid a\n\
                    solid\r\n facet normal 0 0 0 outer loop vertex 1 1 1 vertex 2 1 1 vertex 1 2 1 endloop endfacet endsolid\r\n";
        let m = read(text.as_bytes()).unwrap();
        assert_eq!(m.faces.len(), 2);
        assert_eq!(m.positions.len(), 6);
    }

    #[test]
    fn bad_input_is_a_one_line_error() {
        let tri = "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n";
        let good_bin = write_vec(&tetra(), false);
        let mut wrong_count = good_bin.clone();
        wrong_count[80..84].copy_from_slice(&4_000_000_000u32.to_le_bytes());
        let mut nan_bin = good_bin.clone();
        nan_bin[96..100].copy_from_slice(&f32::NAN.to_le_bytes());
        let cases: Vec<(Vec<u8>, &str)> = vec![
            (vec![], "empty file"),
            (vec![0; 80], "too short"),
            (vec![0; 84], "no triangles"),
            (good_bin[..good_bin.len() - 7].to_vec(), "header says 4 triangles (284 bytes) but the file has 277"),
            (wrong_count, "header says 4000000000 triangles"),
            (nan_bin, "facet 0 has a non-finite coordinate"),
            (tri.as_bytes().to_vec(), "missing 'endsolid'"),
            (tri.replace("endloop\n", "").into_bytes(), "expected 'vertex' or 'endloop'"),
            (tri.replace("vertex 1 0 0", "vertex 1 zero 0").into_bytes(), "line 5: coordinate 'zero' is not a number"),
            (tri.replace("vertex 0 1 0\n", "").into_bytes(), "facet 0 has 2 vertices"),
            (tri.replace("vertex 0 1 0\n", "vertex 0 1 0\nvertex 1 1 0\n").into_bytes(), "facet 0 has 4 vertices"),
            (format!("{tri}endsolid").replace("vertex 0 0 0", "vertex nan 0 0").into_bytes(), "non-finite"),
            (format!("{tri}endsolid\ngarbage").into_bytes(), "expected 'solid', found 'garbage'"),
            (b"solid x\nendsolid x\n".to_vec(), "no triangles"),
            (b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 0 0 0\nvertex 1 0 0\nendloop\nendfacet\nendsolid\n".to_vec(), "degenerate"),
        ];
        for (input, want) in cases {
            let e = read(&input).unwrap_err().to_string();
            assert!(e.contains(want), "{e:?} should contain {want:?}");
            assert!(!e.contains('\n'), "{e:?}");
        }
    }
}
