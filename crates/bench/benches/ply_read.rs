//! Binary PLY reading throughput: `lodkit_mesh::io::load` (file read +
//! decode + validate) against the `ply-rs` crate's generic parser, on the
//! same 1M-triangle binary little-endian file.
//!
//! The file is a 708 × 708 vertex height field (z = a smooth wave), two
//! triangles per quad (999,698 triangles, 501,264 vertices, ≈ 19 MB),
//! written once with lodkit's own PLY writer into a temp dir. Throughput is
//! the file size, so criterion reports bytes per second. Run with
//! `cargo bench -p lodkit-bench --bench ply_read`.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::{Model, TriMesh, io};

/// A `side × side` vertex grid over [0, 1]², z = 0.05 sin(6x) cos(4y),
/// split into `2 (side - 1)²` triangles.
fn height_field(side: u32) -> TriMesh {
    let scale = 1.0 / (side - 1) as f32;
    let positions = (0..side * side)
        .map(|i| {
            let (x, y) = ((i % side) as f32 * scale, (i / side) as f32 * scale);
            Vec3::new(x, y, 0.05 * (6.0 * x).sin() * (4.0 * y).cos())
        })
        .collect();
    let mut faces = Vec::with_capacity(2 * ((side - 1) * (side - 1)) as usize);
    for row in 0..side - 1 {
        for col in 0..side - 1 {
            let a = row * side + col;
            let (b, c, d) = (a + 1, a + side, a + side + 1);
            faces.push([a, b, d]);
            faces.push([a, d, c]);
        }
    }
    TriMesh::new(positions, faces)
}

fn read_lodkit(path: &Path) -> usize {
    match io::load(path).expect("lodkit reads its own file") {
        Model::Mesh(m) => m.face_count(),
        other => panic!("expected a mesh, got a {}", other.kind()),
    }
}

fn read_ply_rs(path: &Path) -> usize {
    let file = std::fs::File::open(path).expect("open");
    let mut reader = std::io::BufReader::new(file);
    let ply = ply_rs::parser::Parser::<ply_rs::ply::DefaultElement>::new()
        .read_ply(&mut reader)
        .expect("ply-rs reads the file");
    ply.payload.get("face").map_or(0, Vec::len)
}

fn ply_read(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("grid_1m.ply");
    let mesh = height_field(708);
    io::save_mesh(&path, &mesh, io::WriteOptions::default()).expect("write the bench file");
    let len = std::fs::metadata(&path).expect("stat").len();
    assert_eq!(read_lodkit(&path), mesh.face_count());
    assert_eq!(read_ply_rs(&path), mesh.face_count());

    let mut group = c.benchmark_group("ply_read");
    group
        .sample_size(10)
        .warm_up_time(Duration::from_secs(1))
        .measurement_time(Duration::from_secs(3))
        .throughput(Throughput::Bytes(len));
    group.bench_function(BenchmarkId::new("lodkit", "tris=1M"), |b| {
        b.iter(|| read_lodkit(black_box(&path)))
    });
    group.bench_function(BenchmarkId::new("ply-rs", "tris=1M"), |b| {
        b.iter(|| read_ply_rs(black_box(&path)))
    });
    group.finish();
}

criterion_group!(benches, ply_read);
criterion_main!(benches);
