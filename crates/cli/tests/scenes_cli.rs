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
    let chain = lodkit_mesh::io::load_scene(&out.join("mug_scan_lods.glb")).unwrap();
    assert_eq!(chain.roots.len(), 2);
}
