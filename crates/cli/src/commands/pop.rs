//! `lodkit pop encode|decode|stats`: progressive octree particle streams
//! (`.pop`, see `docs/formats/pop.md` and the `lodkit-particles` crate).
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::{Args, Subcommand, ValueEnum};
use lodkit::stream_encode::{StreamSource, encode_model};
use lodkit_mesh::Model;
use lodkit_mesh::io::WriteOptions;
use lodkit_particles::silhouette::{
    CarvedOctree, SilhouetteOptions, SilhouetteSource, encode_carved,
};
use lodkit_particles::{
    DecodeOptions, EncodeOptions, Mode, Placement, ThinningOptions, TriangulateOptions, decode,
    decode_prefix, triangulate,
};
use serde::Serialize;

use crate::ui::Ui;
use crate::ui::value::{self, Real};

#[derive(Subcommand)]
pub enum PopCommand {
    /// Encode a mesh, point cloud or range image as a progressive `.pop` stream.
    #[command(
        after_help = "Examples:\n  lodkit pop encode bunny.ply -o bunny.pop\n  lodkit pop encode scan.ply -o scan.pop --depth 9 --precision 14 --mode baseline\n  lodkit pop encode cloud.ply -o cloud.pop --raw"
    )]
    Encode(EncodeArgs),
    /// Decode one level of a `.pop` stream to a mesh (or its particles).
    #[command(
        after_help = "Examples:\n  lodkit pop decode bunny.pop -o bunny.ply            # the finest level it holds\n  lodkit pop decode bunny.pop --level 5 -o bunny5.ply\n  lodkit pop decode bunny.pop --level 6 --precision 10 --points -o p.ply\n  head -c 20000 bunny.pop > part.pop; lodkit pop decode part.pop -o part.ply"
    )]
    Decode(DecodeArgs),
    /// Per-level figures of a `.pop` stream (the paper's Table 1 and bits per particle).
    #[command(
        after_help = "Examples:\n  lodkit pop stats bunny.pop\n  lodkit pop stats bunny.pop --json"
    )]
    Stats {
        file: PathBuf,
        /// Print the figures as JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Clone, Copy, ValueEnum)]
pub enum ModeArg {
    /// The paper's raw hierarchical bits (§7.1).
    Baseline,
    /// Context-adaptive range coding.
    Entropy,
}

#[derive(Clone, Copy, ValueEnum)]
pub enum PlacementArg {
    /// The mean of the leaf's samples (§5.5).
    Mean,
    /// On the samples' plane at the leaf's middle column (cheap tangential bits).
    Column,
}

#[derive(Args)]
pub struct EncodeArgs {
    /// Input mesh, point cloud or range image. A cloud or range image is
    /// coded from its reconstructed surface, at about one particle per
    /// sample (see --raw).
    #[arg(required_unless_present = "silhouettes")]
    pub input: Option<PathBuf>,
    /// Code a cloud's or range image's samples as they are, one particle
    /// per occupied leaf (faster; at the samples' own detail the direct
    /// triangulation of raw points has holes).
    #[arg(long, conflicts_with = "silhouettes")]
    pub raw: bool,
    /// Carve the octree from calibrated photographs instead: a NeRF
    /// transforms.json or a COLMAP cameras.txt / images.txt (or a folder
    /// holding one); silhouettes from mask images, alpha or --key-colour.
    #[arg(long, value_name = "CAMERAS_FILE", conflicts_with = "input")]
    pub silhouettes: Option<PathBuf>,
    #[command(flatten)]
    pub carve: CarveArgs,
    /// Output `.pop` file.
    #[arg(short, long, value_parser = value::output(&["pop"], "a progressive stream"))]
    pub output: PathBuf,
    /// Octree resolution R, in 1..=12 (default: from the sampling density).
    #[arg(long, value_parser = value::range(lodkit::limits::POP_DEPTH))]
    pub depth: Option<u8>,
    /// Vertex precision N in bits, in 1..=16 and at least R (default 12,
    /// raised to R when R is larger).
    #[arg(long, value_parser = value::range(lodkit::limits::POP_BITS))]
    pub precision: Option<u8>,
    #[arg(long, value_enum, default_value_t = ModeArg::Entropy)]
    pub mode: ModeArg,
    /// Vertex placement in entropy mode (default: column; the baseline
    /// codes means).
    #[arg(long, value_enum)]
    pub placement: Option<PlacementArg>,
    /// Also thin the outer boundary (with the hole-preventing test).
    #[arg(long)]
    pub outer_thinning: bool,
    /// With --outer-thinning: relax it below this level (1–16), or `auto`:
    /// the level that leaves the coarse levels fewest non-manifold triangles.
    #[arg(long, default_value = "auto", value_parser = parse_relax, requires = "outer_thinning")]
    pub relax_below: u8,
    /// Also code particle normals.
    #[arg(long)]
    pub normals: bool,
    /// Drop the input's colours.
    #[arg(long)]
    pub no_colours: bool,
    /// Print the encoding's figures as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Options of `--silhouettes` (shared with `lodkit build`).
#[derive(Args, Clone, Default)]
pub struct CarveArgs {
    /// Silhouettes by background colour: pixels within --key-tolerance of
    /// this colour (hex RRGGBB) are background.
    #[arg(long, value_name = "RRGGBB", value_parser = parse_hex_colour)]
    pub key_colour: Option<[u8; 3]>,
    /// Largest per-channel difference from --key-colour still background,
    /// in 0..=255.
    #[arg(long, value_name = "N", default_value_t = 24, value_parser = value::int(0u8, 255), requires = "key_colour")]
    pub key_tolerance: u8,
    /// Silhouettes from the images' alpha channel even where masks exist.
    #[arg(long, conflicts_with = "key_colour")]
    pub alpha: bool,
    /// The box to carve, world units (default: the cameras' common view).
    #[arg(long, value_name = "X0,Y0,Z0,X1,Y1,Z1", value_parser = parse_bbox, allow_hyphen_values = true)]
    pub bbox: Option<[f32; 6]>,
    /// Footprint margin in pixels, in [0, 16]: how far a silhouette edge
    /// may pass the object.
    #[arg(long, value_name = "PIXELS", default_value_t = 1.0, value_parser = Real::closed(0.0, 16.0).f32())]
    pub margin: f32,
}

impl CarveArgs {
    pub fn source(&self) -> SilhouetteSource {
        match (self.key_colour, self.alpha) {
            (Some(colour), _) => SilhouetteSource::Key {
                colour,
                tolerance: self.key_tolerance,
            },
            (None, true) => SilhouetteSource::Alpha,
            (None, false) => SilhouetteSource::Auto,
        }
    }

    pub fn options(&self) -> SilhouetteOptions {
        SilhouetteOptions {
            bbox: self.bbox.map(|b| {
                (
                    lodkit_mesh::glam::Vec3::new(b[0], b[1], b[2]),
                    lodkit_mesh::glam::Vec3::new(b[3], b[4], b[5]),
                )
            }),
            margin: self.margin,
        }
    }
}

fn parse_hex_colour(s: &str) -> std::result::Result<[u8; 3], String> {
    let h = s.trim().trim_start_matches('#');
    if h.len() != 6 || !h.bytes().all(|c| c.is_ascii_hexdigit()) {
        return Err("expected a colour as six hex digits RRGGBB, e.g. 00ff00".into());
    }
    let byte = |i: usize| u8::from_str_radix(&h[i..i + 2], 16).map_err(|e| e.to_string());
    Ok([byte(0)?, byte(2)?, byte(4)?])
}

fn parse_bbox(s: &str) -> std::result::Result<[f32; 6], String> {
    let v: Option<Vec<f32>> = s.split(',').map(|v| v.trim().parse::<f32>().ok()).collect();
    match v.as_deref() {
        Some(&[a, b, c, d, e, f])
            if [a, b, c, d, e, f]
                .iter()
                .all(|x| x.is_finite() && x.abs() <= 1e15)
                && a < d
                && b < e
                && c < f =>
        {
            Ok([a, b, c, d, e, f])
        }
        _ => Err(
            "expected X0,Y0,Z0,X1,Y1,Z1: six finite numbers with each minimum below its maximum"
                .into(),
        ),
    }
}

/// Reads an image set and carves it (`lodkit pop encode --silhouettes`,
/// `lodkit build`): the thinned octree with its attributes.
pub fn carve_image_set(
    ui: &Ui,
    path: &Path,
    carve: &CarveArgs,
    opts: &EncodeOptions,
) -> Result<CarvedOctree> {
    ui.run(|events| {
        lodkit::input::carve_image_set(events, path, carve.source(), &carve.options(), opts)
    })
}

#[derive(Args)]
pub struct DecodeArgs {
    /// Input `.pop` file.
    pub input: PathBuf,
    /// Level r to decode, in 0..=16 (default: the finest the file holds,
    /// which for a prefix is the finest of its complete chunks).
    #[arg(long, value_parser = value::int(0u8, *lodkit::limits::POP_BITS.end()))]
    pub level: Option<u8>,
    /// Vertex precision to decode, in 1..=16 (default: all present).
    #[arg(long, value_parser = value::range(lodkit::limits::POP_BITS))]
    pub precision: Option<u8>,
    /// Output file (.ply, .obj, .stl, .glb; with --points also .xyz, .pts).
    #[arg(short, long, value_parser = value::output(&["ply", "obj", "stl", "glb", "xyz", "pts"], "the decoded level"))]
    pub output: PathBuf,
    /// Write the particles as a point cloud instead of triangulating.
    #[arg(long)]
    pub points: bool,
    /// Decimate during triangulation (§6.3): merge cubes joined by edges
    /// shorter than this fraction of the cube size, in [0, 1].
    #[arg(long, value_name = "FRACTION", value_parser = lodkit::limits::POP_DECIMATE.f32(), conflicts_with = "points")]
    pub decimate: Option<f32>,
    /// Refuse a file whose last chunk is cut short (default: decode every
    /// complete chunk before the cut and say where it stopped).
    #[arg(long)]
    pub strict: bool,
    /// Print what was decoded as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(ui: &Ui, cmd: &PopCommand) -> Result<()> {
    match cmd {
        PopCommand::Encode(a) => run_encode(ui, a),
        PopCommand::Decode(a) => run_decode(ui, a),
        PopCommand::Stats { file, json } => run_stats(ui, file, *json),
    }
}

fn run_encode(ui: &Ui, a: &EncodeArgs) -> Result<()> {
    if let (Some(n), Some(r)) = (a.precision, a.depth)
        && n < r
    {
        return Err(crate::ui::usage(format!(
            "--precision {n} is below --depth {r}: the precision N must be in {r}..=16"
        )));
    }
    if matches!(a.mode, ModeArg::Baseline) && matches!(a.placement, Some(PlacementArg::Column)) {
        return Err(crate::ui::usage(
            "--placement column applies to --mode entropy; the baseline codes means",
        ));
    }
    if a.silhouettes.is_none()
        && (a.carve.key_colour.is_some()
            || a.carve.alpha
            || a.carve.bbox.is_some()
            || a.carve.margin != 1.0)
    {
        return Err(crate::ui::usage(
            "--key-colour, --key-tolerance, --alpha, --bbox and --margin apply to --silhouettes",
        ));
    }
    let precision = a.precision.unwrap_or(lodkit_particles::DEFAULT_PRECISION);
    let opts = EncodeOptions {
        depth: a.depth,
        precision,
        mode: match a.mode {
            ModeArg::Baseline => Mode::Baseline,
            ModeArg::Entropy => Mode::Entropy,
        },
        thinning: ThinningOptions {
            outer: a.outer_thinning,
            relax_below: a.relax_below,
        },
        normals: a.normals,
        colours: !a.no_colours,
        placement: match a.placement {
            Some(PlacementArg::Mean) => Placement::Mean,
            Some(PlacementArg::Column) | None => Placement::SurfaceColumn,
        },
        ..EncodeOptions::DEFAULT
    };
    let (e, input, source) = match (&a.silhouettes, &a.input) {
        (Some(cams), _) => {
            let c = carve_image_set(ui, cams, &a.carve, &opts)?;
            let step = ui.spinner("encoding octree particles");
            let e = encode_carved(&c, &opts)?;
            step.finish();
            ui.status(format!(
                "{}: {} views carved to R = {}, {} surface leaves, {} particles after thinning",
                cams.display(),
                c.report.views,
                c.report.depth,
                c.report.surface_leaves,
                c.report.particles
            ));
            (e, cams.clone(), "carved")
        }
        (None, Some(input)) => {
            let model = super::load(ui, input)?;
            let source = if a.raw {
                StreamSource::Samples
            } else {
                StreamSource::Surface
            };
            let (e, plan) = ui.run(|events| {
                encode_model(&model, &input.display().to_string(), &opts, source, events)
            })?;
            if let Some((resolution, triangles)) = plan.reconstruction {
                ui.status(format!(
                    "{}: {} samples reconstructed at lattice resolution {resolution} ({triangles} triangles); coding that surface (--raw codes the samples)",
                    input.display(),
                    plan.samples
                ));
            }
            (e, input.clone(), plan.source)
        }
        (None, None) => return Err(crate::ui::usage("give an input file or --silhouettes")),
    };
    lodkit_mesh::io::write_atomic(&a.output, &e.bytes)?;
    let r = &e.report;
    if a.json {
        #[derive(Serialize)]
        struct Encoded<'a> {
            input: String,
            output: String,
            source: &'a str,
            #[serde(flatten)]
            report: &'a lodkit_particles::EncodeReport,
        }
        return super::print_json(&Encoded {
            input: input.display().to_string(),
            output: a.output.display().to_string(),
            source,
            report: r,
        });
    }
    if let Some(n) = a.precision
        && r.precision != n
    {
        ui.status(format!(
            "precision raised from --precision {n} to N = R = {}: a stream's precision is at least its octree resolution",
            r.precision
        ));
    }
    ui.status(format!(
        "{}: {} particles, R = {}, N = {}, {} bytes ({} mode), structure {:.2} bits/particle (paper's estimate {:.2}), {:.2} bits/particle in all",
        a.output.display(),
        r.particles,
        r.depth,
        r.precision,
        r.total_bytes,
        r.mode,
        r.structure_bits_per_particle(),
        61.0 / 12.0,
        r.total_bytes as f64 * 8.0 / r.particles.max(1) as f64
    ));
    if let Some(l) = r.relax_below {
        ui.status(format!("outer thinning relaxed below level {l}"));
    }
    Ok(())
}

/// `--relax-below`: `auto` ([`ThinningOptions::AUTO_RELAX`]) or a level.
fn parse_relax(v: &str) -> std::result::Result<u8, String> {
    if v == "auto" {
        return Ok(ThinningOptions::AUTO_RELAX);
    }
    match v.parse::<u8>() {
        Ok(l) if lodkit::limits::POP_BITS.contains(&l) => Ok(l),
        _ => Err(format!(
            "expected `auto` or a level from {} to {}, got `{v}`",
            lodkit::limits::POP_BITS.start(),
            lodkit::limits::POP_BITS.end()
        )),
    }
}

fn read_pop(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))
}

#[derive(Serialize)]
struct DecodedReport {
    input: String,
    output: String,
    level: u8,
    /// The finest level the file (or its complete chunks) holds.
    finest_level: u8,
    /// The stream's octree resolution R (its finest level when whole).
    depth: u8,
    particles: usize,
    precision: u8,
    /// `None` with `--points`.
    triangles: Option<usize>,
    bytes_read: usize,
    file_bytes: usize,
    /// Where a cut file stopped (`None`: every chunk read was whole).
    cut: Option<CutReport>,
}

#[derive(Serialize)]
struct CutReport {
    chunk: usize,
    offset: usize,
    message: String,
}

fn run_decode(ui: &Ui, a: &DecodeArgs) -> Result<()> {
    if !a.points {
        super::mesh_output(&a.output).map_err(|_| {
            crate::ui::usage(format!(
                "{}: a triangulated level is a mesh (.ply, .obj, .stl, .glb); give --points to write the particles as points",
                a.output.display()
            ))
        })?;
    }
    let name = a.input.display().to_string();
    let bytes = read_pop(&a.input)?;
    let step = ui.spinner("decoding");
    let opts = DecodeOptions {
        max_level: a.level,
        max_precision: a.precision,
    };
    let d = if a.strict {
        decode(&bytes, &opts)
    } else {
        decode_prefix(&bytes, &opts)
    }
    .with_context(|| {
        if a.strict {
            format!("{name} (--strict: a cut chunk is refused)")
        } else {
            name.clone()
        }
    })?;
    step.finish();
    let finest = d.finest_level();
    let r = a.level.unwrap_or(finest);
    if r > finest {
        let held = if d.cut.is_some() {
            "its complete chunks hold"
        } else {
            "it holds"
        };
        return Err(crate::ui::usage(format!(
            "--level {r} is outside 0..={finest}: the levels {held} in {name}"
        )));
    }
    if let Some(n) = a.precision
        && n != d.precision
    {
        ui.status(format!(
            "{name}: decoded at {} bits, not the --precision {n} asked: this stream's positions carry {}..={} bits",
            d.precision, d.header.depth, d.header.precision
        ));
    }
    if let Some(c) = &d.cut {
        ui.status(format!(
            "{name}: stopped at byte {} of {}, where chunk {} is cut short ({}); decoded the {} complete chunks before it (levels 0..={finest})",
            c.offset,
            bytes.len(),
            c.chunk,
            c.message,
            c.chunk
        ));
    }
    let s = d.surface(r).with_context(|| name.clone())?;
    let model = if a.points {
        Model::Points(s.to_point_cloud())
    } else {
        let t = triangulate(
            &s,
            &TriangulateOptions {
                decimate: a.decimate,
                ..TriangulateOptions::DEFAULT
            },
        );
        Model::Mesh(t.mesh)
    };
    lodkit_mesh::io::save(&a.output, &model, WriteOptions::default())?;
    let triangles = match &model {
        Model::Mesh(m) => Some(m.faces.len()),
        _ => None,
    };
    if a.json {
        return super::print_json(&DecodedReport {
            input: name,
            output: a.output.display().to_string(),
            level: r,
            finest_level: finest,
            depth: d.header.depth,
            particles: s.cells.len(),
            precision: d.precision,
            triangles,
            bytes_read: d.bytes_read,
            file_bytes: bytes.len(),
            cut: d.cut.as_ref().map(|c| CutReport {
                chunk: c.chunk,
                offset: c.offset,
                message: c.message.clone(),
            }),
        });
    }
    let what = match triangles {
        Some(n) => format!("{n} triangles"),
        None => "points".into(),
    };
    ui.status(format!(
        "{}: level {r}, {} particles at {} bits, {what}, {} of {} stream bytes read",
        a.output.display(),
        s.cells.len(),
        d.precision,
        d.bytes_read,
        bytes.len()
    ));
    Ok(())
}

/// `lodkit pop stats FILE` (also what `lodkit info FILE.pop` prints): each
/// level's particles and triangles, as text or JSON.
fn run_stats(ui: &Ui, file: &Path, json: bool) -> Result<()> {
    let s = ui.run(|events| lodkit::info::pop_stats(events, file))?;
    if json {
        return super::print_json(&s);
    }
    crate::out!("{s}")?;
    Ok(())
}
