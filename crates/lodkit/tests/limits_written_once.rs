//! Every range and default of `lodkit::limits` is written once: the CLI's
//! sources (`crates/cli/src`) and pylodkit's (`python/src`,
//! `python/pylodkit`) read them from the library instead of repeating
//! them. The code of those folders is searched for each limit's literal
//! spellings; comments and docstrings (help text, prose) are not code and
//! are passed over. Each spelling list must also match `limits.rs`, so a
//! list cannot drift from the value it guards. The defaults the engines'
//! option types own (the simplifier's heap and weights, the metric's
//! seed) are guarded the same way against their own home file.

use std::path::{Path, PathBuf};

/// A limit and the ways its numbers are written as code.
const SPELLINGS: &[(&str, &[&str])] = &[
    ("SAMPLES", &["10_000_000", "10000000"]),
    (
        "HEAP_SIZE",
        &[
            "1 << 24",
            "1usize << 24",
            "2**24",
            "2 ** 24",
            "16777216",
            "16_777_216",
        ],
    ),
    ("WEIGHT", &["1e6"]),
    ("MEMORY", &["1 << 50"]),
    (
        "LEVELS",
        &["1..=32", "1, 32)", "1usize, 32)", "MAX_LEVELS: usize = 32"],
    ),
    (
        "TARGET_FACES",
        &["u32::MAX as usize", "\"target\", target, 0, 2**32"],
    ),
    (
        "MCO_RESOLUTION",
        &["2..=512", "2, 512)", "2u32, 512)", "u32 = 512"],
    ),
    (
        "DEFAULT_LEVELS",
        &[
            "DEFAULT_LEVELS: usize = 6",
            "6 if levels is None",
            "default_value_t = 6",
            "halving_targets(6)",
        ],
    ),
    (
        "RATIO",
        &[
            "Real = Real::closed(0.0, 1.0)",
            "Real::closed(0.0, 1.0).f32()",
            "\"ratio\", ratio, 0.0, 1.0",
            "\"ratios\", r, 0.0, 1.0",
            "\"lods\", r, 0.0, 1.0",
        ],
    ),
    (
        "PRUNE",
        &["Real::closed_open(0.0, 1.0)", "\"prune\", prune, 0.0, 1.0"],
    ),
    ("CREASE_DEGREES", &["Real::closed(0.0, 180.0)"]),
    (
        "POP_DEPTH",
        &["1..=12", "u8 = 12", "int = 12", "1u8, 12)", "1, 12)"],
    ),
    (
        "POP_BITS",
        &["1..=16", "u8 = 16", "int = 16", "1u8, 16)", "1, 16)"],
    ),
    ("FOV", &["Real::closed(1.0, 170.0)", "1.0, 170.0)"]),
    (
        "VIEW_FOV",
        &[
            "Real::open(0.0, 180.0)",
            "0.0, 180.0, lo_open=True, hi_open=True",
        ],
    ),
    ("VIEWPORT", &["Real::closed(1.0, 65536.0)", "1.0, 65536.0)"]),
    (
        "DEFAULT_TOLERANCE",
        &[
            "DEFAULT_TOLERANCE: f32 = 1.0",
            "tolerance.unwrap_or(1.0)",
            "1.0 if tolerance is None",
            "tolerance = 1.0)",
        ],
    ),
    (
        "DEFAULT_FOV",
        &[
            "DEFAULT_FOV: f32 = 35.0",
            "default_value_t = 35.0",
            "fov: float = 35.0",
            "fov = 35.0",
        ],
    ),
    (
        "ELEVATION",
        &[
            "Real::closed(-90.0, 90.0)",
            "(-90.0..=90.0)",
            "-90.0, 90.0)",
        ],
    ),
    (
        "DEFAULT_VIEW",
        &[
            "(f32, f32) = (30.0, 20.0)",
            "default_value = \"30,20\"",
            "azimuth: float = 30",
            "elevation: float = 20",
            "azimuth = 30.0",
            "elevation = 20.0",
        ],
    ),
    (
        "DEFAULT_PICTURE_SIZE",
        &[
            "(u32, u32) = (1024, 1024)",
            "default_value = \"1024x1024\"",
            "(1024, 1024)",
            "width = 1024",
            "height = 1024",
        ],
    ),
    (
        "DEFAULT_BACKGROUND",
        &[
            "[u8; 3] = [255, 255, 255]",
            "default_value = \"255,255,255\"",
            "(255, 255, 255)",
        ],
    ),
    (
        "POP_DECIMATE",
        &[
            "POP_DECIMATE: Real = Real::closed(0.0, 1.0)",
            "\"decimate\", decimate, 0.0, 1.0",
        ],
    ),
];

/// Defaults an engine's option type owns: its home file (from the
/// workspace root), the item, and the ways the CLI or pylodkit would write
/// them as code.
const ENGINE_DEFAULTS: &[(&str, &str, &[&str])] = &[
    (
        "crates/simplify/src/options.rs",
        "AttributeWeights::DEFAULT",
        &[
            "normal: 0.05",
            "color: 0.05",
            "uv: 0.1",
            "normal_weight: float = 0.05",
            "color_weight: float = 0.05",
            "uv_weight: float = 0.1",
            "normal_weight = 0.05",
            "color_weight = 0.05",
            "uv_weight = 0.1",
        ],
    ),
    (
        "crates/simplify/src/options.rs",
        "Options::DEFAULT_HEAP_SIZE",
        &[
            "DEFAULT_HEAP_SIZE: usize = 1",
            "heap_size: int = 1",
            "heap_size = 1,",
            "heap_size = 1)",
        ],
    ),
    (
        "crates/mco/src/view_dependent_cut.rs",
        "lodkit_mco::Camera::looking_at",
        &[
            "vfov_deg: 60.0",
            "viewport_height: 1080.0",
            "unwrap_or(60.0)",
            "unwrap_or(1080.0)",
            "60.0 if fov is None",
            "1080.0 if viewport is None",
            "fov = 60.0",
            "viewport = 1080.0",
        ],
    ),
    (
        "crates/mesh/src/metrics/mod.rs",
        "metrics::DEFAULT_SEED",
        &["DEFAULT_SEED: u64 = 1998", "1998"],
    ),
];

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

/// `lit` in `line` as a whole token (no digit, letter or `_` glued to
/// either end: `100000000` does not hold `10000000`).
fn holds(line: &str, lit: &str) -> bool {
    let glued = |c: Option<char>| c.is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
    line.match_indices(lit).any(|(i, _)| {
        let before = line[..i].chars().next_back();
        let after = line[i + lit.len()..].chars().next();
        let first = lit.chars().next();
        let last = lit.chars().next_back();
        let glued_before = glued(before) && glued(first);
        let glued_after = glued(after) && glued(last);
        !glued_before && !glued_after
    })
}

/// The code lines of a source file: comments, and Python docstrings,
/// left out.
fn code_lines(path: &Path) -> Vec<(usize, String)> {
    let text = std::fs::read_to_string(path).unwrap_or_default();
    let python = path.extension().is_some_and(|e| e == "py" || e == "pyi");
    let mut in_doc = false;
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let t = line.trim_start();
        if python {
            let quotes = t.matches("\"\"\"").count();
            if in_doc || quotes > 0 {
                if quotes % 2 == 1 {
                    in_doc = !in_doc;
                }
                continue;
            }
            if t.starts_with('#') {
                continue;
            }
        } else if t.starts_with("//") {
            continue;
        }
        out.push((i + 1, line.to_string()));
    }
    out
}

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    let mut entries: Vec<_> = entries.filter_map(|e| e.ok()).map(|e| e.path()).collect();
    entries.sort();
    for p in entries {
        if p.is_dir() {
            sources(&p, out);
        } else if p
            .extension()
            .is_some_and(|e| e == "rs" || e == "py" || e == "pyi")
        {
            out.push(p);
        }
    }
}

#[test]
fn every_spelling_list_matches_the_limit_it_guards() {
    let home = code_lines(&root().join("crates/lodkit/src/limits.rs"));
    for (name, spellings) in SPELLINGS {
        assert!(
            home.iter()
                .any(|(_, l)| spellings.iter().any(|s| holds(l, s))),
            "{name}: none of {spellings:?} is in limits.rs"
        );
    }
}

#[test]
fn every_engine_default_list_matches_its_home() {
    for (home, name, spellings) in ENGINE_DEFAULTS {
        let lines = code_lines(&root().join(home));
        assert!(
            lines
                .iter()
                .any(|(_, l)| spellings.iter().any(|s| holds(l, s))),
            "{name}: none of {spellings:?} is in {home}"
        );
    }
}

#[test]
fn no_limit_is_written_again_in_the_cli_or_pylodkit() {
    let mut files = Vec::new();
    for dir in ["crates/cli/src", "python/src", "python/pylodkit"] {
        sources(&root().join(dir), &mut files);
    }
    assert!(
        !files.is_empty(),
        "no sources found under {}",
        root().display()
    );
    let mut found = Vec::new();
    for f in &files {
        for (n, line) in code_lines(f) {
            let lists = SPELLINGS
                .iter()
                .map(|(name, s)| (format!("lodkit::limits::{name}"), *s))
                .chain(
                    ENGINE_DEFAULTS
                        .iter()
                        .map(|(_, name, s)| (name.to_string(), *s)),
                );
            for (name, spellings) in lists {
                if let Some(s) = spellings.iter().find(|s| holds(&line, s)) {
                    found.push(format!(
                        "{}:{n}: {s} ({name})",
                        f.strip_prefix(root()).unwrap_or(f).display()
                    ));
                }
            }
        }
    }
    assert!(
        found.is_empty(),
        "limits written again instead of read from lodkit::limits:\n{}",
        found.join("\n")
    );
}
