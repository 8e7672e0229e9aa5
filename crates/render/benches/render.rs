//! Render time of the shipped bunny (69 451 faces) at two image sizes and
//! the supersampling factors `lodkit render` uses (3) and a mask-only ring
//! would use (1), labelled by problem size. Run with
//! `cargo bench -p lodkit-render --bench render`.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use lodkit_render::{Camera, RenderOptions, render};

fn bench(c: &mut Criterion) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/models/stanford_bunny.ply");
    let mesh = lodkit_mesh::io::load_mesh(&path).expect("the shipped bunny");
    let cam = Camera::orbit(&mesh.bbox(), 30.0, 20.0, 35.0, 1.0).unwrap();
    let mut g = c.benchmark_group("render_bunny");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    for (size, s) in [(512u32, 1u32), (512, 3), (1024, 1), (1024, 3)] {
        let opts = RenderOptions {
            width: size,
            height: size,
            supersample: s,
            ..RenderOptions::DEFAULT
        };
        g.bench_function(format!("tris=69451/px={size}x{size}/ss={s}"), |b| {
            b.iter(|| black_box(render(&mesh, &cam, &opts).unwrap()))
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
