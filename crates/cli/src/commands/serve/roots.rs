//! What `lodkit serve` publishes: its roots, the model listing, and the one
//! place where a URL path becomes a file path.
//!
//! Containment invariant: [`Roots::resolve`] returns only regular files whose
//! canonical path (every symlink resolved) lies inside the canonical path of
//! one root, or is that root when the root is a file. URL segments are
//! percent-decoded one by one and a decoded segment may not be empty, `.`,
//! `..`, start with a dot, or hold `/`, `\` or NUL, so nothing a client sends
//! can climb out before the canonical check even runs; the check then catches
//! symlinks. Hidden names (leading dot) are neither listed nor served.

use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use serde::Serialize;

/// URL prefix of the models: `/models/<name>` where `<name>` is the
/// listing's `name`, percent-encoded segment by segment.
pub const MODELS_PREFIX: &str = "/models/";

/// Directories deeper than this below a root are not listed (a bound on the
/// walk, far past any `lodkit build` output).
const MAX_DEPTH: usize = 32;
/// The listing stops after this many files (a bound on the answer's size).
const MAX_ENTRIES: usize = 100_000;

/// One published root.
struct Mount {
    /// First URL segment, or empty for a sole directory root (mounted at
    /// `/models/` itself).
    name: String,
    /// Canonical path.
    path: PathBuf,
    is_dir: bool,
}

/// The roots given on the command line.
pub struct Roots {
    mounts: Vec<Mount>,
    /// The roots as the user wrote them, for the banner.
    shown: String,
}

/// One line of `GET /api/models`.
#[derive(Serialize, Debug, Clone, PartialEq, Eq)]
pub struct Entry {
    /// Path below the roots with `/` separators (`lods/bunny_lod1.ply`).
    pub name: String,
    /// Absolute URL path to fetch it (`/models/lods/bunny_lod1.ply`).
    pub url: String,
    /// `pop|mco|glb|gltf|ply|obj|stl|xyz|tileset|other`, from the name:
    /// `tileset` is a 3D Tiles `tileset.json` (see [`Roots::list`]).
    pub kind: &'static str,
    pub bytes: u64,
}

impl Roots {
    /// Checks and canonicalizes the roots. One directory is mounted at
    /// `/models/`; otherwise each root is mounted at its base name (a
    /// repeated base name gets `-2`, `-3`, …).
    ///
    /// Errors: a root that does not exist or is neither a file nor a
    /// directory, named in the message.
    pub fn new(paths: &[PathBuf]) -> Result<Self> {
        let mut mounts: Vec<Mount> = Vec::with_capacity(paths.len());
        for p in paths {
            let canon = match std::fs::canonicalize(p) {
                Ok(c) => c,
                Err(e) => bail!("{}: cannot serve it: {e}", p.display()),
            };
            let meta = std::fs::metadata(&canon)?;
            if !meta.is_dir() && !meta.is_file() {
                bail!("{}: not a file or a directory", p.display());
            }
            let base = canon
                .file_name()
                .map(|n| n.to_string_lossy().into_owned())
                .unwrap_or_else(|| "root".to_string());
            let mut name = base.clone();
            let mut n = 2;
            while mounts.iter().any(|m| m.name == name) {
                name = format!("{base}-{n}");
                n += 1;
            }
            mounts.push(Mount {
                name,
                path: canon,
                is_dir: meta.is_dir(),
            });
        }
        if let [only] = mounts.as_mut_slice()
            && only.is_dir
        {
            only.name.clear();
        }
        let shown = paths
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ");
        Ok(Roots { mounts, shown })
    }

    /// The roots as given, comma-separated.
    pub fn shown(&self) -> &str {
        &self.shown
    }

    /// The file behind `raw`, the percent-encoded URL path after
    /// [`MODELS_PREFIX`]; `None` for anything that is not a regular file
    /// inside a root (see the module's containment invariant).
    pub fn resolve(&self, raw: &str) -> Option<PathBuf> {
        let mut segments = Vec::new();
        for s in raw.split('/') {
            segments.push(decode_segment(s)?);
        }
        let (mount, rest) = match self.mounts.as_slice() {
            [only] if only.name.is_empty() => (only, &segments[..]),
            mounts => {
                let (first, rest) = segments.split_first()?;
                (mounts.iter().find(|m| m.name == *first)?, rest)
            }
        };
        let candidate = if mount.is_dir {
            if rest.is_empty() {
                return None;
            }
            let mut p = mount.path.clone();
            p.extend(rest);
            p
        } else if rest.is_empty() {
            mount.path.clone()
        } else {
            return None;
        };
        let canon = std::fs::canonicalize(&candidate).ok()?;
        let inside = if mount.is_dir {
            canon.starts_with(&mount.path)
        } else {
            canon == mount.path
        };
        (inside && std::fs::metadata(&canon).ok()?.is_file()).then_some(canon)
    }

    /// Every servable file of every root, sorted by name. Symlinked files
    /// are listed when they resolve inside their root; symlinked directories
    /// are not walked (no loops, nothing outside).
    ///
    /// A folder holding a `tileset.json` is a 3D Tiles tileset: that file is
    /// listed with kind `tileset` (the viewer opens it), and a `tileset.json`
    /// below it (an external tileset, a part of the same tileset) as `other`.
    pub fn list(&self) -> Vec<Entry> {
        let mut out = Vec::new();
        for m in &self.mounts {
            if m.is_dir {
                walk(&m.path, &m.path, &m.name, 0, &mut out);
            } else if let Ok(meta) = std::fs::metadata(&m.path) {
                out.push(entry(m.name.clone(), meta.len()));
            }
        }
        out.sort_by(|a, b| a.name.cmp(&b.name));
        out.truncate(MAX_ENTRIES);
        mark_external_tilesets(&mut out);
        out
    }
}

fn walk(root: &Path, dir: &Path, prefix: &str, depth: usize, out: &mut Vec<Entry>) {
    if depth > MAX_DEPTH {
        return;
    }
    let Ok(read) = std::fs::read_dir(dir) else {
        return;
    };
    for e in read.flatten() {
        if out.len() >= MAX_ENTRIES {
            return;
        }
        let file_name = e.file_name();
        let Some(file_name) = file_name.to_str() else {
            continue; // not expressible in a URL we would decode back
        };
        if file_name.starts_with('.') || file_name.contains('\\') {
            continue;
        }
        let name = if prefix.is_empty() {
            file_name.to_string()
        } else {
            format!("{prefix}/{file_name}")
        };
        let Ok(ty) = e.file_type() else { continue };
        if ty.is_dir() {
            walk(root, &e.path(), &name, depth + 1, out);
        } else if ty.is_file() {
            if let Ok(meta) = e.metadata() {
                out.push(entry(name, meta.len()));
            }
        } else if ty.is_symlink()
            && let Ok(canon) = std::fs::canonicalize(e.path())
            && canon.starts_with(root)
            && let Ok(meta) = std::fs::metadata(&canon)
            && meta.is_file()
        {
            out.push(entry(name, meta.len()));
        }
    }
}

fn entry(name: String, bytes: u64) -> Entry {
    let url = format!(
        "{MODELS_PREFIX}{}",
        name.split('/')
            .map(encode_segment)
            .collect::<Vec<_>>()
            .join("/")
    );
    Entry {
        kind: kind_of(&name),
        name,
        url,
        bytes,
    }
}

/// Turns `tileset` entries inside another tileset's folder into `other`:
/// they are external tilesets of that one. Cost: tilesets², over the
/// tileset entries only.
fn mark_external_tilesets(entries: &mut [Entry]) {
    let folders: Vec<String> = entries
        .iter()
        .filter(|e| e.kind == "tileset")
        .map(|e| e.name[..e.name.len() - TILESET_FILE.len()].to_string())
        .collect();
    for e in entries.iter_mut().filter(|e| e.kind == "tileset") {
        let folder = &e.name[..e.name.len() - TILESET_FILE.len()];
        if folders
            .iter()
            .any(|f| f.len() < folder.len() && folder.starts_with(f.as_str()))
        {
            e.kind = "other";
        }
    }
}

/// The file that makes a folder a 3D Tiles tileset.
const TILESET_FILE: &str = "tileset.json";

/// The listing's `kind` of a file name (`/`-separated path): `tileset` for
/// a `tileset.json`, otherwise from its extension.
pub fn kind_of(name: &str) -> &'static str {
    let base = name.rsplit('/').next().unwrap_or(name);
    if base == TILESET_FILE {
        return "tileset";
    }
    let ext = name.rsplit_once('.').map(|(_, e)| e.to_ascii_lowercase());
    match ext.as_deref() {
        Some("pop") => "pop",
        Some("mco") => "mco",
        Some("glb") => "glb",
        Some("gltf") => "gltf",
        Some("ply") => "ply",
        Some("obj") => "obj",
        Some("stl") => "stl",
        Some("xyz") => "xyz",
        _ => "other",
    }
}

/// Percent-decodes one URL segment; `None` when it is malformed or names
/// something a client may not reach (see the module doc).
fn decode_segment(s: &str) -> Option<String> {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let hi = (*b.get(i + 1)? as char).to_digit(16)?;
            let lo = (*b.get(i + 2)? as char).to_digit(16)?;
            out.push((hi * 16 + lo) as u8);
            i += 3;
        } else {
            out.push(b[i]);
            i += 1;
        }
    }
    let ok = !out.is_empty()
        && out[0] != b'.'
        && !out.iter().any(|&c| c == b'/' || c == b'\\' || c == 0);
    if !ok {
        return None;
    }
    String::from_utf8(out).ok()
}

/// Percent-encodes one path segment: everything but RFC 3986's unreserved
/// characters.
fn encode_segment(s: &str) -> String {
    let mut out = String::with_capacity(s.len());
    for &c in s.as_bytes() {
        if c.is_ascii_alphanumeric() || matches!(c, b'-' | b'.' | b'_' | b'~') {
            out.push(c as char);
        } else {
            out.push_str(&format!("%{c:02X}"));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn decode_segment_refuses_every_way_out() {
        for bad in [
            "", ".", "..", "%2e%2e", "%2E.", ".hidden", "a%2fb", "a%2Fb", "a%5cb", "a\\b", "a%00b",
            "%", "%2", "%zz", "%ff",
        ] {
            assert_eq!(decode_segment(bad), None, "{bad}");
        }
        assert_eq!(decode_segment("a%20b.ply").as_deref(), Some("a b.ply"));
        assert_eq!(decode_segment("x..y").as_deref(), Some("x..y"));
    }

    #[test]
    fn encode_segment_round_trips_through_decode() {
        for s in ["bunny lod 1.ply", "ü.glb", "a+b&c?.pop", "100%.mco"] {
            assert_eq!(decode_segment(&encode_segment(s)).as_deref(), Some(s));
        }
    }

    #[test]
    fn kind_follows_the_extension_case_blind() {
        assert_eq!(kind_of("a/b.POP"), "pop");
        assert_eq!(kind_of("x.mco"), "mco");
        assert_eq!(kind_of("report.md"), "other");
        assert_eq!(kind_of("noext"), "other");
        assert_eq!(kind_of("city/tileset.json"), "tileset");
        assert_eq!(kind_of("tileset.json"), "tileset");
        assert_eq!(kind_of("lods/lods.json"), "other");
        assert_eq!(kind_of("my_tileset.json"), "other");
    }

    #[test]
    fn a_tileset_is_listed_once_its_external_tilesets_as_other() {
        let dir = tempfile::tempdir().unwrap();
        let d = dir.path();
        for f in [
            "bunny.pop",
            "city/tileset.json",
            "city/0.glb",
            "city/a/tileset.json",
            "city/a/1.glb",
            "other/tileset.json",
        ] {
            let p = d.join(f);
            std::fs::create_dir_all(p.parent().unwrap()).unwrap();
            std::fs::write(&p, b"{}").unwrap();
        }
        let roots = Roots::new(&[d.to_path_buf()]).unwrap();
        let kinds: Vec<(String, &str)> =
            roots.list().into_iter().map(|e| (e.name, e.kind)).collect();
        let kind = |n: &str| kinds.iter().find(|(m, _)| m == n).map(|(_, k)| *k);
        assert_eq!(kind("city/tileset.json"), Some("tileset"));
        assert_eq!(kind("other/tileset.json"), Some("tileset"));
        assert_eq!(kind("city/a/tileset.json"), Some("other"));
        assert_eq!(kind("city/0.glb"), Some("glb"));
        assert_eq!(kind("bunny.pop"), Some("pop"));
    }
}
