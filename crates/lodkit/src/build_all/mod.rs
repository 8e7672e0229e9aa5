//! The build job (`lodkit build [INPUT] --out DIR`), the main one.
//!
//! Stages, one file each in this folder: the input of any kind
//! (`input.rs`: meshes as they are, point clouds, range images and scan
//! sets reconstructed first), the discrete LOD chain ([`crate::lod_chain`],
//! HQMS), the continuous model (`continuous.rs`, marching cube octree), the
//! progressive stream (`progressive.rs`, octree particles), each measured
//! against the input through one shared distance index ([`crate::measure`]),
//! the 3D Tiles tileset (`tileset.rs`, `lodkit_tiles`), then
//! `report.md` and `report.html` (`html.rs`, `html_page.rs`).
//!
//! Every option is checked before anything is written, and the whole
//! folder is written beside `--out` and moved into place at the end
//! (`staging.rs`): a failed or killed build leaves `--out` as it was, and
//! only a folder an earlier build made (its `.lodkit-build.json` lists
//! every file) is ever replaced.
//!
//! Everything written is byte-identical from run to run, except the
//! per-level wall times in `lods/lods.json` and the stage timings in
//! `report.html` (and so those two files' sizes in `.lodkit-build.json`).

mod chart;
mod continuous;
mod html;
mod html_page;
mod input;
pub(crate) mod progressive;
mod staging;
mod tileset;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use anyhow::{Context, Result};
use lodkit_mesh::info::model_info;
use lodkit_mesh::io::{Format, WriteOptions, write_atomic};
use lodkit_mesh::metrics::Reference;
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::halving_targets;
use plotters::style::{BLUE, RED, RGBColor};

use crate::measure;
pub use crate::measure::Sampling;
use crate::output::OutputOptions;
use crate::progress::{Event, Progress};
use chart::{Series, error_chart};

const BUILTIN_NAME: &str = "stanford_bunny";
/// One build: what [`run`] reads, writes and how.
#[derive(Debug, Clone)]
pub struct BuildJob {
    /// Input: a mesh (any format), a point cloud (.xyz, .pts, PLY without
    /// faces), a range image (range-grid PLY), a scan set (.conf, or a
    /// folder of range images) or a calibrated image set; the built-in
    /// Stanford bunny when `None`.
    pub input: Option<PathBuf>,
    /// Output folder; replaced as a whole when the build succeeds, and
    /// only when an earlier build made it.
    pub out: PathBuf,
    /// Levels of the discrete LOD chain, each half the previous one
    /// ([`crate::limits::LEVELS`]).
    pub levels: usize,
    /// How every error is measured (samples per kind, or skipped).
    pub sampling: Sampling,
    /// Merge a textured or multi-part input into one mesh (materials and
    /// textures dropped) instead of keeping them in the GLB outputs.
    pub merge: bool,
    /// Normals and compression of the meshes written.
    pub output: OutputOptions,
}

/// What [`run`] wrote.
#[derive(Debug, Clone, serde::Serialize)]
pub struct BuildReport {
    /// The model's name (the input's stem, or `stanford_bunny`).
    pub model: String,
    /// Each file written, relative to the output folder, with its size
    /// (the tileset by its `tiles/tileset.json`; the manifest lists its
    /// tiles too).
    pub outputs: Vec<(String, usize)>,
}

/// The wall time of each stage, for the HTML report.
pub struct Timings(pub Vec<(String, f64)>);

impl Timings {
    fn time<T>(&mut self, stage: &str, f: impl FnOnce() -> Result<T>) -> Result<T> {
        let t = Instant::now();
        let r = f()?;
        self.0.push((stage.to_string(), t.elapsed().as_secs_f64()));
        Ok(r)
    }
}

/// Builds every level of detail of `args.input` into `args.out`: the
/// input as GLB and PLY, the HQMS chain (`lods/`), the marching cube
/// octree (`.mco`), the progressive stream (`.pop`), the 3D Tiles
/// tileset (`tiles/tileset.json`, `lodkit_tiles`), each measured
/// against the input, with `report.md`, `report.html` and the manifest
/// `.lodkit-build.json`. The folder is made beside `args.out` and moved
/// into place at the end: a failed build leaves `args.out` as it was.
/// Errors: the input named with what is wrong; an output folder lodkit
/// did not make is a [`crate::usage::Usage`]; a degenerate product is an
/// error after the whole folder is written (each sent as
/// [`Event::Warning`]). Cost: dominated by the octree build and the
/// measurements (about 4 samples per face of each level).
pub fn run(args: &BuildJob, events: &Progress) -> Result<BuildReport> {
    let sampling = args.sampling;
    let mut timings = Timings(Vec::new());
    // Everything that can fail on the input or the options fails here,
    // before the output folder is touched.
    let input = timings.time("reading the input", || match &args.input {
        Some(path) => input::load(events, path, args.merge),
        None => {
            events.status("no input given: building the built-in Stanford bunny (Stanford 3D Scanning Repository)");
            let m = crate::input::builtin_bunny()?;
            Ok(input::BuildInput {
                name: BUILTIN_NAME.to_string(),
                samples: (m.positions.len(), "vertices"),
                stream_source: Model::Mesh(m.clone()),
                surface: m,
                reconstruction: None,
                path: input::InputPath::Mesh,
                scene: None,
            })
        }
    })?;
    if let (Some(scene), Some(path)) = (&input.scene, &args.input) {
        // The report draws the textures: their pixels are checked now,
        // before the output folder is touched.
        crate::materials::texture_budget(&path.display().to_string(), scene)?;
    }
    let staging = staging::Staging::new(&args.out, args.input.as_deref())?;
    let Written {
        outputs,
        degenerate,
    } = write_all(events, args, &input, sampling, staging.dir(), &mut timings)?;
    staging.commit()?;
    let out = args.out.as_path();
    if !degenerate.is_empty() {
        // Written whole (the report says what went wrong), but not a
        // success: a warning per product, even under -q, and exit 1.
        let source = args
            .input
            .as_ref()
            .map_or(input.name.clone(), |p| p.display().to_string());
        for d in &degenerate {
            events.emit(&Event::Warning(&format!(
                "warning: {source}: degenerate {d}"
            )));
        }
        anyhow::bail!(
            "{source}: {} degenerate product(s) in {}; see its report.md",
            degenerate.len(),
            out.display()
        );
    }
    Ok(BuildReport {
        model: input.name,
        outputs,
    })
}

/// Writes every output into `dir`; returns each file (relative) and its
/// size.
fn write_all(
    events: &Progress,
    args: &BuildJob,
    input: &input::BuildInput,
    sampling: Sampling,
    dir: &Path,
    timings: &mut Timings,
) -> Result<Written> {
    let name = input.name.as_str();
    let mesh: &TriMesh = &input.surface;
    let model = Model::Mesh(mesh.clone());
    let mut outputs: Vec<String> = Vec::new();
    timings.time("writing the input as GLB and PLY", || {
        for (format, ext) in [(Format::Glb, "glb"), (Format::Ply, "ply")] {
            let file = format!("{name}.{ext}");
            let step = events.spinner(&format!("writing {file}"));
            let bytes = match (&input.scene, format) {
                // A scene's GLB keeps its materials, images and nodes; its
                // PLY is the scene merged (one mesh, UVs kept).
                (Some(scene), Format::Glb) => {
                    let scene = args.output.scene(scene.clone(), &dir.join(&file))?;
                    lodkit_mesh::io::gltf::write_scene_glb_with(&scene, &args.output.glb())
                }
                _ => args.output.encode(format, &model, WriteOptions::default()),
            }
            .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
            write_atomic(&dir.join(&file), &bytes)?;
            step.finish();
            outputs.push(file);
        }
        Ok(())
    })?;

    let mut report = String::new();
    writeln!(report, "# lodkit build report: {name}\n")?;
    let input_sentence = match &args.input {
        None => "Input: the built-in Stanford Bunny (Stanford 3D Scanning Repository, Stanford University \
                 Computer Graphics Laboratory)."
            .to_string(),
        Some(p) => format!("Input: `{}`", p.display()),
    };
    writeln!(report, "{input_sentence}\n")?;
    let mut path_sentence = path_sentence(&input.path, name);
    if let Some(scene) = &input.scene {
        write!(
            path_sentence,
            " Its materials are kept ({}): `{name}.glb` and every level of the HQMS chain \
             (`lods/*.glb`) carry them, one primitive per material (each level's images scaled to \
             its size), and so do the tiles (`tiles/`); \
             `{name}.ply`, the octree and the stream hold its geometry merged into one mesh.",
            crate::input::describe(scene)
        )?;
    }
    writeln!(report, "{path_sentence}\n")?;
    writeln!(
        report,
        "## Input\n\n```text\n{}```\n",
        model_info(&model).to_text()
    )?;

    let reference = timings.time("indexing the input for measurement", || {
        Reference::new(mesh).map_err(|e| anyhow::anyhow!("{name}: {e}"))
    })?;

    // Discrete LOD chain (HQMS).
    let chain = timings.time("HQMS chain (simplify, measure, write)", || {
        let opts = lodkit_simplify::Options {
            target: lodkit_simplify::Target::Ratio(1.0),
            ..lodkit_simplify::Options::DEFAULT
        };
        let (out, targets) = (dir.join("lods"), halving_targets(args.levels));
        crate::lod_chain::write_chain(
            events,
            &reference,
            name,
            name,
            &out,
            input.scene.as_ref(),
            &targets,
            &opts,
            sampling,
            &args.output,
            &mut |_| {},
        )
    })?;
    writeln!(
        report,
        "## Discrete LOD chain (HQMS)\n\nEach level is simplified from the previous one; errors {}, \
         in object units (bounding-box diagonal {:.6}).\n",
        sampling.describe(),
        mesh.bbox().diagonal()
    )?;
    writeln!(
        report,
        "| level | file | triangles | vertices | samples | estimated error | measured mean | measured max | stopped |\n\
         |---:|---|---:|---:|---:|---:|---:|---:|---|"
    )?;
    writeln!(
        report,
        "| 0 | `{name}.ply` | {} | {} | - | 0 | 0 | 0 | input |",
        mesh.faces.len(),
        mesh.positions.len()
    )?;
    for (l, m) in chain.lods.levels.iter().zip(&chain.measured) {
        writeln!(
            report,
            "| {} | `lods/{}` | {} | {} | {} | {:.3e} | {} | {} | {} |",
            l.level,
            l.file,
            l.triangles,
            l.vertices,
            m.map_or("-".into(), |m| m.samples.to_string()),
            l.estimated_error,
            measure::cell(m.map(|m| m.mean)),
            measure::cell(m.map(|m| m.max)),
            l.stop
        )?;
    }
    writeln!(
        report,
        "\nAll levels in one file: `lods/{}` (one node per level); per-level data and times: `lods/lods.json`.\n",
        chain.lods.glb
    )?;
    let curve = |f: &dyn Fn(usize) -> Option<f64>| -> Vec<(f64, f64)> {
        chain
            .lods
            .levels
            .iter()
            .enumerate()
            .filter_map(|(i, l)| f(i).map(|y| (l.triangles as f64, y)))
            .collect()
    };
    let svg = error_chart(
        &format!("{name}: error against triangle count"),
        &[
            Series {
                name: "measured max (Hausdorff)",
                points: curve(&|i| chain.measured[i].map(|m| m.max)),
                color: RED,
            },
            Series {
                name: "measured mean",
                points: curve(&|i| chain.measured[i].map(|m| m.mean)),
                color: BLUE,
            },
            Series {
                name: "estimated (quadric)",
                points: curve(&|i| Some(chain.lods.levels[i].estimated_error as f64)),
                color: RGBColor(120, 120, 120),
            },
        ],
    )?;
    write_atomic(&dir.join("lod_error.svg"), svg.as_bytes())?;
    writeln!(report, "![error against triangle count](lod_error.svg)\n")?;
    for l in &chain.lods.levels {
        outputs.push(format!("lods/{}", l.file));
    }
    outputs.push(format!("lods/{}", chain.lods.glb));
    outputs.push("lods/lods.json".into());
    outputs.push("lod_error.svg".into());

    let cont = timings.time("marching cube octree (build, cut, measure)", || {
        continuous::section(
            events,
            &reference,
            input.reconstruction.as_ref(),
            name,
            dir,
            sampling,
            &mut report,
        )
    })?;
    outputs.extend(cont.files.iter().cloned());

    let prog = timings.time("progressive stream (encode, decode, measure)", || {
        progressive::section(events, &reference, input, dir, sampling, &mut report)
    })?;
    outputs.push(prog.file.clone());

    let tiles = timings.time("3D Tiles tileset (levels, measure, write)", || {
        tileset::section(events, input, args, dir, &mut report)
    })?;
    outputs.push(tileset::TILESET.into());

    let details = details(input, &cont, &prog);
    let diagonal = mesh.bbox().diagonal() as f64;
    writeln!(
        report,
        "## Detail against the input\n\nEach product's finest level beside the input's samples it \
         should keep (about as many; under {} % of them, under {} triangles or particles, or a mean \
         error over {} % of the diagonal is a degenerate product, and the build fails).\n",
        measure::SMALLEST_SHARE * 100.0,
        measure::FEWEST_PRIMITIVES,
        measure::LARGEST_MEAN_ERROR * 100.0
    )?;
    writeln!(
        report,
        "| product | finest level | input | share | mean error | verdict |\n|---|---:|---:|---:|---:|---|"
    )?;
    let mut degenerate = Vec::new();
    for d in &details {
        let verdict = d.degenerate(diagonal);
        writeln!(
            report,
            "| {} | {} {} | {} {} | {:.2} | {} | {} |",
            d.product,
            d.count,
            d.unit,
            d.expected,
            d.expected_unit,
            d.count as f64 / d.expected.max(1) as f64,
            measure::cell(d.mean),
            verdict.as_deref().unwrap_or("ok"),
        )?;
        if let Some(v) = verdict {
            degenerate.push(format!("{}: {v}", d.product));
        }
    }
    writeln!(report)?;

    writeln!(report, "## Outputs\n\n| file | bytes |\n|---|---:|")?;
    for file in &outputs {
        // lods.json holds wall times, so its size may change between runs;
        // the report stays byte-identical by not quoting it.
        let path = dir.join(file);
        let len = std::fs::metadata(&path)
            .with_context(|| format!("{}", path.display()))?
            .len();
        if file.ends_with(".json") {
            writeln!(report, "| `{file}` | (varies: holds timings) |")?;
        } else {
            writeln!(report, "| `{file}` | {len} |")?;
        }
    }
    write_atomic(&dir.join("report.md"), report.as_bytes())?;
    outputs.push("report.md".into());
    let step = events.spinner("rendering report.html");
    let materials = input
        .scene
        .as_ref()
        .map(|s| crate::materials::render_materials(events, name, s, s.merged().face_materials))
        .transpose()?;
    let html = html::report(&html::Inputs {
        name,
        intro: vec![
            input_sentence.replace('`', ""),
            path_sentence.replace('`', ""),
            tiles.replace('`', ""),
        ],
        reference: &reference,
        sampling,
        chain: &chain,
        continuous: &cont,
        progressive: &prog,
        timings: &timings.0,
        degenerate: &degenerate,
        materials: materials.as_ref(),
    })?;
    write_atomic(&dir.join("report.html"), html.as_bytes())?;
    step.finish();
    outputs.push("report.html".into());
    let outputs = outputs
        .into_iter()
        .map(|file| {
            let path = dir.join(&file);
            let len = std::fs::metadata(&path)
                .with_context(|| format!("{}", path.display()))?
                .len() as usize;
            Ok((file, len))
        })
        .collect::<Result<_>>()?;
    Ok(Written {
        outputs,
        degenerate,
    })
}

/// What [`write_all`] wrote: each file (relative) with its size, and the
/// degenerate products (one line each; see [`measure::Detail`]).
struct Written {
    outputs: Vec<(String, usize)>,
    degenerate: Vec<String>,
}

/// Each product's finest level against the input's samples: the stream's
/// particles against the samples it encodes (a mesh's vertices, a cloud's
/// points), the octree's full cut against a mesh's triangles, or against
/// the reconstructed input's samples.
fn details(
    input: &input::BuildInput,
    cont: &continuous::Continuous,
    prog: &progressive::Progressive,
) -> Vec<measure::Detail> {
    let (samples, unit) = input.samples;
    let finest = prog.levels.last();
    let stream = measure::Detail {
        product: format!("stream {}", prog.file),
        count: finest.map_or(0, |l| l.particles),
        unit: "particles",
        triangles: finest.map_or(0, |l| l.mesh.faces.len()),
        expected: samples,
        expected_unit: unit,
        mean: finest.and_then(|l| l.measured).map(|m| m.mean),
    };
    let (expected, expected_unit) = match input.path {
        input::InputPath::Mesh => (input.surface.faces.len(), "triangles"),
        _ => (samples, unit),
    };
    let full = cont.cuts.iter().find(|c| c.percent == 100.0);
    let octree = measure::Detail {
        product: format!("octree {}", cont.file),
        count: cont.full_triangles,
        unit: "triangles",
        triangles: cont.full_triangles,
        expected,
        expected_unit,
        mean: full.and_then(|c| c.mco).map(|m| m.mean),
    };
    vec![octree, stream]
}

/// The report's sentence on which path the input took.
fn path_sentence(path: &input::InputPath, name: &str) -> String {
    match path {
        input::InputPath::Mesh => {
            "Path: a mesh. The HQMS chain simplifies it, the marching cube octree is \
             built from it, the progressive stream encodes it; every error is measured against it."
                .to_string()
        }
        input::InputPath::Reconstructed(what) => format!(
            "Path: a {what}, reconstructed first as a marching cube octree (`lodkit mco build`); \
             its full-resolution surface (`{name}.ply`) feeds the HQMS chain and is the reference \
             every error is measured against; the progressive stream encodes it too."
        ),
        input::InputPath::Carved(what, _) => format!(
            "Path: a {what} (`lodkit pop encode --silhouettes`); the finest level of its particles, \
             triangulated (`{name}.ply`), feeds the HQMS chain and the marching cube octree (built from it) and is \
             the reference every error is measured against; the progressive stream encodes the \
             carved particles as points."
        ),
    }
}
