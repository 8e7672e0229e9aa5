//! `lodkit-bench` — lodkit next to its peers, in one process: the
//! simplifier against meshoptimizer (`simplify`, feature `peers`), the
//! octree's extraction against a `memcpy` (`mco`). Kept apart from the
//! `lodkit` binary so the product links no benchmark code.
//!
//! Exit codes: 0 success, 1 bad input or failure, 2 usage error (from
//! clap, or `simplify` without the `peers` feature).

#![forbid(unsafe_code)]

mod mco;
mod simplify;
mod ui;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Counts live bytes for the memory columns.
#[global_allocator]
static ALLOC: lodkit_bench::alloc::CountingAlloc = lodkit_bench::alloc::CountingAlloc;

/// In-process comparisons with peer libraries (simplify: meshoptimizer, with `--features peers`).
#[derive(Parser)]
#[command(
    name = "lodkit-bench",
    version,
    after_help = "Examples:\n  lodkit-bench simplify\n  lodkit-bench simplify scan.ply --json\n  lodkit-bench mco"
)]
struct Cli {
    /// Print nothing but errors (and the tables).
    #[arg(short, long, global = true, conflicts_with = "verbose")]
    quiet: bool,
    /// Print the time of each stage.
    #[arg(short, long, global = true)]
    verbose: bool,
    #[command(subcommand)]
    what: What,
}

#[derive(Subcommand)]
enum What {
    /// HQMS vs meshopt_simplify at 50%, 10%, 1% and 1,000 triangles.
    Simplify(simplify::SimplifyArgs),
    /// Marching-cube-octree extraction time next to memcpy of the same index buffer.
    Mco(mco::BenchMcoArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let ui = ui::Ui {
        quiet: cli.quiet,
        verbose: cli.verbose,
    };
    let result = match &cli.what {
        What::Simplify(a) => simplify::run(&ui, a),
        What::Mco(a) => mco::run(&ui, a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            let line = e
                .chain()
                .map(|c| c.to_string())
                .collect::<Vec<_>>()
                .join(": ");
            eprintln!("lodkit-bench: error: {}", line.replace('\n', " "));
            let usage = e.downcast_ref::<lodkit::usage::Usage>().is_some();
            ExitCode::from(if usage { 2 } else { 1 })
        }
    }
}
