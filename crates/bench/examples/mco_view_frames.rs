//! Kept view-dependent cuts only, along the orbit of `mco_view_cut`, for
//! instruction counts: `ROUNDS` rounds of `FRAMES` cameras through one
//! `ViewCut`, after one warm-up cut (which builds the model's layout).
//! The instructions of a kept cut are the difference of two runs under
//! callgrind divided by the cuts between them:
//!
//! ```text
//! cargo build --release -p lodkit-bench --no-default-features --example mco_view_frames
//! valgrind --tool=callgrind target/release/examples/mco_view_frames model.mco 0.569 64 1
//! valgrind --tool=callgrind target/release/examples/mco_view_frames model.mco 0.569 64 3
//! # (I(3) - I(1)) / 128 = instructions per kept cut on 5.6-degree steps
//! ```

use std::path::Path;

use lodkit_bench::mco::orbit;
use lodkit_mco::{McoModel, ViewCut};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 5 {
        eprintln!("usage: mco_view_frames MODEL.mco TOLERANCE_PX FRAMES ROUNDS");
        std::process::exit(2);
    }
    let model = McoModel::load(Path::new(&args[1]))?;
    let tolerance: f32 = args[2].parse()?;
    let frames: usize = args[3].parse::<usize>()?.max(1);
    let rounds: usize = args[4].parse()?;
    let cameras = orbit(&model, frames, 1.2);
    let mut cut = ViewCut::new();
    cut.update(&model, &cameras[frames - 1], tolerance);
    let mut triangles = 0usize;
    for _ in 0..rounds {
        for c in &cameras {
            triangles += cut.update(&model, c, tolerance).len() / 3;
        }
    }
    println!(
        "{} cuts, {} triangles on average",
        frames * rounds,
        triangles / (frames * rounds).max(1)
    );
    Ok(())
}
