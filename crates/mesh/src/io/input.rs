//! The rules every reader follows before decoding: which files may be read
//! ([`read_file`]), which paths named inside a file may be followed
//! ([`resolve_inside`]), and how text starts ([`strip_bom`]).
//!
//! Every path-based read of lodkit-mesh goes through [`read_file`]: the
//! file given to [`super::load`], a `.conf` file and the scans it lists,
//! and external glTF buffers. Every path written inside a file (a glTF
//! buffer URI, a `.conf` scan name) goes through [`resolve_inside`].

use std::io::Read;
use std::path::{Component, Path, PathBuf};

use crate::error::{Error, Result};

/// Reads a whole regular file, at most [`super::MAX_FILE_BYTES`] bytes.
///
/// Refuses at once, with one line naming the file, anything that is not a
/// regular file (after following symlinks): a directory, a FIFO, a socket,
/// a character or block device (`/dev/zero`, `/dev/urandom`). Such inputs
/// would block forever or never end. The type is checked before opening
/// (opening a FIFO blocks until a writer comes) and again on the opened
/// handle; the read itself is capped at `MAX_FILE_BYTES + 1` bytes, so a
/// file that grows while being read is refused instead of filling memory.
/// Cost: one `stat`, one open, one read of the file.
pub fn read_file(path: &Path) -> Result<Vec<u8>> {
    let meta = std::fs::metadata(path).map_err(|e| Error::io(path, e))?;
    check_regular(path, &meta)?;
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    let meta = file.metadata().map_err(|e| Error::io(path, e))?;
    check_regular(path, &meta)?;
    super::overwrite_guard::note(&meta);
    let cap = super::MAX_FILE_BYTES;
    // `meta.len() <= cap` was checked, so the capacity fits in memory terms
    // the caller accepted; the read is still capped in case the file grows.
    let mut bytes = Vec::with_capacity(usize::try_from(meta.len()).unwrap_or(0));
    file.take(cap + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| Error::io(path, e))?;
    if bytes.len() as u64 > cap {
        return Err(too_large(path, bytes.len() as u64));
    }
    Ok(bytes)
}

fn check_regular(path: &Path, meta: &std::fs::Metadata) -> Result<()> {
    if meta.is_dir() {
        return Err(Error::unsupported(path, "is a directory"));
    }
    if !meta.is_file() {
        return Err(Error::unsupported(
            path,
            "is not a regular file (a FIFO, socket or device is refused)",
        ));
    }
    if meta.len() > super::MAX_FILE_BYTES {
        return Err(too_large(path, meta.len()));
    }
    Ok(())
}

fn too_large(path: &Path, len: u64) -> Error {
    Error::unsupported(
        path,
        format!(
            "file is {len} bytes, over the {}-byte limit",
            super::MAX_FILE_BYTES
        ),
    )
}

/// `bytes` without a leading UTF-8 byte-order mark (`EF BB BF`). Every
/// text reader (OBJ, the PLY header, ASCII STL, XYZ/PTS, `.conf`, glTF
/// JSON) calls this first, so a BOM never becomes part of the first token.
pub fn strip_bom(bytes: &[u8]) -> &[u8] {
    bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes)
}

/// Resolves `name`, a path written inside a file (a glTF buffer or image
/// URI after percent-decoding, an `mtllib` or texture name, PLY's
/// `TextureFile`, a `.conf` scan name, a NeRF `file_path`, a COLMAP image
/// name), against `dir`, the folder of the file that names it. Every such
/// path in lodkit goes through this one function.
///
/// The rule: `name` must be a relative path that stays inside `dir`, and
/// must name something *in* it. Refused (with the reason, for the caller
/// to put in its one-line error) are an empty name, a name that is only
/// `.` components (the folder itself), an absolute path (`/…`, `\…`, a
/// Windows drive or UNC prefix), any `..` component, a URI scheme (`file:`,
/// `http:`, any `word:` — so also a name with a colon in its first
/// component), a backslash (a Windows separator that would mean something
/// else there) and a NUL byte. Then, when the path exists, its real path
/// (every symlink resolved, [`std::fs::canonicalize`]) must lie inside the
/// real path of `dir`: a symlink — to a file or to a folder on the way —
/// that leads out of the folder is refused, as `lodkit serve` does for its
/// roots.
///
/// Returns `dir` joined with `name` (as the user would write it, for
/// messages); when nothing is there, the read that follows reports the
/// missing file. Two spellings of one file (`a.png`, `./a.png`, a link
/// inside the folder) have one [`real_path`]. Cost: linear in the name,
/// plus two `realpath` calls.
pub fn resolve_inside(dir: &Path, name: &str) -> std::result::Result<PathBuf, String> {
    let joined = lexically_inside(dir, name)?;
    let real = match std::fs::canonicalize(&joined) {
        Ok(p) => p,
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(joined),
        Err(e) => return Err(refusal(name, &format!("cannot be resolved ({e})"))),
    };
    let real_dir = std::fs::canonicalize(dir)
        .map_err(|e| refusal(name, &format!("has no readable folder ({e})")))?;
    if real != real_dir && real.starts_with(&real_dir) {
        Ok(joined)
    } else {
        Err(refusal(name, "leads out of its folder through a symlink"))
    }
}

/// `path` with every symlink resolved, or `path` itself when it cannot be
/// (it does not exist): the key under which a file named several ways is
/// read once.
pub fn real_path(path: &Path) -> PathBuf {
    std::fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf())
}

fn refusal(name: &str, why: &str) -> String {
    format!(
        "'{}' {why} (only relative paths inside the file's own folder are read)",
        crate::error::clip(name, 64)
    )
}

/// The lexical half of [`resolve_inside`]: `dir` joined with `name` when
/// `name` passes the name rules, without touching the file system.
pub fn lexically_inside(dir: &Path, name: &str) -> std::result::Result<PathBuf, String> {
    let refuse = |why: &str| Err(refusal(name, why));
    if name.is_empty() {
        return refuse("is empty");
    }
    if name.contains('\0') {
        return refuse("contains a NUL byte");
    }
    if name.contains('\\') {
        return refuse("contains a backslash");
    }
    let first = name.split('/').next().unwrap_or("");
    if first.contains(':') {
        return refuse("is a URI or a drive path");
    }
    let rel = Path::new(name);
    let mut normal = 0usize;
    for c in rel.components() {
        match c {
            Component::Normal(_) => normal += 1,
            Component::CurDir => {}
            Component::ParentDir => return refuse("leaves its folder with '..'"),
            Component::RootDir | Component::Prefix(_) => return refuse("is an absolute path"),
        }
    }
    if normal == 0 {
        return refuse("names the folder itself, not a file in it");
    }
    Ok(dir.join(rel))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_relative_names_inside_the_folder_resolve() {
        let d = Path::new("/data/scans");
        assert_eq!(
            resolve_inside(d, "a/b.bin").unwrap(),
            Path::new("/data/scans/a/b.bin")
        );
        assert_eq!(
            resolve_inside(d, "./b.bin").unwrap(),
            Path::new("/data/scans/./b.bin")
        );
        for bad in [
            "",
            "/etc/passwd",
            "../x.bin",
            "a/../../x.bin",
            "../../../../proc/self/environ",
            "file:///etc/passwd",
            "file:x.bin",
            "http://example.com/x.bin",
            "C:/x.bin",
            "a\\..\\x.bin",
            "\\\\server\\share",
            "a\0b",
        ] {
            assert!(resolve_inside(d, bad).is_err(), "{bad:?} was accepted");
        }
    }

    #[test]
    fn a_name_must_name_something_in_the_folder() {
        let d = Path::new("/data/scans");
        for bad in [".", "./", "././", "./."] {
            let e = resolve_inside(d, bad).unwrap_err();
            assert!(e.contains("names the folder itself"), "{bad:?}: {e}");
        }
        // `.png` added to `.` is a file named `..png` in the folder.
        assert_eq!(
            resolve_inside(d, "..png").unwrap(),
            Path::new("/data/scans/..png")
        );
    }

    #[cfg(unix)]
    #[test]
    fn symlinks_out_of_the_folder_are_refused_and_those_inside_followed() {
        use std::os::unix::fs::symlink;
        let root = tempfile::tempdir().unwrap();
        let outside = root.path().join("outside");
        let dir = root.path().join("dir");
        std::fs::create_dir_all(outside.join("deep")).unwrap();
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        std::fs::write(outside.join("secret.png"), b"s").unwrap();
        std::fs::write(dir.join("sub/own.png"), b"o").unwrap();
        symlink(outside.join("secret.png"), dir.join("file_link.png")).unwrap();
        symlink(&outside, dir.join("dir_link")).unwrap();
        symlink(dir.join("sub/own.png"), dir.join("inner_link.png")).unwrap();
        symlink("sub", dir.join("sub_link")).unwrap();
        symlink(&dir, dir.join("loop")).unwrap();
        for bad in [
            "file_link.png",
            "dir_link/secret.png",
            "./dir_link/deep/../secret.png",
        ] {
            let e = resolve_inside(&dir, bad).unwrap_err();
            assert!(e.contains("symlink") || e.contains(".."), "{bad}: {e}");
        }
        let own = std::fs::canonicalize(dir.join("sub/own.png")).unwrap();
        for good in [
            "inner_link.png",
            "sub_link/own.png",
            "./sub/own.png",
            "loop/sub/own.png",
        ] {
            let p = resolve_inside(&dir, good).unwrap();
            assert_eq!(p, dir.join(good));
            assert_eq!(real_path(&p), own, "{good}");
        }
        // Nothing there: the lexical path, for the read to report.
        assert_eq!(
            resolve_inside(&dir, "missing.png").unwrap(),
            dir.join("missing.png")
        );
        // A symlink to the folder itself names no file in it.
        assert!(resolve_inside(&dir, "loop").is_err());
    }

    #[test]
    fn non_regular_files_are_refused_at_once() {
        for dev in ["/dev/zero", "/dev/urandom", "/dev/null"] {
            if Path::new(dev).exists() {
                let e = read_file(Path::new(dev)).unwrap_err().to_string();
                assert!(e.contains(dev) && e.contains("not a regular file"), "{e}");
            }
        }
        let dir = tempfile::tempdir().unwrap();
        let e = read_file(dir.path()).unwrap_err().to_string();
        assert!(e.contains("is a directory"), "{e}");
    }

    #[cfg(unix)]
    #[test]
    fn a_fifo_is_refused_without_blocking() {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe.ply");
        let ok = std::process::Command::new("mkfifo")
            .arg(&fifo)
            .status()
            .is_ok_and(|s| s.success());
        if !ok {
            return; // no mkfifo on this system
        }
        // Would block forever (no writer) if it were opened.
        let e = super::super::load(&fifo).unwrap_err().to_string();
        assert!(
            e.contains("pipe.ply") && e.contains("not a regular file"),
            "{e}"
        );
    }

    #[test]
    fn the_bom_is_stripped_once() {
        assert_eq!(strip_bom(b"\xEF\xBB\xBFv 1"), b"v 1");
        assert_eq!(strip_bom(b"v 1"), b"v 1");
        assert_eq!(strip_bom(b"\xEF\xBB"), b"\xEF\xBB");
    }
}
