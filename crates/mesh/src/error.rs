//! One error type for everything that reads, writes or validates geometry.
//!
//! Every message names the file it is about and what is wrong, on one line,
//! so the CLI can print it verbatim: `bunny.ply: face 12 has index 99999 but
//! the mesh has 35947 vertices`.

use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// A format-level problem found while decoding bytes (no path attached yet).
/// `Display` escapes control characters ([`escape`]).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{}", escape(.0))]
pub struct ParseError(pub String);

impl ParseError {
    /// A one-line message (no trailing newline).
    pub fn new(msg: impl Into<String>) -> Self {
        ParseError(msg.into())
    }
}

/// `s` cut to at most `max` bytes (on a character boundary) with `…`
/// appended when cut: quotes a piece of a bad file in a one-line message
/// without pasting megabytes of it.
pub(crate) fn clip(s: &str, max: usize) -> String {
    let mut end = s.len().min(max);
    while !s.is_char_boundary(end) {
        end -= 1;
    }
    if end < s.len() {
        format!("{}…", &s[..end])
    } else {
        s.to_string()
    }
}

/// `s` with every character that could act on a terminal or break the
/// one-line rule written as an escape: C0 controls (newline, tab, ESC,
/// BEL…) and DEL as `\xNN`, C1 controls, the line/paragraph separators and
/// the bidirectional overrides as `\u{NNNN}`. Everything else, non-ASCII
/// text included, is kept. Every [`Error`] and [`ParseError`] message goes
/// through it when displayed, so bytes quoted from a file and file names
/// never reach the terminal raw. Borrows when nothing needs escaping.
pub fn escape(s: &str) -> Cow<'_, str> {
    let bad = |c: char| {
        c.is_control()
            || matches!(c, '\u{2028}' | '\u{2029}' | '\u{202A}'..='\u{202E}' | '\u{2066}'..='\u{2069}')
    };
    if !s.chars().any(bad) {
        return Cow::Borrowed(s);
    }
    let mut out = String::with_capacity(s.len() + 8);
    for c in s.chars() {
        if !bad(c) {
            out.push(c);
        } else if (c as u32) < 0x80 {
            out.push_str(&format!("\\x{:02x}", c as u32));
        } else {
            out.push_str(&format!("\\u{{{:04x}}}", c as u32));
        }
    }
    Cow::Owned(out)
}

fn escape_path(p: &Path) -> String {
    escape(&p.display().to_string()).into_owned()
}

/// Shorthand for returning a [`ParseError`] from a decoder.
#[macro_export]
macro_rules! parse_err {
    ($($arg:tt)*) => { $crate::ParseError(format!($($arg)*)) };
}

/// Errors from lodkit's mesh layer. `Display` is always a single line, with
/// the path and the message [`escape`]d.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be read or written.
    #[error("{}: {}", escape_path(path), escape(&source.to_string()))]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The file's bytes are not valid for its format.
    #[error("{}: {}", escape_path(path), escape(message))]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where in the file.
        message: String,
    },
    /// The file is valid but lodkit cannot use it that way (unknown
    /// extension, a point cloud where a mesh is needed, too large…).
    #[error("{}: {}", escape_path(path), escape(message))]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is not supported.
        message: String,
    },
    /// An argument or an in-memory model breaks a precondition.
    #[error("{}", escape(.0))]
    Invalid(String),
}

impl Error {
    /// [`Error::Io`] for `path`.
    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io {
            path: path.to_path_buf(),
            source,
        }
    }
    /// [`Error::Parse`] for `path`.
    pub fn parse(path: &Path, e: ParseError) -> Self {
        Error::Parse {
            path: path.to_path_buf(),
            message: e.0,
        }
    }
    /// [`Error::Unsupported`] for `path`.
    pub fn unsupported(path: &Path, message: impl Into<String>) -> Self {
        Error::Unsupported {
            path: path.to_path_buf(),
            message: message.into(),
        }
    }
}

/// `Result` with lodkit-mesh's [`Error`] by default.
pub type Result<T, E = Error> = std::result::Result<T, E>;
