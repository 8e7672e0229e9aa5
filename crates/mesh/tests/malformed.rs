//! Every file of the malformed-input corpus (`tests/malformed/`, made by
//! `scripts/make_malformed_corpus.py`) must be refused by
//! `lodkit_mesh::io::load` (a `.conf` by `io::conf::load_scans`) with a
//! one-line error naming the file, and never make it panic.

use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::PathBuf;

fn corpus_dir() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/malformed")
}

#[test]
fn every_malformed_file_is_a_clean_one_line_error() {
    let mut files: Vec<PathBuf> = std::fs::read_dir(corpus_dir())
        .expect("tests/malformed exists (run scripts/make_malformed_corpus.py)")
        .map(|e| e.unwrap().path())
        .filter(|p| p.file_name().is_some_and(|n| n != "README.md"))
        .collect();
    files.sort();
    assert!(
        files.len() >= 30,
        "the corpus should hold at least 30 files, it has {}",
        files.len()
    );
    let mut failures = Vec::new();
    for path in &files {
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        let load = || {
            if path.extension().is_some_and(|e| e == "conf") {
                lodkit_mesh::io::conf::load_scans(path)
                    .map(|_| lodkit_mesh::Model::Points(Default::default()))
            } else {
                lodkit_mesh::io::load(path)
            }
        };
        match catch_unwind(AssertUnwindSafe(load)) {
            Err(_) => failures.push(format!("{name}: PANICKED")),
            Ok(Ok(model)) => failures.push(format!("{name}: accepted as a {}", model.kind())),
            Ok(Err(e)) => {
                let msg = e.to_string();
                if msg.contains('\n') {
                    failures.push(format!("{name}: error is not one line: {msg:?}"));
                } else if !msg.contains(&name) {
                    failures.push(format!("{name}: error does not name the file: {msg:?}"));
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "malformed files not refused cleanly:\n{}",
        failures.join("\n")
    );
}

/// Each format has its own corpus files, so a broken format cannot hide
/// behind the others.
#[test]
fn corpus_covers_every_format() {
    let names: Vec<String> = std::fs::read_dir(corpus_dir())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    for ext in [
        "ply", "obj", "stl", "gltf", "glb", "xyz", "pts", "las", "conf",
    ] {
        let n = names
            .iter()
            .filter(|n| n.ends_with(&format!(".{ext}")))
            .count();
        assert!(n >= 3, "only {n} .{ext} files in the corpus");
    }
}
