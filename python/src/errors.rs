//! lodkit's errors as Python exceptions (`pylodkit.errors`): the same one
//! line the CLI prints, in an exception class that says what kind of
//! failure it is.
//!
//! - `InputError` (a `ValueError`): bad data — a malformed file, an array
//!   of the wrong shape, a mesh the crates refuse. The CLI's exit 1.
//! - `FileError` (an `OSError`): a file that cannot be read or written.
//! - `OptionError` (a `ValueError`): an option outside its range, or a
//!   request a job's options cannot serve (the library's
//!   `lodkit::usage::Usage`). The CLI's exit 2.
//!
//! All three derive from `pylodkit.errors.LodkitError`. They are defined
//! in Python (a class with two bases, `LodkitError` and `ValueError` /
//! `OSError`, is plain there) and looked up here when raised.

use pyo3::exceptions::{PyOSError, PyValueError};
use pyo3::prelude::*;

/// Which `pylodkit.errors` class to raise.
#[derive(Clone, Copy)]
pub enum Kind {
    Input,
    File,
    Option,
}

/// A `pylodkit.errors` exception carrying `msg` (falls back to the
/// built-in `ValueError` / `OSError` if the package is not importable,
/// e.g. when `_lodkit` is loaded on its own).
pub fn raise(kind: Kind, msg: impl Into<String>) -> PyErr {
    let msg = msg.into();
    let name = match kind {
        Kind::Input => "InputError",
        Kind::File => "FileError",
        Kind::Option => "OptionError",
    };
    Python::attach(|py| {
        let made = py
            .import("pylodkit.errors")
            .and_then(|m| m.getattr(name))
            .and_then(|cls| cls.call1((msg.clone(),)));
        match made {
            Ok(exc) => PyErr::from_value(exc),
            Err(_) => match kind {
                Kind::Input | Kind::Option => PyValueError::new_err(msg),
                Kind::File => PyOSError::new_err(msg),
            },
        }
    })
}

/// `InputError(msg)`.
pub fn input(msg: impl Into<String>) -> PyErr {
    raise(Kind::Input, msg)
}

/// A mesh-layer error: `Io` is a `FileError`, the rest `InputError`.
pub fn mesh(e: lodkit_mesh::Error) -> PyErr {
    match e {
        lodkit_mesh::Error::Io { .. } => raise(Kind::File, e.to_string()),
        _ => input(e.to_string()),
    }
}

/// A continuous-LOD error: as [`mesh`] for the geometry it read, else
/// `InputError` (a `.mco` file that cannot be opened is told apart by the
/// caller, which knows the path).
pub fn mco(e: lodkit_mco::Error) -> PyErr {
    match e {
        lodkit_mco::Error::Mesh(m) => mesh(m),
        other => input(other.to_string()),
    }
}

/// A library job's error, with its one line: a `Usage` is an
/// `OptionError`, a failure to read or write a file a `FileError`, the
/// rest (bad input) an `InputError`.
pub fn job(e: anyhow::Error) -> PyErr {
    let kind = if e.downcast_ref::<lodkit::usage::Usage>().is_some() {
        Kind::Option
    } else if e.chain().any(|c| c.is::<std::io::Error>()) {
        Kind::File
    } else {
        Kind::Input
    };
    raise(kind, lodkit::usage::one_line(&e))
}
