//! How a job tells its caller what it is doing: one [`Event`] type, sent
//! to a callback the caller owns. The terminal draws bars and lines from
//! it, Python may pass a function, a server could stream it; a caller that
//! wants nothing passes [`Progress::silent`].

use std::time::{Duration, Instant};

use crate::report::Level;

/// One thing a job reports while it runs. Events arrive in order from the
/// calling thread, except [`Event::Advance`], which an out-of-core phase
/// sends from its worker threads.
#[derive(Debug)]
pub enum Event<'a> {
    /// A line for the user (`wrote …`, `note: …`, `warning: …`); a front-end
    /// may hide it when asked to be quiet.
    Note(&'a str),
    /// A line that must reach the user even when they asked for quiet (a
    /// degenerate product of `build`).
    Warning(&'a str),
    /// A stage of unknown length starts; `long` when it may take seconds
    /// or more (a front-end off a terminal then names it as it starts).
    /// Every start is followed by its [`Event::StageFinished`].
    StageStarted { name: &'a str, long: bool },
    /// The stage last started is done, after `seconds` of wall time.
    StageFinished { name: &'a str, seconds: f64 },
    /// A phase of known size starts (`len` units: faces or vertices).
    Phase { name: &'a str, len: u64 },
    /// `n` more units of the current phase are done.
    Advance(u64),
    /// The last phase is done.
    PhasesFinished,
    /// The wall time of one phase of an out-of-core run, once it is over
    /// (for a front-end's verbose mode).
    Timing { name: &'a str, seconds: f64 },
    /// A level of a LOD chain is written and measured.
    Level(&'a Level),
}

/// The callback a job reports to. Cheap to copy: a reference.
#[derive(Clone, Copy)]
pub struct Progress<'a> {
    sink: &'a (dyn Fn(&Event<'_>) + Sync),
}

impl<'a> Progress<'a> {
    /// Reports to `sink`, which must accept events from several threads
    /// (see [`Event::Advance`]).
    pub fn new(sink: &'a (dyn Fn(&Event<'_>) + Sync)) -> Self {
        Progress { sink }
    }

    /// Reports to nobody.
    pub fn silent() -> Progress<'static> {
        Progress { sink: &|_| {} }
    }

    /// Sends one event.
    pub fn emit(&self, e: &Event<'_>) {
        (self.sink)(e)
    }

    /// Sends [`Event::Note`].
    pub(crate) fn status(&self, msg: impl AsRef<str>) {
        self.emit(&Event::Note(msg.as_ref()));
    }

    /// A short stage of unknown length: finished by [`Step::finish`].
    pub(crate) fn spinner(&self, name: &str) -> Step<'a> {
        self.start(name, false)
    }

    /// A long stage (seconds or more).
    pub(crate) fn stage(&self, name: &str) -> Step<'a> {
        self.start(name, true)
    }

    fn start(&self, name: &str, long: bool) -> Step<'a> {
        self.emit(&Event::StageStarted { name, long });
        Step {
            progress: *self,
            name: name.to_string(),
            start: Instant::now(),
        }
    }
}

/// A stage started by [`Progress`]; [`Step::finish`] reports its end.
pub(crate) struct Step<'a> {
    progress: Progress<'a>,
    name: String,
    start: Instant,
}

impl Step<'_> {
    /// Sends [`Event::StageFinished`]; returns the stage's wall time.
    pub(crate) fn finish(self) -> Duration {
        let t = self.start.elapsed();
        self.progress.emit(&Event::StageFinished {
            name: &self.name,
            seconds: t.as_secs_f64(),
        });
        t
    }
}

/// A byte count in words, in the largest binary unit that keeps it at
/// least 1 (`64.0 MiB`, `2.9 GiB`, `512 B`).
pub fn human_bytes(n: u64) -> String {
    const UNITS: [&str; 5] = ["KiB", "MiB", "GiB", "TiB", "PiB"];
    if n < 1024 {
        return format!("{n} B");
    }
    let mut v = n as f64 / 1024.0;
    let mut u = 0;
    while v >= 1024.0 && u + 1 < UNITS.len() {
        v /= 1024.0;
        u += 1;
    }
    format!("{v:.1} {}", UNITS[u])
}
