//! The bench's terminal manners: status lines on stderr (`-q` hides
//! them), each stage named as it starts and timed with `-v`, tables and
//! JSON on stdout.
use std::path::Path;
use std::time::Instant;

use anyhow::Result;

pub struct Ui {
    pub quiet: bool,
    pub verbose: bool,
}

impl Ui {
    /// A status line on stderr (suppressed by `-q`).
    pub fn status(&self, msg: impl AsRef<str>) {
        if !self.quiet {
            eprintln!("{}", msg.as_ref());
        }
    }

    /// A stage of work, named as it starts.
    pub fn stage(&self, msg: &str) -> Step {
        self.status(msg);
        Step {
            label: msg.to_string(),
            start: Instant::now(),
            verbose: self.verbose && !self.quiet,
        }
    }
}

/// One timed stage; prints its time with `-v` when finished.
pub struct Step {
    label: String,
    start: Instant,
    verbose: bool,
}

impl Step {
    pub fn finish(self) {
        if self.verbose {
            eprintln!(
                "{}: {:.3} s",
                self.label,
                self.start.elapsed().as_secs_f64()
            );
        }
    }
}

/// Loads a file that must be a triangle mesh.
pub fn load_mesh(path: &Path) -> Result<lodkit_mesh::TriMesh> {
    lodkit::input::load_mesh(&lodkit::Progress::silent(), path)
}

/// Pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> Result<()> {
    crate::outln!("{}", serde_json::to_string_pretty(value)?)?;
    Ok(())
}

/// `println!` that returns the write error instead of panicking.
#[macro_export]
macro_rules! outln {
    ($($arg:tt)*) => {{
        use std::io::Write as _;
        writeln!(std::io::stdout().lock(), $($arg)*)
    }};
}

/// Option parsers over [`lodkit::limits`]' ranges: a value out of range is
/// a usage error (exit 2) naming the range.
pub mod value {
    use std::fmt::Display;
    use std::str::FromStr;

    /// An integer in `lo..=hi`.
    pub fn int<T>(
        lo: T,
        hi: T,
    ) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
    where
        T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
    {
        move |s: &str| match s.trim().parse::<T>() {
            Ok(v) if v >= lo && v <= hi => Ok(v),
            _ => Err(format!("expected an integer in {lo}..={hi}")),
        }
    }

    /// An integer in one of [`lodkit::limits`]' ranges.
    pub fn range<T>(
        r: std::ops::RangeInclusive<T>,
    ) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
    where
        T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
    {
        int(*r.start(), *r.end())
    }
}
