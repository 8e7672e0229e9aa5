//! The reconstruction figure on real data: the Stanford bunny
//! rebuilt from its 10 real range scans and from 8 virtual scans has a
//! symmetric mean error of at most half a cube against
//! `stanford_bunny.ply`. Skips when `../shared/data` is absent.

use std::path::{Path, PathBuf};

use lodkit_mco::{Options, ScanOptions, build_from_range_images, scan_mesh};
use lodkit_mesh::metrics::{CompareOptions, compare};

fn shared() -> Option<PathBuf> {
    let p = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data");
    p.join("meshes/stanford_bunny.ply").exists().then_some(p)
}

fn check(name: &str, model: &lodkit_mco::McoModel, reference: &lodkit_mesh::TriMesh, seconds: f64) {
    let full = model.mesh_at_lod(model.max_lod());
    let opts = CompareOptions {
        samples: Some(200_000),
        ..Default::default()
    };
    let r = compare(&full, reference, &opts).unwrap();
    let grid = model.grid();
    let half = 0.5 * grid.cube() as f64;
    eprintln!(
        "{name}: resolution {}, cube {:.6}, {} triangles; symmetric mean {:.6} (half cube {:.6}), \
         rec→ref mean {:.6}, ref→rec mean {:.6}, Hausdorff {:.6}; build {:.2} s",
        grid.resolution(),
        grid.cube(),
        full.faces.len(),
        r.symmetric.mean,
        half,
        r.a_to_b.mean,
        r.b_to_a.mean,
        r.symmetric.max,
        seconds
    );
    assert!(
        r.symmetric.mean <= half,
        "{name}: {} > {half}",
        r.symmetric.mean
    );
}

#[test]
fn bunny_from_its_ten_real_scans() {
    let Some(data) = shared() else {
        eprintln!("skipped: ../shared/data is absent");
        return;
    };
    let reference = lodkit_mesh::io::load_mesh(&data.join("meshes/stanford_bunny.ply")).unwrap();
    let scans: Vec<_> =
        lodkit_mesh::io::conf::load_scans(&data.join("range/stanford_bunny/bun.conf"))
            .unwrap()
            .into_iter()
            .map(|(_, r)| r)
            .collect();
    assert_eq!(scans.len(), 10);
    let t = std::time::Instant::now();
    let model = build_from_range_images(&scans, &Options::default()).unwrap();
    check(
        "10 real scans",
        &model,
        &reference,
        t.elapsed().as_secs_f64(),
    );
}

#[test]
fn bunny_from_eight_virtual_scans() {
    let Some(data) = shared() else {
        eprintln!("skipped: ../shared/data is absent");
        return;
    };
    let reference = lodkit_mesh::io::load_mesh(&data.join("meshes/stanford_bunny.ply")).unwrap();
    let opts = ScanOptions {
        views: 8,
        width: 300,
        height: 300,
        elevation_deg: 30.0,
        alternate: true,
        ..Default::default()
    };
    let scans = scan_mesh(&reference, &opts).unwrap();
    let t = std::time::Instant::now();
    let model = build_from_range_images(&scans, &Options::default()).unwrap();
    check(
        "8 virtual scans",
        &model,
        &reference,
        t.elapsed().as_secs_f64(),
    );
}
