//! The LOD chain job (`lodkit lods IN --out DIR`): a discrete LOD chain —
//! each level simplified from the previous one — written as one PLY per
//! level, one GLB with the input and every level as an `MSFT_lod` chain,
//! and `lods.json` (per level: triangles, vertices, estimated and measured
//! error, time). Each level has fewer triangles
//! than the one before: a chain that stalls ends there, with one line
//! saying so, rather than write a level twice.
use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::Reference;
use lodkit_simplify::{Options, Target};

use crate::measure::Sampling;
use crate::output::OutputOptions;
use crate::plan::out_of_core_plan;
use crate::progress::{Event, Progress};
use write::Chain;

mod job;
pub mod level_textures;
mod out_of_core;
mod scene;
pub(crate) mod write;

pub use crate::report::{Level, Lods};
pub use job::{LodChainJob, LodChainReport};
pub use write::{GlbLevel, chain_glb};

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
            other => anyhow::bail!(
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
    if let Some(line) = write::stopped_early(&report.levels, targets.len()) {
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

/// The chain of `lodkit lods` and `build`: of `scene` with its materials
/// when given ([`super::scene::write_scene_chain`]: scene GLBs),
/// else of the reference's mesh ([`write::write_mesh_chain`]: PLY levels); the
/// arguments are theirs.
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_chain(
    events: &Progress,
    reference: &Reference,
    input: &str,
    stem: &str,
    out: &Path,
    scene: Option<&lodkit_mesh::Scene>,
    targets: &[Target],
    opts: &Options,
    sampling: Sampling,
    output: &OutputOptions,
    on_level: &mut dyn FnMut(&Level),
) -> Result<Chain> {
    match scene {
        Some(s) => scene::write_scene_chain(
            events, reference, input, stem, out, s, targets, opts, sampling, output, on_level,
        ),
        None => write::write_mesh_chain(
            events, reference, input, stem, out, targets, opts, sampling, output, on_level,
        ),
    }
}
