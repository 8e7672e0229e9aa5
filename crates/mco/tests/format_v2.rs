//! `.mco` version 2 on the shipped bunny, built from its mesh and from
//! `lodkit build`'s 8 virtual scans: no larger than the bunny's binary PLY,
//! a first chunk of a few kilobytes, and a whole file that reads back with
//! the in-memory model's LOD numbers and triangle counts.

use std::path::Path;

use lodkit_mco::{
    McoModel, Options, ScanOptions, build_from_mesh, build_from_range_images, scan_mesh,
};

/// The writer's target size of chunk 0 (`FIRST_CHUNK_BYTES` in
/// `mco_file/v2.rs`, `docs/formats/mco.md`).
const FIRST_CHUNK_BYTES: u64 = 4096;

/// `lodkit build`'s scans (its `BUILD_SCANS`): 8 views, alternately 30°
/// above and below the horizon, 300 × 300 samples each.
const BUILD_SCANS: ScanOptions = ScanOptions {
    views: 8,
    width: 300,
    height: 300,
    elevation_deg: 30.0,
    alternate: true,
    noise: 0.0,
    seed: 1,
};

fn check(what: &str, model: &McoModel, ply_bytes: u64) {
    let bytes = model.to_bytes();
    assert_eq!(McoModel::file_version(&bytes), Some(2));
    let chunks = McoModel::chunk_table(&bytes).unwrap();
    eprintln!(
        "bunny {what}: v2 {} bytes, PLY {ply_bytes}; {} chunks (bytes, last LOD): {:?}",
        bytes.len(),
        chunks.len(),
        chunks
            .iter()
            .map(|c| (c.bytes, c.last_lod))
            .collect::<Vec<_>>()
    );
    assert!(
        bytes.len() as u64 <= ply_bytes,
        "{what}: {} > {ply_bytes}",
        bytes.len()
    );
    assert!(chunks[0].bytes <= 2 * FIRST_CHUNK_BYTES);
    let back = McoModel::from_bytes(&bytes).unwrap();
    assert_eq!(back.max_lod(), model.max_lod());
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let n = model.max_lod();
    for k in [0, 1, n / 4, n / 2, n] {
        model.extract_lod(k, &mut a);
        back.extract_lod(k, &mut b);
        assert_eq!(a.len(), b.len(), "{what}: LOD {k}");
    }
}

#[test]
fn bunny_v2_is_no_larger_than_its_binary_ply() {
    let ply = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/models/stanford_bunny.ply");
    let ply_bytes = std::fs::metadata(&ply).unwrap().len();
    let mesh = lodkit_mesh::io::load_mesh(&ply).unwrap();
    let model = build_from_mesh(&mesh, &Options::default()).unwrap();
    check("from its mesh", &model, ply_bytes);
    let scans = scan_mesh(&mesh, &BUILD_SCANS).unwrap();
    let model = build_from_range_images(&scans, &Options::default()).unwrap();
    check("from the build's 8 scans", &model, ply_bytes);
}
