//! Marching cube octree: build throughput (input points per second,
//! labelled by input size so growth with size is visible) and extraction
//! (triangles per second: the birth/death tables and the §6.1 traversal,
//! next to a memcpy of the same index buffer).
//!
//! Inputs are `shapes::blob` meshes (their vertices with area-weighted
//! normals are the samples) at a resolution of twice their sample spacing,
//! the default. Run with `cargo bench -p lodkit-bench --bench mco`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use lodkit_mco::pipeline::{Options, build_from_mesh};
use lodkit_mesh::shapes;

fn build(c: &mut Criterion) {
    let mut g = c.benchmark_group("mco_build");
    g.sample_size(10).measurement_time(Duration::from_secs(10));
    for tris in [40_000usize, 160_000, 640_000] {
        let mesh = shapes::blob(tris);
        let points = mesh.positions.len();
        g.throughput(Throughput::Elements(points as u64));
        g.bench_with_input(BenchmarkId::new("points", points), &mesh, |b, m| {
            b.iter(|| build_from_mesh(black_box(m), &Options::default()).unwrap())
        });
    }
    g.finish();
}

fn extract(c: &mut Criterion) {
    let mesh = shapes::blob(640_000);
    let model = build_from_mesh(&mesh, &Options::default()).unwrap();
    let full = model.full_triangles();
    let mut g = c.benchmark_group("mco_extract");
    let mut idx = Vec::new();
    for target in [full / 100, full / 10, full] {
        let k = model.lod_for_triangles(target);
        model.extract_lod(k, &mut idx);
        let src = idx.clone();
        let mut dst = vec![0u32; src.len()];
        g.throughput(Throughput::Elements((src.len() / 3) as u64));
        g.bench_with_input(
            BenchmarkId::new("extract_tris", src.len() / 3),
            &k,
            |b, &k| b.iter(|| model.extract_lod(black_box(k), &mut idx)),
        );
        g.bench_with_input(
            BenchmarkId::new("traversal_tris", src.len() / 3),
            &k,
            |b, &k| b.iter(|| model.extract_lod_traversal(black_box(k), &mut idx)),
        );
        g.bench_with_input(
            BenchmarkId::new("memcpy_tris", src.len() / 3),
            &src,
            |b, s| b.iter(|| dst.copy_from_slice(black_box(s))),
        );
    }
    g.finish();
}

criterion_group!(benches, build, extract);
criterion_main!(benches);
