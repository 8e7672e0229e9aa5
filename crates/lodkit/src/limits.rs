//! Every range and default of every option of the jobs, in one place:
//! the CLI's parsers, pylodkit's checks and the docs read them from here,
//! so a range is written once. Integer ranges are `RangeInclusive`s; real
//! ranges are [`Real`]s, which can check a value and say themselves in
//! words (`a number in [0, 1]`).

use std::ops::RangeInclusive;

/// Most samples per kind a measurement may ask for (`--samples` of
/// `compare`, `lods`, `build`, `bench`): each costs about 100 bytes over
/// the sample kinds and both meshes, so 1 GB at the limit.
pub const SAMPLES: RangeInclusive<usize> = 1..=MAX_SAMPLES;
/// The upper end of [`SAMPLES`].
pub const MAX_SAMPLES: usize = 10_000_000;

/// Levels of a halving LOD chain (`--levels`): past 32 halvings a
/// 4-billion-triangle mesh has no triangle left.
pub const LEVELS: RangeInclusive<usize> = 1..=32;
/// Levels of a halving chain when none are asked for.
pub const DEFAULT_LEVELS: usize = 6;

/// A triangle budget (`--target`).
pub const TARGET_FACES: RangeInclusive<usize> = 0..=u32::MAX as usize;
/// A fraction of the input's triangles (`--ratio`, `--ratios`).
pub const RATIO: Real = Real::closed(0.0, 1.0);
/// An object-space error bound (`--max-error`), input units.
pub const MAX_ERROR: Real = Real::NON_NEGATIVE;
/// Records in the simplifier's replacement-selection heap (`--heap-size`):
/// up to 2^24 (a few hundred MB at most).
pub const HEAP_SIZE: RangeInclusive<usize> = 1..=1 << 24;
/// The simplifier's attribute weights (`--normal-weight`, `--color-weight`,
/// `--uv-weight`), relative to the bounding-box extent.
pub const WEIGHT: Real = Real::closed(0.0, 1e6);
/// Components smaller than this fraction of the bounding-box diagonal are
/// removed first (`--prune`); 1 would remove every component.
pub const PRUNE: Real = Real::closed_open(0.0, 1.0);

/// A memory budget in bytes (`--memory`): from 1 MiB (below it the block
/// size is already at the simplifier's floor of 256 faces, so a smaller
/// budget changes nothing) to 1 PiB, far past any machine's memory (a
/// budget above the machine's memory only means the in-core path is taken).
pub const MEMORY: RangeInclusive<u64> = 1 << 20..=1 << 50;

/// The octree resolution of a model built from a mesh (`mco build
/// --resolution`, `lodkit-bench mco --resolution`): the engine takes up to
/// [`lodkit_mco::MAX_RESOLUTION`], but memory grows with its square on a
/// surface that fills the lattice (an octahedron at 512 took 250 MB on a
/// 2-core machine; 2000 on a small sphere took 6.8 GB).
pub const MCO_RESOLUTION: RangeInclusive<u32> = 2..=512;

/// The octree resolution R of `pop encode --depth`: each level quadruples
/// the cells of a surface, and at 12 a closed surface that fills the cube
/// has about 10^8 of them. The format allows up to 16; legal depths too big
/// for the input are refused by the encoder before it samples.
pub const POP_DEPTH: RangeInclusive<u8> = 1..=12;
/// A `.pop` stream's vertex precision in bits (`--precision`), and its
/// highest level: the format's 16-bit coordinates.
pub const POP_BITS: RangeInclusive<u8> = 1..=16;
/// `pop decode --decimate`: cubes joined by edges shorter than this
/// fraction of the cube size are merged.
pub const POP_DECIMATE: Real = Real::closed(0.0, 1.0);

/// A welding distance (`convert --weld`), object units.
pub const WELD: Real = Real::NON_NEGATIVE;

/// A crease angle in degrees (`--normals auto=DEGREES`).
pub const CREASE_DEGREES: Real = Real::closed(0.0, 180.0);

/// A view-dependent cut's vertical field of view in degrees (`mco extract
/// --fov`; default: `lodkit_mco::Camera::looking_at`'s).
pub const VIEW_FOV: Real = Real::open(0.0, 180.0);
/// A view-dependent cut's viewport height in pixels (`mco extract
/// --viewport`; default: `lodkit_mco::Camera::looking_at`'s).
pub const VIEWPORT: Real = Real::closed(1.0, 65536.0);
/// A view-dependent cut's largest projected error in pixels (`mco extract
/// --tolerance`).
pub const TOLERANCE: Real = Real::POSITIVE;
/// The tolerance when none is given: one pixel.
pub const DEFAULT_TOLERANCE: f32 = 1.0;

/// A picture's vertical field of view in degrees (`render --fov`).
pub const FOV: Real = Real::closed(1.0, 170.0);
/// The field of view of a picture when none is asked for.
pub const DEFAULT_FOV: f32 = 35.0;
/// A camera's elevation in degrees (`render --view`, `--elevations`),
/// towards +Y.
pub const ELEVATION: Real = Real::closed(-90.0, 90.0);
/// Azimuth and elevation in degrees of a picture when none are asked for
/// (`render --view`).
pub const DEFAULT_VIEW: (f32, f32) = (30.0, 20.0);
/// Each side of a picture in pixels (`render --size`).
pub const PICTURE_SIZE: RangeInclusive<u32> = 1..=lodkit_render::MAX_SIZE;
/// Width and height of a picture when none are asked for.
pub const DEFAULT_PICTURE_SIZE: (u32, u32) = (1024, 1024);
/// A picture's background when none is asked for: white (RGB, 0..=255).
pub const DEFAULT_BACKGROUND: [u8; 3] = [255, 255, 255];

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

    /// `(lo, lo_open, hi, hi_open)`, for a front-end that checks values
    /// itself (pylodkit); an absent end is infinite.
    pub const fn bounds(&self) -> (f64, bool, f64, bool) {
        (self.lo, self.lo_open, self.hi, self.hi_open)
    }

    /// Whether `v` is finite and within the range.
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
    pub fn vec3(self) -> impl Fn(&str) -> Result<[f32; 3], String> + Clone + Send + Sync + 'static {
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
