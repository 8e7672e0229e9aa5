//! End-to-end tests of `lodkit render` (one view, rings) and
//! `lodkit compare --heatmap`.
mod common;

use std::path::Path;

use common::{bunny, lodkit, stderr};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

fn ok(o: &std::process::Output) {
    assert!(o.status.success(), "{}", stderr(o));
}

/// Decodes a PNG: (width, height, channels, bytes).
fn png(path: &Path) -> (u32, u32, usize, Vec<u8>) {
    let dec = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut r = dec.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    (info.width, info.height, info.color_type.samples(), buf)
}

fn sphere(dir: &Path) -> std::path::PathBuf {
    let p = dir.join("sphere.ply");
    lodkit_mesh::io::save_mesh(
        &p,
        &lodkit_mesh::shapes::icosphere(3),
        lodkit_mesh::io::WriteOptions::default(),
    )
    .unwrap();
    p
}

#[test]
fn render_the_bunny_twice_gives_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.png");
    let b = dir.path().join("b.png");
    for out in [&a, &b] {
        ok(&lodkit(&[
            "-q",
            "render",
            &bunny(),
            "-o",
            s(out),
            "--size",
            "160x120",
            "--view",
            "-40,25",
        ]));
    }
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
    let (w, h, ch, px) = png(&a);
    assert_eq!((w, h, ch), (160, 120, 4));
    // Opaque, white background in the corner, the bunny in the middle.
    assert!(px.chunks_exact(4).all(|p| p[3] == 255));
    assert_eq!(&px[..4], &[255, 255, 255, 255]);
    let object = px
        .chunks_exact(4)
        .filter(|p| p[..3] != [255, 255, 255])
        .count();
    let frac = object as f64 / (w * h) as f64;
    assert!(frac > 0.15 && frac < 0.6, "bunny covers {frac}");
    // The JSON form states the same.
    let o = lodkit(&[
        "render",
        &bunny(),
        "-o",
        s(&a),
        "--size",
        "160x120",
        "--view",
        "-40,25",
        "--json",
    ]);
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["views"], 1);
    assert!((v["coverage"].as_f64().unwrap() - frac).abs() < 0.02);
    assert_eq!(std::fs::read(&a).unwrap(), std::fs::read(&b).unwrap());
}

#[test]
fn bad_option_values_exit_2_naming_the_range() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("x.png");
    let b = bunny();
    for (args, range) in [
        (vec!["--size", "0x10"], "1..=8192"),
        (vec!["--size", "9000x10"], "1..=8192"),
        (vec!["--size", "ten"], "WxH"),
        (vec!["--view", "nan,0"], "finite"),
        (vec!["--view", "0,91"], "[-90, 90]"),
        (vec!["--view", "0,-90.5"], "[-90, 90]"),
        (vec!["--background", "256,0,0"], "0..=255"),
        (vec!["--fov", "0"], "[1, 170]"),
        (vec!["--lod", "3"], ".mco"),
        (vec!["--level", "3"], ".pop"),
    ] {
        let mut all = vec!["render", b.as_str(), "-o", s(&out)];
        all.extend(&args);
        let o = lodkit(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(range), "{args:?}: {}", stderr(&o));
    }
    let ring = dir.path().join("ring");
    for args in [
        vec!["--ring", "0", "--out", s(&ring)],
        vec!["--ring", "4"],
        vec!["--ring", "4", "--out", s(&ring), "--elevations", "10,95"],
        vec!["--ring", "4", "--out", s(&ring), "-o", s(&out)],
    ] {
        let mut all = vec!["render", b.as_str()];
        all.extend(&args);
        let o = lodkit(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
    }
    assert!(!out.exists() && !ring.exists(), "nothing written");
}

#[test]
fn bad_input_exits_1_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("broken.ply");
    std::fs::write(
        &bad,
        b"ply\nformat ascii 1.0\nelement vertex 3\nend_header\n1 2\n",
    )
    .unwrap();
    let out = dir.path().join("x.png");
    for input in [bad.clone(), dir.path().join("missing.obj")] {
        let o = lodkit(&["render", s(&input), "-o", s(&out)]);
        assert_eq!(o.status.code(), Some(1));
        let e = stderr(&o);
        assert_eq!(e.trim().lines().count(), 1, "{e}");
        assert!(e.contains(s(&input)), "{e}");
    }
    assert!(!out.exists());
}

#[test]
fn mco_cuts_and_pop_levels_render() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = sphere(dir.path());
    let pop = dir.path().join("s.pop");
    ok(&lodkit(&[
        "-q",
        "pop",
        "encode",
        s(&mesh),
        "-o",
        s(&pop),
        "--depth",
        "5",
    ]));
    let a = dir.path().join("pop.png");
    ok(&lodkit(&[
        "-q",
        "render",
        s(&pop),
        "--level",
        "4",
        "-o",
        s(&a),
        "--size",
        "64x64",
    ]));
    let (_, _, _, px) = png(&a);
    assert!(px.chunks_exact(4).any(|p| p[..3] != [255, 255, 255]));
    let o = lodkit(&["render", s(&pop), "--level", "9", "-o", s(&a)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("0..=5"), "{}", stderr(&o));

    let model = dir.path().join("s.mco");
    ok(&lodkit(&[
        "-q",
        "mco",
        "build",
        s(&mesh),
        "-o",
        s(&model),
        "--resolution",
        "16",
    ]));
    let b = dir.path().join("mco.png");
    ok(&lodkit(&[
        "-q",
        "render",
        s(&model),
        "--triangles",
        "200",
        "-o",
        s(&b),
        "--size",
        "64x64",
    ]));
    let (_, _, _, px) = png(&b);
    assert!(px.chunks_exact(4).any(|p| p[..3] != [255, 255, 255]));
    let o = lodkit(&["render", s(&model), "--level", "2", "-o", s(&b)]);
    assert_eq!(o.status.code(), Some(2));
}

/// The silhouette carver's view of a ring: read the files a user's
/// photographs would come in, project surface points with them, find each
/// in its mask.
#[test]
fn ring_files_parse_back_and_project_the_surface_into_every_mask() {
    let dir = tempfile::tempdir().unwrap();
    let ring = dir.path().join("ring");
    ok(&lodkit(&[
        "-q",
        "render",
        &bunny(),
        "--ring",
        "6",
        "--elevations",
        "-30,0,45",
        "--size",
        "96x80",
        "--out",
        s(&ring),
    ]));
    let t: serde_json::Value =
        serde_json::from_slice(&std::fs::read(ring.join("transforms.json")).unwrap()).unwrap();
    let (fx, fy, cx, cy) = (
        t["fl_x"].as_f64().unwrap(),
        t["fl_y"].as_f64().unwrap(),
        t["cx"].as_f64().unwrap(),
        t["cy"].as_f64().unwrap(),
    );
    assert_eq!((t["w"].as_u64(), t["h"].as_u64()), (Some(96), Some(80)));
    assert!((cx, cy) == (48.0, 40.0));
    let frames = t["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 18);
    let cameras = std::fs::read_to_string(ring.join("sparse/0/cameras.txt")).unwrap();
    let line = cameras.lines().find(|l| !l.starts_with('#')).unwrap();
    assert_eq!(line, format!("1 PINHOLE 96 80 {fx} {fy} {cx} {cy}"));
    let images = std::fs::read_to_string(ring.join("sparse/0/images.txt")).unwrap();
    let poses: Vec<&str> = images
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
        .collect();
    assert_eq!(poses.len(), 18);
    assert_eq!(
        std::fs::read_to_string(ring.join("sparse/0/points3D.txt"))
            .unwrap()
            .lines()
            .filter(|l| !l.starts_with('#'))
            .count(),
        0
    );
    let mesh = lodkit_mesh::io::load_mesh(Path::new(&bunny())).unwrap();
    // Every 50th referenced vertex.
    let mut used = vec![false; mesh.positions.len()];
    for f in &mesh.faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    let points: Vec<[f64; 3]> = mesh
        .positions
        .iter()
        .zip(&used)
        .filter(|(_, u)| **u)
        .step_by(50)
        .map(|(p, _)| [p.x as f64, p.y as f64, p.z as f64])
        .collect();
    for (i, f) in frames.iter().enumerate() {
        let name = format!("{i:03}.png");
        assert_eq!(f["file_path"], format!("images/{name}"));
        assert_eq!(f["mask_path"], format!("masks/{name}"));
        let (w, h, ch, rgba) = png(&ring.join("images").join(&name));
        assert_eq!((w, h, ch), (96, 80, 4));
        let (mw, mh, mch, mask) = png(&ring.join("masks").join(&name));
        assert_eq!((mw, mh, mch), (96, 80, 1));
        // alpha is the object: the mask is where alpha > 0.
        for (p, m) in rgba.chunks_exact(4).zip(&mask) {
            assert_eq!(*m, if p[3] > 0 { 255 } else { 0 });
        }
        let cover = mask.iter().filter(|&&m| m == 255).count() as f64 / mask.len() as f64;
        assert!(cover > 0.03 && cover < 0.6, "view {i}: {cover}");
        let m: Vec<Vec<f64>> = f["transform_matrix"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                r.as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect()
            })
            .collect();
        let pose: Vec<&str> = poses[i].split(' ').collect();
        assert_eq!(pose[0], (i + 1).to_string());
        assert_eq!(pose[8], "1");
        assert_eq!(pose[9], name);
        let q: Vec<f64> = pose[1..5].iter().map(|v| v.parse().unwrap()).collect();
        let tr: Vec<f64> = pose[5..8].iter().map(|v| v.parse().unwrap()).collect();
        let (qw, qx, qy, qz) = (q[0], q[1], q[2], q[3]);
        let r = [
            [
                1.0 - 2.0 * (qy * qy + qz * qz),
                2.0 * (qx * qy - qw * qz),
                2.0 * (qx * qz + qw * qy),
            ],
            [
                2.0 * (qx * qy + qw * qz),
                1.0 - 2.0 * (qx * qx + qz * qz),
                2.0 * (qy * qz - qw * qx),
            ],
            [
                2.0 * (qx * qz - qw * qy),
                2.0 * (qy * qz + qw * qx),
                1.0 - 2.0 * (qx * qx + qy * qy),
            ],
        ];
        let hit = |u: f64, v: f64| {
            let (a, b) = (u.floor() as i64, v.floor() as i64);
            (-1..=1).any(|dy| {
                (-1..=1).any(|dx| {
                    let (x, y) = (a + dx, b + dy);
                    x >= 0 && y >= 0 && x < 96 && y < 80 && mask[(y * 96 + x) as usize] == 255
                })
            })
        };
        for x in &points {
            // COLMAP: world-to-camera, OpenCV axes.
            let c: Vec<f64> = (0..3)
                .map(|k| (0..3).map(|j| r[k][j] * x[j]).sum::<f64>() + tr[k])
                .collect();
            let (u, v) = (fx * c[0] / c[2] + cx, fy * c[1] / c[2] + cy);
            assert!(
                hit(u, v),
                "view {i}: {x:?} projects to ({u:.1}, {v:.1}) outside the mask"
            );
            // NeRF: camera-to-world, OpenGL axes, row-major.
            let d = [x[0] - m[0][3], x[1] - m[1][3], x[2] - m[2][3]];
            let g: Vec<f64> = (0..3)
                .map(|k| (0..3).map(|j| m[j][k] * d[j]).sum())
                .collect();
            let (u2, v2) = (cx + fx * g[0] / -g[2], cy - fy * g[1] / -g[2]);
            assert!((u - u2).abs() < 1e-3 && (v - v2).abs() < 1e-3);
        }
    }
    // A second run writes the same bytes.
    let again = dir.path().join("again");
    ok(&lodkit(&[
        "-q",
        "render",
        &bunny(),
        "--ring",
        "6",
        "--elevations",
        "-30,0,45",
        "--size",
        "96x80",
        "--out",
        s(&again),
    ]));
    for f in [
        "transforms.json",
        "sparse/0/images.txt",
        "images/007.png",
        "masks/017.png",
    ] {
        assert_eq!(
            std::fs::read(ring.join(f)).unwrap(),
            std::fs::read(again.join(f)).unwrap(),
            "{f}"
        );
    }
}

#[test]
fn compare_heatmap_colours_b_by_distance_and_states_the_scale() {
    let dir = tempfile::tempdir().unwrap();
    let simplified = common::repo().join("data/reference/stanford_bunny_simplified.ply");
    let out = dir.path().join("heat.ply");
    let o = lodkit(&[
        "compare",
        &bunny(),
        s(&simplified),
        "--samples",
        "20000",
        "--heatmap",
        s(&out),
    ]);
    ok(&o);
    let text = String::from_utf8_lossy(&o.stdout);
    let line = text
        .lines()
        .find(|l| l.starts_with("heat map: 0 (blue) … "))
        .unwrap();
    assert!(
        line.contains("(red) object units") && line.contains("% of the diagonal"),
        "{line}"
    );
    let o = lodkit(&[
        "compare",
        &bunny(),
        s(&simplified),
        "--samples",
        "20000",
        "--heatmap",
        s(&out),
        "--json",
    ]);
    ok(&o);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    let h = &v["heatmap"];
    let max = h["max"].as_f64().unwrap();
    assert!(max > 0.0 && h["max_percent_of_diagonal"].as_f64().unwrap() > 0.0);
    assert!(v["symmetric"].is_object(), "the report is still there");
    // The scale is in the PLY header too.
    let bytes = std::fs::read(&out).unwrap();
    let header = String::from_utf8_lossy(
        &bytes[..bytes.windows(10).position(|w| w == b"end_header").unwrap()],
    )
    .into_owned();
    assert!(
        header.contains("comment heat map: 0 (blue) ... "),
        "{header}"
    );
    // Colours follow the distances: the farthest vertex is red, the nearest blue.
    let b = lodkit_mesh::io::load_mesh(&out).unwrap();
    let a = lodkit_mesh::io::load_mesh(Path::new(&bunny())).unwrap();
    let index = lodkit_mesh::metrics::SurfaceIndex::new(&a).unwrap();
    let d = index.distances(&b.positions);
    let colours = b.colors.as_ref().expect("vertex colours written");
    let far = (0..d.len()).max_by(|&i, &j| d[i].total_cmp(&d[j])).unwrap();
    let near = (0..d.len()).min_by(|&i, &j| d[i].total_cmp(&d[j])).unwrap();
    assert!((d[far] as f64 - max).abs() < 1e-9 * max.max(1.0) + 1e-7);
    let [r, _, bl, _] = colours[far];
    assert!(r > 150 && bl < 80, "far vertex {:?}", colours[far]);
    let [r, _, bl, _] = colours[near];
    assert!(bl > 150 && r < 80, "near vertex {:?}", colours[near]);
    assert_eq!(colours[far][..3], lodkit_render::colour_scale(1.0));
    // Formats without vertex colours are refused before anything runs.
    for bad in ["heat.stl", "heat.xyz"] {
        let o = lodkit(&[
            "compare",
            &bunny(),
            s(&simplified),
            "--heatmap",
            s(&dir.path().join(bad)),
        ]);
        assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
        assert!(stderr(&o).contains(".ply, .obj or .glb"), "{}", stderr(&o));
    }
}

#[test]
fn a_textured_scene_renders_with_its_textures() {
    let dir = tempfile::tempdir().unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("../mesh/tests/data/textured");
    // Saturated texels (the checker's red, the stripes' blue and yellow)
    // where the clay colour is nearly grey.
    let saturated = |p: &Path| {
        let (_, _, ch, px) = png(p);
        px.chunks_exact(ch)
            .filter(|c| c[0].max(c[1]).max(c[2]) - c[0].min(c[1]).min(c[2]) > 80)
            .count()
    };
    let textured = dir.path().join("parts.png");
    let o = lodkit(&[
        "render",
        s(&data.join("parts.gltf")),
        "-o",
        s(&textured),
        "--size",
        "128x128",
    ]);
    ok(&o);
    assert!(
        stderr(&o).contains("2 materials, 2 textures"),
        "{}",
        stderr(&o)
    );
    assert!(saturated(&textured) > 500, "{}", saturated(&textured));
    let again = dir.path().join("again.png");
    ok(&lodkit(&[
        "render",
        s(&data.join("parts.gltf")),
        "-o",
        s(&again),
        "--size",
        "128x128",
    ]));
    assert_eq!(
        std::fs::read(&textured).unwrap(),
        std::fs::read(&again).unwrap()
    );
    // The same geometry without its materials is clay.
    let merged = dir.path().join("merged.ply");
    ok(&lodkit(&[
        "convert",
        s(&data.join("parts.gltf")),
        s(&merged),
        "--merge",
    ]));
    let clay = dir.path().join("clay.png");
    ok(&lodkit(&[
        "render",
        s(&merged),
        "-o",
        s(&clay),
        "--size",
        "128x128",
    ]));
    assert_eq!(saturated(&clay), 0);
}
