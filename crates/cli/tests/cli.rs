//! End-to-end tests of the `lodkit` binary: exit codes, messages, outputs.

use std::path::{Path, PathBuf};

mod common;
use common::{bunny, lodkit, repo, stderr};

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// Every file under `dir`, relative, sorted.
fn tree(dir: &Path) -> Vec<String> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                out.push(p.strip_prefix(dir).unwrap().display().to_string());
            }
        }
    }
    out.sort();
    out
}

/// `lods.json` without its wall times (the only field allowed to differ).
fn without_times(bytes: &[u8]) -> serde_json::Value {
    let mut v: serde_json::Value = serde_json::from_slice(bytes).unwrap();
    for l in v["levels"].as_array_mut().unwrap() {
        l.as_object_mut().unwrap().remove("seconds");
    }
    v
}

#[test]
fn build_without_input_writes_the_bunny_and_its_lod_chain_deterministically() {
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a"), dir.path().join("b"));
    for out in [&a, &b] {
        let o = lodkit(&[
            "-q",
            "build",
            "--levels",
            "3",
            "--samples",
            "100000",
            "--out",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
    }
    let n = "stanford_bunny";
    let mut expected: Vec<String> = vec![
        format!("{n}.glb"),
        format!("{n}.ply"),
        "lod_error.svg".into(),
        format!("lods/{n}_lod1.ply"),
        format!("lods/{n}_lod2.ply"),
        format!("lods/{n}_lod3.ply"),
        format!("lods/{n}_lods.glb"),
        "lods/lods.json".into(),
        "report.md".into(),
        "report.html".into(),
        ".lodkit-build.json".into(),
        format!("{n}.mco"),
        format!("{n}.pop"),
        "tiles/tileset.json".into(),
        "tiles/.lodkit-build.json".into(),
    ];
    // The tileset's tiles, whatever their number (compared below).
    let tiles: Vec<String> = tree(&a)
        .into_iter()
        .filter(|f| f.starts_with("tiles/tiles/") && f.ends_with(".glb"))
        .collect();
    assert!(!tiles.is_empty(), "no tiles in {:?}", tree(&a));
    expected.extend(tiles);
    expected.sort();
    // Nothing but the outputs: no temp files left behind.
    assert_eq!(tree(&a), expected);
    for file in &expected {
        let x = std::fs::read(a.join(file)).unwrap();
        let y = std::fs::read(b.join(file)).unwrap();
        assert!(!x.is_empty(), "{file} is empty");
        if file == ".lodkit-build.json" {
            // Every file but the manifest, at its size; two sizes vary
            // (timings), the rest are the same in both runs.
            let sizes = |m: &[u8]| {
                let mut v: serde_json::Value = serde_json::from_slice(m).unwrap();
                let files = v["files"].as_object_mut().unwrap();
                for varies in ["lods/lods.json", "report.html"] {
                    assert!(files.remove(varies).is_some(), "{varies} not listed");
                }
                v
            };
            let listed = sizes(&x);
            assert_eq!(listed, sizes(&y), "{file} differs between two runs");
            let n = listed["files"].as_object().unwrap().len();
            assert_eq!(n + 3, expected.len(), "{listed}");
        } else if file.ends_with(".html") {
            // The stage timings vary; they sit between these markers.
            let strip = |h: &[u8]| {
                let h = String::from_utf8_lossy(h).into_owned();
                let (a, b) = (
                    h.find("<!-- varies -->").unwrap(),
                    h.find("<!-- /varies -->").unwrap(),
                );
                format!("{}{}", &h[..a], &h[b..])
            };
            assert_eq!(strip(&x), strip(&y), "{file} differs between two runs");
        } else if file.ends_with("lods.json") {
            assert_eq!(
                without_times(&x),
                without_times(&y),
                "{file} differs between two runs"
            );
        } else {
            // Compare as text where it is text, so a failure is readable.
            assert!(
                x == y,
                "{file} differs between two runs:\n{}\n---\n{}",
                String::from_utf8_lossy(&x),
                String::from_utf8_lossy(&y)
            );
        }
    }
    let report = std::fs::read_to_string(a.join("report.md")).unwrap();
    assert!(report.contains("vertices: 35947"), "{report}");
    assert!(report.contains("faces: 69451"), "{report}");
    assert!(
        report.contains("## Discrete LOD chain (HQMS)") && report.contains("lod_error.svg"),
        "{report}"
    );
    assert!(
        report.contains("## Continuous LOD (marching cube octree)") && report.contains("| 10 |"),
        "{report}"
    );
    assert!(
        report.contains("## Progressive stream (octree particles)"),
        "{report}"
    );
    // The chain halves the bunny three times, each level measured.
    let lods = without_times(&std::fs::read(a.join("lods/lods.json")).unwrap());
    let levels = lods["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 3);
    for (i, l) in levels.iter().enumerate() {
        let target = (69451usize >> (i + 1)) as f64;
        let tris = l["triangles"].as_f64().unwrap();
        assert!(
            tris <= target + 1.0 && tris >= target * 0.995,
            "level {i}: {tris} for {target}"
        );
        assert!(l["measured_max_error"].as_f64().unwrap() > 0.0);
    }
    // The GLB reads back as the same mesh.
    let o = lodkit(&[
        "info",
        "--json",
        a.join(format!("{n}.glb")).to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["faces"], 69451);
}

#[test]
fn info_reports_the_bunny_topology_as_json() {
    let o = lodkit(&["info", "--json", &bunny()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["kind"], "mesh");
    assert_eq!(v["vertices"], 35947);
    assert_eq!(v["faces"], 69451);
    // The values the shared data README lists for this file.
    assert_eq!(v["boundary_edges"], 223);
    assert_eq!(v["boundary_loops"], 5);
    assert_eq!(v["non_manifold_edges"], 0);
    assert_eq!(v["unreferenced_vertices"], 1113);
}

/// A report with its wall times taken out: JSON keys ending in
/// `_seconds`, and in text the numbers printed with 3 decimals (the time
/// columns; the other figures have 2).
fn without_timings(out: &[u8], json: bool) -> String {
    fn strip(v: &mut serde_json::Value) {
        match v {
            serde_json::Value::Object(m) => {
                m.retain(|k, _| !k.ends_with("_seconds"));
                m.values_mut().for_each(strip);
            }
            serde_json::Value::Array(a) => a.iter_mut().for_each(strip),
            _ => {}
        }
    }
    if json {
        let mut v: serde_json::Value = serde_json::from_slice(out).unwrap();
        strip(&mut v);
        return v.to_string();
    }
    let timed = |t: &str| {
        t.split_once('.').is_some_and(|(a, b)| {
            !a.is_empty()
                && a.bytes().all(|c| c.is_ascii_digit())
                && b.len() == 3
                && b.bytes().all(|c| c.is_ascii_digit())
        })
    };
    String::from_utf8_lossy(out)
        .lines()
        .map(|l| {
            l.split_whitespace()
                .map(|t| if timed(t) { "#" } else { t })
                .collect::<Vec<_>>()
                .join(" ")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn info_describes_mco_and_pop_files_as_their_own_commands_do() {
    let dir = tempfile::tempdir().unwrap();
    let mco = dir.path().join("Bunny.MCO").display().to_string();
    let pop = dir.path().join("bunny.pop").display().to_string();
    let b = bunny();
    let made = lodkit(&["-q", "mco", "build", &b, "-o", &mco, "--resolution", "16"]);
    assert!(made.status.success(), "{}", stderr(&made));
    let made = lodkit(&["-q", "pop", "encode", &b, "-o", &pop, "--depth", "5"]);
    assert!(made.status.success(), "{}", stderr(&made));
    for (file, own) in [(&mco, ["mco", "info"]), (&pop, ["pop", "stats"])] {
        for json in [false, true] {
            let flag: &[&str] = if json { &["--json"] } else { &[] };
            let a = lodkit(&[&["info", file.as_str()], flag].concat());
            assert!(a.status.success(), "{file}: {}", stderr(&a));
            let b = lodkit(&[&own[..], &[file.as_str()], flag].concat());
            assert!(b.status.success(), "{file}: {}", stderr(&b));
            assert_eq!(
                without_timings(&a.stdout, json),
                without_timings(&b.stdout, json),
                "{file} --json {json}"
            );
            assert!(!a.stdout.is_empty());
        }
    }
    // A file that is not what its extension says: one line naming it, exit 1.
    for name in ["broken.mco", "broken.pop"] {
        let f = dir.path().join(name);
        std::fs::write(&f, b"not a model").unwrap();
        let o = lodkit(&["-q", "info", f.to_str().unwrap()]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{name}: {e}");
        assert_eq!(e.trim_end().lines().count(), 1, "{name}: {e}");
        assert!(e.contains(name) && !e.contains("panicked"), "{name}: {e}");
    }
}

#[test]
fn usage_errors_exit_2_and_bad_input_exits_1() {
    assert_eq!(lodkit(&["info"]).status.code(), Some(2));
    assert_eq!(lodkit(&["frobnicate"]).status.code(), Some(2));
    let o = lodkit(&["info", "/nonexistent/file.ply"]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("/nonexistent/file.ply") && e.lines().count() == 1,
        "{e}"
    );
    let o = lodkit(&["info", "notes.docx"]);
    assert_eq!(o.status.code(), Some(1));
}

#[test]
fn every_malformed_file_exits_1_with_one_line_and_no_panic() {
    let dir = repo().join("tests/malformed");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e != "md"))
        .collect();
    files.sort();
    assert!(files.len() >= 30, "corpus has only {} files", files.len());
    for f in files {
        let o = lodkit(&["info", f.to_str().unwrap()]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{}: {e}", f.display());
        assert!(!e.contains("panicked"), "{}: {e}", f.display());
        assert_eq!(e.trim_end().lines().count(), 1, "{}: {e}", f.display());
        let name = f.file_name().unwrap().to_str().unwrap();
        assert!(
            e.contains(name),
            "{}: message does not name the file: {e}",
            f.display()
        );
    }
}

#[test]
fn convert_keeps_the_mesh_across_formats() {
    let dir = tempfile::tempdir().unwrap();
    let mut last = bunny();
    for ext in ["obj", "stl", "glb", "ply"] {
        let out = dir
            .path()
            .join(format!("bunny.{ext}"))
            .display()
            .to_string();
        let o = lodkit(&["-q", "convert", &last, &out]);
        assert!(o.status.success(), "{ext}: {}", stderr(&o));
        let o = lodkit(&["info", "--json", &out]);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["faces"], 69451, "{ext}");
        last = out;
    }
    // Writing a point cloud to a mesh-only format is refused, not faked.
    let cloud = dir.path().join("bunny.xyz").display().to_string();
    assert!(
        lodkit(&["-q", "convert", &bunny(), &cloud])
            .status
            .success()
    );
    let o = lodkit(&[
        "convert",
        &cloud,
        dir.path().join("x.stl").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(stderr(&o).contains("x.stl"), "{}", stderr(&o));
}

/// A small closed mesh (an octahedron, 2 units across) written as OBJ.
fn octahedron(dir: &Path) -> String {
    let p = dir.join("octahedron.obj");
    std::fs::write(
        &p,
        "v 1 0 0\nv -1 0 0\nv 0 1 0\nv 0 -1 0\nv 0 0 1\nv 0 0 -1\n\
         f 1 3 5\nf 3 2 5\nf 2 4 5\nf 4 1 5\nf 3 1 6\nf 2 3 6\nf 4 2 6\nf 1 4 6\n",
    )
    .unwrap();
    p.display().to_string()
}

/// One test per option value that must be refused at parse time: exit 2,
/// one message naming the option's allowed range, nothing written.
macro_rules! refused {
    ($name:ident, [$($arg:expr),* $(,)?], [$($word:expr),* $(,)?]) => {
        #[test]
        fn $name() {
            // `@bunny`: the shipped bunny; `@out`: a folder in a scratch dir.
            let dir = tempfile::tempdir().unwrap();
            let out = dir.path().join("out").display().to_string();
            let bunny = bunny();
            let args: Vec<&str> = [$($arg),*]
                .into_iter()
                .map(|a| match a {
                    "@bunny" => bunny.as_str(),
                    "@out" => out.as_str(),
                    a => a,
                })
                .collect();
            let o = lodkit(&args);
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(2), "{e}");
            $(assert!(e.contains($word), "expected {:?} in: {e}", $word);)*
            assert!(std::fs::read_dir(dir.path()).unwrap().next().is_none(), "wrote something");
        }
    };
}

mod refused_at_parse_time {
    use super::*;

    // Issue 15 item 6: out of range is a usage error naming the range.
    refused!(
        simplify_ratio_above_one,
        ["simplify", "@bunny", "-o", "x.ply", "--ratio", "2"],
        ["--ratio", "[0, 1]"]
    );
    refused!(
        lods_zero_levels,
        ["lods", "@bunny", "--out", "@out", "--levels", "0"],
        ["--levels", "1..=32"]
    );
    refused!(
        mco_view_with_two_numbers,
        ["mco", "extract", "m.mco", "-o", "x.ply", "--view", "0,0.1"],
        ["--view", "X,Y,Z"]
    );
    refused!(
        mco_look_at_without_view,
        [
            "mco",
            "extract",
            "m.mco",
            "-o",
            "x.ply",
            "--lod",
            "1",
            "--look-at",
            "0,0,0"
        ],
        ["--look-at", "--view"]
    );
    refused!(
        mco_fov_out_of_range,
        [
            "mco", "extract", "m.mco", "-o", "x.ply", "--view", "0,0,1", "--fov", "180"
        ],
        ["--fov", "(0, 180)"]
    );
    refused!(
        pop_precision_below_depth,
        [
            "pop",
            "encode",
            "@bunny",
            "-o",
            "x.pop",
            "--depth",
            "6",
            "--precision",
            "4"
        ],
        ["--precision 4", "6..=16"]
    );
    refused!(
        pop_encode_to_ply,
        ["pop", "encode", "@bunny", "-o", "x.ply"],
        ["x.ply", ".pop"]
    );
    refused!(
        simplify_to_points,
        ["simplify", "@bunny", "-o", "x.xyz", "--target", "100"],
        ["x.xyz", ".ply"]
    );
    refused!(
        pop_decode_mesh_to_points,
        ["pop", "decode", "b.pop", "-o", "x.xyz"],
        ["x.xyz", "--points"]
    );
    refused!(
        mco_build_to_ply,
        ["mco", "build", "@bunny", "-o", "x.ply"],
        ["x.ply", ".mco"]
    );
    refused!(
        relax_below_without_outer_thinning,
        [
            "pop",
            "encode",
            "@bunny",
            "-o",
            "x.pop",
            "--relax-below",
            "5"
        ],
        ["--outer-thinning"]
    );
    refused!(
        placement_column_in_baseline,
        [
            "pop",
            "encode",
            "@bunny",
            "-o",
            "x.pop",
            "--mode",
            "baseline",
            "--placement",
            "column"
        ],
        ["--placement", "baseline"]
    );
    refused!(
        decimate_with_points,
        [
            "pop",
            "decode",
            "b.pop",
            "-o",
            "x.xyz",
            "--points",
            "--decimate",
            "0.5"
        ],
        ["--decimate", "--points"]
    );
    refused!(
        ascii_for_glb,
        ["convert", "@bunny", "x.glb", "--ascii"],
        ["--ascii", ".ply"]
    );

    // Issue 14 item 2: every option that sizes memory has an upper bound.
    refused!(
        huge_heap,
        [
            "simplify",
            "@bunny",
            "-o",
            "x.ply",
            "--target",
            "10",
            "--heap-size",
            "1000000000000"
        ],
        ["--heap-size", "1..=16777216"]
    );
    refused!(
        huge_level_count,
        ["lods", "@bunny", "--out", "@out", "--levels", "100000000"],
        ["--levels", "1..=32"]
    );
    refused!(
        huge_pop_depth,
        ["pop", "encode", "@bunny", "-o", "x.pop", "--depth", "16"],
        ["--depth", "1..=12"]
    );
    refused!(
        huge_render_size,
        ["render", "@bunny", "-o", "x.png", "--size", "100000x10"],
        ["--size", "1..=8192"]
    );
    refused!(
        huge_mco_resolution,
        [
            "mco",
            "build",
            "@bunny",
            "-o",
            "x.mco",
            "--resolution",
            "2000"
        ],
        ["--resolution", "2..=512"]
    );
    refused!(
        huge_sample_count,
        ["compare", "@bunny", "@bunny", "--samples", "100000000000"],
        ["--samples", "1..=10000000"]
    );
    refused!(
        huge_scan,
        [
            "scan",
            "@bunny",
            "--out",
            "@out",
            "--views",
            "360",
            "--size",
            "4096x4096"
        ],
        ["--views", "33554432"]
    );

    // Issue 14 item 9: non-finite and out-of-domain values.
    refused!(
        max_error_nan,
        ["simplify", "@bunny", "-o", "x.ply", "--max-error", "nan"],
        ["--max-error", "finite"]
    );
    refused!(
        prune_nan,
        [
            "simplify", "@bunny", "-o", "x.ply", "--target", "10", "--prune", "nan"
        ],
        ["--prune", "[0, 1)"]
    );
    refused!(
        prune_two,
        [
            "simplify", "@bunny", "-o", "x.ply", "--target", "10", "--prune", "2"
        ],
        ["--prune", "[0, 1)"]
    );
    refused!(
        normal_weight_nan,
        [
            "simplify",
            "@bunny",
            "-o",
            "x.ply",
            "--target",
            "10",
            "--normal-weight",
            "nan"
        ],
        ["--normal-weight", "[0, 1000000]"]
    );
    refused!(
        weld_nan,
        ["convert", "@bunny", "x.obj", "--weld", "nan"],
        ["--weld", "finite"]
    );
    refused!(
        decimate_nan,
        ["pop", "decode", "b.pop", "-o", "x.ply", "--decimate", "nan"],
        ["--decimate", "[0, 1]"]
    );
    refused!(
        scan_elevation_nan,
        ["scan", "@bunny", "--out", "@out", "--elevation", "nan"],
        ["--elevation", "[-90, 90]"]
    );
    refused!(
        scan_noise_inf,
        ["scan", "@bunny", "--out", "@out", "--noise", "inf"],
        ["--noise", "finite"]
    );
    refused!(
        tolerance_zero,
        [
            "mco",
            "extract",
            "m.mco",
            "-o",
            "x.ply",
            "--view",
            "0,0,1",
            "--tolerance",
            "0"
        ],
        ["--tolerance", "> 0"]
    );
    refused!(
        ratio_overflowing_f32,
        ["simplify", "@bunny", "-o", "x.ply", "--max-error", "1e39"],
        ["--max-error", "finite"]
    );
}

#[test]
fn a_legal_pop_depth_too_big_for_the_mesh_is_refused_before_work() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron(dir.path());
    let out = dir.path().join("o.pop");
    let o = lodkit(&[
        "pop",
        "encode",
        &mesh,
        "-o",
        out.to_str().unwrap(),
        "--depth",
        "10",
    ]);
    let e = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("depth 10") && e.contains("octahedron.obj") && e.contains("or less fits"),
        "{e}"
    );
    assert!(!out.exists());
}

#[test]
fn a_raised_pop_precision_is_said() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron(dir.path());
    let out = dir.path().join("o.pop");
    let o = lodkit(&[
        "pop",
        "encode",
        &mesh,
        "-o",
        out.to_str().unwrap(),
        "--precision",
        "1",
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("precision raised from --precision 1"), "{e}");
}

#[test]
fn convert_to_points_says_it_drops_the_faces() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron(dir.path());
    let out = dir.path().join("o.xyz");
    let o = lodkit(&["convert", &mesh, out.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("6 points") && e.contains("8 faces are dropped"),
        "{e}"
    );
}

#[test]
fn convert_takes_dash_o_like_every_command_and_prints_json() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron(dir.path());
    let out = dir.path().join("o.xyz");
    let o = lodkit(&["convert", &mesh, "-o", out.to_str().unwrap(), "--json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["written"], "point cloud");
    assert_eq!(v["vertices"], 6);
    assert_eq!(v["faces_dropped"], 8);
    assert_eq!(v["bytes"], std::fs::metadata(&out).unwrap().len());
    // Both spellings at once, or neither, is a usage error.
    let both = lodkit(&["convert", &mesh, "a.ply", "-o", "b.ply"]);
    assert_eq!(both.status.code(), Some(2), "{}", stderr(&both));
    let neither = lodkit(&["convert", &mesh]);
    assert_eq!(neither.status.code(), Some(2), "{}", stderr(&neither));
}

#[test]
fn a_txt_input_says_it_is_read_as_xyz() {
    let dir = tempfile::tempdir().unwrap();
    let txt = dir.path().join("cloud.txt");
    std::fs::write(&txt, "0 0 0\n1 0 0\n0 1 0\n").unwrap();
    let o = lodkit(&["info", txt.to_str().unwrap()]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(e.contains("cloud.txt as XYZ points"), "{e}");
}

#[test]
fn errors_name_the_files_path() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron(dir.path());
    let missing = dir.path().join("sub/missing.ply");
    let o = lodkit(&["compare", &mesh, missing.to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains(missing.to_str().unwrap()),
        "{}",
        stderr(&o)
    );
    let o = lodkit(&[
        "lods",
        missing.to_str().unwrap(),
        "--out",
        dir.path().to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains(missing.to_str().unwrap()),
        "{}",
        stderr(&o)
    );
}

#[test]
fn dash_o_is_a_file_and_dash_dash_out_a_folder_in_every_command() {
    // The help of each command that writes a folder shows --out DIR and
    // no -o; those that write one file show -o.
    for (cmd, folder) in [
        (&["lods"][..], true),
        (&["scan"], true),
        (&["simplify"], false),
        (&["pop", "encode"], false),
        (&["pop", "decode"], false),
        (&["mco", "build"], false),
        (&["mco", "extract"], false),
        (&["render"], false),
    ] {
        let mut args = cmd.to_vec();
        args.push("--help");
        let o = lodkit(&args);
        let h = String::from_utf8_lossy(&o.stdout).into_owned();
        if folder {
            assert!(
                h.contains("--out <DIR>") && !h.contains("-o,"),
                "{cmd:?}: {h}"
            );
        } else {
            assert!(h.contains("-o, --output"), "{cmd:?}: {h}");
        }
    }
}

#[test]
fn off_a_terminal_long_stages_print_a_line_each_unless_quiet() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = octahedron(dir.path());
    let out = dir.path().join("l");
    let args = [
        "lods",
        &mesh,
        "--out",
        out.to_str().unwrap(),
        "--levels",
        "1",
        "--samples",
        "1000",
    ];
    let o = lodkit(&args);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("level 1: ") && e.contains("measured mean"),
        "{e}"
    );
    let mut quiet = vec!["-q"];
    quiet.extend_from_slice(&args);
    let o = lodkit(&quiet);
    assert!(o.status.success());
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
    let o = lodkit(&["compare", &mesh, &mesh, "--samples", "1000"]);
    assert!(o.status.success());
    assert!(
        stderr(&o).contains("measuring (1000 samples"),
        "{}",
        stderr(&o)
    );
    let o = lodkit(&["-q", "compare", &mesh, &mesh, "--samples", "1000"]);
    assert!(stderr(&o).is_empty(), "{}", stderr(&o));
}

/// An output never replaces an input: `render in.ply -o in.ply` is
/// refused by its extension, `-o` a link (symbolic or hard) to the input
/// as the input itself (exit 2); `convert` and `simplify` onto their
/// input, through any path or link, are refused before writing (exit 1,
/// one line naming the path). The input keeps its bytes every time.
#[test]
fn an_output_never_replaces_an_input() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n).display().to_string();
    let input = d("in.ply");
    let o = lodkit(&["generate", "blob", "--triangles", "2000", "-o", &input]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = std::fs::read(&input).unwrap();
    std::os::unix::fs::symlink(&input, d("sym.png")).unwrap();
    std::fs::hard_link(&input, d("hard.png")).unwrap();
    std::os::unix::fs::symlink(&input, d("sym.ply")).unwrap();
    std::fs::hard_link(&input, d("hard.ply")).unwrap();
    for out in ["in.ply", "sym.png", "hard.png"] {
        let o = lodkit(&["render", &input, "-o", &d(out), "--size", "32x32"]);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{out}: {e}");
        let says = if out == "in.ply" {
            "is written as .png"
        } else {
            "is the input"
        };
        assert!(e.contains(says), "{out}: {e}");
    }
    let dotted = format!("{}/./in.ply", dir.path().display());
    for out in [input.as_str(), &dotted, &d("sym.ply"), &d("hard.ply")] {
        for cmd in [
            vec!["convert", &input, "-o", out],
            vec!["simplify", &input, "-o", out, "--ratio", "0.5"],
        ] {
            let o = lodkit(&cmd);
            let e = stderr(&o);
            assert_eq!(o.status.code(), Some(1), "{cmd:?}: {e}");
            assert!(
                e.contains("is an input of this run") && e.trim().lines().count() == 1,
                "{e}"
            );
        }
    }
    assert_eq!(std::fs::read(&input).unwrap(), before);
    // Another output is written as before.
    let o = lodkit(&["render", &input, "-o", &d("pic.png"), "--size", "32x32"]);
    assert!(o.status.success(), "{}", stderr(&o));
}

/// `build --out DIR` replaces DIR only when it is provably an earlier
/// build: a folder of the user's files (a report.md among them) is
/// refused, and so is an earlier build that holds the input, or whose
/// files changed (one added, one resized, a link), each with one line
/// (exit 2), the folder left as it was. An untouched earlier build is
/// replaced.
#[test]
fn build_replaces_only_a_folder_that_is_provably_an_earlier_build() {
    let dir = tempfile::tempdir().unwrap();
    let d = |n: &str| dir.path().join(n);
    let input = d("blob.ply");
    let o = lodkit(&["generate", "blob", "--triangles", "2000", "-o", s(&input)]);
    assert!(o.status.success(), "{}", stderr(&o));
    let build = |input: &Path, out: &Path| {
        lodkit(&[
            "-q",
            "build",
            s(input),
            "--out",
            s(out),
            "--levels",
            "1",
            "--no-measure",
        ])
    };
    let refused = |input: &Path, out: &Path, says: &str| {
        let before = tree(out);
        let o = build(input, out);
        let e = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{e}");
        assert!(e.contains(says) && e.trim().lines().count() == 1, "{e}");
        assert_eq!(tree(out), before, "{e}");
        for f in std::fs::read_dir(dir.path()).unwrap() {
            let n = f.unwrap().file_name().to_string_lossy().into_owned();
            assert!(!n.contains(".lodkit-"), "left behind: {n}");
        }
    };
    // The user's folder: a report.md is no proof.
    let user = d("thesis");
    std::fs::create_dir_all(user.join("photos")).unwrap();
    std::fs::write(user.join("report.md"), "my report").unwrap();
    std::fs::write(user.join("thesis.tex"), "my thesis").unwrap();
    std::fs::write(user.join("photos/a.jpg"), "a photo").unwrap();
    refused(&input, &user, "not a lodkit build");

    let out = d("out");
    let o = build(&input, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    let files = tree(&out);
    assert!(
        files.contains(&".lodkit-build.json".to_string()),
        "{files:?}"
    );
    // Its own input: a file of the build, listed in its manifest.
    refused(&out.join("blob.ply"), &out, "holds the input");
    // Rebuilt over itself: replaced.
    let o = build(&input, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(tree(&out), files);
    // Changed since: a file added, a file resized, a link, a folder.
    std::fs::write(out.join("notes.txt"), "mine").unwrap();
    refused(&input, &out, "notes.txt is not one of its files");
    std::fs::remove_file(out.join("notes.txt")).unwrap();
    std::fs::write(out.join("report.md"), "edited").unwrap();
    refused(&input, &out, "report.md has changed");
    std::fs::write(out.join("report.md"), "").unwrap();
    let o = build(&input, &out);
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    std::fs::remove_dir_all(&out).unwrap();
    let o = build(&input, &out);
    assert!(o.status.success(), "{}", stderr(&o));
    std::os::unix::fs::symlink(&input, out.join("link.ply")).unwrap();
    refused(&input, &out, "link.ply is a link");
    std::fs::remove_file(out.join("link.ply")).unwrap();
    std::fs::create_dir(out.join("mine")).unwrap();
    refused(&input, &out, "mine/ is not one of its folders");
}
