//! One error type for everything that reads, writes or validates geometry.
//!
//! Every message names the file it is about and what is wrong, on one line,
//! so the CLI can print it verbatim: `bunny.ply: face 12 has index 99999 but
//! the mesh has 35947 vertices`.

use std::path::{Path, PathBuf};

/// A format-level problem found while decoding bytes (no path attached yet).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
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

/// Shorthand for returning a [`ParseError`] from a decoder.
#[macro_export]
macro_rules! parse_err {
    ($($arg:tt)*) => { $crate::error::ParseError(format!($($arg)*)) };
}

/// Errors from lodkit's mesh layer. `Display` is always a single line.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// The file's bytes are not valid for its format.
    #[error("{}: {message}", path.display())]
    Parse {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where in the file.
        message: String,
    },
    /// The file is valid but lodkit cannot use it that way (unknown
    /// extension, a point cloud where a mesh is needed, too large…).
    #[error("{}: {message}", path.display())]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// What is not supported.
        message: String,
    },
    /// An argument or an in-memory model breaks a precondition.
    #[error("{0}")]
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
