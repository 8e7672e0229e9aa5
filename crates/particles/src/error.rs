//! Errors of the particle coder.

/// What went wrong; the CLI adds the file name.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The input model cannot be encoded (empty, non-finite, bad option).
    #[error("{0}")]
    Input(String),
    /// The `.pop` stream is not a valid stream: truncated, corrupted or of
    /// an unknown version. The message says which chunk and why.
    #[error("invalid .pop stream: {0}")]
    Stream(String),
}

/// Result alias of this crate.
pub type Result<T, E = Error> = std::result::Result<T, E>;

pub(crate) fn stream_err<T>(msg: impl Into<String>) -> Result<T> {
    Err(Error::Stream(msg.into()))
}
