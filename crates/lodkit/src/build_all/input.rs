//! Every input kind `build` takes, reduced to what its stages need: a
//! surface for the HQMS chain and the measurements, and the samples the
//! progressive stream is built from.
//!
//! - a **mesh** (any format) is the surface; the stream samples it;
//! - a **point cloud** (`.xyz`, `.pts`, a PLY without faces), a **range
//!   image** (range-grid PLY) or a **scan set** (a `.conf`, or a folder of
//!   range images, posed by the one `.conf` in it if there is one) is
//!   first reconstructed as a marching cube octree (`lodkit_mco`, as
//!   `lodkit mco build` does); its full-resolution cut is the surface, and
//!   the stream encodes that surface (a direct triangulation of raw
//!   points at their own spacing is full of holes);
//! - a **calibrated image set** (a NeRF `transforms.json`, a COLMAP
//!   `cameras.txt` / `images.txt`) is carved from its silhouettes into
//!   octree particles (`lodkit pop encode --silhouettes`); the finest
//!   level's triangulation is the surface, the coloured particles are the
//!   stream's points.

use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use lodkit_mco::McoModel;
use lodkit_mesh::{Model, TriMesh};

use crate::input::Input;
use crate::progress::Progress;

/// How the input reached the surface the chain starts from.
pub enum InputPath {
    /// The input is a mesh.
    Mesh,
    /// The input was reconstructed: what it was (`"point cloud"`, `"range
    /// image"`, `"scan set of 8 range images"`).
    Reconstructed(String),
    /// A calibrated image set carved into octree particles: what it was
    /// (`"calibrated image set of 36 views, carved … at R = 8"`), and the
    /// octree depth it was carved at.
    Carved(String, u8),
}

/// The loaded input.
pub struct BuildInput {
    /// Output file stem.
    pub name: String,
    /// The surface: the mesh itself, or the reconstruction.
    pub surface: TriMesh,
    /// What the progressive stream encodes: the mesh, the reconstructed
    /// surface, or the carved particles.
    pub stream_source: Model,
    /// The input's own samples (a mesh's vertices, a cloud's points, range
    /// images' valid pixels, carved particles) and what they are: the count
    /// each product's finest level is held against.
    pub samples: (usize, &'static str),
    /// The reconstruction, for non-mesh inputs.
    pub reconstruction: Option<McoModel>,
    /// Which path the input took.
    pub path: InputPath,
    /// The input as a scene, when it has materials, textures or parts a
    /// single mesh would lose (and `--merge` is off): the input GLB and the
    /// HQMS chain keep them; `surface` is then the scene merged.
    pub scene: Option<lodkit_mesh::Scene>,
}

/// Loads `path` (any kind; see the module docs) and reconstructs it when
/// it is not a mesh; a mesh with materials, textures or parts is kept as a
/// scene unless `merge`. Errors name the file.
pub fn load(events: &Progress, path: &Path, merge: bool) -> Result<BuildInput> {
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .filter(|s| !s.is_empty())
        .unwrap_or_else(|| "model".into());
    if path.is_dir() && !lodkit_mesh::io::cameras::is_calibration(path) {
        let (what, models) = scan_folder(events, path)?;
        return reconstruct(events, path, name, what, &models);
    }
    let model = match crate::input::load_input(events, path, !merge)? {
        Input::Silhouettes(calibration) => return carve(events, path, name, calibration),
        Input::Scans(set) => {
            let what = format!("scan set of {} range images", set.scans.len());
            let models: Vec<Model> = set
                .scans
                .into_iter()
                .map(|(_, r)| Model::Range(r))
                .collect();
            return reconstruct(events, path, name, what, &models);
        }
        Input::Scene(scene) => {
            let surface = scene.merged().mesh;
            if surface.faces.is_empty() {
                bail!("{}: the mesh has no faces", path.display());
            }
            return Ok(BuildInput {
                name,
                samples: (surface.positions.len(), "vertices"),
                stream_source: Model::Mesh(surface.clone()),
                surface,
                reconstruction: None,
                path: InputPath::Mesh,
                scene: Some(scene),
            });
        }
        Input::Model(model) => model,
    };
    match model {
        Model::Mesh(m) => {
            if m.faces.is_empty() {
                bail!("{}: the mesh has no faces", path.display());
            }
            Ok(BuildInput {
                name,
                samples: (m.positions.len(), "vertices"),
                stream_source: Model::Mesh(m.clone()),
                surface: m,
                reconstruction: None,
                path: InputPath::Mesh,
                scene: None,
            })
        }
        other => {
            let what = other.kind().to_string();
            reconstruct(events, path, name, what, &[other])
        }
    }
}

/// A folder of range images: the `.conf` in it when there is exactly one,
/// else every `.ply` in it (name order), each as its file poses it.
fn scan_folder(events: &Progress, dir: &Path) -> Result<(String, Vec<Model>)> {
    let mut confs = Vec::new();
    let mut plys: Vec<PathBuf> = Vec::new();
    for e in
        std::fs::read_dir(dir).with_context(|| format!("{}: cannot read folder", dir.display()))?
    {
        let p = e
            .with_context(|| format!("{}: cannot read folder", dir.display()))?
            .path();
        if crate::input::is_scan_set(&p) {
            confs.push(p);
        } else if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("ply")) {
            plys.push(p);
        }
    }
    match confs.len() {
        1 => {
            let set = crate::input::load_scans(events, &confs[0])?;
            return Ok((
                format!(
                    "scan set of {} range images ({})",
                    set.scans.len(),
                    confs[0].display()
                ),
                set.scans
                    .into_iter()
                    .map(|(_, r)| Model::Range(r))
                    .collect(),
            ));
        }
        0 => {}
        n => bail!(
            "{}: holds {n} .conf files; give the one to build as the input",
            dir.display()
        ),
    }
    plys.sort();
    if plys.is_empty() {
        bail!(
            "{}: holds no range image (.ply) and no .conf",
            dir.display()
        );
    }
    let mut models = Vec::with_capacity(plys.len());
    for p in &plys {
        match crate::input::load(events, p)? {
            m @ Model::Range(_) => models.push(m),
            other => bail!(
                "{}: holds a {}, not a range image (a scan folder holds range-grid PLYs)",
                p.display(),
                other.kind()
            ),
        }
    }
    Ok((format!("scan set of {} range images", models.len()), models))
}

/// Reconstructs `models` as a marching cube octree; its full cut is the
/// surface, and the stream's source.
fn reconstruct(
    events: &Progress,
    path: &Path,
    name: String,
    what: String,
    models: &[Model],
) -> Result<BuildInput> {
    let step = events.spinner(&format!("reconstructing the {what}"));
    let model = lodkit_mco::build_from_models(models, &lodkit_mco::Options::default())
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    let surface = model.mesh_at_lod(model.max_lod());
    step.finish();
    if surface.faces.is_empty() {
        bail!("{}: the reconstruction has no triangles", path.display());
    }
    let samples = models
        .iter()
        .map(|m| crate::measure::sample_count(m).0)
        .sum();
    let unit = match models {
        [Model::Points(_)] => "points",
        _ => "samples",
    };
    Ok(BuildInput {
        name,
        samples: (samples, unit),
        stream_source: Model::Mesh(surface.clone()),
        surface,
        reconstruction: Some(model),
        path: InputPath::Reconstructed(what),
        scene: None,
    })
}

/// A calibrated image set: carved (default depth and silhouette source),
/// its finest level triangulated.
fn carve(
    events: &Progress,
    path: &Path,
    name: String,
    calibration: lodkit_mesh::io::cameras::Calibration,
) -> Result<BuildInput> {
    // `ring/transforms.json`, `ring/sparse/0/cameras.txt`: named `ring`.
    let name = path
        .ancestors()
        .skip(1)
        .filter_map(|p| p.file_name())
        .map(|n| n.to_string_lossy().into_owned())
        .find(|n| n != "sparse" && n.parse::<u32>().is_err())
        .unwrap_or(name);
    let opts = lodkit_particles::EncodeOptions::DEFAULT;
    let c = crate::input::carve(
        events,
        calibration,
        lodkit_particles::silhouette::SilhouetteSource::Auto,
        &lodkit_particles::silhouette::SilhouetteOptions {
            bbox: None,
            margin: 1.0,
        },
        &opts,
    )?;
    let e = lodkit_particles::silhouette::encode_carved(&c, &opts)?;
    let d = lodkit_particles::decode(&e.bytes, &lodkit_particles::DecodeOptions::default())
        .with_context(|| path.display().to_string())?;
    let surface = d
        .triangulate(
            d.finest_level(),
            &lodkit_particles::TriangulateOptions::DEFAULT,
        )
        .with_context(|| path.display().to_string())?
        .mesh;
    if surface.faces.is_empty() {
        bail!("{}: the carved hull has no triangles", path.display());
    }
    let particles = c.particles();
    Ok(BuildInput {
        name,
        surface,
        samples: (particles.positions.len(), "particles"),
        stream_source: Model::Points(particles),
        reconstruction: None,
        path: InputPath::Carved(
            format!(
                "calibrated image set of {} views, carved from its silhouettes at R = {}",
                c.report.views, c.report.depth
            ),
            c.report.depth,
        ),
        scene: None,
    })
}
