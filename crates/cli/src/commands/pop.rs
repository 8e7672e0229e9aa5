//! `lodkit pop encode|decode|stats`: progressive octree particle streams
//! (`.pop`, see `docs/formats/pop.md` and the `lodkit-particles` crate).
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand, ValueEnum};
use lodkit_mesh::Model;
use lodkit_mesh::io::WriteOptions;
use lodkit_particles::{
    DecodeOptions, EncodeOptions, Mode, Placement, ThinningOptions, TriangulateOptions, decode,
    encode, stream_stats, triangulate,
};

use crate::ui::Ui;

#[derive(Subcommand)]
pub enum PopCommand {
    /// Encode a mesh or point cloud as a progressive `.pop` stream.
    #[command(
        after_help = "Examples:\n  lodkit pop encode bunny.ply -o bunny.pop\n  lodkit pop encode scan.ply -o scan.pop --depth 9 --precision 14 --mode baseline"
    )]
    Encode(EncodeArgs),
    /// Decode one level of a `.pop` stream to a mesh (or its particles).
    #[command(
        after_help = "Examples:\n  lodkit pop decode bunny.pop --level 6 -o bunny6.ply\n  lodkit pop decode bunny.pop --level 8 --precision 10 --points -o p.ply"
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
    /// Input mesh or point cloud.
    pub input: PathBuf,
    /// Output `.pop` file.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Octree resolution R (default: from the sampling density).
    #[arg(long)]
    pub depth: Option<u8>,
    /// Vertex precision N in bits (R..=16).
    #[arg(long, default_value_t = lodkit_particles::DEFAULT_PRECISION)]
    pub precision: u8,
    #[arg(long, value_enum, default_value_t = ModeArg::Entropy)]
    pub mode: ModeArg,
    /// Vertex placement in entropy mode (the baseline codes means).
    #[arg(long, value_enum, default_value_t = PlacementArg::Column)]
    pub placement: PlacementArg,
    /// Also thin the outer boundary (with the hole-preventing test).
    #[arg(long)]
    pub outer_thinning: bool,
    /// Relax outer thinning below this level (1–16), or `auto`: the level
    /// that leaves the coarse levels fewest non-manifold triangles.
    #[arg(long, default_value = "auto", value_parser = parse_relax)]
    pub relax_below: u8,
    /// Also code particle normals.
    #[arg(long)]
    pub normals: bool,
    /// Drop the input's colours.
    #[arg(long)]
    pub no_colours: bool,
}

#[derive(Args)]
pub struct DecodeArgs {
    /// Input `.pop` file.
    pub input: PathBuf,
    /// Level r to decode (default: the finest present).
    #[arg(long)]
    pub level: Option<u8>,
    /// Vertex precision to decode (default: all present).
    #[arg(long)]
    pub precision: Option<u8>,
    /// Output file (.ply, .obj, .stl, .glb; .xyz for points).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Write the particles as a point cloud instead of triangulating.
    #[arg(long)]
    pub points: bool,
    /// Decimate during triangulation (§6.3): merge cubes joined by edges
    /// shorter than this fraction of the cube size.
    #[arg(long, value_name = "FRACTION")]
    pub decimate: Option<f32>,
}

pub fn run(ui: &Ui, cmd: &PopCommand) -> Result<()> {
    match cmd {
        PopCommand::Encode(a) => run_encode(ui, a),
        PopCommand::Decode(a) => run_decode(ui, a),
        PopCommand::Stats { file, json } => run_stats(ui, file, *json),
    }
}

fn run_encode(ui: &Ui, a: &EncodeArgs) -> Result<()> {
    let model = super::load(ui, &a.input)?;
    let opts = EncodeOptions {
        depth: a.depth,
        precision: a.precision,
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
            PlacementArg::Mean => Placement::Mean,
            PlacementArg::Column => Placement::SurfaceColumn,
        },
        ..EncodeOptions::DEFAULT
    };
    let step = ui.spinner("encoding octree particles");
    let e = encode(&model, &opts).with_context(|| format!("encoding {}", a.input.display()))?;
    step.finish();
    lodkit_mesh::io::write_atomic(&a.output, &e.bytes)?;
    let r = &e.report;
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
        Ok(l @ 1..=16) => Ok(l),
        _ => Err(format!(
            "expected `auto` or a level from 1 to 16, got `{v}`"
        )),
    }
}

fn read_pop(path: &Path) -> Result<Vec<u8>> {
    std::fs::read(path).with_context(|| format!("{}: cannot read", path.display()))
}

fn run_decode(ui: &Ui, a: &DecodeArgs) -> Result<()> {
    let bytes = read_pop(&a.input)?;
    let step = ui.spinner("decoding");
    let opts = DecodeOptions {
        max_level: a.level,
        max_precision: a.precision,
    };
    let d = decode(&bytes, &opts).with_context(|| a.input.display().to_string())?;
    step.finish();
    let r = a.level.unwrap_or(d.header.depth);
    if r as usize >= d.levels.len() {
        bail!(
            "{}: level {r} is not in the stream (it has {} levels)",
            a.input.display(),
            d.levels.len()
        );
    }
    let s = d
        .surface(r)
        .with_context(|| a.input.display().to_string())?;
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
    let what = match &model {
        Model::Mesh(m) => format!("{} triangles", m.faces.len()),
        _ => "points".into(),
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

fn run_stats(ui: &Ui, file: &Path, json: bool) -> Result<()> {
    let bytes = read_pop(file)?;
    let step = ui.spinner("decoding and triangulating every level");
    let s = stream_stats(&bytes, &TriangulateOptions::DEFAULT)
        .with_context(|| file.display().to_string())?;
    step.finish();
    if json {
        return super::print_json(&s);
    }
    crate::out!("{s}")?;
    Ok(())
}
