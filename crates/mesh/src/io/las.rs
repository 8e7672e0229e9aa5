//! LAS and LAZ point clouds (ASPRS LAS 1.0–1.4; LAZ through the `las`
//! crate's pure-Rust `laz` decoder).
//!
//! **What is read**: every point's position and, in the point formats that
//! have it (2, 3, 5, 7, 8, 10), its RGB colour. Intensity, returns,
//! classes, GPS time and extra bytes are dropped (a [`PointCloud`] has no
//! such fields); there are no normals.
//!
//! **Coordinates are kept exact.** LAS stores each coordinate as an
//! integer × scale + offset, in `f64`; airborne scans sit far from zero
//! (the Autzen sample: x ≈ 636,000 ft), where an `f32` has a step of
//! 0.06 ft. So the reader picks an **origin** — the centre of the points'
//! integer box, on the file's own grid (offset + scale × integer) — and
//! the cloud's positions are `(integer × scale + offset) − origin`,
//! computed in `f64` and then stored as `f32`, which keeps them within
//! 1e-4 of the file's values for any cloud less than a few hundred
//! kilometres across. Units are the file's (feet, metres, degrees: never
//! converted). [`LasCloud::origin`] gives the origin back, and
//! [`super::decode_located`] / [`super::load_located`] carry it beside the
//! [`crate::Model`]; the plain [`super::load`] drops it, so a LAS read
//! through it is centred on its origin.
//!
//! **Colours**: LAS colours are 16-bit. Some writers store 8-bit values
//! unscaled (0–255); so when *every* channel of *every* point is ≤ 255 the
//! values are taken as they are, otherwise each is shifted right by 8
//! (`65535 → 255`). Alpha is 255.
//!
//! **Bad input** is a one-line [`ParseError`]; no count read from the file
//! sizes an allocation before it is checked against the file's bytes: an
//! uncompressed file must hold `points × record length` bytes after its
//! header; a LAZ file may claim at most [`MAX_LAZ_POINTS_PER_BYTE`] points
//! per compressed byte, its chunk table at most one chunk per 20 bytes of
//! point data, and an extended VLR no more bytes than the file has. Points
//! are decoded in batches of [`BATCH`], so memory follows the points
//! actually decoded. Cost: one pass over the points; memory: a copy of the
//! file's bytes (the decoder needs an owned stream) plus the cloud.
//!
//! Not in the `wasm32` build (the browser reads `.mco`/`.pop`, and the
//! `las` crate's date type brings wasm-bindgen imports): there [`read`]
//! is a one-line error.

#[cfg(not(target_arch = "wasm32"))]
use std::io::Cursor;

#[cfg(not(target_arch = "wasm32"))]
use glam::Vec3;

use crate::error::ParseError;
use crate::mesh::PointCloud;
#[cfg(not(target_arch = "wasm32"))]
use crate::parse_err;

/// The most points a LAZ file may claim per byte of compressed point data.
/// LAZ compresses real scans 5–15×, that is 1–5 bytes per point; 64 points
/// a byte is far beyond any real file and still bounds the work a lying
/// header can ask for.
pub const MAX_LAZ_POINTS_PER_BYTE: u64 = 64;

/// Points decoded per batch.
pub const BATCH: u64 = 1 << 16;

/// A decoded LAS/LAZ file.
#[derive(Debug, Clone, PartialEq)]
pub struct LasCloud {
    /// The points, relative to [`LasCloud::origin`], in the file's units.
    pub cloud: PointCloud,
    /// Where the cloud's zero lies, in the file's coordinates and units
    /// (a point on the file's integer grid).
    pub origin: [f64; 3],
    /// The coordinate reference system, when the header says it: the WKT
    /// text, or `EPSG:n` from the GeoTIFF keys.
    pub crs: Option<String>,
}

/// Whether `bytes` start like a LAS/LAZ file (`LASF`).
pub fn is_las(bytes: &[u8]) -> bool {
    bytes.starts_with(b"LASF")
}

/// Decodes a LAS or LAZ file (see the module docs for what is kept and
/// how counts are bounded).
#[cfg(not(target_arch = "wasm32"))]
pub fn read(bytes: &[u8]) -> Result<LasCloud, ParseError> {
    precheck(bytes)?;
    quietly_caught(|| decode(bytes))
}

/// On `wasm32` LAS/LAZ is not read: a one-line error.
#[cfg(target_arch = "wasm32")]
pub fn read(_bytes: &[u8]) -> Result<LasCloud, ParseError> {
    Err(ParseError::new("LAS/LAZ is not read in the wasm32 build"))
}

#[cfg(not(target_arch = "wasm32"))]
thread_local! {
    static QUIET: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
}

/// Runs `f`, turning a panic into a one-line error. The LAZ decoder
/// asserts on some corrupt streams instead of returning an error; its
/// panic is caught here, and a process-wide hook (installed once, which
/// hands every other panic to the hook that was there before) keeps it
/// from printing while this thread decodes.
#[cfg(not(target_arch = "wasm32"))]
fn quietly_caught<T>(f: impl FnOnce() -> Result<T, ParseError>) -> Result<T, ParseError> {
    static HOOK: std::sync::Once = std::sync::Once::new();
    HOOK.call_once(|| {
        let previous = std::panic::take_hook();
        std::panic::set_hook(Box::new(move |info| {
            if !QUIET.with(|q| q.get()) {
                previous(info);
            }
        }));
    });
    QUIET.with(|q| q.set(true));
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    QUIET.with(|q| q.set(false));
    result.unwrap_or_else(|payload| {
        let why = payload
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| payload.downcast_ref::<String>().cloned())
            .unwrap_or_default();
        Err(parse_err!(
            "corrupt point data (the LAS/LAZ decoder failed: {})",
            crate::error::clip(why.lines().next().unwrap_or(""), 80)
        ))
    })
}

/// A reader over `source` (a LAS/LAZ file of `file_len` bytes whose
/// `precheck` passed), its header, point count and transforms, with the
/// count checked against the point data's bytes.
#[cfg(not(target_arch = "wasm32"))]
fn open_reader<R: std::io::Read + std::io::Seek + Send + Sync + std::fmt::Debug + 'static>(
    source: R,
    file_len: u64,
    data_start: u64,
) -> Result<(las::Reader, las::Header, u64, [las::Transform; 3]), ParseError> {
    let reader = las::Reader::new(source).map_err(|e| parse_err!("bad LAS header: {e}"))?;
    let header = reader.header().clone();
    let n = header.number_of_points();
    let format = header.point_format();
    let record_len = u64::from(format.len());
    let data_bytes = file_len.saturating_sub(data_start);
    if format.is_compressed {
        let most = data_bytes.saturating_mul(MAX_LAZ_POINTS_PER_BYTE);
        if n > most {
            return Err(parse_err!(
                "header claims {n} points but the file has {data_bytes} bytes of compressed \
                 point data (at most {most} points)"
            ));
        }
    } else if n.saturating_mul(record_len) > data_bytes {
        return Err(parse_err!(
            "header claims {n} points of {record_len} bytes but the file has {data_bytes} bytes \
             of point data"
        ));
    }
    if n == 0 {
        return Err(parse_err!("the file has no points"));
    }
    let t = header.transforms();
    let (tx, ty, tz) = (t.x, t.y, t.z);
    for (axis, tr) in [("x", tx), ("y", ty), ("z", tz)] {
        if !(tr.scale.is_finite() && tr.scale != 0.0 && tr.offset.is_finite()) {
            return Err(parse_err!(
                "{axis} scale {} / offset {} is not a usable transform",
                tr.scale,
                tr.offset
            ));
        }
    }
    Ok((reader, header, n, [tx, ty, tz]))
}

/// Calls `f` with each batch of `n` points' integer coordinates and RGB
/// (when the format has colours), in file order.
#[cfg(not(target_arch = "wasm32"))]
fn for_each_batch(
    reader: &mut las::Reader,
    header: &las::Header,
    n: u64,
    mut f: impl FnMut(&mut dyn Iterator<Item = [i32; 3]>, Option<&mut dyn Iterator<Item = [u16; 3]>>),
) -> Result<(), ParseError> {
    let mut batch = las::PointDataBuilder::new().for_header(header).build();
    let mut left = n;
    while left > 0 {
        let got = reader
            .fill_points(left.min(BATCH), &mut batch)
            .map_err(|e| parse_err!("point {}: {e}", n - left))?;
        if got == 0 {
            return Err(parse_err!(
                "the file ends after {} of the {n} points its header claims",
                n - left
            ));
        }
        let mut ints = batch
            .x_raw()
            .zip(batch.y_raw())
            .zip(batch.z_raw())
            .map(|((x, y), z)| [x, y, z]);
        match batch.rgb() {
            Some(c) => f(&mut ints, Some(&mut c.map(|(r, g, b)| [r, g, b]))),
            None => f(&mut ints, None),
        }
        left -= got;
    }
    Ok(())
}

/// The origin rule of the module docs: the centre of the integer box
/// `lo..=hi`, on the integer grid (`mid`), and where it lies in the
/// file's coordinates.
#[cfg(not(target_arch = "wasm32"))]
fn origin_of(lo: [i32; 3], hi: [i32; 3], trs: &[las::Transform; 3]) -> ([i64; 3], [f64; 3]) {
    let mid: [i64; 3] =
        std::array::from_fn(|k| (i64::from(lo[k]) + i64::from(hi[k])).div_euclid(2));
    let origin: [f64; 3] = std::array::from_fn(|k| mid[k] as f64 * trs[k].scale + trs[k].offset);
    (mid, origin)
}

/// A point's position relative to the origin `mid` (see the module docs).
#[cfg(not(target_arch = "wasm32"))]
fn relative(p: [i32; 3], mid: &[i64; 3], trs: &[las::Transform; 3]) -> Vec3 {
    Vec3::from_array(std::array::from_fn(|k| {
        ((i64::from(p[k]) - mid[k]) as f64 * trs[k].scale) as f32
    }))
}

/// A colour by the colour rule of the module docs (`narrow`: every
/// channel of every point ≤ 255).
#[cfg(not(target_arch = "wasm32"))]
fn to_rgba8(c: [u16; 3], narrow: bool) -> [u8; 4] {
    let to8 = |v: u16| if narrow { v as u8 } else { (v >> 8) as u8 };
    [to8(c[0]), to8(c[1]), to8(c[2]), 255]
}

#[cfg(not(target_arch = "wasm32"))]
fn decode(bytes: &[u8]) -> Result<LasCloud, ParseError> {
    let data_start = u64::from(u32_at(bytes, 96));
    let (mut reader, header, n, trs) =
        open_reader(Cursor::new(bytes.to_vec()), bytes.len() as u64, data_start)?;
    // Integers and colours first (the origin needs the integer box).
    let cap = n.min(BATCH * 16) as usize;
    let mut ints: Vec<[i32; 3]> = Vec::with_capacity(cap);
    let mut rgb: Vec<[u16; 3]> = Vec::new();
    for_each_batch(&mut reader, &header, n, |i, c| {
        ints.extend(i);
        if let Some(c) = c {
            rgb.extend(c);
        }
    })?;
    let mut lo = [i32::MAX; 3];
    let mut hi = [i32::MIN; 3];
    for p in &ints {
        for k in 0..3 {
            lo[k] = lo[k].min(p[k]);
            hi[k] = hi[k].max(p[k]);
        }
    }
    let (mid, origin) = origin_of(lo, hi, &trs);
    let positions = ints.iter().map(|&p| relative(p, &mid, &trs)).collect();
    drop(ints);
    let colors = (rgb.len() as u64 == n).then(|| {
        let narrow = rgb.iter().all(|c| c.iter().all(|&v| v <= 255));
        rgb.iter().map(|&c| to_rgba8(c, narrow)).collect()
    });
    let crs = crs_of(&header);
    Ok(LasCloud {
        cloud: PointCloud {
            positions,
            normals: None,
            colors,
        },
        origin,
        crs,
    })
}

/// A LAS/LAZ file read in passes without holding its points or its bytes
/// (out-of-core tiling): [`LasStream::open`] reads it once for the
/// integer box (the origin) and the colours' range, then each
/// [`LasStream::for_each`] reads it again, giving every point as
/// [`read`] would (relative to the same origin, the same colours). The
/// same checks as [`read`], the header's on bytes read from the file
/// where the in-core reader reads them from its copy. Memory: one batch
/// of [`BATCH`] points and the decoder's buffers.
#[cfg(not(target_arch = "wasm32"))]
#[derive(Debug)]
pub struct LasStream {
    path: std::path::PathBuf,
    n: u64,
    trs: [las::Transform; 3],
    mid: [i64; 3],
    origin: [f64; 3],
    /// `Some(narrow)` when the points have colours.
    colors: Option<bool>,
}

#[cfg(not(target_arch = "wasm32"))]
impl LasStream {
    /// Opens `path` and reads its points once (see the type's docs).
    /// Errors: I/O, anything [`read`] refuses; one line naming the file.
    pub fn open(path: &std::path::Path) -> crate::Result<LasStream> {
        let io = |e| crate::Error::io(path, e);
        let file = std::fs::File::open(path).map_err(io)?;
        let len = file.metadata().map_err(io)?.len();
        let at = |at: u64, n: usize| read_at(&file, at, n);
        let bad = |e| crate::Error::parse(path, e);
        precheck_at(len, &at).map_err(bad)?;
        let data_start = at(96, 4).map_or(0, |b| u64::from(u32_at(&b, 0)));
        let mut lo = [i32::MAX; 3];
        let mut hi = [i32::MIN; 3];
        let mut narrow = true;
        drop(file);
        let file = std::fs::File::open(path).map_err(io)?;
        let (n, trs, has_colors) = quietly_caught(|| {
            let source = std::io::BufReader::with_capacity(1 << 20, file);
            let (mut reader, header, n, trs) = open_reader(source, len, data_start)?;
            let has_colors = header.point_format().has_color;
            for_each_batch(&mut reader, &header, n, |ints, rgb| {
                for p in ints {
                    for k in 0..3 {
                        lo[k] = lo[k].min(p[k]);
                        hi[k] = hi[k].max(p[k]);
                    }
                }
                if let Some(rgb) = rgb {
                    for c in rgb {
                        narrow &= c.iter().all(|&v| v <= 255);
                    }
                }
            })?;
            Ok((n, trs, has_colors))
        })
        .map_err(bad)?;
        let (mid, origin) = origin_of(lo, hi, &trs);
        Ok(LasStream {
            path: path.to_path_buf(),
            n,
            trs,
            mid,
            origin,
            colors: has_colors.then_some(narrow),
        })
    }

    /// The point count the header of the file at `path` claims, from its
    /// header alone (`None`: not a LAS/LAZ header): what deciding how to
    /// read a file needs; [`open`](Self::open) checks it.
    pub fn header_count(path: &std::path::Path) -> Option<u64> {
        let file = std::fs::File::open(path).ok()?;
        let head = read_at(&file, 0, 227)?;
        if !is_las(&head) {
            return None;
        }
        let legacy = u64::from(u32_at(&head, 107));
        let (major, minor) = (head[24], head[25]);
        if (major, minor) >= (1, 4) && u16_at(&head, 94) >= 375 {
            let b = read_at(&file, 247, 8)?;
            return Some(u64::from_le_bytes(b.try_into().ok()?).max(legacy));
        }
        Some(legacy)
    }

    /// Points in the file.
    pub fn len(&self) -> u64 {
        self.n
    }

    /// Whether the file has no points (never: [`open`](Self::open)
    /// refuses such a file).
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// Where the points' zero lies ([`LasCloud::origin`]).
    pub fn origin(&self) -> [f64; 3] {
        self.origin
    }

    /// Whether the points have colours.
    pub fn has_colors(&self) -> bool {
        self.colors.is_some()
    }

    /// Calls `f` with every point's position (relative to
    /// [`origin`](Self::origin), z-up as stored) and colour (RGBA8; zero
    /// without colours), in file order. Errors: I/O, a file that changed
    /// since it was opened.
    pub fn for_each(&self, mut f: impl FnMut(Vec3, [u8; 4])) -> crate::Result<()> {
        let bad = |e| crate::Error::parse(&self.path, e);
        let file = std::fs::File::open(&self.path).map_err(|e| crate::Error::io(&self.path, e))?;
        let len = file
            .metadata()
            .map_err(|e| crate::Error::io(&self.path, e))?
            .len();
        let data_start = read_at(&file, 96, 4).map_or(0, |b| u64::from(u32_at(&b, 0)));
        let narrow = self.colors.unwrap_or(true);
        drop(file);
        let file = std::fs::File::open(&self.path).map_err(|e| crate::Error::io(&self.path, e))?;
        quietly_caught(|| {
            let source = std::io::BufReader::with_capacity(1 << 20, file);
            let (mut reader, header, n, _) = open_reader(source, len, data_start)?;
            if n != self.n {
                return Err(parse_err!("the file changed while it was read"));
            }
            for_each_batch(&mut reader, &header, n, |ints, rgb| match rgb {
                Some(rgb) => {
                    for (p, c) in ints.zip(rgb) {
                        f(relative(p, &self.mid, &self.trs), to_rgba8(c, narrow));
                    }
                }
                None => {
                    for p in ints {
                        f(relative(p, &self.mid, &self.trs), [0; 4]);
                    }
                }
            })
        })
        .map_err(bad)
    }
}

/// The header's CRS as text: WKT when present, else `EPSG:n` from the
/// projected (or geodetic) GeoTIFF key; `None` when neither is there or
/// they do not parse.
#[cfg(not(target_arch = "wasm32"))]
fn crs_of(header: &las::Header) -> Option<String> {
    if let Some(wkt) = header.get_wkt_crs_bytes() {
        let text = String::from_utf8_lossy(wkt);
        let text = text.trim_end_matches('\0').trim();
        if !text.is_empty() {
            return Some(text.to_string());
        }
    }
    let geo = header.get_geotiff_crs().ok().flatten()?;
    geo.get_projected_crs_geo_key_value()
        .or_else(|| geo.get_geodetic_crs_geo_key_value())
        .filter(|&code| code != 0 && code != 32767)
        .map(|code| format!("EPSG:{code}"))
}

#[cfg(not(target_arch = "wasm32"))]
fn u16_at(b: &[u8], at: usize) -> u16 {
    b.get(at..at + 2)
        .map_or(0, |s| u16::from_le_bytes([s[0], s[1]]))
}

#[cfg(not(target_arch = "wasm32"))]
fn u32_at(b: &[u8], at: usize) -> u32 {
    b.get(at..at + 4)
        .map_or(0, |s| u32::from_le_bytes(s.try_into().unwrap_or([0; 4])))
}

/// Checks, on the raw bytes, the counts the `las`/`laz` decoders would
/// otherwise allocate from unchecked: the extended VLR's length and the
/// LAZ chunk count.
/// `n` bytes of `file` from `at` (`None`: past its end, or unreadable).
#[cfg(not(target_arch = "wasm32"))]
fn read_at(file: &std::fs::File, at: u64, n: usize) -> Option<Vec<u8>> {
    use std::io::{Read, Seek, SeekFrom};
    let mut f = file;
    f.seek(SeekFrom::Start(at)).ok()?;
    let mut b = vec![0u8; n];
    f.read_exact(&mut b).ok()?;
    Some(b)
}

#[cfg(not(target_arch = "wasm32"))]
fn precheck(bytes: &[u8]) -> Result<(), ParseError> {
    precheck_at(bytes.len() as u64, &|at, n| {
        let at = usize::try_from(at).ok()?;
        bytes.get(at..at.checked_add(n)?).map(<[u8]>::to_vec)
    })
}

/// [`precheck`] on a file of `len` bytes read through `at(offset, n)`
/// (`None`: past the end): the in-core reader passes its copy, the
/// stream reads the few bytes it needs from the file.
#[cfg(not(target_arch = "wasm32"))]
fn precheck_at(len: u64, at: &dyn Fn(u64, usize) -> Option<Vec<u8>>) -> Result<(), ParseError> {
    const MIN_HEADER: usize = 227;
    let head = at(0, 375)
        .or_else(|| at(0, len.min(375) as usize))
        .unwrap_or_default();
    if !is_las(&head) {
        return Err(parse_err!("not a LAS/LAZ file (no 'LASF' signature)"));
    }
    if head.len() < MIN_HEADER {
        return Err(parse_err!(
            "the file is {len} bytes, shorter than a LAS header ({MIN_HEADER} bytes)"
        ));
    }
    let u64_at = |o: u64| at(o, 8).map(|b| u64::from_le_bytes(b.try_into().unwrap_or([0; 8])));
    let (major, minor) = (head[24], head[25]);
    let header_size = u16_at(&head, 94);
    // LAS 1.4: start of the first extended VLR (u64 at 235), their count
    // (u32 at 243); the decoder reads the first one and sizes its data
    // from a u64 length 20 bytes into it.
    if (major, minor) >= (1, 4) && header_size >= 375 && len >= 247 {
        let start = u64_at(235).unwrap_or(0);
        let count = u32_at(&head, 243);
        if count > 0 {
            let length = start.checked_add(20).and_then(u64_at).ok_or_else(|| {
                parse_err!("extended VLR at byte {start} lies past the end of the file")
            })?;
            if length > len.saturating_sub(start.saturating_add(60)) {
                return Err(parse_err!(
                    "extended VLR at byte {start} claims {length} bytes, more than the file holds"
                ));
            }
        }
    }
    // LAZ (point format with bit 7 or 6 set): the chunk table's offset is
    // the first 8 bytes of point data (-1: in the file's last 8 bytes).
    let format_byte = head[104];
    if format_byte & 0xC0 != 0 {
        let data_start = u64::from(u32_at(&head, 96));
        let mut table = u64_at(data_start).unwrap_or(0);
        if table == u64::MAX {
            table = u64_at(len.saturating_sub(8)).unwrap_or(0);
        }
        if table > data_start && table.saturating_add(8) <= len {
            let chunks = at(table + 4, 4).map_or(0, |b| u64::from(u32_at(&b, 0)));
            let most = (table - data_start) / 20 + 1;
            if chunks > most {
                return Err(parse_err!(
                    "LAZ chunk table claims {chunks} chunks in {} bytes of point data",
                    table - data_start
                ));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn short_and_foreign_bytes_are_one_line_errors() {
        for (bytes, want) in [
            (&b"ply\n"[..], "no 'LASF'"),
            (&b"LASF"[..], "shorter than a LAS header"),
        ] {
            let e = read(bytes).unwrap_err().0;
            assert!(e.contains(want) && !e.contains('\n'), "{e}");
        }
    }
}
