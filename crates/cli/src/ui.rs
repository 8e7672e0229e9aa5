//! Terminal manners: quiet/verbose levels, progress bars that hide
//! themselves when stderr is not a terminal, one-line errors.

use std::io::IsTerminal;
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use lodkit::{Event, Progress};

pub struct Ui {
    quiet: bool,
    verbose: bool,
    tty: bool,
    /// The library's stages now running, innermost last.
    steps: std::sync::Mutex<Vec<Step>>,
    /// The library's phases.
    phases: Phases,
}

impl Ui {
    pub fn new(quiet: bool, verbose: bool) -> Self {
        let tty = std::io::stderr().is_terminal();
        Ui {
            quiet,
            verbose,
            tty,
            steps: std::sync::Mutex::new(Vec::new()),
            phases: Phases {
                bar: std::sync::Mutex::new(None),
                tty: tty && !quiet,
                lines: !tty && !quiet,
            },
        }
    }

    /// Runs `f` with a [`Progress`] that draws the library's events here.
    pub fn run<R>(&self, f: impl FnOnce(&Progress) -> R) -> R {
        let sink = |e: &Event<'_>| self.draw(e);
        f(&Progress::new(&sink))
    }

    /// One library event on the terminal: notes as status lines, stages
    /// as spinners, phases as bars, warnings even under `-q`, timings and
    /// each stage's time with `-v`.
    pub fn draw(&self, e: &Event<'_>) {
        match e {
            Event::Note(line) => self.status(line),
            Event::Warning(line) => eprintln!("{line}"),
            Event::StageStarted { name, long } => {
                let step = if *long {
                    self.stage(name)
                } else {
                    self.spinner(name)
                };
                self.steps.lock().unwrap_or_else(|e| e.into_inner()).push(step);
            }
            Event::StageFinished { .. } => {
                let step = self.steps.lock().unwrap_or_else(|e| e.into_inner()).pop();
                if let Some(step) = step {
                    step.finish();
                }
            }
            Event::Phase { name, len } => self.phases.phase(name, *len),
            Event::Advance(n) => self.phases.advance(*n),
            Event::PhasesFinished => self.phases.finish(),
            Event::Timing { name, seconds } => {
                if self.is_verbose() {
                    self.status(format!("{name}: {seconds:.3} s"));
                }
            }
            Event::Level(l) => self.status(format!(
                "level {}: {} triangles, {} vertices, error est. {:.3e} / measured mean {:.3e} max {:.3e}: {}",
                l.level,
                l.triangles,
                l.vertices,
                l.estimated_error,
                l.measured_mean_error,
                l.measured_max_error,
                l.stop
            )),
        }
    }

    /// A status line on stderr (suppressed by `-q`).
    pub fn status(&self, msg: impl AsRef<str>) {
        if !self.quiet {
            eprintln!("{}", msg.as_ref());
        }
    }

    /// Whether `-v` is on (and `-q` off).
    pub fn is_verbose(&self) -> bool {
        self.verbose && !self.quiet
    }

    /// The error chain on one line: `lodkit: error: <outer>: <inner>`.
    pub fn error(&self, e: &anyhow::Error) {
        let line = lodkit::usage::one_line(e);
        // Control bytes from file names or contents never reach the
        // terminal raw.
        eprintln!("lodkit: error: {}", lodkit_mesh::escape(&line));
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

impl Ui {
    /// A long stage of work (seconds or more): a spinner on a terminal;
    /// off a terminal (a log, a pipe, CI) one line naming the stage as it
    /// starts, so a long command is never silent there. `-q` hides both.
    pub fn stage(&self, msg: &str) -> Step {
        if !self.tty && !self.quiet {
            eprintln!("{msg}");
        }
        self.spinner(msg)
    }
}

/// Progress of a job in phases of known size (the out-of-core
/// simplifier's): on a terminal a bar per phase with its ETA; off a
/// terminal one line per phase as it starts; `-q` hides both.
/// Shareable across threads (the phases advance from rayon's workers).
pub struct Phases {
    /// The current phase's bar (a hidden one off a terminal); `None`
    /// before the first phase.
    bar: std::sync::Mutex<Option<ProgressBar>>,
    tty: bool,
    lines: bool,
}

impl Phases {
    /// A phase starts with `len` units of work: the previous bar is
    /// cleared, a new one drawn (or its name printed off a terminal).
    pub fn phase(&self, msg: &str, len: u64) {
        let bar = if self.tty {
            let b = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
            b.set_style(
                ProgressStyle::with_template(
                    "{msg} [{bar:30}] {percent:>3}% {elapsed} (ETA {eta})",
                )
                .expect("static template")
                .progress_chars("=> "),
            );
            b.enable_steady_tick(Duration::from_millis(200));
            b
        } else {
            if self.lines {
                eprintln!("{msg}");
            }
            ProgressBar::hidden()
        };
        bar.set_message(msg.to_string());
        // A poisoned lock only means a worker panicked mid-update; the bar
        // itself is still sound, and the panic is reported on its own.
        let mut cur = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(old) = cur.replace(bar) {
            old.finish_and_clear();
        }
    }

    /// `n` more units of the current phase are done.
    pub fn advance(&self, n: u64) {
        let cur = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(b) = cur.as_ref() {
            b.inc(n);
        }
    }

    /// The last bar cleared.
    pub fn finish(&self) {
        let mut cur = self.bar.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(old) = cur.take() {
            old.finish_and_clear();
        }
    }
}

pub use lodkit::usage::{Usage, usage};

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

/// Whether an error is stdout being closed by the reader (`| head`).
pub fn is_broken_pipe(e: &anyhow::Error) -> bool {
    e.chain().any(|c| {
        c.downcast_ref::<std::io::Error>()
            .is_some_and(|io| io.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// Typed option values: every numeric option of every command is parsed by
/// one of these, so a value out of range (or `nan`, `inf`) is a usage error
/// (exit 2) whose message names the allowed range, before anything is read
/// or written.
pub mod value {
    use std::fmt::Display;
    use std::path::PathBuf;
    use std::str::FromStr;

    pub use lodkit::limits::Real;

    /// An integer in one of [`lodkit::limits`]' ranges.
    pub fn range<T>(
        r: std::ops::RangeInclusive<T>,
    ) -> impl Fn(&str) -> Result<T, String> + Clone + Send + Sync + 'static
    where
        T: FromStr + PartialOrd + Display + Copy + Send + Sync + 'static,
    {
        int(*r.start(), *r.end())
    }

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

    /// A size in bytes in `lo..=hi`: a whole number of bytes, or a number
    /// (decimals allowed) with a unit K, M, G, T or P, powers of 1024 (a
    /// trailing `B` or `iB` and any case accepted: `8G`, `512MiB`, `1.5g`).
    pub fn bytes(
        lo: u64,
        hi: u64,
    ) -> impl Fn(&str) -> Result<u64, String> + Clone + Send + Sync + 'static {
        move |s: &str| {
            let bad = || {
                format!(
                    "expected a size in {}..={}: a number of bytes, or a number with K, M, G, T or P \
                     (powers of 1024), e.g. 8G or 512M",
                    short(lo),
                    short(hi)
                )
            };
            let t = s.trim().to_ascii_lowercase();
            let (body, unit_needed) = match t.strip_suffix("ib") {
                Some(b) => (b, true),
                None => (t.strip_suffix('b').unwrap_or(&t), false),
            };
            let (num, shift) = match body.char_indices().last() {
                Some((i, c)) if "kmgtp".contains(c) => {
                    (&body[..i], 10 * (1 + "kmgtp".find(c).unwrap_or(0)))
                }
                _ if unit_needed => return Err(bad()),
                _ => (body, 0),
            };
            let v = if shift == 0 {
                num.parse::<u64>().map_err(|_| bad())?
            } else {
                // Decimals only with a unit; the product is checked against
                // `hi` as a float first, so it cannot overflow the cast.
                let x: f64 = num.parse().map_err(|_| bad())?;
                let b = x * (1u64 << shift) as f64;
                if !b.is_finite() || b < 0.0 || b > hi as f64 {
                    return Err(bad());
                }
                b.round() as u64
            };
            if (lo..=hi).contains(&v) {
                Ok(v)
            } else {
                Err(bad())
            }
        }
    }

    /// A Ray address for `--ray`: `local`, `auto`, or `HOST:PORT` (a
    /// `ray://` prefix allowed) — checked here so a typo is a usage error,
    /// not a failed cluster start minutes later.
    pub fn ray_address(s: &str) -> Result<String, String> {
        let bad = || {
            format!(
                "expected local, auto or HOST:PORT (a running Ray cluster's address), got {s:?}"
            )
        };
        if s == "local" || s == "auto" {
            return Ok(s.to_string());
        }
        let hp = s.strip_prefix("ray://").unwrap_or(s);
        let (host, port) = hp.rsplit_once(':').ok_or_else(bad)?;
        let host_ok = !host.is_empty()
            && host
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || ".-_[]:".contains(c));
        match port.parse::<u16>() {
            Ok(p) if p > 0 && host_ok => Ok(s.to_string()),
            _ => Err(bad()),
        }
    }

    /// `n` bytes in the largest unit of [`bytes`] that divides it (`1M`,
    /// `1P`), else in bytes.
    fn short(n: u64) -> String {
        for (i, u) in ["P", "T", "G", "M", "K"].iter().enumerate() {
            let unit = 1u64 << (10 * (5 - i));
            if n >= unit && n.is_multiple_of(unit) {
                return format!("{}{u}", n / unit);
            }
        }
        n.to_string()
    }

    /// `WIDTHxHEIGHT`, each side in `min..=max`.
    pub fn size(
        min: u32,
        max: u32,
    ) -> impl Fn(&str) -> Result<(u32, u32), String> + Clone + Send + Sync + 'static {
        move |s: &str| {
            let bad =
                || format!("expected WIDTHxHEIGHT with each side in {min}..={max}, e.g. 256x256");
            let (w, h) = s.split_once(['x', 'X']).ok_or_else(bad)?;
            let side = |v: &str| match v.trim().parse::<u32>() {
                Ok(n) if (min..=max).contains(&n) => Ok(n),
                _ => Err(bad()),
            };
            Ok((side(w)?, side(h)?))
        }
    }

    /// An output file whose extension is one of `exts` (lower case, no
    /// dot), so `-o x.ply` on a command that writes `.pop` is refused
    /// rather than written with the wrong contents.
    pub fn output(
        exts: &'static [&'static str],
        what: &'static str,
    ) -> impl Fn(&str) -> Result<PathBuf, String> + Clone + Send + Sync + 'static {
        move |s: &str| {
            let p = PathBuf::from(s);
            let ext = p
                .extension()
                .and_then(|e| e.to_str())
                .map(|e| e.to_ascii_lowercase());
            match ext {
                Some(e) if exts.contains(&e.as_str()) => Ok(p),
                _ => Err(format!(
                    "{s}: {what} is written as {}",
                    exts.iter()
                        .map(|e| format!(".{e}"))
                        .collect::<Vec<_>>()
                        .join(", ")
                )),
            }
        }
    }

    /// Output extensions that hold a triangle mesh.
    pub const MESH_OUT: &[&str] = &["ply", "obj", "stl", "glb"];

    /// `--normals keep|none|auto[=DEGREES]`, DEGREES a crease angle in
    /// [0, 180] ([`lodkit_mesh::normals::NormalsMode`]).
    pub fn normals()
    -> impl Fn(&str) -> Result<lodkit_mesh::normals::NormalsMode, String> + Clone + Send + Sync + 'static
    {
        use lodkit_mesh::normals::{DEFAULT_CREASE_DEGREES, NormalsMode};
        |s: &str| {
            let bad = || {
                format!(
                    "expected keep, none, auto or auto=DEGREES with DEGREES in [0, 180] (a crease angle; \
                     auto alone is {DEFAULT_CREASE_DEGREES})"
                )
            };
            match s.trim() {
                "keep" => Ok(NormalsMode::Keep),
                "none" => Ok(NormalsMode::None),
                "auto" => Ok(NormalsMode::Auto(DEFAULT_CREASE_DEGREES)),
                t => {
                    let d = t.strip_prefix("auto=").ok_or_else(bad)?;
                    let deg = lodkit::limits::CREASE_DEGREES.f32()(d).map_err(|_| bad())?;
                    Ok(NormalsMode::Auto(deg))
                }
            }
        }
    }
}

/// The output options of the commands that write meshes (`convert`,
/// `simplify`, `lods`, `build`): normals and GLB compression.
#[derive(clap::Args, Debug, Clone, Default)]
pub struct OutputArgs {
    /// Vertex normals of what is written: keep, none, or auto[=DEGREES]
    /// (smooth normals, hard across edges sharper than DEGREES in [0, 180],
    /// default 60; vertices split at creases). Default: auto for .glb
    /// outputs of meshes without normals, keep otherwise.
    #[arg(long, value_name = "MODE", value_parser = value::normals())]
    pub normals: Option<lodkit_mesh::normals::NormalsMode>,
    /// Write .glb outputs compressed: EXT_meshopt_compression with
    /// KHR_mesh_quantization (needs lodkit built with `--features compress`).
    #[arg(long)]
    pub compress: bool,
}

impl OutputArgs {
    /// The library's output options these flags give.
    pub fn options(&self) -> lodkit::output::OutputOptions {
        lodkit::output::OutputOptions {
            normals: self.normals,
            compress: self.compress,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::value::bytes;

    #[test]
    fn sizes_parse_with_binary_units_and_refuse_out_of_range() {
        let memory = lodkit::limits::MEMORY;
        let p = bytes(*memory.start(), *memory.end());
        assert_eq!(p("8G"), Ok(8 << 30));
        assert_eq!(p("512m"), Ok(512 << 20));
        assert_eq!(p("512MiB"), Ok(512 << 20));
        assert_eq!(p("1.5GB"), Ok(3 << 29));
        assert_eq!(p("1048576"), Ok(1 << 20));
        assert_eq!(p("1P"), Ok(*memory.end()));
        for bad in [
            "0", "", "G", "8x", "8iB", "-1G", "nanG", "infG", "1023K", "2P", "1e30G",
        ] {
            let e = p(bad).unwrap_err();
            assert!(e.contains("1M..=1P"), "{bad}: {e}");
        }
    }
}
