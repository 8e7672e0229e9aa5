//! `lodkit build [INPUT] --out DIR`: the main job.
//!
//! Loads the model (the built-in Stanford bunny when no input is given),
//! writes it as GLB and PLY, builds the discrete LOD chain (HQMS, each level
//! half the previous one) with its measured errors and an error chart, and
//! writes `report.md`. Each capability (continuous LOD, progressive
//! streams) adds its outputs and its section of the report here.
//!
//! Everything written is byte-identical from run to run, except the
//! per-level wall times in `lods/lods.json`.

use std::fmt::Write as _;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use lodkit_mesh::info::model_info;
use lodkit_mesh::io::{Format, WriteOptions, encode, write_atomic};
use lodkit_mesh::metrics::{CompareOptions, compare};
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::{Options, Target, halving_targets};
use plotters::style::{BLUE, RED, RGBColor};

use crate::chart::{Series, error_chart};
use crate::ui::Ui;

const BUILTIN_NAME: &str = "stanford_bunny";

#[derive(Args)]
pub struct BuildArgs {
    /// Input mesh; the built-in Stanford bunny when omitted.
    pub input: Option<PathBuf>,
    /// Output directory (created if missing).
    #[arg(long, short, default_value = "lodkit-out")]
    pub out: PathBuf,
    /// Levels of the discrete LOD chain, each half the previous one.
    #[arg(long, default_value_t = 6)]
    pub levels: usize,
    /// Samples per kind for the measured errors (`compare`).
    #[arg(long, default_value_t = 1_000_000)]
    pub samples: usize,
    /// Print the list of outputs as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(ui: &Ui, args: &BuildArgs) -> Result<()> {
    let out = args.out.as_path();
    let (name, model) = match &args.input {
        Some(path) => {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "model".into());
            (stem, super::load(ui, path)?)
        }
        None => {
            ui.status("no input given: building the built-in Stanford bunny (Stanford 3D Scanning Repository)");
            (
                BUILTIN_NAME.to_string(),
                Model::Mesh(super::builtin_bunny()?),
            )
        }
    };
    let mesh: &TriMesh = match &model {
        Model::Mesh(m) => m,
        other => anyhow::bail!(
            "{name}: holds a {} with no faces; `build` needs a mesh for now",
            other.kind()
        ),
    };
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output directory", out.display()))?;

    let mut outputs: Vec<(String, usize)> = Vec::new();
    for (format, ext) in [(Format::Glb, "glb"), (Format::Ply, "ply")] {
        let file = format!("{name}.{ext}");
        let step = ui.spinner(&format!("writing {file}"));
        let bytes = encode(format, &model, WriteOptions::default())
            .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
        write_atomic(&out.join(&file), &bytes)?;
        step.finish();
        outputs.push((file, bytes.len()));
    }

    let mut report = String::new();
    writeln!(report, "# lodkit build report: {name}\n")?;
    match &args.input {
        None => writeln!(
            report,
            "Input: the built-in Stanford Bunny (Stanford 3D Scanning Repository, Stanford University \
             Computer Graphics Laboratory).\n"
        )?,
        Some(p) => writeln!(report, "Input: `{}`\n", p.display())?,
    }
    writeln!(
        report,
        "## Input\n\n```text\n{}```\n",
        model_info(&model).to_text()
    )?;

    // Discrete LOD chain (HQMS).
    let lods_dir = out.join("lods");
    let chain = super::lods::write_chain(
        ui,
        mesh,
        &name,
        &name,
        &lods_dir,
        &halving_targets(args.levels),
        &Options {
            target: Target::Ratio(1.0),
            ..Options::DEFAULT
        },
        args.samples,
    )?;
    writeln!(
        report,
        "## Discrete LOD chain (HQMS)\n\nEach level is simplified from the previous one; errors are measured \
         against the input with `lodkit compare` ({} samples of each kind), symmetric, in object units \
         (bounding-box diagonal {:.6}).\n",
        args.samples,
        mesh.bbox().diagonal()
    )?;
    writeln!(
        report,
        "| level | file | triangles | vertices | estimated error | measured mean | measured max | stopped |\n\
         |---:|---|---:|---:|---:|---:|---:|---|"
    )?;
    writeln!(
        report,
        "| 0 | `{name}.ply` | {} | {} | 0 | 0 | 0 | input |",
        mesh.faces.len(),
        mesh.positions.len()
    )?;
    for l in &chain.levels {
        writeln!(
            report,
            "| {} | `lods/{}` | {} | {} | {:.3e} | {:.3e} | {:.3e} | {} |",
            l.level,
            l.file,
            l.triangles,
            l.vertices,
            l.estimated_error,
            l.measured_mean_error,
            l.measured_max_error,
            l.stop
        )?;
    }
    writeln!(
        report,
        "\nAll levels in one file: `lods/{}` (one node per level); per-level data and times: `lods/lods.json`.\n",
        chain.glb
    )?;
    let curve = |f: fn(&super::lods::Level) -> f64| -> Vec<(f64, f64)> {
        chain
            .levels
            .iter()
            .map(|l| (l.triangles as f64, f(l)))
            .collect()
    };
    let svg = error_chart(
        &format!("{name}: error against triangle count"),
        &[
            Series {
                name: "measured max (Hausdorff)",
                points: curve(|l| l.measured_max_error),
                color: RED,
            },
            Series {
                name: "measured mean",
                points: curve(|l| l.measured_mean_error),
                color: BLUE,
            },
            Series {
                name: "estimated (quadric)",
                points: curve(|l| l.estimated_error as f64),
                color: RGBColor(120, 120, 120),
            },
        ],
    )?;
    write_atomic(&out.join("lod_error.svg"), svg.as_bytes())?;
    writeln!(report, "![error against triangle count](lod_error.svg)\n")?;
    for l in &chain.levels {
        outputs.push((format!("lods/{}", l.file), 0));
    }
    outputs.push((format!("lods/{}", chain.glb), 0));
    outputs.push(("lods/lods.json".into(), 0));
    outputs.push(("lod_error.svg".into(), svg.len()));

    // Continuous LOD: the marching cube octree built from virtual scans.
    let input = Input {
        ui,
        mesh,
        name: &name,
        out,
        samples: args.samples,
    };
    continuous_lod(&input, &mut report, &mut outputs)?;

    // Progressive stream: octree particles, level by level.
    progressive_stream(&input, &mut report, &mut outputs)?;

    writeln!(report, "## Outputs\n\n| file | bytes |\n|---|---:|")?;
    for (file, _) in &outputs {
        // lods.json holds wall times, so its size may change between runs;
        // the report stays byte-identical by not quoting it.
        let path = out.join(file);
        let len = std::fs::metadata(&path)
            .with_context(|| format!("{}", path.display()))?
            .len();
        if file.ends_with(".json") {
            writeln!(report, "| `{file}` | (varies: holds timings) |")?;
        } else {
            writeln!(report, "| `{file}` | {len} |")?;
        }
    }
    write_atomic(&out.join("report.md"), report.as_bytes())?;
    outputs.push(("report.md".into(), report.len()));
    for (file, bytes) in outputs.iter_mut() {
        *bytes = std::fs::metadata(out.join(&*file))
            .map(|m| m.len() as usize)
            .unwrap_or(0);
    }

    if args.json {
        let list: Vec<_> = outputs
            .iter()
            .map(|(file, bytes)| serde_json::json!({ "path": out.join(file), "bytes": bytes }))
            .collect();
        return super::print_json(&serde_json::json!({ "model": name, "outputs": list }));
    }
    for (file, bytes) in &outputs {
        ui.status(format!(
            "wrote {} ({bytes} bytes)",
            out.join(file).display()
        ));
    }
    Ok(())
}

/// What every section of the build reads: the input mesh, its name, the
/// output directory and the sample count for error measurements.
#[derive(Clone, Copy)]
struct Input<'a> {
    ui: &'a Ui,
    mesh: &'a TriMesh,
    name: &'a str,
    out: &'a std::path::Path,
    samples: usize,
}

/// The thesis's experiment on the input: 8 virtual range scans
/// (`scans/`), the marching cube octree built from them (`NAME.mco`), and
/// extractions at 50 / 10 / 1 % of its full size, each measured against
/// the input next to an HQMS simplification of the input to the same
/// triangle count.
fn continuous_lod(
    input: &Input,
    report: &mut String,
    outputs: &mut Vec<(String, usize)>,
) -> Result<()> {
    let Input {
        ui,
        mesh,
        name,
        out,
        samples,
    } = *input;
    let step = ui.spinner("scanning the input from 8 virtual views");
    let scans = lodkit_mco::scan_mesh(mesh, &BUILD_SCANS)?;
    let written = lodkit_mco::write_scans(&out.join("scans"), name, &scans)?;
    step.finish();
    let step = ui.spinner("building the marching cube octree");
    let model = lodkit_mco::build_from_range_images(&scans, &lodkit_mco::Options::default())?;
    let mco_file = format!("{name}.mco");
    model.save(&out.join(&mco_file))?;
    step.finish();
    let step = ui.spinner("measuring extractions");
    let rows = extraction_errors(&model, mesh, &[50.0, 10.0, 1.0], Some(samples))?;
    let copts = CompareOptions {
        samples: Some(samples),
        ..CompareOptions::default()
    };
    let mut hqms = Vec::with_capacity(rows.len());
    for r in &rows {
        let s = lodkit_simplify::simplify(
            mesh,
            &Options {
                target: Target::Faces(r.triangles),
                ..Options::DEFAULT
            },
        )
        .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        hqms.push(compare(&s.mesh, mesh, &copts)?.symmetric);
    }
    step.finish();
    writeln!(
        report,
        "## Continuous LOD (marching cube octree)\n\n{} virtual range scans of the input ({}×{}, \
         `scans/`, with `{name}.conf`) rebuilt as a marching cube octree (`{mco_file}`: {} triangles \
         at full resolution, LOD numbers 0..={}). Any triangle budget is cut from it by referencing only; \
         below, extractions at fractions of full size against the input, next to HQMS simplifying \
         the input to the same count ({samples} samples of each kind, symmetric).\n",
        scans.len(),
        BUILD_SCANS.width,
        BUILD_SCANS.height,
        model.full_triangles(),
        model.max_lod(),
    )?;
    writeln!(
        report,
        "| % of full | LOD | triangles | MCO mean | MCO max | HQMS mean | HQMS max |\n|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for (r, h) in rows.iter().zip(&hqms) {
        writeln!(
            report,
            "| {} | {} | {} | {:.3e} | {:.3e} | {:.3e} | {:.3e} |",
            r.percent, r.lod, r.triangles, r.mean, r.max, h.mean, h.max
        )?;
    }
    writeln!(report)?;
    for p in written {
        let rel = p.strip_prefix(out).unwrap_or(&p).display().to_string();
        outputs.push((rel, 0));
    }
    outputs.push((mco_file, 0));
    Ok(())
}

/// The virtual scans of `build`'s continuous-LOD section: 8 views,
/// alternately 30° above and below the horizon, 300 × 300 samples each.
const BUILD_SCANS: lodkit_mco::ScanOptions = lodkit_mco::ScanOptions {
    views: 8,
    width: 300,
    height: 300,
    elevation_deg: 30.0,
    alternate: true,
    noise: 0.0,
    seed: 1,
};

/// One extraction of the continuous model measured against the input.
struct ExtractionError {
    /// Requested fraction of the full triangle count, per cent.
    percent: f64,
    lod: usize,
    triangles: usize,
    /// Symmetric mean and max (Hausdorff) distance, object units.
    mean: f64,
    max: f64,
}

/// Extractions at `percents` of full size, each compared with `reference`
/// (Metro, `samples` per kind); empty extractions are left out.
fn extraction_errors(
    model: &lodkit_mco::McoModel,
    reference: &TriMesh,
    percents: &[f64],
    samples: Option<usize>,
) -> Result<Vec<ExtractionError>> {
    let full = model.full_triangles();
    let opts = CompareOptions {
        samples,
        ..Default::default()
    };
    let mut out = Vec::with_capacity(percents.len());
    let mut idx = Vec::new();
    for &percent in percents {
        let target = ((full as f64 * percent / 100.0).round() as usize).max(1);
        let lod = model.extract_triangles(target, &mut idx);
        let mesh = model.mesh_from_indices(&idx);
        if mesh.faces.is_empty() {
            continue;
        }
        let r = compare(&mesh, reference, &opts)?.symmetric;
        out.push(ExtractionError {
            percent,
            lod,
            triangles: mesh.faces.len(),
            mean: r.mean,
            max: r.max,
        });
    }
    Ok(out)
}

/// The input as a progressive octree-particle stream (`NAME.pop`, entropy
/// mode, outer thinning): per level, the bytes a reader needs so far, the
/// particles, the triangles of the direct triangulation and their error
/// against the input.
fn progressive_stream(
    input: &Input,
    report: &mut String,
    outputs: &mut Vec<(String, usize)>,
) -> Result<()> {
    let Input {
        ui,
        mesh,
        name,
        out,
        samples,
    } = *input;
    use lodkit_particles::ThinningOptions;
    use lodkit_particles::TriangulateOptions;
    use lodkit_particles::{EncodeOptions, encode, progressive_levels};
    let step = ui.spinner("encoding the progressive particle stream");
    // Outer thinning keeps non-manifold triangles rare (see crates/particles).
    let opts = EncodeOptions {
        thinning: ThinningOptions {
            outer: true,
            ..ThinningOptions::DEFAULT
        },
        ..EncodeOptions::DEFAULT
    };
    let enc =
        encode(&Model::Mesh(mesh.clone()), &opts).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    let file = format!("{name}.pop");
    write_atomic(&out.join(&file), &enc.bytes)?;
    step.finish();
    let step = ui.spinner("decoding and measuring every level");
    let levels = progressive_levels(&enc.bytes, &TriangulateOptions::DEFAULT)
        .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
    let copts = CompareOptions {
        samples: Some(samples),
        ..CompareOptions::default()
    };
    writeln!(
        report,
        "## Progressive stream (octree particles)\n\n`{file}` ({} bytes, entropy-coded, outer thinning{}): \
         a reader that has the first *bytes so far* can show level *r*, triangulated directly from its \
         particles, with *N* bits per coordinate (the level chunks alone give N = R; the refinement \
         layers that follow them bring the finest level to the stream's full precision); errors \
         against the input, symmetric ({samples} samples of each kind).\n",
        enc.bytes.len(),
        enc.report.relax_below.map_or(String::new(), |l| format!(
            " relaxed below level {l}, the level chosen for this object"
        ))
    )?;
    writeln!(
        report,
        "| level | N | bytes so far | particles | triangles | mean error | max error |\n|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for l in &levels {
        let (mean, max) = if l.mesh.faces.is_empty() {
            ("-".to_string(), "-".to_string())
        } else {
            let c = compare(&l.mesh, mesh, &copts)?;
            (
                format!("{:.3e}", c.symmetric.mean),
                format!("{:.3e}", c.symmetric.max),
            )
        };
        writeln!(
            report,
            "| {} | {} | {} | {} | {} | {mean} | {max} |",
            l.level,
            l.precision,
            l.bytes_so_far,
            l.particles,
            l.mesh.faces.len()
        )?;
    }
    writeln!(report)?;
    step.finish();
    outputs.push((file, 0));
    Ok(())
}
