//! `lodkit simplify IN -o OUT`: one mesh to one budget with the HQMS
//! simplifier (`lodkit-simplify`).
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Args;
use lodkit_mesh::io::{WriteOptions, write_atomic};
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::{AttributeWeights, Options, Simplifier, Target};

use crate::ui::value::{self, Real};
use crate::ui::{Ui, human_bytes};

/// Largest `--heap-size`: 2^24 records (a few hundred MB at most).
pub const MAX_HEAP_SIZE: usize = 1 << 24;

/// Range of the attribute weights.
const WEIGHT: Real = Real::closed(0.0, 1e6);

/// Options shared by `simplify` and `lods`.
#[derive(Args, Debug, Clone)]
pub struct SimplifyOpts {
    /// Stop before any collapse whose estimated object-space error (input
    /// units, a finite number >= 0) would exceed E.
    #[arg(long, value_name = "E", value_parser = Real::NON_NEGATIVE.f32())]
    pub max_error: Option<f32>,
    /// Keep border vertices (edges with one face) in place.
    #[arg(long)]
    pub lock_border: bool,
    /// Keep every hole and open rim (the paper's hole filling is on by default).
    #[arg(long)]
    pub no_fill_holes: bool,
    /// Records in the replacement-selection heap, in 1..=16777216 (2^24:
    /// its memory grows with it).
    #[arg(long, default_value_t = Options::DEFAULT_HEAP_SIZE, value_name = "N",
          value_parser = value::int(1usize, MAX_HEAP_SIZE))]
    pub heap_size: usize,
    /// Weight of normals in the cost (relative to the bounding-box extent), in [0, 1000000].
    #[arg(long, default_value_t = AttributeWeights::DEFAULT.normal, value_name = "W", value_parser = WEIGHT.f32())]
    pub normal_weight: f32,
    /// Weight of colours in the cost, in [0, 1000000].
    #[arg(long, default_value_t = AttributeWeights::DEFAULT.color, value_name = "W", value_parser = WEIGHT.f32())]
    pub color_weight: f32,
    /// Weight of UVs in the cost, in [0, 1000000].
    #[arg(long, default_value_t = AttributeWeights::DEFAULT.uv, value_name = "W", value_parser = WEIGHT.f32())]
    pub uv_weight: f32,
    /// Remove components smaller than this fraction of the bounding-box
    /// diagonal first, in [0, 1) (1 would remove every component).
    #[arg(long, value_name = "FRACTION", value_parser = Real::closed_open(0.0, 1.0).f32())]
    pub prune: Option<f32>,
    /// Merge every mesh, primitive and instance into one mesh, dropping
    /// materials (by default .glb and .obj outputs keep them, one
    /// primitive per material, borders kept closed).
    #[arg(long)]
    pub merge: bool,
}

impl SimplifyOpts {
    pub fn options(&self, target: Target) -> Result<Options> {
        Ok(Options {
            target,
            max_error: self.max_error,
            lock_border: self.lock_border,
            fill_holes: !self.no_fill_holes,
            heap_size: self.heap_size,
            weights: AttributeWeights {
                normal: self.normal_weight,
                color: self.color_weight,
                uv: self.uv_weight,
            },
            prune: self.prune,
            ..Options::DEFAULT
        })
    }
}

#[derive(Args, Debug)]
#[command(group(
    clap::ArgGroup::new("budget")
        .required(true)
        .multiple(true)
        .args(["target", "ratio", "max_error"])
))]
pub struct SimplifyArgs {
    /// Input mesh (.ply, .obj, .stl, .gltf, .glb).
    pub input: PathBuf,
    /// Output mesh; the format follows the extension (.ply, .obj, .stl, .glb).
    #[arg(short, long, value_parser = value::output(value::MESH_OUT, "the simplified mesh"))]
    pub output: PathBuf,
    /// Triangle budget, in 0..=4294967295.
    #[arg(long, value_name = "FACES", conflicts_with = "ratio", value_parser = value::int(0usize, u32::MAX as usize))]
    pub target: Option<usize>,
    /// Fraction of the input's triangles to keep, in [0, 1].
    #[arg(long, value_name = "R", value_parser = Real::closed(0.0, 1.0).f32())]
    pub ratio: Option<f32>,
    #[command(flatten)]
    pub opts: SimplifyOpts,
    #[command(flatten)]
    pub scale: OutOfCoreArgs,
    #[command(flatten)]
    pub out: crate::ui::OutputArgs,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

/// `--memory` and `--ray`, shared by `simplify` and `lods`.
#[derive(Args, Debug)]
pub struct OutOfCoreArgs {
    /// Memory budget, in 1M..=1P bytes (K, M, G, T, P: powers of 1024; e.g.
    /// 8G, 512M). A binary PLY or STL whose in-core estimate (80 bytes per face)
    /// exceeds it is simplified out of core, in blocks staged beside the
    /// output (--target or --ratio; normals, colours, UVs kept), with the in-core
    /// error when SIZE is at least 320 bytes per target face. Default: a
    /// third of the machine's memory.
    #[arg(long, value_name = "SIZE", value_parser = value::bytes(MIN_MEMORY, MAX_MEMORY))]
    pub memory: Option<u64>,
    /// Run the blocks of an out-of-core run as Ray tasks: `local` starts a
    /// local cluster for the run, `auto` or HOST:PORT joins a running one
    /// (every node must see the output's folder at the same path). Needs a
    /// Python with pylodkit and ray (`python3`, or $LODKIT_PYTHON). The
    /// output is the same bytes as without.
    #[arg(long, value_name = "ADDRESS", value_parser = value::ray_address)]
    pub ray: Option<String>,
}

impl OutOfCoreArgs {
    /// Where the blocks run.
    pub fn runner(&self) -> lodkit_scale::Runner {
        match &self.ray {
            None => lodkit_scale::Runner::Threads,
            Some(address) => lodkit_scale::Runner::Ray {
                address: address.clone(),
                python: std::env::var_os("LODKIT_PYTHON")
                    .map_or_else(|| "python3".into(), PathBuf::from),
                workers: None,
            },
        }
    }
}

/// Smallest `--memory`: 1 MiB (below it the block size is already at the
/// simplifier's floor of 256 faces, so a smaller budget changes nothing).
pub const MIN_MEMORY: u64 = 1 << 20;
/// Largest `--memory`: 1 PiB, far past any machine's memory (a budget
/// above the machine's memory only means the in-core path is taken).
pub const MAX_MEMORY: u64 = 1 << 50;

#[derive(serde::Serialize)]
struct Report<'a> {
    input: &'a Path,
    output: &'a Path,
    input_triangles: usize,
    target_triangles: usize,
    triangles: usize,
    vertices: usize,
    estimated_error: f32,
    passes: u32,
    stop: String,
    seconds: f64,
    /// Present only out of core, so the in-core report is unchanged.
    #[serde(skip_serializing_if = "Option::is_none")]
    out_of_core: Option<OutOfCoreReport>,
}

/// The out-of-core run in `--json` (`estimated_error` and `passes` above
/// are then the final in-core pass's, over the merged blocks).
#[derive(serde::Serialize)]
struct OutOfCoreReport {
    memory: u64,
    estimated_in_core_bytes: u64,
    /// Non-empty blocks per round.
    round_blocks: Vec<usize>,
    /// Triangles after each round.
    round_triangles: Vec<u64>,
    resumed_blocks: usize,
    bytes_read: u64,
    bytes_written: u64,
    /// Seconds per phase, in order.
    phases: Vec<(String, f64)>,
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

pub fn run(ui: &Ui, a: &SimplifyArgs) -> Result<()> {
    let format = super::mesh_output(&a.output)?;
    a.out.check(Some(format), &a.output.display().to_string())?;
    let target = target_of(a.target, a.ratio, a.opts.max_error)?;
    let opts = a.opts.options(target)?;
    if let Some(plan) = out_of_core_plan(ui, &a.input, &a.scale, &a.opts)? {
        return run_out_of_core(ui, a, format, &opts, &plan);
    }
    if a.scale.ray.is_some() {
        ui.status(format!(
            "note: {} fits --memory, so it is simplified in core here and --ray is not used",
            a.input.display()
        ));
    }
    let mesh: TriMesh = match super::scene::load_input(
        ui,
        &a.input,
        !a.opts.merge && super::scene::holds_scenes(&a.output),
    )? {
        super::scene::Input::Scene(scene) => return run_scene(ui, a, &scene, &opts),
        super::scene::Input::Model(Model::Mesh(m)) => m,
        super::scene::Input::Model(other) => bail!(
            "{}: holds a {} with no faces, a mesh is needed",
            a.input.display(),
            other.kind()
        ),
    };
    let step = ui.spinner("simplifying");
    let out = Simplifier::new()
        .simplify(&mesh, &opts)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    let t = step.finish();
    let r = out.report;
    let bytes = a
        .out
        .encode(format, &Model::Mesh(out.mesh), WriteOptions::default())
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.output.display()))?;
    write_atomic(&a.output, &bytes)?;
    if a.json {
        return super::print_json(&Report {
            input: &a.input,
            output: &a.output,
            input_triangles: mesh.faces.len(),
            target_triangles: r.target_faces,
            triangles: r.triangles,
            vertices: r.vertices,
            estimated_error: r.estimated_error,
            passes: r.passes,
            stop: r.stop.to_string(),
            seconds: t.as_secs_f64(),
            out_of_core: None,
        });
    }
    ui.status(format!(
        "wrote {} ({} → {} triangles, {} vertices, estimated error {:.3e}, {} passes, {:.3} s): {}",
        a.output.display(),
        mesh.faces.len(),
        r.triangles,
        r.vertices,
        r.estimated_error,
        r.passes,
        t.as_secs_f64(),
        r.stop
    ));
    Ok(())
}

/// `simplify` on a scene: every mesh simplified, materials kept
/// (`lodkit_simplify::scene`), written as .glb or .obj.
fn run_scene(ui: &Ui, a: &SimplifyArgs, scene: &lodkit_mesh::Scene, opts: &Options) -> Result<()> {
    let step = ui.spinner("simplifying");
    let (out, reports) = lodkit_simplify::scene::simplify_scene(scene, opts)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    let t = step.finish();
    let r = lodkit_simplify::scene::combined_report(&reports)
        .ok_or_else(|| anyhow::anyhow!("{}: the scene has no meshes", a.input.display()))?;
    let out = a.out.scene(out, &a.output)?;
    lodkit_mesh::io::save_scene_with(&a.output, &out, WriteOptions::default(), &a.out.glb())?;
    if a.json {
        return super::print_json(&Report {
            input: &a.input,
            output: &a.output,
            input_triangles: scene.face_count(),
            target_triangles: r.target_faces,
            triangles: r.triangles,
            vertices: r.vertices,
            estimated_error: r.estimated_error,
            passes: r.passes,
            stop: r.stop.to_string(),
            seconds: t.as_secs_f64(),
            out_of_core: None,
        });
    }
    ui.status(format!(
        "wrote {} ({} → {} triangles, {} vertices, estimated error {:.3e}, {:.3} s; {}): {}",
        a.output.display(),
        scene.face_count(),
        r.triangles,
        r.vertices,
        r.estimated_error,
        t.as_secs_f64(),
        super::scene::describe(&out),
        r.stop
    ));
    Ok(())
}

/// Why an input goes out of core: its estimated in-core bytes over the
/// budget.
pub struct Plan {
    pub memory: u64,
    pub in_core: u64,
    pub file_bytes: u64,
    /// Face records in the file's header.
    pub faces: u64,
}

/// Whether `a.input` is simplified out of core: a `.ply` that
/// [`lodkit_scale::needs_out_of_core`] says would not fit `--memory` and
/// that the stream reader accepts (binary, vertices then faces). A `.ply`
/// too big but not streamable (ASCII, another layout) is simplified in
/// core as before, with one line saying so; every other input takes the
/// in-core path untouched. Options the out-of-core path cannot honour are
/// refused here (exit 2), before anything is written: falling back in
/// core would risk exactly the memory exhaustion `--memory` guards.
pub fn out_of_core_plan(
    ui: &Ui,
    input: &Path,
    scale: &OutOfCoreArgs,
    o: &SimplifyOpts,
) -> Result<Option<Plan>> {
    use lodkit_mesh::io::Format;
    let per_face = match Format::from_path(input) {
        Some(Format::Ply) => lodkit_scale::PLY_BYTES_PER_FACE,
        Some(Format::Stl) => lodkit_scale::STL_BYTES_PER_FACE,
        _ => return Ok(None),
    };
    let Ok(meta) = std::fs::metadata(input) else {
        // The in-core reader reports a missing file as it always has.
        return Ok(None);
    };
    let memory = scale.memory.unwrap_or_else(lodkit_scale::default_memory);
    let file_bytes = meta.len();
    let in_core = lodkit_scale::in_core_bytes(file_bytes, per_face);
    if !meta.is_file() || in_core <= memory {
        return Ok(None);
    }
    let streamed = if per_face == lodkit_scale::STL_BYTES_PER_FACE {
        lodkit_mesh::io::stl_stream::StlStream::open(input).map(|s| s.triangles())
    } else {
        lodkit_mesh::io::ply::stream::PlyStream::open(input).map(|s| s.face_records())
    };
    let faces = match streamed {
        Ok(n) => n,
        Err(e) => {
            ui.status(format!(
                "note: {} needs about {} in core, over --memory {}, but cannot be streamed ({e}); simplifying in core",
                input.display(),
                human_bytes(in_core),
                human_bytes(memory),
            ));
            return Ok(None);
        }
    };
    let refused = [
        (o.max_error.is_some(), "--max-error"),
        (o.prune.is_some(), "--prune"),
    ];
    let refused: Vec<&str> = refused.iter().filter(|r| r.0).map(|r| r.1).collect();
    if !refused.is_empty() {
        return Err(crate::ui::usage(format!(
            "{}: needs about {} in core, over --memory {}, so it would be simplified out of core, \
             which simplifies to a face budget and does not honour {}; drop {} \
             or give a --memory of at least {} to simplify in core",
            input.display(),
            human_bytes(in_core),
            human_bytes(memory),
            refused.join(", "),
            if refused.len() == 1 { "it" } else { "them" },
            human_bytes(in_core),
        )));
    }
    Ok(Some(Plan {
        memory,
        in_core,
        file_bytes,
        faces,
    }))
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
    ui: &Ui,
    a: &SimplifyArgs,
    format: lodkit_mesh::io::Format,
    opts: &Options,
    plan: &Plan,
) -> Result<()> {
    // The staging key holds everything that changes the blocks: the
    // options and the budget (the grid depends on nothing else).
    let settings = format!("{opts:?}; memory {}", plan.memory);
    let staging = lodkit_scale::staging_dir(&a.input, &a.output, &settings);
    ui.status(format!(
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
        ui.status(format!(
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
        ui.status(format!(
            "removed {}, the staging folder an earlier run for this output left",
            old.display()
        ));
    }
    if staging.exists() {
        ui.status(format!(
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
    let progress = ui.phases();
    let start = std::time::Instant::now();
    let result = lodkit_scale::simplify_file(&a.input, &so, &|e| match e {
        lodkit_scale::Event::Phase(name, len) => progress.phase(name, len),
        lodkit_scale::Event::Advance(n) => progress.advance(n),
    });
    progress.finish();
    let kept = |e: &dyn std::fmt::Display| super::lods_out_of_core::kept(e, &staging);
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
    super::lods_out_of_core::remove_staging(ui, &staging);
    if ui.is_verbose() {
        for (name, secs) in &rep.phases {
            ui.status(format!("{name}: {secs:.3} s"));
        }
    }
    if a.json {
        return super::print_json(&Report {
            input: &a.input,
            output: &a.output,
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
    ui.status(format!(
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
    ));
    Ok(())
}
