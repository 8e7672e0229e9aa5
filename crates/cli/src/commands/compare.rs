//! `lodkit compare A B`: Metro-style distances.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;

use crate::ui::Ui;

#[derive(Args)]
pub struct CompareArgs {
    /// First mesh (e.g. the original).
    pub a: PathBuf,
    /// Second mesh (e.g. the simplified one).
    pub b: PathBuf,
    /// Face samples per mesh (default: max(10 × faces of the larger mesh, 1M)).
    #[arg(long)]
    pub samples: Option<usize>,
    /// Seed of the sample positions (same seed → identical numbers).
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
}

pub fn run(_ui: &Ui, _args: &CompareArgs) -> Result<()> {
    anyhow::bail!("compare is not wired yet")
}
