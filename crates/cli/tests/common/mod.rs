//! Helpers shared by the CLI's end-to-end tests.
#![allow(dead_code)] // each test binary uses its own subset

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

/// Runs the built `lodkit` binary with `args`.
pub fn lodkit(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lodkit"))
        .args(args)
        .output()
        .expect("run lodkit")
}

/// The repository root.
pub fn repo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// The shipped Stanford bunny's path.
pub fn bunny() -> String {
    repo()
        .join("data/models/stanford_bunny.ply")
        .display()
        .to_string()
}

/// What a run printed on stderr.
pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Every file under `dir`, by relative path, with its bytes.
pub fn files(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                let rel = p.strip_prefix(dir).unwrap().display().to_string();
                out.push((rel, std::fs::read(&p).unwrap()));
            }
        }
    }
    out.sort();
    out
}

/// `lodkit tiles INPUT --out OUT EXTRA...`.
pub fn tiles(input: &str, out: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["tiles", input, "--out", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    lodkit(&args)
}
