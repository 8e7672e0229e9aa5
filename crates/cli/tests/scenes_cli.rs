//! End-to-end: `convert`, `simplify` and `lods` keep a scene's materials,
//! textures and parts when writing .glb / .obj, and `--merge` gives one
//! mesh as before.

use std::path::{Path, PathBuf};

mod common;
use common::{lodkit, stderr};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../mesh/tests/data/textured")
        .join(name)
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

#[test]
fn convert_and_simplify_keep_materials_and_textures() {
    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("parts.glb");
    let o = lodkit(&["convert", s(&data("parts.obj")), s(&glb)]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("3 materials, 2 images"),
        "{}",
        stderr(&o)
    );
    let lod = dir.path().join("out/lod.obj");
    std::fs::create_dir(dir.path().join("out")).unwrap();
    let o = lodkit(&[
        "simplify",
        s(&data("parts.gltf")),
        "-o",
        s(&lod),
        "--ratio",
        "0.5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let back = lodkit_mesh::io::load_scene(&lod).unwrap();
    assert_eq!(back.materials.len(), 2);
    assert_eq!(
        std::fs::read(dir.path().join("out/checker.png")).unwrap(),
        std::fs::read(data("checker.png")).unwrap()
    );
    // --merge: one mesh, no material.
    let one = dir.path().join("one.glb");
    let o = lodkit(&[
        "simplify",
        s(&data("parts.gltf")),
        "-o",
        s(&one),
        "--ratio",
        "0.5",
        "--merge",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let m = lodkit_mesh::io::load_scene(&one).unwrap();
    assert!(m.materials.is_empty() && m.images.is_empty());
}

#[test]
fn lods_of_a_textured_scan_embed_its_texture_in_every_level() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lods");
    let o = lodkit(&[
        "lods",
        s(&data("mug_scan.ply")),
        "--out",
        s(&out),
        "--ratios",
        "0.5,0.1",
        "--samples",
        "2000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let png = std::fs::read(data("mug_scan.png")).unwrap();
    for f in [
        "mug_scan_lod1.glb",
        "mug_scan_lod2.glb",
        "mug_scan_lods.glb",
    ] {
        let sc = lodkit_mesh::io::load_scene(&out.join(f)).unwrap();
        assert_eq!(sc.images.len(), 1, "{f}");
        assert_eq!(sc.images[0].bytes, png, "{f}");
    }
    // The chain: level 0 (the input) alone in the scene, MSFT_lod over
    // the other levels' root nodes, measured error in extras.
    let chain = lodkit_mesh::io::load_scene(&out.join("mug_scan_lods.glb")).unwrap();
    assert_eq!(chain.roots.len(), 1);
    assert_eq!(
        chain.nodes[chain.roots[0]].name.as_deref(),
        Some("mug_scan_LOD0")
    );
    let input = lodkit_mesh::io::load_scene(&data("mug_scan.ply")).unwrap();
    assert_eq!(chain.face_count(), input.face_count());
    let glb = std::fs::read(out.join("mug_scan_lods.glb")).unwrap();
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let j: serde_json::Value = serde_json::from_slice(&glb[20..20 + len]).unwrap();
    let base = &j["nodes"][j["scenes"][0]["nodes"][0].as_u64().unwrap() as usize];
    let ids = base["extensions"]["MSFT_lod"]["ids"].as_array().unwrap();
    assert_eq!(ids.len(), 2);
    let lod1 = &j["nodes"][ids[0].as_u64().unwrap() as usize];
    assert_eq!(lod1["name"], "mug_scan_LOD1");
    assert_eq!(lod1["extras"]["error"]["measured"], true);
    assert!(lod1["extras"]["error"]["max"].as_f64().unwrap() > 0.0);
    assert_eq!(
        base["extras"]["MSFT_screencoverage"]
            .as_array()
            .unwrap()
            .len(),
        3
    );
}

#[test]
fn compress_on_a_scene_needs_a_glb_output() {
    let dir = tempfile::tempdir().unwrap();
    let o = lodkit(&[
        "convert",
        s(&data("parts.gltf")),
        s(&dir.path().join("x.obj")),
        "--compress",
    ]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
}

#[cfg(feature = "compress")]
#[test]
fn compressed_scene_lods_keep_materials_and_images() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lods");
    let o = lodkit(&[
        "lods",
        s(&data("parts.gltf")),
        "--out",
        s(&out),
        "--ratios",
        "0.5",
        "--samples",
        "2000",
        "--compress",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let input = lodkit_mesh::io::load_scene(&data("parts.gltf")).unwrap();
    for f in ["parts_lod1.glb", "parts_lods.glb"] {
        let sc = lodkit_mesh::io::load_scene(&out.join(f)).unwrap();
        assert_eq!(sc.materials, input.materials, "{f}");
        for (x, y) in sc.images.iter().zip(&input.images) {
            assert_eq!(x.bytes, y.bytes, "{f}");
        }
    }
}

#[test]
fn build_keeps_the_materials_of_a_multi_part_textured_input() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = lodkit(&[
        "build",
        s(&data("parts.gltf")),
        "--out",
        s(&out),
        "--levels",
        "2",
        "--samples",
        "2000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let input = lodkit_mesh::io::load_scene(&data("parts.gltf")).unwrap();
    let checker = std::fs::read(data("checker.png")).unwrap();
    // The input GLB and every level of the chain keep the materials, the
    // images byte for byte and the parts.
    for f in [
        "parts.glb",
        "lods/parts_lod1.glb",
        "lods/parts_lod2.glb",
        "lods/parts_lods.glb",
    ] {
        let sc = lodkit_mesh::io::load_scene(&out.join(f)).unwrap();
        assert_eq!(sc.materials.len(), input.materials.len(), "{f}");
        assert_eq!(sc.images.len(), input.images.len(), "{f}");
        assert!(sc.images.iter().any(|i| i.bytes == checker), "{f}");
        assert!(sc.meshes.len() >= input.meshes.len(), "{f}");
    }
    let chain = lodkit_mesh::io::load_scene(&out.join("lods/parts_lods.glb")).unwrap();
    assert_eq!(chain.roots.len(), 1);
    assert_eq!(
        chain.nodes[chain.roots[0]].name.as_deref(),
        Some("parts_LOD0")
    );
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("materials are kept"), "{report}");
    assert!(report.contains("`lods/parts_lod1.glb`"), "{report}");
    assert!(out.join("report.html").is_file() && out.join("parts.pop").is_file());
    // --merge: one mesh, no material anywhere, PLY levels as for any mesh.
    let merged = dir.path().join("merged");
    let o = lodkit(&[
        "build",
        s(&data("parts.gltf")),
        "--out",
        s(&merged),
        "--levels",
        "1",
        "--no-measure",
        "--merge",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let sc = lodkit_mesh::io::load_scene(&merged.join("parts.glb")).unwrap();
    assert!(sc.materials.is_empty() && sc.images.is_empty());
    assert!(merged.join("lods/parts_lod1.ply").is_file());
}
