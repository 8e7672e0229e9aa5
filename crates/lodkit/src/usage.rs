//! The one error kind a front-end must tell apart: a request these options
//! or this build cannot serve (the CLI's exit 2), as opposed to bad input
//! or a failure (exit 1), which every job reports as a plain
//! `anyhow::Error` naming the file and what is wrong.

/// A request this build or these options cannot serve. Jobs return it
/// inside their `anyhow::Error`; find it with `downcast_ref::<Usage>()`.
#[derive(Debug)]
pub struct Usage(pub String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// A [`Usage`] as an `anyhow::Error`.
pub fn usage(msg: impl Into<String>) -> anyhow::Error {
    Usage(msg.into()).into()
}
