//! Every broken image set of `tests/malformed/calibrations/` (made by
//! `scripts/make_malformed_calibrations.py`) through every command that
//! reads one: `lodkit info`, `lodkit pop encode --silhouettes` and
//! `lodkit build` each exit 1 with one line on stderr naming the
//! calibration file and, where one camera is at fault, that camera (and,
//! where `expect.txt` has a `says:` line, that message); and write
//! nothing.

mod common;

use std::process::Command;

#[test]
fn every_malformed_image_set_fails_with_one_line_naming_the_file_and_the_camera() {
    let root = common::repo().join("tests/malformed/calibrations");
    let mut cases: Vec<_> = std::fs::read_dir(&root)
        .expect("tests/malformed/calibrations exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    cases.sort();
    assert!(cases.len() >= 20, "only {} cases", cases.len());
    let mut failures = Vec::new();
    for case in &cases {
        let expect = std::fs::read_to_string(case.join("expect.txt")).unwrap();
        let mut lines = expect.lines();
        let file = case.join(lines.next().unwrap());
        let camera = lines.next().unwrap_or("").trim().to_string();
        // `carving`: the set reads, only carving finds the fault;
        // `says: TEXT`: the text the one line must hold (its message).
        let rest: Vec<&str> = lines.collect();
        let carving_only = rest.iter().any(|l| l.trim() == "carving");
        let says = rest
            .iter()
            .find_map(|l| l.strip_prefix("says: "))
            .map(str::trim);
        let file_name = file.file_name().unwrap().to_string_lossy().into_owned();
        // A COLMAP model's errors name the file of the faulty line.
        let names_file = |l: &str| {
            l.contains(&file_name) || (file_name == "cameras.txt" && l.contains("images.txt"))
        };
        let out = tempfile::tempdir().unwrap();
        let f = file.display().to_string();
        let o = out.path().display().to_string();
        for args in [
            vec!["info".to_string(), f.clone()],
            vec![
                "pop".into(),
                "encode".into(),
                "--silhouettes".into(),
                f.clone(),
                "-o".into(),
                format!("{o}/p.pop"),
                "--depth".into(),
                "4".into(),
            ],
            vec![
                "build".into(),
                f.clone(),
                "--out".into(),
                format!("{o}/b"),
                "--no-measure".into(),
            ],
        ] {
            if carving_only && args[0] == "info" {
                continue;
            }
            let shown = format!(
                "{} lodkit {}",
                case.file_name().unwrap().to_string_lossy(),
                args[0]
            );
            let r = Command::new(env!("CARGO_BIN_EXE_lodkit"))
                .args(&args)
                .env("LODKIT_VIEWER", "skip")
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&r.stderr);
            let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
            if r.status.code() != Some(1) {
                failures.push(format!("{shown}: exit {:?}: {err}", r.status.code()));
            } else if lines.len() != 1 {
                failures.push(format!("{shown}: {} lines: {err}", lines.len()));
            } else if !names_file(lines[0]) || !lines[0].contains(&camera) {
                failures.push(format!(
                    "{shown}: does not name {file_name} and '{camera}': {err}"
                ));
            } else if let Some(text) = says
                && !lines[0].contains(text)
            {
                failures.push(format!("{shown}: does not say '{text}': {err}"));
            }
            let written: Vec<_> = std::fs::read_dir(out.path()).unwrap().collect();
            if !written.is_empty() {
                failures.push(format!("{shown}: wrote into the output folder"));
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
