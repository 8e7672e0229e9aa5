//! The LOD chain job (`lodkit lods IN --out DIR`): a discrete LOD chain — each level simplified
//! from the previous one — written as one PLY per level, one GLB with the
//! input and every level as an `MSFT_lod` chain, and `lods.json` (per level: triangles, vertices,
//! estimated and measured error, time). Each level has fewer triangles
//! than the one before: a chain that stalls ends there, with one line
//! saying so, rather than write a level twice.
use std::path::PathBuf;
use std::time::Instant;

use anyhow::Result;
use lodkit_mesh::TriMesh;
use lodkit_simplify::{Options, Target};

use crate::measure::Sampling;
use crate::output::OutputOptions;
use crate::plan::{OutOfCore, out_of_core_plan};
use crate::progress::{Event, Progress};
use write::write_chain;

mod out_of_core;
mod scene;
pub(crate) mod write;

/// One LOD chain: what [`run`] reads, writes and how.
#[derive(Debug, Clone)]
pub struct LodChainJob {
    /// Input mesh or scene (any format `lodkit_mesh::io::load` reads).
    pub input: PathBuf,
    /// Output directory (created if missing).
    pub out: PathBuf,
    /// One target a level, each smaller than the one before
    /// ([`lodkit_simplify::halving_targets`] for a halving chain).
    pub targets: Vec<Target>,
    /// The simplifier's options (their target is not used).
    pub options: Options,
    /// Merge a scene into one mesh, dropping materials.
    pub merge: bool,
    /// The memory budget and where out-of-core blocks run.
    pub scale: OutOfCore,
    /// Samples per kind for the measured error; `None`: 4 per face of
    /// each level, within 50 000..=1 000 000.
    pub samples: Option<usize>,
    /// Normals and compression of what is written.
    pub output: OutputOptions,
    /// Send the out-of-core run's notes and each level as events (off when
    /// the caller prints `lods.json` itself and wants nothing else).
    pub notes: bool,
}

/// One level of a chain, as `lods.json` lists it (errors in object
/// units; NaN, written as null, where not measured).
#[derive(Debug, serde::Serialize)]
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

/// `lods.json`: the input and every level.
#[derive(Debug, serde::Serialize)]
pub struct Lods {
    pub input: String,
    pub input_triangles: usize,
    pub input_vertices: usize,
    pub glb: String,
    pub levels: Vec<Level>,
}

/// What [`run`] did: `lods.json`'s contents (also written to the
/// output folder) and the one-line summary.
pub struct LodChainReport {
    /// `lods.json` as written.
    pub json: String,
    /// The `wrote …` line.
    pub summary: String,
}

/// The targets of `--ratios R,R,…` (`None`: `levels` halvings, default
/// [`crate::limits::DEFAULT_LEVELS`]). Errors ([`crate::usage::Usage`]):
/// no ratio, or one not smaller than the one before.
pub fn targets_of(ratios: Option<&[f32]>, levels: Option<usize>) -> Result<Vec<Target>> {
    let targets: Vec<Target> = match (ratios, levels) {
        (Some(r), _) => r.iter().map(|&x| Target::Ratio(x)).collect(),
        (None, n) => lodkit_simplify::halving_targets(n.unwrap_or(crate::limits::DEFAULT_LEVELS)),
    };
    if targets.is_empty() {
        return Err(crate::usage::usage(
            "--ratios: give at least one fraction in [0, 1]",
        ));
    }
    if let Some(r) = ratios
        && let Some(w) = r.windows(2).find(|w| w[1] >= w[0])
    {
        return Err(crate::usage::usage(format!(
            "--ratios: each level must be smaller than the one before, but {} is followed by {}",
            w[0], w[1]
        )));
    }
    Ok(targets)
}

/// Makes the chain of `a.input` with `a.targets`, each level from the
/// previous one: `STEM_lodN.ply` per level (`.glb` for a scene, materials
/// kept), `STEM_lods.glb` (an `MSFT_lod` chain) and `lods.json`, in
/// `a.out`; a binary PLY over `a.scale.memory` is made out of core
/// (levels not measured, [`crate::plan`]). Each level is sent as
/// [`Event::Level`] once written. Errors: the input or output named with
/// what is wrong. Cost: the simplifier's, plus one distance measurement a
/// level.
pub fn run(a: &LodChainJob, events: &Progress) -> Result<LodChainReport> {
    let targets = a.targets.clone();
    let opts = Options {
        target: Target::Ratio(1.0),
        ..a.options.clone()
    };
    let stem = a
        .input
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string();
    if let Some(plan) = out_of_core_plan(events, &a.input, &a.scale, &opts)? {
        return out_of_core::run(events, a, &stem, &targets, &opts, &plan);
    }
    if a.scale.ray.is_some() {
        events.status(format!(
            "note: {} fits --memory, so its chain is made in core here and --ray is not used",
            a.input.display()
        ));
    }
    // A scene (materials, parts) keeps them unless --merge: a chain of
    // scene GLBs, measured merged.
    let (mesh, scene): (TriMesh, Option<lodkit_mesh::Scene>) =
        match crate::input::load_input(events, &a.input, !a.merge)? {
            crate::input::Input::Scene(s) => (s.merged().mesh, Some(s)),
            crate::input::Input::Model(lodkit_mesh::Model::Mesh(m)) => (m, None),
            crate::input::Input::Model(other) => anyhow::bail!(
                "{}: holds a {} with no faces, a mesh is needed",
                a.input.display(),
                other.kind()
            ),
        };
    let start = Instant::now();
    let notes = a.notes;
    let reference = lodkit_mesh::metrics::Reference::new(&mesh)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    let sampling = a.samples.map_or(Sampling::Adaptive, Sampling::PerKind);
    let input = a.input.display().to_string();
    let mut on_level = |l: &Level| {
        if notes {
            events.emit(&Event::Level(l));
        }
    };
    let chain = write_chain(
        events,
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
        events.status(line);
    }
    let total = start.elapsed().as_secs_f64();
    let json = serde_json::to_string_pretty(&report)? + "\n";
    let what = match &scene {
        Some(s) => crate::input::describe(s),
        None => format!("{total:.3} s"),
    };
    let summary = format!(
        "wrote {} levels, {} and lods.json to {} ({what})",
        report.levels.len(),
        report.glb,
        a.out.display(),
    );
    Ok(LodChainReport { json, summary })
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
