//! `lodkit lods IN --out DIR`: a discrete LOD chain — each level simplified
//! from the previous one — written as one PLY per level, one GLB with a
//! node per level, and `lods.json` (per level: triangles, vertices,
//! estimated and measured error, time).
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use clap::Args;
use lodkit_mesh::io::{Format, WriteOptions, encode, gltf::write_glb, write_atomic};
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::{Options, Simplifier, Target, halving_targets};

use super::simplify::SimplifyOpts;
use crate::ui::Ui;
use crate::ui::value::{self, Real};

#[derive(Args, Debug)]
pub struct LodsArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Comma-separated fractions of the input's triangles, one level each.
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
    /// Samples per kind for the measured error (`compare`), in 1..=10000000;
    /// by default each level gets 4 per face, within 50000..=1000000.
    #[arg(long, value_parser = value::int(1usize, value::MAX_SAMPLES))]
    pub samples: Option<usize>,
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
    let opts = a.opts.options(Target::Ratio(1.0))?;
    let mesh: TriMesh = super::load_mesh(ui, &a.input)?;
    let stem = a
        .input
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string();
    let start = Instant::now();
    let json = a.json;
    let report = write_chain_reporting(
        ui,
        &mesh,
        &a.input.display().to_string(),
        &stem,
        &a.out,
        &targets,
        &opts,
        a.samples,
        &mut |l| {
            if !json {
                ui.status(format!(
                    "level {}: {} triangles, {} vertices, error est. {:.3e} / measured mean {:.3e} max {:.3e}: {}",
                    l.level, l.triangles, l.vertices, l.estimated_error, l.measured_mean_error, l.measured_max_error, l.stop
                ));
            }
        },
    )?;
    let total = start.elapsed().as_secs_f64();
    let json = serde_json::to_string_pretty(&report)? + "\n";
    if a.json {
        crate::out!("{json}")?;
        return Ok(());
    }
    ui.status(format!(
        "wrote {} levels, {} and lods.json to {} ({:.3} s)",
        report.levels.len(),
        report.glb,
        a.out.display(),
        total
    ));
    Ok(())
}

/// Simplifies `mesh` into one level per target (each from the previous
/// level), measures each level against `mesh` (its distance index built
/// once; `samples` per kind, or [`lodkit_mesh::metrics::level_samples`]), and writes `<stem>_lodN.ply`, `<stem>_lods.glb` and `lods.json`
/// into `out`, calling `on_level` with each level as soon as it is
/// measured and written (so a long chain reports one line per level as it
/// goes, on a terminal or not).
#[allow(clippy::too_many_arguments)]
pub fn write_chain_reporting(
    ui: &Ui,
    mesh: &TriMesh,
    input_label: &str,
    stem: &str,
    out: &Path,
    targets: &[Target],
    opts: &Options,
    samples: Option<usize>,
    on_level: &mut dyn FnMut(&Level),
) -> Result<Lods> {
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output directory", out.display()))?;
    let mut ws = Simplifier::new();
    let mut levels = Vec::new();
    let mut meshes: Vec<(String, TriMesh)> = Vec::new();
    let step = ui.spinner("simplifying");
    let chain = ws
        .lod_chain(mesh, opts, targets)
        .map_err(|e| anyhow::anyhow!("{input_label}: {e}"))?;
    step.finish();
    let reference = lodkit_mesh::metrics::Reference::new(mesh)
        .map_err(|e| anyhow::anyhow!("{input_label}: {e}"))?;
    for (i, l) in chain.into_iter().enumerate() {
        let name = format!("{stem}_lod{}", i + 1);
        let file = format!("{name}.ply");
        let step = ui.spinner(&format!("measuring level {}", i + 1));
        let (mean, max) = if l.mesh.faces.is_empty() {
            (f64::NAN, f64::NAN)
        } else {
            let c = reference.compare_level(&l.mesh, samples)?;
            (c.symmetric.mean, c.symmetric.max)
        };
        step.finish();
        let bytes = encode(
            Format::Ply,
            &Model::Mesh(l.mesh.clone()),
            WriteOptions::default(),
        )
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.join(&file).display()))?;
        write_atomic(&out.join(&file), &bytes)?;
        levels.push(Level {
            level: i + 1,
            file,
            target_triangles: l.report.target_faces,
            triangles: l.report.triangles,
            vertices: l.report.vertices,
            estimated_error: l.report.estimated_error,
            measured_mean_error: mean,
            measured_max_error: max,
            seconds: l.report.seconds,
            stop: l.report.stop.to_string(),
        });
        on_level(levels.last().expect("just pushed"));
        meshes.push((name, l.mesh));
    }
    let glb_name = format!("{stem}_lods.glb");
    let named: Vec<(&str, &TriMesh)> = meshes
        .iter()
        .filter(|(_, m)| !m.faces.is_empty())
        .map(|(n, m)| (n.as_str(), m))
        .collect();
    let glb =
        write_glb(&named).map_err(|e| anyhow::anyhow!("{}: {e}", out.join(&glb_name).display()))?;
    write_atomic(&out.join(&glb_name), &glb)?;
    let report = Lods {
        input: input_label.to_string(),
        input_triangles: mesh.faces.len(),
        input_vertices: mesh.positions.len(),
        glb: glb_name,
        levels,
    };
    let json = serde_json::to_string_pretty(&report)? + "\n";
    write_atomic(&out.join("lods.json"), json.as_bytes())?;
    Ok(report)
}
