//! `lodkit render`: a picture of a mesh, point cloud, `.mco` cut or `.pop`
//! level, or a calibrated ring of views ([`lodkit::render`]).
use std::path::{Path, PathBuf};

use anyhow::Result;
use clap::Args;
use clap::error::ErrorKind;
use lodkit::limits;
use lodkit::render::{RenderJob, Select, Views};
use lodkit_render::{Normals, RenderOptions};

use crate::ui::Ui;
use crate::ui::value;

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
    #[arg(long, value_name = "AZ,EL", value_parser = parse_view, allow_hyphen_values = true, conflicts_with = "ring",
          default_value_t = View { azimuth: limits::DEFAULT_VIEW.0, elevation: limits::DEFAULT_VIEW.1 })]
    pub view: View,
    /// Image size in pixels, each side in 1..=8192.
    #[arg(long, value_name = "WxH",
          default_value_t = Size(limits::DEFAULT_PICTURE_SIZE.0, limits::DEFAULT_PICTURE_SIZE.1),
          value_parser = parse_size)]
    pub size: Size,
    /// Background colour, three values in 0..=255.
    #[arg(long, value_name = "R,G,B", default_value_t = Rgb(limits::DEFAULT_BACKGROUND), value_parser = parse_rgb)]
    pub background: Rgb,
    /// Vertical field of view in degrees, in [1, 170].
    #[arg(long, value_name = "DEG", default_value_t = limits::DEFAULT_FOV, value_parser = limits::FOV.f32())]
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

/// `WIDTHxHEIGHT` in pixels.
#[derive(Clone, Copy, Debug)]
pub struct Size(pub u32, pub u32);

// As the values are written on the command line (clap shows defaults so).
impl std::fmt::Display for View {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{},{}", self.azimuth, self.elevation)
    }
}

impl std::fmt::Display for Rgb {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let [r, g, b] = self.0;
        write!(f, "{r},{g},{b}")
    }
}

impl std::fmt::Display for Size {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}x{}", self.0, self.1)
    }
}

fn parse_size(s: &str) -> std::result::Result<Size, String> {
    let (lo, hi) = (*limits::PICTURE_SIZE.start(), *limits::PICTURE_SIZE.end());
    value::size(lo, hi)(s).map(|(w, h)| Size(w, h))
}

#[derive(Clone, Debug)]
pub struct Elevations(pub Vec<f32>);

fn numbers(s: &str) -> Option<Vec<f32>> {
    s.split(',').map(|v| v.trim().parse::<f32>().ok()).collect()
}

fn parse_elevation(e: f32) -> std::result::Result<f32, String> {
    if limits::ELEVATION.contains(e as f64) {
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

pub fn run(ui: &Ui, a: &RenderArgs) -> Result<()> {
    let select = match check_kind(a) {
        Kind::Mco => Select::Mco {
            triangles: a.triangles,
            lod: a.lod,
        },
        Kind::Pop => Select::Pop { level: a.level },
        Kind::Geometry => Select::Geometry,
    };
    check_output(a);
    let views = match (a.ring, &a.out) {
        (Some(n), Some(dir)) => Views::Ring {
            per_elevation: n,
            dir: dir.clone(),
            elevations: a.elevations.0.clone(),
        },
        _ => Views::One {
            output: a.output.clone().expect("clap requires -o without --ring"),
            azimuth: a.view.azimuth,
            elevation: a.view.elevation,
        },
    };
    let job = RenderJob {
        input: a.input.clone(),
        select,
        views,
        fov: a.fov,
        options: RenderOptions {
            width: a.size.0,
            height: a.size.1,
            background: a.background.0,
            normals: if a.smooth {
                Normals::Smooth
            } else {
                Normals::Auto
            },
            ..RenderOptions::DEFAULT
        },
    };
    let report = match ui.run(|events| lodkit::render::run(&job, events)) {
        // A cut or level outside the input's range: in clap's manner.
        Err(e) if e.downcast_ref::<lodkit::usage::Usage>().is_some() => usage(e.to_string()),
        r => r?,
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
        report.width,
        report.height,
        report.coverage * 100.0,
        if report.views == 1 { "" } else { " on average" }
    ));
    Ok(())
}
