//! `lodkit compare A B`: Metro-style distances.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit_mesh::metrics::CompareOptions;

use crate::ui::Ui;
use crate::ui::value;

#[derive(Args)]
pub struct CompareArgs {
    /// First mesh (e.g. the original).
    pub a: PathBuf,
    /// Second mesh (e.g. the simplified one).
    pub b: PathBuf,
    /// Samples of each kind (vertex, edge, face) per mesh, MeshLab's
    /// `SampleNum`, in 1..=10000000 (default: max(10 × faces of the larger
    /// mesh, 1M), at most 10000000).
    #[arg(long, value_parser = value::range(lodkit::limits::SAMPLES))]
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
    /// Also write B with per-vertex colours from each vertex's distance to
    /// A (blue = 0 to red = the largest), as .ply, .obj or .glb.
    #[arg(long, value_name = "OUT", value_parser = heatmap_output)]
    pub heatmap: Option<PathBuf>,
}

pub fn run(ui: &Ui, args: &CompareArgs) -> Result<()> {
    let job = lodkit::compare::CompareJob {
        a: args.a.clone(),
        b: args.b.clone(),
        options: CompareOptions {
            samples: args.samples,
            seed: args.seed,
            vertex_samples: !args.no_vertex_samples,
            edge_samples: !args.no_edge_samples,
            face_samples: !args.no_face_samples,
        },
        heatmap: args.heatmap.clone(),
    };
    let r = ui.run(|events| lodkit::compare::run(&job, events))?;
    if args.json {
        return super::print_json(&r);
    }
    crate::outln!("A: {}\nB: {}", args.a.display(), args.b.display())?;
    crate::outln!("{}", r.report)?;
    if let Some(h) = &r.heatmap {
        crate::outln!("{}", h.line())?;
        ui.status(format!(
            "wrote {} (B's {} vertices coloured by their distance to A)",
            h.file, h.vertices
        ));
    }
    Ok(())
}

/// `--heatmap`'s value: a format with vertex colours and faces (exit 2
/// otherwise).
fn heatmap_output(s: &str) -> std::result::Result<PathBuf, String> {
    let p = PathBuf::from(s);
    if lodkit::compare::holds_heatmap(&p) {
        Ok(p)
    } else {
        Err(format!(
            "{s}: a heat map needs a format with vertex colours and faces: .ply, .obj or .glb"
        ))
    }
}
