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
    assert!(
        m.faces.len().abs_diff(target as usize) <= (target as usize / 100).max(40),
        "{} faces for a budget of {target}",
        m.faces.len()
    );
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
fn scan_build_and_extract_print_json() {
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
}

/// A `.mco` cut short (a partial download or copy) is read as far as its
/// complete chunks go: `info` and `extract` say where it stopped (one line
/// on stderr) and serve the LOD numbers those chunks cover, exactly as the
/// whole file; `--strict` refuses it.
#[test]
fn a_cut_short_model_serves_its_complete_chunks() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("torus.ply");
    lodkit_mesh::io::save_mesh(
        &mesh,
        &lodkit_mesh::shapes::torus(1.0, 0.3, 64, 32),
        lodkit_mesh::io::WriteOptions::default(),
    )
    .unwrap();
    let model = dir.path().join("t.mco");
    ok(&lodkit(&[
        "-q",
        "mco",
        "build",
        s(&mesh),
        "-o",
        s(&model),
        "--resolution",
        "48",
    ]));
    let info = |p: &Path, extra: &[&str]| {
        let mut args = vec!["mco", "info", s(p), "--json"];
        args.extend_from_slice(extra);
        lodkit(&args)
    };
    let whole = info(&model, &[]);
    ok(&whole);
    assert!(
        whole.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&whole.stderr)
    );
    let w: serde_json::Value = serde_json::from_slice(&whole.stdout).unwrap();
    assert!(w["cut_short"].is_null(), "{w}");
    let chunks = w["chunks"].as_array().unwrap();
    assert!(chunks.len() >= 4, "{w}");
    // Cut inside chunk 2: chunks 0 and 1 are whole.
    let bytes = std::fs::read(&model).unwrap();
    let at =
        (chunks[2]["offset"].as_u64().unwrap() + chunks[2]["bytes"].as_u64().unwrap() / 2) as usize;
    let cut = dir.path().join("cut.mco");
    std::fs::write(&cut, &bytes[..at]).unwrap();
    let served = chunks[1]["last_lod"].as_u64().unwrap();

    let o = info(&cut, &[]);
    ok(&o);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(
        err.contains("cut.mco")
            && err.contains("stopped at byte")
            && err.contains("2 complete chunks"),
        "{err}"
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["cut_short"]["chunks"], 2, "{v}");
    assert_eq!(v["cut_short"]["max_lod"], served, "{v}");
    assert_eq!(v["cut_short"]["total_max_lod"], w["lod_numbers"], "{v}");
    assert_eq!(v["lod_numbers"], served, "{v}");
    assert_eq!(v["chunks"].as_array().unwrap().len(), 2, "{v}");

    // The prefix cuts the served LOD numbers as the whole file does.
    let extract = |p: &Path, lod: u64, out: &Path, extra: &[&str]| {
        let lod = lod.to_string();
        let mut args = vec!["mco", "extract", s(p), "--lod", &lod, "-o", s(out)];
        args.extend_from_slice(extra);
        lodkit(&args)
    };
    let (a, b) = (dir.path().join("a.ply"), dir.path().join("b.ply"));
    ok(&extract(&model, served, &a, &["-q"]));
    let o = extract(&cut, served, &b, &[]);
    ok(&o);
    assert!(String::from_utf8_lossy(&o.stderr).contains("stopped at byte"));
    // The same triangles (the prefix's extraction may list them in another
    // order).
    let triangles = |p: &Path| {
        let m = lodkit_mesh::io::load_mesh(p).unwrap();
        let mut t: Vec<[[u32; 3]; 3]> = m
            .faces
            .iter()
            .map(|f| {
                let v = f.map(|i| m.positions[i as usize].to_array().map(f32::to_bits));
                let s = (0..3).min_by_key(|&j| v[j]).unwrap();
                [v[s], v[(s + 1) % 3], v[(s + 2) % 3]]
            })
            .collect();
        t.sort_unstable();
        t
    };
    let (ta, tb) = (triangles(&a), triangles(&b));
    assert!(!ta.is_empty());
    assert!(
        ta == tb,
        "the prefix cuts LOD {served} otherwise than the whole file"
    );
    // Past what the complete chunks hold: a bad option value.
    let o = extract(&cut, served + 1, &b, &["-q"]);
    assert_eq!(
        o.status.code(),
        Some(2),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );

    // --strict refuses the cut file, in one line naming it.
    for o in [
        info(&cut, &["--strict"]),
        extract(&cut, 0, &b, &["--strict"]),
    ] {
        assert_eq!(o.status.code(), Some(1));
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(err.trim_end().lines().count(), 1, "{err}");
        assert!(err.contains("cut.mco") && err.contains("--strict"), "{err}");
    }
    // Cut before chunk 0 is whole: nothing to serve.
    let head = dir.path().join("head.mco");
    std::fs::write(&head, &bytes[..150]).unwrap();
    let o = info(&head, &[]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(err.trim_end().lines().count(), 1, "{err}");
    assert!(err.contains("head.mco") && err.contains("chunk 0"), "{err}");
}

/// Coloured inputs and point clouds give `.mco` files that `info` and
/// `extract` read back, colours kept.
#[test]
fn coloured_points_and_meshes_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let mut sheet = lodkit_mesh::TriMesh::default();
    let n = 30u32;
    for j in 0..=n {
        for i in 0..=n {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            sheet.positions.push(lodkit_mesh::glam::Vec3::new(
                x,
                y,
                0.1 * (6.0 * x).sin() * (4.0 * y).cos(),
            ));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            sheet.faces.push([v, v + 1, v + n + 2]);
            sheet.faces.push([v, v + n + 2, v + n + 1]);
        }
    }
    sheet.colors = Some(
        sheet
            .positions
            .iter()
            .map(|p| [(p.x * 255.0) as u8, (p.y * 255.0) as u8, 90, 255])
            .collect(),
    );
    let points = lodkit_mesh::PointCloud {
        positions: sheet.positions.clone(),
        normals: None,
        colors: sheet.colors.clone(),
    };
    let inputs = [
        ("sheet.ply", lodkit_mesh::Model::Mesh(sheet)),
        ("cloud.ply", lodkit_mesh::Model::Points(points)),
    ];
    for (name, m) in inputs {
        let input = dir.path().join(name);
        lodkit_mesh::io::save(&input, &m, lodkit_mesh::io::WriteOptions::default()).unwrap();
        let model = dir.path().join(name.replace(".ply", ".mco"));
        ok(&lodkit(&["-q", "mco", "build", s(&input), "-o", s(&model)]));
        ok(&lodkit(&["mco", "info", s(&model)]));
        let out = dir.path().join(name.replace(".ply", "_cut.ply"));
        ok(&lodkit(&[
            "-q",
            "mco",
            "extract",
            s(&model),
            "--triangles",
            "500",
            "-o",
            s(&out),
        ]));
        let cut = lodkit_mesh::io::load_mesh(&out).unwrap();
        assert!(
            cut.faces.len() > 100,
            "{name}: {} triangles",
            cut.faces.len()
        );
        assert!(cut.colors.is_some(), "{name}: colours lost");
    }
}
