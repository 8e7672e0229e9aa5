//! A build's memory estimate next to the build itself: run it under
//! `/usr/bin/time -v` to compare the estimate with the peak resident size.
//!
//! ```text
//! cargo run --release -p lodkit-mco --example build_memory -- sphere 400
//! cargo run --release -p lodkit-mco --example build_memory -- blob 0
//! ```
//!
//! The shape is `sphere` (an icosphere of 1,280 triangles) or `blob` (a
//! 200,000-triangle blob); resolution 0 means the default.

use lodkit_mco::{Options, build_from_mesh, estimate_build_bytes};
use lodkit_mesh::{Model, shapes};

fn main() -> Result<(), lodkit_mco::Error> {
    let args: Vec<String> = std::env::args().collect();
    let mesh = match args.get(1).map(String::as_str) {
        Some("blob") => shapes::blob(200_000),
        _ => shapes::icosphere(3),
    };
    let r: u32 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(0);
    let opts = Options {
        resolution: (r > 0).then_some(r),
    };
    let est = estimate_build_bytes(&[Model::Mesh(mesh.clone())], &opts)?;
    println!("estimate: {:.3} GB", est as f64 / 1e9);
    let m = build_from_mesh(&mesh, &opts)?;
    println!(
        "built: {} nodes, {} triangles",
        m.info().nodes,
        m.full_triangles()
    );
    Ok(())
}
