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

/// Option parsers: an integer within a range (clap's own check, whose
/// message names the range), e.g. one of [`lodkit::limits`]' ranges.
pub mod value {
    use clap::builder::RangedU64ValueParser;

    /// A `u32` in `r`.
    pub fn range_u32(r: std::ops::RangeInclusive<u32>) -> RangedU64ValueParser<u32> {
        RangedU64ValueParser::new().range(u64::from(*r.start())..=u64::from(*r.end()))
    }

    /// A `usize` in `r`.
    pub fn range(r: std::ops::RangeInclusive<usize>) -> RangedU64ValueParser<usize> {
        RangedU64ValueParser::new().range(*r.start() as u64..=*r.end() as u64)
    }
}
