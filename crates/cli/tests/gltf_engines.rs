//! glTF the way engines read it: the MSFT_lod chain with level 0,
//! `--normals`, `--compress` (EXT_meshopt_compression + KHR_mesh_quantization),
//! point clouds as POINTS, and one-line refusals of what cannot be read.
//! Real loaders (glTF-Validator, Babylon.js, three.js) check the same files
//! in `scripts/check-gltf.sh`.

mod common;

use std::path::Path;

use common::{bunny, lodkit, stderr};

/// The JSON chunk of a GLB.
fn glb_json(path: &Path) -> serde_json::Value {
    let b = std::fs::read(path).unwrap();
    assert_eq!(&b[..4], b"glTF");
    let len = u32::from_le_bytes(b[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&b[20..20 + len]).unwrap()
}

/// Whether `info --json` lists the attribute.
fn has(v: &serde_json::Value, attr: &str) -> bool {
    v["attributes"]
        .as_array()
        .is_some_and(|a| a.contains(&attr.into()))
}

fn info(path: &Path) -> serde_json::Value {
    let o = lodkit(&["info", "--json", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).unwrap()
}

/// A unit cube without normals: 8 shared corners, 12 triangles.
fn cube(dir: &Path) -> String {
    let mut s = String::new();
    for i in 0..8 {
        s += &format!("v {} {} {}\n", i & 1, (i >> 1) & 1, (i >> 2) & 1);
    }
    for f in [
        [1, 3, 4],
        [1, 4, 2],
        [5, 6, 8],
        [5, 8, 7],
        [1, 2, 6],
        [1, 6, 5],
        [3, 7, 8],
        [3, 8, 4],
        [1, 5, 7],
        [1, 7, 3],
        [2, 4, 8],
        [2, 8, 6],
    ] {
        s += &format!("f {} {} {}\n", f[0], f[1], f[2]);
    }
    let p = dir.join("cube.obj");
    std::fs::write(&p, s).unwrap();
    p.display().to_string()
}

#[test]
fn the_lod_chain_glb_is_an_msft_lod_chain_with_level_0_first() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("lods");
    let o = lodkit(&[
        "-q",
        "lods",
        &bunny(),
        "--out",
        out.to_str().unwrap(),
        "--levels",
        "3",
        "--samples",
        "2000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let glb = out.join("stanford_bunny_lods.glb");
    let j = glb_json(&glb);
    assert!(
        j["extensionsUsed"]
            .as_array()
            .unwrap()
            .contains(&"MSFT_lod".into())
    );
    assert!(
        j.get("extensionsRequired").is_none(),
        "MSFT_lod is optional"
    );
    // One root: level 0, the input, with the three levels behind MSFT_lod.
    let roots = j["scenes"][0]["nodes"].as_array().unwrap();
    assert_eq!(roots.len(), 1);
    let base = &j["nodes"][roots[0].as_u64().unwrap() as usize];
    assert_eq!(base["name"], "stanford_bunny_LOD0");
    assert_eq!(base["extras"]["triangles"], 69451);
    assert_eq!(base["extras"]["lod"], 0);
    assert_eq!(base["extras"]["error"]["max"], 0.0);
    let ids = base["extensions"]["MSFT_lod"]["ids"].as_array().unwrap();
    assert_eq!(ids.len(), 3);
    let cover: Vec<f64> = base["extras"]["MSFT_screencoverage"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    assert_eq!(cover.len(), 4);
    // Strictly decreasing: a switch by coverage reaches every level.
    assert!(cover.windows(2).all(|w| w[0] > w[1]), "{cover:?}");
    assert_eq!(*cover.last().unwrap(), 0.0);
    let mut last_tris = 69451;
    for (k, id) in ids.iter().enumerate() {
        let n = &j["nodes"][id.as_u64().unwrap() as usize];
        assert_eq!(n["name"], format!("stanford_bunny_LOD{}", k + 1));
        let e = &n["extras"]["error"];
        assert_eq!(e["measured"], true);
        let (max, pct) = (
            e["max"].as_f64().unwrap(),
            e["max_percent_of_diagonal"].as_f64().unwrap(),
        );
        assert!(max > 0.0 && pct > 0.0 && pct < 10.0, "{e}");
        let tris = n["extras"]["triangles"].as_u64().unwrap();
        assert!(tris < last_tris);
        last_tris = tris;
    }
    // The bunny has no normals, so the GLB gets auto normals.
    assert!(
        j["meshes"][0]["primitives"][0]["attributes"]
            .get("NORMAL")
            .is_some()
    );
    // A loader without MSFT_lod (lodkit's own) sees level 0 alone.
    assert_eq!(info(&glb)["faces"], 69451);
    // Byte-identical on a rerun.
    let out2 = dir.path().join("lods2");
    let o = lodkit(&[
        "-q",
        "lods",
        &bunny(),
        "--out",
        out2.to_str().unwrap(),
        "--levels",
        "3",
        "--samples",
        "2000",
    ]);
    assert!(o.status.success());
    assert_eq!(
        std::fs::read(&glb).unwrap(),
        std::fs::read(out2.join("stanford_bunny_lods.glb")).unwrap()
    );
}

#[test]
fn normals_auto_splits_creases_keep_and_none_do_what_they_say() {
    let dir = tempfile::tempdir().unwrap();
    let cube = cube(dir.path());
    let glb = |name: &str, extra: &[&str]| {
        let p = dir.path().join(name);
        let mut args = vec!["-q", "convert", &cube, p.to_str().unwrap()];
        args.extend_from_slice(extra);
        let o = lodkit(&args);
        assert!(o.status.success(), "{extra:?}: {}", stderr(&o));
        p
    };
    // Default for a mesh without normals: auto at 60°, so the cube's
    // 90° edges stay hard: 3 vertices per corner.
    let v = info(&glb("auto.glb", &[]));
    assert_eq!(
        (v["vertices"].as_u64(), v["faces"].as_u64()),
        (Some(24), Some(12))
    );
    assert!(has(&v, "normals"), "{v}");
    // No crease at 180°: smooth, no split.
    assert_eq!(
        info(&glb("smooth.glb", &["--normals", "auto=180"]))["vertices"],
        8
    );
    let v = info(&glb("none.glb", &["--normals", "none"]));
    assert_eq!(v["vertices"], 8);
    assert!(!has(&v, "normals"), "{v}");
    // PLY keeps the mesh as it is unless asked.
    let ply = dir.path().join("c.ply");
    assert!(
        lodkit(&["-q", "convert", &cube, ply.to_str().unwrap()])
            .status
            .success()
    );
    assert!(!has(&info(&ply), "normals"));
    // A bad value is a usage error naming the range.
    for bad in ["auto=200", "sharp", "auto=nan"] {
        let o = lodkit(&["convert", &cube, "x.glb", "--normals", bad]);
        assert_eq!(o.status.code(), Some(2), "{bad}");
        assert!(stderr(&o).contains("[0, 180]"), "{}", stderr(&o));
    }
}

#[test]
fn point_clouds_become_points_primitives_and_read_back() {
    let dir = tempfile::tempdir().unwrap();
    let xyz = dir.path().join("c.xyz");
    let mut s = String::new();
    for i in 0..100 {
        let t = i as f32 * 0.1;
        s += &format!("{} {} {} 0.0 0.6 0.8\n", t.cos(), t.sin(), t * 0.01);
    }
    std::fs::write(&xyz, s).unwrap();
    let glb = dir.path().join("c.glb");
    let o = lodkit(&[
        "-q",
        "convert",
        xyz.to_str().unwrap(),
        glb.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let j = glb_json(&glb);
    let prim = &j["meshes"][0]["primitives"][0];
    assert_eq!(prim["mode"], 0, "POINTS");
    assert!(prim["attributes"].get("NORMAL").is_some());
    let v = info(&glb);
    assert_eq!(v["points"], 100, "{v}");
    // PLY with colours: COLOR_0 kept.
    let ply = dir.path().join("c.ply");
    let mut s = String::from(
        "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
         property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
    );
    s += "0 0 0 255 0 0\n1 0 0 0 255 0\n0 1 0 10 20 30\n";
    std::fs::write(&ply, s).unwrap();
    let glb = dir.path().join("p.glb");
    assert!(
        lodkit(&[
            "-q",
            "convert",
            ply.to_str().unwrap(),
            glb.to_str().unwrap()
        ])
        .status
        .success()
    );
    let back = dir.path().join("back.ply");
    assert!(
        lodkit(&[
            "-q",
            "convert",
            glb.to_str().unwrap(),
            back.to_str().unwrap(),
            "--ascii"
        ])
        .status
        .success()
    );
    let text = std::fs::read_to_string(&back).unwrap();
    assert!(text.contains("0 1 0 10 20 30"), "{text}");
}

#[test]
fn compress_writes_meshopt_and_quantization_or_says_which_feature() {
    let dir = tempfile::tempdir().unwrap();
    let plain = dir.path().join("plain.glb");
    let packed = dir.path().join("packed.glb");
    assert!(
        lodkit(&["-q", "convert", &bunny(), plain.to_str().unwrap()])
            .status
            .success()
    );
    let o = lodkit(&[
        "-q",
        "convert",
        &bunny(),
        packed.to_str().unwrap(),
        "--compress",
    ]);
    if !o.status.success() {
        // A build without the `compress` feature says how to get it.
        assert_eq!(o.status.code(), Some(1));
        assert!(stderr(&o).contains("--features compress"), "{}", stderr(&o));
        return;
    }
    let j = glb_json(&packed);
    let req: Vec<&str> = j["extensionsRequired"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert!(req.contains(&"EXT_meshopt_compression") && req.contains(&"KHR_mesh_quantization"));
    let (a, b) = (
        std::fs::metadata(&plain).unwrap().len(),
        std::fs::metadata(&packed).unwrap().len(),
    );
    assert!(b * 3 < a, "compressed {b} bytes vs {a}");
    // lodkit reads it back (meshopt decoders, dequantisation): same
    // triangles, positions within the 14-bit grid.
    let v = info(&packed);
    assert_eq!(v["faces"], 69451, "{v}");
    let back = dir.path().join("back.ply");
    assert!(
        lodkit(&[
            "-q",
            "convert",
            packed.to_str().unwrap(),
            back.to_str().unwrap()
        ])
        .status
        .success()
    );
    let o = lodkit(&[
        "compare",
        "--json",
        &bunny(),
        back.to_str().unwrap(),
        "--samples",
        "20000",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let c: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let max = c["symmetric"]["max"].as_f64().unwrap();
    let diag = c["diagonal"].as_f64().unwrap_or(0.25);
    assert!(max < diag / 16383.0 * 2.0, "max {max}, diag {diag}: {c}");
    // Deterministic.
    let again = dir.path().join("again.glb");
    assert!(
        lodkit(&[
            "-q",
            "convert",
            &bunny(),
            again.to_str().unwrap(),
            "--compress"
        ])
        .status
        .success()
    );
    assert_eq!(
        std::fs::read(&packed).unwrap(),
        std::fs::read(&again).unwrap()
    );
    // --compress is for .glb only.
    let o = lodkit(&["convert", &bunny(), "x.ply", "--compress"]);
    assert_eq!(o.status.code(), Some(2));
}

#[test]
fn draco_files_are_refused_in_one_line_naming_the_extension() {
    let dir = tempfile::tempdir().unwrap();
    let p = dir.path().join("draco.gltf");
    std::fs::write(
        &p,
        r#"{"asset":{"version":"2.0"},"extensionsUsed":["KHR_draco_mesh_compression"],
"extensionsRequired":["KHR_draco_mesh_compression"],
"buffers":[{"byteLength":4,"uri":"data:application/octet-stream;base64,AAAAAA=="}],
"bufferViews":[{"buffer":0,"byteLength":4}],
"accessors":[{"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0},"extensions":{"KHR_draco_mesh_compression":{"bufferView":0,"attributes":{"POSITION":0}}}}]}],
"nodes":[{"mesh":0}],"scenes":[{"nodes":[0]}],"scene":0}"#,
    )
    .unwrap();
    let o = lodkit(&["info", p.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert_eq!(e.trim().lines().count(), 1, "{e}");
    assert!(
        e.contains("KHR_draco_mesh_compression") && e.contains("draco.gltf"),
        "{e}"
    );
}
