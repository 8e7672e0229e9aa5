//! `lodkit tiles CLOUD --memory`: a vertex-only binary PLY over the
//! budget is tiled out of core into the in-core bytes, read back with the
//! `gltf` crate (every point in one tile), the same bytes on a rerun,
//! nothing staged left.

use std::path::Path;

mod common;
use common::{files, stderr, tiles};
use lodkit_mesh::glam::Vec3;

/// A coloured spiral sheet of 30k points as binary PLY: about 1.4 MB to
/// tile in core, so `--memory 1M` sends it out of core.
fn cloud(dir: &Path) -> (String, usize) {
    let n = 30_000;
    let positions: Vec<Vec3> = (0..n)
        .map(|i| {
            let t = i as f32 * 0.001;
            Vec3::new(
                t.cos() * (1.0 + t),
                t.sin() * (1.0 + t),
                (i % 97) as f32 * 0.01,
            )
        })
        .collect();
    let colors = (0..n).map(|i| [(i % 256) as u8, 9, 200, 255]).collect();
    let c = lodkit_mesh::PointCloud {
        positions,
        normals: None,
        colors: Some(colors),
    };
    let p = dir.join("cloud.ply");
    lodkit_mesh::io::save(&p, &lodkit_mesh::Model::Points(c), Default::default()).unwrap();
    (p.display().to_string(), n)
}

/// The points of every tile `json` (a tileset file in `base`) names,
/// external tilesets followed; each GLB parsed by the `gltf` crate.
fn count_points(tile: &serde_json::Value, base: &Path) -> usize {
    let mut n = 0;
    if let Some(uri) = tile["content"]["uri"].as_str() {
        let path = base.join(uri);
        let bytes = std::fs::read(&path).unwrap();
        if uri.ends_with(".json") {
            let doc: serde_json::Value = serde_json::from_slice(&bytes).unwrap();
            return count_points(&doc["root"], path.parent().unwrap());
        }
        // Parsed and validated, except that the crate does not know the
        // one extension the tiles require (KHR_mesh_quantization: the
        // positions on the tileset's grid).
        let glb = gltf::Gltf::from_slice_without_validation(&bytes)
            .unwrap_or_else(|e| panic!("{uri}: {e}"));
        let required: Vec<&str> = glb.extensions_required().collect();
        assert_eq!(required, ["KHR_mesh_quantization"], "{uri}");
        for mesh in glb.meshes() {
            for prim in mesh.primitives() {
                assert_eq!(prim.mode(), gltf::mesh::Mode::Points, "{uri}");
                let pos = prim.get(&gltf::Semantic::Positions).expect("positions");
                assert!(prim.get(&gltf::Semantic::Colors(0)).is_some(), "{uri}");
                n += pos.count();
            }
        }
    }
    for c in tile["children"].as_array().into_iter().flatten() {
        n += count_points(c, base);
    }
    n
}

#[test]
fn a_cloud_over_the_budget_gives_the_in_core_bytes_out_of_core() {
    let dir = tempfile::tempdir().unwrap();
    let (input, n) = cloud(dir.path());
    let (a, b, c) = (
        dir.path().join("a"),
        dir.path().join("b"),
        dir.path().join("c"),
    );
    let args = ["--memory", "1M", "--leaf-points", "1000", "--no-compress"];
    let o = tiles(&input, &a, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("out of core:") && err.contains("over --memory 1.0 MiB"),
        "{err}"
    );
    let o = tiles(&input, &b, &args);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(files(&a) == files(&b), "a rerun gives the same bytes");
    let o = tiles(&input, &c, &["--leaf-points", "1000", "--no-compress"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(!stderr(&o).contains("out of core"), "{}", stderr(&o));
    assert!(files(&a) == files(&c), "the in-core bytes");
    let left: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.contains("lodkit-"))
        .collect();
    assert!(left.is_empty(), "{left:?}");
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(a.join("tileset.json")).unwrap()).unwrap();
    assert_eq!(doc["root"]["refine"], "ADD");
    assert_eq!(count_points(&doc["root"], &a), n, "every point in one tile");
}

#[test]
fn a_truncated_cloud_out_of_core_is_one_line_and_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let (input, _) = cloud(dir.path());
    let bytes = std::fs::read(&input).unwrap();
    std::fs::write(&input, &bytes[..bytes.len() - 3]).unwrap();
    let out = dir.path().join("t");
    let o = tiles(&input, &out, &["--memory", "1M"]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    let last = err.trim_end().lines().last().unwrap_or("");
    assert!(last.contains("cloud.ply"), "{err}");
    assert!(!out.exists());
    let left = std::fs::read_dir(dir.path()).unwrap().count();
    assert_eq!(left, 1, "nothing but the input");
}
