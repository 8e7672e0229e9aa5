//! `lodkit build [INPUT] --out DIR`: the main job ([`lodkit::build_all`]).
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit::build_all::Sampling;
use lodkit::limits;

use crate::ui::{Ui, value};

#[derive(Args)]
pub struct BuildArgs {
    /// Input: a mesh (any format), a point cloud (.xyz, .pts, PLY without
    /// faces), a range image (range-grid PLY), or a scan set (.conf, or a
    /// folder of range images); the built-in Stanford bunny when omitted.
    pub input: Option<PathBuf>,
    /// Output folder; replaced as a whole when the build succeeds.
    #[arg(long, short, default_value = "lodkit-out")]
    pub out: PathBuf,
    /// Levels of the discrete LOD chain, each half the previous one.
    #[arg(long, default_value_t = limits::DEFAULT_LEVELS, value_name = "N", value_parser = value::range(limits::LEVELS))]
    pub levels: usize,
    /// Samples per kind for every measured error (default: 4 per face
    /// of each level, 50 000 to 1 000 000).
    #[arg(long, value_name = "N", conflicts_with = "no_measure", value_parser = value::range(limits::SAMPLES))]
    pub samples: Option<usize>,
    /// Skip every error measurement (the report shows "-").
    #[arg(long)]
    pub no_measure: bool,
    /// Merge a textured or multi-part input into one mesh (materials and
    /// textures dropped) instead of keeping them in the GLB outputs.
    #[arg(long)]
    pub merge: bool,
    #[command(flatten)]
    pub output: crate::ui::OutputArgs,
    /// Print the list of outputs as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(ui: &Ui, args: &BuildArgs) -> Result<()> {
    let job = lodkit::build_all::BuildJob {
        input: args.input.clone(),
        out: args.out.clone(),
        levels: args.levels,
        sampling: match (args.no_measure, args.samples) {
            (true, _) => Sampling::Skip,
            (false, Some(n)) => Sampling::PerKind(n),
            (false, None) => Sampling::Adaptive,
        },
        merge: args.merge,
        output: args.output.options(),
    };
    let report = ui.run(|events| lodkit::build_all::run(&job, events))?;
    let out = args.out.as_path();
    if args.json {
        let list: Vec<_> = report
            .outputs
            .iter()
            .map(|(file, bytes)| serde_json::json!({ "path": out.join(file), "bytes": bytes }))
            .collect();
        return super::print_json(&serde_json::json!({ "model": report.model, "outputs": list }));
    }
    for (file, bytes) in &report.outputs {
        ui.status(format!(
            "wrote {} ({bytes} bytes)",
            out.join(file).display()
        ));
    }
    Ok(())
}
