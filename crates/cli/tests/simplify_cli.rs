//! End-to-end tests of `lodkit simplify` and `lodkit lods`.

use std::path::Path;

use lodkit_mesh::io::{WriteOptions, save_mesh};
use lodkit_mesh::{Model, TriMesh};

mod common;
use common::{lodkit, stderr};

fn mesh_at(p: &Path) -> TriMesh {
    match lodkit_mesh::io::load(p).unwrap() {
        Model::Mesh(m) => m,
        other => panic!("{}", other.kind()),
    }
}

fn blob_file(dir: &Path, n: usize) -> String {
    let p = dir.join("blob.ply");
    save_mesh(&p, &lodkit_mesh::shapes::blob(n), WriteOptions::default()).unwrap();
    p.display().to_string()
}

#[test]
fn simplify_writes_the_target_face_count() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob_file(dir.path(), 20_000);
    let out = dir.path().join("lod.ply");
    let o = lodkit(&[
        "simplify",
        &input,
        "-o",
        out.to_str().unwrap(),
        "--target",
        "2000",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = mesh_at(&out);
    assert!(
        m.faces.len() <= 2000 && m.faces.len() >= 1990,
        "{}",
        m.faces.len()
    );
    let j: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(j["triangles"], m.faces.len());
    assert_eq!(j["stop"], "reached the target");
    assert!(j["estimated_error"].as_f64().unwrap() > 0.0);
}

#[test]
fn simplify_by_max_error_says_why_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob_file(dir.path(), 20_000);
    let out = dir.path().join("lod.obj");
    let o = lodkit(&[
        "simplify",
        &input,
        "-o",
        out.to_str().unwrap(),
        "--max-error",
        "0.01",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("--max-error"), "{}", stderr(&o));
    assert!(mesh_at(&out).faces.len() < 20_000);
}

#[test]
fn simplify_without_a_budget_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob_file(dir.path(), 2_000);
    let out = dir.path().join("lod.ply");
    let o = lodkit(&["simplify", &input, "-o", out.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    let o = lodkit(&[
        "simplify",
        &input,
        "-o",
        out.to_str().unwrap(),
        "--ratio",
        "3",
    ]);
    // Out of range: a usage error naming the range, before the input is read.
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("--ratio") && stderr(&o).contains("[0, 1]"));
}

#[test]
fn lods_writes_every_level_a_glb_and_lods_json() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob_file(dir.path(), 20_000);
    let out = dir.path().join("lods");
    let o = lodkit(&[
        "-q",
        "lods",
        &input,
        "--out",
        out.to_str().unwrap(),
        "--ratios",
        "0.5,0.1,0.02",
        "--samples",
        "20000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("lods.json")).unwrap()).unwrap();
    let levels = j["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    let mut prev = usize::MAX;
    for l in levels {
        let m = mesh_at(&out.join(l["file"].as_str().unwrap()));
        assert_eq!(l["triangles"], m.faces.len());
        assert!(m.faces.len() < prev);
        prev = m.faces.len();
        assert!(l["measured_mean_error"].as_f64().unwrap() > 0.0);
        assert!(
            l["measured_max_error"].as_f64().unwrap() >= l["measured_mean_error"].as_f64().unwrap()
        );
    }
    let glb = mesh_at(&out.join(j["glb"].as_str().unwrap()));
    assert!(!glb.faces.is_empty());
}

/// The JSON chunk of a GLB.
fn glb_json(path: &Path) -> serde_json::Value {
    let b = std::fs::read(path).unwrap();
    let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + len]).unwrap()
}

#[test]
fn lods_stops_a_stalled_chain_at_its_last_new_level_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    // 80 faces: halving ten times stalls at the smallest closed mesh.
    let input = dir.path().join("ico.ply");
    save_mesh(
        &input,
        &lodkit_mesh::shapes::icosphere(1),
        WriteOptions::default(),
    )
    .unwrap();
    let out = dir.path().join("lods");
    let o = lodkit(&[
        "lods",
        input.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--levels",
        "10",
        "--samples",
        "2000",
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    let j: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("lods.json")).unwrap()).unwrap();
    let levels = j["levels"].as_array().unwrap();
    let n = levels.len();
    assert!((1..10).contains(&n), "{j}");
    let last = &levels[n - 1];
    let said: Vec<&str> = e
        .lines()
        .filter(|l| l.contains("stopped at level"))
        .collect();
    assert_eq!(said.len(), 1, "{e}");
    assert!(
        said[0].contains(&format!("stopped at level {n} of 10"))
            && said[0].contains(&format!("level {n}'s {}", last["triangles"])),
        "{e}"
    );
    // Every level written once, each smaller than the one before, in the
    // PLY files and in the GLB.
    let mut prev = 80;
    for l in levels {
        let t = l["triangles"].as_u64().unwrap() as usize;
        assert!(t < prev, "{j}");
        prev = t;
        assert_eq!(
            mesh_at(&out.join(l["file"].as_str().unwrap())).faces.len(),
            t
        );
    }
    assert!(!out.join(format!("ico_lod{}.ply", n + 1)).exists());
    let g = glb_json(&out.join("ico_lods.glb"));
    let base = &g["nodes"][g["scenes"][0]["nodes"][0].as_u64().unwrap() as usize];
    assert_eq!(
        base["extensions"]["MSFT_lod"]["ids"]
            .as_array()
            .unwrap()
            .len(),
        n
    );
    // Ratios that do not fall are refused before any work: exit 2.
    for r in ["0.2,0.5", "0.5,0.5"] {
        let o = lodkit(&[
            "lods",
            input.to_str().unwrap(),
            "--out",
            dir.path().join("no").to_str().unwrap(),
            "--ratios",
            r,
        ]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{r}: {e}");
        assert!(
            e.contains("--ratios") && e.trim_end().lines().count() == 1,
            "{e}"
        );
        assert!(!dir.path().join("no").exists());
    }
}
