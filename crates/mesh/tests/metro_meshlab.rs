//! Agreement with MeshLab: `compare` with default options on the Stanford
//! bunny against its quadric-simplified version must match MeshLab's
//! Hausdorff Distance filter (run by `scripts/meshlab_reference.py`, stored
//! in `data/reference/meshlab_hausdorff.json`) within 2% on mean and RMS and
//! 5% on max, in both directions.
//!
//! The reference was produced with lodkit's default per-kind sample count
//! and the same sample kinds (vertices, edges, faces), on the files as
//! saved, with the original's unreferenced vertices removed on MeshLab's
//! side (lodkit never samples them).

use std::path::{Path, PathBuf};

use lodkit_mesh::io::load_mesh;
use lodkit_mesh::metrics::{CompareOptions, DirectionStats, compare, referenced_vertices};
use serde_json::Value;

fn repo(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join(rel)
}

fn num(v: &Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("reference JSON lacks number {key:?} in {v}"))
}

/// Relative difference of `ours` from `theirs`, in percent.
fn pct_diff(ours: f64, theirs: f64) -> f64 {
    100.0 * (ours - theirs).abs() / theirs.abs()
}

fn check_direction(name: &str, ours: &DirectionStats, theirs: &Value) {
    let rows = [
        ("max", ours.max, num(theirs, "max"), 5.0),
        ("mean", ours.mean, num(theirs, "mean"), 2.0),
        ("rms", ours.rms, num(theirs, "RMS"), 2.0),
    ];
    for (what, o, t, tol) in rows {
        let d = pct_diff(o, t);
        eprintln!("{name:<24} {what:<5} lodkit {o:.6e}  MeshLab {t:.6e}  diff {d:.3}%");
        assert!(
            d <= tol,
            "{name} {what}: lodkit {o:e} vs MeshLab {t:e} differ by {d:.3}% (> {tol}%)"
        );
    }
    // Same sampling budget: MeshLab's edge sampler rounds its spacing, so
    // allow a few samples either way.
    let n = num(theirs, "n_samples");
    assert!(
        (ours.samples as f64 - n).abs() <= 1e-4 * n,
        "{name}: {} samples vs MeshLab's {n}",
        ours.samples
    );
    // Same diagonal for the relative figures (MeshLab: the sampled mesh's).
    let diag = num(theirs, "diag_mesh_0");
    assert!(
        (ours.diagonal - diag).abs() <= 1e-6 * diag,
        "{name}: diagonal {} vs MeshLab's {diag}",
        ours.diagonal
    );
}

#[test]
fn bunny_vs_simplified_bunny_agrees_with_meshlab() {
    let reference: Value = serde_json::from_str(
        &std::fs::read_to_string(repo("data/reference/meshlab_hausdorff.json")).unwrap(),
    )
    .unwrap();
    let original = load_mesh(&repo("data/models/stanford_bunny.ply")).unwrap();
    let simplified = load_mesh(&repo("data/reference/stanford_bunny_simplified.ply")).unwrap();

    // The meshes are the ones MeshLab measured.
    assert_eq!(
        original.faces.len() as f64,
        num(&reference["original"], "faces")
    );
    assert_eq!(
        referenced_vertices(&original).len() as f64,
        num(&reference, "original_referenced_vertices")
    );
    assert_eq!(
        simplified.faces.len() as f64,
        num(&reference["simplified"], "faces")
    );

    let start = std::time::Instant::now();
    let report = compare(&original, &simplified, &CompareOptions::default()).unwrap();
    eprintln!("default compare took {:?}", start.elapsed());
    eprintln!("{report}");

    let h = &reference["hausdorff"];
    assert_eq!(
        report.samples_per_kind as f64,
        num(h, "samplenum"),
        "the reference was made with another sample count than lodkit's default"
    );
    for flag in ["samplevert", "sampleedge", "sampleface"] {
        assert_eq!(h["params"][flag], Value::Bool(true), "{flag}");
    }
    check_direction(
        "original -> simplified",
        &report.a_to_b,
        &h["original_to_simplified"],
    );
    check_direction(
        "simplified -> original",
        &report.b_to_a,
        &h["simplified_to_original"],
    );
    // Symmetric max is the Hausdorff distance: the larger direction.
    let hd = num(&h["original_to_simplified"], "max").max(num(&h["simplified_to_original"], "max"));
    assert!(pct_diff(report.symmetric.max, hd) <= 5.0);
}
