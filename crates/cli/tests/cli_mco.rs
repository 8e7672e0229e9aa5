//! End-to-end tests of `lodkit scan` and `lodkit mco build|extract|info`.

use std::path::Path;
use std::process::Output;

mod common;
use common::lodkit;

fn ok(o: &Output) {
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn scan_build_extract_info_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("sphere.ply");
    lodkit_mesh::io::save_mesh(
        &mesh,
        &lodkit_mesh::shapes::icosphere(3),
        lodkit_mesh::io::WriteOptions::default(),
    )
    .unwrap();
    let scans = dir.path().join("scans");
    ok(&lodkit(&[
        "-q",
        "scan",
        s(&mesh),
        "--views",
        "4",
        "--size",
        "48x40",
        "--elevation",
        "30",
        "--alternate",
        "--out",
        s(&scans),
    ]));
    let conf = scans.join("sphere.conf");
    assert!(conf.exists() && scans.join("sphere_003.ply").exists());
    let model = dir.path().join("s.mco");
    ok(&lodkit(&[
        "-q",
        "mco",
        "build",
        s(&conf),
        "-o",
        s(&model),
        "--resolution",
        "16",
    ]));
    let info = lodkit(&["mco", "info", s(&model), "--json"]);
    ok(&info);
    let v: serde_json::Value = serde_json::from_slice(&info.stdout).unwrap();
    let full = v["full_triangles"].as_u64().unwrap();
    assert!(full > 500, "{v}");
    assert_eq!(v["resolution"], 16);
    let out = dir.path().join("half.ply");
    let target = full / 2;
    ok(&lodkit(&[
        "-q",
        "mco",
        "extract",
        s(&model),
        "--triangles",
        &target.to_string(),
        "-o",
        s(&out),
    ]));
    let m = lodkit_mesh::io::load_mesh(&out).unwrap();
    assert!(m.faces.len().abs_diff(target as usize) <= (target as usize / 100).max(40));
    let near = dir.path().join("near.ply");
    ok(&lodkit(&[
        "-q",
        "mco",
        "extract",
        s(&model),
        "--view",
        "0,0,3",
        "--tolerance",
        "2",
        "-o",
        s(&near),
    ]));
    assert!(lodkit_mesh::io::load_mesh(&near).unwrap().faces.len() > 10);
    // Same inputs, same bytes.
    let again = dir.path().join("t.mco");
    ok(&lodkit(&[
        "-q",
        "mco",
        "build",
        s(&conf),
        "-o",
        s(&again),
        "--resolution",
        "16",
    ]));
    let (a, b) = (
        std::fs::read(&model).unwrap(),
        std::fs::read(&again).unwrap(),
    );
    // The build time differs; everything before it (signature, lattice) and
    // all arrays after the header must match.
    assert_eq!(a.len(), b.len());
    assert_eq!(a[..48], b[..48]);
    assert_eq!(a[56..a.len() - 4], b[56..b.len() - 4]);
}

#[test]
fn bad_models_and_options_are_one_line_errors() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.mco");
    std::fs::write(&bad, b"LODKMCO\0 definitely not a model").unwrap();
    for args in [
        vec!["mco", "info", s(&bad)],
        vec!["mco", "extract", s(&bad), "--lod", "3", "-o", "x.ply"],
    ] {
        let o = lodkit(&args);
        assert_eq!(o.status.code(), Some(1));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("bad.mco"), "{err}");
    }
    // Neither --lod, --triangles nor --view: usage error.
    let o = lodkit(&["mco", "extract", s(&bad), "-o", "x.ply"]);
    assert_eq!(o.status.code(), Some(2));
    let o = lodkit(&[
        "scan",
        "nothing.ply",
        "--size",
        "12",
        "--out",
        s(dir.path()),
    ]);
    // A malformed option value is a usage error, before the file is read.
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&o.stderr).contains("2..=4096"));
}

#[test]
fn scan_build_extract_and_bench_print_json() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("sphere.ply");
    lodkit_mesh::io::save_mesh(
        &mesh,
        &lodkit_mesh::shapes::icosphere(2),
        lodkit_mesh::io::WriteOptions::default(),
    )
    .unwrap();
    let json = |args: &[&str]| -> serde_json::Value {
        let o = lodkit(args);
        ok(&o);
        serde_json::from_slice(&o.stdout).unwrap_or_else(|e| panic!("{args:?}: {e}"))
    };
    let scans = dir.path().join("scans");
    let v = json(&[
        "scan",
        s(&mesh),
        "--views",
        "2",
        "--size",
        "16x16",
        "--out",
        s(&scans),
        "--json",
    ]);
    assert_eq!(v["scans"].as_array().unwrap().len(), 2, "{v}");
    assert!(v["conf"].as_str().unwrap().ends_with("sphere.conf"));
    let model = dir.path().join("s.mco");
    let v = json(&[
        "mco",
        "build",
        s(&mesh),
        "-o",
        s(&model),
        "--resolution",
        "12",
        "--json",
    ]);
    assert_eq!(v["resolution"], 12);
    assert!(v["full_triangles"].as_u64().unwrap() > 0, "{v}");
    let v = json(&[
        "mco",
        "extract",
        s(&model),
        "--lod",
        "0",
        "-o",
        s(&dir.path().join("root.ply")),
        "--json",
    ]);
    assert_eq!(v["lod"], 0);
    assert!(v["triangles"].as_u64().is_some(), "{v}");
    let v = json(&["bench", "mco", s(&model), "--budget", "0.01", "--json"]);
    assert!(!v.as_array().unwrap().is_empty(), "{v}");
    assert!(v[0]["extract_us"].as_f64().is_some(), "{v}");
}
