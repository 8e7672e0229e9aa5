//! `lodkit-bench mco [MODEL...]`: extraction time (birth/death tables and
//! the §6.1 traversal) next to a memcpy of the same index buffer.
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use lodkit_bench::mco::{default_targets, time_extraction};
use lodkit_mco::{McoModel, Options, build_from_mesh};

use crate::ui::{Ui, value};
use lodkit::limits::{self, Real};
use serde::Serialize;

/// Marching-cube-octree extraction time next to memcpy of the same index buffer.
#[derive(Args, Debug)]
pub struct BenchMcoArgs {
    /// Models to measure (.mco, or a mesh to build first); default: the
    /// built-in bunny and a 1M-triangle synthetic blob.
    pub inputs: Vec<PathBuf>,
    /// Resolution for meshes built here, in 2..=512 (default: from the sampling).
    #[arg(long, value_parser = value::range_u32(limits::MCO_RESOLUTION))]
    pub resolution: Option<u32>,
    /// Seconds spent per measured size (roughly), in (0, 60].
    #[arg(long, default_value_t = 0.5, value_parser = Real::open_closed(0.0, 60.0).f64())]
    pub budget: f64,
    /// Print the rows as JSON.
    #[arg(long)]
    pub json: bool,
}

/// One measured size of one model, for `--json`.
#[derive(Serialize)]
struct Row {
    model: String,
    target: usize,
    triangles: usize,
    extract_us: f64,
    traversal_us: f64,
    memcpy_us: f64,
    ratio: f64,
    traversal_ratio: f64,
    mtris_per_s: f64,
}

/// A model and how long it took to build (`None`: loaded from a file).
fn timed_build(mesh: &lodkit_mesh::TriMesh, opts: &Options) -> Result<(McoModel, Option<f64>)> {
    let t = std::time::Instant::now();
    let m = build_from_mesh(mesh, opts)?;
    Ok((m, Some(t.elapsed().as_secs_f64())))
}

/// Measures one model: prints its table, or adds its rows to `json`.
fn table(
    ui: &Ui,
    name: &str,
    (m, seconds): &(McoModel, Option<f64>),
    budget: f64,
    json: Option<&mut Vec<Row>>,
) -> Result<()> {
    let built = seconds.map_or(String::new(), |s| format!(", built in {s:.2} s"));
    ui.status(format!(
        "{name}: {} nodes, {} triangles at full resolution{built}",
        m.info().nodes,
        m.full_triangles(),
    ));
    let step = ui.stage(&format!("timing extraction of {name}"));
    let rows = time_extraction(m, &default_targets(m.full_triangles()), budget);
    step.finish();
    if let Some(out) = json {
        out.extend(rows.iter().map(|r| Row {
            model: name.to_string(),
            target: r.target,
            triangles: r.triangles,
            extract_us: r.extract_s * 1e6,
            traversal_us: r.traversal_s * 1e6,
            memcpy_us: r.memcpy_s * 1e6,
            ratio: r.ratio(),
            traversal_ratio: r.traversal_ratio(),
            mtris_per_s: r.mtris_per_s(),
        }));
        return Ok(());
    }
    crate::outln!(
        "| model | target | triangles | extract (µs) | 6.1 traversal (µs) | memcpy (µs) | ratio | traversal ratio | Mtris/s |"
    )?;
    crate::outln!("|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for r in rows {
        crate::outln!(
            "| {name} | {} | {} | {:.1} | {:.1} | {:.1} | {:.2} | {:.2} | {:.0} |",
            r.target,
            r.triangles,
            r.extract_s * 1e6,
            r.traversal_s * 1e6,
            r.memcpy_s * 1e6,
            r.ratio(),
            r.traversal_ratio(),
            r.mtris_per_s()
        )?;
    }
    let info = m.info();
    ui.status(format!(
        "{name}: birth/death tables {:.1} MB in {} death buckets; traversal arrays {:.1} MB (built on first use); stored triangles {:.1} MB",
        info.extraction_table_bytes as f64 / 1e6,
        info.death_buckets,
        info.traversal_bytes as f64 / 1e6,
        info.stored_triangle_bytes as f64 / 1e6
    ));
    Ok(())
}

pub fn run(ui: &Ui, args: &BenchMcoArgs) -> Result<()> {
    let opts = Options {
        resolution: args.resolution,
    };
    let mut rows: Option<Vec<Row>> = args.json.then(Vec::new);
    if args.inputs.is_empty() {
        let step = ui.stage("building the bunny model");
        let bunny = lodkit::input::builtin_bunny()?;
        let m = timed_build(&bunny, &opts)?;
        step.finish();
        table(ui, "bunny", &m, args.budget, rows.as_mut())?;
        let step = ui.stage("building the 1M-triangle blob model");
        let blob = lodkit_mesh::shapes::blob(1_200_000);
        let m = timed_build(
            &blob,
            &Options {
                resolution: Some(350),
            },
        )?;
        step.finish();
        table(ui, "blob-1M", &m, args.budget, rows.as_mut())?;
    } else {
        for p in &args.inputs {
            let name = p.display().to_string();
            let m = if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("mco")) {
                (McoModel::load(p)?, None)
            } else {
                let mesh = crate::ui::load_mesh(p)?;
                let step = ui.stage(&format!("building the model of {name}"));
                let m = timed_build(&mesh, &opts).with_context(|| name.clone())?;
                step.finish();
                m
            };
            table(ui, &name, &m, args.budget, rows.as_mut())?;
        }
    }
    match rows {
        Some(rows) => crate::ui::print_json(&rows),
        None => Ok(()),
    }
}
