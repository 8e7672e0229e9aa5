//! The simplify job: one mesh or scene to one budget with the HQMS
//! simplifier (`lodkit-simplify`), in core or out of core.
use std::path::PathBuf;

use anyhow::{Result, bail};
use lodkit_mesh::io::{WriteOptions, write_atomic};
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::{Options, Simplifier, Target};

use crate::output::OutputOptions;
use crate::plan::{OutOfCore, Plan, out_of_core_plan};
use crate::progress::{Event, Progress, human_bytes};

/// One simplification: what [`run`] reads, writes and how.
#[derive(Debug, Clone)]
pub struct SimplifyJob {
    /// Input mesh or scene (any format `lodkit_mesh::io::load` reads).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension (.ply, .obj, .stl,
    /// .glb: [`crate::output::mesh_output`]).
    pub output: PathBuf,
    /// The simplifier's options, target included ([`target_of`]).
    pub options: Options,
    /// Merge every mesh, primitive and instance into one mesh, dropping
    /// materials (otherwise .glb and .obj outputs keep them, one
    /// primitive per material, borders kept closed).
    pub merge: bool,
    /// The memory budget and where out-of-core blocks run.
    pub scale: OutOfCore,
    /// Normals and compression of what is written.
    pub out: OutputOptions,
}

/// What [`run`] did: the `--json` report, and its one-line summary.
#[derive(serde::Serialize)]
pub struct Report {
    pub input: PathBuf,
    pub output: PathBuf,
    pub input_triangles: usize,
    pub target_triangles: usize,
    pub triangles: usize,
    pub vertices: usize,
    pub estimated_error: f32,
    pub passes: u32,
    pub stop: String,
    pub seconds: f64,
    /// Present only out of core, so the in-core report is unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub out_of_core: Option<OutOfCoreReport>,
    /// The `wrote …` line.
    #[serde(skip)]
    pub summary: String,
}

/// The out-of-core run in `--json` (`estimated_error` and `passes` above
/// are then the final in-core pass's, over the merged blocks).
#[derive(serde::Serialize)]
pub struct OutOfCoreReport {
    pub memory: u64,
    pub estimated_in_core_bytes: u64,
    /// Non-empty blocks per round.
    pub round_blocks: Vec<usize>,
    /// Triangles after each round.
    pub round_triangles: Vec<u64>,
    pub resumed_blocks: usize,
    pub bytes_read: u64,
    pub bytes_written: u64,
    /// Seconds per phase, in order.
    pub phases: Vec<(String, f64)>,
}

/// The target from `--target` / `--ratio` / `--max-error` (error alone: no face budget).
pub fn target_of(
    target: Option<usize>,
    ratio: Option<f32>,
    max_error: Option<f32>,
) -> Result<Target> {
    Ok(match (target, ratio) {
        (Some(n), _) => Target::Faces(n),
        (None, Some(r)) if (0.0..=1.0).contains(&r) => Target::Ratio(r),
        (None, Some(r)) => bail!("--ratio must be within 0..1, got {r}"),
        (None, None) if max_error.is_some() => Target::Faces(0),
        (None, None) => bail!("give --target FACES, --ratio R or --max-error E"),
    })
}

/// Simplifies `a.input` to `a.options.target` and writes `a.output`
/// atomically: a scene keeps its materials when the output holds scenes
/// and `a.merge` is off; a binary PLY or STL over `a.scale.memory` is
/// simplified out of core ([`crate::plan`]), in blocks staged beside the
/// output. Errors: the input or output named with what is wrong; options
/// this input or output cannot take are a [`crate::usage::Usage`].
/// Cost: the simplifier's (about 80 bytes a face in core).
pub fn run(a: &SimplifyJob, events: &Progress) -> Result<Report> {
    let format = crate::output::mesh_output(&a.output)?;
    a.out.check(Some(format), &a.output.display().to_string())?;
    let opts = &a.options;
    if let Some(plan) = out_of_core_plan(events, &a.input, &a.scale, opts)? {
        return run_out_of_core(events, a, format, opts, &plan);
    }
    if a.scale.ray.is_some() {
        events.status(format!(
            "note: {} fits --memory, so it is simplified in core here and --ray is not used",
            a.input.display()
        ));
    }
    let mesh: TriMesh = match crate::input::load_input(
        events,
        &a.input,
        !a.merge && crate::input::holds_scenes(&a.output),
    )? {
        crate::input::Input::Scene(scene) => return run_scene(events, a, &scene, opts),
        crate::input::Input::Model(Model::Mesh(m)) => m,
        other => bail!(
            "{}: holds a {} with no faces, a mesh is needed",
            a.input.display(),
            other.kind()
        ),
    };
    let start = std::time::Instant::now();
    let out = simplify_mesh(&mesh, opts, events)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    let t = start.elapsed();
    let r = out.report;
    let bytes = a
        .out
        .encode(format, &Model::Mesh(out.mesh), WriteOptions::default())
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.output.display()))?;
    write_atomic(&a.output, &bytes)?;
    let summary = format!(
        "wrote {} ({} → {} triangles, {} vertices, estimated error {:.3e}, {} passes, {:.3} s): {}",
        a.output.display(),
        mesh.faces.len(),
        r.triangles,
        r.vertices,
        r.estimated_error,
        r.passes,
        t.as_secs_f64(),
        r.stop
    );
    Ok(in_core_report(a, mesh.faces.len(), &r, t, summary))
}

/// The report of an in-core run: `r` for the `input_triangles` read.
fn in_core_report(
    a: &SimplifyJob,
    input_triangles: usize,
    r: &lodkit_simplify::LevelReport,
    t: std::time::Duration,
    summary: String,
) -> Report {
    Report {
        input: a.input.clone(),
        output: a.output.clone(),
        input_triangles,
        target_triangles: r.target_faces,
        triangles: r.triangles,
        vertices: r.vertices,
        estimated_error: r.estimated_error,
        passes: r.passes,
        stop: r.stop.to_string(),
        seconds: t.as_secs_f64(),
        out_of_core: None,
        summary,
    }
}

/// One mesh in memory to `opts.target`: the in-core step of [`run`] (a
/// stage named `simplifying`). Errors: the simplifier's, about the mesh
/// (the caller names it). Cost: the simplifier's, about 80 bytes a face.
pub fn simplify_mesh(
    mesh: &TriMesh,
    opts: &Options,
    events: &Progress,
) -> Result<lodkit_simplify::Simplified, lodkit_simplify::Error> {
    let step = events.spinner("simplifying");
    let out = Simplifier::new().simplify(mesh, opts);
    step.finish();
    out
}

/// `simplify` on a scene: every mesh simplified, materials kept
/// (`lodkit_simplify::scene`), written as .glb or .obj.
fn run_scene(
    events: &Progress,
    a: &SimplifyJob,
    scene: &lodkit_mesh::Scene,
    opts: &Options,
) -> Result<Report> {
    let step = events.spinner("simplifying");
    let (out, reports) = lodkit_simplify::scene::simplify_scene(scene, opts)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    let t = step.finish();
    let r = lodkit_simplify::scene::combined_report(&reports)
        .ok_or_else(|| anyhow::anyhow!("{}: the scene has no meshes", a.input.display()))?;
    let out = a.out.scene(out, &a.output)?;
    lodkit_mesh::io::save_scene_with(&a.output, &out, WriteOptions::default(), &a.out.glb())?;
    let summary = format!(
        "wrote {} ({} → {} triangles, {} vertices, estimated error {:.3e}, {:.3} s; {}): {}",
        a.output.display(),
        scene.face_count(),
        r.triangles,
        r.vertices,
        r.estimated_error,
        t.as_secs_f64(),
        crate::input::describe(&out),
        r.stop
    );
    Ok(in_core_report(a, scene.face_count(), &r, t, summary))
}

/// `simplify` out of core (`lodkit_scale::simplify_file`): blocks staged
/// in a folder beside the output, the phases shown as progress, the
/// result written atomically. The staging folder is held by this run
/// alone (a second run of the same job refuses) and removed only after
/// the output is in place; a failed or interrupted run leaves it (it is
/// not listed for removal on a signal), says so in its error, and the same
/// command then resumes from the blocks it finished; a later run for the
/// same output with other options or another input removes it.
fn run_out_of_core(
    events: &Progress,
    a: &SimplifyJob,
    format: lodkit_mesh::io::Format,
    opts: &Options,
    plan: &Plan,
) -> Result<Report> {
    // The staging key holds everything that changes the blocks: the
    // options and the budget (the grid depends on nothing else).
    let settings = format!("{opts:?}; memory {}", plan.memory);
    let staging = lodkit_scale::staging_dir(&a.input, &a.output, &settings);
    events.status(format!(
        "out of core: {} ({}) needs about {} in core ({} B per face), over --memory {}; \
         simplifying in blocks",
        a.input.display(),
        human_bytes(plan.file_bytes),
        human_bytes(plan.in_core),
        lodkit_scale::IN_CORE_BYTES_PER_FACE,
        human_bytes(plan.memory),
    ));
    let target = opts.target.faces(plan.faces as usize) as u64;
    let quality = lodkit_scale::quality_memory(target);
    if plan.memory < quality {
        events.status(format!(
            "note: --memory {} leaves the final pass room for under {}× the target of {} triangles, \
             so the blocks do most of the reduction and the result is coarser than in core; \
             --memory {} or more gives in-core quality",
            human_bytes(plan.memory),
            lodkit_scale::QUALITY_HEADROOM,
            target,
            human_bytes(quality),
        ));
    }
    for old in lodkit_scale::remove_abandoned(&a.output, &staging) {
        events.status(format!(
            "removed {}, the staging folder an earlier run for this output left",
            old.display()
        ));
    }
    if staging.exists() {
        events.status(format!(
            "resuming: {} blocks already done (in {})",
            lodkit_scale::finished_blocks(&staging),
            staging.display()
        ));
    }
    let so = lodkit_scale::ScaleOptions {
        simplify: opts.clone(),
        memory: plan.memory,
        staging: staging.clone(),
        runner: a.scale.runner(),
    };
    let start = std::time::Instant::now();
    let result = lodkit_scale::simplify_file(&a.input, &so, &|e| match e {
        lodkit_scale::Event::Phase(name, len) => events.emit(&Event::Phase { name, len }),
        lodkit_scale::Event::Advance(n) => events.emit(&Event::Advance(n)),
    });
    events.emit(&Event::PhasesFinished);
    let kept = |e: &dyn std::fmt::Display| crate::plan::kept(e, &staging);
    let (mesh, rep) = result.map_err(|e| kept(&e))?;
    let t = start.elapsed();
    // simplify_file's final pass always reports on success.
    let last = rep
        .last
        .ok_or_else(|| anyhow::anyhow!("{}: no final pass report", a.input.display()))?;
    let (triangles, vertices) = (mesh.faces.len(), mesh.positions.len());
    let bytes = a
        .out
        .encode(format, &Model::Mesh(mesh), WriteOptions::default())
        .map_err(|e| kept(&format!("{}: {e}", a.output.display())))?;
    write_atomic(&a.output, &bytes).map_err(|e| kept(&e))?;
    // The output is in place: the blocks are no longer needed.
    crate::plan::remove_staging(events, &staging);
    for (name, seconds) in &rep.phases {
        events.emit(&Event::Timing {
            name,
            seconds: *seconds,
        });
    }
    let rounds = rep.round_blocks.len();
    // The final pass's estimate covers its own collapses only, not the
    // blocks' (which are not carried through the soups): say which.
    let last_pass = if last.estimated_error > 0.0 {
        format!(
            "its own collapses estimated at {:.3e}, the blocks' not included",
            last.estimated_error
        )
    } else {
        "no collapse needed".to_string()
    };
    let summary = format!(
        "wrote {} ({} → {} triangles, {} vertices, {:.3} s; out of core: {} blocks in {} round{}, \
     {} resumed, then a final pass over the merged blocks: {}): {}",
        a.output.display(),
        rep.input_faces,
        triangles,
        vertices,
        t.as_secs_f64(),
        rep.round_blocks.iter().sum::<usize>(),
        rounds,
        if rounds == 1 { "" } else { "s" },
        rep.resumed_blocks,
        last_pass,
        last.stop
    );
    Ok(Report {
        input: a.input.clone(),
        output: a.output.clone(),
        input_triangles: rep.input_faces as usize,
        target_triangles: last.target_faces,
        triangles,
        vertices,
        estimated_error: last.estimated_error,
        passes: last.passes,
        stop: last.stop.to_string(),
        seconds: t.as_secs_f64(),
        out_of_core: Some(OutOfCoreReport {
            memory: plan.memory,
            estimated_in_core_bytes: plan.in_core,
            round_blocks: rep.round_blocks,
            round_triangles: rep.round_faces,
            resumed_blocks: rep.resumed_blocks,
            bytes_read: rep.bytes_read,
            bytes_written: rep.bytes_written,
            phases: rep.phases,
        }),
        summary,
    })
}
