//! The out-of-core tiler forced on small inputs by a tiny memory budget:
//! a valid tileset read back tile by tile, honest errors, levels within
//! the in-core path's bounds, the same bytes on a rerun and after an
//! interrupted run is resumed, nothing left in the staging folder.

mod common;

use std::path::{Path, PathBuf};

use common::{all_files, assert_honest, drawn_at, read_tileset};
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::{CompareOptions, compare};
use lodkit_tiles::{
    OutOfCoreOptions, TilesOptions, TilesReport, tileset_from_mesh, tileset_out_of_core,
    write_tileset,
};

const LEAF: usize = 1_000;

fn opts() -> TilesOptions {
    TilesOptions {
        leaf_triangles: LEAF,
        ..TilesOptions::DEFAULT
    }
}

/// 1 MB: levels over about 12k faces go through block rounds on disk.
const TINY: u64 = 1 << 20;

fn ooc(input: &Path, out: &Path, staging: &Path) -> TilesReport {
    ooc_in(input, out, staging, TINY)
}

fn ooc_in(input: &Path, out: &Path, staging: &Path, memory: u64) -> TilesReport {
    let o = OutOfCoreOptions {
        memory,
        staging: staging.to_path_buf(),
        runner: lodkit_scale::Runner::Threads,
    };
    tileset_out_of_core(input, out, &opts(), &o, &|_| {}).unwrap()
}

/// The mean distance from the input to the cut of the tileset in `dir` at
/// `depth`: every tile of that depth and every shallower leaf (skirts
/// included: they hang below the surface, so the input measures past
/// them).
fn cut_error(input: &TriMesh, dir: &Path, depth: u8) -> f64 {
    let cut = drawn_at(&read_tileset(dir), depth);
    let r = compare(
        input,
        &cut,
        &CompareOptions {
            seed: 3,
            samples: Some(50_000),
            ..CompareOptions::default()
        },
    )
    .unwrap();
    r.a_to_b.mean
}

/// Every tile read back; every tile's geometricError at least its
/// measured distances (`common::assert_honest`); each depth's cut within
/// 1.25× of the in-core tileset's mean error at that depth.
fn check_against_input_and_in_core(input: &TriMesh, dir: &Path, report: &TilesReport) {
    let ts = read_tileset(dir);
    assert_eq!(
        ts.tiles.iter().filter(|t| t.mesh.is_some()).count(),
        report.tiles
    );
    assert!(
        ts.tiles[0].mesh.is_some(),
        "the root holds the whole object"
    );
    let diag = input.bbox().diagonal() as f64;
    for t in &ts.tiles {
        for &c in &t.children {
            assert!(
                ts.tiles[c].error <= t.error,
                "{} above {}",
                ts.tiles[c].name,
                t.name
            );
        }
    }
    // Distances are measured on samples (another seed here): internal
    // tiles get the in-core test's 10 % for what samples miss.
    assert_honest(&ts, input, 1.1);
    // The in-core tileset of the same input.
    let tmp = tempfile::tempdir().unwrap();
    let in_core = tmp.path().join("in-core");
    let t = tileset_from_mesh(input, &opts(), &mut |_| {}).unwrap();
    let rc = write_tileset(&t, &in_core, None, &opts(), &mut |_| {}).unwrap();
    assert_eq!(rc.depth, report.depth, "the same octree");
    for depth in 0..report.depth {
        let (o, c) = (
            cut_error(input, dir, depth),
            cut_error(input, &in_core, depth),
        );
        println!("depth {depth}: mean error out of core {o:.3e}, in core {c:.3e}");
        assert!(
            o <= 1.25 * c + 1e-6 * diag,
            "depth {depth}: out of core {o} over 1.25 × in core {c}"
        );
    }
}

fn staging_is_gone(staging: &Path) {
    assert!(!staging.exists(), "{} left behind", staging.display());
}

fn blob_ply(dir: &Path, triangles: u64) -> PathBuf {
    let p = dir.join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&p, triangles, 11).unwrap();
    p
}

/// With 1 MB, levels go through block rounds and most tiles' errors are
/// bounded through their children's; with 64 MB, the levels are made in
/// core and every tile is measured against its cell's input directly.
#[test]
fn a_blob_out_of_core_is_honest_and_within_the_in_core_bounds() {
    let tmp = tempfile::tempdir().unwrap();
    let input = blob_ply(tmp.path(), 40_000);
    let mesh = lodkit_mesh::io::load_mesh(&input).unwrap();
    for (name, memory) in [("tiny", TINY), ("roomy", 64 << 20)] {
        let (out, staging) = (tmp.path().join(name), tmp.path().join("stage"));
        let report = ooc_in(&input, &out, &staging, memory);
        println!("{name}: {report:?}");
        staging_is_gone(&staging);
        assert!(report.depth >= 3, "{report:?}");
        assert!(report.max_tile_triangles <= LEAF, "{report:?}");
        assert_eq!(report.input_triangles, mesh.faces.len());
        check_against_input_and_in_core(&mesh, &out, &report);
    }
}

#[test]
fn the_shipped_bunny_out_of_core_is_honest_and_within_the_in_core_bounds() {
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/models/stanford_bunny.ply");
    let tmp = tempfile::tempdir().unwrap();
    let (out, staging) = (tmp.path().join("out"), tmp.path().join("stage"));
    let report = ooc(&bunny, &out, &staging);
    println!("{report:?}");
    staging_is_gone(&staging);
    let mesh = lodkit_mesh::io::load_mesh(&bunny).unwrap();
    check_against_input_and_in_core(&mesh, &out, &report);
}

#[test]
fn reruns_and_resumed_runs_give_the_same_bytes() {
    let tmp = tempfile::tempdir().unwrap();
    // 40k faces: the level below the root's parents is made in block
    // rounds (handed over as soups, resumed as done by the chain).
    let input = blob_ply(tmp.path(), 40_000);
    let staging = tmp.path().join("stage");
    let first = tmp.path().join("first");
    ooc(&input, &first, &staging);
    staging_is_gone(&staging);
    let again = tmp.path().join("again");
    ooc(&input, &again, &staging);
    assert_eq!(all_files(&first), all_files(&again), "a rerun");

    // Interrupted after two depths of tiles: the staging folder stays.
    let resumed = tmp.path().join("resumed");
    let o = OutOfCoreOptions {
        memory: TINY,
        staging: staging.clone(),
        runner: lodkit_scale::Runner::Threads,
    };
    let seen = std::sync::atomic::AtomicUsize::new(0);
    let stop = |e: lodkit_tiles::OutOfCoreEvent| {
        if let lodkit_scale::Event::Phase(name, _) = e
            && name.starts_with("tiles")
            && seen.fetch_add(1, std::sync::atomic::Ordering::SeqCst) == 2
        {
            panic!("interrupted");
        }
    };
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tileset_out_of_core(&input, &resumed, &opts(), &o, &stop)
    }));
    assert!(r.is_err());
    assert!(staging.join("tiles").exists() && !resumed.exists());
    // Some staged outputs lost too: the leaves' spill is redone.
    std::fs::remove_file(staging.join("cells/leaves.done")).unwrap();
    let phases = std::sync::Mutex::new(Vec::new());
    tileset_out_of_core(&input, &resumed, &opts(), &o, &|e| {
        if let lodkit_scale::Event::Phase(name, _) = e {
            phases.lock().unwrap().push(name.to_string());
        }
    })
    .unwrap();
    let phases = phases.into_inner().unwrap();
    let depths = first_report_depth(&first) as usize + 1;
    let redone = phases.iter().filter(|p| p.starts_with("tiles")).count();
    assert!(
        redone < depths,
        "{redone} of {depths} depths redone: {phases:?}"
    );
    assert_eq!(all_files(&first), all_files(&resumed), "a resumed run");
    staging_is_gone(&staging);

    // Interrupted again, and a level's spill lost after the chain moved
    // past it: the staging folder starts over, with the same bytes.
    let seen = std::sync::atomic::AtomicUsize::new(0);
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        tileset_out_of_core(
            &input,
            &tmp.path().join("lost"),
            &opts(),
            &o,
            &stop_after(&seen),
        )
    }));
    assert!(r.is_err());
    let d = first_report_depth(&first);
    std::fs::remove_file(staging.join(format!("cells/d{}.done", d - 1))).unwrap();
    let restarted = tmp.path().join("restarted");
    let phases = std::sync::Mutex::new(Vec::new());
    tileset_out_of_core(&input, &restarted, &opts(), &o, &|e| {
        if let lodkit_scale::Event::Phase(name, _) = e {
            phases.lock().unwrap().push(name.to_string());
        }
    })
    .unwrap();
    let phases = phases.into_inner().unwrap();
    let partitions = phases.iter().filter(|p| *p == "partition: faces per cell");
    assert_eq!(partitions.count(), 2, "started over: {phases:?}");
    assert_eq!(all_files(&first), all_files(&restarted), "a restarted run");
    staging_is_gone(&staging);
}

/// A progress callback that panics at the third tile depth.
fn stop_after(
    seen: &std::sync::atomic::AtomicUsize,
) -> impl Fn(lodkit_tiles::OutOfCoreEvent) + Sync + '_ {
    move |e| {
        if let lodkit_scale::Event::Phase(name, _) = e
            && name.starts_with("tiles")
            && seen.fetch_add(1, std::sync::atomic::Ordering::SeqCst) == 2
        {
            panic!("interrupted");
        }
    }
}

fn first_report_depth(dir: &Path) -> u8 {
    read_tileset(dir)
        .tiles
        .iter()
        .map(|t| t.depth)
        .max()
        .unwrap()
}

#[test]
fn bad_inputs_are_one_line_errors() {
    let tmp = tempfile::tempdir().unwrap();
    let o = OutOfCoreOptions {
        memory: TINY,
        staging: tmp.path().join("stage"),
        runner: lodkit_scale::Runner::Threads,
    };
    let text = tmp.path().join("text.ply");
    std::fs::write(
        &text,
        "ply\nformat ascii 1.0\nelement vertex 0\nend_header\n",
    )
    .unwrap();
    let e = tileset_out_of_core(&text, &tmp.path().join("o"), &opts(), &o, &|_| {})
        .err()
        .unwrap()
        .to_string();
    assert!(e.contains("text.ply") && !e.contains('\n'), "{e}");
    assert!(!tmp.path().join("o").exists());
}
