//! `.pop` progressive octree particle streams (`lodkit pop encode|decode`).

use lodkit::progress::Progress;
use lodkit::stream_encode::{StreamSource, encode_model};
use lodkit_particles::{
    DecodeOptions, EncodeOptions, Mode, Placement, ThinningOptions, TriangulateOptions, decode,
    decode_prefix, triangulate,
};
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::convert::{json_to_py, mesh_to_py, model_from_py, points_to_py};
use crate::errors::input;

/// `pop_encode(obj, ...) -> (bytes, report)`: `lodkit pop encode`'s
/// options and defaults (`relax_below = None` is `auto`; a cloud is coded
/// from its reconstructed surface unless `raw`).
#[pyfunction]
#[pyo3(signature = (obj, depth = None, precision = None, mode = "entropy", placement = None,
    outer_thinning = false, relax_below = None, normals = false, colours = true, raw = false))]
#[allow(clippy::too_many_arguments)]
fn pop_encode<'py>(
    py: Python<'py>,
    obj: &Bound<'py, PyAny>,
    depth: Option<u8>,
    precision: Option<u8>,
    mode: &str,
    placement: Option<&str>,
    outer_thinning: bool,
    relax_below: Option<u8>,
    normals: bool,
    colours: bool,
    raw: bool,
) -> PyResult<(Bound<'py, PyBytes>, Bound<'py, PyAny>)> {
    let model = model_from_py(obj)?;
    let mode = match mode {
        "entropy" => Mode::Entropy,
        "baseline" => Mode::Baseline,
        other => {
            return Err(input(format!(
                "mode {other:?}: expected \"entropy\" or \"baseline\""
            )));
        }
    };
    let placement = match placement {
        None | Some("column") => Placement::SurfaceColumn,
        Some("mean") => Placement::Mean,
        Some(other) => {
            return Err(input(format!(
                "placement {other:?}: expected \"column\" or \"mean\""
            )));
        }
    };
    let opts = EncodeOptions {
        depth,
        precision: precision.unwrap_or(lodkit_particles::DEFAULT_PRECISION),
        mode,
        thinning: ThinningOptions {
            outer: outer_thinning,
            relax_below: relax_below.unwrap_or(ThinningOptions::AUTO_RELAX),
        },
        normals,
        colours,
        placement,
        ..EncodeOptions::DEFAULT
    };
    let source = if raw {
        StreamSource::Samples
    } else {
        StreamSource::Surface
    };
    let (e, plan) = py
        .detach(|| encode_model(&model, "the input", &opts, source, &Progress::silent()))
        .map_err(|e| input(e.to_string()))?;
    let report = json_to_py(py, &e.report)?;
    report.set_item("source", plan.source)?;
    Ok((PyBytes::new(py, &e.bytes), report))
}

/// `pop_decode(data, ...) -> (kind, dict, info)`: one level of a stream,
/// triangulated (or its particles with `points`); a prefix decodes its
/// complete chunks unless `strict`.
#[pyfunction]
#[pyo3(signature = (data, level = None, precision = None, points = false, decimate = None, strict = false))]
fn pop_decode<'py>(
    py: Python<'py>,
    data: &[u8],
    level: Option<u8>,
    precision: Option<u8>,
    points: bool,
    decimate: Option<f32>,
    strict: bool,
) -> PyResult<(&'static str, Bound<'py, PyDict>, Bound<'py, PyDict>)> {
    let opts = DecodeOptions {
        max_level: level,
        max_precision: precision,
    };
    let d = py
        .detach(|| {
            if strict {
                decode(data, &opts)
            } else {
                decode_prefix(data, &opts)
            }
        })
        .map_err(|e| input(e.to_string()))?;
    let finest = d.finest_level();
    let r = level.unwrap_or(finest);
    if r > finest {
        let held = if d.cut.is_some() {
            "its complete chunks hold"
        } else {
            "it holds"
        };
        return Err(input(format!(
            "level {r} is outside 0..={finest}: the levels {held} in this stream"
        )));
    }
    let s = d.surface(r).map_err(|e| input(e.to_string()))?;
    let particles = s.cells.len();
    let info = PyDict::new(py);
    info.set_item("level", r)?;
    info.set_item("finest_level", finest)?;
    info.set_item("depth", d.header.depth)?;
    info.set_item("particles", particles)?;
    info.set_item("precision", d.precision)?;
    info.set_item("bytes_read", d.bytes_read)?;
    info.set_item("file_bytes", data.len())?;
    match &d.cut {
        Some(c) => {
            let cut = PyDict::new(py);
            cut.set_item("chunk", c.chunk)?;
            cut.set_item("offset", c.offset)?;
            cut.set_item("message", &c.message)?;
            info.set_item("cut", cut)?;
        }
        None => info.set_item("cut", py.None())?,
    }
    if points {
        info.set_item("triangles", py.None())?;
        let cloud = py.detach(|| s.to_point_cloud());
        return Ok(("points", points_to_py(py, cloud)?, info));
    }
    let t = py.detach(|| {
        triangulate(
            &s,
            &TriangulateOptions {
                decimate,
                ..TriangulateOptions::DEFAULT
            },
        )
    });
    info.set_item("triangles", t.mesh.faces.len())?;
    info.set_item("triangulation", json_to_py(py, &t.stats)?)?;
    Ok(("mesh", mesh_to_py(py, t.mesh)?, info))
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(pop_encode, m)?)?;
    m.add_function(wrap_pyfunction!(pop_decode, m)?)?;
    Ok(())
}
