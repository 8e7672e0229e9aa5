//! `tiles(input, out, leaf_triangles, leaf_points, skirts, memory) -> dict`: the
//! library's `tiles` job (`lodkit tiles`), a 3D Tiles 1.1 tileset of a
//! mesh or point cloud file written into the folder `out`.

use std::path::PathBuf;

use lodkit::progress::Progress;
use lodkit::tiles::{TilesJob, TilesReport};
use lodkit_tiles::{PointTilesOptions, TilesOptions};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::errors::{Kind, raise};

/// Runs the job with the GIL released (`None`: the CLI's defaults); a `Usage` (an output folder that
/// is not lodkit's, an option out of range) and bad input are
/// `InputError`s, an I/O failure a `FileError`.
#[pyfunction]
#[pyo3(signature = (input, out, leaf_triangles = None, leaf_points = None, skirts = true, memory = None, compress = true))]
#[allow(clippy::too_many_arguments)]
pub fn tiles<'py>(
    py: Python<'py>,
    input: PathBuf,
    out: PathBuf,
    leaf_triangles: Option<usize>,
    leaf_points: Option<usize>,
    skirts: bool,
    memory: Option<u64>,
    compress: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let job = TilesJob {
        input,
        out: out.clone(),
        mesh: TilesOptions {
            leaf_triangles: leaf_triangles.unwrap_or(TilesOptions::DEFAULT_LEAF_TRIANGLES),
            compress,
            skirts,
        },
        points: PointTilesOptions {
            leaf_points: leaf_points.unwrap_or(PointTilesOptions::DEFAULT_LEAF_POINTS),
            compress,
        },
        scale: lodkit::plan::OutOfCore { memory, ray: None },
    };
    let report = py
        .detach(|| lodkit::tiles::run(&job, &Progress::silent()))
        .map_err(|e| {
            let io = e.chain().any(|c| c.is::<std::io::Error>());
            raise(if io { Kind::File } else { Kind::Input }, e.to_string())
        })?;
    let d = PyDict::new(py);
    d.set_item("tileset", out.join("tileset.json"))?;
    match report {
        TilesReport::Mesh(r) => {
            d.set_item("kind", "mesh")?;
            d.set_item("tiles", r.tiles)?;
            d.set_item("depth", r.depth)?;
            d.set_item("root_error", r.root_error)?;
            d.set_item("bytes", r.bytes)?;
            d.set_item("level_triangles", r.level_triangles)?;
        }
        TilesReport::Points(r, origin) => {
            d.set_item("kind", "points")?;
            d.set_item("tiles", r.tiles)?;
            d.set_item("depth", r.depth)?;
            d.set_item("root_error", r.root_error)?;
            d.set_item("bytes", r.bytes)?;
            d.set_item("points", r.input_points)?;
            d.set_item("origin", origin)?;
        }
    }
    Ok(d)
}
