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
