//! View-dependent cut times on a large model: a kept `ViewCut` and a
//! fresh `extract_view` per camera, along a 64-camera orbit, at pixel
//! tolerances that give cuts of about 20k, 100k and 300k triangles, next
//! to a `memcpy` of the same index buffer.
//!
//! The model is `shapes::blob(1_200_000)` built at resolution 350 (the
//! 1M-triangle blob of `lodkit bench mco`), or the `.mco` file / mesh
//! given (a mesh is built at `RESOLUTION`, default from its sampling).
//! With `MCO_OUT=PATH` the model is also written there. The model is
//! timed as built and as read back from its `.mco` bytes (a read file
//! numbers its nodes in LOD order, as the browser sees them); a `.mco`
//! given is timed as read.
//!
//! `MCO_FRAMES` (64) and `MCO_ROUNDS` (5) set the cameras of the orbit
//! and the rounds (fewer: for a run under callgrind). The kept
//! `ViewCut` is frame-coherent, so its time depends on the step between
//! cameras: `MCO_FRAMES=240` gives the small steps of a viewer, 4 the
//! jumps of a cut without a previous one.
//!
//! ```text
//! cargo run --release -p lodkit-bench --no-default-features --example mco_view_cut
//! cargo run --release -p lodkit-bench --no-default-features --example mco_view_cut -- model.mco
//! ```

use std::path::Path;
use std::time::Instant;

use lodkit_bench::mco::{orbit, time_view_cuts, tolerance_for};
use lodkit_mco::{McoModel, Options, build_from_mesh};

fn env_or(name: &str, default: usize) -> usize {
    std::env::var(name)
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(default)
}

fn table(name: &str, m: &McoModel) {
    let cameras = orbit(m, env_or("MCO_FRAMES", 64).max(1), 1.2);
    println!(
        "{name}: {} nodes, {} triangles at full resolution",
        m.info().nodes,
        m.full_triangles()
    );
    println!(
        "| model | target | tolerance (px) | triangles min / mean / max | expanded | kept ViewCut median / worst (ms) | fresh extract_view median / worst (ms) | node arrays (before) median / worst (ms) | memcpy (ms) |"
    );
    println!("|---|---:|---:|---|---:|---|---|---|---:|");
    let fixed: Option<Vec<f32>> = std::env::var("MCO_TOLERANCES")
        .ok()
        .map(|s| s.split(',').filter_map(|x| x.parse().ok()).collect());
    let targets = [20_000, 100_000, 300_000];
    for (i, target) in targets.into_iter().enumerate() {
        let tol = match &fixed {
            Some(t) => match t.get(i) {
                Some(&t) => t,
                None => break,
            },
            None => tolerance_for(m, &cameras, target),
        };
        let r = time_view_cuts(m, &cameras, tol, env_or("MCO_ROUNDS", 5));
        println!(
            "| {name} | {target} | {:.3} | {} / {} / {} | {:.0} | {:.3} / {:.3} | {:.3} / {:.3} | {:.3} / {:.3} | {:.3} |",
            r.tolerance_px,
            r.triangles[0],
            r.triangles[1],
            r.triangles[2],
            r.expanded,
            r.kept_s[0] * 1e3,
            r.kept_s[1] * 1e3,
            r.fresh_s[0] * 1e3,
            r.fresh_s[1] * 1e3,
            r.nodes_s[0] * 1e3,
            r.nodes_s[1] * 1e3,
            r.memcpy_s * 1e3,
        );
    }
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let arg = std::env::args().nth(1);
    let resolution = std::env::var("RESOLUTION")
        .ok()
        .and_then(|s| s.parse().ok());
    let t = Instant::now();
    let model = match &arg {
        Some(p) if p.ends_with(".mco") => McoModel::load(Path::new(p))?,
        Some(p) => build_from_mesh(
            &lodkit_mesh::io::load_mesh(Path::new(p))?,
            &Options { resolution },
        )?,
        None => build_from_mesh(
            &lodkit_mesh::shapes::blob(1_200_000),
            &Options {
                resolution: Some(350),
            },
        )?,
    };
    eprintln!("model ready in {:.1} s", t.elapsed().as_secs_f64());
    let bytes = model.to_bytes();
    if let Ok(out) = std::env::var("MCO_OUT") {
        std::fs::write(out, &bytes)?;
    }
    let name = arg.as_deref().unwrap_or("blob-1M");
    table(name, &model);
    if !arg.as_deref().is_some_and(|p| p.ends_with(".mco")) {
        // A model read from a file already is what a reader sees.
        let loaded = McoModel::from_bytes(&bytes)?;
        table(&format!("{name} (read back)"), &loaded);
    }
    Ok(())
}
