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
            line.push_str(": ");
            line.push_str(&cause.to_string());
        }
        eprintln!("lodkit: error: {}", line.replace('\n', " "));
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
