//! Paths named inside files, and what a file may make a reader do: every
//! path a file names resolves inside that file's folder, symlinks
//! included; one file named several ways, or one byte range used many
//! times, is read and kept once; the work of a read is bounded by the
//! bytes it was given; material factors are finite; the files lodkit
//! writes beside an OBJ never take each other's names.

use std::path::Path;

use lodkit_mesh::TriMesh;
use lodkit_mesh::io::{WriteOptions, load, load_scene, save_scene};
use lodkit_mesh::scene::{Image, Material, Scene, Texture, TextureRef};
use serde_json::json;

fn corpus(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/malformed")
        .join(name)
}

fn checker() -> Vec<u8> {
    std::fs::read(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/textured/checker.png"))
        .unwrap()
}

const TRI_OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n";

/// `m.obj` in `dir` with one material per texture name, each face its own.
fn obj_with_textures(dir: &Path, names: &[&str]) {
    let mut mtl = String::new();
    let mut obj = format!("mtllib m.mtl\n{TRI_OBJ}");
    for (i, n) in names.iter().enumerate() {
        mtl += &format!("newmtl t{i}\nKd 1 1 1\nmap_Kd {n}\n");
        obj += &format!("usemtl t{i}\nf 1/1 2/2 3/3\n");
    }
    std::fs::write(dir.join("m.mtl"), mtl).unwrap();
    std::fs::write(dir.join("m.obj"), obj).unwrap();
}

/// A GLB of `json` (padded) and `bin`.
fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut js = serde_json::to_vec(json).unwrap();
    while !js.len().is_multiple_of(4) {
        js.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + js.len() + 8 + b.len();
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(js.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&js);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

#[cfg(unix)]
#[test]
fn a_texture_symlinked_out_of_the_folder_is_refused_file_or_folder() {
    use std::os::unix::fs::symlink;
    let root = tempfile::tempdir().unwrap();
    let secret = root.path().join("secret");
    std::fs::create_dir(&secret).unwrap();
    std::fs::write(secret.join("s.png"), checker()).unwrap();
    std::fs::write(
        secret.join("s.mtl"),
        "newmtl t0\nKd 1 1 1\nmap_Kd tex.png\n",
    )
    .unwrap();
    let dir = root.path().join("model");
    std::fs::create_dir(&dir).unwrap();
    symlink(secret.join("s.png"), dir.join("tex.png")).unwrap();
    symlink(&secret, dir.join("sub")).unwrap();
    // A symlink that stays inside the folder is followed.
    std::fs::write(dir.join("own.png"), checker()).unwrap();
    symlink(dir.join("own.png"), dir.join("alias.png")).unwrap();

    obj_with_textures(&dir, &["tex.png", "sub/s.png", "alias.png"]);
    let s = load_scene(&dir.join("m.obj")).unwrap();
    assert_eq!(
        s.images.len(),
        1,
        "only the texture inside: {:?}",
        s.warnings
    );
    assert!(s.materials[0].base_color_texture.is_none());
    assert!(s.materials[1].base_color_texture.is_none());
    assert!(s.materials[2].base_color_texture.is_some());
    let said = s.warnings.join("\n");
    assert_eq!(said.matches("symlink").count(), 2, "{said}");

    // mtllib through a symlink out of the folder: no material is read.
    symlink(secret.join("s.mtl"), dir.join("lib.mtl")).unwrap();
    std::fs::write(
        dir.join("l.obj"),
        format!("mtllib lib.mtl\n{TRI_OBJ}usemtl t0\nf 1/1 2/2 3/3\n"),
    )
    .unwrap();
    let s = load_scene(&dir.join("l.obj")).unwrap();
    assert!(s.materials.is_empty() && s.images.is_empty());
    assert!(s.warnings.join(" ").contains("symlink"), "{:?}", s.warnings);

    // PLY's TextureFile.
    std::fs::write(
        dir.join("t.ply"),
        "ply\nformat ascii 1.0\ncomment TextureFile tex.png\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n",
    )
    .unwrap();
    let s = load_scene(&dir.join("t.ply")).unwrap();
    assert!(s.images.is_empty(), "{:?}", s.warnings);

    // A glTF image URI and a glTF buffer URI.
    let tri: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    std::fs::write(secret.join("s.bin"), &tri).unwrap();
    symlink(secret.join("s.bin"), dir.join("b.bin")).unwrap();
    let doc = |buffer_uri: &str, image_uri: &str| {
        json!({
            "asset": {"version": "2.0"},
            "buffers": [{"byteLength": 36, "uri": buffer_uri}],
            "bufferViews": [{"buffer": 0, "byteLength": 36}],
            "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                           "min": [0, 0, 0], "max": [1, 1, 0]}],
            "images": [{"uri": image_uri}],
            "textures": [{"source": 0}],
            "materials": [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": 0}]}],
        })
        .to_string()
    };
    std::fs::write(dir.join("own.bin"), &tri).unwrap();
    std::fs::write(dir.join("i.gltf"), doc("own.bin", "tex.png")).unwrap();
    let e = load_scene(&dir.join("i.gltf")).unwrap_err().to_string();
    assert!(
        e.contains("i.gltf") && e.contains("image 0") && e.contains("symlink"),
        "{e}"
    );
    std::fs::write(dir.join("b.gltf"), doc("b.bin", "own.png")).unwrap();
    for e in [
        load_scene(&dir.join("b.gltf")).unwrap_err().to_string(),
        load(&dir.join("b.gltf")).unwrap_err().to_string(),
    ] {
        assert!(
            e.contains("b.gltf") && e.contains("buffer 0") && e.contains("symlink"),
            "{e}"
        );
    }
    std::fs::write(dir.join("ok.gltf"), doc("own.bin", "alias.png")).unwrap();
    assert_eq!(load_scene(&dir.join("ok.gltf")).unwrap().images.len(), 1);
}

#[test]
fn one_texture_named_many_ways_is_read_once() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::create_dir(dir.path().join("t")).unwrap();
    std::fs::write(dir.path().join("big.png"), checker()).unwrap();
    obj_with_textures(
        dir.path(),
        &[
            "big.png",
            "./big.png",
            "././big.png",
            "t/../big.png",
            "big.png",
        ],
    );
    let s = load_scene(&dir.path().join("m.obj")).unwrap();
    // `t/../big.png` is refused (no `..`); the other four are one image.
    assert_eq!(s.images.len(), 1);
    assert_eq!(s.textures.len(), 1);
    let with: Vec<bool> = s
        .materials
        .iter()
        .map(|m| m.base_color_texture.is_some())
        .collect();
    assert_eq!(with, [true, true, true, false, true]);
    let glb = dir.path().join("out.glb");
    save_scene(&glb, &s, WriteOptions::default()).unwrap();
    let back = load_scene(&glb).unwrap();
    assert_eq!(back.images.len(), 1);
    assert_eq!(back.images[0].bytes, checker());
}

/// A GLB whose `n` images all use one buffer view.
fn images_on_one_view(n: usize) -> Vec<u8> {
    let png = checker();
    let mut bin: Vec<u8> = [0f32, 0., 0., 1., 0., 0., 0., 1., 0.]
        .iter()
        .flat_map(|f| f.to_le_bytes())
        .collect();
    bin.extend_from_slice(&png);
    let images: Vec<_> = (0..n)
        .map(|_| json!({"bufferView": 1, "mimeType": "image/png"}))
        .collect();
    let textures: Vec<_> = (0..n).map(|i| json!({"source": i})).collect();
    let materials: Vec<_> = (0..n)
        .map(|i| json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": i}}}))
        .collect();
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": png.len()}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "images": images,
        "textures": textures,
        "materials": materials,
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "material": n - 1}]}],
    });
    glb(&doc, &bin)
}

#[test]
fn images_on_one_buffer_view_are_kept_once() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("many.glb");
    std::fs::write(&p, images_on_one_view(2000)).unwrap();
    let s = load_scene(&p).unwrap();
    assert_eq!(s.images.len(), 1);
    assert_eq!(s.textures.len(), 2000);
    assert!(s.textures.iter().all(|t| t.image == 0));
}

/// A GLB of `accessors` POSITION accessors (each its own mesh) over one
/// buffer view of `vertices` vertices.
fn aliased_positions(accessors: usize, vertices: usize) -> Vec<u8> {
    let bin: Vec<u8> = (0..vertices * 3)
        .flat_map(|i| ((i % 7) as f32).to_le_bytes())
        .collect();
    let acc: Vec<_> = (0..accessors)
        .map(|_| {
            json!({"bufferView": 0, "componentType": 5126, "count": vertices, "type": "VEC3",
                   "min": [0, 0, 0], "max": [6, 6, 6]})
        })
        .collect();
    let meshes: Vec<_> = (0..accessors)
        .map(|i| json!({"primitives": [{"attributes": {"POSITION": i}}]}))
        .collect();
    let nodes: Vec<_> = (0..accessors).map(|i| json!({"mesh": i})).collect();
    let doc = json!({
        "asset": {"version": "2.0"},
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len()}],
        "accessors": acc,
        "meshes": meshes,
        "nodes": nodes,
        "scenes": [{"nodes": (0..accessors).collect::<Vec<_>>()}],
        "scene": 0,
    });
    glb(&doc, &bin)
}

#[test]
fn accessors_aliasing_one_view_are_bounded_by_the_bytes_of_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("alias.glb");
    // 1,100 accessors over one view of 3,840 vertices: 4.2M vertices from
    // a 160 kB file.
    std::fs::write(&p, aliased_positions(1100, 3840)).unwrap();
    for e in [
        load(&p).unwrap_err().to_string(),
        load_scene(&p).unwrap_err().to_string(),
    ] {
        assert!(
            e.contains("alias.glb") && e.contains("over the limit"),
            "{e}"
        );
    }
    // Few accessors over one view still read.
    std::fs::write(&p, aliased_positions(3, 3840)).unwrap();
    assert_eq!(load_scene(&p).unwrap().meshes.len(), 3);
}

#[test]
fn quantised_accessors_aliasing_one_view_are_bounded() {
    let vertices = 4096usize;
    let bin: Vec<u8> = (0..vertices * 4)
        .flat_map(|i| ((i % 5) as u16).to_le_bytes())
        .collect();
    let n = 1300;
    let acc: Vec<_> = (0..n)
        .map(|_| {
            json!({"bufferView": 0, "componentType": 5123, "count": vertices, "type": "VEC3",
                   "min": [0, 0, 0], "max": [4, 4, 4]})
        })
        .collect();
    let mut acc = acc;
    // Each at its own offset: no two are the same accessor.
    for (i, a) in acc.iter_mut().enumerate() {
        a["byteOffset"] = json!((i % 2) * 8);
        a["count"] = json!(vertices - 1 - i / 2);
    }
    let meshes: Vec<_> = (0..n)
        .map(|i| json!({"primitives": [{"attributes": {"POSITION": i}}]}))
        .collect();
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [{"buffer": 0, "byteLength": bin.len(), "byteStride": 8}],
        "accessors": acc,
        "meshes": meshes,
    });
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("q.glb");
    std::fs::write(&p, glb(&doc, &bin)).unwrap();
    let e = load(&p).unwrap_err().to_string();
    assert!(e.contains("q.glb") && e.contains("exceed"), "{e}");
}

#[test]
fn an_image_named_like_an_output_never_overwrites_it() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = Scene::from_mesh(TriMesh {
        positions: vec![glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::Y],
        uvs: Some(vec![glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y]),
        faces: vec![[0, 1, 2]],
        ..Default::default()
    });
    for (i, name) in ["out.mtl", "out.obj"].iter().enumerate() {
        s.images.push(Image {
            name: Some(name.to_string()),
            file_name: Some(name.to_string()),
            mime_type: "image/png".into(),
            bytes: checker(),
        });
        s.textures.push(Texture {
            image: i,
            ..Default::default()
        });
        s.materials.push(Material {
            name: Some(format!("m{i}")),
            base_color_texture: Some(TextureRef::new(i)),
            ..Default::default()
        });
    }
    s.meshes[0].face_materials = vec![0];
    let obj = dir.path().join("out.obj");
    save_scene(&obj, &s, WriteOptions::default()).unwrap();
    let mtl = std::fs::read_to_string(dir.path().join("out.mtl")).unwrap();
    assert!(mtl.contains("newmtl"), "{mtl}");
    assert_eq!(
        std::fs::read(dir.path().join("out.mtl.png")).unwrap(),
        checker()
    );
    let back = load_scene(&obj).unwrap();
    assert_eq!(back.images.len(), 1);
    assert_eq!(back.images[0].bytes, checker());
}

#[test]
fn non_finite_mtl_factors_are_refused_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    for (stmt, key) in [
        ("Kd inf -inf inf", "Kd"),
        ("Kd 1e39 0 0", "Kd"),
        ("Ke 0 nan 0", "Ke"),
        ("Ns 1e300", "Ns"),
        ("d inf", "d"),
    ] {
        std::fs::write(dir.path().join("m.mtl"), format!("newmtl a\n{stmt}\n")).unwrap();
        std::fs::write(
            dir.path().join("m.obj"),
            format!("mtllib m.mtl\n{TRI_OBJ}usemtl a\nf 1 2 3\n"),
        )
        .unwrap();
        let e = load_scene(&dir.path().join("m.obj"))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("m.obj") && e.contains(key) && e.contains("not a finite number"),
            "{stmt}: {e}"
        );
    }
    // An out-of-range colour is clamped, and the GLB written reads back.
    std::fs::write(dir.path().join("m.mtl"), "newmtl a\nKd 2 0.5 -1\n").unwrap();
    let s = load_scene(&dir.path().join("m.obj")).unwrap();
    assert_eq!(s.materials[0].base_color, [1.0, 0.5, 0.0, 1.0]);
    let glb = dir.path().join("m.glb");
    save_scene(&glb, &s, WriteOptions::default()).unwrap();
    assert_eq!(load_scene(&glb).unwrap().materials[0].base_color[1], 0.5);
}

/// The corpus files of these classes, each with the words its one line says.
#[test]
fn the_new_corpus_classes_say_what_is_wrong() {
    for (file, says) in [
        (
            "gltf_image_without_uri_or_view.gltf",
            "image 0 has neither a uri nor a bufferView",
        ),
        (
            "glb_image_view_without_mime_type.glb",
            "image 0 is stored in a bufferView but has no mimeType",
        ),
        (
            "gltf_material_factor_1e39.gltf",
            "material 0: baseColorFactor",
        ),
        (
            "gltf_material_factor_1e300.gltf",
            "material 0: metallicFactor",
        ),
        (
            "gltf_material_emissive_negative.gltf",
            "material 0: emissiveFactor",
        ),
        (
            "gltf_texture_transform_scale_1e999.gltf",
            "number out of range",
        ),
        (
            "glb_second_buffer_without_uri.glb",
            "buffer 1 has no uri: only buffer 0 may be the GLB BIN chunk",
        ),
        (
            "gltf_quantized_negative_byte_offset.gltf",
            "accessor 0: byteOffset -4 is not a whole number >= 0",
        ),
        (
            "gltf_quantized_fractional_count.gltf",
            "accessor 0: count 2.5 is not a whole number >= 0",
        ),
    ] {
        let p = corpus(file);
        let e = load(&p).unwrap_err().to_string();
        assert!(e.contains(file) && e.contains(says), "{file}: {e}");
        assert!(!e.contains('\n'), "{e}");
        if let Err(e) = load_scene(&p) {
            let e = e.to_string();
            assert!(e.contains(file) && e.contains(says), "{file}: {e}");
        } else {
            panic!("{file}: read as a scene");
        }
    }
}
