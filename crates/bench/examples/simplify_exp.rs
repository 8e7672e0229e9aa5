//! Experiment driver: `cargo run --release -p lodkit-bench --example simplify_exp -- MESH RATIO [nofill]`
//! prints lodkit's time, passes and errors against the input (for tuning).
use std::time::Instant;

use lodkit_mesh::metrics::{CompareOptions, compare};
use lodkit_mesh::{Model, io};
use lodkit_simplify::{Options, Simplifier, Target};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let mesh = if args[1].starts_with("blob") {
        lodkit_mesh::shapes::blob(args[1][4..].parse().unwrap())
    } else {
        match io::load(std::path::Path::new(&args[1])).unwrap() {
            Model::Mesh(m) => m,
            _ => panic!("not a mesh"),
        }
    };
    let r: f32 = args[2].parse().unwrap();
    let mut o = Options::ratio(r);
    if r > 1.0 {
        o.target = Target::Faces(r as usize);
    }
    o.fill_holes = !args.iter().any(|a| a == "nofill");
    o.lock_border = args.iter().any(|a| a == "lock");
    if let Some(h) = args.iter().find_map(|a| a.strip_prefix("heap=")) {
        o.heap_size = h.parse().unwrap();
    }
    let mut ws = Simplifier::new();
    let mut best = f64::MAX;
    let mut out = None;
    for _ in 0..3 {
        let t = Instant::now();
        let s = ws.simplify(&mesh, &o).unwrap();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(s);
    }
    let out = out.unwrap();
    if args.iter().any(|a| a == "nocmp") {
        println!(
            "{} faces, {:.2} ms, {} passes",
            out.mesh.faces.len(),
            best * 1e3,
            out.report.passes
        );
        return;
    }
    let c = compare(
        &mesh,
        &out.mesh,
        &CompareOptions {
            samples: Some(300_000),
            ..Default::default()
        },
    )
    .unwrap();
    println!(
        "{} faces, {:.2} ms, {} passes, mean {:.3e} max {:.3e} est {:.3e} ws {:.1} B/v",
        out.mesh.faces.len(),
        best * 1e3,
        out.report.passes,
        c.symmetric.mean,
        c.symmetric.max,
        out.report.estimated_error,
        ws.peak_bytes() as f64 / mesh.positions.len() as f64
    );
}
