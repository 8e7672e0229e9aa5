//! `.pop` decode + direct triangulation throughput (§5.4 + §6 of Yemez &
//! Schmitt): the whole stream is decoded and its finest level triangulated
//! per iteration; throughput is the triangles produced, so criterion
//! reports triangles per second. Inputs: an icosphere (level 6, 81,920
//! triangles) encoded at R = 7 and 8, in both coding modes; labels give
//! the triangle count. Run with `cargo bench -p lodkit-bench --bench pop`.
//! Orientation (not in the paper) is measured separately.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use lodkit_mesh::Model;
use lodkit_particles::{
    DecodeOptions, EncodeOptions, Mode, TriangulateOptions, decode, encode, triangulate,
};

fn decode_and_triangulate(bytes: &[u8], opts: &TriangulateOptions) -> usize {
    let d = decode(bytes, &DecodeOptions::default()).expect("own stream decodes");
    let s = d.surface(d.header.depth).expect("finest level");
    triangulate(&s, opts).mesh.faces.len()
}

fn bench(c: &mut Criterion) {
    let sphere = Model::Mesh(lodkit_mesh::shapes::icosphere(6));
    let mut g = c.benchmark_group("pop_decode_triangulate");
    g.sample_size(10).measurement_time(Duration::from_secs(4));
    for depth in [7u8, 8] {
        for mode in [Mode::Baseline, Mode::Entropy] {
            let opts = EncodeOptions {
                depth: Some(depth),
                precision: 12,
                mode,
                ..EncodeOptions::DEFAULT
            };
            let bytes = encode(&sphere, &opts).expect("encode").bytes;
            for orient in [false, true] {
                let t = TriangulateOptions {
                    orient,
                    ..TriangulateOptions::DEFAULT
                };
                let tris = decode_and_triangulate(&bytes, &t);
                g.throughput(Throughput::Elements(tris as u64));
                let label = format!("{}/orient={orient}/R={depth}/tris={tris}", mode.name());
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
