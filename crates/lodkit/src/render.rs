//! The render job (`lodkit render`): a picture of a mesh, point cloud,
//! textured scene, `.mco` cut or `.pop` level, or a calibrated ring of
//! views (images, masks, `transforms.json` and a COLMAP text model) for
//! shape from silhouette.
use std::path::PathBuf;

use anyhow::{Context, Result, bail};
use lodkit_mesh::Model;
use lodkit_mesh::io::cameras as ring;
use lodkit_mesh::io::write_atomic;
use lodkit_render::{Camera, CameraRing, Image, RenderOptions, render, render_points};
use serde::Serialize;

use crate::progress::Progress;
use crate::usage::usage;

/// Which part of the input is drawn, by its kind.
#[derive(Debug, Clone, Copy)]
pub enum Select {
    /// A `.mco` model: the cut for a triangle budget, or at a LOD number
    /// (default: the finest).
    Mco {
        triangles: Option<usize>,
        lod: Option<usize>,
    },
    /// A `.pop` stream: one octree level (default: the finest it, or its
    /// complete chunks, holds).
    Pop { level: Option<u8> },
    /// Any mesh, cloud or scene `lodkit_mesh::io` reads.
    Geometry,
}

/// The views drawn.
#[derive(Debug, Clone)]
pub enum Views {
    /// One picture from azimuth and elevation (degrees), written as PNG.
    One {
        output: PathBuf,
        azimuth: f32,
        elevation: f32,
    },
    /// `per_elevation` views at each elevation (degrees), with masks and
    /// calibration files, in `dir`.
    Ring {
        per_elevation: u32,
        dir: PathBuf,
        elevations: Vec<f32>,
    },
}

/// One render: what [`run`] reads, draws and writes.
#[derive(Debug, Clone)]
pub struct RenderJob {
    pub input: PathBuf,
    pub select: Select,
    pub views: Views,
    /// Vertical field of view in degrees.
    pub fov: f32,
    /// Image size, background and shading.
    pub options: RenderOptions,
}

/// What is drawn: a mesh or a point cloud, and a line saying which.
enum Drawable {
    Mesh(lodkit_mesh::TriMesh),
    /// A scene merged into one mesh, drawn with its materials.
    Textured(lodkit_mesh::TriMesh, lodkit_render::Materials),
    Points(lodkit_mesh::PointCloud),
}

fn load(events: &Progress, a: &RenderJob) -> Result<(Drawable, String)> {
    let name = a.input.display().to_string();
    match a.select {
        Select::Mco { triangles, lod } => {
            let model = lodkit_mco::McoModel::load(&a.input)?;
            let mut idx = Vec::new();
            let what = if let Some(n) = triangles {
                let lod = model.extract_triangles(n, &mut idx);
                format!("LOD {lod} for a budget of {n} triangles")
            } else {
                let lod = lod.unwrap_or(model.max_lod());
                if lod > model.max_lod() {
                    return Err(usage(format!(
                        "--lod {lod} is outside 0..={} for {name}",
                        model.max_lod()
                    )));
                }
                model.extract_lod(lod, &mut idx);
                format!("LOD {lod}")
            };
            let mesh = model.mesh_from_indices(&idx);
            let what = format!("{what}, {} triangles", mesh.faces.len());
            Ok((Drawable::Mesh(mesh), what))
        }
        Select::Pop { level } => {
            let bytes = std::fs::read(&a.input).with_context(|| format!("{name}: cannot read"))?;
            let opts = lodkit_particles::DecodeOptions {
                max_level: level,
                max_precision: None,
            };
            // A prefix shows the finest level of its complete chunks.
            let d = lodkit_particles::decode_prefix(&bytes, &opts).with_context(|| name.clone())?;
            if d.levels.is_empty() {
                bail!("{name}: the stream holds no complete level");
            }
            let finest = d.levels.len() - 1;
            let r = level.map_or(finest, usize::from);
            if r > finest {
                return Err(usage(format!(
                    "--level {r} is outside 0..={finest} for {name}"
                )));
            }
            let s = d.surface(r as u8).with_context(|| name.clone())?;
            let t =
                lodkit_particles::triangulate(&s, &lodkit_particles::TriangulateOptions::DEFAULT);
            let what = format!(
                "level {r}: {} particles, {} triangles",
                s.cells.len(),
                t.mesh.faces.len()
            );
            Ok((Drawable::Mesh(t.mesh), what))
        }
        Select::Geometry => match crate::input::load_input(events, &a.input, true)? {
            crate::input::Input::Scene(scene) => {
                let merged = scene.merged();
                let materials = crate::materials::render_materials(
                    events,
                    &name,
                    &scene,
                    merged.face_materials,
                )?;
                let mesh = merged.mesh;
                let n = |k: usize, w: &str| format!("{k} {w}{}", if k == 1 { "" } else { "s" });
                let what = format!(
                    "{}, {}, {}",
                    n(mesh.faces.len(), "triangle"),
                    n(materials.looks.len(), "material"),
                    n(materials.textures.len(), "texture")
                );
                Ok((Drawable::Textured(mesh, materials), what))
            }
            crate::input::Input::Model(model) => geometry(model),
            other => bail!(
                "{}: holds a {}, not a mesh or point cloud to draw",
                a.input.display(),
                other.kind()
            ),
        },
    }
}

/// A model as it is drawn: a mesh, or points as discs.
fn geometry(model: Model) -> Result<(Drawable, String)> {
    match model {
        Model::Mesh(m) => {
            let what = format!("{} triangles", m.faces.len());
            Ok((Drawable::Mesh(m), what))
        }
        Model::Points(p) => {
            let what = format!("{} points as discs", p.len());
            Ok((Drawable::Points(p), what))
        }
        Model::Range(r) => {
            let p = r.to_point_cloud();
            let what = format!("range image, {} points as discs", p.len());
            Ok((Drawable::Points(p), what))
        }
    }
}

impl Drawable {
    /// The points that frame the picture: a mesh's referenced vertices
    /// (a scan's stray unreferenced vertices are not drawn).
    fn points(&self) -> Vec<lodkit_mesh::glam::Vec3> {
        match self {
            Drawable::Mesh(m) | Drawable::Textured(m, _) => {
                let mut used = vec![false; m.positions.len()];
                for f in &m.faces {
                    for &v in f {
                        used[v as usize] = true;
                    }
                }
                m.positions
                    .iter()
                    .zip(&used)
                    .filter_map(|(p, &u)| u.then_some(*p))
                    .collect()
            }
            Drawable::Points(p) => p.positions.clone(),
        }
    }
    fn bbox(&self) -> lodkit_mesh::Aabb {
        lodkit_mesh::Aabb::from_points(&self.points())
    }
    fn draw(&self, cam: &Camera, opts: &RenderOptions) -> Result<Image> {
        Ok(match self {
            Drawable::Mesh(m) => render(m, cam, opts)?,
            Drawable::Textured(m, t) => lodkit_render::render_textured(m, t, cam, opts)?,
            Drawable::Points(p) => render_points(p, cam, opts)?,
        })
    }
}

/// What [`run`] drew and wrote (`lodkit render --json`).
#[derive(Debug, Serialize)]
pub struct RenderReport {
    pub input: String,
    /// What was drawn, in words (`LOD 7, 5000 triangles`).
    pub drawn: String,
    pub width: u32,
    pub height: u32,
    /// One view: the output file; a ring: the folder.
    pub output: String,
    pub views: usize,
    /// Mean fraction of the image the object covers.
    pub coverage: f64,
}

/// Draws `a.input` (a mesh, cloud, scene with its textures, a `.mco` cut
/// or a `.pop` level, as `a.select` says) with `a.options`: one view
/// written as a PNG, or a ring of views with masks and calibration files
/// (NeRF `transforms.json`, COLMAP text) in a folder, each file written
/// atomically. Errors: the input named with what is wrong; a cut or
/// level outside the input's range is a [`crate::usage::Usage`]. Cost: one
/// rasterisation a view.
pub fn run(a: &RenderJob, events: &Progress) -> Result<RenderReport> {
    let (drawable, drawn) = load(events, a)?;
    let bbox = drawable.bbox();
    if bbox.is_empty() {
        bail!("{}: nothing to draw (no vertices)", a.input.display());
    }
    let opts = a.options;
    let (w, h) = (opts.width, opts.height);
    let report = match &a.views {
        Views::Ring {
            per_elevation: n,
            dir,
            elevations,
        } => {
            let ring = CameraRing::new(&bbox, *n, elevations, a.fov, w, h)?;
            for sub in [ring::IMAGES_DIR, ring::MASKS_DIR, ring::COLMAP_DIR] {
                std::fs::create_dir_all(dir.join(sub))
                    .with_context(|| format!("{}: cannot create", dir.join(sub).display()))?;
            }
            let step = events.stage(&format!("rendering {} views", ring.views.len()));
            let mut coverage = 0.0;
            for (i, v) in ring.views.iter().enumerate() {
                let img = drawable.draw(&v.camera, &opts)?;
                let mask = img.mask();
                coverage += mask.coverage();
                let name = ring.file_name(i);
                write_atomic(&dir.join(ring::IMAGES_DIR).join(&name), &img.to_png()?)?;
                write_atomic(&dir.join(ring::MASKS_DIR).join(&name), &mask.to_png()?)?;
            }
            for (path, text) in ring.calibration_files() {
                write_atomic(&dir.join(path), text.as_bytes())?;
            }
            step.finish();
            RenderReport {
                input: a.input.display().to_string(),
                drawn,
                width: w,
                height: h,
                output: dir.display().to_string(),
                views: ring.views.len(),
                coverage: coverage / ring.views.len() as f64,
            }
        }
        Views::One {
            output: out,
            azimuth,
            elevation,
        } => {
            let cam = Camera::frame(
                &drawable.points(),
                *azimuth,
                *elevation,
                a.fov,
                w as f32 / h as f32,
            )?;
            let step = events.spinner("rendering");
            let img = drawable.draw(&cam, &opts)?;
            let coverage = img.mask().coverage();
            write_atomic(out, &img.over(opts.background).to_png()?)?;
            step.finish();
            RenderReport {
                input: a.input.display().to_string(),
                drawn,
                width: w,
                height: h,
                output: out.display().to_string(),
                views: 1,
                coverage,
            }
        }
    };
    Ok(report)
}
