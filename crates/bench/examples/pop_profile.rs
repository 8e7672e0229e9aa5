//! Profiling driver for decode + triangulate, the criterion bench `pop`'s
//! loop without criterion, so a profiler (`perf record`, `valgrind
//! --tool=callgrind`) sees one input and nothing else:
//!
//! `cargo run --release -p lodkit-bench --example pop_profile -- INPUT [ITERATIONS] [orient]`
//!
//! `INPUT` is a `.pop` file or `MODEL:R:N[:baseline]` as for
//! `pop_decode_time` (`MODEL` = `icosphereL` for the bench's icosphere);
//! `--save FILE` writes the encoded stream and exits, so a profile need not
//! include the encoder. Prints the best time of each stage (decode,
//! `surface`, triangulation) and the triangles/s of the three together.
use std::time::Instant;

use lodkit_particles::{DecodeOptions, TriangulateOptions, decode, triangulate, triangulate_owned};

#[path = "pop_shared/stream_input.rs"]
mod stream_input;
use stream_input::load;

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let save = args.iter().position(|a| a == "--save").map(|i| {
        let path = args.remove(i + 1);
        args.remove(i);
        path
    });
    let input = args.first().expect("INPUT");
    let bytes = load(input);
    if let Some(path) = save {
        std::fs::write(&path, &bytes).expect("writes");
        return;
    }
    let iterations: usize = args.get(1).map_or(20, |v| v.parse().expect("iterations"));
    let orient = args.get(2).is_some_and(|v| v == "orient");
    let opts = TriangulateOptions {
        orient,
        ..TriangulateOptions::DEFAULT
    };
    // A digest of what the loop produces, so an optimisation can be
    // checked to change nothing (outside the timed loop).
    let d = decode(&bytes, &DecodeOptions::default()).expect("decodes");
    let s = d.surface(d.header.depth).expect("finest level");
    let t = triangulate(&s, &opts);
    if std::env::var_os("POP_PROFILE_STATS").is_some() {
        eprintln!(
            "{:?} disambiguated {} fallbacks {}",
            t.stats.configurations, t.stats.disambiguated, t.stats.fallbacks
        );
    }
    let mut h = std::hash::DefaultHasher::new();
    std::hash::Hash::hash(&d.q, &mut h);
    std::hash::Hash::hash(&s.cells, &mut h);
    std::hash::Hash::hash(&t.mesh.faces, &mut h);
    println!("digest {:016x}", std::hash::Hasher::finish(&h));
    let mut best = [f64::INFINITY; 3];
    let mut tris = 0;
    for _ in 0..iterations {
        let t0 = Instant::now();
        let d = decode(&bytes, &DecodeOptions::default()).expect("decodes");
        let t1 = Instant::now();
        let depth = d.header.depth;
        let s = d.into_surface(depth).expect("finest level");
        let t2 = Instant::now();
        tris = triangulate_owned(s, &opts).mesh.faces.len();
        let t3 = Instant::now();
        for (b, t) in best.iter_mut().zip([t1 - t0, t2 - t1, t3 - t2]) {
            *b = b.min(t.as_secs_f64() * 1e3);
        }
    }
    let total: f64 = best.iter().sum();
    println!(
        "{input}: {tris} triangles; best ms: decode {:.2}, surface {:.2}, triangulate {:.2}; {:.2} M triangles/s",
        best[0],
        best[1],
        best[2],
        tris as f64 / (total * 1e3)
    );
}
