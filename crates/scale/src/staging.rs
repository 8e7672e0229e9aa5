//! The staging folder and the memory budget.
//!
//! A staging folder is lodkit's by its `lock` file (made with the folder,
//! holding [`LOCK_TEXT`]), and in use while a run holds an advisory lock
//! on that file ([`StagingLock`]): a second run of the same job refuses at
//! once instead of sharing the blocks, and only a folder no run holds is
//! removed ([`remove_staging`], [`remove_abandoned`]). What the folder
//! holds is checked before a run trusts it (`round_manifest.rs`: sizes and checksums
//! in the round manifests and beside each block output, no links).

use std::fs::File;
use std::path::{Path, PathBuf};

/// Maps an I/O error on `p` to the one-line message naming it.
pub(crate) fn io_err(p: &Path) -> impl Fn(std::io::Error) -> String + use<> {
    let p = p.to_path_buf();
    move |e| format!("{}: {e}", p.display())
}

/// A third of the machine's memory (`MemTotal` in /proc/meminfo), leaving
/// room for other processes and the page cache; 4 GiB where that file
/// cannot be read.
pub fn default_memory() -> u64 {
    std::fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|s| {
            let line = s.lines().find(|l| l.starts_with("MemTotal:"))?;
            let kb: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
            Some(kb * 1024 / 3)
        })
        .unwrap_or(4 << 30)
}

/// Names how blocks are cut and simplified: part of the staging key, so
/// a rerun never resumes from blocks an earlier version (another goal per
/// block, another grid) left behind. Change it with any such change.
const BLOCKS_VERSION: &str =
    "border-aware goal, final-pass headroom, shifted round when tight, checksummed blocks";

/// FNV-1a, 64 bits: a stable hash (the key must not change between runs
/// or builds, which std's hasher does not promise).
fn fnv(bytes: &[u8], mut h: u64) -> u64 {
    for &b in bytes {
        h ^= b as u64;
        h = h.wrapping_mul(0x100_0000_01b3);
    }
    h
}

/// The staging folder beside `output` for simplifying `input` with
/// `settings` (any text that changes the result: options, memory): its
/// name holds a key of the input's size and modification time and of
/// `settings`, so a rerun of the same job finds the blocks an interrupted
/// run finished, and any other job gets a folder of its own.
pub fn staging_dir(input: &Path, output: &Path, settings: &str) -> PathBuf {
    let meta = std::fs::metadata(input).ok();
    let len = meta.as_ref().map_or(0, |m| m.len());
    let mtime = meta
        .and_then(|m| m.modified().ok())
        .and_then(|t| t.duration_since(std::time::UNIX_EPOCH).ok())
        .map_or(0, |d| d.as_nanos());
    let mut h = fnv(&len.to_le_bytes(), 0xcbf2_9ce4_8422_2325);
    h = fnv(&mtime.to_le_bytes(), h);
    h = fnv(input.as_os_str().as_encoded_bytes(), h);
    h = fnv(settings.as_bytes(), h);
    h = fnv(BLOCKS_VERSION.as_bytes(), h);
    let dir = match output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    dir.join(format!("{}{h:016x}", staging_prefix(output)))
}

/// `.NAME.lodkit-staging-` for `output` (NAME shortened to keep the
/// folder's name within `NAME_MAX`): every staging folder of that output
/// starts so, followed by 16 hex digits.
fn staging_prefix(output: &Path) -> String {
    let name = output
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    let name = lodkit_mesh::io::fit_name(&name, ".".len() + STAGING_TAG.len() + 16);
    format!(".{name}{STAGING_TAG}")
}

const STAGING_TAG: &str = ".lodkit-staging-";

/// The text of a staging folder's `lock` file: what makes the folder
/// lodkit's.
pub const LOCK_TEXT: &str = "lodkit staging folder: in use while a run holds a lock on this file\n";

/// A staging folder this run holds: created if needed, its `lock` file
/// locked (an advisory `flock`, released when this is dropped or the
/// process ends, however it ends).
#[derive(Debug)]
pub struct StagingLock {
    _file: File,
}

/// Why a staging folder could not be taken.
fn busy(dir: &Path) -> String {
    format!(
        "{}: another lodkit run is using this staging folder (the same job on the same \
         output); wait for it to end, or give another output",
        dir.display()
    )
}

impl StagingLock {
    /// Creates `dir` (and its `lock` file) if needed and locks it.
    /// Errors (one line naming the folder): another run holds it; `dir` or
    /// its `lock` is a link or not what lodkit makes (a folder lodkit
    /// did not make is never used); I/O.
    pub fn take(dir: &Path) -> Result<StagingLock, String> {
        Self::try_take(dir)?.ok_or_else(|| busy(dir))
    }

    /// [`take`](Self::take), `None` where another run holds `dir`.
    fn try_take(dir: &Path) -> Result<Option<StagingLock>, String> {
        let io = |p: &Path, e: std::io::Error| format!("{}: {e}", p.display());
        // A run that removes the folder while we open its lock file leaves
        // us a lock on a deleted file, and one that has just made the
        // folder may not have written its lock file yet: then try again
        // (for a second at most).
        for _ in 0..50 {
            match std::fs::symlink_metadata(dir) {
                Ok(m) if m.is_dir() => {}
                Ok(_) => {
                    return Err(format!(
                        "{}: is not a folder lodkit made (a link or a file); remove it or give another output",
                        dir.display()
                    ));
                }
                Err(_) => {
                    std::fs::create_dir_all(dir.parent().unwrap_or(Path::new(".")))
                        .map_err(|e| io(dir, e))?;
                    match std::fs::create_dir(dir) {
                        Ok(()) => {}
                        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => continue,
                        Err(e) => return Err(io(dir, e)),
                    }
                    let lock = dir.join("lock");
                    std::fs::OpenOptions::new()
                        .write(true)
                        .create_new(true)
                        .open(&lock)
                        .and_then(|mut f| std::io::Write::write_all(&mut f, LOCK_TEXT.as_bytes()))
                        .map_err(|e| io(&lock, e))?;
                }
            }
            let lock = dir.join("lock");
            if !is_lodkits(dir) {
                let young = std::fs::symlink_metadata(dir)
                    .and_then(|m| m.modified())
                    .is_ok_and(|t| t.elapsed().is_ok_and(|e| e.as_secs() < 2));
                if young {
                    std::thread::sleep(std::time::Duration::from_millis(20));
                    continue;
                }
                return Err(format!(
                    "{}: is not a staging folder lodkit made (no lock file of lodkit's); \
                     remove it or give another output",
                    dir.display()
                ));
            }
            let file = File::open(&lock).map_err(|e| io(&lock, e))?;
            match file.try_lock() {
                Ok(()) => {}
                Err(std::fs::TryLockError::WouldBlock) => return Ok(None),
                Err(std::fs::TryLockError::Error(e)) => return Err(io(&lock, e)),
            }
            if same_file(&file, &lock) {
                return Ok(Some(StagingLock { _file: file }));
            }
        }
        Ok(None)
    }
}

/// Whether the opened `file` is still the one at `path`.
fn same_file(file: &File, path: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        match (file.metadata(), std::fs::symlink_metadata(path)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = file;
        path.is_file()
    }
}

/// Whether `dir` is a staging folder lodkit made: a real folder (not a
/// link) whose `lock` is a regular file holding [`LOCK_TEXT`].
fn is_lodkits(dir: &Path) -> bool {
    let lock = dir.join("lock");
    std::fs::symlink_metadata(dir).is_ok_and(|m| m.is_dir())
        && std::fs::symlink_metadata(&lock).is_ok_and(|m| m.is_file() && m.len() < 4096)
        && std::fs::read(&lock).is_ok_and(|t| t == LOCK_TEXT.as_bytes())
}

/// Removes the staging folder `dir` unless another run holds it: taken,
/// then removed whole while held. `Ok(false)`: another run holds it (it
/// is that run's now); `Ok(true)` also when there was nothing to remove.
/// Errors: I/O, naming the folder.
pub fn remove_staging(dir: &Path) -> Result<bool, String> {
    if std::fs::symlink_metadata(dir).is_err() {
        return Ok(true);
    }
    let Some(held) = StagingLock::try_take(dir)? else {
        return Ok(false);
    };
    let r = std::fs::remove_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()));
    drop(held);
    r.map(|()| true)
}

/// Removes the staging folders beside `output` that earlier runs for the
/// same output left (another input, other options, or a failed run never
/// rerun) and that no run holds, except `keep` (this run's): each must be
/// lodkit's ([`is_lodkits`]) and free ([`StagingLock`]). Returns the
/// folders removed. Errors are skipped (litter stays litter).
pub fn remove_abandoned(output: &Path, keep: &Path) -> Vec<PathBuf> {
    let prefix = staging_prefix(output);
    let parent = match output.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    };
    let Ok(entries) = std::fs::read_dir(parent) else {
        return Vec::new();
    };
    let mut removed = Vec::new();
    for e in entries.flatten() {
        let name = e.file_name();
        let Some(hex) = name.to_str().and_then(|n| n.strip_prefix(&prefix)) else {
            continue;
        };
        let path = e.path();
        if hex.len() != 16
            || !hex.bytes().all(|b| b.is_ascii_hexdigit())
            || path.file_name() == keep.file_name()
            || !is_lodkits(&path)
        {
            continue;
        }
        if remove_staging(&path) == Ok(true) {
            removed.push(path);
        }
    }
    removed.sort();
    removed
}

/// Blocks an earlier run left finished in `staging` (their `.out` files,
/// over every round folder): what a rerun of the same job will skip once
/// their checksums hold. 0 where the folder does not exist. Cost: one
/// directory listing per round.
pub fn finished_blocks(staging: &Path) -> usize {
    // Round folders are `r0`, `r1` (see `run.rs`); a block's output is
    // `bNNNNN.out` (`partition::block_output`), written atomically, so its
    // presence means the block is done.
    (0..2)
        .filter_map(|r| std::fs::read_dir(staging.join(format!("r{r}"))).ok())
        .flatten()
        .filter_map(|e| e.ok())
        .filter(|e| e.path().extension().is_some_and(|x| x == "out"))
        .count()
}
