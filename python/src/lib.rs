//! `pylodkit._lodkit`: the native half of the `pylodkit` Python package
//! (the pure-Python half, `python/pylodkit/`, wraps it in `Mesh` /
//! `PointCloud` classes, checks option ranges and documents each call).
//!
//! Contract of every function here:
//! - **Inputs** are numpy arrays read in place (see [`convert`]), or paths
//!   for the library's jobs on files ([`jobs`]); options arrive already
//!   range-checked by the Python layer against `LIMITS`, with the defaults
//!   of `DEFAULTS` (both read from `lodkit::limits` and the engines'
//!   option types, as the CLI reads them).
//! - **The GIL is released** (`Python::detach`) around every computation:
//!   file reading and writing, simplification, measurement, builds, cuts,
//!   encoding, decoding. Other Python threads run meanwhile.
//! - **Errors** are `pylodkit.errors` exceptions carrying the crates' one
//!   line ([`errors`]): what the CLI prints, without the file name when
//!   there is no file.
//! - Only the crates' public APIs are used (no dependency on the CLI).
//! - **Progress**: the jobs on files take `progress`, a function called
//!   with each of the job's events as a dict ([`progress`]).

use std::path::PathBuf;

use lodkit_mesh::io::WriteOptions;
use lodkit_mesh::metrics::{CompareOptions, Reference};
use lodkit_simplify::{AttributeWeights, LevelReport, Options, Simplifier, Target};
use pyo3::prelude::*;
use pyo3::types::PyDict;

mod convert;
mod errors;
mod jobs;
mod mco;
mod pop;
mod progress;
mod scale;
mod tiles;

use convert::{json_to_py, mesh_from_py, mesh_to_py, model_from_py, model_to_py};
use errors::input;

use lodkit::limits;
use lodkit::measure::Sampling;

/// `load(path) -> (kind, dict)`: any file lodkit reads (format by
/// extension); kind is `"mesh"` or `"points"`.
#[pyfunction]
fn load<'py>(py: Python<'py>, path: PathBuf) -> PyResult<(Bound<'py, PyAny>, Bound<'py, PyDict>)> {
    let model = py
        .detach(|| lodkit_mesh::io::load(&path))
        .map_err(errors::mesh)?;
    let (k, d) = model_to_py(py, model)?;
    Ok((k.into_any(), d))
}

/// `save(obj, path, ascii)`: a mesh or points, atomically (format by
/// extension, as `lodkit convert` writes it).
#[pyfunction]
#[pyo3(signature = (obj, path, ascii = false))]
fn save(py: Python<'_>, obj: &Bound<'_, PyAny>, path: PathBuf, ascii: bool) -> PyResult<()> {
    let model = model_from_py(obj)?;
    py.detach(|| lodkit_mesh::io::save(&path, &model, WriteOptions { ascii }))
        .map_err(errors::mesh)
}

/// `bunny() -> dict`: the Stanford bunny (35,947 vertices, 69,451 faces).
#[pyfunction]
fn bunny(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let m = py
        .detach(lodkit::input::builtin_bunny)
        .map_err(|e| input(e.to_string()))?;
    mesh_to_py(py, m)
}

/// `blob(triangles, seed) -> dict`: lodkit's noise-displaced sphere of
/// about `triangles` faces (closed, genus 0; the benchmarks' large mesh).
#[pyfunction]
#[pyo3(signature = (triangles, seed = lodkit_mesh::shapes::DEFAULT_NOISE_SEED))]
fn blob(py: Python<'_>, triangles: usize, seed: u32) -> PyResult<Bound<'_, PyDict>> {
    let m = py.detach(|| lodkit_mesh::shapes::blob_with_seed(triangles, seed));
    mesh_to_py(py, m)
}

/// `icosphere(level) -> dict`: 20 × 4^level faces on the unit sphere.
#[pyfunction]
fn icosphere(py: Python<'_>, level: u32) -> PyResult<Bound<'_, PyDict>> {
    let m = py.detach(|| lodkit_mesh::shapes::icosphere(level));
    mesh_to_py(py, m)
}

/// `write_atomic(path, data)`: lodkit's atomic write (temporary file
/// beside the target, fsync, rename).
#[pyfunction]
fn write_atomic(py: Python<'_>, path: PathBuf, data: &[u8]) -> PyResult<()> {
    py.detach(|| lodkit_mesh::io::write_atomic(&path, data))
        .map_err(errors::mesh)
}

/// One level of [`write_lod_glb`]: `(mesh, lod, measured, estimated)`.
type GlbLevelArgs<'py> = (Bound<'py, PyAny>, usize, Option<(f64, f64)>, f64);

/// `write_lod_glb(path, stem, levels)`: an LOD chain as one GLB, as
/// `lodkit lods` writes `STEM_lods.glb` (`lodkit::lod_chain::chain_glb`:
/// the same nodes, extras, coverages and normals), written atomically.
/// `levels`: `(mesh, lod, measured, estimated)` per level, level 0 (the
/// input, measured `(0, 0)`) first; `measured` is the level's `(mean,
/// max)` distance to the input or `None`, `estimated` the simplifier's
/// estimate, both in object units.
#[pyfunction]
fn write_lod_glb(
    py: Python<'_>,
    path: PathBuf,
    stem: String,
    levels: Vec<GlbLevelArgs<'_>>,
) -> PyResult<()> {
    let mut meshes = Vec::with_capacity(levels.len());
    let mut rest = Vec::with_capacity(levels.len());
    for (mesh, lod, measured, estimated) in &levels {
        meshes.push(mesh_from_py(mesh)?);
        rest.push((*lod, *measured, *estimated));
    }
    py.detach(|| -> Result<(), lodkit_mesh::Error> {
        let diagonal = meshes.first().map_or(0.0, |m| m.bbox().diagonal() as f64);
        let glb_levels: Vec<lodkit::lod_chain::GlbLevel> = rest
            .iter()
            .zip(&meshes)
            .map(
                |(&(lod, measured, estimated), mesh)| lodkit::lod_chain::GlbLevel {
                    lod,
                    mesh,
                    measured,
                    estimated,
                },
            )
            .collect();
        let bytes = lodkit::lod_chain::chain_glb(
            &stem,
            &glb_levels,
            diagonal,
            &lodkit::output::OutputOptions::default(),
        )
        .map_err(|e| lodkit_mesh::Error::parse(&path, e))?;
        lodkit_mesh::io::write_atomic(&path, &bytes)
    })
    .map_err(errors::mesh)
}

/// The simplifier options, from the Python keywords (CLI defaults).
#[allow(clippy::too_many_arguments)]
pub(crate) fn options(
    target: Target,
    max_error: Option<f32>,
    lock_border: bool,
    fill_holes: bool,
    heap_size: usize,
    normal_weight: f32,
    color_weight: f32,
    uv_weight: f32,
    prune: Option<f32>,
) -> Options {
    Options {
        target,
        max_error,
        lock_border,
        fill_holes,
        heap_size,
        weights: AttributeWeights {
            normal: normal_weight,
            color: color_weight,
            uv: uv_weight,
        },
        prune,
        ..Options::DEFAULT
    }
}

/// The target from `target` / `ratio` / `max_error`, as `lodkit
/// simplify` resolves it (error alone: no face budget).
fn target_of(
    target: Option<usize>,
    ratio: Option<f32>,
    max_error: Option<f32>,
) -> PyResult<Target> {
    Ok(match (target, ratio) {
        (Some(n), _) => Target::Faces(n),
        (None, Some(r)) => Target::Ratio(r),
        (None, None) if max_error.is_some() => Target::Faces(0),
        (None, None) => {
            return Err(crate::errors::input(
                "give target=FACES, ratio=R or max_error=E",
            ));
        }
    })
}

/// `lodkit simplify --json`'s report fields (no paths).
fn report_dict<'py>(
    py: Python<'py>,
    input_faces: usize,
    r: &LevelReport,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("input_triangles", input_faces)?;
    d.set_item("target_triangles", r.target_faces)?;
    d.set_item("triangles", r.triangles)?;
    d.set_item("vertices", r.vertices)?;
    d.set_item("estimated_error", r.estimated_error)?;
    d.set_item("passes", r.passes)?;
    d.set_item("collapses", r.collapses)?;
    d.set_item("stop", r.stop.to_string())?;
    d.set_item("chain_end", r.chain_end.map(|s| s.to_string()))?;
    d.set_item("seconds", r.seconds)?;
    Ok(d)
}

/// `simplify(mesh, ...) -> (dict, report)`: one mesh to one budget, by
/// the library's in-core step (`lodkit::simplify::simplify_mesh`).
#[pyfunction]
#[pyo3(signature = (mesh, target = None, ratio = None, max_error = None, lock_border = false,
    fill_holes = true, heap_size = Options::DEFAULT_HEAP_SIZE,
    normal_weight = AttributeWeights::DEFAULT.normal, color_weight = AttributeWeights::DEFAULT.color,
    uv_weight = AttributeWeights::DEFAULT.uv, prune = None, progress = None))]
#[allow(clippy::too_many_arguments)]
fn simplify<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    target: Option<usize>,
    ratio: Option<f32>,
    max_error: Option<f32>,
    lock_border: bool,
    fill_holes: bool,
    heap_size: usize,
    normal_weight: f32,
    color_weight: f32,
    uv_weight: f32,
    prune: Option<f32>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<(Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    let m = mesh_from_py(mesh)?;
    let opts = options(
        target_of(target, ratio, max_error)?,
        max_error,
        lock_border,
        fill_holes,
        heap_size,
        normal_weight,
        color_weight,
        uv_weight,
        prune,
    );
    let faces = m.faces.len();
    let bridge = progress::Bridge::new(progress)?;
    let out = bridge
        .run(py, |events| {
            lodkit::simplify::simplify_mesh(&m, &opts, events)
        })?
        .map_err(|e| input(e.to_string()))?;
    let report = report_dict(py, faces, &out.report)?;
    Ok((mesh_to_py(py, out.mesh)?, report))
}

/// `lod_chain(mesh, ratios, ...) -> [(dict, report)]`: each level from
/// the previous (`lodkit lods`); with `measure`, each level's symmetric
/// Metro distance to the input as `lods.json` has it.
#[pyfunction]
#[pyo3(signature = (mesh, ratios, max_error = None, lock_border = false, fill_holes = true,
    heap_size = Options::DEFAULT_HEAP_SIZE, normal_weight = AttributeWeights::DEFAULT.normal,
    color_weight = AttributeWeights::DEFAULT.color, uv_weight = AttributeWeights::DEFAULT.uv,
    prune = None, measure = true, samples = None))]
#[allow(clippy::too_many_arguments)]
fn lod_chain<'py>(
    py: Python<'py>,
    mesh: &Bound<'py, PyAny>,
    ratios: Vec<f32>,
    max_error: Option<f32>,
    lock_border: bool,
    fill_holes: bool,
    heap_size: usize,
    normal_weight: f32,
    color_weight: f32,
    uv_weight: f32,
    prune: Option<f32>,
    measure: bool,
    samples: Option<usize>,
) -> PyResult<Vec<(Bound<'py, PyDict>, Bound<'py, PyDict>)>> {
    let m = mesh_from_py(mesh)?;
    let opts = options(
        Target::Ratio(1.0),
        max_error,
        lock_border,
        fill_holes,
        heap_size,
        normal_weight,
        color_weight,
        uv_weight,
        prune,
    );
    let targets: Vec<Target> = ratios.iter().map(|&r| Target::Ratio(r)).collect();
    let faces = m.faces.len();
    type Level = (lodkit_simplify::Simplified, Option<(f64, f64, u64)>);
    let levels: Vec<Level> = py
        .detach(|| -> Result<Vec<Level>, String> {
            let chain = Simplifier::new()
                .lod_chain(&m, &opts, &targets)
                .map_err(|e| e.to_string())?;
            if !measure {
                return Ok(chain.into_iter().map(|l| (l, None)).collect());
            }
            // Measured as the library's chain measures its levels.
            let reference = Reference::new(&m).map_err(|e| e.to_string())?;
            let sampling = samples.map_or(Sampling::Adaptive, Sampling::PerKind);
            chain
                .into_iter()
                .map(|l| {
                    let d = sampling
                        .measure(&reference, &l.mesh)
                        .map_err(|e| e.to_string())?;
                    Ok((l, d.map(|d| (d.mean, d.max, d.samples))))
                })
                .collect()
        })
        .map_err(input)?;
    levels
        .into_iter()
        .enumerate()
        .map(|(i, (l, measured))| {
            let report = report_dict(py, faces, &l.report)?;
            report.set_item("level", i + 1)?;
            report.set_item("measured_mean_error", measured.map(|m| m.0))?;
            report.set_item("measured_max_error", measured.map(|m| m.1))?;
            report.set_item("samples", measured.map(|m| m.2))?;
            Ok((mesh_to_py(py, l.mesh)?, report))
        })
        .collect()
}

/// `compare(a, b, ...) -> dict`: `lodkit compare --json`'s report, measured
/// by the library's `lodkit::compare::measure` (the `compare` job's
/// measurement; the meshes are called `mesh a` and `mesh b` in errors).
#[pyfunction]
#[pyo3(signature = (a, b, samples = None, seed = lodkit_mesh::metrics::DEFAULT_SEED,
    vertex_samples = true, edge_samples = true, face_samples = true, progress = None))]
// Python keyword options, one parameter each (as the CLI's flags).
#[allow(clippy::too_many_arguments)]
fn compare<'py>(
    py: Python<'py>,
    a: &Bound<'py, PyAny>,
    b: &Bound<'py, PyAny>,
    samples: Option<usize>,
    seed: u64,
    vertex_samples: bool,
    edge_samples: bool,
    face_samples: bool,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let a = mesh_from_py(a)?;
    let b = mesh_from_py(b)?;
    let opts = CompareOptions {
        samples,
        seed,
        vertex_samples,
        edge_samples,
        face_samples,
    };
    let bridge = progress::Bridge::new(progress)?;
    let report = bridge
        .run(py, |events| {
            lodkit::compare::measure(&a, &b, ("mesh a", "mesh b"), &opts, events)
        })?
        .map_err(errors::job)?;
    json_to_py(py, &report)
}

/// `LIMITS`: every option range of `lodkit::limits` by name: an integer
/// range as `(lo, hi)`, a real one as `(lo, hi, lo_open, hi_open)` (an
/// absent end infinite). pylodkit checks its keywords against these.
fn limits_dict(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    let int = |r: &std::ops::RangeInclusive<usize>| (*r.start(), *r.end());
    let real = |r: limits::Real| {
        let (lo, lo_open, hi, hi_open) = r.bounds();
        (lo, hi, lo_open, hi_open)
    };
    d.set_item("samples", int(&limits::SAMPLES))?;
    d.set_item("levels", int(&limits::LEVELS))?;
    d.set_item("target", int(&limits::TARGET_FACES))?;
    d.set_item("heap_size", int(&limits::HEAP_SIZE))?;
    d.set_item(
        "resolution",
        (
            *limits::MCO_RESOLUTION.start(),
            *limits::MCO_RESOLUTION.end(),
        ),
    )?;
    let int8 = |r: &std::ops::RangeInclusive<u8>| (*r.start(), *r.end());
    d.set_item("pop_depth", int8(&limits::POP_DEPTH))?;
    d.set_item("pop_bits", int8(&limits::POP_BITS))?;
    d.set_item("pop_decimate", real(limits::POP_DECIMATE))?;
    d.set_item("ratio", real(limits::RATIO))?;
    d.set_item("max_error", real(limits::MAX_ERROR))?;
    d.set_item("weight", real(limits::WEIGHT))?;
    d.set_item("prune", real(limits::PRUNE))?;
    d.set_item("memory", (*limits::MEMORY.start(), *limits::MEMORY.end()))?;
    d.set_item(
        "tile_leaf_triangles",
        int(&lodkit_tiles::TilesOptions::LEAF_TRIANGLES),
    )?;
    d.set_item(
        "tile_leaf_points",
        int(&lodkit_tiles::PointTilesOptions::LEAF_POINTS),
    )?;
    d.set_item("memory", (*limits::MEMORY.start(), *limits::MEMORY.end()))?;
    d.set_item("fov", real(limits::FOV))?;
    d.set_item("view_fov", real(limits::VIEW_FOV))?;
    d.set_item("viewport", real(limits::VIEWPORT))?;
    d.set_item("tolerance", real(limits::TOLERANCE))?;
    d.set_item("elevation", real(limits::ELEVATION))?;
    d.set_item(
        "picture_size",
        (*limits::PICTURE_SIZE.start(), *limits::PICTURE_SIZE.end()),
    )?;
    Ok(d)
}

/// `DEFAULTS`: the default of every option pylodkit offers by name, from
/// `lodkit::limits` and the engines' option types (what the CLI's flags
/// default to).
fn defaults_dict(py: Python<'_>) -> PyResult<Bound<'_, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("levels", limits::DEFAULT_LEVELS)?;
    d.set_item("heap_size", Options::DEFAULT_HEAP_SIZE)?;
    d.set_item("normal_weight", AttributeWeights::DEFAULT.normal)?;
    d.set_item("color_weight", AttributeWeights::DEFAULT.color)?;
    d.set_item("uv_weight", AttributeWeights::DEFAULT.uv)?;
    d.set_item("seed", lodkit_mesh::metrics::DEFAULT_SEED)?;
    d.set_item("noise_seed", lodkit_mesh::shapes::DEFAULT_NOISE_SEED)?;
    d.set_item("fov", limits::DEFAULT_FOV)?;
    d.set_item("azimuth", limits::DEFAULT_VIEW.0)?;
    d.set_item("elevation", limits::DEFAULT_VIEW.1)?;
    d.set_item("width", limits::DEFAULT_PICTURE_SIZE.0)?;
    d.set_item("height", limits::DEFAULT_PICTURE_SIZE.1)?;
    d.set_item("background", limits::DEFAULT_BACKGROUND.map(u32::from))?;
    Ok(d)
}

#[pymodule]
fn _lodkit(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(load, m)?)?;
    m.add_function(wrap_pyfunction!(save, m)?)?;
    m.add_function(wrap_pyfunction!(bunny, m)?)?;
    m.add_function(wrap_pyfunction!(blob, m)?)?;
    m.add_function(wrap_pyfunction!(icosphere, m)?)?;
    m.add_function(wrap_pyfunction!(write_atomic, m)?)?;
    m.add_function(wrap_pyfunction!(write_lod_glb, m)?)?;
    m.add_function(wrap_pyfunction!(simplify, m)?)?;
    m.add_function(wrap_pyfunction!(lod_chain, m)?)?;
    m.add_function(wrap_pyfunction!(compare, m)?)?;
    m.add_function(wrap_pyfunction!(scale::block_task_count, m)?)?;
    m.add_function(wrap_pyfunction!(scale::run_block_task, m)?)?;
    m.add_function(wrap_pyfunction!(tiles::tiles, m)?)?;
    mco::register(m)?;
    pop::register(m)?;
    jobs::register(m)?;
    m.add("LIMITS", limits_dict(m.py())?)?;
    m.add("DEFAULTS", defaults_dict(m.py())?)?;
    m.add("DEFAULT_LEVELS", limits::DEFAULT_LEVELS)?;
    Ok(())
}
