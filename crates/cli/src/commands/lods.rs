//! `lodkit lods IN --out DIR`: a discrete LOD chain — each level simplified
//! from the previous one — written as one PLY per level, one GLB with the
//! input and every level as an `MSFT_lod` chain, and `lods.json` (per level: triangles, vertices,
//! estimated and measured error, time). Each level has fewer triangles
//! than the one before: a chain that stalls ends there, with one line
//! saying so, rather than write a level twice.
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use clap::Args;
use lodkit_mesh::TriMesh;
use lodkit_simplify::{Target, halving_targets};

use super::build::Sampling;
use super::build::lod_chain::write_chain;
use super::simplify::{OutOfCoreArgs, SimplifyOpts, out_of_core_plan};
use crate::ui::Ui;
use crate::ui::value::{self, Real};

#[derive(Args, Debug)]
pub struct LodsArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Comma-separated fractions of the input's triangles, one level each,
    /// each smaller than the one before.
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "R,R,...",
        conflicts_with = "levels",
        value_parser = Real::closed(0.0, 1.0).f32()
    )]
    pub ratios: Option<Vec<f32>>,
    /// Number of levels, each half the previous one, in 1..=32 (default 6).
    #[arg(long, value_name = "N", value_parser = value::int(1usize, value::MAX_LEVELS))]
    pub levels: Option<usize>,
    #[command(flatten)]
    pub opts: SimplifyOpts,
    #[command(flatten)]
    pub scale: OutOfCoreArgs,
    /// Samples per kind for the measured error (`compare`), in 1..=10000000;
    /// by default each level gets 4 per face, within 50000..=1000000.
    #[arg(long, value_parser = value::int(1usize, value::MAX_SAMPLES))]
    pub samples: Option<usize>,
    #[command(flatten)]
    pub output: crate::ui::OutputArgs,
    /// Print lods.json on stdout too.
    #[arg(long)]
    pub json: bool,
}

#[derive(serde::Serialize)]
pub struct Level {
    pub level: usize,
    pub file: String,
    pub target_triangles: usize,
    pub triangles: usize,
    pub vertices: usize,
    pub estimated_error: f32,
    pub measured_mean_error: f64,
    pub measured_max_error: f64,
    pub seconds: f64,
    pub stop: String,
}

#[derive(serde::Serialize)]
pub struct Lods {
    pub input: String,
    pub input_triangles: usize,
    pub input_vertices: usize,
    pub glb: String,
    pub levels: Vec<Level>,
}

pub fn run(ui: &Ui, a: &LodsArgs) -> Result<()> {
    let targets: Vec<Target> = match (&a.ratios, a.levels) {
        (Some(r), _) => r.iter().map(|&x| Target::Ratio(x)).collect(),
        (None, Some(n)) => halving_targets(n),
        (None, None) => halving_targets(6),
    };
    if targets.is_empty() {
        return Err(crate::ui::usage(
            "--ratios: give at least one fraction in [0, 1]",
        ));
    }
    if let Some(r) = &a.ratios
        && let Some(w) = r.windows(2).find(|w| w[1] >= w[0])
    {
        return Err(crate::ui::usage(format!(
            "--ratios: each level must be smaller than the one before, but {} is followed by {}",
            w[0], w[1]
        )));
    }
    let opts = a.opts.options(Target::Ratio(1.0))?;
    let stem = a
        .input
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string();
    if let Some(plan) = out_of_core_plan(ui, &a.input, &a.scale, &a.opts)? {
        return super::lods_out_of_core::run(ui, a, &stem, &targets, &opts, &plan);
    }
    if a.scale.ray.is_some() {
        ui.status(format!(
            "note: {} fits --memory, so its chain is made in core here and --ray is not used",
            a.input.display()
        ));
    }
    // A scene (materials, parts) keeps them unless --merge: a chain of
    // scene GLBs, measured merged.
    let (mesh, scene): (TriMesh, Option<lodkit_mesh::Scene>) =
        match super::scene::load_input(ui, &a.input, !a.opts.merge)? {
            super::scene::Input::Scene(s) => (s.merged().mesh, Some(s)),
            super::scene::Input::Model(lodkit_mesh::Model::Mesh(m)) => (m, None),
            super::scene::Input::Model(other) => anyhow::bail!(
                "{}: holds a {} with no faces, a mesh is needed",
                a.input.display(),
                other.kind()
            ),
        };
    let start = Instant::now();
    let json = a.json;
    let reference = lodkit_mesh::metrics::Reference::new(&mesh)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    let sampling = a.samples.map_or(Sampling::Adaptive, Sampling::PerKind);
    let input = a.input.display().to_string();
    let mut on_level = |l: &Level| {
        if !json {
            ui.status(format!(
                "level {}: {} triangles, {} vertices, error est. {:.3e} / measured mean {:.3e} max {:.3e}: {}",
                l.level, l.triangles, l.vertices, l.estimated_error, l.measured_mean_error, l.measured_max_error, l.stop
            ));
        }
    };
    let chain = write_chain(
        ui,
        &reference,
        &input,
        &stem,
        &a.out,
        scene.as_ref(),
        &targets,
        &opts,
        sampling,
        &a.output,
        &mut on_level,
    )?;
    let report = chain.lods;
    if let Some(line) = stopped_early(&report.levels, targets.len()) {
        ui.status(line);
    }
    let total = start.elapsed().as_secs_f64();
    let json = serde_json::to_string_pretty(&report)? + "\n";
    if a.json {
        crate::out!("{json}")?;
        return Ok(());
    }
    let what = match &scene {
        Some(s) => super::scene::describe(s),
        None => format!("{total:.3} s"),
    };
    ui.status(format!(
        "wrote {} levels, {} and lods.json to {} ({what})",
        report.levels.len(),
        report.glb,
        a.out.display(),
    ));
    Ok(())
}

/// The line saying why a chain has fewer levels than asked: the chain
/// ends at the first level that would remove no triangle from the one
/// before ([`lodkit_simplify::lod_chain`]), rather than write it twice.
/// `None` when every level was made.
pub fn stopped_early(levels: &[Level], asked: usize) -> Option<String> {
    let last = levels.last()?;
    if levels.len() >= asked {
        return None;
    }
    let why = if last.stop == lodkit_simplify::StopReason::Reached.to_string() {
        String::new()
    } else {
        format!(" (level {}: {})", last.level, last.stop)
    };
    Some(format!(
        "note: stopped at level {} of {}: level {} would remove no triangle from level {}'s {}{why}",
        last.level,
        asked,
        last.level + 1,
        last.level,
        last.triangles
    ))
}
