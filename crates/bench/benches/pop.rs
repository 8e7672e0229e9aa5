//! `.pop` decode + direct triangulation throughput (§5.4 + §6 of Yemez &
//! Schmitt): per iteration the whole stream is decoded and its finest
//! level built and triangulated, on the calling thread (nothing in the
//! decoder or the triangulation spawns threads); throughput is the
//! triangles produced, so criterion reports triangles per second. Inputs:
//! an icosphere (level 6, 81,920 triangles) encoded at R = 7, 8 and 9, and
//! the shipped Stanford bunny at R = 8, in both coding modes; labels give
//! the input, mode, R and triangle count. Orientation (not in the paper)
//! is measured separately, at R = 8. Run with
//! `cargo bench -p lodkit-bench --bench pop`.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use lodkit_mesh::Model;
use lodkit_particles::{
    DecodeOptions, EncodeOptions, Mode, TriangulateOptions, decode, encode, triangulate_owned,
};

fn decode_and_triangulate(bytes: &[u8], opts: &TriangulateOptions) -> usize {
    let d = decode(bytes, &DecodeOptions::default()).expect("own stream decodes");
    let depth = d.header.depth;
    // The level is built only to be triangulated: its cells and particles
    // move into the surface and the mesh rather than being copied.
    let s = d.into_surface(depth).expect("finest level");
    triangulate_owned(s, opts).mesh.faces.len()
}

fn bench(c: &mut Criterion) {
    let sphere = Model::Mesh(lodkit_mesh::shapes::icosphere(6));
    let bunny_path =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/models/stanford_bunny.ply");
    let bunny = lodkit_mesh::io::load(&bunny_path).expect("the repository ships the bunny");
    let inputs: [(&str, &Model, u8); 4] = [
        ("icosphere", &sphere, 7),
        ("icosphere", &sphere, 8),
        ("icosphere", &sphere, 9),
        ("bunny", &bunny, 8),
    ];
    let mut g = c.benchmark_group("pop_decode_triangulate");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    for (name, model, depth) in inputs {
        for mode in [Mode::Baseline, Mode::Entropy] {
            let opts = EncodeOptions {
                depth: Some(depth),
                precision: 12,
                mode,
                ..EncodeOptions::DEFAULT
            };
            let bytes = encode(model, &opts).expect("encode").bytes;
            let orients: &[bool] = if depth == 8 { &[false, true] } else { &[false] };
            for &orient in orients {
                let t = TriangulateOptions {
                    orient,
                    ..TriangulateOptions::DEFAULT
                };
                let tris = decode_and_triangulate(&bytes, &t);
                g.throughput(Throughput::Elements(tris as u64));
                let label = format!(
                    "{name}/{}/orient={orient}/R={depth}/tris={tris}",
                    mode.name()
                );
                g.bench_with_input(BenchmarkId::from_parameter(label), &bytes, |b, bytes| {
                    b.iter(|| black_box(decode_and_triangulate(bytes, &t)))
                });
            }
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
