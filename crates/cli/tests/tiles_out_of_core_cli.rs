//! `lodkit tiles --memory`: a binary PLY over the budget is tiled out of
//! core (deterministic, nothing staged left), one under it in core, a bad
//! budget refused.

use std::path::Path;

mod common;
use common::{files, stderr, tiles};

/// A binary PLY blob of about 20k triangles: about 8 MB to tile in core,
/// so `--memory 1M` sends it out of core.
fn blob(dir: &Path) -> String {
    let p = dir.join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&p, 20_000, 3).unwrap();
    p.display().to_string()
}

#[test]
fn a_tiny_budget_tiles_out_of_core_with_the_same_bytes_twice() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob(dir.path());
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    let args = ["--memory", "1M", "--leaf-triangles", "2000"];
    let o = tiles(&input, &a, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("out of core:") && err.contains("over --memory 1.0 MiB"),
        "{err}"
    );
    assert!(a.join("tileset.json").is_file());
    let o = tiles(&input, &b, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(files(&a), files(&b));
    let left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("lodkit-"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    // Every tile reads back.
    for (name, bytes) in files(&a) {
        if name.ends_with(".glb") {
            match lodkit_mesh::io::gltf::read_model(&bytes, None) {
                Ok(lodkit_mesh::Model::Mesh(m)) => assert!(!m.faces.is_empty(), "{name}"),
                other => panic!("{name}: {:?}", other.err()),
            }
        }
    }
}

#[test]
fn a_mesh_within_the_budget_is_tiled_in_core() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob(dir.path());
    let o = tiles(&input, &dir.path().join("t"), &["--memory", "1G"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("out of core"), "{}", stderr(&o));
}

#[test]
fn a_bad_budget_is_a_usage_error() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob(dir.path());
    let o = tiles(&input, &dir.path().join("t"), &["--memory", "12"]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(!dir.path().join("t").exists());
}

#[test]
fn ray_without_pylodkit_fails_in_one_line_naming_the_runner() {
    let dir = tempfile::tempdir().unwrap();
    let input = blob(dir.path());
    let out = dir.path().join("t");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_lodkit"))
        .args(["tiles", &input, "--out", out.to_str().unwrap()])
        .args([
            "--memory",
            "1M",
            "--leaf-triangles",
            "2000",
            "--ray",
            "local",
        ])
        .env("LODKIT_PYTHON", "/nonexistent/python3")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    let errors: Vec<&str> = err.lines().filter(|l| l.contains("error")).collect();
    assert_eq!(errors.len(), 1, "{err}");
    assert!(
        errors[0].contains("blob.ply")
            && errors[0].contains("--ray")
            && errors[0].contains("LODKIT_PYTHON")
            && !errors[0].contains("simplify:"),
        "{err}"
    );
    assert!(!out.exists());
}
