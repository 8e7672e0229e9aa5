//! The staging folder and the memory budget.

use std::path::{Path, PathBuf};

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
const BLOCKS_VERSION: &str = "border-aware goal, final-pass headroom, shifted round when tight";

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
    let name = output
        .file_name()
        .map_or_else(|| "out".into(), |n| n.to_string_lossy().into_owned());
    dir.join(format!(".{name}.lodkit-staging-{h:016x}"))
}

/// Blocks an earlier run left finished in `staging` (their `.out` files,
/// over every round folder): what a rerun of the same job will skip. 0
/// where the folder does not exist. Cost: one directory listing per round.
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
