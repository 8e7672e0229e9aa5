//! `lodkit bench mco`: extraction time (birth/death tables and the §6.1
//! traversal) next to a memcpy of the same index buffer, in one run (meant to hang under `lodkit bench mco`).
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit_bench::mco::{default_targets, time_extraction};
use lodkit_mco::{McoModel, Options, build_from_mesh};

use crate::ui::Ui;

#[derive(Args, Debug)]
pub struct BenchMcoArgs {
    /// Models to measure (.mco, or a mesh to build first); default: the
    /// built-in bunny and a 1M-triangle synthetic blob.
    pub inputs: Vec<PathBuf>,
    /// Resolution for meshes built here (default: from the sampling).
    #[arg(long)]
    pub resolution: Option<u32>,
    /// Seconds spent per measured size (roughly).
    #[arg(long, default_value_t = 0.5)]
    pub budget: f64,
}

/// A model and how long it took to build (`None`: loaded from a file).
fn timed_build(mesh: &lodkit_mesh::TriMesh, opts: &Options) -> Result<(McoModel, Option<f64>)> {
    let t = std::time::Instant::now();
    let m = build_from_mesh(mesh, opts)?;
    Ok((m, Some(t.elapsed().as_secs_f64())))
}

fn table(ui: &Ui, name: &str, (m, seconds): &(McoModel, Option<f64>), budget: f64) -> Result<()> {
    let built = seconds.map_or(String::new(), |s| format!(", built in {s:.2} s"));
    ui.status(format!(
        "{name}: {} nodes, {} triangles at full resolution{built}",
        m.info().nodes,
        m.full_triangles(),
    ));
    crate::outln!(
        "| model | target | triangles | extract (µs) | 6.1 traversal (µs) | memcpy (µs) | ratio | traversal ratio | Mtris/s |"
    )?;
    crate::outln!("|---|---:|---:|---:|---:|---:|---:|---:|---:|")?;
    for r in time_extraction(m, &default_targets(m.full_triangles()), budget) {
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
    if args.inputs.is_empty() {
        let step = ui.spinner("building the bunny model");
        let bunny = super::builtin_bunny()?;
        let m = timed_build(&bunny, &opts)?;
        step.finish();
        table(ui, "bunny", &m, args.budget)?;
        let step = ui.spinner("building the 1M-triangle blob model");
        let blob = lodkit_mesh::shapes::blob(1_200_000);
        let m = timed_build(
            &blob,
            &Options {
                resolution: Some(350),
            },
        )?;
        step.finish();
        table(ui, "blob-1M", &m, args.budget)?;
        return Ok(());
    }
    for p in &args.inputs {
        let name = p.display().to_string();
        let m = if p.extension().is_some_and(|e| e.eq_ignore_ascii_case("mco")) {
            (McoModel::load(p)?, None)
        } else {
            timed_build(&super::load_mesh(ui, p)?, &opts)?
        };
        table(ui, &name, &m, args.budget)?;
    }
    Ok(())
}
