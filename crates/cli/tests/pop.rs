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

#[test]
fn a_cut_stream_is_a_one_line_error_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let pop = dir.path().join("bunny.pop");
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
    let bytes = std::fs::read(&pop).unwrap();
    let cut = dir.path().join("cut.pop");
    std::fs::write(&cut, &bytes[..bytes.len() - 3]).unwrap();
    let out = dir.path().join("x.ply");
    let o = lodkit(&[
        "pop",
        "decode",
        cut.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let e = stderr(&o);
    assert!(e.contains("cut.pop") && e.contains("truncated"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
    assert!(!out.exists());
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
