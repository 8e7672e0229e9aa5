//! End-to-end tests of the `lodkit` binary: exit codes, messages, outputs.

use std::path::{Path, PathBuf};

mod common;
use common::{bunny, lodkit, repo, stderr};

/// Every file under `dir`, relative, sorted.
fn tree(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().display().to_string());
            }
        }
    }
    out.sort();
    out
}

/// `lods.json` without its wall times (the only field allowed to differ).
fn without_times(bytes: &[u8]) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    for l in v["levels"].as_array_mut().unwrap() {
        l.as_object_mut().unwrap().remove("seconds");
    }
    v
}

#[test]
fn build_without_input_writes_the_bunny_and_its_lod_chain_deterministically() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for out in [&a, &b] {
        let o = lodkit(&[
            "-q",
            "build",
            "--levels",
            "3",
            "--samples",
            "100000",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let n = "stanford_bunny";
    let mut expected: Vec<String> = vec![
        format!("{n}.glb"),
        format!("{n}.ply"),
        "lod_error.svg".into(),
        format!("lods/{n}_lod1.ply"),
        format!("lods/{n}_lod2.ply"),
        format!("lods/{n}_lod3.ply"),
        format!("lods/{n}_lods.glb"),
        "lods/lods.json".into(),
        "report.md".into(),
        "report.html".into(),
        format!("{n}.mco"),
        format!("{n}.pop"),
        format!("scans/{n}.conf"),
    ];
    expected.extend((0..8).map(|i| format!("scans/{n}_{i:03}.ply")));
    expected.sort();
    // Nothing but the outputs: no temp files left behind.
    assert_eq!(tree(&a), expected);
    for file in &expected {
        let x = std::fs::read(a.join(file)).unwrap();
        let y = std::fs::read(b.join(file)).unwrap();
        assert!(!x.is_empty(), "{file} is empty");
        if file.ends_with(".html") {
            // The stage timings vary; they sit between these markers.
            let strip = |h: &[u8]| {
                let h = String::from_utf8_lossy(h).into_owned();
                let (a, b) = (
                    h.find("<!-- varies -->").unwrap(),
                    h.find("<!-- /varies -->").unwrap(),
                );
                format!("{}{}", &h[..a], &h[b..])
            };
            assert_eq!(strip(&x), strip(&y), "{file} differs between two runs");
        } else if file.ends_with(".json") {
            assert_eq!(
                without_times(&x),
                without_times(&y),
                "{file} differs between two runs"
            );
        } else {
            // Compare as text where it is text, so a failure is readable.
            assert!(
                x == y,
                "{file} differs between two runs:\n{}\n---\n{}",
                String::from_utf8_lossy(&x),
                String::from_utf8_lossy(&y)
            );
        }
    }
    let report = std::fs::read_to_string(a.join("report.md")).unwrap();
    assert!(report.contains("vertices: 35947"), "{report}");
    assert!(report.contains("faces: 69451"), "{report}");
    assert!(
        report.contains("## Discrete LOD chain (HQMS)") && report.contains("lod_error.svg"),
        "{report}"
    );
    assert!(
        report.contains("## Continuous LOD (marching cube octree)") && report.contains("| 10 |"),
        "{report}"
    );
    assert!(
        report.contains("## Progressive stream (octree particles)"),
        "{report}"
    );
    // The chain halves the bunny three times, each level measured.
    let lods = without_times(&std::fs::read(a.join("lods/lods.json")).unwrap());
    let levels = lods["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    for (i, l) in levels.iter().enumerate() {
        let target = (69451usize >> (i + 1)) as f64;
        let tris = l["triangles"].as_f64().unwrap();
        assert!(
            tris <= target + 1.0 && tris >= target * 0.995,
            "level {i}: {tris} for {target}"
        );
        assert!(l["measured_max_error"].as_f64().unwrap() > 0.0);
    }
    // The GLB reads back as the same mesh.
    let o = lodkit(&[
        "info",
        "--json",
        a.join(format!("{n}.glb")).to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["faces"], 69451);
}

#[test]
fn info_reports_the_bunny_topology_as_json() {
    let o = lodkit(&["info", "--json", &bunny()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["kind"], "mesh");
    assert_eq!(v["vertices"], 35947);
    assert_eq!(v["faces"], 69451);
    // The values the shared data README lists for this file.
    assert_eq!(v["boundary_edges"], 223);
    assert_eq!(v["boundary_loops"], 5);
    assert_eq!(v["non_manifold_edges"], 0);
    assert_eq!(v["unreferenced_vertices"], 1113);
}

#[test]
fn usage_errors_exit_2_and_bad_input_exits_1() {
    assert_eq!(lodkit(&["info"]).status.code(), Some(2));
    assert_eq!(lodkit(&["frobnicate"]).status.code(), Some(2));
    let o = lodkit(&["info", "/nonexistent/file.ply"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("/nonexistent/file.ply") && e.lines().count() == 1,
        "{e}"
    );
    let o = lodkit(&["info", "notes.docx"]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn every_malformed_file_exits_1_with_one_line_and_no_panic() {
    let dir = repo().join("tests/malformed");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e != "md"))
        .collect();
    files.sort();
    assert!(files.len() >= 30, "corpus has only {} files", files.len());
    for f in files {
        let o = lodkit(&["info", f.to_str().unwrap()]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{}: {e}", f.display());
        assert!(!e.contains("panicked"), "{}: {e}", f.display());
        assert_eq!(e.trim_end().lines().count(), 1, "{}: {e}", f.display());
        let name = f.file_name().unwrap().to_str().unwrap();
        assert!(
            e.contains(name),
            "{}: message does not name the file: {e}",
            f.display()
        );
    }
}

#[test]
fn convert_keeps_the_mesh_across_formats() {
    let dir = tempfile::tempdir().unwrap();
    let mut last = bunny();
    for ext in ["obj", "stl", "glb", "ply"] {
        let out = dir
            .path()
            .join(format!("bunny.{ext}"))
            .display()
            .to_string();
        let o = lodkit(&["-q", "convert", &last, &out]);
        assert!(o.status.success(), "{ext}: {}", stderr(&o));
        let o = lodkit(&["info", "--json", &out]);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["faces"], 69451, "{ext}");
        last = out;
    }
    // Writing a point cloud to a mesh-only format is refused, not faked.
    let cloud = dir.path().join("bunny.xyz").display().to_string();
    assert!(
        lodkit(&["-q", "convert", &bunny(), &cloud])
            .status
            .success()
    );
    let o = lodkit(&[
        "convert",
        &cloud,
        dir.path().join("x.stl").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("x.stl"), "{}", stderr(&o));
}

/// `lodkit bench simplify` runs against meshoptimizer when the build links
/// it (feature `peers`, on in workspace-wide builds through the bench
/// crate's default) and otherwise says how to get it, exit 2.
#[test]
fn bench_simplify_runs_with_the_peers_feature_and_explains_itself_without() {
    let mesh = repo().join("data/reference/stanford_bunny_simplified.ply");
    let args = [
        "bench",
        "simplify",
        mesh.to_str().unwrap(),
        "--runs",
        "1",
        "--samples",
        "20000",
    ];
    let o = lodkit(&args);
    if lodkit_bench::PEERS {
        assert!(o.status.success(), "{}", stderr(&o));
        let table = String::from_utf8_lossy(&o.stdout);
        assert!(table.contains("mo tris"), "{table}");
        assert_eq!(
            table
                .lines()
                .filter(|l| l.contains("bunny_simplified"))
                .count(),
            4
        );
    } else {
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        let e = stderr(&o);
        assert!(
            e.contains("--features peers") && e.lines().count() == 1,
            "{e}"
        );
    }
}
