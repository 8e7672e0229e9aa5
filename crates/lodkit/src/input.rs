//! Loading inputs: one [`Input`] for every kind lodkit reads — a mesh, a
//! point cloud or a range image (any file the mesh crate reads), a scene
//! kept when the output can hold it (meshes with materials, parts and
//! nodes), a scan set (range images posed by a `.conf`) and a calibrated
//! image set (NeRF `transforms.json`, COLMAP `cameras.txt` /
//! `images.txt`) carved from its silhouettes — and one loader,
//! [`load_input`], that tells them apart; beside it the built-in Stanford
//! bunny. Every loader names the file in its errors and reports its
//! reading as a stage.
use std::path::{Path, PathBuf};

use anyhow::Result;
use lodkit_mesh::io::Format;
use lodkit_mesh::io::cameras::{self, Calibration};
use lodkit_mesh::{Model, RangeImage, Scene};

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
/// nodes), a plain model for the one-mesh path, a scan set or a
/// calibrated image set.
pub enum Input {
    /// Materials, several parts or named / transformed nodes to keep.
    Scene(Scene),
    /// A mesh, point cloud or range image, exactly as
    /// `lodkit_mesh::io::load` reads it.
    Model(Model),
    /// Range images with their poses, as a `.conf` lists them.
    Scans(ScanSet),
    /// Calibrated views (NeRF `transforms.json`, a COLMAP text model),
    /// their images not yet read: [`carve`] reads and carves them.
    Silhouettes(Calibration),
}

impl Input {
    /// What the input holds, for messages: `mesh`, `point cloud`, `range
    /// image` (as [`Model::kind`]), `scene`, `scan set`, `calibrated image
    /// set`.
    pub fn kind(&self) -> &'static str {
        match self {
            Input::Scene(_) => "scene",
            Input::Model(m) => m.kind(),
            Input::Scans(_) => "scan set",
            Input::Silhouettes(_) => "calibrated image set",
        }
    }
}

/// Range images with their poses: what a `.conf` lists (the Stanford
/// scanning repository's layout, and what `lodkit scan` writes).
#[derive(Debug, Clone)]
pub struct ScanSet {
    /// The `.conf` read.
    pub conf: PathBuf,
    /// Each scan's path and its range image, pose set, in the file's order.
    pub scans: Vec<(PathBuf, RangeImage)>,
}

/// Whether a path names a scan set (ends in `.conf`).
pub fn is_scan_set(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("conf"))
}

/// Reads the scan set a `.conf` lists (every scan loaded, each inside the
/// `.conf`'s folder) as one stage. Errors: the `.conf` or the scan named,
/// and what is wrong. Cost: every scan read once.
pub fn load_scans(events: &Progress, conf: &Path) -> Result<ScanSet> {
    let step = events.spinner(&format!("reading {}", conf.display()));
    let scans = lodkit_mesh::io::conf::load_scans(conf)?;
    step.finish();
    Ok(ScanSet {
        conf: conf.to_path_buf(),
        scans,
    })
}

/// Reads a calibration (a `transforms.json` or any `.json` in its layout,
/// a COLMAP `cameras.txt` / `images.txt`, or a folder holding one) as one
/// stage; its images are read by [`carve`]. Errors: one line naming the
/// file and the camera. Cost: the file's size (plus one image header when
/// a NeRF file gives no image size).
pub fn load_silhouettes(events: &Progress, path: &Path) -> Result<Calibration> {
    let step = events.spinner(&format!("reading the cameras of {}", path.display()));
    let calibration = cameras::read(path)?;
    step.finish();
    Ok(calibration)
}

/// Whether `output`'s format holds scenes (.glb, .obj).
pub fn holds_scenes(output: &Path) -> bool {
    matches!(Format::from_path(output), Some(Format::Glb | Format::Obj))
}

/// Loads `input`, whatever it holds: a `.conf` as a scan set
/// ([`load_scans`]); a `transforms.json`, `cameras.txt` or `images.txt`
/// as a calibrated image set ([`load_silhouettes`]); any other file as a
/// [`Scene`] when `keeps` (the output can hold one and `--merge` is off)
/// and the input has something a single mesh would lose (materials,
/// textures, several meshes, node names or transforms), else as a model.
/// The scene's warnings (a missing texture) are sent as statuses.
///
/// Errors: one line naming the file (or the scan, or the camera) and what
/// is wrong. Cost: the file read once (a scan set: every scan; a
/// calibration: its text, the images are read by [`carve`]).
pub fn load_input(events: &Progress, input: &Path, keeps: bool) -> Result<Input> {
    if is_scan_set(input) {
        return Ok(Input::Scans(load_scans(events, input)?));
    }
    if cameras::is_calibration(input) {
        return Ok(Input::Silhouettes(load_silhouettes(events, input)?));
    }
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
            Model::Mesh(m) => lodkit_mesh::io::ply_scene(input, m),
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
    let calibration = load_silhouettes(events, path)?;
    carve(events, calibration, source, options, opts)
}

/// Reads the images of a calibration ([`load_silhouettes`], or
/// [`Input::Silhouettes`]) and carves the views from their silhouettes
/// (`source`): the thinned octree with its attributes. Errors: the
/// calibration's file, the camera and what is wrong. Cost: each image
/// decoded once, within the run's pixel budget.
pub fn carve(
    events: &Progress,
    calibration: Calibration,
    source: lodkit_particles::silhouette::SilhouetteSource,
    options: &lodkit_particles::silhouette::SilhouetteOptions,
    opts: &lodkit_particles::EncodeOptions,
) -> Result<lodkit_particles::silhouette::CarvedOctree> {
    use lodkit_particles::silhouette::{ImageSet, carve_octree};
    let step = events.spinner(&format!(
        "reading the images of {}",
        calibration.file.display()
    ));
    let set = ImageSet::from_calibration(calibration, source)?;
    step.finish();
    let step = events.spinner(&format!(
        "carving {} views from their silhouettes",
        set.calibration.views.len()
    ));
    let c = carve_octree(&set, options, opts)?;
    step.finish();
    Ok(c)
}
