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
fn lods_levels_carry_textures_scaled_to_their_size() {
    // The mug scan with a 512² texture (the shipped one is 64², already
    // the smallest a level keeps). UVs span the image, so any pattern does.
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(data("mug_scan.ply"), dir.path().join("mug_scan.ply")).unwrap();
    // Noise (a texture worth its texels: nothing for PNG to predict).
    let rgba = (0..512u32 * 512)
        .flat_map(|i| {
            let h = i.wrapping_mul(2_654_435_761).rotate_left(13) ^ i;
            [h as u8, (h >> 8) as u8, (h >> 16) as u8, 255]
        })
        .collect();
    let big = lodkit_mesh::image::RgbaImage {
        width: 512,
        height: 512,
        rgba,
        has_alpha: false,
    };
    let png = lodkit_mesh::image::encode_png(&big).unwrap();
    std::fs::write(dir.path().join("mug_scan.png"), &png).unwrap();
    let out = dir.path().join("lods");
    let o = lodkit(&[
        "lods",
        s(&dir.path().join("mug_scan.ply")),
        "--out",
        s(&out),
        "--ratios",
        "0.5,0.1",
        "--samples",
        "2000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let input = lodkit_mesh::io::load_scene(&dir.path().join("mug_scan.ply")).unwrap();
    let mut sides = vec![512];
    for f in ["mug_scan_lod1.glb", "mug_scan_lod2.glb"] {
        let sc = lodkit_mesh::io::load_scene(&out.join(f)).unwrap();
        assert_eq!(sc.images.len(), 1, "{f}");
        let im = lodkit_mesh::image::decode_rgba(&sc.images[0].bytes).unwrap();
        let ratio = sc.face_count() as f64 / input.face_count() as f64;
        let want = (512.0 * ratio.sqrt()).round() as u32;
        assert_eq!((im.width, im.height), (want, want), "{f}: {ratio}");
        let bytes = sc.images[0].bytes.len();
        assert!(
            bytes < png.len(),
            "{f}: {bytes} bytes, source {}",
            png.len()
        );
        sides.push(im.width);
    }
    assert!(sides.windows(2).all(|w| w[1] < w[0]), "{sides:?}");
    // The chain GLB: one image per level, each level's faces on its own.
    let chain = lodkit_mesh::io::load_scene(&out.join("mug_scan_lods.glb")).unwrap();
    let mut chain_sides: Vec<u32> = chain
        .images
        .iter()
        .map(|i| lodkit_mesh::image::decode_rgba(&i.bytes).unwrap().width)
        .collect();
    chain_sides.sort_unstable_by(|a, b| b.cmp(a));
    assert_eq!(chain_sides, sides);
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
    // Its tileset keeps the materials and textures too.
    let root = lodkit_mesh::io::load_scene(&out.join("tiles/tiles/0-0-0-0.glb")).unwrap();
    assert!(root.materials.len() >= 2, "{:?}", root.materials);
    assert!(!root.images.is_empty());
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

/// Every scene folder of the malformed corpus (`tests/malformed/scenes/`,
/// made by `scripts/make_malformed_corpus.py`): `convert` to GLB and to
/// OBJ and `render` each exit 1 with one line naming the input and saying
/// what `expect.txt` says, and write nothing.
#[test]
fn every_malformed_scene_fails_with_its_one_line() {
    let root = common::repo().join("tests/malformed/scenes");
    let mut cases: Vec<PathBuf> = std::fs::read_dir(&root)
        .expect("tests/malformed/scenes exists")
        .map(|e| e.unwrap().path())
        .collect();
    cases.sort();
    assert!(cases.len() >= 3, "only {} cases", cases.len());
    let mut failures = Vec::new();
    for case in &cases {
        let expect = std::fs::read_to_string(case.join("expect.txt")).unwrap();
        let mut lines = expect.lines();
        let input = case.join(lines.next().unwrap());
        let says = lines
            .find_map(|l| l.strip_prefix("says: "))
            .unwrap()
            .trim()
            .to_string();
        let name = input.file_name().unwrap().to_string_lossy().into_owned();
        let out = tempfile::tempdir().unwrap();
        let o = |f: &str| out.path().join(f).display().to_string();
        for args in [
            vec!["convert".to_string(), s(&input).into(), o("c.glb")],
            vec!["convert".to_string(), s(&input).into(), o("c.obj")],
            vec![
                "render".to_string(),
                s(&input).into(),
                "-o".into(),
                o("r.png"),
                "--size".into(),
                "64x64".into(),
            ],
        ] {
            let a: Vec<&str> = args.iter().map(String::as_str).collect();
            let r = lodkit(&a);
            let err = stderr(&r);
            let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
            let shown = format!("{} lodkit {}", case.display(), args[0]);
            if r.status.code() != Some(1) || lines.len() != 1 {
                failures.push(format!("{shown}: exit {:?}: {err}", r.status.code()));
            } else if !lines[0].contains(&name) || !lines[0].contains(&says) {
                failures.push(format!(
                    "{shown}: does not name {name} and say '{says}': {err}"
                ));
            }
        }
        let written: Vec<_> = std::fs::read_dir(out.path()).unwrap().collect();
        if !written.is_empty() {
            failures.push(format!("{}: wrote {written:?}", case.display()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A PNG whose header says `w × h` pixels, with next to no data.
fn png_claiming(w: u32, h: u32) -> Vec<u8> {
    let chunk = |kind: &[u8], data: &[u8]| {
        let mut c = (data.len() as u32).to_be_bytes().to_vec();
        let mut body = kind.to_vec();
        body.extend_from_slice(data);
        c.extend_from_slice(&body);
        c.extend_from_slice(&crc32(&body).to_be_bytes());
        c
    };
    let mut ihdr = w.to_be_bytes().to_vec();
    ihdr.extend_from_slice(&h.to_be_bytes());
    ihdr.extend_from_slice(&[8, 6, 0, 0, 0]);
    let mut out = b"\x89PNG\r\n\x1a\n".to_vec();
    out.extend(chunk(b"IHDR", &ihdr));
    // A zlib stream of a few zero bytes: the rows run out at once.
    out.extend(chunk(
        b"IDAT",
        &[0x78, 0x9c, 0x63, 0x00, 0x00, 0x00, 0x01, 0x00, 0x01],
    ));
    out.extend(chunk(b"IEND", &[]));
    out
}

fn crc32(bytes: &[u8]) -> u32 {
    let mut c = 0xFFFF_FFFFu32;
    for &b in bytes {
        c ^= u32::from(b);
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

#[test]
fn a_texture_whose_header_claims_gigapixels_is_refused_before_decoding() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("big.png"), png_claiming(16384, 16384)).unwrap();
    std::fs::write(dir.path().join("m.mtl"), "newmtl a\nmap_Kd big.png\n").unwrap();
    std::fs::write(
        dir.path().join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    let png = dir.path().join("r.png");
    let o = lodkit(&[
        "render",
        s(&dir.path().join("m.obj")),
        "-o",
        s(&png),
        "--size",
        "64x64",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("m.obj") && err.contains("big.png") && err.contains("16384x16384"),
        "{err}"
    );
    assert!(!png.exists());
    // build draws the textures in its report: refused before its folder
    // is made.
    let out = dir.path().join("b");
    let o = lodkit(&[
        "build",
        s(&dir.path().join("m.obj")),
        "--out",
        s(&out),
        "--no-measure",
    ]);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(err.contains("m.obj") && err.contains("big.png"), "{err}");
    assert!(!out.exists());
}

#[cfg(unix)]
#[test]
fn a_texture_symlinked_out_of_the_folder_is_neither_embedded_nor_copied() {
    use std::os::unix::fs::symlink;
    let root = tempfile::tempdir().unwrap();
    let secret = root.path().join("secret");
    std::fs::create_dir(&secret).unwrap();
    let png = std::fs::read(data("checker.png")).unwrap();
    std::fs::write(secret.join("s.png"), &png).unwrap();
    let dir = root.path().join("model");
    std::fs::create_dir(&dir).unwrap();
    symlink(secret.join("s.png"), dir.join("tex.png")).unwrap();
    symlink(&secret, dir.join("sub")).unwrap();
    std::fs::write(
        dir.join("m.mtl"),
        "newmtl a\nmap_Kd tex.png\nnewmtl b\nmap_Kd sub/s.png\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
         usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 2/2 4/1 3/3\n",
    )
    .unwrap();
    let out = root.path().join("out");
    std::fs::create_dir(&out).unwrap();
    for target in ["c.glb", "c.obj"] {
        let o = lodkit(&["convert", s(&dir.join("m.obj")), s(&out.join(target))]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).contains("symlink"), "{}", stderr(&o));
    }
    let glb = std::fs::read(out.join("c.glb")).unwrap();
    assert!(!glb.windows(png.len()).any(|w| w == png.as_slice()));
    let mut names: Vec<String> = std::fs::read_dir(&out)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    names.sort();
    assert_eq!(names, ["c.glb", "c.mtl", "c.obj"]);
}
