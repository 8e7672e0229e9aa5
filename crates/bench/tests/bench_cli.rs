//! The `lodkit-bench` binary.
use std::path::Path;
use std::process::{Command, Output};

fn bench(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodkit-bench"))
        .args(args)
        .output()
        .unwrap()
}

/// `lodkit-bench simplify` runs against meshoptimizer when the build links
/// it (feature `peers`, on in workspace-wide builds through the bench
/// crate's default) and otherwise says how to get it, exit 2.
#[test]
fn bench_simplify_runs_with_the_peers_feature_and_explains_itself_without() {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../..")
        .join("data/reference/stanford_bunny_simplified.ply");
    let args = [
        "simplify",
        mesh.to_str().unwrap(),
        "--runs",
        "1",
        "--samples",
        "20000",
    ];
    let o = bench(&args);
    if lodkit_bench::PEERS {
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
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
        assert_eq!(
            o.status.code(),
            Some(2),
            "{}",
            String::from_utf8_lossy(&o.stderr)
        );
        let e = String::from_utf8_lossy(&o.stderr);
        assert!(
            e.contains("--features peers") && e.lines().count() == 1,
            "{e}"
        );
    }
}

/// Both sides timed, and the counting allocator installed in the binary.
#[test]
#[cfg(feature = "peers")]
fn bench_simplify_prints_both_sides() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    let mesh = lodkit_mesh::shapes::blob(10_000);
    lodkit_mesh::io::save_mesh(&input, &mesh, lodkit_mesh::io::WriteOptions::default()).unwrap();
    let input = input.to_str().unwrap();
    let o = bench(&[
        "simplify",
        input,
        "--runs",
        "1",
        "--samples",
        "20000",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let rows: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let rows = rows.as_array().unwrap();
    assert_eq!(rows.len(), 4);
    for r in rows {
        assert!(r["lodkit_ms"].as_f64().unwrap() > 0.0 && r["meshopt_ms"].as_f64().unwrap() > 0.0);
        // The counting allocator is installed in the binary.
        assert!(r["lodkit_bytes_per_vertex"].as_f64().unwrap() > 0.0);
        assert!(r["lodkit_triangles"].as_u64() <= r["target_triangles"].as_u64());
    }
}

/// An out-of-range value is a usage error naming its range.
#[test]
fn a_huge_blob_is_refused_naming_the_range() {
    let o = bench(&["simplify", "--blob", "1000000000"]);
    let e = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{e}");
    assert!(e.contains("--blob") && e.contains("1000..=10000000"), "{e}");
}

/// `mco` builds a mesh's model and prints its rows as JSON.
#[test]
fn mco_prints_json() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("sphere.ply");
    lodkit_mesh::io::save_mesh(
        &mesh,
        &lodkit_mesh::shapes::icosphere(2),
        lodkit_mesh::io::WriteOptions::default(),
    )
    .unwrap();
    let o = bench(&[
        "mco",
        mesh.to_str().unwrap(),
        "--resolution",
        "12",
        "--budget",
        "0.01",
        "--json",
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(!v.as_array().unwrap().is_empty(), "{v}");
    assert!(v[0]["extract_us"].as_f64().is_some(), "{v}");
}
