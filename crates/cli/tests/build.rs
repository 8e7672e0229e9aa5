//! End-to-end tests of `lodkit build`: every input kind, options checked
//! before anything is written, the output folder replaced whole or left
//! as it was, and the structure of `report.html`.

mod common;

use std::path::{Path, PathBuf};

use common::{bunny, lodkit, stderr};
use lodkit_mesh::io::{WriteOptions, save};
use lodkit_mesh::{Model, PointCloud, TriMesh};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The bunny simplified to about 1 000 triangles: small enough that a
/// whole build takes a moment.
fn small_bunny() -> TriMesh {
    let m = lodkit_mesh::io::load_mesh(Path::new(&bunny())).unwrap();
    lodkit_simplify::simplify(&m, &lodkit_simplify::Options::faces(1_000))
        .unwrap()
        .mesh
}

/// Runs `build INPUT --out OUT` with cheap options; returns report.md.
fn build_ok(input: &Path, out: &Path) -> String {
    let o = lodkit(&[
        "-q",
        "build",
        s(input),
        "--out",
        s(out),
        "--levels",
        "2",
        "--samples",
        "2000",
    ]);
    assert!(o.status.success(), "{}: {}", input.display(), stderr(&o));
    for f in [
        "report.md",
        "report.html",
        "lod_error.svg",
        "lods/lods.json",
        "tiles/tileset.json",
    ] {
        assert!(out.join(f).is_file(), "{}: no {f}", input.display());
    }
    std::fs::read_to_string(out.join("report.md")).unwrap()
}

/// Everything in `dir` (relative paths, sorted).
fn tree(dir: &Path) -> Vec<String> {
    fn walk(base: &Path, d: &Path, out: &mut Vec<String>) {
        for e in std::fs::read_dir(d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                walk(base, &p, out);
            } else {
                out.push(p.strip_prefix(base).unwrap().display().to_string());
            }
        }
    }
    let mut v = Vec::new();
    walk(dir, dir, &mut v);
    v.sort();
    v
}

/// No `.NAME.lodkit-tmp-*` or `-old-*` folder is left beside `out`.
fn no_staging_left(out: &Path) {
    let parent = out.parent().unwrap();
    for e in std::fs::read_dir(parent).unwrap() {
        let n = e.unwrap().file_name().to_string_lossy().into_owned();
        assert!(!n.contains(".lodkit-"), "left behind: {n}");
    }
}

#[test]
fn meshes_of_every_format_take_the_mesh_path() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = Model::Mesh(small_bunny());
    for ext in ["ply", "obj", "stl", "glb"] {
        let input = dir.path().join(format!("small.{ext}"));
        save(&input, &mesh, WriteOptions::default()).unwrap();
        let out = dir.path().join(format!("out_{ext}"));
        let report = build_ok(&input, &out);
        assert!(report.contains("Path: a mesh."), "{ext}: {report}");
        // The octree is built from the mesh itself: no virtual scans.
        assert!(!out.join("scans").exists(), "{ext}");
        assert!(out.join("small.mco").is_file() && out.join("small.pop").is_file());
        no_staging_left(&out);
    }
}

#[test]
fn build_writes_a_tileset_listed_in_its_manifest_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("small.ply");
    save(&input, &Model::Mesh(small_bunny()), WriteOptions::default()).unwrap();
    let out = dir.path().join("out");
    let report = build_ok(&input, &out);
    assert!(report.contains("## 3D Tiles"), "{report}");
    assert!(
        report.contains("3D Tiles: `tiles/tileset.json`, 1 tiles in 1 levels"),
        "{report}"
    );
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(html.contains("3D Tiles: tiles/tileset.json"));
    // The manifest lists the tileset and its tiles; every tile reads back.
    let manifest: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join(".lodkit-build.json")).unwrap()).unwrap();
    let files = manifest["files"].as_object().unwrap();
    assert!(files.contains_key("tiles/tileset.json"), "{files:?}");
    let tiles: Vec<&String> = files
        .keys()
        .filter(|f| f.starts_with("tiles/tiles/") && f.ends_with(".glb"))
        .collect();
    assert!(!tiles.is_empty(), "{files:?}");
    let faces: usize = tiles
        .iter()
        .map(|f| {
            lodkit_mesh::io::load_mesh(&out.join(f))
                .unwrap()
                .faces
                .len()
        })
        .sum();
    assert_eq!(faces, small_bunny().faces.len());
    let tileset: serde_json::Value =
        serde_json::from_slice(&std::fs::read(out.join("tiles/tileset.json")).unwrap()).unwrap();
    assert_eq!(tileset["asset"]["version"], "1.1");
    assert_eq!(tileset["root"]["content"]["uri"], "tiles/0-0-0-0.glb");
}

#[test]
fn point_clouds_are_reconstructed_first() {
    let dir = tempfile::tempdir().unwrap();
    let m = small_bunny();
    let cloud = Model::Points(PointCloud {
        positions: m.positions.clone(),
        normals: None,
        colors: None,
    });
    for ext in ["xyz", "pts", "ply"] {
        let input = dir.path().join(format!("cloud.{ext}"));
        save(&input, &cloud, WriteOptions::default()).unwrap();
        let out = dir.path().join(format!("out_{ext}"));
        let report = build_ok(&input, &out);
        assert!(
            report.contains("Path: a point cloud, reconstructed first"),
            "{ext}: {report}"
        );
        assert!(
            report.contains("from the reconstructed surface"),
            "{ext}: {report}"
        );
        // No virtual scans: the reconstruction is the model.
        assert!(!out.join("scans").exists(), "{ext}");
        assert!(report.contains("The input's reconstruction"), "{report}");
    }
}

/// `lodkit scan` writes range images and a `.conf`; `build` takes one
/// range image, the `.conf`, and the folder.
#[test]
fn range_images_and_scan_sets_are_reconstructed_first() {
    let dir = tempfile::tempdir().unwrap();
    let scans = dir.path().join("scans");
    let o = lodkit(&[
        "-q",
        "scan",
        &bunny(),
        "--out",
        s(&scans),
        "--views",
        "4",
        "--size",
        "64x64",
        "--alternate",
        "--elevation",
        "30",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let cases: [(PathBuf, &str); 3] = [
        (scans.join("stanford_bunny_000.ply"), "Path: a range image,"),
        (
            scans.join("stanford_bunny.conf"),
            "Path: a scan set of 4 range images,",
        ),
        (scans.clone(), "Path: a scan set of 4 range images ("),
    ];
    for (i, (input, expect)) in cases.iter().enumerate() {
        let out = dir.path().join(format!("out_{i}"));
        let report = build_ok(input, &out);
        assert!(report.contains(expect), "{}: {report}", input.display());
    }
}

#[test]
fn bad_options_are_usage_errors_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("report.md"), "an earlier build").unwrap();
    for (args, says) in [
        (vec!["--levels", "0"], "1..=32"),
        (vec!["--levels", "33"], "1..=32"),
        (vec!["--samples", "0"], "1.."),
        (vec!["--samples", "10", "--no-measure"], "--no-measure"),
    ] {
        let mut all = vec!["build", "--out", s(&out)];
        all.extend(args.iter().copied());
        let o = lodkit(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(says), "{args:?}: {}", stderr(&o));
        assert_eq!(tree(&out), vec!["report.md".to_string()], "{args:?}");
    }
    // A folder of other files is never replaced.
    let other = dir.path().join("other");
    std::fs::create_dir(&other).unwrap();
    std::fs::write(other.join("notes.txt"), "mine").unwrap();
    let o = lodkit(&["build", "--out", s(&other)]);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(stderr(&o).contains("not a lodkit build"), "{}", stderr(&o));
    assert_eq!(tree(&other), vec!["notes.txt".to_string()]);
    no_staging_left(&out);
}

#[test]
fn a_failed_build_leaves_the_folder_as_it_was_and_a_good_one_replaces_it() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    std::fs::create_dir(&out).unwrap();
    std::fs::write(out.join("report.md"), "an earlier build").unwrap();
    std::fs::write(out.join("stale.ply"), "from an earlier build").unwrap();
    // An earlier build's manifest: every file it wrote, with its size.
    std::fs::write(
        out.join(".lodkit-build.json"),
        r#"{"lodkit_build": 1, "files": {"report.md": 16, "stale.ply": 21}}"#,
    )
    .unwrap();
    let bad = dir.path().join("bad.ply");
    std::fs::write(&bad, "ply\nformat nonsense\n").unwrap();
    for input in [bad.clone(), dir.path().join("missing.ply")] {
        let o = lodkit(&["build", s(&input), "--out", s(&out)]);
        assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
        assert!(stderr(&o).contains(s(&input)), "{}", stderr(&o));
        assert_eq!(
            tree(&out),
            vec![".lodkit-build.json", "report.md", "stale.ply"]
        );
        no_staging_left(&out);
    }
    let input = dir.path().join("small.ply");
    save(&input, &Model::Mesh(small_bunny()), WriteOptions::default()).unwrap();
    build_ok(&input, &out);
    assert!(
        !out.join("stale.ply").exists(),
        "the folder is replaced whole"
    );
    no_staging_left(&out);
}

/// `report.html`: every picture an embedded PNG that shows the model,
/// every chart and table present, and the page the same from run to run
/// outside its timings.
#[test]
fn report_html_is_self_contained_and_deterministic() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("small.ply");
    save(&input, &Model::Mesh(small_bunny()), WriteOptions::default()).unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    build_ok(&input, &a);
    build_ok(&input, &b);
    let html = std::fs::read_to_string(a.join("report.html")).unwrap();
    let strip = |h: &str| {
        let (start, end) = (
            h.find("<!-- varies -->").unwrap(),
            h.find("<!-- /varies -->").unwrap(),
        );
        format!("{}{}", &h[..start], &h[end..])
    };
    let other = std::fs::read_to_string(b.join("report.html")).unwrap();
    assert_eq!(
        strip(&html),
        strip(&other),
        "report.html differs outside its timings"
    );
    assert!(html.starts_with("<!DOCTYPE html>"));
    // Nothing fetched: no external reference of any kind.
    for bad in ["http://", "https://", "<script", "<link"] {
        let n = html.matches(bad).count();
        // SVG's own namespace is the one URL allowed.
        let allowed = html.matches("http://www.w3.org/2000/svg").count()
            + html.matches("http://www.w3.org/1999/xlink").count();
        assert!(
            bad != "http://" && n == 0 || bad == "http://" && n == allowed,
            "{bad}"
        );
    }
    // Input, 2 HQMS levels, the MCO cuts, the stream levels, the heat map.
    assert!(every_picture_shows_the_model(&html) >= 6);
    for needle in [
        "error against triangle count, every form",
        ".pop error against bytes received",
        "linearGradient",
        "Stage timings",
        "<dt>estimated error</dt>",
        "% of the diagonal",
    ] {
        assert!(html.contains(needle), "no {needle}");
    }
    assert!(
        html.matches("<svg").count() >= 3,
        "two charts and a colour bar"
    );
    assert!(html.matches("<table>").count() >= 4);
}

#[test]
fn no_measure_skips_every_measurement() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("small.ply");
    save(&input, &Model::Mesh(small_bunny()), WriteOptions::default()).unwrap();
    let out = dir.path().join("out");
    let o = lodkit(&[
        "-q",
        "build",
        s(&input),
        "--out",
        s(&out),
        "--levels",
        "2",
        "--no-measure",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(
        report.contains("are not measured (`--no-measure`)"),
        "{report}"
    );
    assert!(
        report.contains("| 1 | `lods/small_lod1.ply` | 500 |"),
        "{report}"
    );
    assert!(out.join("report.html").is_file());
}

/// A build ended by SIGTERM removes its staging folder and leaves `--out`
/// as it was (absent here); a staging folder left by a build killed
/// outright (its process gone) is removed by the next build of that `--out`.
#[cfg(target_os = "linux")]
#[test]
fn a_killed_build_leaves_no_folder_behind() {
    use std::time::{Duration, Instant};
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_lodkit"))
        .args(["-q", "build", &bunny(), "--out", s(&out)])
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let staged = dir.path().join(format!(".out.lodkit-tmp-{}", child.id()));
    let start = Instant::now();
    // Past the input check: the staging folder has files in it.
    while !std::fs::read_dir(&staged).is_ok_and(|mut d| d.next().is_some()) {
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no staging folder"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let sent = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    assert!(!child.wait().unwrap().success());
    assert!(!out.exists());
    no_staging_left(&out);

    // A dead process's folder (pids above the kernel's pid_max never run),
    // lodkit's by its manifest marked as being written, is removed; one
    // without it is not lodkit's and is kept.
    let stale = dir.path().join(".out.lodkit-tmp-4294967294");
    std::fs::create_dir_all(stale.join("lods")).unwrap();
    std::fs::write(stale.join("lods/x.ply"), b"half").unwrap();
    std::fs::write(
        stale.join(".lodkit-build.json"),
        r#"{"lodkit_build": 1, "writing": true, "files": {}}"#,
    )
    .unwrap();
    let foreign = dir.path().join(".out.lodkit-tmp-4294967293");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("mine.txt"), b"mine").unwrap();
    build_ok(&small_input(dir.path()), &out);
    assert!(!stale.exists());
    assert_eq!(std::fs::read(foreign.join("mine.txt")).unwrap(), b"mine");
    std::fs::remove_dir_all(&foreign).unwrap();
    no_staging_left(&out);
}

/// The small bunny saved as a PLY in `dir`.
fn small_input(dir: &Path) -> PathBuf {
    let p = dir.join("small_in.ply");
    save(&p, &Model::Mesh(small_bunny()), WriteOptions::default()).unwrap();
    p
}

/// A one-sided scan, as a laser or stereo scanner sees a table top: `n × n`
/// points on a gently wavy open sheet, jittered (deterministically) by a
/// tenth of their spacing, no normals.
fn wavy_sheet(n: usize) -> PointCloud {
    let mut state = 0x2545_f491_4f6c_dd1du64;
    let mut jitter = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 40) as f32 / (1u64 << 24) as f32 - 0.5
    };
    let step = 1.0 / n as f32;
    let mut positions = Vec::with_capacity(n * n);
    for i in 0..n {
        for j in 0..n {
            let x = i as f32 * step + 0.1 * step * jitter();
            let y = j as f32 * step + 0.1 * step * jitter();
            let z = 0.08 * (3.0 * x).sin() * (2.0 * y).cos();
            positions.push(lodkit_mesh::glam::Vec3::new(x, y, z));
        }
    }
    PointCloud {
        positions,
        normals: None,
        colors: None,
    }
}

/// The row of report.md's detail table for `product` (`stream` or
/// `octree`): its finest level's count and the input's.
fn detail_row(report: &str, product: &str) -> (usize, usize, String) {
    let row = report
        .lines()
        .find(|l| l.starts_with(&format!("| {product} ")))
        .unwrap_or_else(|| panic!("no {product} row: {report}"));
    let cells: Vec<&str> = row.split('|').map(str::trim).collect();
    let first = |c: &str| c.split(' ').next().unwrap().parse::<usize>().unwrap();
    (first(cells[2]), first(cells[3]), cells[6].to_string())
}

/// `x` is within a factor 2 of `of`.
fn within_2x(x: usize, of: usize) -> bool {
    2 * x >= of && x <= 2 * of
}

/// A one-sided point cloud keeps its detail in the stream (no outer
/// thinning eating the sheet; leaves about as many as its points) and in
/// the octree; the stream, read back, has it at its finest level.
#[test]
fn a_one_sided_cloud_keeps_its_detail_in_every_product() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = wavy_sheet(60);
    let n = cloud.positions.len();
    let input = dir.path().join("sheet.xyz");
    save(&input, &Model::Points(cloud), WriteOptions::default()).unwrap();
    let out = dir.path().join("out");
    let report = build_ok(&input, &out);
    let (particles, samples, verdict) = detail_row(&report, "stream");
    assert_eq!(samples, n, "{report}");
    assert!(
        within_2x(particles, n),
        "{particles} particles for {n} points: {report}"
    );
    assert_eq!(verdict, "ok", "{report}");
    let (triangles, _, verdict) = detail_row(&report, "octree");
    assert!(
        within_2x(triangles, n),
        "{triangles} triangles for {n} points: {report}"
    );
    assert_eq!(verdict, "ok", "{report}");
    // Read back: the finest level decoded from the file.
    let bytes = std::fs::read(out.join("sheet.pop")).unwrap();
    let d = lodkit_particles::decode(&bytes, &lodkit_particles::DecodeOptions::default()).unwrap();
    let finest = d.surface(d.finest_level()).unwrap();
    assert_eq!(finest.positions.len(), particles);
    // Every render of the cloud's report shows it.
    let html = std::fs::read_to_string(out.join("report.html")).unwrap();
    assert!(every_picture_shows_the_model(&html) >= 6);
}

/// A mesh's octree comes from the mesh (its full cut about the input's
/// triangle count, read back from the `.mco`), and its stream's finest
/// level holds about the mesh's vertex count.
#[test]
fn a_mesh_keeps_its_detail_in_the_octree_and_the_stream() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = small_bunny();
    let (faces, vertices) = (mesh.faces.len(), mesh.positions.len());
    let input = dir.path().join("small.ply");
    save(&input, &Model::Mesh(mesh), WriteOptions::default()).unwrap();
    let out = dir.path().join("out");
    let report = build_ok(&input, &out);
    let model = lodkit_mco::McoModel::load(&out.join("small.mco")).unwrap();
    assert!(
        within_2x(model.full_triangles(), faces),
        "{} triangles for {faces}: {report}",
        model.full_triangles()
    );
    assert_eq!(detail_row(&report, "octree").0, model.full_triangles());
    let bytes = std::fs::read(out.join("small.pop")).unwrap();
    let d = lodkit_particles::decode(&bytes, &lodkit_particles::DecodeOptions::default()).unwrap();
    let particles = d.surface(d.finest_level()).unwrap().positions.len();
    assert!(
        within_2x(particles, vertices),
        "{particles} particles for {vertices} vertices: {report}"
    );
    for product in ["stream", "octree"] {
        assert_eq!(detail_row(&report, product).2, "ok", "{report}");
    }
}

/// A cloud whose one far outlier makes the reconstruction's lattice
/// coarser than the whole object: the octree keeps a handful of triangles.
/// The build writes everything, says which product is degenerate and why
/// (a warning even under -q, a row of report.md), and exits 1.
#[test]
fn a_degenerate_product_is_a_warning_and_exit_1() {
    let dir = tempfile::tempdir().unwrap();
    let n = 2000;
    let mut positions: Vec<lodkit_mesh::glam::Vec3> = (0..n)
        .map(|i| {
            // A Fibonacci sphere of radius 0.01.
            let z = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let (r, t) = ((1.0 - z * z).sqrt(), i as f32 * 2.399_963);
            lodkit_mesh::glam::Vec3::new(r * t.cos(), r * t.sin(), z) * 0.01
        })
        .collect();
    positions.push(lodkit_mesh::glam::Vec3::splat(100.0));
    let input = dir.path().join("outlier.xyz");
    let cloud = PointCloud {
        positions,
        normals: None,
        colors: None,
    };
    save(&input, &Model::Points(cloud), WriteOptions::default()).unwrap();
    let out = dir.path().join("out");
    let o = lodkit(&[
        "-q",
        "build",
        s(&input),
        "--out",
        s(&out),
        "--levels",
        "2",
        "--samples",
        "2000",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains(&format!(
            "warning: {}: degenerate octree outlier.mco",
            s(&input)
        )),
        "{err}"
    );
    assert!(err.contains("degenerate product(s)"), "{err}");
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    let (triangles, points, verdict) = detail_row(&report, "octree");
    assert!(triangles < 100 && points == n + 1, "{report}");
    assert!(verdict.starts_with("its finest level has"), "{report}");
    no_staging_left(&out);
}

/// Every `<img>` of a report page is an embedded 256 × 256 PNG with more
/// than 500 pixels that are not the white background; returns how many.
fn every_picture_shows_the_model(html: &str) -> usize {
    let imgs: Vec<&str> = html.split("<img ").skip(1).collect();
    use base64::Engine as _;
    for img in &imgs {
        let src = img
            .split("src=\"data:image/png;base64,")
            .nth(1)
            .expect("every <img> is a data: PNG");
        let b64 = &src[..src.find('"').unwrap()];
        let png = base64::engine::general_purpose::STANDARD
            .decode(b64)
            .unwrap();
        let mut reader = png::Decoder::new(std::io::Cursor::new(png))
            .read_info()
            .unwrap();
        let mut buf = vec![0; reader.output_buffer_size().unwrap()];
        let info = reader.next_frame(&mut buf).unwrap();
        assert_eq!((info.width, info.height), (256, 256));
        let px = info.line_size * info.height as usize;
        let step = info.color_type.samples();
        let drawn = buf[..px]
            .chunks_exact(step)
            .filter(|p| p[..3] != [255, 255, 255])
            .count();
        assert!(
            drawn > 500,
            "a picture shows almost nothing ({drawn} pixels)"
        );
    }
    imgs.len()
}
