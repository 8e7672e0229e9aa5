//! The native side of the browser checks, through the same library calls
//! as the CLI (`lodkit pop decode`, `lodkit mco extract`), not through this
//! crate's ABI.
//!
//! ```text
//! cargo run --release -p lodkit-wasm --example native -- digest FILE.pop LEVEL FILE.mco BUDGET
//! cargo run --release -p lodkit-wasm --example native -- time FILE.pop [ROUNDS]
//! cargo run --release -p lodkit-wasm --example native -- time-mco FILE.mco BUDGET [ROUNDS]
//! cargo run --release -p lodkit-wasm --example native -- blob TRIANGLES OUT.ply
//! ```
//! `blob` writes `lodkit_mesh::shapes::blob` (the benchmarks' synthetic
//! mesh) for `lodkit pop encode` / `lodkit mco build`.
//! `digest` prints one JSON object: the triangle count and [`digest`] of
//! `.pop` level `LEVEL` and of the `.mco` cut for `BUDGET` triangles (the
//! browser test compares them with the wasm build's). `time` prints the best
//! decode + triangulate time of the finest level (one line of JSON); `time-mco`
//! the best view-dependent cut at about `BUDGET` triangles.

use std::time::Instant;

use glam::Vec3;
use lodkit_mco::{Camera, McoModel};
use lodkit_particles::{DecodeOptions, TriangulateOptions, decode, triangulate};
use lodkit_wasm::digest;

fn pop_level(bytes: &[u8], level: Option<u8>) -> (usize, u64) {
    let d = decode(
        bytes,
        &DecodeOptions {
            max_level: level,
            max_precision: None,
        },
    )
    .expect("a valid .pop");
    let r = level.unwrap_or(d.header.depth);
    let s = d.surface(r).expect("level present");
    let t = triangulate(&s, &TriangulateOptions::DEFAULT);
    let idx = t.mesh.faces.as_flattened();
    (t.mesh.faces.len(), digest(idx, &t.mesh.positions))
}

/// The camera the browser test and the benchmark use for a view cut: on the
/// model's bounding-cube diagonal, `dist` cube sizes from its centre.
fn camera_for(lo: Vec3, hi: Vec3, dist: f32) -> Camera {
    let c = (lo + hi) * 0.5;
    let size = (hi - lo).max_element();
    Camera {
        vfov_deg: 45.0,
        viewport_height: 1080.0,
        aspect: 16.0 / 9.0,
        ..Camera::looking_at(c + Vec3::new(0.0, 0.15, 1.0).normalize() * size * dist, c)
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    match args.first().map(String::as_str) {
        Some("digest") => {
            let pop = std::fs::read(&args[1]).expect("readable .pop");
            let level: u8 = args[2].parse().expect("a level number");
            let (pop_tris, pop_digest) = pop_level(&pop, Some(level));
            let model = McoModel::load(args[3].as_ref()).expect("a valid .mco");
            let budget: usize = args[4].parse().expect("a triangle budget");
            let mut idx = Vec::new();
            let lod = model.extract_triangles(budget, &mut idx);
            let mco_digest = digest(&idx, model.positions());
            println!(
                "{{\"pop\":{{\"level\":{level},\"triangles\":{pop_tris},\"digest\":\"{pop_digest:016x}\"}},\"mco\":{{\"budget\":{budget},\"lod\":{lod},\"triangles\":{},\"digest\":\"{mco_digest:016x}\"}}}}",
                idx.len() / 3
            );
        }
        Some("blob") => {
            let n: usize = args[1].parse().expect("a triangle count");
            let mesh = lodkit_mesh::shapes::blob(n);
            lodkit_mesh::io::save(
                args[2].as_ref(),
                &lodkit_mesh::Model::Mesh(mesh),
                lodkit_mesh::io::WriteOptions::default(),
            )
            .expect("writable output");
        }
        Some("time") => {
            let pop = std::fs::read(&args[1]).expect("readable .pop");
            let rounds: usize = args
                .get(2)
                .map_or(10, |r| r.parse().expect("a round count"));
            let mut best = f64::INFINITY;
            let mut tris = 0;
            for _ in 0..rounds {
                let t = Instant::now();
                tris = pop_level(&pop, None).0;
                best = best.min(t.elapsed().as_secs_f64());
            }
            println!(
                "{{\"file\":{:?},\"bytes\":{},\"triangles\":{tris},\"best_ms\":{:.3},\"mb_per_s\":{:.2}}}",
                args[1],
                pop.len(),
                best * 1e3,
                pop.len() as f64 / best / 1e6
            );
        }
        Some("time-mco") => {
            let model = McoModel::load(args[1].as_ref()).expect("a valid .mco");
            let budget: usize = args[2].parse().expect("a triangle budget");
            let rounds: usize = args
                .get(3)
                .map_or(20, |r| r.parse().expect("a round count"));
            let (lo, hi) = model.bounds();
            // The tolerance that gives about `budget` triangles at this view.
            let cam = camera_for(lo, hi, 1.5);
            let mut idx = Vec::new();
            let (mut a, mut b) = (0.01f32, 1000.0f32);
            for _ in 0..30 {
                let m = (a * b).sqrt();
                model.extract_view(&cam, m, &mut idx);
                if idx.len() / 3 > budget { a = m } else { b = m }
            }
            let mut best = f64::INFINITY;
            for _ in 0..rounds {
                let t = Instant::now();
                model.extract_view(&cam, b, &mut idx);
                best = best.min(t.elapsed().as_secs_f64());
            }
            println!(
                "{{\"file\":{:?},\"full_triangles\":{},\"tolerance_px\":{b:.4},\"triangles\":{},\"best_ms\":{:.3}}}",
                args[1],
                model.full_triangles(),
                idx.len() / 3,
                best * 1e3
            );
        }
        _ => {
            eprintln!(
                "usage: native digest FILE.pop LEVEL FILE.mco BUDGET | time FILE.pop [ROUNDS] | time-mco FILE.mco BUDGET [ROUNDS]"
            );
            std::process::exit(2);
        }
    }
}
