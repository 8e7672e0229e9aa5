//! Profiling driver: simplifies one mesh (a file, or `blob:N`) to a target
//! `REPEAT` times with a reused workspace and prints the best time, the
//! report and a hash of the output (for determinism checks).
//!
//! `cargo run --release -p lodkit-bench --example simplify_loop -- MESH TARGET [REPEAT [SAMPLES]]`
//! where `TARGET` is a face count or a ratio with `%` (`1%`). With
//! `SAMPLES`, also prints the symmetric mean / max distance of the output
//! from the input (`compare`, that many samples per kind).

use std::hash::{DefaultHasher, Hash, Hasher};
use std::time::Instant;

use lodkit_simplify::{Options, Simplifier, Target};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: simplify_loop MESH|blob:N TARGET[%] [REPEAT]");
        std::process::exit(2);
    }
    let mesh = match args[1].strip_prefix("blob:") {
        Some(n) => lodkit_mesh::shapes::blob(n.parse().expect("blob size")),
        None => lodkit_mesh::io::load_mesh(std::path::Path::new(&args[1])).expect("mesh"),
    };
    let target = match args[2].strip_suffix('%') {
        Some(p) => Target::Ratio(p.parse::<f32>().expect("percent") / 100.0),
        None => Target::Faces(args[2].parse().expect("faces")),
    };
    let repeat: usize = args.get(3).map_or(5, |r| r.parse().expect("repeat"));
    let opts = Options {
        target,
        ..Options::DEFAULT
    };
    let mut ws = Simplifier::new();
    let mut best = f64::INFINITY;
    let mut best_cpu = f64::INFINITY;
    let mut last = None;
    for _ in 0..repeat.max(1) {
        let t = Instant::now();
        let c = cpu_seconds();
        let r = ws.simplify(&mesh, &opts).expect("simplify");
        best_cpu = best_cpu.min(cpu_seconds() - c);
        best = best.min(t.elapsed().as_secs_f64());
        last = Some(r);
    }
    let r = last.expect("one run");
    let mut h = DefaultHasher::new();
    for p in &r.mesh.positions {
        p.to_array().map(f32::to_bits).hash(&mut h);
    }
    r.mesh.faces.hash(&mut h);
    println!(
        "{} -> {} tris, {} passes, {} collapses, err {:.3e}, best {:.2} ms (cpu {:.2} ms), hash {:016x}",
        mesh.faces.len(),
        r.mesh.faces.len(),
        r.report.passes,
        r.report.collapses,
        r.report.estimated_error,
        best * 1e3,
        best_cpu * 1e3,
        h.finish()
    );
    if let Some(n) = args.get(4) {
        let opts = lodkit_mesh::metrics::CompareOptions {
            samples: Some(n.parse().expect("samples")),
            ..Default::default()
        };
        let c = lodkit_mesh::metrics::compare(&mesh, &r.mesh, &opts).expect("compare");
        println!(
            "symmetric mean {:.3e} max {:.3e}",
            c.symmetric.mean, c.symmetric.max
        );
    }
}

/// This thread's CPU time (NaN where the clock is missing): unlike wall
/// time it does not count the time other processes held the core.
fn cpu_seconds() -> f64 {
    lodkit_bench::simplify::thread_cpu_seconds().unwrap_or(f64::NAN)
}
