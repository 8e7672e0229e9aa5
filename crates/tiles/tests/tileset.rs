//! A tileset of a generated closed mesh, read back as a client reads it.

mod common;

use common::{all_files, assert_honest, read_tileset};
use lodkit_mesh::shapes::blob;
use lodkit_tiles::{Error, MANIFEST, TilesOptions, tileset_from_mesh, write_tileset};

const LEAF: usize = 1_000;

fn opts() -> TilesOptions {
    TilesOptions {
        leaf_triangles: LEAF,
        ..TilesOptions::DEFAULT
    }
}

fn build(dir: &std::path::Path, mesh: &lodkit_mesh::TriMesh) -> lodkit_tiles::TilesReport {
    let ts = tileset_from_mesh(mesh, &opts(), &mut |_| {}).unwrap();
    write_tileset(&ts, dir, None, &opts(), &mut |_| {}).unwrap()
}

#[test]
fn tileset_reads_back_with_monotone_measured_errors() {
    let input = blob(40_000);
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("tiles-out");
    let report = build(&out, &input);
    assert!(
        report.depth >= 3,
        "deep enough for an external tileset: {report:?}"
    );
    assert!(report.max_tile_triangles <= LEAF, "{report:?}");
    let ts = read_tileset(&out);
    assert!(ts.json_files > 1, "external tilesets below depth 3");
    assert_eq!(
        ts.tiles.iter().filter(|t| t.mesh.is_some()).count(),
        report.tiles
    );
    let root = &ts.tiles[0];
    assert!(root.mesh.is_some(), "the root holds the whole object");
    assert!(ts.tileset_error >= root.error && root.error > 0.0);
    let diag = input.bbox().diagonal() as f64;
    for t in &ts.tiles {
        for &c in &t.children {
            let ch = &ts.tiles[c];
            assert!(
                ch.error <= t.error,
                "{} {} > {} {}",
                ch.name,
                ch.error,
                t.name,
                t.error
            );
            // The child's box lies in the parent's.
            let lo = (ch.centre - ch.half) - (t.centre - t.half);
            let hi = (t.centre + t.half) - (ch.centre + ch.half);
            assert!(lo.min_element() >= -1e-6 * diag && hi.min_element() >= -1e-6 * diag);
        }
        if t.children.is_empty() {
            // A leaf is the input, rounded to its depth's grid.
            assert!(
                t.error > 0.0 && t.error <= 1e-4 * diag,
                "{}: {}",
                t.name,
                t.error
            );
        }
    }
    assert_honest(&ts, &input, 1.1);
    // Bounding boxes are z-up: the input's y extent is the box's z.
    let b = input.bbox();
    assert!((root.half.z * 2.0 - (b.max.y - b.min.y) as f64).abs() <= 1e-3 * diag);
}

#[test]
fn same_input_same_bytes_and_the_folder_is_replaced_whole() {
    let input = blob(12_000);
    let tmp = tempfile::tempdir().unwrap();
    let (a, b) = (tmp.path().join("a"), tmp.path().join("b"));
    build(&a, &input);
    build(&b, &input);
    let (fa, fb) = (all_files(&a), all_files(&b));
    assert!(fa.iter().any(|(p, _)| p == MANIFEST));
    assert_eq!(fa, fb);
    // Writing again over lodkit's own folder replaces it.
    build(&a, &input);
    assert_eq!(all_files(&a), fb);
}

#[test]
fn a_folder_with_a_users_file_is_refused_and_kept() {
    let input = blob(2_000);
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("mine");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("notes.txt"), b"mine").unwrap();
    let ts = tileset_from_mesh(&input, &opts(), &mut |_| {}).unwrap();
    let err = write_tileset(&ts, &out, None, &opts(), &mut |_| {}).unwrap_err();
    assert!(matches!(err, Error::Usage(_)), "{err}");
    assert!(err.to_string().contains("not a lodkit build"), "{err}");
    assert_eq!(std::fs::read(out.join("notes.txt")).unwrap(), b"mine");
    assert_eq!(std::fs::read_dir(&out).unwrap().count(), 1);
    assert_eq!(
        std::fs::read_dir(tmp.path()).unwrap().count(),
        1,
        "no temporary folder left"
    );
}

#[test]
fn bad_inputs_are_errors_not_panics() {
    let empty = lodkit_mesh::TriMesh::default();
    assert!(matches!(
        tileset_from_mesh(&empty, &opts(), &mut |_| {}),
        Err(Error::Input(_))
    ));
    let small = TilesOptions {
        leaf_triangles: 1,
        ..opts()
    };
    assert!(matches!(
        tileset_from_mesh(&blob(100), &small, &mut |_| {}),
        Err(Error::Usage(_))
    ));
}

#[test]
fn a_small_mesh_is_one_root_tile() {
    let input = blob(500);
    let tmp = tempfile::tempdir().unwrap();
    let report = build(&tmp.path().join("o"), &input);
    assert_eq!((report.tiles, report.depth), (1, 0));
    let ts = read_tileset(&tmp.path().join("o"));
    assert_eq!(ts.tiles.len(), 1);
    // The input itself, rounded to the root's grid.
    let diag = input.bbox().size().length() as f64;
    assert!(ts.tiles[0].error > 0.0 && ts.tiles[0].error < 1e-4 * diag);
    assert!(ts.tileset_error > ts.tiles[0].error);
}

/// Each depth's cut above the leaves is within 1.25× the mean error of
/// simplifying the input in core to the same triangle count (a blob has
/// no normals: the levels are simplified on their geometry, as
/// `lodkit simplify` does such a file).
#[test]
fn levels_are_within_a_quarter_of_in_core_simplification() {
    let input = blob(100_000);
    assert!(input.normals.is_none());
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("t");
    let o = TilesOptions {
        skirts: false,
        ..opts()
    };
    let ts = tileset_from_mesh(&input, &o, &mut |_| {}).unwrap();
    write_tileset(&ts, &out, None, &o, &mut |_| {}).unwrap();
    let read = read_tileset(&out);
    let first_leaf = read
        .tiles
        .iter()
        .filter(|t| t.children.is_empty())
        .map(|t| t.depth)
        .min()
        .unwrap();
    assert!(first_leaf >= 2, "two levels above the leaves");
    let reference = lodkit_mesh::metrics::Reference::new(&input).unwrap();
    for depth in 0..first_leaf {
        let mut cut = lodkit_mesh::TriMesh::default();
        for t in read.tiles.iter().filter(|t| t.depth == depth) {
            let m = t.mesh.as_ref().unwrap();
            let base = cut.positions.len() as u32;
            cut.positions.extend_from_slice(&m.positions);
            cut.faces
                .extend(m.faces.iter().map(|f| f.map(|v| v + base)));
        }
        let simplified =
            lodkit_simplify::simplify(&input, &lodkit_simplify::Options::faces(cut.faces.len()))
                .unwrap()
                .mesh;
        let tiles = reference.compare_level(&cut, None).unwrap().symmetric.mean;
        let direct = reference
            .compare_level(&simplified, None)
            .unwrap()
            .symmetric
            .mean;
        println!(
            "depth {depth}: {} triangles, mean {tiles:.3e} against {direct:.3e}",
            cut.faces.len()
        );
        assert!(tiles <= 1.25 * direct, "depth {depth}: {tiles} vs {direct}");
    }
}

/// Honest errors on real scans (`../shared/data`, skipped when absent):
/// the closed bunny and the RGB-D mug scan (a grid mesh with a rim, the
/// geometry of the textured scan), each tileset written and read back.
#[test]
fn real_scans_get_honest_errors() {
    let shared = std::env::var_os("LODKIT_SHARED_DATA").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
        std::path::PathBuf::from,
    );
    for (name, leaf) in [
        ("meshes/stanford_bunny_closed_glmark2.ply", 2_000),
        ("textured/table_scene_mug_rgbd.obj", 8_000),
    ] {
        let path = shared.join(name);
        if !path.exists() {
            println!("skipped: {} is absent", path.display());
            continue;
        }
        let input = lodkit_mesh::io::load_mesh(&path).unwrap();
        let tmp = tempfile::tempdir().unwrap();
        let out = tmp.path().join("t");
        let opts = TilesOptions {
            leaf_triangles: leaf,
            ..TilesOptions::DEFAULT
        };
        let ts = tileset_from_mesh(&input, &opts, &mut |_| {}).unwrap();
        let report = write_tileset(&ts, &out, None, &opts, &mut |_| {}).unwrap();
        assert!(report.depth >= 2, "{name}: {report:?}");
        let read = read_tileset(&out);
        println!(
            "{name}: {} tiles, depth {}, root geometricError {:.3e}",
            report.tiles, report.depth, read.tiles[0].error
        );
        assert_honest(&read, &input, 1.1);
    }
}
