//! An output folder written as a whole or not at all, and never over a
//! user's files: the rule of `lodkit build --out` and `lodkit tiles --out`
//! (one manifest, so either command may replace a folder the other wrote).
//!
//! Every file goes into a temporary sibling folder, which replaces the
//! target only when the job has finished. A failed job removes its
//! temporary folder, and so does one ended by Ctrl-C, SIGTERM or SIGHUP
//! (the folder is listed with [`super::interrupt::TempGuard`]); the target
//! stays as it was.
//!
//! Which folder a job may replace: lodkit's own, provably. Each job ends
//! with [`MANIFEST`] in its folder, listing every file it wrote with its
//! size; the target is replaced only when it is absent, empty, or holds
//! exactly the files its manifest lists, at the listed sizes (nothing
//! else: no other file, folder or link), and never when the input lies
//! inside it (canonical paths) or it is the current folder or one above
//! it. Anything else is refused before a byte is written, with one line
//! saying what is not lodkit's ([`FolderError::Refused`]: the CLI's exit
//! 2). The check is made again just before the swap, so a file added to
//! the target during the job is not lost either.
//!
//! A job killed outright (SIGKILL, power loss) leaves the hidden
//! `.NAME.lodkit-tmp-PID` (or, in the instant of the swap,
//! `.NAME.lodkit-old-PID`) beside the target, never a folder at the
//! target. The next job on the same target removes such folders when their
//! process is gone (on Linux, where `/proc` tells) and they are provably
//! lodkit's: a temporary folder holds [`MANIFEST`] from its creation
//! (marked as being written), an old one a complete manifest matching its
//! files.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::interrupt::TempGuard;

/// Why an output folder could not be written.
#[derive(Debug, thiserror::Error)]
pub enum FolderError {
    /// The target may not be replaced (not provably lodkit's, holds the
    /// input, no folder name…): a request the caller must change.
    #[error("{0}")]
    Refused(String),
    /// Creating, renaming or removing a folder failed.
    #[error("{}: {source}", path.display())]
    Io {
        /// The folder.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// Writing the manifest failed.
    #[error(transparent)]
    Write(#[from] crate::Error),
}

type Result<T> = std::result::Result<T, FolderError>;

/// An I/O error on `path`.
fn io(path: &Path) -> impl FnOnce(std::io::Error) -> FolderError + '_ {
    move |source| FolderError::Io {
        path: path.to_path_buf(),
        source,
    }
}

fn usage(msg: String) -> FolderError {
    FolderError::Refused(msg)
}

/// The manifest every build folder holds: the files lodkit wrote there.
pub const MANIFEST: &str = ".lodkit-build.json";

/// The manifest's format version.
const VERSION: u32 = 1;

/// [`MANIFEST`]'s contents: every file of the build (relative paths with
/// `/`, sorted) and its size in bytes; `writing` while the build runs.
#[derive(Serialize, Deserialize)]
struct Manifest {
    lodkit_build: u32,
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    writing: bool,
    files: BTreeMap<String, u64>,
}

/// A build's temporary output folder.
pub struct Staging {
    /// Where the finished build goes.
    target: PathBuf,
    /// The input file or folder, kept out of `target`.
    input: Option<PathBuf>,
    /// Where it is written meanwhile (a sibling of `target`).
    dir: PathBuf,
    done: bool,
    /// Keeps `dir` listed for removal on a signal until the build ends.
    _guard: TempGuard,
}

impl Staging {
    /// Checks `target` (see the module docs: absent, empty, or a lodkit
    /// build that does not hold `input`) and creates the temporary
    /// sibling. Errors: a usage error (exit 2) naming what is not
    /// lodkit's, or I/O creating the folders.
    pub fn new(target: &Path, input: Option<&Path>) -> Result<Self> {
        check_target(target, input)?;
        let name = target
            .file_name()
            .map(|n| n.to_string_lossy().into_owned())
            .ok_or_else(|| usage(format!("--out {}: needs a folder name", target.display())))?;
        let parent = match target.parent() {
            Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
            _ => PathBuf::from("."),
        };
        std::fs::create_dir_all(&parent).map_err(io(&parent))?;
        let name = short_name(&name);
        remove_stale(&parent, &name);
        let dir = parent.join(format!(".{name}.lodkit-tmp-{}", std::process::id()));
        if std::fs::symlink_metadata(&dir).is_ok() {
            // Left by an earlier process of this pid and not provably
            // lodkit's (`remove_stale` removed it otherwise): kept.
            return Err(usage(format!(
                "{}: exists already; remove it if no lodkit build is running",
                dir.display()
            )));
        }
        let guard = TempGuard::new(&dir);
        std::fs::create_dir(&dir).map_err(io(&dir))?;
        let marker = Manifest {
            lodkit_build: VERSION,
            writing: true,
            files: BTreeMap::new(),
        };
        write_manifest(&dir, &marker)?;
        Ok(Staging {
            target: target.to_path_buf(),
            input: input.map(Path::to_path_buf),
            dir,
            done: false,
            _guard: guard,
        })
    }

    /// The temporary folder every output is written into.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    /// Lists every file of the finished folder in its manifest, then moves
    /// it into place: the previous build (if any, checked again) is
    /// renamed aside, the new one renamed in, the old one removed.
    pub fn commit(mut self) -> Result<()> {
        let files = walk(&self.dir)
            .map_err(|why| usage(format!("{}: {why}", self.dir.display())))?
            .into_iter()
            .filter(|(p, _)| p != MANIFEST)
            .collect();
        write_manifest(
            &self.dir,
            &Manifest {
                lodkit_build: VERSION,
                writing: false,
                files,
            },
        )?;
        let target = &self.target;
        check_target(target, self.input.as_deref())?;
        if std::fs::symlink_metadata(target).is_ok() {
            let old = self.dir.with_file_name(
                self.dir
                    .file_name()
                    .map(|n| n.to_string_lossy().replace("lodkit-tmp", "lodkit-old"))
                    .unwrap_or_default(),
            );
            std::fs::rename(target, &old).map_err(io(target))?;
            if let Err(e) = std::fs::rename(&self.dir, target) {
                // Put the previous build back where it was.
                let _ = std::fs::rename(&old, target);
                return Err(io(target)(e));
            }
            std::fs::remove_dir_all(&old).map_err(io(&old))?;
        } else {
            std::fs::rename(&self.dir, target).map_err(io(target))?;
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

/// `name` shortened so `.NAME.lodkit-tmp-PID` fits a file name's limit.
fn short_name(name: &str) -> String {
    super::fit_name(name, ".".len() + ".lodkit-tmp-".len() + 10)
}

fn write_manifest(dir: &Path, m: &Manifest) -> Result<()> {
    let json = serde_json::to_string_pretty(m).map_err(|e| usage(e.to_string()))? + "\n";
    super::write_atomic(&dir.join(MANIFEST), json.as_bytes())?;
    Ok(())
}

/// Every regular file under `dir` (relative, `/`-separated) and its size,
/// links not followed. Errors: a symlink or anything not a file or a
/// folder (what lodkit never writes), or an unreadable folder, as a
/// phrase naming it.
fn walk(dir: &Path) -> std::result::Result<BTreeMap<String, u64>, String> {
    fn go(
        base: &Path,
        d: &Path,
        out: &mut BTreeMap<String, u64>,
    ) -> std::result::Result<(), String> {
        let rel = |p: &Path| {
            p.strip_prefix(base)
                .unwrap_or(p)
                .to_string_lossy()
                .replace('\\', "/")
        };
        let entries = std::fs::read_dir(d).map_err(|e| format!("{}: {e}", d.display()))?;
        for e in entries {
            let e = e.map_err(|e| format!("{}: {e}", d.display()))?;
            let p = e.path();
            let t = e.file_type().map_err(|e| format!("{}: {e}", p.display()))?;
            if t.is_dir() {
                go(base, &p, out)?;
            } else if t.is_file() {
                let len = e
                    .metadata()
                    .map_err(|e| format!("{}: {e}", p.display()))?
                    .len();
                out.insert(rel(&p), len);
            } else {
                return Err(format!("{} is a link or a special file", rel(&p)));
            }
        }
        Ok(())
    }
    let mut out = BTreeMap::new();
    go(dir, dir, &mut out)?;
    Ok(out)
}

/// Why `dir` is not provably a finished lodkit build (`None`: it is):
/// its manifest must be complete and list exactly the files under it, at
/// their sizes, and no folder but those holding them.
fn not_a_build(dir: &Path) -> Option<String> {
    let text = match std::fs::read(dir.join(MANIFEST)) {
        Ok(t) => t,
        Err(_) => return Some(format!("no {MANIFEST}")),
    };
    let m: Manifest = match serde_json::from_slice(&text) {
        Ok(m) => m,
        Err(_) => return Some(format!("{MANIFEST} is not one lodkit wrote")),
    };
    if m.lodkit_build != VERSION || m.writing {
        return Some(format!("{MANIFEST} is not one of a finished build"));
    }
    let found = match walk(dir) {
        Ok(f) => f,
        Err(why) => return Some(why),
    };
    for (path, len) in &found {
        if path == MANIFEST {
            continue;
        }
        match m.files.get(path) {
            None => return Some(format!("{path} is not one of its files")),
            Some(l) if l != len => {
                return Some(format!(
                    "{path} has changed ({len} bytes, the build wrote {l})"
                ));
            }
            Some(_) => {}
        }
    }
    if let Some(missing) = m.files.keys().find(|p| !found.contains_key(*p)) {
        return Some(format!("{missing} is missing"));
    }
    // Folders: only those holding a listed file.
    let wanted: BTreeSet<PathBuf> = m
        .files
        .keys()
        .flat_map(|p| Path::new(p).ancestors().skip(1).map(Path::to_path_buf))
        .collect();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        let Ok(entries) = std::fs::read_dir(&d) else {
            return Some(format!("{} cannot be read", d.display()));
        };
        for e in entries.flatten() {
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                let p = e.path();
                let rel = p.strip_prefix(dir).unwrap_or(&p).to_path_buf();
                if !wanted.contains(&rel) {
                    return Some(format!("{}/ is not one of its folders", rel.display()));
                }
                stack.push(p);
            }
        }
    }
    None
}

/// Removes `.NAME.lodkit-tmp-PID` and `.NAME.lodkit-old-PID` folders in
/// `parent` whose process no longer runs and that are provably lodkit's
/// (a temporary folder: its manifest marked as being written; an old one:
/// a finished build, [`not_a_build`]). Only where `/proc/self` exists
/// (Linux): elsewhere a live build's folder cannot be told from a dead
/// one's, so nothing is removed. Errors are ignored (the folder is only
/// litter; the build does not need it gone).
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
        let (pid, tmp) = match (
            rest.strip_prefix(".lodkit-tmp-"),
            rest.strip_prefix(".lodkit-old-"),
        ) {
            (Some(p), _) => (p, true),
            (_, Some(p)) => (p, false),
            _ => continue,
        };
        let Ok(pid) = pid.parse::<u32>() else {
            continue;
        };
        // This process has made no folder yet: one of its pid is an
        // earlier process's (pids are reused).
        if (pid != me && Path::new(&format!("/proc/{pid}")).exists())
            || !e.file_type().is_ok_and(|t| t.is_dir())
        {
            continue;
        }
        let path = e.path();
        let ours = if tmp {
            std::fs::read(path.join(MANIFEST))
                .ok()
                .and_then(|t| serde_json::from_slice::<Manifest>(&t).ok())
                .is_some_and(|m| m.lodkit_build == VERSION)
        } else {
            not_a_build(&path).is_none()
        };
        if ours {
            let _ = std::fs::remove_dir_all(path);
        }
    }
}

/// `target` must be absent, an empty folder, or a finished lodkit build
/// ([`not_a_build`]) that holds neither the input nor the current folder.
fn check_target(target: &Path, input: Option<&Path>) -> Result<()> {
    let refuse =
        |why: String| -> Result<()> { Err(usage(format!("--out {}: {why}", target.display()))) };
    let Ok(meta) = std::fs::metadata(target) else {
        if std::fs::symlink_metadata(target).is_ok() {
            return refuse("is a link to nothing; give a new or empty folder".into());
        }
        return Ok(());
    };
    if !meta.is_dir() {
        return refuse("exists and is not a folder".into());
    }
    let t = target.canonicalize().map_err(io(target))?;
    if std::env::current_dir().is_ok_and(|cwd| cwd.starts_with(&t)) {
        return refuse("is the current folder or one above it; give a folder of its own".into());
    }
    if let Some(i) = input.and_then(|i| i.canonicalize().ok())
        && i.starts_with(&t)
    {
        return refuse(format!(
            "holds the input {}; a build replaces its folder whole, so give a folder that does \
             not hold the input",
            input.unwrap_or(&i).display()
        ));
    }
    let empty = std::fs::read_dir(target)
        .map_err(io(target))?
        .next()
        .is_none();
    if empty {
        return Ok(());
    }
    match not_a_build(target) {
        None => Ok(()),
        Some(why) => refuse(format!(
            "holds files that are not a lodkit build ({why}); give a new or empty folder, or a \
             folder an earlier build made"
        )),
    }
}
