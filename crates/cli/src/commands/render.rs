//! `lodkit render`: a picture of a mesh, point cloud, `.mco` cut or `.pop`
//! level, or a calibrated ring of views (images, masks, `transforms.json`
//! and a COLMAP text model) for shape from silhouette.
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::Args;
use clap::error::ErrorKind;
use lodkit_mesh::Model;
use lodkit_mesh::io::write_atomic;
use lodkit_render::{
    Camera, CameraRing, Image, MAX_SIZE, Normals, RenderOptions, render, render_points, ring,
};
use serde::Serialize;

use crate::ui::Ui;
use crate::ui::value::{self, Real};

/// Most views per elevation of a ring.
const MAX_RING: u32 = 720;
/// Most elevations of a ring.
const MAX_ELEVATIONS: usize = 16;

#[derive(Args)]
pub struct RenderArgs {
    /// Input: a mesh or point cloud (.ply, .obj, .stl, .gltf, .glb, .xyz,
    /// .pts; points are drawn as discs), a continuous-LOD model (.mco) or a
    /// progressive stream (.pop).
    pub input: PathBuf,
    /// Output PNG of one view (RGBA, opaque: the object over the
    /// background); a .png path that is not the input.
    #[arg(short, long, value_name = "FILE", required_unless_present = "ring",
          value_parser = value::output(&["png"], "a picture"))]
    pub output: Option<PathBuf>,
    /// Camera azimuth and elevation in degrees: azimuth about +Y from the
    /// +Z side towards +X, elevation in [-90, 90] towards +Y.
    #[arg(long, value_name = "AZ,EL", default_value = "30,20", value_parser = parse_view, allow_hyphen_values = true, conflicts_with = "ring")]
    pub view: View,
    /// Image size in pixels, each side in 1..=8192.
    #[arg(long, value_name = "WxH", default_value = "1024x1024", value_parser = value::size(1, MAX_SIZE))]
    pub size: (u32, u32),
    /// Background colour, three values in 0..=255.
    #[arg(long, value_name = "R,G,B", default_value = "255,255,255", value_parser = parse_rgb)]
    pub background: Rgb,
    /// Vertical field of view in degrees, in [1, 170].
    #[arg(long, value_name = "DEG", default_value_t = 35.0, value_parser = Real::closed(1.0, 170.0).f32())]
    pub fov: f32,
    /// Smooth shading from computed vertex normals when the mesh has none
    /// (default: the mesh's normals if it has them, else flat faces).
    #[arg(long)]
    pub smooth: bool,
    /// .mco only: the cut for this triangle budget (default: the finest LOD).
    #[arg(long, value_name = "N", conflicts_with = "lod")]
    pub triangles: Option<usize>,
    /// .mco only: the cut at this LOD number (0 = coarsest).
    #[arg(long, value_name = "N")]
    pub lod: Option<usize>,
    /// .pop only: the octree level to decode and triangulate, in 0..=16
    /// (default: the finest the stream, or its complete chunks, holds).
    #[arg(long, value_name = "L", value_parser = value::int(0u8, 16))]
    pub level: Option<u8>,
    /// Write a ring of N views per elevation into --out instead of one
    /// picture (N in 1..=720).
    #[arg(long, value_name = "N", requires = "out", conflicts_with = "output",
          value_parser = clap::value_parser!(u32).range(1..=MAX_RING as i64))]
    pub ring: Option<u32>,
    /// Folder of the ring: images/, masks/, transforms.json, sparse/0/.
    #[arg(long, value_name = "DIR", requires = "ring")]
    pub out: Option<PathBuf>,
    /// Ring elevations in degrees, comma-separated, each in [-90, 90]
    /// (at most 16).
    #[arg(long, value_name = "LIST", default_value = "20", value_parser = parse_elevations, allow_hyphen_values = true, requires = "ring")]
    pub elevations: Elevations,
    /// Print what was written as JSON.
    #[arg(long)]
    pub json: bool,
}

#[derive(Clone, Copy, Debug)]
pub struct View {
    pub azimuth: f32,
    pub elevation: f32,
}

#[derive(Clone, Copy, Debug)]
pub struct Rgb(pub [u8; 3]);

#[derive(Clone, Debug)]
pub struct Elevations(pub Vec<f32>);

fn numbers(s: &str) -> Option<Vec<f32>> {
    s.split(',').map(|v| v.trim().parse::<f32>().ok()).collect()
}

fn parse_elevation(e: f32) -> std::result::Result<f32, String> {
    if e.is_finite() && (-90.0..=90.0).contains(&e) {
        Ok(e)
    } else {
        Err(format!("elevation {e} is outside [-90, 90] degrees"))
    }
}

fn parse_view(s: &str) -> std::result::Result<View, String> {
    match numbers(s).as_deref() {
        Some(&[az, el]) => {
            if !az.is_finite() {
                return Err(format!("azimuth {az} is not a finite number of degrees"));
            }
            Ok(View {
                azimuth: az,
                elevation: parse_elevation(el)?,
            })
        }
        _ => Err("expected AZ,EL in degrees, e.g. 30,20 (elevation in [-90, 90])".into()),
    }
}

fn parse_rgb(s: &str) -> std::result::Result<Rgb, String> {
    let v: Option<Vec<u8>> = s.split(',').map(|v| v.trim().parse::<u8>().ok()).collect();
    match v.as_deref() {
        Some(&[r, g, b]) => Ok(Rgb([r, g, b])),
        _ => Err("expected R,G,B with each value in 0..=255, e.g. 255,255,255".into()),
    }
}

fn parse_elevations(s: &str) -> std::result::Result<Elevations, String> {
    let v = numbers(s).ok_or_else(|| {
        "expected comma-separated elevations in degrees, each in [-90, 90]".to_string()
    })?;
    if v.is_empty() || v.len() > MAX_ELEVATIONS {
        return Err(format!("expected 1..={MAX_ELEVATIONS} elevations"));
    }
    Ok(Elevations(
        v.into_iter()
            .map(parse_elevation)
            .collect::<std::result::Result<_, _>>()?,
    ))
}

/// What the input is, from its extension.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Kind {
    Mco,
    Pop,
    Geometry,
}

fn kind(path: &Path) -> Kind {
    match path
        .extension()
        .and_then(|e| e.to_str())
        .map(|e| e.to_ascii_lowercase())
        .as_deref()
    {
        Some("mco") => Kind::Mco,
        Some("pop") => Kind::Pop,
        _ => Kind::Geometry,
    }
}

/// A usage error (exit 2), in clap's manner.
fn usage(msg: String) -> ! {
    clap::Error::raw(ErrorKind::ArgumentConflict, format!("{msg}\n")).exit()
}

/// The options that select a cut or level must match the input's kind;
/// checked before anything is read.
fn check_kind(a: &RenderArgs) -> Kind {
    let k = kind(&a.input);
    let name = a.input.display();
    if k != Kind::Mco && (a.triangles.is_some() || a.lod.is_some()) {
        usage(format!(
            "--triangles and --lod apply to .mco models, not to {name}"
        ));
    }
    if k != Kind::Pop && a.level.is_some() {
        usage(format!("--level applies to .pop streams, not to {name}"));
    }
    k
}

/// The picture must not replace the input (the same file through any
/// path or link, which the extension check alone does not rule out for an
/// input named `.png`); the input is listed so that no write of this run
/// replaces it (`lodkit_mesh::io::overwrite_guard`), its textures being
/// listed as they are read. A usage error (exit 2).
fn check_output(a: &RenderArgs) {
    lodkit_mesh::io::overwrite_guard::protect(&a.input);
    if let (Some(out), Ok(i)) = (&a.output, std::fs::metadata(&a.input))
        && let Ok(o) = std::fs::metadata(out)
        && same_file(&i, &o)
    {
        usage(format!(
            "-o {}: is the input {}; give another output path",
            out.display(),
            a.input.display()
        ));
    }
}

/// Whether two files are one (device and inode; never on non-Unix).
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        a.dev() == b.dev() && a.ino() == b.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (a, b);
        false
    }
}

/// What is drawn: a mesh or a point cloud, and a line saying which.
enum Drawable {
    Mesh(lodkit_mesh::TriMesh),
    /// A scene merged into one mesh, drawn with its materials.
    Textured(lodkit_mesh::TriMesh, lodkit_render::Materials),
    Points(lodkit_mesh::PointCloud),
}

fn load(ui: &Ui, a: &RenderArgs, k: Kind) -> Result<(Drawable, String)> {
    let name = a.input.display().to_string();
    match k {
        Kind::Mco => {
            let model = lodkit_mco::McoModel::load(&a.input)?;
            let mut idx = Vec::new();
            let what = if let Some(n) = a.triangles {
                let lod = model.extract_triangles(n, &mut idx);
                format!("LOD {lod} for a budget of {n} triangles")
            } else {
                let lod = a.lod.unwrap_or(model.max_lod());
                if lod > model.max_lod() {
                    usage(format!(
                        "--lod {lod} is outside 0..={} for {name}",
                        model.max_lod()
                    ));
                }
                model.extract_lod(lod, &mut idx);
                format!("LOD {lod}")
            };
            let mesh = model.mesh_from_indices(&idx);
            let what = format!("{what}, {} triangles", mesh.faces.len());
            Ok((Drawable::Mesh(mesh), what))
        }
        Kind::Pop => {
            let bytes = std::fs::read(&a.input).with_context(|| format!("{name}: cannot read"))?;
            let opts = lodkit_particles::DecodeOptions {
                max_level: a.level,
                max_precision: None,
            };
            // A prefix shows the finest level of its complete chunks.
            let d = lodkit_particles::decode_prefix(&bytes, &opts).with_context(|| name.clone())?;
            if d.levels.is_empty() {
                bail!("{name}: the stream holds no complete level");
            }
            let finest = d.levels.len() - 1;
            let r = a.level.map_or(finest, usize::from);
            if r > finest {
                usage(format!("--level {r} is outside 0..={finest} for {name}"));
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
        Kind::Geometry => match super::load_input(ui, &a.input, true)? {
            super::Input::Scene(scene) => {
                let merged = scene.merged();
                let materials = super::render_materials(ui, &name, &scene, merged.face_materials)?;
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
            super::Input::Model(model) => geometry(model),
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

#[derive(Serialize)]
struct Report {
    input: String,
    drawn: String,
    width: u32,
    height: u32,
    /// One view: the output file; a ring: the folder.
    output: String,
    views: usize,
    /// Mean fraction of the image the object covers.
    coverage: f64,
}

pub fn run(ui: &Ui, a: &RenderArgs) -> Result<()> {
    let k = check_kind(a);
    check_output(a);
    let (drawable, drawn) = load(ui, a, k)?;
    let bbox = drawable.bbox();
    if bbox.is_empty() {
        bail!("{}: nothing to draw (no vertices)", a.input.display());
    }
    let opts = RenderOptions {
        width: a.size.0,
        height: a.size.1,
        background: a.background.0,
        normals: if a.smooth {
            Normals::Smooth
        } else {
            Normals::Auto
        },
        ..RenderOptions::DEFAULT
    };
    let (w, h) = (opts.width, opts.height);
    let report = if let (Some(n), Some(dir)) = (a.ring, &a.out) {
        let ring = CameraRing::new(&bbox, n, &a.elevations.0, a.fov, w, h)?;
        for sub in [ring::IMAGES_DIR, ring::MASKS_DIR, ring::COLMAP_DIR] {
            std::fs::create_dir_all(dir.join(sub))
                .with_context(|| format!("{}: cannot create", dir.join(sub).display()))?;
        }
        let step = ui.stage(&format!("rendering {} views", ring.views.len()));
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
        Report {
            input: a.input.display().to_string(),
            drawn,
            width: w,
            height: h,
            output: dir.display().to_string(),
            views: ring.views.len(),
            coverage: coverage / ring.views.len() as f64,
        }
    } else {
        let out = a.output.as_ref().expect("clap requires -o without --ring");
        let cam = Camera::frame(
            &drawable.points(),
            a.view.azimuth,
            a.view.elevation,
            a.fov,
            w as f32 / h as f32,
        )?;
        let step = ui.spinner("rendering");
        let img = drawable.draw(&cam, &opts)?;
        let coverage = img.mask().coverage();
        write_atomic(out, &img.over(opts.background).to_png()?)?;
        step.finish();
        Report {
            input: a.input.display().to_string(),
            drawn,
            width: w,
            height: h,
            output: out.display().to_string(),
            views: 1,
            coverage,
        }
    };
    if a.json {
        return super::print_json(&report);
    }
    ui.status(format!(
        "wrote {} ({} view{} of {}, {}: {}x{}, object covers {:.1} % of the image{})",
        report.output,
        report.views,
        if report.views == 1 { "" } else { "s" },
        report.input,
        report.drawn,
        w,
        h,
        report.coverage * 100.0,
        if report.views == 1 { "" } else { " on average" }
    ));
    Ok(())
}
