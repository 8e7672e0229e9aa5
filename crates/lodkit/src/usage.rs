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

/// A job's error on one line, as every front-end shows it: the message,
/// then each cause it does not already quote (library errors name their
/// source themselves: `x.ply: No such file`), newlines as spaces. Control
/// bytes are left to the caller (a terminal escapes them).
pub fn one_line(e: &anyhow::Error) -> String {
    let mut line = e.to_string();
    for cause in e.chain().skip(1) {
        let cause = cause.to_string();
        if !line.contains(&cause) {
            line.push_str(": ");
            line.push_str(&cause);
        }
    }
    line.replace('\n', " ")
}
