//! `McoModel`: the continuous-LOD model of `lodkit-mco`, built (by the
//! library's `lodkit::mco_build`, as `lodkit mco build`), saved, loaded
//! and cut from Python (`lodkit mco extract|info`).

use std::path::PathBuf;

use glam::Vec3;
use lodkit_mco::{Camera, McoModel};
use lodkit_mesh::Model;
use pyo3::prelude::*;
use pyo3::types::{PyBytes, PyDict};

use crate::convert::{json_to_py, mesh_to_py, model_from_py};
use crate::errors::{self, Kind, input, raise};

/// A built marching cube octree: one vertex buffer, cut at any triangle
/// budget, LOD number or camera. Immutable, so cuts from several Python
/// threads run at once (each releases the GIL).
#[pyclass(name = "McoModel", module = "pylodkit._lodkit", frozen)]
pub struct PyMco {
    inner: McoModel,
}

/// `mco_build(inputs, resolution, progress) -> McoModel`: the library's
/// build (`lodkit::mco_build`, what `lodkit mco build` runs): every input
/// on one lattice, a `.conf` path adding its posed scans. Inputs are named
/// in messages by their path, else `input N` (from 1).
#[pyfunction]
#[pyo3(signature = (inputs, resolution = None, progress = None))]
fn mco_build<'py>(
    py: Python<'py>,
    inputs: Vec<Bound<'py, PyAny>>,
    resolution: Option<u32>,
    progress: Option<Bound<'py, PyAny>>,
) -> PyResult<PyMco> {
    let mut models = Vec::with_capacity(inputs.len());
    for (i, obj) in inputs.iter().enumerate() {
        let path = obj
            .extract::<PathBuf>()
            .ok()
            .filter(|_| !obj.hasattr("shape").unwrap_or(false));
        match path {
            Some(path)
                if path
                    .extension()
                    .is_some_and(|e| e.eq_ignore_ascii_case("conf")) =>
            {
                let scans = py
                    .detach(|| lodkit_mesh::io::conf::load_scans(&path))
                    .map_err(errors::mesh)?;
                models.extend(
                    scans
                        .into_iter()
                        .map(|(p, r)| (p.display().to_string(), Model::Range(r))),
                );
            }
            Some(path) => models.push((path.display().to_string(), model_from_py(obj)?)),
            None => models.push((format!("input {}", i + 1), model_from_py(obj)?)),
        }
    }
    let bridge = crate::progress::Bridge::new(progress)?;
    let (inner, _) = bridge
        .run(py, |events| {
            lodkit::mco_build::build_model(&models, resolution, events)
        })?
        .map_err(errors::job)?;
    Ok(PyMco { inner })
}

/// `mco_load(path) -> McoModel`.
#[pyfunction]
fn mco_load(py: Python<'_>, path: PathBuf) -> PyResult<PyMco> {
    let r = py.detach(|| McoModel::load(&path));
    match r {
        Ok(inner) => Ok(PyMco { inner }),
        // Tell "cannot open" (an OSError) from "malformed" (bad data).
        Err(e) if std::fs::File::open(&path).is_err() => Err(raise(Kind::File, e.to_string())),
        Err(e) => Err(errors::mco(e)),
    }
}

/// `mco_from_bytes(data) -> McoModel`.
#[pyfunction]
fn mco_from_bytes(py: Python<'_>, data: &[u8]) -> PyResult<PyMco> {
    let inner = py
        .detach(|| McoModel::from_bytes(data))
        .map_err(errors::mco)?;
    Ok(PyMco { inner })
}

/// `lodkit mco info --json`'s model fields (no file fields), and whether
/// the model has colours.
#[derive(serde::Serialize)]
struct Info {
    #[serde(flatten)]
    model: lodkit::report::McoModelInfo,
    has_colors: bool,
}

#[pymethods]
impl PyMco {
    /// The highest LOD number (every leaf cube).
    #[getter]
    fn max_lod(&self) -> usize {
        self.inner.max_lod()
    }

    /// Triangles at full resolution.
    #[getter]
    fn full_triangles(&self) -> usize {
        self.inner.full_triangles()
    }

    /// Triangles of the cut at LOD number `k`.
    fn triangles_at_lod(&self, k: usize) -> usize {
        self.inner.triangles_at_lod(k)
    }

    /// The bounding box `((x, y, z), (x, y, z))`.
    fn bounds(&self) -> ([f32; 3], [f32; 3]) {
        let (lo, hi) = self.inner.bounds();
        (lo.to_array(), hi.to_array())
    }

    /// The cut nearest a triangle budget: `(mesh dict, lod)`.
    fn extract_triangles<'py>(
        &self,
        py: Python<'py>,
        triangles: usize,
    ) -> PyResult<(Bound<'py, PyDict>, usize)> {
        let model = &self.inner;
        let (mesh, k) = py.detach(|| {
            let mut idx = Vec::new();
            let k = model.extract_triangles(triangles, &mut idx);
            (model.mesh_from_indices(&idx), k)
        });
        Ok((mesh_to_py(py, mesh)?, k))
    }

    /// The cut at LOD number `lod` (`0..=max_lod`).
    fn extract_lod<'py>(&self, py: Python<'py>, lod: usize) -> PyResult<Bound<'py, PyDict>> {
        let model = &self.inner;
        if lod > model.max_lod() {
            return Err(input(format!(
                "lod {lod} is outside 0..={} for this model",
                model.max_lod()
            )));
        }
        let mesh = py.detach(|| {
            let mut idx = Vec::new();
            model.extract_lod(lod, &mut idx);
            model.mesh_from_indices(&idx)
        });
        mesh_to_py(py, mesh)
    }

    /// The view-dependent cut for a camera at `position` looking at
    /// `look_at` (default: the model's centre): `(mesh dict, expanded nodes)`.
    /// `None`: `lodkit mco extract`'s defaults (the camera's field of view
    /// and viewport, [`lodkit::limits::DEFAULT_TOLERANCE`]).
    #[pyo3(signature = (position, look_at = None, fov = None, viewport = None, tolerance = None))]
    fn extract_view<'py>(
        &self,
        py: Python<'py>,
        position: [f32; 3],
        look_at: Option<[f32; 3]>,
        fov: Option<f32>,
        viewport: Option<f32>,
        tolerance: Option<f32>,
    ) -> PyResult<(Bound<'py, PyDict>, usize)> {
        let model = &self.inner;
        let position = Vec3::from(position);
        let (lo, hi) = model.bounds();
        let target = look_at.map_or((lo + hi) * 0.5, Vec3::from);
        if position == target {
            return Err(input(
                "view and look_at are the same point: the camera has no direction",
            ));
        }
        let cam = Camera::looking_at(position, target);
        let cam = Camera {
            vfov_deg: fov.unwrap_or(cam.vfov_deg),
            viewport_height: viewport.unwrap_or(cam.viewport_height),
            ..cam
        };
        let tolerance = tolerance.unwrap_or(lodkit::limits::DEFAULT_TOLERANCE);
        let (mesh, n) = py.detach(|| {
            let mut idx = Vec::new();
            let n = model.extract_view(&cam, tolerance, &mut idx);
            (model.mesh_from_indices(&idx), n)
        });
        Ok((mesh_to_py(py, mesh)?, n))
    }

    /// Writes the model as a `.mco` file, atomically.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        let model = &self.inner;
        py.detach(|| model.save(&path)).map_err(errors::mco)
    }

    /// The `.mco` bytes (what `save` writes).
    fn to_bytes<'py>(&self, py: Python<'py>) -> Bound<'py, PyBytes> {
        let model = &self.inner;
        let bytes = py.detach(|| model.to_bytes());
        PyBytes::new(py, &bytes)
    }

    /// `lodkit mco info --json`'s model figures, as a dict.
    fn info<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let m = self.inner.info();
        let info = Info {
            model: lodkit::report::McoModelInfo::of(&self.inner),
            has_colors: m.has_colors,
        };
        json_to_py(py, &info)
    }
}

pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyMco>()?;
    m.add_function(wrap_pyfunction!(mco_build, m)?)?;
    m.add_function(wrap_pyfunction!(mco_load, m)?)?;
    m.add_function(wrap_pyfunction!(mco_from_bytes, m)?)?;
    Ok(())
}
