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
    assert_eq!(o.status.code(), Some(1));
}
