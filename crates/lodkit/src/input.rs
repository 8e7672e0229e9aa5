//! Loading inputs: any file the mesh crate reads, scenes kept when the
//! output can hold them (meshes with materials, parts and nodes), the
//! built-in Stanford bunny, and calibrated image sets carved from their
//! silhouettes. Every loader names the file in its errors and reports
//! its reading as a stage.
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::io::Format;
use lodkit_mesh::{Model, Scene};

use crate::progress::Progress;

/// The Stanford bunny (`data/models/stanford_bunny.ply`), built into the
/// binary so `lodkit build` and the benches work from any directory.
pub const BUILTIN_BUNNY: &[u8] = include_bytes!("../../../data/models/stanford_bunny.ply");

/// Decodes the built-in bunny.
pub fn builtin_bunny() -> Result<lodkit_mesh::TriMesh> {
    match lodkit_mesh::io::decode(lodkit_mesh::io::Format::Ply, BUILTIN_BUNNY, None) {
        Ok(Model::Mesh(m)) => Ok(m),
        Ok(other) => anyhow::bail!("built-in bunny: holds a {}, not a mesh", other.kind()),
        Err(e) => anyhow::bail!("built-in bunny: {e}"),
    }
}

/// Whether a path ends in `.txt`, which the readers take as XYZ.
fn is_txt(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("txt"))
}

/// Loads any supported file as one stage (a `.txt` is read as XYZ
/// points, and says so).
pub fn load(events: &Progress, path: &Path) -> Result<Model> {
    if is_txt(path) {
        events.status(format!(
            "reading {} as XYZ points (x y z [nx ny nz] per line)",
            path.display()
        ));
    }
    let step = events.spinner(&format!("reading {}", path.display()));
    let model = lodkit_mesh::io::load(path)?;
    step.finish();
    Ok(model)
}

/// Loads a file that must be a triangle mesh.
pub fn load_mesh(events: &Progress, path: &Path) -> Result<lodkit_mesh::TriMesh> {
    match load(events, path)? {
        Model::Mesh(m) => Ok(m),
        other => anyhow::bail!(
            "{}: holds a {} with no faces, a mesh is needed",
            path.display(),
            other.kind()
        ),
    }
}

/// What an input became: a scene to keep (materials, several meshes,
/// nodes), or a plain model for the one-mesh path.
pub enum Input {
    /// Materials, several parts or named / transformed nodes to keep.
    Scene(Scene),
    /// Everything else: the model exactly as `lodkit_mesh::io::load` reads it.
    Model(Model),
}

/// Whether `output`'s format holds scenes (.glb, .obj).
pub fn holds_scenes(output: &Path) -> bool {
    matches!(Format::from_path(output), Some(Format::Glb | Format::Obj))
}

/// Loads `input`: as a [`Scene`] when `keeps` (the output can hold one and
/// `--merge` is off) and the input has something a single mesh would
/// lose (materials, textures, several meshes, node names or transforms);
/// otherwise as a model, exactly as before. The scene's warnings (a
/// missing texture) are printed.
pub fn load_input(events: &Progress, input: &Path, keeps: bool) -> Result<Input> {
    let fmt = Format::from_path(input);
    if !keeps
        || !matches!(
            fmt,
            Some(Format::Obj | Format::Gltf | Format::Glb | Format::Ply)
        )
    {
        return Ok(Input::Model(load(events, input)?));
    }
    let scene = if fmt == Some(Format::Ply) {
        match load(events, input)? {
            Model::Mesh(m) => lodkit_mesh::io::scene_io::ply_scene(input, m),
            other => return Ok(Input::Model(other)),
        }
    } else {
        // The one-mesh reader first: its checks (instancing bounded by the
        // file's size, world coordinates within ±MAX_COORDINATE after every
        // node transform) hold for the scene path too, and a scene that is
        // one plain mesh takes exactly the old path and bytes.
        let model = load(events, input)?;
        let step = events.spinner(&format!("reading {}", input.display()));
        let s = lodkit_mesh::io::load_scene(input)?;
        step.finish();
        if s.is_plain_mesh() {
            return Ok(Input::Model(model));
        }
        s
    };
    for w in &scene.warnings {
        events.status(format!("warning: {}: {w}", input.display()));
    }
    if scene.is_plain_mesh() {
        let mut scene = scene;
        return Ok(Input::Model(Model::Mesh(scene.meshes.swap_remove(0).mesh)));
    }
    Ok(Input::Scene(scene))
}

/// A one-line summary of a scene for the `wrote` line.
pub fn describe(scene: &Scene) -> String {
    let prims: usize = scene
        .meshes
        .iter()
        .map(|m| {
            let mut ids = m.face_materials.clone();
            ids.sort_unstable();
            ids.dedup();
            ids.len()
        })
        .sum();
    let plural = |n: usize, w: &str| {
        let s = if n == 1 {
            ""
        } else if w.ends_with('h') {
            "es"
        } else {
            "s"
        };
        format!("{n} {w}{s}")
    };
    format!(
        "scene: {}, {}, {}, {}, {}",
        plural(scene.meshes.len(), "mesh"),
        plural(prims, "primitive"),
        plural(scene.face_count(), "triangle"),
        plural(scene.materials.len(), "material"),
        plural(scene.images.len(), "image")
    )
}

/// Reads a calibrated image set (`transforms.json` or a COLMAP text
/// model) and carves it from its silhouettes (`source`): the thinned
/// octree with its attributes. Errors: the set's file and what is wrong
/// with it. Cost: each image decoded once, within the run's pixel budget.
pub fn carve_image_set(
    events: &Progress,
    path: &Path,
    source: lodkit_particles::silhouette::SilhouetteSource,
    options: &lodkit_particles::silhouette::SilhouetteOptions,
    opts: &lodkit_particles::EncodeOptions,
) -> Result<lodkit_particles::silhouette::CarvedOctree> {
    use lodkit_particles::silhouette::{ImageSet, carve_octree};
    let step = events.spinner(&format!("reading the images of {}", path.display()));
    let set = ImageSet::load(path, source)?;
    step.finish();
    let step = events.spinner(&format!(
        "carving {} views from their silhouettes",
        set.calibration.views.len()
    ));
    let c = carve_octree(&set, options, opts)?;
    step.finish();
    Ok(c)
}
