//! Terminal manners: quiet/verbose levels, progress bars that hide
//! themselves when stderr is not a terminal, one-line errors.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

pub struct Ui {
    quiet: bool,
    verbose: bool,
    tty: bool,
}

impl Ui {
    pub fn new(quiet: bool, verbose: bool) -> Self {
        Ui {
            quiet,
            verbose,
            tty: std::io::stderr().is_terminal(),
        }
    }

    /// A status line on stderr (suppressed by `-q`).
    pub fn status(&self, msg: impl AsRef<str>) {
        if !self.quiet {
            eprintln!("{}", msg.as_ref());
        }
    }

    /// The error chain on one line: `lodkit: error: <outer>: <inner>`.
    pub fn error(&self, e: &anyhow::Error) {
        let mut line = e.to_string();
        for cause in e.chain().skip(1) {
            // Library errors already quote their source (`x.ply: No such
            // file`); don't say it twice.
            let cause = cause.to_string();
            if !line.contains(&cause) {
                line.push_str(": ");
                line.push_str(&cause);
            }
        }
        // Control bytes from file names or contents never reach the
        // terminal raw.
        let line = line.replace('\n', " ");
        eprintln!("lodkit: error: {}", lodkit_mesh::error::escape(&line));
    }

    /// A spinner for a step of unknown length; hidden unless stderr is a
    /// terminal and not `-q`.
    pub fn spinner(&self, msg: &str) -> Step {
        let bar = if self.tty && !self.quiet {
            let b = ProgressBar::with_draw_target(None, ProgressDrawTarget::stderr());
            b.set_style(
                ProgressStyle::with_template("{spinner} {msg} {elapsed}").expect("static template"),
            );
            b.enable_steady_tick(Duration::from_millis(100));
            b
        } else {
            ProgressBar::hidden()
        };
        bar.set_message(msg.to_string());
        Step {
            bar,
            start: Instant::now(),
            label: msg.to_string(),
            verbose: self.verbose && !self.quiet,
        }
    }
}

/// One timed stage of work; prints its time with `-v` when finished.
pub struct Step {
    bar: ProgressBar,
    start: Instant,
    label: String,
    verbose: bool,
}

impl Step {
    pub fn finish(self) -> Duration {
        let t = self.start.elapsed();
        self.bar.finish_and_clear();
        if self.verbose {
            eprintln!("{}: {:.3} s", self.label, t.as_secs_f64());
        }
        t
    }
}

/// `println!` that returns the write error instead of panicking, so
/// `lodkit info x.ply | head -1` ends quietly (see `main`'s broken-pipe
/// handling) rather than with a panic message.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// `print!` counterpart of [`outln!`].
#[macro_export]
macro_rules! out {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        write!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// A request this build or these options cannot serve (exit 2, like
/// clap's usage errors), as opposed to bad input (exit 1).
#[derive(Debug)]
pub struct Usage(pub String);

impl std::fmt::Display for Usage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

impl std::error::Error for Usage {}

/// Whether an error is stdout being closed by the reader (`| head`).
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}
