//! End-to-end tests of `lodkit pop encode|decode|stats`.

mod common;
use common::{bunny, lodkit, stderr};

#[test]
fn encode_decode_and_stats_the_bunny() {
    let dir = tempfile::tempdir().unwrap();
    let pop = dir.path().join("bunny.pop");
    let pop_s = pop.to_str().unwrap();
    for mode in ["baseline", "entropy"] {
        let o = lodkit(&[
            "pop",
            "encode",
            &bunny(),
            "-o",
            pop_s,
            "--depth",
            "5",
            "--mode",
            mode,
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stderr(&o).contains("bits/particle"), "{}", stderr(&o));
        let mesh = dir.path().join("l4.ply");
        let o = lodkit(&[
            "-q",
            "pop",
            "decode",
            pop_s,
            "--level",
            "4",
            "-o",
            mesh.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = lodkit(&["info", mesh.to_str().unwrap(), "--json"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = lodkit(&["pop", "stats", pop_s, "--json"]);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["depth"], 5);
        assert_eq!(v["levels"].as_array().unwrap().len(), 6);
        assert_eq!(v["mode"], mode);
    }
}

/// The bunny encoded at depth 5 into `dir/bunny.pop`; its bytes.
fn bunny_pop(dir: &std::path::Path) -> Vec<u8> {
    let pop = dir.join("bunny.pop");
    let o = lodkit(&[
        "-q",
        "pop",
        "encode",
        &bunny(),
        "-o",
        pop.to_str().unwrap(),
        "--depth",
        "5",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    std::fs::read(&pop).unwrap()
}

#[test]
fn a_stream_cut_inside_a_chunk_decodes_its_complete_chunks_and_says_where_it_stopped() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = bunny_pop(dir.path());
    let cut = dir.path().join("cut.pop");
    std::fs::write(&cut, &bytes[..bytes.len() / 4]).unwrap();
    let out = dir.path().join("x.ply");
    let o = lodkit(&[
        "pop",
        "decode",
        cut.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    let e = stderr(&o);
    assert!(o.status.success(), "{e}");
    assert!(
        e.contains("cut.pop: stopped at byte") && e.contains("complete chunks before it"),
        "{e}"
    );
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    // The default level is the finest the prefix holds, below the stream's depth.
    assert_eq!(v["level"], v["finest_level"]);
    assert!(v["level"].as_u64().unwrap() < 5, "{v}");
    assert!(v["cut"]["offset"].as_u64().unwrap() <= bytes.len() as u64 / 4);
    assert!(out.exists());
}

#[test]
fn strict_refuses_a_cut_stream_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = bunny_pop(dir.path());
    let cut = dir.path().join("cut.pop");
    std::fs::write(&cut, &bytes[..bytes.len() - 3]).unwrap();
    let out = dir.path().join("x.ply");
    let o = lodkit(&[
        "pop",
        "decode",
        cut.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--strict",
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(
        e.contains("cut.pop") && e.contains("truncated") && e.contains("--strict"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(!out.exists());
}

#[test]
fn a_level_past_what_a_prefix_holds_is_a_usage_error_naming_the_range() {
    let dir = tempfile::tempdir().unwrap();
    let bytes = bunny_pop(dir.path());
    let cut = dir.path().join("cut.pop");
    std::fs::write(&cut, &bytes[..bytes.len() / 4]).unwrap();
    let o = lodkit(&[
        "pop",
        "decode",
        cut.to_str().unwrap(),
        "--level",
        "5",
        "-o",
        dir.path().join("x.ply").to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(2));
    let e = stderr(&o);
    assert!(
        e.contains("--level 5 is outside 0..=") && e.contains("cut.pop"),
        "{e}"
    );
}

#[test]
fn the_help_examples_decode_the_bunny() {
    let dir = tempfile::tempdir().unwrap();
    let pop = dir.path().join("bunny.pop");
    let o = lodkit(&["-q", "pop", "encode", &bunny(), "-o", pop.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let help = String::from_utf8_lossy(&lodkit(&["pop", "decode", "--help"]).stdout).into_owned();
    let mut ran = 0;
    for line in help.lines().map(str::trim) {
        let Some(cmd) = line.strip_prefix("lodkit pop decode ") else {
            continue;
        };
        let cmd = cmd.split('#').next().unwrap();
        let args: Vec<String> = cmd
            .split_whitespace()
            .map(|a| match a {
                "bunny.pop" => pop.display().to_string(),
                a if a.ends_with(".ply") => dir.path().join(a).display().to_string(),
                a => a.to_string(),
            })
            .collect();
        let mut all = vec!["pop", "decode"];
        all.extend(args.iter().map(String::as_str));
        let o = lodkit(&all);
        assert!(o.status.success(), "{line}: {}", stderr(&o));
        ran += 1;
    }
    assert!(ran >= 3, "{help}");
}

#[test]
fn encode_and_decode_print_json() {
    let dir = tempfile::tempdir().unwrap();
    let pop = dir.path().join("bunny.pop");
    let o = lodkit(&[
        "pop",
        "encode",
        &bunny(),
        "-o",
        pop.to_str().unwrap(),
        "--depth",
        "5",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["depth"], 5);
    assert!(v["particles"].as_u64().unwrap() > 0);
    assert!(v["total_bytes"].as_u64().unwrap() > 0);
    let o = lodkit(&[
        "pop",
        "decode",
        pop.to_str().unwrap(),
        "-o",
        dir.path().join("p.xyz").to_str().unwrap(),
        "--points",
        "--json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(v["level"], 5);
    assert!(v["cut"].is_null() && v["triangles"].is_null(), "{v}");
}

#[test]
fn outer_thinning_reports_the_relax_level_it_chose_or_was_given() {
    let dir = tempfile::tempdir().unwrap();
    let pop = dir.path().join("bunny.pop");
    let pop_s = pop.to_str().unwrap();
    let bunny = bunny();
    let encode = |extra: &[&str]| {
        let mut args = vec!["pop", "encode", bunny.as_str(), "-o", pop_s, "--depth", "6"];
        args.extend_from_slice(extra);
        lodkit(&args)
    };
    let o = encode(&["--outer-thinning"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("outer thinning relaxed below level 4"),
        "{}",
        stderr(&o)
    );
    let o = encode(&["--outer-thinning", "--relax-below", "5"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("relaxed below level 5"),
        "{}",
        stderr(&o)
    );
    let o = encode(&["--outer-thinning", "--relax-below", "often"]);
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("expected `auto` or a level"),
        "{}",
        stderr(&o)
    );
}

/// `n` points on a bumpy unit sphere (a Fibonacci spiral), coloured, as
/// an ASCII PLY point cloud: an unorganised scan's samples.
fn write_cloud(path: &std::path::Path, n: usize) {
    let mut s = format!(
        "ply\nformat ascii 1.0\nelement vertex {n}\nproperty float x\nproperty float y\nproperty float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
    );
    for i in 0..n {
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let r = (1.0 - z * z).sqrt();
        let a = i as f64 * 2.399963229728653;
        let (x, y) = (r * a.cos(), r * a.sin());
        let k = 1.0 + 0.08 * (5.0 * x).sin() * (4.0 * y).sin() * (3.0 * z).sin();
        let c = |v: f64| (40.0 + 100.0 * (v + 1.0)) as u8;
        s += &format!(
            "{:.6} {:.6} {:.6} {} {} {}\n",
            x * k,
            y * k,
            z * k,
            c(x),
            c(y),
            c(z)
        );
    }
    std::fs::write(path, s).unwrap();
}

/// A point cloud's stream codes its reconstructed surface at about one
/// particle per sample (within 2× of the points), coloured, and its
/// finest level triangulates; `--raw` codes the samples as they are.
#[test]
fn a_cloud_is_coded_from_its_surface_at_its_detail() {
    let dir = tempfile::tempdir().unwrap();
    let cloud = dir.path().join("cloud.ply");
    let n = 30_000;
    write_cloud(&cloud, n);
    for (raw, source) in [(false, "surface"), (true, "samples")] {
        let pop = dir.path().join(format!("{source}.pop"));
        let mut args = vec![
            "-q",
            "pop",
            "encode",
            cloud.to_str().unwrap(),
            "-o",
            pop.to_str().unwrap(),
            "--json",
        ];
        if raw {
            args.push("--raw");
        }
        let o = lodkit(&args);
        assert!(o.status.success(), "{}", stderr(&o));
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(v["source"], source);
        let particles = v["particles"].as_u64().unwrap() as usize;
        if !raw {
            assert!(
                (n / 2..=2 * n).contains(&particles),
                "{particles} particles for {n} points"
            );
        }
        let mesh = dir.path().join(format!("{source}.ply"));
        let o = lodkit(&[
            "-q",
            "pop",
            "decode",
            pop.to_str().unwrap(),
            "-o",
            mesh.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", stderr(&o));
        let o = lodkit(&["info", mesh.to_str().unwrap(), "--json"]);
        let v: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert!(v["faces"].as_u64().unwrap() > 0, "{v}");
        if !raw {
            let attrs = v["attributes"].to_string();
            assert!(attrs.contains("colors"), "{v}");
        }
    }
}
