//! numpy arrays ↔ lodkit's geometry types.
//!
//! In: any object with `vertices` (n, 3) float32/float64 and `faces`
//! (m, 3) int32/int64/uint32/uint64, and optionally `normals` (n, 3)
//! float, `colors` (n, 3|4) uint8 or float in [0, 1], `uvs` (n, 2) float
//! (a `pylodkit.Mesh`, a `trimesh.Trimesh` for its vertices and faces);
//! point clouds have `points` instead. The numpy buffer is read in place
//! through a read-only borrow (no intermediate numpy copy, whatever the
//! dtype or strides); the one copy is into the `TriMesh`'s own vectors,
//! made while the GIL is held so no Python thread can write to the array
//! while it is read.
//!
//! Out: faces uint32 (m, 3) and colors uint8 (n, 4) are the crates' own
//! vectors handed to numpy (`Vec::into_flattened`, no copy); vertices, normals (float32 (n, 3)) and uvs (float32 (n, 2)) are
//! copied once out of glam's vectors, a pass of a few microseconds per
//! thousand vertices (a cast would need glam's `bytemuck` feature, which
//! would change the build of every crate that shares glam with this one).

use glam::{Vec2, Vec3};
use lodkit_mesh::{Model, PointCloud, TriMesh};
use numpy::ndarray::{Array2, ArrayView2};
use numpy::{Element, PyArray2, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyString};

use crate::errors::input;

/// `dtype` and `shape` of an object, for messages.
fn describe(obj: &Bound<'_, PyAny>) -> String {
    let dtype = obj.getattr("dtype").and_then(|d| d.str()).ok();
    let shape = obj.getattr("shape").and_then(|d| d.str()).ok();
    match (dtype, shape) {
        (Some(d), Some(s)) => format!("an array of dtype {d} and shape {s}"),
        _ => format!(
            "a {}",
            obj.get_type()
                .name()
                .map_or_else(|_| "value".to_string(), |n| n.to_string())
        ),
    }
}

fn rows<T: Element + Copy, O>(
    a: &ArrayView2<'_, T>,
    name: &str,
    cols: &[usize],
    mut f: impl FnMut(&[T]) -> O,
) -> PyResult<Vec<O>> {
    if !cols.contains(&a.ncols()) {
        let want = cols
            .iter()
            .map(|c| c.to_string())
            .collect::<Vec<_>>()
            .join(" or ");
        return Err(input(format!(
            "{name}: expected shape (n, {want}), got ({}, {})",
            a.nrows(),
            a.ncols()
        )));
    }
    Ok(match a.as_slice() {
        Some(s) => s.chunks_exact(a.ncols()).map(&mut f).collect(),
        None => {
            let mut row = Vec::with_capacity(a.ncols());
            a.rows()
                .into_iter()
                .map(|r| {
                    row.clear();
                    row.extend(r.iter().copied());
                    f(&row)
                })
                .collect()
        }
    })
}

/// A float array of `C` columns (float32 read as is, float64 narrowed).
fn floats<O, const C: usize>(
    obj: &Bound<'_, PyAny>,
    name: &str,
    f: impl Fn([f32; C]) -> O,
) -> PyResult<Vec<O>> {
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f32>>() {
        return rows::<f32, O>(&a.as_array(), name, &[C], |r| {
            f(std::array::from_fn(|i| r[i]))
        });
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f64>>() {
        return rows::<f64, O>(&a.as_array(), name, &[C], |r| {
            f(std::array::from_fn(|i| r[i] as f32))
        });
    }
    Err(input(format!(
        "{name}: expected a float32 or float64 array of shape (n, {C}), got {}",
        describe(obj)
    )))
}

/// Triangle indices of any integer dtype numpy meshes use; each must be
/// in `0..vertices`.
fn faces(obj: &Bound<'_, PyAny>, vertices: usize) -> PyResult<Vec<[u32; 3]>> {
    fn read<T: Element + Copy + TryInto<u32> + std::fmt::Display>(
        a: &PyReadonlyArray2<'_, T>,
        vertices: usize,
    ) -> PyResult<Vec<[u32; 3]>> {
        let mut bad: Option<String> = None;
        let mut face = 0usize;
        let out = rows::<T, [u32; 3]>(&a.as_array(), "faces", &[3], |r| {
            let mut f = [0u32; 3];
            for (k, &v) in r.iter().enumerate() {
                match v.try_into() {
                    Ok(i) if (i as usize) < vertices => f[k] = i,
                    _ => {
                        if bad.is_none() {
                            bad = Some(format!(
                                "faces: face {face} has vertex index {v} but the mesh has {vertices} vertices"
                            ));
                        }
                    }
                }
            }
            face += 1;
            f
        })?;
        match bad {
            Some(msg) => Err(input(msg)),
            None => Ok(out),
        }
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, i32>>() {
        return read(&a, vertices);
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, i64>>() {
        return read(&a, vertices);
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, u32>>() {
        return read(&a, vertices);
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, u64>>() {
        return read(&a, vertices);
    }
    Err(input(format!(
        "faces: expected an int32, int64, uint32 or uint64 array of shape (m, 3), got {}",
        describe(obj)
    )))
}

/// RGBA8 colours from uint8 (n, 3|4) or float (n, 3|4) in [0, 1].
fn colors(obj: &Bound<'_, PyAny>) -> PyResult<Vec<[u8; 4]>> {
    fn rgba<T: Copy>(r: &[T], to: impl Fn(T) -> u8) -> [u8; 4] {
        [
            to(r[0]),
            to(r[1]),
            to(r[2]),
            if r.len() == 4 { to(r[3]) } else { 255 },
        ]
    }
    let unit = |x: f64| (x.clamp(0.0, 1.0) * 255.0).round() as u8;
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, u8>>() {
        return rows::<u8, _>(&a.as_array(), "colors", &[3, 4], |r| rgba(r, |x| x));
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f32>>() {
        return rows::<f32, _>(&a.as_array(), "colors", &[3, 4], |r| {
            rgba(r, |x| unit(x as f64))
        });
    }
    if let Ok(a) = obj.extract::<PyReadonlyArray2<'_, f64>>() {
        return rows::<f64, _>(&a.as_array(), "colors", &[3, 4], |r| rgba(r, unit));
    }
    Err(input(format!(
        "colors: expected a uint8 array (0..255) or a float array (0..1) of shape (n, 3) or (n, 4), got {}",
        describe(obj)
    )))
}

/// `obj.name`, `None` when missing or `None`.
fn attr<'py>(obj: &Bound<'py, PyAny>, name: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
    match obj.getattr(name) {
        Ok(v) if v.is_none() => Ok(None),
        Ok(v) => Ok(Some(v)),
        Err(e) if e.is_instance_of::<pyo3::exceptions::PyAttributeError>(obj.py()) => Ok(None),
        Err(e) => Err(e),
    }
}

/// Per-vertex attribute check: one entry per vertex.
fn per_vertex<T>(v: Vec<T>, n: usize, name: &str) -> PyResult<Vec<T>> {
    if v.len() != n {
        return Err(input(format!(
            "{name}: has {} rows but the mesh has {n} vertices (one per vertex is needed)",
            v.len()
        )));
    }
    Ok(v)
}

fn vec3s(obj: &Bound<'_, PyAny>, name: &str) -> PyResult<Vec<Vec3>> {
    floats::<Vec3, 3>(obj, name, Vec3::from_array)
}

/// A `TriMesh` from a mesh-like object (see the module docs).
pub fn mesh_from_py(obj: &Bound<'_, PyAny>) -> PyResult<TriMesh> {
    let Some(v) = attr(obj, "vertices")? else {
        return Err(input(format!(
            "expected a mesh (an object with `vertices` and `faces` arrays, e.g. pylodkit.Mesh or trimesh.Trimesh), got {}",
            describe(obj)
        )));
    };
    let positions = vec3s(&v, "vertices")?;
    let n = positions.len();
    let faces = match attr(obj, "faces")? {
        Some(f) => faces(&f, n)?,
        None => return Err(input("faces: a mesh needs a faces array (m, 3)")),
    };
    let normals = match attr(obj, "normals")? {
        Some(a) => Some(per_vertex(vec3s(&a, "normals")?, n, "normals")?),
        None => None,
    };
    let colors = match attr(obj, "colors")? {
        Some(a) => Some(per_vertex(colors(&a)?, n, "colors")?),
        None => None,
    };
    let uvs = match attr(obj, "uvs")? {
        Some(a) => Some(per_vertex(
            floats::<Vec2, 2>(&a, "uvs", Vec2::from_array)?,
            n,
            "uvs",
        )?),
        None => None,
    };
    Ok(TriMesh {
        positions,
        normals,
        colors,
        uvs,
        faces,
    })
}

/// A `PointCloud` from a bare (n, 3) array or an object with `points`
/// (or `vertices`) and optional `normals`, `colors`.
pub fn points_from_py(obj: &Bound<'_, PyAny>) -> PyResult<PointCloud> {
    if obj.hasattr("shape")? && obj.hasattr("dtype")? {
        return Ok(PointCloud {
            positions: vec3s(obj, "points")?,
            ..PointCloud::default()
        });
    }
    let (p, name) = match attr(obj, "points")? {
        Some(p) => (p, "points"),
        None => match attr(obj, "vertices")? {
            Some(p) => (p, "vertices"),
            None => {
                return Err(input(format!(
                    "expected a point cloud (an (n, 3) array or an object with a `points` array), got {}",
                    describe(obj)
                )));
            }
        },
    };
    let positions = vec3s(&p, name)?;
    let n = positions.len();
    let normals = match attr(obj, "normals")? {
        Some(a) => Some(per_vertex(vec3s(&a, "normals")?, n, "normals")?),
        None => None,
    };
    let colors = match attr(obj, "colors")? {
        Some(a) => Some(per_vertex(colors(&a)?, n, "colors")?),
        None => None,
    };
    Ok(PointCloud {
        positions,
        normals,
        colors,
    })
}

/// A mesh (it has faces) or a point cloud (it has none), or a path to a
/// file of either.
pub fn model_from_py(obj: &Bound<'_, PyAny>) -> PyResult<Model> {
    if let Ok(path) = obj.extract::<std::path::PathBuf>()
        && !obj.hasattr("shape")?
    {
        return lodkit_mesh::io::load(&path).map_err(crate::errors::mesh);
    }
    let is_mesh =
        !(obj.hasattr("shape")? && obj.hasattr("dtype")?) && attr(obj, "faces")?.is_some();
    Ok(if is_mesh {
        Model::Mesh(mesh_from_py(obj)?)
    } else {
        Model::Points(points_from_py(obj)?)
    })
}

/// A numpy (n, c) array that owns `flat` (no copy).
fn array2<'py, T: Element>(py: Python<'py>, flat: Vec<T>, cols: usize) -> Bound<'py, PyArray2<T>> {
    let n = flat.len() / cols;
    let a = Array2::from_shape_vec((n, cols), flat).expect("whole rows");
    PyArray2::from_owned_array(py, a)
}

/// glam vectors as a numpy (n, C) float32 array (one copy, see the module docs).
fn vec_rows<'py, const C: usize>(
    py: Python<'py>,
    v: &[impl Copy + Into<[f32; C]>],
) -> Bound<'py, PyArray2<f32>> {
    let mut flat = Vec::with_capacity(v.len() * C);
    for &p in v {
        flat.extend_from_slice(&p.into());
    }
    array2(py, flat, C)
}

/// The mesh as a dict of numpy arrays (`vertices`, `faces`, `normals`,
/// `colors`, `uvs`; absent attributes are `None`).
pub fn mesh_to_py<'py>(py: Python<'py>, m: TriMesh) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("vertices", vec_rows::<3>(py, &m.positions))?;
    d.set_item("faces", array2(py, m.faces.into_flattened(), 3))?;
    d.set_item("normals", m.normals.map(|n| vec_rows::<3>(py, &n)))?;
    d.set_item(
        "colors",
        m.colors.map(|c| array2(py, c.into_flattened(), 4)),
    )?;
    d.set_item("uvs", m.uvs.map(|t| vec_rows::<2>(py, &t)))?;
    Ok(d)
}

/// The point cloud as a dict (`points`, `normals`, `colors`).
pub fn points_to_py<'py>(py: Python<'py>, p: PointCloud) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("points", vec_rows::<3>(py, &p.positions))?;
    d.set_item("normals", p.normals.map(|n| vec_rows::<3>(py, &n)))?;
    d.set_item(
        "colors",
        p.colors.map(|c| array2(py, c.into_flattened(), 4)),
    )?;
    Ok(d)
}

/// A model as `(kind, dict)`: `"mesh"` or `"points"` (a range image is
/// its valid samples as points).
pub fn model_to_py<'py>(
    py: Python<'py>,
    m: Model,
) -> PyResult<(Bound<'py, PyString>, Bound<'py, PyDict>)> {
    Ok(match m {
        Model::Mesh(m) => (PyString::new(py, "mesh"), mesh_to_py(py, m)?),
        Model::Points(p) => (PyString::new(py, "points"), points_to_py(py, p)?),
        Model::Range(r) => (
            PyString::new(py, "points"),
            points_to_py(py, r.to_point_cloud())?,
        ),
    })
}

/// A serde value as a Python object, through JSON (the same keys and
/// numbers the CLI's `--json` prints).
pub fn json_to_py<'py>(py: Python<'py>, v: &impl serde::Serialize) -> PyResult<Bound<'py, PyAny>> {
    let text = serde_json::to_string(v).map_err(|e| input(e.to_string()))?;
    py.import("json")?.getattr("loads")?.call1((text,))
}
