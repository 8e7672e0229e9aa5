//! Scenes through the readers and writers: materials, textures (byte for
//! byte), samplers, primitives and node transforms survive OBJ + MTL →
//! GLB → OBJ and glTF → GLB; texture files are copied beside an OBJ
//! output without overwriting anything; paths never leave the folder.
//! Inputs: `tests/data/textured` (made by its `make.py`).

use std::path::{Path, PathBuf};

use lodkit_mesh::io::{WriteOptions, gltf, load_scene, save_scene};
use lodkit_mesh::scene::{AlphaMode, NO_MATERIAL, Scene, Transform};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/textured")
        .join(name)
}

fn bytes(name: &str) -> Vec<u8> {
    std::fs::read(data(name)).unwrap()
}

/// Distinct material ids of each mesh (its primitives), in first-use order.
fn primitives(s: &Scene) -> Vec<Vec<u32>> {
    s.meshes
        .iter()
        .map(|m| {
            let mut v: Vec<u32> = Vec::new();
            for &f in &m.face_materials {
                if !v.contains(&f) {
                    v.push(f);
                }
            }
            v
        })
        .collect()
}

#[test]
fn gltf_scene_keeps_meshes_primitives_nodes_materials_and_images() {
    let s = load_scene(&data("parts.gltf")).unwrap();
    assert_eq!(s.meshes.len(), 2);
    assert_eq!(s.meshes[0].name.as_deref(), Some("ball"));
    assert_eq!(primitives(&s), vec![vec![0, 1], vec![1]]);
    let names: Vec<_> = s.nodes.iter().map(|n| n.name.clone().unwrap()).collect();
    assert_eq!(names, ["root", "ball_node", "crate_holder", "crate_node"]);
    assert_eq!(s.roots, [0]);
    assert_eq!(s.nodes[0].children, [1, 2]);
    assert_eq!(s.nodes[2].children, [3]);
    assert!(matches!(
        s.nodes[2].transform,
        Transform::Trs {
            scale: [1.0, 2.0, 1.0],
            ..
        }
    ));
    assert_eq!(s.materials.len(), 2);
    assert_eq!(s.materials[1].alpha_mode, AlphaMode::Mask);
    assert_eq!(s.materials[1].alpha_cutoff, Some(0.3));
    assert!(s.materials[0].double_sided);
    assert_eq!(s.images[0].bytes, bytes("checker.png"));
    assert_eq!(s.images[1].bytes, bytes("stripes.jpg"));
    assert_eq!(s.images[0].mime_type, "image/png");
    assert_eq!(s.images[1].mime_type, "image/jpeg");
    assert_eq!(s.samplers.len(), 2);
    assert_eq!(s.samplers[0].wrap_s, 33071);
    assert_eq!(s.samplers[1].min_filter, Some(9987));
    // The crate sits at root (0,1,0) + holder (2.5,0,0) with scale y 2,
    // + its own (0,0.25,0): world y of its centre is 1 + 2 * 0.25.
    let inst = s.instances();
    assert_eq!(inst.len(), 2);
    let c = inst[1].1.transform_point3(glam::Vec3::ZERO);
    assert!((c - glam::Vec3::new(2.5, 1.5, 0.0)).length() < 1e-6, "{c}");
}

/// Everything but floating-point noise of the V flip is the same.
fn assert_same_scene(a: &Scene, b: &Scene) {
    assert_eq!(a.materials, b.materials);
    assert_eq!(a.textures, b.textures);
    assert_eq!(a.samplers, b.samplers);
    assert_eq!(a.images.len(), b.images.len());
    for (x, y) in a.images.iter().zip(&b.images) {
        assert_eq!(x.bytes, y.bytes);
        assert_eq!(x.mime_type, y.mime_type);
    }
    assert_eq!(a.nodes, b.nodes);
    assert_eq!(a.roots, b.roots);
    assert_eq!(primitives(a), primitives(b));
    // Faces in the same order with the same corners (unused vertices are
    // not written, so vertex arrays may be shorter).
    for (x, y) in a.meshes.iter().zip(&b.meshes) {
        assert_eq!(x.mesh.faces.len(), y.mesh.faces.len());
        assert_eq!(x.face_materials, y.face_materials);
        let (u, v) = (x.mesh.uvs.as_ref().unwrap(), y.mesh.uvs.as_ref().unwrap());
        for (f, g) in x.mesh.faces.iter().zip(&y.mesh.faces) {
            for c in 0..3 {
                let (p, q) = (f[c] as usize, g[c] as usize);
                assert_eq!(x.mesh.positions[p], y.mesh.positions[q]);
                assert!((u[p] - v[q]).abs().max_element() < 1e-6);
            }
        }
    }
}

#[test]
fn glb_round_trip_keeps_everything_and_is_deterministic() {
    let s = load_scene(&data("parts.gltf")).unwrap();
    let glb = gltf::write_scene_glb(&s).unwrap();
    assert_eq!(glb, gltf::write_scene_glb(&s).unwrap());
    let back = gltf::read_scene(&glb, None).unwrap();
    // The writer emits primitives grouped by material: the same order here.
    assert_same_scene(&s, &back);
    // The old one-mesh reader still reads the scene GLB, in world space.
    let merged = gltf::read(&glb, None).unwrap();
    assert_eq!(merged.faces.len(), s.face_count());
}

#[test]
fn obj_mtl_to_glb_to_obj_keeps_materials_and_texture_bytes() {
    let s = load_scene(&data("parts.obj")).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.meshes.len(), 2);
    let names: Vec<_> = s
        .materials
        .iter()
        .map(|m| m.name.clone().unwrap())
        .collect();
    assert_eq!(names, ["checker", "stripes", "plain"]);
    // Shared material: "stripes" on both objects.
    assert_eq!(primitives(&s), vec![vec![0, 1], vec![1, 2]]);
    let st = &s.materials[1];
    assert_eq!(st.base_color, [0.9, 0.8, 0.7, 0.75]);
    assert_eq!(st.alpha_mode, AlphaMode::Blend);
    assert_eq!((st.roughness, st.metallic), (0.4, 0.2));
    assert_eq!(st.emissive, [0.1, 0.0, 0.0]);
    assert!(st.emissive_texture.is_some() && st.base_color_texture.is_some());
    assert_eq!(s.materials[0].mtl.shininess, Some(20.0));
    assert_eq!(s.materials[0].mtl.illum, Some(2));
    // Two files, read once each, whichever slots use them.
    assert_eq!(s.images.len(), 2);
    assert_eq!(s.images[0].bytes, bytes("checker.png"));
    assert_eq!(s.images[1].bytes, bytes("stripes.jpg"));

    let dir = tempfile::tempdir().unwrap();
    let glb = dir.path().join("parts.glb");
    save_scene(&glb, &s, WriteOptions::default()).unwrap();
    let g = load_scene(&glb).unwrap();
    assert_eq!(g.materials, s.materials);
    assert_eq!(primitives(&g), primitives(&s));
    std::fs::create_dir(dir.path().join("out")).unwrap();
    let obj = dir.path().join("out/again.obj");
    save_scene(&obj, &g, WriteOptions::default()).unwrap();
    // The texture files are copied beside the OBJ, unchanged.
    assert_eq!(
        std::fs::read(dir.path().join("out/checker.png")).unwrap(),
        bytes("checker.png")
    );
    assert_eq!(
        std::fs::read(dir.path().join("out/stripes.jpg")).unwrap(),
        bytes("stripes.jpg")
    );
    let o = load_scene(&obj).unwrap();
    assert!(o.warnings.is_empty(), "{:?}", o.warnings);
    assert_eq!(o.materials, s.materials);
    assert_eq!(primitives(&o), primitives(&s));
    for (a, b) in o.images.iter().zip(&s.images) {
        assert_eq!(a.bytes, b.bytes);
    }
    for (a, b) in o.meshes.iter().zip(&s.meshes) {
        assert_eq!(a.mesh.positions, b.mesh.positions);
        assert_eq!(a.face_materials, b.face_materials);
        // UVs where a texture samples them (an untextured primitive is
        // written without TEXCOORD_0, which glTF-Validator would call unused).
        let (ua, ub) = (a.mesh.uvs.as_ref().unwrap(), b.mesh.uvs.as_ref().unwrap());
        for (f, &m) in b.mesh.faces.iter().zip(&b.face_materials) {
            let textured = m != lodkit_mesh::scene::NO_MATERIAL
                && s.materials[m as usize].texture_refs().next().is_some();
            if textured {
                for &v in f {
                    assert_eq!(ua[v as usize], ub[v as usize]);
                }
            }
        }
    }
}

#[test]
fn an_obj_output_never_overwrites_a_file_and_reuses_identical_ones() {
    let s = load_scene(&data("parts.obj")).unwrap();
    let dir = tempfile::tempdir().unwrap();
    // Another image under the texture's name, and the texture itself.
    std::fs::write(dir.path().join("checker.png"), b"someone else's file").unwrap();
    std::fs::write(dir.path().join("stripes.jpg"), bytes("stripes.jpg")).unwrap();
    let obj = dir.path().join("lod.obj");
    save_scene(&obj, &s, WriteOptions::default()).unwrap();
    assert_eq!(
        std::fs::read(dir.path().join("checker.png")).unwrap(),
        b"someone else's file"
    );
    assert_eq!(
        std::fs::read(dir.path().join("checker_1.png")).unwrap(),
        bytes("checker.png")
    );
    let mtl = std::fs::read_to_string(dir.path().join("lod.mtl")).unwrap();
    assert!(mtl.contains("map_Kd checker_1.png"), "{mtl}");
    assert!(mtl.contains("map_Kd stripes.jpg"), "{mtl}");
    let back = load_scene(&obj).unwrap();
    assert_eq!(back.images[0].bytes, bytes("checker.png"));
    // Same scene, same folder: same files, nothing new.
    save_scene(&obj, &s, WriteOptions::default()).unwrap();
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(
        names,
        [
            "checker.png",
            "checker_1.png",
            "lod.mtl",
            "lod.obj",
            "stripes.jpg"
        ]
    );
}

#[test]
fn ply_texture_file_and_textured_obj_scans_read_their_texture() {
    let ply = lodkit_mesh::io::load_mesh(&data("mug_scan.ply")).unwrap();
    let s = lodkit_mesh::io::ply_scene(&data("mug_scan.ply"), ply);
    assert_eq!(s.materials.len(), 1);
    assert_eq!(s.images[0].bytes, bytes("mug_scan.png"));
    assert!(s.meshes[0].face_materials.iter().all(|&m| m == 0));
    let o = load_scene(&data("mug_scan.obj")).unwrap();
    assert_eq!(o.images[0].bytes, bytes("mug_scan.png"));
    assert_eq!(o.meshes[0].mesh.faces.len(), s.meshes[0].mesh.faces.len());
    assert!(o.meshes[0].face_materials.iter().all(|&m| m == 0));
}

#[test]
fn texture_paths_that_leave_the_folder_are_refused_or_skipped() {
    let dir = tempfile::tempdir().unwrap();
    let sub = dir.path().join("sub");
    std::fs::create_dir(&sub).unwrap();
    std::fs::write(dir.path().join("secret.png"), bytes("checker.png")).unwrap();
    // glTF: an image URI escaping the folder (also percent-encoded) is an error.
    let doc = std::fs::read_to_string(data("parts.gltf")).unwrap();
    std::fs::copy(data("parts.bin"), sub.join("parts.bin")).unwrap();
    std::fs::copy(data("stripes.jpg"), sub.join("stripes.jpg")).unwrap();
    for uri in ["../secret.png", "%2E%2E/secret.png", "file:///etc/passwd"] {
        let bad = doc.replace("\"checker.png\"", &format!("\"{uri}\""));
        let p = sub.join("bad.gltf");
        std::fs::write(&p, bad).unwrap();
        let e = load_scene(&p).unwrap_err().to_string();
        assert!(e.contains("bad.gltf") && e.contains("image 0"), "{e}");
        assert!(!e.contains('\n'), "{e}");
    }
    // OBJ: such a texture is skipped with a warning, the geometry read.
    let mtl = "newmtl m\nKd 1 1 1\nmap_Kd ../secret.png\n";
    std::fs::write(sub.join("a.mtl"), mtl).unwrap();
    std::fs::write(sub.join("a.obj"), "mtllib a.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl m\nf 1/1 2/2 3/3\n").unwrap();
    let s = load_scene(&sub.join("a.obj")).unwrap();
    assert_eq!(s.materials.len(), 1);
    assert!(s.materials[0].base_color_texture.is_none());
    assert!(
        s.warnings[0].contains("leaves its folder"),
        "{:?}",
        s.warnings
    );
    // A missing library: a warning, faces without material.
    std::fs::write(
        sub.join("b.obj"),
        "mtllib nowhere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
    )
    .unwrap();
    let s = load_scene(&sub.join("b.obj")).unwrap();
    assert!(s.materials.is_empty());
    assert_eq!(s.meshes[0].face_materials, [NO_MATERIAL]);
    assert!(s.warnings[0].contains("nowhere.mtl"), "{:?}", s.warnings);
}

#[test]
fn a_scene_glb_holds_only_what_it_uses() {
    // A material no face uses, and its texture, are not written.
    let mut s = load_scene(&data("parts.gltf")).unwrap();
    for f in &mut s.meshes[1].face_materials {
        *f = 0;
    }
    for f in &mut s.meshes[0].face_materials {
        *f = 0;
    }
    let back = gltf::read_scene(&gltf::write_scene_glb(&s).unwrap(), None).unwrap();
    assert_eq!(back.materials.len(), 1);
    assert_eq!(back.textures.len(), 1);
    assert_eq!(back.images.len(), 1);
    assert_eq!(back.samplers.len(), 1);
    assert_eq!(back.images[0].bytes, bytes("checker.png"));
}
