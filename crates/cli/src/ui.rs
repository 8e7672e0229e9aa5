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

    /// Whether `-v` is on (and `-q` off).
    pub fn is_verbose(&self) -> bool {
        self.verbose && !self.quiet
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

impl Ui {
    /// Progress of a job in phases of known size (the out-of-core
    /// simplifier's `Event`s): on a terminal a bar per phase with its
    /// ETA; off a terminal one line per phase as it starts, like
    /// [`Ui::stage`]; `-q` hides both. Shareable across threads (the
    /// phases advance from rayon's workers).
    pub fn phases(&self) -> Phases {
        Phases {
            bar: std::sync::Mutex::new(None),
            tty: self.tty && !self.quiet,
            lines: !self.tty && !self.quiet,
        }
    }
}

/// See [`Ui::phases`].
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

/// A usage error (exit 2) as an `anyhow::Error`.
pub fn usage(msg: impl Into<String>) -> anyhow::Error {
    Usage(msg.into()).into()
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

/// Typed option values: every numeric option of every command is parsed by
/// one of these, so a value out of range (or `nan`, `inf`) is a usage error
/// (exit 2) whose message names the allowed range, before anything is read
/// or written.
pub mod value {
    use std::fmt::Display;
    use std::path::PathBuf;
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

    /// A finite real in an interval; each end closed or open, the upper
    /// end possibly absent (`hi = inf`: any finite value above `lo`).
    #[derive(Clone, Copy, Debug)]
    pub struct Real {
        lo: f64,
        lo_open: bool,
        hi: f64,
        hi_open: bool,
    }

    impl Real {
        /// `[lo, hi]`.
        pub const fn closed(lo: f64, hi: f64) -> Real {
            Real {
                lo,
                lo_open: false,
                hi,
                hi_open: false,
            }
        }
        /// `[lo, hi)`.
        pub const fn closed_open(lo: f64, hi: f64) -> Real {
            Real {
                lo,
                lo_open: false,
                hi,
                hi_open: true,
            }
        }
        /// `(lo, hi]`.
        pub const fn open_closed(lo: f64, hi: f64) -> Real {
            Real {
                lo,
                lo_open: true,
                hi,
                hi_open: false,
            }
        }
        /// `(lo, hi)`.
        pub const fn open(lo: f64, hi: f64) -> Real {
            Real {
                lo,
                lo_open: true,
                hi,
                hi_open: true,
            }
        }
        /// Any finite value `≥ 0`.
        pub const NON_NEGATIVE: Real = Real::closed(0.0, f64::INFINITY);
        /// Any finite value `> 0`.
        pub const POSITIVE: Real = Real::open(0.0, f64::INFINITY);
        /// Any finite value.
        pub const FINITE: Real = Real::open(f64::NEG_INFINITY, f64::INFINITY);

        pub fn contains(&self, v: f64) -> bool {
            v.is_finite()
                && if self.lo_open {
                    v > self.lo
                } else {
                    v >= self.lo
                }
                && if self.hi_open {
                    v < self.hi
                } else {
                    v <= self.hi
                }
        }

        /// The range in words: `[0, 1]`, `(0, 180)`, `> 0`, `≥ 0`.
        pub fn describe(&self) -> String {
            match (self.lo.is_finite(), self.hi.is_finite()) {
                (false, false) => "a finite number".into(),
                (true, false) => {
                    format!(
                        "a finite number {} {}",
                        if self.lo_open { ">" } else { ">=" },
                        self.lo
                    )
                }
                (false, true) => {
                    format!(
                        "a finite number {} {}",
                        if self.hi_open { "<" } else { "<=" },
                        self.hi
                    )
                }
                (true, true) => format!(
                    "a number in {}{}, {}{}",
                    if self.lo_open { '(' } else { '[' },
                    self.lo,
                    self.hi,
                    if self.hi_open { ')' } else { ']' }
                ),
            }
        }

        fn check(&self, s: &str) -> Result<f64, String> {
            match s.trim().parse::<f64>() {
                Ok(v) if self.contains(v) => Ok(v),
                _ => Err(format!("expected {}", self.describe())),
            }
        }

        /// The parser of an `f32` option (also refusing values that
        /// overflow `f32`).
        pub fn f32(self) -> impl Fn(&str) -> Result<f32, String> + Clone + Send + Sync + 'static {
            move |s: &str| {
                let v = self.check(s)? as f32;
                if v.is_finite() && self.contains(v as f64) {
                    Ok(v)
                } else {
                    Err(format!("expected {}", self.describe()))
                }
            }
        }

        /// The parser of an `f64` option.
        pub fn f64(self) -> impl Fn(&str) -> Result<f64, String> + Clone + Send + Sync + 'static {
            move |s: &str| self.check(s)
        }

        /// The parser of `X,Y,Z`: three values, each in this range.
        pub fn vec3(
            self,
        ) -> impl Fn(&str) -> Result<[f32; 3], String> + Clone + Send + Sync + 'static {
            move |s: &str| {
                let bad = || format!("expected X,Y,Z: three numbers, each {}", self.describe());
                let v: Vec<f32> = s
                    .split(',')
                    .map(|x| self.f32()(x))
                    .collect::<Result<_, _>>()
                    .map_err(|_| bad())?;
                match v.as_slice() {
                    &[x, y, z] => Ok([x, y, z]),
                    _ => Err(bad()),
                }
            }
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

    /// Most samples per kind a measurement may ask for (`--samples` of
    /// `compare`, `lods`, `bench`): each costs about 100 bytes over the
    /// sample kinds and both meshes, so 1 GB at the limit.
    pub const MAX_SAMPLES: usize = 10_000_000;

    /// Most levels of a halving LOD chain (`--levels`): past 32 halvings
    /// a 4-billion-triangle mesh has no triangle left.
    pub const MAX_LEVELS: usize = 32;

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
                    let deg = Real::closed(0.0, 180.0).f32()(d).map_err(|_| bad())?;
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
    /// The normals mode for `mesh` written as `format` (see `--normals`).
    pub fn normals_for(
        &self,
        mesh: &lodkit_mesh::TriMesh,
        format: lodkit_mesh::io::Format,
    ) -> lodkit_mesh::normals::NormalsMode {
        use lodkit_mesh::normals::NormalsMode;
        match (self.normals, format) {
            (Some(m), _) => m,
            (None, lodkit_mesh::io::Format::Glb) => NormalsMode::default_for(mesh),
            (None, _) => NormalsMode::Keep,
        }
    }

    /// `scene` as `--normals` asks, each mesh on its own (as
    /// [`OutputArgs::normals_for`] decides for one mesh; face order and
    /// face materials unchanged). `--compress` for an output that is not
    /// .glb is refused (exit 2).
    pub fn scene(
        &self,
        mut scene: lodkit_mesh::Scene,
        output: &std::path::Path,
    ) -> anyhow::Result<lodkit_mesh::Scene> {
        let format =
            lodkit_mesh::io::Format::from_path(output).unwrap_or(lodkit_mesh::io::Format::Glb);
        self.check(Some(format), &output.display().to_string())?;
        for m in &mut scene.meshes {
            if let std::borrow::Cow::Owned(x) = self.normals_for(&m.mesh, format).apply(&m.mesh) {
                m.mesh = x;
            }
        }
        Ok(scene)
    }

    /// Refuses `--compress` for an output that is not .glb (exit 2).
    pub fn check(&self, format: Option<lodkit_mesh::io::Format>, what: &str) -> anyhow::Result<()> {
        if self.compress && format != Some(lodkit_mesh::io::Format::Glb) {
            return Err(usage(format!(
                "--compress applies to .glb outputs, not to {what}"
            )));
        }
        Ok(())
    }

    /// The GLB writer's options.
    pub fn glb(&self) -> lodkit_mesh::io::gltf::GlbOptions {
        lodkit_mesh::io::gltf::GlbOptions {
            compress: self.compress,
        }
    }

    /// `model` as `format` bytes with these options: normals first (a
    /// mesh only), then the GLB writer with `compress`, or
    /// [`lodkit_mesh::io::encode`] for every other format.
    pub fn encode(
        &self,
        format: lodkit_mesh::io::Format,
        model: &lodkit_mesh::Model,
        opts: lodkit_mesh::io::WriteOptions,
    ) -> Result<Vec<u8>, lodkit_mesh::ParseError> {
        use lodkit_mesh::Model;
        use lodkit_mesh::io::Format;
        let changed;
        let model = match model {
            Model::Mesh(m) => match self.normals_for(m, format).apply(m) {
                std::borrow::Cow::Borrowed(_) => model,
                std::borrow::Cow::Owned(x) => {
                    changed = Model::Mesh(x);
                    &changed
                }
            },
            _ => model,
        };
        if format == Format::Glb && self.compress {
            lodkit_mesh::io::check_readable(format, model)?;
            return lodkit_mesh::io::gltf::write_model_glb(model, &self.glb());
        }
        lodkit_mesh::io::encode(format, model, opts)
    }
}

#[cfg(test)]
mod tests {
    use super::value::bytes;

    #[test]
    fn sizes_parse_with_binary_units_and_refuse_out_of_range() {
        let p = bytes(1 << 20, 1 << 50);
        assert_eq!(p("8G"), Ok(8 << 30));
        assert_eq!(p("512m"), Ok(512 << 20));
        assert_eq!(p("512MiB"), Ok(512 << 20));
        assert_eq!(p("1.5GB"), Ok(3 << 29));
        assert_eq!(p("1048576"), Ok(1 << 20));
        assert_eq!(p("1P"), Ok(1 << 50));
        for bad in [
            "0", "", "G", "8x", "8iB", "-1G", "nanG", "infG", "1023K", "2P", "1e30G",
        ] {
            let e = p(bad).unwrap_err();
            assert!(e.contains("1M..=1P"), "{bad}: {e}");
        }
    }
}
