//! `lodkit lods IN --out DIR`: a discrete LOD chain ([`lodkit::lod_chain`]).
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit::limits;
use lodkit_simplify::Target;

use crate::ui::{Ui, value};

#[derive(Args, Debug)]
pub struct LodsArgs {
    /// Input mesh.
    pub input: PathBuf,
    /// Output directory (created if missing).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Comma-separated fractions of the input's triangles, one level each,
    /// each smaller than the one before.
    #[arg(
        long,
        value_delimiter = ',',
        value_name = "R,R,...",
        conflicts_with = "levels",
        value_parser = limits::RATIO.f32()
    )]
    pub ratios: Option<Vec<f32>>,
    /// Number of levels, each half the previous one, in 1..=32 (default 6).
    #[arg(long, value_name = "N", value_parser = value::range(limits::LEVELS))]
    pub levels: Option<usize>,
    #[command(flatten)]
    pub opts: crate::args::SimplifyOpts,
    #[command(flatten)]
    pub scale: crate::args::OutOfCoreArgs,
    /// Samples per kind for the measured error (`compare`), in 1..=10000000;
    /// by default each level gets 4 per face, within 50000..=1000000.
    #[arg(long, value_parser = value::range(limits::SAMPLES))]
    pub samples: Option<usize>,
    #[command(flatten)]
    pub output: crate::ui::OutputArgs,
    /// Print lods.json on stdout too.
    #[arg(long)]
    pub json: bool,
}

pub fn run(ui: &Ui, a: &LodsArgs) -> Result<()> {
    let job = lodkit::lod_chain::LodChainJob {
        input: a.input.clone(),
        out: a.out.clone(),
        targets: lodkit::lod_chain::targets_of(a.ratios.as_deref(), a.levels)?,
        options: a.opts.options(Target::Ratio(1.0)),
        merge: a.opts.merge,
        scale: a.scale.options(),
        samples: a.samples,
        output: a.output.options(),
        notes: !a.json,
    };
    let report = ui.run(|events| lodkit::lod_chain::run(&job, events))?;
    if a.json {
        crate::out!("{}", report.json)?;
        return Ok(());
    }
    ui.status(&report.summary);
    Ok(())
}
