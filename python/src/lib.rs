//! `pylodkit._lodkit`: the native half of the `pylodkit` Python package
//! (the pure-Python half, `python/pylodkit/`, wraps it in `Mesh` /
//! `PointCloud` classes, checks option ranges and documents each call).
//!
//! Contract of every function here:
//! - **Inputs** are numpy arrays read in place (see [`convert`]); options
//!   arrive already range-checked by the Python layer, with the CLI's
//!   defaults (`crates/cli/src/commands/{simplify,lods,compare,mco,pop}.rs`).
//! - **The GIL is released** (`Python::detach`) around every computation:
//!   file reading and writing, simplification, measurement, builds, cuts,
//!   encoding, decoding. Other Python threads run meanwhile.
//! - **Errors** are `pylodkit.errors` exceptions carrying the crates' one
//!   line ([`errors`]): what the CLI prints, without the file name when
//!   there is no file.
//! - Only the crates' public APIs are used (no dependency on the CLI).

use std::path::PathBuf;

use lodkit_mesh::io::WriteOptions;
use lodkit_mesh::metrics::{CompareOptions, Reference};
use lodkit_simplify::{AttributeWeights, LevelReport, Options, Simplifier, Target};
use pyo3::prelude::*;
use pyo3::types::PyDict;

mod convert;
mod errors;
mod mco;
mod pop;
mod scale;
mod tiles;

use convert::{json_to_py, mesh_from_py, mesh_to_py, model_from_py, model_to_py};
use errors::input;

use lodkit::limits::{self, MAX_SAMPLES};

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
#[pyo3(signature = (triangles, seed = 1))]
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

/// `write_lod_glb(path, levels)`: an LOD chain as one GLB, as `lodkit lods`
/// writes `NAME_lods.glb` (`lodkit_mesh::io::gltf::write_lod_glb`), written
/// atomically. `levels`: `(mesh, name, extras_json, error)` per level,
/// level 0 (the input) first; `extras_json` is the node's extras (a JSON
/// object), `error` the level's error against level 0 in object units
/// (its measured maximum, else the estimate). Level k is shown down to the
/// coverage at which level k + 1's error is one pixel
/// (`gltf::error_coverage` on level 0's diagonal), the last down to 0, and
/// the writer makes the values strictly decrease. Meshes without normals
/// get smooth ones, as the CLI's GLBs do.
#[pyfunction]
fn write_lod_glb(
    py: Python<'_>,
    path: PathBuf,
    levels: Vec<(Bound<'_, PyAny>, String, String, f64)>,
) -> PyResult<()> {
    use lodkit_mesh::io::gltf;
    let mut meshes = Vec::with_capacity(levels.len());
    let mut rest = Vec::with_capacity(levels.len());
    for (mesh, name, extras, error) in &levels {
        meshes.push(mesh_from_py(mesh)?);
        let extras: serde_json::Map<String, serde_json::Value> = serde_json::from_str(extras)
            .map_err(|e| input(format!("level {name}: extras: {e}")))?;
        rest.push((name.clone(), extras, *error));
    }
    py.detach(|| -> Result<(), lodkit_mesh::Error> {
        let diagonal = meshes.first().map_or(0.0, |m| m.bbox().diagonal() as f64);
        let with_normals: Vec<_> = meshes
            .iter()
            .map(|m| lodkit_mesh::normals::NormalsMode::default_for(m).apply(m))
            .collect();
        let glb_levels: Vec<gltf::LodLevel> = rest
            .iter()
            .zip(&with_normals)
            .enumerate()
            .map(|(k, ((name, extras, _), m))| gltf::LodLevel {
                name: name.clone(),
                mesh: m,
                extras: extras.clone(),
                coverage: rest
                    .get(k + 1)
                    .map_or(0.0, |next| gltf::error_coverage(next.2, diagonal)),
            })
            .collect();
        let bytes = gltf::write_lod_glb(&glb_levels, &gltf::GlbOptions::default())
            .map_err(|e| lodkit_mesh::Error::parse(&path, e))?;
        lodkit_mesh::io::write_atomic(&path, &bytes)
    })
    .map_err(errors::mesh)
}

/// The simplifier options, from the Python keywords (CLI defaults).
#[allow(clippy::too_many_arguments)]
fn options(
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

/// `simplify(mesh, ...) -> (dict, report)`: one mesh to one budget.
#[pyfunction]
#[pyo3(signature = (mesh, target = None, ratio = None, max_error = None, lock_border = false,
    fill_holes = true, heap_size = Options::DEFAULT_HEAP_SIZE,
    normal_weight = AttributeWeights::DEFAULT.normal, color_weight = AttributeWeights::DEFAULT.color,
    uv_weight = AttributeWeights::DEFAULT.uv, prune = None))]
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
    let out = py
        .detach(|| Simplifier::new().simplify(&m, &opts))
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
            let reference = Reference::new(&m).map_err(|e| e.to_string())?;
            chain
                .into_iter()
                .map(|l| {
                    if l.mesh.faces.is_empty() {
                        return Ok((l, None));
                    }
                    let r = reference
                        .compare_level(&l.mesh, samples)
                        .map_err(|e| e.to_string())?;
                    let d = Some((r.symmetric.mean, r.symmetric.max, r.samples_per_kind));
                    Ok((l, d))
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

/// `compare(a, b, ...) -> dict`: `lodkit compare --json`'s report.
#[pyfunction]
#[pyo3(signature = (a, b, samples = None, seed = lodkit_mesh::metrics::DEFAULT_SEED,
    vertex_samples = true, edge_samples = true, face_samples = true))]
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
    // The default grows with the meshes; bounded like an explicit count.
    let n = opts
        .resolved_samples(a.faces.len(), b.faces.len())
        .min(MAX_SAMPLES);
    let opts = CompareOptions {
        samples: Some(n),
        ..opts
    };
    let report = py
        .detach(|| lodkit_mesh::metrics::compare(&a, &b, &opts))
        .map_err(|e| {
            input(
                e.to_string()
                    .replace("mesh A", "mesh a")
                    .replace("mesh B", "mesh b"),
            )
        })?;
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
    m.add("LIMITS", limits_dict(m.py())?)?;
    m.add("DEFAULT_LEVELS", limits::DEFAULT_LEVELS)?;
    Ok(())
}
