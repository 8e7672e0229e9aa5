//! Release driver for profiling the build (`perf record`, callgrind) and for
//! checking that a change keeps the output byte-identical: builds
//! `shapes::blob(TRIS)` — or, with `bunny`, the Stanford bunny from its 10
//! real range scans in `../shared/data` — `REPEAT` times and prints the
//! best time, input points per second and a CRC of the encoded model. Beside the wall time it prints the best thread CPU
//! time, which a loaded machine inflates far less (other processes
//! preempting this one do not count). With `MCO_OUT=PATH` in the
//! environment the last model is also written there (for
//! `mco_compare_models`, which checks that two builds draw the same meshes).
//!
//! ```text
//! cargo run --release -p lodkit-bench --example mco_build_driver -- 640000 3
//! cargo run --release -p lodkit-bench --example mco_build_driver -- bunny 3
//! ```

use std::time::Instant;

use lodkit_bench::simplify::thread_cpu_seconds;
use lodkit_mco::{McoModel, Options, build_from_mesh, build_from_models, build_from_range_images};
use lodkit_mesh::shapes;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let what = args.get(1).map_or("640000", String::as_str);
    let repeat: usize = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(3);
    let build: Box<dyn Fn() -> McoModel>;
    let points;
    if what == "bunny" {
        let conf = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../../shared/data/range/stanford_bunny/bun.conf");
        let scans: Vec<_> = lodkit_mesh::io::conf::load_scans(&conf)
            .expect("the bunny's scans")
            .into_iter()
            .map(|(_, r)| r)
            .collect();
        points = scans
            .iter()
            .map(|r| r.valid.iter().filter(|&&v| v).count())
            .sum();
        build = Box::new(move || build_from_range_images(&scans, &Options::default()).unwrap());
    } else if let Some(tris) = what.strip_prefix("cloud") {
        let mesh = shapes::blob(tris.parse().expect("cloudTRIANGLES"));
        points = mesh.positions.len();
        let cloud = [lodkit_mesh::Model::Points(lodkit_mesh::PointCloud {
            positions: mesh.positions.clone(),
            normals: Some(lodkit_mesh::normals::vertex_normals(&mesh)),
            colors: None,
        })];
        build = Box::new(move || build_from_models(&cloud, &Options::default()).unwrap());
    } else {
        let mesh = shapes::blob(what.parse().expect("a triangle count or `bunny`"));
        points = mesh.positions.len();
        build = Box::new(move || build_from_mesh(&mesh, &Options::default()).unwrap());
    }
    let mut best = f64::INFINITY;
    let mut best_cpu = f64::INFINITY;
    let mut crc = 0;
    let mut shape = String::new();
    for _ in 0..repeat {
        let t = Instant::now();
        let c = thread_cpu_seconds();
        let m = build();
        best_cpu = best_cpu.min(thread_cpu_seconds().unwrap_or(f64::NAN) - c.unwrap_or(f64::NAN));
        best = best.min(t.elapsed().as_secs_f64());
        shape = format!(
            "resolution {}, {} nodes, {} triangles",
            m.grid().resolution(),
            m.info().nodes,
            m.full_triangles()
        );
        // The file ends with its own CRC; hash what it covers.
        let bytes = m.to_bytes();
        crc = crc32fast::hash(&bytes[..bytes.len() - 4]);
        if let Some(path) = std::env::var_os("MCO_OUT") {
            std::fs::write(path, &bytes).expect("write MCO_OUT");
        }
    }
    println!(
        "{what}: {points} points, best {best:.3} s, {:.0} points/s, \
         thread CPU {best_cpu:.3} s, {:.0} points/CPU-s, crc {crc:08x}, {shape}",
        points as f64 / best,
        points as f64 / best_cpu
    );
}
