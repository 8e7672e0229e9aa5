//! `lodkit simplify IN -o OUT`: one mesh to one budget
//! ([`lodkit::simplify`]).
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit::limits;

use crate::ui::{Ui, value};

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
    #[arg(long, value_name = "FACES", conflicts_with = "ratio", value_parser = value::range(limits::TARGET_FACES))]
    pub target: Option<usize>,
    /// Fraction of the input's triangles to keep, in [0, 1].
    #[arg(long, value_name = "R", value_parser = limits::RATIO.f32())]
    pub ratio: Option<f32>,
    #[command(flatten)]
    pub opts: crate::args::SimplifyOpts,
    #[command(flatten)]
    pub scale: crate::args::OutOfCoreArgs,
    #[command(flatten)]
    pub out: crate::ui::OutputArgs,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(ui: &Ui, a: &SimplifyArgs) -> Result<()> {
    let target = lodkit::simplify::target_of(a.target, a.ratio, a.opts.max_error)?;
    let job = lodkit::simplify::SimplifyJob {
        input: a.input.clone(),
        output: a.output.clone(),
        options: a.opts.options(target),
        merge: a.opts.merge,
        scale: a.scale.options(),
        out: a.out.options(),
    };
    let report = ui.run(|events| lodkit::simplify::run(&job, events))?;
    if a.json {
        return super::print_json(&report);
    }
    ui.status(&report.summary);
    Ok(())
}
