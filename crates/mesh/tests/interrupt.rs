//! Ctrl-C in the middle of a write removes the temporary file: this test
//! runs itself again as a child that opts in, starts a write that stalls
//! half-way, and is sent SIGINT / SIGTERM while the temp
//! file exists. A folder listed with `TempGuard` goes the same way.

#![cfg(unix)]

use std::io::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

const CHILD: &str = "LODKIT_INTERRUPT_TEST_TARGET";
const CHILD_DIR: &str = "LODKIT_INTERRUPT_TEST_DIR";

/// The child: stages a folder with a file in it and never finishes.
#[test]
fn child_stager() {
    let Some(dir) = std::env::var_os(CHILD_DIR) else {
        return; // only meaningful as the child of the test below
    };
    lodkit_mesh::io::interrupt::remove_temp_files_on_signal();
    let dir = PathBuf::from(dir);
    let _guard = lodkit_mesh::io::interrupt::TempGuard::new(&dir);
    std::fs::create_dir(&dir).unwrap();
    std::fs::create_dir(dir.join("lods")).unwrap();
    std::fs::write(dir.join("lods/a.ply"), b"half").unwrap();
    std::fs::write(dir.join("ready"), b"").unwrap();
    std::thread::sleep(Duration::from_secs(60));
    panic!("the staging was not interrupted");
}

#[test]
fn sigterm_removes_a_guarded_folder() {
    if std::env::var_os(CHILD_DIR).is_some() {
        return;
    }
    let parent = tempfile::tempdir().unwrap();
    let dir = parent.path().join(".out.staging");
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "child_stager", "--nocapture", "--test-threads=1"])
        .env(CHILD_DIR, &dir)
        .spawn()
        .unwrap();
    let start = Instant::now();
    while !dir.join("ready").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no folder appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let sent = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let status = child.wait().unwrap();
    assert!(!status.success());
    assert!(!dir.exists(), "the staged folder was left behind");
}

/// The child: writes to `$CHILD` and never finishes on its own.
#[test]
fn child_writer() {
    let Some(target) = std::env::var_os(CHILD) else {
        return; // only meaningful as the child of the test below
    };
    lodkit_mesh::io::interrupt::remove_temp_files_on_signal();
    let _ = lodkit_mesh::io::write_atomic_with(Path::new(&target), |f| {
        f.write_all(b"half of the output")?;
        f.sync_all()?;
        std::thread::sleep(Duration::from_secs(60));
        Ok(())
    });
    panic!("the write was not interrupted");
}

fn temp_files(dir: &Path) -> Vec<PathBuf> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "tmp"))
        .collect()
}

fn interrupt_a_write(signal: &str, code: i32) {
    let dir = tempfile::tempdir().unwrap();
    let target = dir.path().join("out.ply");
    std::fs::write(&target, b"old").unwrap();
    let mut child = Command::new(std::env::current_exe().unwrap())
        .args(["--exact", "child_writer", "--nocapture", "--test-threads=1"])
        .env(CHILD, &target)
        .spawn()
        .unwrap();
    let start = Instant::now();
    while temp_files(dir.path()).is_empty() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "no temp file appeared"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    // The handler thread starts before the temp file is listed, so it is
    // ready once the file exists.
    let sent = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(sent.success());
    let status = child.wait().unwrap();
    use std::os::unix::process::ExitStatusExt as _;
    assert_eq!(
        status.signal().or(status.code().map(|c| c - 128)),
        Some(code),
        "{status:?}"
    );
    assert_eq!(temp_files(dir.path()), Vec::<PathBuf>::new());
    assert_eq!(std::fs::read(&target).unwrap(), b"old");
}

#[test]
fn sigint_removes_the_temp_file() {
    if std::env::var_os(CHILD).is_none() {
        interrupt_a_write("-INT", 2);
    }
}

#[test]
fn sigterm_removes_the_temp_file() {
    if std::env::var_os(CHILD).is_none() {
        interrupt_a_write("-TERM", 15);
    }
}
