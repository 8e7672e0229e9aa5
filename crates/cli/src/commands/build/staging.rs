//! The output folder written as a whole or not at all: every file goes
//! into a temporary sibling folder, which replaces `--out` only when the
//! build has finished. A failed build removes its temporary folder, and
//! so does one ended by Ctrl-C, SIGTERM or SIGHUP (the folder is listed
//! with `lodkit_mesh::io::interrupt::TempGuard`); `--out` stays as it was.
//! A build killed outright (SIGKILL, power loss) leaves the hidden
//! `.NAME.lodkit-tmp-PID` beside `--out`, never a folder at `--out`; the
//! next build of the same `--out` removes such folders whose process is
//! gone (on Linux, where `/proc` tells).

use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use lodkit_mesh::io::interrupt::TempGuard;

use crate::ui::Usage;

/// A build's temporary output folder.
pub struct Staging {
    /// Where the finished build goes.
    target: PathBuf,
    /// Where it is written meanwhile (a sibling of `target`).
    dir: PathBuf,
    done: bool,
    /// Keeps `dir` listed for removal on a signal until the build ends.
    _guard: TempGuard,
}

impl Staging {
    /// Checks `target` (a new path, an empty folder or a previous build's
    /// folder, holding `report.md`) and creates the temporary sibling.
    /// Anything else at `target` is refused before a byte is written: a
    /// build replaces its folder whole, so it must not take a folder of
    /// other files with it.
    pub fn new(target: &Path) -> Result<Self> {
        check_target(target)?;
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| Usage(format!("--out {}: needs a folder name", target.display())))?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent)
            .with_context(|| format!("{}: cannot create folder", parent.display()))?;
        remove_stale(&parent, &name);
        let dir = parent.join(format!(".{name}.lodkit-tmp-{}", std::process::id()));
        if dir.exists() {
            std::fs::remove_dir_all(&dir)
                .with_context(|| format!("{}: cannot remove stale folder", dir.display()))?;
        }
        let guard = TempGuard::new(&dir);
        std::fs::create_dir(&dir)
            .with_context(|| format!("{}: cannot create output folder", dir.display()))?;
        Ok(Staging {
            target: target.to_path_buf(),
            dir,
            done: false,
            _guard: guard,
        })
    }

    /// The temporary folder every output is written into.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Moves the finished folder into place: the previous folder (if any)
    /// is renamed aside, the new one renamed in, the old one removed.
    pub fn commit(mut self) -> Result<()> {
        let target = &self.target;
        if target.exists() {
            let old = self.dir.with_file_name(
                self.dir
                    .file_name()
                    .map(|n| n.to_string_lossy().replace("lodkit-tmp", "lodkit-old"))
                    .unwrap_or_default(),
            );
            std::fs::rename(target, &old).with_context(|| {
                format!("{}: cannot move the previous build aside", target.display())
            })?;
            if let Err(e) = std::fs::rename(&self.dir, target) {
                // Put the previous build back where it was.
                let _ = std::fs::rename(&old, target);
                return Err(e).with_context(|| {
                    format!("{}: cannot move the new build into place", target.display())
                });
            }
            std::fs::remove_dir_all(&old)
                .with_context(|| format!("{}: cannot remove the previous build", old.display()))?;
        } else {
            std::fs::rename(&self.dir, target).with_context(|| {
                format!("{}: cannot move the new build into place", target.display())
            })?;
        }
        self.done = true;
        Ok(())
    }
}

impl Drop for Staging {
    fn drop(&mut self) {
        if !self.done {
            let _ = std::fs::remove_dir_all(&self.dir);
        }
    }
}

/// Removes `.NAME.lodkit-tmp-PID` and `.NAME.lodkit-old-PID` folders in
/// `parent` whose process no longer runs: what a build killed outright
/// left. Only where `/proc/self` exists (Linux): elsewhere a live build's
/// folder cannot be told from a dead one's, so nothing is removed. Errors
/// are ignored (the folder is only litter; the build does not need it gone).
fn remove_stale(parent: &Path, name: &str) {
    if !Path::new("/proc/self").exists() {
        return;
    }
    let Ok(entries) = std::fs::read_dir(parent) else {
        return;
    };
    let me = std::process::id();
    for e in entries.flatten() {
        let file = e.file_name();
        let Some(file) = file.to_str() else { continue };
        let Some(rest) = file.strip_prefix('.').and_then(|f| f.strip_prefix(name)) else {
            continue;
        };
        let pid = rest
            .strip_prefix(".lodkit-tmp-")
            .or_else(|| rest.strip_prefix(".lodkit-old-"))
            .and_then(|p| p.parse::<u32>().ok());
        let Some(pid) = pid else { continue };
        if pid != me
            && !Path::new(&format!("/proc/{pid}")).exists()
            && e.file_type().is_ok_and(|t| t.is_dir())
        {
            let _ = std::fs::remove_dir_all(e.path());
        }
    }
}

/// `target` must be absent, an empty folder, or a folder holding
/// `report.md` (a previous build), and not the current folder or one above
/// it.
fn check_target(target: &Path) -> Result<()> {
    let Ok(meta) = std::fs::metadata(target) else {
        return Ok(());
    };
    if !meta.is_dir() {
        return Err(Usage(format!(
            "--out {}: exists and is not a folder",
            target.display()
        ))
        .into());
    }
    if let (Ok(t), Ok(cwd)) = (target.canonicalize(), std::env::current_dir())
        && cwd.starts_with(&t)
    {
        return Err(Usage(format!(
            "--out {}: is the current folder or one above it; give a folder of its own",
            target.display()
        ))
        .into());
    }
    let empty = std::fs::read_dir(target)
        .with_context(|| format!("{}: cannot read folder", target.display()))?
        .next()
        .is_none();
    if !empty && !target.join("report.md").is_file() {
        return Err(Usage(format!(
            "--out {}: holds files that are not a lodkit build (no report.md); give a new or empty folder",
            target.display()
        ))
        .into());
    }
    Ok(())
}
