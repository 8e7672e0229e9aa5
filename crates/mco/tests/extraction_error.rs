//! Extraction quality against the scanned shape: a model rebuilt from
//! virtual scans of a sphere is close to it at full size, and its error
//! grows as the triangle budget shrinks.

use lodkit_mco::{Options, ScanOptions, build_from_range_images, scan_mesh};
use lodkit_mesh::metrics::{CompareOptions, compare};

#[test]
fn errors_grow_as_the_budget_shrinks() {
    let sphere = lodkit_mesh::shapes::icosphere(4);
    let scans = ScanOptions {
        views: 8,
        width: 64,
        height: 64,
        elevation_deg: 30.0,
        alternate: true,
        noise: 0.0,
        seed: 1,
    };
    let images = scan_mesh(&sphere, &scans).unwrap();
    let m = build_from_range_images(
        &images,
        &Options {
            resolution: Some(24),
        },
    )
    .unwrap();
    let opts = CompareOptions {
        samples: Some(20_000),
        ..Default::default()
    };
    let full = m.full_triangles();
    let mut idx = Vec::new();
    let rows: Vec<(usize, f64)> = [100.0, 10.0, 1.0]
        .iter()
        .map(|percent| {
            let target = ((full as f64 * percent / 100.0).round() as usize).max(1);
            m.extract_triangles(target, &mut idx);
            let mesh = m.mesh_from_indices(&idx);
            let r = compare(&mesh, &sphere, &opts).unwrap();
            (mesh.faces.len(), r.symmetric.mean)
        })
        .collect();
    let cube = m.grid().cube() as f64;
    assert!(rows[0].1 < 0.5 * cube, "{rows:?}");
    assert!(rows[0].1 <= rows[1].1 && rows[1].1 <= rows[2].1, "{rows:?}");
    assert!(rows[2].0 < rows[1].0);
}
