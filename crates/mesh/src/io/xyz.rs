//! XYZ and PTS text point clouds.
//!
//! **XYZ**: one point per line, whitespace-separated columns. The number of
//! columns on the first data line decides the layout, and every other data
//! line must have the same number:
//! - 3: `x y z`;
//! - 6: `x y z r g b` when, on *every* data line, the last three columns are
//!   integer literals (no `.`, no exponent) in `0..=255`; otherwise
//!   `x y z nx ny nz`. (The writer prints normals with `{:?}`, which always
//!   has a `.` or an exponent, so its own files are never misread.)
//! - 9: `x y z nx ny nz r g b` (colours as integers `0..=255`).
//!
//! **PTS** (Leica style): a line holding a single integer is a point count
//! for the lines that follow (a file may hold several such sections, or none
//! at all); data lines are `x y z`, `x y z intensity`, `x y z r g b` or
//! `x y z intensity r g b`. Intensity is read and dropped (a [`PointCloud`]
//! has no intensity). Counts are only compared with the lines actually
//! present: they never size an allocation.
//!
//! Both: blank lines and lines starting with `#` are skipped, a trailing
//! `\r` is ignored, colours get alpha 255. Writers use Rust's shortest
//! round-trip float formatting, so `write → read` gives back the same `f32`s.
//!
//! Bad input (non-numbers, a wrong column count, a colour outside
//! `0..=255`, a non-finite coordinate, a PTS count that does not match its
//! lines, a file with no points, invalid UTF-8) is a one-line [`ParseError`]
//! naming the line; nothing panics.

use std::io::Write;

use glam::Vec3;

use crate::error::ParseError;
use crate::error::clip;
use crate::mesh::PointCloud;
use crate::parse_err;

/// The most columns any layout uses; longer lines are only counted.
const MAX_COLS: usize = 9;

/// One non-blank, non-comment line: its 1-based number, its column count
/// and its first [`MAX_COLS`] tokens (no per-line allocation, so a
/// multi-gigabyte file costs only its points).
struct DataLine<'a> {
    number: usize,
    count: usize,
    buf: [&'a str; MAX_COLS],
}

impl<'a> DataLine<'a> {
    fn t(&self) -> &[&'a str] {
        &self.buf[..self.count.min(MAX_COLS)]
    }
}

fn as_text(bytes: &[u8]) -> Result<&str, ParseError> {
    std::str::from_utf8(crate::io::input::strip_bom(bytes))
        .map_err(|e| parse_err!("not a text file: invalid UTF-8 at byte {}", e.valid_up_to()))
}

/// The data lines of `text` (blank and `#` lines skipped).
fn data_lines(text: &str) -> impl Iterator<Item = DataLine<'_>> {
    text.split('\n').enumerate().filter_map(|(i, line)| {
        let line = line.trim();
        if line.is_empty() || line.starts_with('#') {
            return None;
        }
        let mut l = DataLine {
            number: i + 1,
            count: 0,
            buf: [""; MAX_COLS],
        };
        for w in line.split_whitespace() {
            if l.count < MAX_COLS {
                l.buf[l.count] = w;
            }
            l.count += 1;
        }
        Some(l)
    })
}

/// Parses a coordinate token; names the line and column on failure.
fn float(tok: &str, line: usize, what: &str) -> Result<f32, ParseError> {
    let v: f32 = tok
        .parse()
        .map_err(|_| parse_err!("line {line}: {what} '{}' is not a number", clip(tok, 32)))?;
    if !v.is_finite() {
        return Err(parse_err!(
            "line {line}: {what} '{}' is not finite",
            clip(tok, 32)
        ));
    }
    Ok(v)
}

fn vec3(t: &[&str], line: usize, what: &str) -> Result<Vec3, ParseError> {
    Ok(Vec3::new(
        float(t[0], line, what)?,
        float(t[1], line, what)?,
        float(t[2], line, what)?,
    ))
}

/// `true` if `tok` is a plain decimal integer in `0..=255`.
fn is_u8_literal(tok: &str) -> bool {
    !tok.is_empty() && tok.bytes().all(|b| b.is_ascii_digit()) && tok.parse::<u8>().is_ok()
}

fn rgb(t: &[&str], line: usize) -> Result<[u8; 4], ParseError> {
    let mut c = [255u8; 4];
    for k in 0..3 {
        if !is_u8_literal(t[k]) {
            return Err(parse_err!(
                "line {line}: colour '{}' is not an integer 0..255",
                clip(t[k], 32)
            ));
        }
        c[k] = t[k].parse().unwrap_or(0);
    }
    Ok(c)
}

/// Reads an XYZ file (layout chosen as described in the module docs).
///
/// Errors: no data lines, a column count other than 3, 6 or 9, a line whose
/// count differs from the first, a token that is not a finite number, a
/// colour that is not an integer `0..=255`.
pub fn read_xyz(bytes: &[u8]) -> Result<PointCloud, ParseError> {
    let text = as_text(bytes)?;
    // Pass 1: layout and line count, nothing stored.
    let first = data_lines(text)
        .next()
        .ok_or_else(|| ParseError::new("no points: the file has no data lines"))?;
    let cols = first.count;
    if !matches!(cols, 3 | 6 | 9) {
        return Err(parse_err!(
            "line {}: {cols} columns; XYZ needs 3 (x y z), 6 (x y z + normal or rgb) or 9 (x y z nx ny nz r g b)",
            first.number
        ));
    }
    let mut n = 0usize;
    let mut six_is_rgb = cols == 6;
    for l in data_lines(text) {
        if l.count != cols {
            return Err(parse_err!(
                "line {}: {} columns, but the first data line (line {}) has {cols}",
                l.number,
                l.count,
                first.number
            ));
        }
        six_is_rgb = six_is_rgb && l.t()[3..6].iter().all(|t| is_u8_literal(t));
        n += 1;
    }
    let has_normals = cols == 9 || (cols == 6 && !six_is_rgb);
    let has_colors = cols == 9 || six_is_rgb;

    // Pass 2: parse.
    let mut cloud = PointCloud {
        positions: Vec::with_capacity(n),
        normals: has_normals.then(|| Vec::with_capacity(n)),
        colors: has_colors.then(|| Vec::with_capacity(n)),
    };
    for l in data_lines(text) {
        let t = l.t();
        cloud
            .positions
            .push(vec3(&t[0..3], l.number, "coordinate")?);
        if let Some(nv) = cloud.normals.as_mut() {
            nv.push(vec3(&t[3..6], l.number, "normal")?);
        }
        if let Some(c) = cloud.colors.as_mut() {
            c.push(rgb(&t[cols - 3..cols], l.number)?);
        }
    }
    Ok(cloud)
}

/// Reads a PTS file (see the module docs for the layouts accepted).
///
/// Errors: no points, a count line that does not match the data lines of
/// its section, a column count other than 3, 4, 6 or 7 (or one that changes
/// between lines), non-numbers, non-finite coordinates, bad colours.
pub fn read_pts(bytes: &[u8]) -> Result<PointCloud, ParseError> {
    let text = as_text(bytes)?;
    let mut positions = Vec::new();
    let mut colors: Vec<[u8; 4]> = Vec::new();
    let mut layout: Option<(usize, usize)> = None; // (columns, first line)
    // The open section: (declared count, line of the count, points seen).
    let mut section: Option<(u64, usize, u64)> = None;
    let close = |s: Option<(u64, usize, u64)>| -> Result<(), ParseError> {
        match s {
            Some((want, at, got)) if want != got => Err(parse_err!(
                "line {at}: the count says {want} points but {got} follow"
            )),
            _ => Ok(()),
        }
    };
    for l in data_lines(text) {
        let t = l.t();
        if l.count == 1 {
            let n: u64 = t[0].parse().map_err(|_| {
                parse_err!(
                    "line {}: '{}' is not a point count (one column)",
                    l.number,
                    clip(t[0], 32)
                )
            })?;
            close(section.take())?;
            section = Some((n, l.number, 0));
            continue;
        }
        let cols = l.count;
        match layout {
            None => {
                if !matches!(cols, 3 | 4 | 6 | 7) {
                    return Err(parse_err!(
                        "line {}: {cols} columns; PTS needs 3 (x y z), 4 (+ intensity), 6 (+ r g b) or 7 (+ intensity r g b)",
                        l.number
                    ));
                }
                layout = Some((cols, l.number));
            }
            Some((c, first)) if c != cols => {
                return Err(parse_err!(
                    "line {}: {cols} columns, but line {first} has {c}",
                    l.number
                ));
            }
            _ => {}
        }
        positions.push(vec3(&t[0..3], l.number, "coordinate")?);
        if cols == 4 || cols == 7 {
            float(t[3], l.number, "intensity")?;
        }
        if cols >= 6 {
            colors.push(rgb(&t[cols - 3..cols], l.number)?);
        }
        if let Some(s) = section.as_mut() {
            s.2 += 1;
        }
    }
    close(section)?;
    if positions.is_empty() {
        return Err(ParseError::new("no points: the file has no data lines"));
    }
    let has_colors = !colors.is_empty();
    Ok(PointCloud {
        positions,
        normals: None,
        colors: has_colors.then_some(colors),
    })
}

/// Writes `x y z [nx ny nz] [r g b]` per point, normals and colours when
/// present (alpha is dropped). Floats use `{:?}` (shortest round-trip, always
/// with a `.` or exponent) so [`read_xyz`] never mistakes normals for colours.
pub fn write_xyz(out: &mut Vec<u8>, p: &PointCloud) -> std::io::Result<()> {
    for i in 0..p.positions.len() {
        let q = p.positions[i];
        write!(out, "{:?} {:?} {:?}", q.x, q.y, q.z)?;
        if let Some(n) = &p.normals {
            let n = n[i];
            write!(out, " {:?} {:?} {:?}", n.x, n.y, n.z)?;
        }
        if let Some(c) = &p.colors {
            let c = c[i];
            write!(out, " {} {} {}", c[0], c[1], c[2])?;
        }
        out.push(b'\n');
    }
    Ok(())
}

/// Writes a PTS file: a count line, then `x y z` per point, or
/// `x y z 0 r g b` (intensity unknown, written as 0) when colours are
/// present. Normals and alpha are not stored by PTS and are dropped.
pub fn write_pts(out: &mut Vec<u8>, p: &PointCloud) -> std::io::Result<()> {
    writeln!(out, "{}", p.positions.len())?;
    for i in 0..p.positions.len() {
        let q = p.positions[i];
        write!(out, "{:?} {:?} {:?}", q.x, q.y, q.z)?;
        if let Some(c) = &p.colors {
            let c = c[i];
            write!(out, " 0 {} {} {}", c[0], c[1], c[2])?;
        }
        out.push(b'\n');
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud(normals: bool, colors: bool) -> PointCloud {
        let positions = vec![
            Vec3::new(0.1, -2.5, 3.0e-7),
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-1.0e20, 0.333_333_34, 7.0),
        ];
        PointCloud {
            normals: normals
                .then(|| vec![Vec3::Z, Vec3::new(0.0, -1.0, 0.0), Vec3::new(0.6, 0.8, 0.0)]),
            colors: colors.then(|| vec![[0, 0, 1, 255], [255, 128, 7, 255], [9, 9, 9, 255]]),
            positions,
        }
    }

    fn xyz_round_trip(p: &PointCloud) -> PointCloud {
        let mut out = Vec::new();
        write_xyz(&mut out, p).unwrap();
        read_xyz(&out).unwrap()
    }

    #[test]
    fn xyz_round_trips_every_layout() {
        for (n, c) in [(false, false), (true, false), (false, true), (true, true)] {
            let p = cloud(n, c);
            assert_eq!(xyz_round_trip(&p), p, "normals {n} colours {c}");
        }
    }

    #[test]
    fn xyz_six_columns_rgb_vs_normals() {
        let rgb = read_xyz(b"0 0 0 255 0 10\n1 1 1 0 0 1\n").unwrap();
        assert!(rgb.normals.is_none());
        assert_eq!(rgb.colors.unwrap()[0], [255, 0, 10, 255]);
        // One line with a float makes the whole file normals.
        let nrm = read_xyz(b"0 0 0 0 0 1\n1 1 1 0.6 0.8 0\n").unwrap();
        assert!(nrm.colors.is_none());
        assert_eq!(nrm.normals.unwrap()[1], Vec3::new(0.6, 0.8, 0.0));
    }

    #[test]
    fn xyz_skips_comments_blank_lines_and_crlf() {
        let p = read_xyz(b"# header\r\n\r\n1 2 3\r\n  # more\n4 5 6").unwrap();
        assert_eq!(
            p.positions,
            vec![Vec3::new(1.0, 2.0, 3.0), Vec3::new(4.0, 5.0, 6.0)]
        );
    }

    #[test]
    fn xyz_bad_input_is_a_line_numbered_error() {
        let cases: [(&[u8], &str); 8] = [
            (b"", "no points"),
            (b"# only a comment\n", "no points"),
            (b"1 2\n", "2 columns"),
            (b"1 2 3\n4 5\n", "line 2: 2 columns"),
            (b"1 2 x\n", "line 1: coordinate 'x' is not a number"),
            (
                b"1 2 3\nnan 0 0\n",
                "line 2: coordinate 'nan' is not finite",
            ),
            (b"1 2 3 1 2 3 4 5 300\n", "colour '300'"),
            (b"1 2 3\n\xff\n", "invalid UTF-8"),
        ];
        for (input, want) in cases {
            let e = read_xyz(input).unwrap_err().to_string();
            assert!(e.contains(want), "{e:?} should contain {want:?}");
            assert!(!e.contains('\n'));
        }
    }

    #[test]
    fn pts_round_trips_with_and_without_colours() {
        for c in [false, true] {
            let p = cloud(false, c);
            let mut out = Vec::new();
            write_pts(&mut out, &p).unwrap();
            assert_eq!(read_pts(&out).unwrap(), p);
        }
        // Normals are not part of PTS: dropped.
        let mut out = Vec::new();
        write_pts(&mut out, &cloud(true, false)).unwrap();
        assert!(read_pts(&out).unwrap().normals.is_none());
    }

    #[test]
    fn pts_layouts_and_sections() {
        let p = read_pts(b"2\n1 2 3 -120 10 20 30\n4 5 6 7 1 2 3\n1\n7 8 9 0 0 0 0\n").unwrap();
        assert_eq!(p.len(), 3);
        assert_eq!(p.colors.unwrap()[2], [0, 0, 0, 255]);
        let q = read_pts(b"1 2 3 0.5\n4 5 6 0.25\n").unwrap();
        assert_eq!(q.len(), 2);
        assert!(q.colors.is_none());
    }

    #[test]
    fn pts_bad_input_is_an_error() {
        let cases: [(&[u8], &str); 6] = [
            (b"3\n1 2 3\n4 5 6\n", "count says 3 points but 2 follow"),
            (b"4000000000\n1 2 3\n", "count says 4000000000"),
            (b"-5\n1 2 3\n", "not a point count"),
            (b"1 2\n", "2 columns"),
            (b"1 2 3 4 5\n", "5 columns"),
            (b"0\n", "no points"),
        ];
        for (input, want) in cases {
            let e = read_pts(input).unwrap_err().to_string();
            assert!(e.contains(want), "{e:?} should contain {want:?}");
        }
    }
}
