//! The library's jobs on files (`lodkit::{simplify, lod_chain,
//! build_all, compare, render, info}`), one function each: what the
//! `lodkit` command runs, with the same options, the same outputs (bytes)
//! and the same one-line errors.
//!
//! Contract of every function here:
//! - **Inputs** are paths and option values; options arrive range-checked
//!   by the Python layer against `LIMITS` (the library checks again where
//!   it must: a request it cannot serve is an `OptionError`).
//! - **Progress**: `progress` (a function of one dict, or `None`) gets the
//!   job's events ([`crate::progress`]); the GIL is released while the job
//!   runs and taken for each call.
//! - **Returns** the job's report as the CLI's `--json` prints it, as a
//!   dict (`json.loads` of the same serde types: one definition).
//! - **Errors**: [`crate::errors::job`] — `OptionError`, `FileError` or
//!   `InputError` with the CLI's line.

use std::path::PathBuf;

use lodkit::build_all::{BuildJob, Sampling};
use lodkit::compare::CompareJob;
use lodkit::info::Info;
use lodkit::lod_chain::LodChainJob;
use lodkit::output::OutputOptions;
use lodkit::plan::OutOfCore;
use lodkit::render::{RenderJob, Select, Views};
use lodkit::simplify::SimplifyJob;
use lodkit_mesh::metrics::CompareOptions;
use lodkit_render::{Normals, RenderOptions};
use lodkit_simplify::{AttributeWeights, Options, Target};
use pyo3::prelude::*;

use crate::convert::json_to_py;
use crate::errors::{self, Kind, raise};
use crate::progress::Bridge;

/// `simplify_file(input, output, ...) -> dict`: `lodkit simplify IN -o
/// OUT --json` (in core, or out of core over `memory` bytes).
#[pyfunction]
#[pyo3(signature = (input, output, target = None, ratio = None, max_error = None,
    lock_border = false, fill_holes = true, heap_size = Options::DEFAULT_HEAP_SIZE,
    normal_weight = AttributeWeights::DEFAULT.normal, color_weight = AttributeWeights::DEFAULT.color,
    uv_weight = AttributeWeights::DEFAULT.uv, prune = None, merge = false, memory = None,
    progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn simplify_file<'py>(
    py: Python<'py>,
    input: PathBuf,
    output: PathBuf,
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
    merge: bool,
    memory: Option<u64>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let target = lodkit::simplify::target_of(target, ratio, max_error)
        .map_err(|e| raise(Kind::Option, e.to_string()))?;
    let job = SimplifyJob {
        input,
        output,
        options: crate::options(
            target,
            max_error,
            lock_border,
            fill_holes,
            heap_size,
            normal_weight,
            color_weight,
            uv_weight,
            prune,
        ),
        merge,
        scale: OutOfCore { memory, ray: None },
        out: OutputOptions::default(),
    };
    let bridge = Bridge::new(progress)?;
    let report = bridge
        .run(py, |events| lodkit::simplify::run(&job, events))?
        .map_err(errors::job)?;
    json_to_py(py, &report)
}

/// `lod_chain_file(input, out, ...) -> dict`: `lodkit lods IN --out DIR
/// --json` (`lods.json` as a dict); `ratios` or `levels` halvings.
#[pyfunction]
#[pyo3(signature = (input, out, ratios = None, levels = None, max_error = None,
    lock_border = false, fill_holes = true, heap_size = Options::DEFAULT_HEAP_SIZE,
    normal_weight = AttributeWeights::DEFAULT.normal, color_weight = AttributeWeights::DEFAULT.color,
    uv_weight = AttributeWeights::DEFAULT.uv, prune = None, samples = None, merge = false,
    memory = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn lod_chain_file<'py>(
    py: Python<'py>,
    input: PathBuf,
    out: PathBuf,
    ratios: Option<Vec<f32>>,
    levels: Option<usize>,
    max_error: Option<f32>,
    lock_border: bool,
    fill_holes: bool,
    heap_size: usize,
    normal_weight: f32,
    color_weight: f32,
    uv_weight: f32,
    prune: Option<f32>,
    samples: Option<usize>,
    merge: bool,
    memory: Option<u64>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let targets = lodkit::lod_chain::targets_of(ratios.as_deref(), levels).map_err(errors::job)?;
    let job = LodChainJob {
        input,
        out,
        targets,
        options: crate::options(
            Target::Ratio(1.0),
            max_error,
            lock_border,
            fill_holes,
            heap_size,
            normal_weight,
            color_weight,
            uv_weight,
            prune,
        ),
        merge,
        scale: OutOfCore { memory, ray: None },
        samples,
        output: OutputOptions::default(),
        notes: true,
    };
    let bridge = Bridge::new(progress)?;
    let report = bridge
        .run(py, |events| lodkit::lod_chain::run(&job, events))?
        .map_err(errors::job)?;
    py.import("json")?.getattr("loads")?.call1((report.json,))
}

/// `build(input, out, ...) -> dict`: `lodkit build [IN] --out DIR`
/// (`input=None`: the built-in bunny); the report lists every file
/// written with its size.
#[pyfunction]
#[pyo3(signature = (input, out, levels = lodkit::limits::DEFAULT_LEVELS, samples = None,
    measure = true, merge = false, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn build<'py>(
    py: Python<'py>,
    input: Option<PathBuf>,
    out: PathBuf,
    levels: usize,
    samples: Option<usize>,
    measure: bool,
    merge: bool,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let job = BuildJob {
        input,
        out,
        levels,
        sampling: match (measure, samples) {
            (false, _) => Sampling::Skip,
            (true, Some(n)) => Sampling::PerKind(n),
            (true, None) => Sampling::Adaptive,
        },
        merge,
        output: OutputOptions::default(),
    };
    let bridge = Bridge::new(progress)?;
    let report = bridge
        .run(py, |events| lodkit::build_all::run(&job, events))?
        .map_err(errors::job)?;
    json_to_py(py, &report)
}

/// `compare_files(a, b, ...) -> dict`: `lodkit compare A B --json`
/// (`heatmap`: also B coloured by its distance to A, written there).
#[pyfunction]
#[pyo3(signature = (a, b, samples = None, seed = lodkit_mesh::metrics::DEFAULT_SEED,
    vertex_samples = true, edge_samples = true, face_samples = true, heatmap = None,
    progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn compare_files<'py>(
    py: Python<'py>,
    a: PathBuf,
    b: PathBuf,
    samples: Option<usize>,
    seed: u64,
    vertex_samples: bool,
    edge_samples: bool,
    face_samples: bool,
    heatmap: Option<PathBuf>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    if let Some(h) = &heatmap
        && !lodkit::compare::holds_heatmap(h)
    {
        return Err(raise(
            Kind::Option,
            format!(
                "heatmap={}: a heat map needs a format with vertex colours and faces: .ply, .obj or .glb",
                h.display()
            ),
        ));
    }
    let job = CompareJob {
        a,
        b,
        options: CompareOptions {
            samples,
            seed,
            vertex_samples,
            edge_samples,
            face_samples,
        },
        heatmap,
    };
    let bridge = Bridge::new(progress)?;
    let report = bridge
        .run(py, |events| lodkit::compare::run(&job, events))?
        .map_err(errors::job)?;
    json_to_py(py, &report)
}

/// `render(input, output, ...) -> dict`: `lodkit render IN -o PNG --json`,
/// one view. `triangles` / `lod` pick a `.mco` cut, `level` a `.pop`
/// level; the Python layer refuses them for other inputs.
#[pyfunction]
#[pyo3(signature = (input, output, azimuth = lodkit::limits::DEFAULT_VIEW.0,
    elevation = lodkit::limits::DEFAULT_VIEW.1, width = lodkit::limits::DEFAULT_PICTURE_SIZE.0,
    height = lodkit::limits::DEFAULT_PICTURE_SIZE.1, fov = lodkit::limits::DEFAULT_FOV,
    background = lodkit::limits::DEFAULT_BACKGROUND, smooth = false, triangles = None,
    lod = None, level = None, progress = None))]
#[allow(clippy::too_many_arguments)]
pub fn render<'py>(
    py: Python<'py>,
    input: PathBuf,
    output: PathBuf,
    azimuth: f32,
    elevation: f32,
    width: u32,
    height: u32,
    fov: f32,
    background: [u8; 3],
    smooth: bool,
    triangles: Option<usize>,
    lod: Option<usize>,
    level: Option<u8>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    if same_file(&input, &output) {
        return Err(raise(
            Kind::Option,
            format!(
                "output={}: is the input {}; give another output path",
                output.display(),
                input.display()
            ),
        ));
    }
    let ext = input
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase);
    let select = match ext.as_deref() {
        Some("mco") => Select::Mco { triangles, lod },
        Some("pop") => Select::Pop { level },
        _ => Select::Geometry,
    };
    let job = RenderJob {
        input,
        select,
        views: Views::One {
            output,
            azimuth,
            elevation,
        },
        fov,
        options: RenderOptions {
            width,
            height,
            background,
            normals: if smooth {
                Normals::Smooth
            } else {
                Normals::Auto
            },
            ..RenderOptions::DEFAULT
        },
    };
    let bridge = Bridge::new(progress)?;
    let report = bridge
        .run(py, |events| lodkit::render::run(&job, events))?
        .map_err(errors::job)?;
    json_to_py(py, &report)
}

/// Whether two paths name one existing file (device and inode; never on
/// non-Unix).
fn same_file(a: &std::path::Path, b: &std::path::Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        match (std::fs::metadata(a), std::fs::metadata(b)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = (a, b);
        false
    }
}

/// `info(path) -> (kind, dict)`: `lodkit info FILE --json` and what kind
/// of file it described (`"model"`, `"mco"`, `"pop"` or `"image_set"`).
#[pyfunction]
#[pyo3(signature = (path, progress = None))]
pub fn info<'py>(
    py: Python<'py>,
    path: PathBuf,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<(&'static str, Bound<'py, PyAny>)> {
    let bridge = Bridge::new(progress)?;
    let info = bridge
        .run(py, |events| lodkit::info::run(&path, events))?
        .map_err(errors::job)?;
    Ok(match &info {
        Info::Model { info, .. } => ("model", json_to_py(py, info)?),
        Info::Mco(i) => ("mco", json_to_py(py, i)?),
        Info::Pop(i) => ("pop", json_to_py(py, i)?),
        Info::ImageSet(i) => ("image_set", json_to_py(py, i)?),
    })
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simplify_file, m)?)?;
    m.add_function(wrap_pyfunction!(lod_chain_file, m)?)?;
    m.add_function(wrap_pyfunction!(build, m)?)?;
    m.add_function(wrap_pyfunction!(compare_files, m)?)?;
    m.add_function(wrap_pyfunction!(render, m)?)?;
    m.add_function(wrap_pyfunction!(info, m)?)?;
    Ok(())
}
