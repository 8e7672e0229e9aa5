//! Decode time of `.pop` files, structure and precision apart from the
//! triangulation, best of `--runs` (default 7) in one process:
//!
//! `cargo run --release -p lodkit-bench --example pop_decode_time -- INPUT...`
//!
//! An input is a `.pop` file, or `MODEL:R:N[:baseline]` to encode a mesh
//! or point cloud first (`MODEL` = `icosphereL` for the icosphere of
//! level `L` the criterion bench uses) (depth `R`, precision `N`, entropy mode unless
//! `baseline`) — so a format change needs no rebuilt CLI.
//!
//! Prints per file: particles, structure bits per particle, ms for the
//! structure + attributes, ms for the whole decode (with the precision
//! layers), ms to triangulate the finest level, and the triangles/s of
//! decode + triangulate.
use std::time::Instant;

use lodkit_particles::{DecodeOptions, TriangulateOptions, decode, triangulate};

#[path = "pop_shared/stream_input.rs"]
mod stream_input;
use stream_input::load;

fn best<T>(runs: usize, mut f: impl FnMut() -> T) -> (f64, T) {
    let mut best = f64::INFINITY;
    let mut out = None;
    for _ in 0..runs {
        let t = Instant::now();
        let v = f();
        best = best.min(t.elapsed().as_secs_f64());
        out = Some(v);
    }
    (best * 1e3, out.expect("at least one run"))
}

fn main() {
    let mut runs = 7;
    let mut files = Vec::new();
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--runs" {
            runs = args.next().and_then(|v| v.parse().ok()).unwrap_or(runs);
        } else {
            files.push(a);
        }
    }
    println!(
        "input\tbytes\tparticles\tstructure_bpp\tstructure_ms\tdecode_ms\ttriangulate_ms\tMtris_per_s"
    );
    for f in files {
        let bytes = load(&f);
        let structure_only = DecodeOptions {
            max_precision: Some(0),
            ..DecodeOptions::default()
        };
        let (ms_s, d) = best(runs, || decode(&bytes, &structure_only).expect("decodes"));
        let bits: usize = d.structure_bytes.iter().sum::<usize>() * 8;
        let particles = d.header.particles as f64;
        let (ms_d, d) = best(runs, || {
            decode(&bytes, &DecodeOptions::default()).expect("decodes")
        });
        let s = d.surface(d.header.depth).expect("finest level");
        let (ms_t, tris) = best(runs, || {
            triangulate(&s, &TriangulateOptions::DEFAULT)
                .mesh
                .faces
                .len()
        });
        println!(
            "{f}\t{}\t{}\t{:.3}\t{ms_s:.2}\t{ms_d:.2}\t{ms_t:.2}\t{:.2}",
            bytes.len(),
            d.header.particles,
            bits as f64 / particles,
            tris as f64 / ((ms_d + ms_t) * 1e3)
        );
    }
}
