//! `lodkit-bench simplify [MESH...]`: lodkit's simplifier against
//! meshoptimizer in this process (see `lodkit_bench::simplify`; needs the
//! `peers` feature, else a one-line error and exit 2).
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit_bench::simplify::{BenchConfig, format_table, run_case, standard_targets};
use lodkit_mesh::TriMesh;

use crate::ui::{Ui, value};

/// Largest synthetic blob of `bench simplify --blob`, in triangles.
const MAX_BLOB: usize = 10_000_000;

/// HQMS vs meshopt_simplify at 50%, 10%, 1% and 1,000 triangles.
#[derive(Args, Debug)]
pub struct SimplifyArgs {
    /// Meshes to run (default: the bunny and a 1M-triangle blob).
    pub meshes: Vec<PathBuf>,
    /// Timed runs per side (the best is kept), in 1..=100.
    #[arg(long, default_value_t = 3, value_parser = value::range(1..=100))]
    pub runs: usize,
    /// Samples per kind for the error measurement, in 1..=10000000.
    #[arg(long, default_value_t = 1_000_000, value_parser = value::range(lodkit::limits::SAMPLES))]
    pub samples: usize,
    /// Triangles of the synthetic blob when no mesh is given, in
    /// 1000..=10000000.
    #[arg(long, default_value_t = 1_000_000, value_parser = value::range(1000..=MAX_BLOB), conflicts_with = "meshes")]
    pub blob: usize,
    /// Print the rows as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(ui: &Ui, a: &SimplifyArgs) -> Result<()> {
    let SimplifyArgs {
        meshes,
        runs,
        samples,
        blob,
        json,
    } = a;
    if !lodkit_bench::PEERS {
        return Err(lodkit::usage::Usage(format!(
            "lodkit-bench simplify: {}",
            lodkit_bench::simplify::NO_PEERS
        ))
        .into());
    }
    let mut inputs: Vec<(String, TriMesh)> = Vec::new();
    if meshes.is_empty() {
        inputs.push(("bunny".into(), lodkit::input::builtin_bunny()?));
        inputs.push((format!("blob {}", blob), lodkit_mesh::shapes::blob(*blob)));
    } else {
        for p in meshes {
            let name = p.display().to_string();
            inputs.push((name, crate::ui::load_mesh(p)?));
        }
    }
    let cfg = BenchConfig {
        runs: *runs,
        samples: *samples,
    };
    let mut rows = Vec::new();
    for (name, mesh) in &inputs {
        for (label, target) in standard_targets() {
            let step = ui.stage(&format!("{name} at {label}"));
            let row = run_case(name, mesh, &label, target, &cfg)
                .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
            step.finish();
            if !json {
                ui.status(
                    format_table(std::slice::from_ref(&row))
                        .lines()
                        .nth(1)
                        .unwrap_or(""),
                );
            }
            rows.push(row);
        }
    }
    if *json {
        return crate::ui::print_json(&rows);
    }
    crate::outln!("{}", format_table(&rows))?;
    Ok(())
}
