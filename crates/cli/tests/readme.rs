//! The README's console examples, run as written with `trycmd`: every
//! command in a ```` ```console ```` block of `README.md` runs against this
//! build of `lodkit`, and its output must match the block line for line
//! (`...` stands for omitted lines, `[..]` for the rest of a line: wall
//! times only), so no number the README shows can go stale.
//!
//! The examples run in a scratch directory holding a copy of the shipped
//! `data/` files they read, so they write nothing into the repository.
//! trycmd drops the last newline of each expected output (its files end
//! each output with a blank line); the README's blocks don't, so the copy
//! gets that blank line after each output ([`with_trycmd_spacing`]): line
//! numbers in a failure are the copy's, the diff is the README's.
//! On a mismatch trycmd prints the diff; fix the README, not the test.
#![cfg(unix)] // the examples use `cat`

use std::path::Path;

mod common;
use common::repo;

/// The files under `data/` that the README's examples read.
const DATA: &[&str] = &[
    "data/models/stanford_bunny.ply",
    "data/reference/stanford_bunny_simplified.ply",
];

#[test]
fn readme_console_examples_print_what_the_readme_shows() {
    let scratch = tempfile::tempdir().unwrap();
    let case = scratch.path().join("README.md");
    let readme = std::fs::read_to_string(repo().join("README.md")).unwrap();
    std::fs::write(&case, with_trycmd_spacing(&readme)).unwrap();
    // trycmd's layout: `README.in/` is copied into a fresh sandbox where the
    // commands run; an (empty) `README.out/` turns the sandbox on.
    let input = scratch.path().join("README.in");
    for file in DATA {
        let to = input.join(file);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(repo().join(file), &to).unwrap();
    }
    std::fs::create_dir(scratch.path().join("README.out")).unwrap();
    let cat = ["/bin/cat", "/usr/bin/cat"]
        .into_iter()
        .find(|p| Path::new(p).exists())
        .expect("cat");
    trycmd::TestCases::new()
        .register_bin("lodkit", Path::new(env!("CARGO_BIN_EXE_lodkit")))
        .register_bin("cat", Path::new(cat))
        .case(&case)
        .run();
}

/// `readme` with an empty line after each command's output in a
/// `console` block (before the next `$ ` line or the closing fence). Every
/// fence in the README carries a language, so a bare one closes a block.
fn with_trycmd_spacing(readme: &str) -> String {
    let mut out = String::with_capacity(readme.len() + 1024);
    let (mut in_console, mut in_step) = (false, false);
    for line in readme.lines() {
        let fence = line.starts_with("```");
        if in_step && (fence || line.starts_with("$ ")) {
            out.push('\n');
        }
        if fence {
            in_console = !in_console && line.trim_start_matches('`').trim() == "console";
            in_step = false;
        } else if in_console && line.starts_with("$ ") {
            in_step = true;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}
