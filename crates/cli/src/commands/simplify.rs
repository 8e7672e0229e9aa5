//! `lodkit simplify IN -o OUT`: one mesh to one budget with the HQMS
//! simplifier (`lodkit-simplify`).
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::Args;
use lodkit_mesh::io::{WriteOptions, write_atomic};
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::{AttributeWeights, Options, Simplifier, Target};

use crate::ui::Ui;
use crate::ui::value::{self, Real};

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
    pub out: crate::ui::OutputArgs,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

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
