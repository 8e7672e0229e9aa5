//! File formats: detection, loading and atomic saving.
//!
//! Every reader takes the whole file as bytes (`&[u8]`) and returns a
//! [`ParseError`] on bad input; [`load`] attaches the path. No reader
//! allocates from an unchecked header count: counts are first checked
//! against the bytes that remain. Every writer produces bytes that
//! [`write_atomic`] puts in place with a temp file + rename, so a failed run
//! never leaves a half-written file, and the same model always produces the
//! same bytes.
//!
//! # Entry points
//!
//! - [`load`] / [`load_mesh`]: a file → [`Model`] / [`TriMesh`]. The format
//!   comes from the extension ([`Format::from_path`]); files over
//!   [`MAX_FILE_BYTES`] and anything that is not a regular file (a
//!   directory, FIFO or device) are refused before reading
//!   ([`input::read_file`], the one door of every path-based read). Errors
//!   name the file and what is wrong, on one line ([`Error`]). Cost: one
//!   read of the file plus one linear decode; memory: the file's bytes plus
//!   the model.
//! - [`decode`]: bytes of a known format → [`Model`] (what `load` does after
//!   reading; no file system access except external glTF buffers beside
//!   `base_dir`). Guarantees on any input: no panic, no allocation sized by
//!   an unchecked count, and the result passes [`TriMesh::validate`].
//! - [`save`] / [`save_mesh`]: a model → a file, atomically via
//!   [`write_atomic`] (temp file, `fsync`, rename): on error the old file
//!   is untouched and no temp file stays. [`encode`] gives the bytes.
//!   Deterministic: the same model and options give the same bytes.
//! - [`load_located`] / [`decode_located`]: the same, plus where the
//!   positions' zero lies in the file's own coordinates ([`Located`]):
//!   LAS/LAZ positions are stored relative to an `f64` origin so that
//!   `f32` keeps them exact; every other format's origin is `None`.
//! - One module per format (`ply`, `obj`, `stl`, `gltf`, `xyz`, `conf`,
//!   `las`, `cameras`; those other crates call by name are public), each documenting what it reads, what it writes and its
//!   conventions (units are never converted; UV origin and colour space are).

pub mod cameras;
pub mod conf;
pub mod gltf;
pub mod input;
pub mod interrupt;
mod las;
#[cfg(not(target_arch = "wasm32"))]
pub use las::LasStream;
pub mod mtl;
mod obj;
// Output folders live on a file system with signals: not in the browser.
#[cfg(not(target_arch = "wasm32"))]
pub mod out_folder;
pub mod overwrite_guard;
pub mod ply;
mod scene_io;
mod stl;
pub mod stl_stream;
mod xyz;

pub use scene_io::{has_materials, load_scene, ply_scene, save_scene, save_scene_with};

#[cfg(not(target_arch = "wasm32"))]
use std::io::Write;
use std::path::Path;

use crate::error::{Error, ParseError, Result};
use crate::mesh::{Model, PointCloud, TriMesh};

/// The formats lodkit reads and writes, chosen by file extension.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Format {
    /// Stanford PLY (`.ply`): meshes, point clouds and range grids.
    Ply,
    /// Wavefront OBJ (`.obj`): meshes.
    Obj,
    /// STL (`.stl`), binary or ASCII: meshes.
    Stl,
    /// glTF 2.0 JSON (`.gltf`, buffers embedded as data URIs or beside it).
    Gltf,
    /// Binary glTF 2.0 (`.glb`).
    Glb,
    /// `x y z [nx ny nz] [r g b]` text points (`.xyz`).
    Xyz,
    /// Leica-style `.pts`: optional count line, then `x y z [intensity] [r g b]`.
    Pts,
    /// ASPRS LAS (`.las`) or LAZ (`.laz`): point clouds, read only.
    Las,
}

impl Format {
    /// The format of a path's extension (case-insensitive; `.txt` reads as
    /// XYZ); `None` for an unknown or missing extension.
    pub fn from_path(path: &Path) -> Option<Format> {
        let ext = path.extension()?.to_str()?.to_ascii_lowercase();
        Some(match ext.as_str() {
            "ply" => Format::Ply,
            "obj" => Format::Obj,
            "stl" => Format::Stl,
            "gltf" => Format::Gltf,
            "glb" => Format::Glb,
            "xyz" | "txt" => Format::Xyz,
            "pts" => Format::Pts,
            "las" | "laz" => Format::Las,
            _ => return None,
        })
    }
    /// The format's short name, for messages (`"PLY"`, `"glTF"`, …).
    pub fn name(self) -> &'static str {
        match self {
            Format::Ply => "PLY",
            Format::Obj => "OBJ",
            Format::Stl => "STL",
            Format::Gltf => "glTF",
            Format::Glb => "GLB",
            Format::Xyz => "XYZ",
            Format::Pts => "PTS",
            Format::Las => "LAS",
        }
    }
}

/// Options for writing; the defaults are what `lodkit convert` uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct WriteOptions {
    /// PLY and STL: binary (default) or ASCII.
    pub ascii: bool,
}

impl WriteOptions {
    /// The defaults: binary.
    pub const DEFAULT: WriteOptions = WriteOptions { ascii: false };
}

impl Default for WriteOptions {
    fn default() -> Self {
        WriteOptions::DEFAULT
    }
}

/// Files larger than this (16 GiB) are refused before reading, and no read
/// goes past it (a guard against a runaway file filling memory); files
/// that are not regular files are refused outright ([`input::read_file`]).
pub const MAX_FILE_BYTES: u64 = 16 << 30;

/// Reads a geometry file of any supported format.
pub fn load(path: &Path) -> Result<Model> {
    let format = Format::from_path(path).ok_or_else(|| {
        Error::unsupported(
            path,
            "unknown file extension (expected .ply, .obj, .stl, .gltf, .glb, .xyz, .pts, .las or .laz)",
        )
    })?;
    let bytes = input::read_file(path)?;
    decode(format, &bytes, path.parent()).map_err(|e| Error::parse(path, e))
}

/// A decoded model and where its zero lies in the file's own coordinates.
#[derive(Debug, Clone, PartialEq)]
pub struct Located {
    /// The model; its positions are relative to `origin` when that is set.
    pub model: Model,
    /// The `f64` point, in the file's coordinates and units, that the
    /// model's positions are relative to: set by the LAS/LAZ reader
    /// (LAS/LAZ), `None` for every format whose positions are the file's
    /// own.
    pub origin: Option<[f64; 3]>,
    /// The coordinate reference system the file names (LAS/LAZ: WKT or
    /// `EPSG:n`), when it names one.
    pub crs: Option<String>,
}

/// [`load`], keeping the origin and CRS a file gives ([`Located`]).
/// Errors and cost as [`load`].
pub fn load_located(path: &Path) -> Result<Located> {
    let format = Format::from_path(path).ok_or_else(|| {
        Error::unsupported(
            path,
            "unknown file extension (expected .ply, .obj, .stl, .gltf, .glb, .xyz, .pts, .las or .laz)",
        )
    })?;
    let bytes = input::read_file(path)?;
    decode_located(format, &bytes, path.parent()).map_err(|e| Error::parse(path, e))
}

/// [`decode`], keeping the origin and CRS a file gives ([`Located`]).
/// Guarantees as [`decode`].
pub fn decode_located(
    format: Format,
    bytes: &[u8],
    base_dir: Option<&Path>,
) -> Result<Located, ParseError> {
    if format == Format::Las {
        let l = las::read(bytes)?;
        let model = Model::Points(l.cloud);
        check_decoded(&model)?;
        return Ok(Located {
            model,
            origin: Some(l.origin),
            crs: l.crs,
        });
    }
    Ok(Located {
        model: decode(format, bytes, base_dir)?,
        origin: None,
        crs: None,
    })
}

/// Decodes bytes of a known format. `base_dir` resolves external glTF
/// buffers; `None` refuses them. A LAS/LAZ cloud comes back relative to
/// its origin, which this drops ([`decode_located`] keeps it).
pub fn decode(format: Format, bytes: &[u8], base_dir: Option<&Path>) -> Result<Model, ParseError> {
    let model = match format {
        Format::Ply => ply::read(bytes)?,
        Format::Obj => Model::Mesh(obj::read(bytes)?),
        Format::Stl => Model::Mesh(stl::read(bytes)?),
        Format::Gltf | Format::Glb => gltf::read_model(bytes, base_dir)?,
        Format::Xyz => Model::Points(xyz::read_xyz(bytes)?),
        Format::Pts => Model::Points(xyz::read_pts(bytes)?),
        Format::Las => Model::Points(las::read(bytes)?.cloud),
    };
    check_decoded(&model)?;
    Ok(model)
}

/// What every decoded model passes: its `validate()` and
/// [`check_coordinates`].
fn check_decoded(model: &Model) -> Result<(), ParseError> {
    match model {
        Model::Mesh(m) => m.validate()?,
        Model::Points(p) => p.validate()?,
        Model::Range(r) => r.validate()?,
    }
    check_coordinates(model)
}

/// The largest coordinate magnitude lodkit reads or writes: `1e18`.
///
/// Why this bound: every stage measures squared distances in `f32`. With
/// all coordinates within ±`MAX_COORDINATE`, a squared distance between
/// two points is at most `3 · (2e18)² = 1.2e37`, well inside `f32`'s
/// `3.4e38`, so no distance, bounding-box diagonal or error overflows to
/// infinity or reads back as zero. Beyond it (about `1.8e19` a single
/// squared coordinate overflows) results would be silently wrong, so
/// every reader refuses such a file with one line ([`decode`]), every
/// writer refuses to write one ([`check_readable`]), and a `.conf` pose
/// may not translate past it. Small magnitudes are not bounded: the
/// stages that depend on scale (particle sampling, simplification error)
/// work in a frame normalised to the model's extent.
pub const MAX_COORDINATE: f32 = 1e18;

/// Refuses a model with a coordinate beyond ±[`MAX_COORDINATE`] (the
/// first one found, by index). Non-finite values are `validate()`'s job
/// and are refused there first. Cost: one pass over the positions.
pub fn check_coordinates(model: &Model) -> Result<(), ParseError> {
    let (what, first) = match model {
        Model::Mesh(m) => ("vertex", first_out_of_range(&m.positions)),
        Model::Points(p) => ("point", first_out_of_range(&p.positions)),
        Model::Range(r) => (
            "range point",
            r.points
                .iter()
                .zip(&r.valid)
                .position(|(p, &ok)| ok && !within_range(*p)),
        ),
    };
    let positions = match model {
        Model::Mesh(m) => &m.positions,
        Model::Points(p) => &p.positions,
        Model::Range(r) => &r.points,
    };
    match first {
        None => Ok(()),
        Some(i) => {
            let p = positions[i];
            Err(crate::parse_err!(
                "{what} {i} ({:e} {:e} {:e}) is beyond the supported coordinate range of \
                 ±{MAX_COORDINATE:e} (squared distances would overflow 32-bit floats)",
                p.x,
                p.y,
                p.z
            ))
        }
    }
}

/// Opens `path` for a streaming reader: the file, its length, and its
/// first `max` bytes (fewer in a shorter file), read from the start (the
/// file is left after them). Errors: I/O, naming the path.
pub(crate) fn open_head(path: &Path, max: u64) -> Result<(std::fs::File, u64, Vec<u8>)> {
    use std::io::Read;
    let io = |e| Error::io(path, e);
    let mut f = std::fs::File::open(path).map_err(io)?;
    let meta = f.metadata().map_err(io)?;
    overwrite_guard::note(&meta);
    let len = meta.len();
    let mut head = Vec::with_capacity(max.min(1 << 16) as usize);
    (&mut f).take(max).read_to_end(&mut head).map_err(io)?;
    Ok((f, len, head))
}

fn within_range(p: glam::Vec3) -> bool {
    p.abs().max_element() <= MAX_COORDINATE
}

fn first_out_of_range(points: &[glam::Vec3]) -> Option<usize> {
    points.iter().position(|p| !within_range(*p))
}

/// Reads a file that must hold a triangle mesh.
pub fn load_mesh(path: &Path) -> Result<TriMesh> {
    match load(path)? {
        Model::Mesh(m) => Ok(m),
        other => Err(Error::unsupported(
            path,
            format!("holds a {} with no faces, a mesh is needed", other.kind()),
        )),
    }
}

/// Encodes a model in `format`. Point clouds and range images written to a
/// mesh-only format are refused with a clear message.
///
/// lodkit reads back everything it writes: a model that [`decode`] would
/// refuse in `format` is refused here instead ([`check_readable`]).
pub fn encode(format: Format, model: &Model, opts: WriteOptions) -> Result<Vec<u8>, ParseError> {
    check_readable(format, model)?;
    let mut out = Vec::new();
    match (format, model) {
        (Format::Ply, Model::Mesh(m)) => ply::write_mesh(&mut out, m, opts.ascii),
        (Format::Ply, Model::Points(p)) => ply::write_points(&mut out, p, opts.ascii),
        (Format::Ply, Model::Range(r)) => {
            ply::write_points(&mut out, &r.to_point_cloud(), opts.ascii)
        }
        (Format::Obj, Model::Mesh(m)) => obj::write(&mut out, m),
        (Format::Stl, Model::Mesh(m)) => stl::write(&mut out, m, opts.ascii),
        (Format::Glb, m) => {
            out = gltf::write_model_glb(m, &gltf::GlbOptions::default())?;
            Ok(())
        }
        (Format::Xyz, m) => xyz::write_xyz(&mut out, &as_points(m)),
        (Format::Pts, m) => xyz::write_pts(&mut out, &as_points(m)),
        (Format::Gltf, _) => {
            return Err(ParseError::new(
                "writing .gltf is not supported; write .glb",
            ));
        }
        (Format::Las, _) => {
            return Err(ParseError::new(
                "writing LAS/LAZ is not supported; write .ply, .xyz, .pts or .glb",
            ));
        }
        (f, m) => {
            return Err(crate::parse_err!(
                "cannot write a {} as {}: the format holds meshes only",
                m.kind(),
                f.name()
            ));
        }
    }
    .map_err(|e| ParseError(e.to_string()))?;
    Ok(out)
}

/// Refuses to write what the reader of `format` would refuse to read back:
/// a model that fails its `validate()` (non-finite values, a face index out
/// of range or repeated) or has a coordinate beyond [`MAX_COORDINATE`]
/// ([`check_coordinates`]); no faces in a mesh-only format (OBJ, STL, GLB
/// readers refuse a file without triangles); in STL, no triangle with three
/// distinct corners (STL stores corners, not indices, and its reader drops
/// triangles whose corners coincide); no points in XYZ/PTS (an empty file is
/// not a point cloud). Cost: one pass over the faces.
pub fn check_readable(format: Format, model: &Model) -> Result<(), ParseError> {
    let refuse = |why: String| {
        Err(crate::parse_err!(
            "cannot write this {} as {}: {why}, so the file could not be read back",
            model.kind(),
            format.name()
        ))
    };
    match model {
        Model::Mesh(m) => m.validate()?,
        Model::Points(p) => p.validate()?,
        Model::Range(r) => r.validate()?,
    }
    check_coordinates(model)?;
    match (format, model) {
        (Format::Obj | Format::Stl | Format::Glb, Model::Mesh(m)) if m.faces.is_empty() => {
            refuse("it has no faces".into())
        }
        (Format::Stl, Model::Mesh(m)) => {
            // The STL reader welds bitwise-equal corners (`-0 == 0`).
            let key = |v: glam::Vec3| (v + glam::Vec3::ZERO).to_array().map(f32::to_bits);
            let proper = m.faces.iter().any(|f| {
                let [a, b, c] = f.map(|i| key(m.positions[i as usize]));
                a != b && b != c && a != c
            });
            if proper {
                Ok(())
            } else {
                refuse("every triangle has coincident corners".into())
            }
        }
        (Format::Xyz | Format::Pts | Format::Glb, m) => {
            let n = match m {
                Model::Mesh(m) => m.positions.len(),
                Model::Points(p) => p.positions.len(),
                Model::Range(r) => r.valid_count(),
            };
            if n == 0 {
                refuse("it has no points".into())
            } else {
                Ok(())
            }
        }
        _ => Ok(()),
    }
}

fn as_points(m: &Model) -> PointCloud {
    match m {
        Model::Mesh(m) => PointCloud {
            positions: m.positions.clone(),
            normals: m.normals.clone(),
            colors: m.colors.clone(),
        },
        Model::Points(p) => p.clone(),
        Model::Range(r) => r.to_point_cloud(),
    }
}

/// Writes a model to `path` (format from the extension), atomically.
pub fn save(path: &Path, model: &Model, opts: WriteOptions) -> Result<()> {
    let format = Format::from_path(path).ok_or_else(|| {
        Error::unsupported(
            path,
            "unknown output extension (expected .ply, .obj, .stl, .glb, .xyz or .pts)",
        )
    })?;
    let bytes = encode(format, model, opts).map_err(|e| Error::unsupported(path, e.0))?;
    write_atomic(path, &bytes)
}

/// Writes a mesh to `path`, atomically.
pub fn save_mesh(path: &Path, mesh: &TriMesh, opts: WriteOptions) -> Result<()> {
    save(path, &Model::Mesh(mesh.clone()), opts)
}

/// On `wasm32` there is no file system to write to (the browser build
/// only reads bytes it is given): every write is refused with one line.
#[cfg(target_arch = "wasm32")]
pub fn write_atomic(path: &Path, _bytes: &[u8]) -> Result<()> {
    Err(Error::unsupported(
        path,
        "writing files is not available on wasm32",
    ))
}

/// On `wasm32` there is no file system to write to: refused with one line.
#[cfg(target_arch = "wasm32")]
pub fn write_atomic_with(
    path: &Path,
    _write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<()> {
    write_atomic(path, &[])
}

/// Writes `bytes` to a temp file beside `path`, syncs it and renames it
/// over `path`: readers see either the old file or the whole new one.
///
/// The temp file is created exclusively (`O_EXCL`) under an unpredictable
/// name in `path`'s folder (the `tempfile` crate), so it never follows or
/// overwrites a file or symlink someone else planted. The rename replaces
/// `path` itself: if `path` is a symlink, the link is replaced, never the
/// file it points to. An existing regular file's permissions are kept; a
/// new file gets the usual `0666` minus the umask. On any error (and when
/// the temp file is dropped) the temp file is removed, so a failed write
/// leaves the old file untouched and nothing else. A signal runs no
/// destructor: in a process that called
/// [`interrupt::remove_temp_files_on_signal`] (the CLI does), SIGINT,
/// SIGTERM and SIGHUP remove the temp file before the process dies;
/// otherwise it (`.NAME.XXXXXX.tmp`) stays behind. NAME is shortened
/// ([`fit_name`]) when the temp name would pass [`NAME_MAX`], so any
/// legal output name can be written. In a process that called
/// [`overwrite_guard::refuse_overwriting_inputs`] (the CLI does), a `path`
/// whose file was read as an input is refused before anything is written.
#[cfg(not(target_arch = "wasm32"))]
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    write_atomic_with(path, |f| f.write_all(bytes))
}

/// [`write_atomic`] for output produced piece by piece: `write` fills the
/// temp file (it need not flush or sync), then it is synced and renamed
/// over `path`, with every guarantee of [`write_atomic`].
#[cfg(not(target_arch = "wasm32"))]
pub fn write_atomic_with(
    path: &Path,
    write: impl FnOnce(&mut std::fs::File) -> std::io::Result<()>,
) -> Result<()> {
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| Error::unsupported(path, "output path has no file name"))?;
    overwrite_guard::check(path)?;
    let kept = std::fs::symlink_metadata(path)
        .ok()
        .filter(|m| m.is_file())
        .map(|m| m.permissions());
    // `.NAME.XXXXXX.tmp`, NAME shortened when the whole would pass
    // NAME_MAX (a legal 250-byte output name must still be writable).
    let prefix = format!(".{}.", fit_name(&name.to_string_lossy(), 12));
    let mut builder = tempfile::Builder::new();
    builder.prefix(&prefix).suffix(".tmp");
    #[cfg(unix)]
    let default_mode = {
        use std::os::unix::fs::PermissionsExt as _;
        // Applied at creation, so the umask still applies, as with
        // `File::create`.
        std::fs::Permissions::from_mode(0o666)
    };
    #[cfg(unix)]
    builder.permissions(default_mode);
    let result = (|| {
        let mut tmp = builder.tempfile_in(dir)?;
        // Listed until renamed or removed (declared after `tmp`, so it is
        // dropped first: delisted before `tmp` removes the file).
        let _pending = interrupt::Pending::new(tmp.path());
        write(tmp.as_file_mut())?;
        if let Some(perms) = kept {
            tmp.as_file().set_permissions(perms)?;
        }
        tmp.as_file().sync_all()?;
        tmp.persist(path).map_err(|e| e.error)?;
        Ok(())
    })();
    result.map_err(|e: std::io::Error| Error::io(path, e))
}

/// The longest file name most file systems allow, in bytes (Linux's
/// `NAME_MAX`; also the limit of APFS, NTFS and ext4).
pub const NAME_MAX: usize = 255;

/// `name`, shortened so that `extra` more bytes still fit in
/// [`NAME_MAX`]: unchanged when it fits; else cut at a character boundary
/// and ended with `~` and 16 hex digits of a hash of the whole name, so two
/// long names that share a beginning still give different results. What
/// temporary and staging names beside an output are built from. Cost:
/// linear in the name.
pub fn fit_name(name: &str, extra: usize) -> String {
    let room = NAME_MAX.saturating_sub(extra);
    if name.len() <= room {
        return name.to_string();
    }
    // FNV-1a, 64 bits: stable between runs and builds.
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for &b in name.as_bytes() {
        h ^= b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    let tail = format!("~{h:016x}");
    let mut cut = room.saturating_sub(tail.len());
    while !name.is_char_boundary(cut) {
        cut -= 1;
    }
    format!("{}{tail}", &name[..cut])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::shapes;

    /// An output name of 250 bytes (legal) is written: its temp name is
    /// shortened to fit NAME_MAX; names that fit are kept as they are.
    #[test]
    fn a_name_near_name_max_is_written_and_temp_names_fit() {
        let dir = tempfile::tempdir().unwrap();
        let long = format!("{}.ply", "é".repeat(121)); // 246 bytes
        let path = dir.path().join(&long);
        save_mesh(&path, &shapes::icosphere(0), WriteOptions::default()).unwrap();
        assert_eq!(names(dir.path()), std::slice::from_ref(&long));
        assert_eq!(load_mesh(&path).unwrap().faces.len(), 20);
        let path = dir.path().join(format!("{}.ply", "a".repeat(247)));
        save_mesh(&path, &shapes::icosphere(0), WriteOptions::default()).unwrap();
        for n in [long.as_str(), "m.ply", &"b".repeat(255)] {
            let f = fit_name(n, 12);
            assert!(f.len() + 12 <= NAME_MAX, "{f}");
            if n.len() + 12 <= NAME_MAX {
                assert_eq!(f, n);
            }
        }
        assert_ne!(
            fit_name(&format!("{}1", "a".repeat(300)), 32),
            fit_name(&format!("{}2", "a".repeat(300)), 32)
        );
    }

    fn names(dir: &Path) -> Vec<String> {
        let mut v: Vec<String> = std::fs::read_dir(dir)
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        v.sort();
        v
    }

    #[test]
    fn save_replaces_the_target_whole_and_leaves_no_temp_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("m.ply");
        std::fs::write(&path, b"old contents").unwrap();
        save_mesh(&path, &shapes::icosphere(1), WriteOptions::default()).unwrap();
        assert_eq!(names(dir.path()), ["m.ply"]);
        let back = load_mesh(&path).unwrap();
        assert_eq!(back.faces.len(), 80);
    }

    #[test]
    fn a_failed_save_leaves_the_old_file_and_nothing_else() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("cloud.stl");
        std::fs::write(&path, b"old contents").unwrap();
        let cloud = Model::Points(PointCloud {
            positions: vec![glam::Vec3::ZERO],
            ..Default::default()
        });
        let err = save(&path, &cloud, WriteOptions::default())
            .unwrap_err()
            .to_string();
        assert!(
            err.contains("cloud.stl") && err.contains("meshes only"),
            "{err}"
        );
        assert_eq!(std::fs::read(&path).unwrap(), b"old contents");
        assert_eq!(names(dir.path()), ["cloud.stl"]);
        // A missing directory is an I/O error naming the path, not a panic.
        let missing = dir.path().join("no/such/dir/m.ply");
        let err = save_mesh(&missing, &shapes::icosphere(0), WriteOptions::default()).unwrap_err();
        assert!(err.to_string().contains("no/such/dir/m.ply"), "{err}");
    }

    /// Coordinates beyond ±MAX_COORDINATE are refused on read and on write,
    /// in every format; within it (1e-10 to 1e15 scales) they read back.
    #[test]
    fn coordinates_beyond_the_stated_range_are_refused_both_ways() {
        let scaled = |k: f32| {
            let mut m = shapes::icosphere(1);
            m.positions.iter_mut().for_each(|p| *p *= k);
            Model::Mesh(m)
        };
        for f in [
            Format::Ply,
            Format::Obj,
            Format::Stl,
            Format::Glb,
            Format::Xyz,
        ] {
            for k in [1e-10, 1.0, 1e15] {
                let bytes = encode(f, &scaled(k), WriteOptions::default()).unwrap();
                assert!(decode(f, &bytes, None).is_ok(), "{f:?} at {k}");
            }
            let e = encode(f, &scaled(1e19), WriteOptions::default())
                .unwrap_err()
                .0;
            assert!(
                e.contains("beyond the supported coordinate range of ±1e18"),
                "{e}"
            );
        }
        let text = b"v 0 0 0\nv 1 0 0\nv 0 2e18 0\nf 1 2 3\n";
        let e = decode(Format::Obj, text, None).unwrap_err().0;
        assert!(
            e.contains("vertex 2 (0e0 2e18 0e0) is beyond the supported coordinate range"),
            "{e}"
        );
        let e = decode(Format::Xyz, b"0 0 0\n1e30 0 0\n", None)
            .unwrap_err()
            .0;
        assert!(e.contains("point 1 (1e30 0e0 0e0)"), "{e}");
    }

    #[test]
    fn same_model_same_bytes_in_every_format() {
        let m = Model::Mesh(shapes::torus(1.0, 0.3, 12, 8));
        for f in [
            Format::Ply,
            Format::Obj,
            Format::Stl,
            Format::Glb,
            Format::Xyz,
            Format::Pts,
        ] {
            for ascii in [false, true] {
                let a = encode(f, &m, WriteOptions { ascii }).unwrap();
                let b = encode(f, &m, WriteOptions { ascii }).unwrap();
                assert_eq!(a, b, "{f:?}");
            }
        }
    }
}
