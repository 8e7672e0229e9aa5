//! `lodkit compare A B`: Metro-style distances.
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args;
use lodkit_mesh::metrics::{CompareOptions, compare};

use crate::ui::Ui;

#[derive(Args)]
pub struct CompareArgs {
    /// First mesh (e.g. the original).
    pub a: PathBuf,
    /// Second mesh (e.g. the simplified one).
    pub b: PathBuf,
    /// Samples of each kind (vertex, edge, face) per mesh, MeshLab's
    /// `SampleNum` (default: max(10 × faces of the larger mesh, 1M)).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Seed of the sample positions (same seed → identical numbers).
    #[arg(long, default_value_t = lodkit_mesh::metrics::DEFAULT_SEED)]
    pub seed: u64,
    /// Skip vertex samples.
    #[arg(long)]
    pub no_vertex_samples: bool,
    /// Skip edge samples.
    #[arg(long)]
    pub no_edge_samples: bool,
    /// Skip face samples.
    #[arg(long)]
    pub no_face_samples: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(ui: &Ui, args: &CompareArgs) -> Result<()> {
    let a = super::load_mesh(ui, &args.a)?;
    let b = super::load_mesh(ui, &args.b)?;
    let opts = CompareOptions {
        samples: args.samples,
        seed: args.seed,
        vertex_samples: !args.no_vertex_samples,
        edge_samples: !args.no_edge_samples,
        face_samples: !args.no_face_samples,
    };
    let n = opts.resolved_samples(a.faces.len(), b.faces.len());
    let step = ui.spinner(&format!("measuring ({n} samples of each kind per mesh)"));
    let report = compare(&a, &b, &opts)
        .with_context(|| format!("comparing {} with {}", args.a.display(), args.b.display()))?;
    step.finish();
    if args.json {
        return super::print_json(&report);
    }
    crate::outln!("A: {}\nB: {}", args.a.display(), args.b.display())?;
    crate::outln!("{report}")?;
    Ok(())
}
