//! Linear-time check of the HQMS simplifier: time per input triangle at
//! 10k, 100k, 1M (and, with `LODKIT_BENCH_4M=1`, 4M) triangles, simplifying
//! a noise blob to 1% of its triangles. Criterion reports triangles per
//! second (`Throughput::Elements`), so a flat throughput across sizes is
//! linear time. Run with `cargo bench -p lodkit-bench --bench simplify`.

use std::hint::black_box;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use lodkit_mesh::shapes::blob;
use lodkit_simplify::{Options, Simplifier};

fn sizes() -> Vec<(&'static str, usize)> {
    let mut v = vec![("10k", 10_000), ("100k", 100_000), ("1M", 1_000_000)];
    if std::env::var_os("LODKIT_BENCH_4M").is_some() {
        v.push(("4M", 4_000_000));
    }
    v
}

fn bench(c: &mut Criterion) {
    let mut g = c.benchmark_group("simplify_to_1pct");
    g.sample_size(10).warm_up_time(Duration::from_secs(1));
    let mut ws = Simplifier::new();
    let opts = Options::ratio(0.01);
    for (label, n) in sizes() {
        let mesh = blob(n);
        g.throughput(Throughput::Elements(mesh.faces.len() as u64));
        g.measurement_time(Duration::from_secs(if n >= 1_000_000 { 20 } else { 5 }));
        g.bench_with_input(BenchmarkId::new("tris", label), &mesh, |b, m| {
            b.iter(|| black_box(ws.simplify(m, &opts).expect("valid mesh")))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
