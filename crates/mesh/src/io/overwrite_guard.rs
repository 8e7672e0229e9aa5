//! Outputs that would replace an input of the same run are refused.
//!
//! The rule: every file a path-based reader opens ([`super::input::read_file`],
//! the streaming readers' [`super::open_head`]) is listed by its device and
//! inode; [`super::write_atomic`] refuses to replace a path whose file (a
//! symlink followed) is listed. Device and inode, not the path: a hard
//! link, a symlink or a `./x/../x` spelling of an input is the same file
//! and is refused as well.
//!
//! Opt-in, because a library user may well read a file, change the model
//! and save it back: the CLI opts in ([`refuse_overwriting_inputs`]), and
//! a command may list a file it reads another way ([`protect`]). On
//! non-Unix targets (no inode numbers) nothing is listed or refused.

#[cfg(unix)]
use std::collections::HashSet;
use std::path::Path;
#[cfg(unix)]
use std::sync::Mutex;

use crate::error::Result;

/// `(device, inode)` of every input so far; `None` until opted in.
#[cfg(unix)]
static INPUTS: Mutex<Option<HashSet<(u64, u64)>>> = Mutex::new(None);

/// From now on, every file read is an input that no write of this
/// process may replace (see the module docs). Idempotent.
pub fn refuse_overwriting_inputs() {
    #[cfg(unix)]
    {
        let mut g = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
        g.get_or_insert_with(HashSet::new);
    }
}

/// Lists `path` as an input (for a file read without
/// [`super::input::read_file`]). No effect before
/// [`refuse_overwriting_inputs`], or when `path` does not exist.
pub fn protect(path: &Path) {
    if let Ok(m) = std::fs::metadata(path) {
        note(&m);
    }
}

/// Lists the file of `meta` (from `metadata` or an opened handle).
pub(crate) fn note(meta: &std::fs::Metadata) {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        let mut g = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(set) = g.as_mut() {
            set.insert((meta.dev(), meta.ino()));
        }
    }
    #[cfg(not(unix))]
    let _ = meta;
}

/// Refuses `path` as an output when its file is a listed input. Cost:
/// one `stat`. (Nothing writes on wasm32.)
#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
pub(crate) fn check(path: &Path) -> Result<()> {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt as _;
        let Ok(m) = std::fs::metadata(path) else {
            return Ok(());
        };
        let g = INPUTS.lock().unwrap_or_else(|e| e.into_inner());
        if g.as_ref().is_some_and(|s| s.contains(&(m.dev(), m.ino()))) {
            return Err(crate::error::Error::unsupported(
                path,
                "is an input of this run (the same file, through this path or a link); \
                 lodkit never writes over its input: give another output path",
            ));
        }
    }
    #[cfg(not(unix))]
    let _ = path;
    Ok(())
}
