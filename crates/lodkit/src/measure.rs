//! How the jobs measure each level against its input: Metro distances
//! through one [`Reference`] (the input's index built once), with a sample
//! count per level ([`lodkit_mesh::metrics::level_samples`] unless
//! `--samples` fixes it), or not at all (`--no-measure`).

use anyhow::Result;
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::Reference;

/// The `--samples` / `--no-measure` choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Sampling {
    /// `--no-measure`: no distance is measured.
    Skip,
    /// Per-kind count from the level's size ([`lodkit_mesh::metrics::level_samples`]).
    Adaptive,
    /// `--samples N`: `N` per kind for every level.
    PerKind(usize),
}

/// One level's symmetric distances to the input (object units).
#[derive(Clone, Copy, Debug)]
pub struct Measured {
    pub mean: f64,
    pub max: f64,
    /// Samples of each kind that were used.
    pub samples: u64,
}

impl Sampling {
    /// Whether anything is measured.
    pub fn measures(self) -> bool {
        self != Sampling::Skip
    }

    /// `level` against the input: `None` when skipped or when the level has
    /// no faces.
    pub fn measure(self, reference: &Reference, level: &TriMesh) -> Result<Option<Measured>> {
        let samples = match self {
            Sampling::Skip => return Ok(None),
            Sampling::Adaptive => None,
            Sampling::PerKind(n) => Some(n),
        };
        if level.faces.is_empty() {
            return Ok(None);
        }
        let r = reference.compare_level(level, samples)?;
        Ok(Some(Measured {
            mean: r.symmetric.mean,
            max: r.symmetric.max,
            samples: r.samples_per_kind,
        }))
    }

    /// The sentence the report gives about the sample counts.
    pub fn describe(self) -> String {
        match self {
            Sampling::Skip => "are not measured (`--no-measure`)".into(),
            Sampling::Adaptive => format!(
                "are measured against the input with `lodkit compare`'s Metro sampling, symmetric, \
                 {} samples of each kind per face of the level ({}–{}; column *samples*)",
                lodkit_mesh::metrics::LEVEL_SAMPLES_PER_FACE,
                lodkit_mesh::metrics::MIN_LEVEL_SAMPLES,
                lodkit_mesh::metrics::DEFAULT_MIN_SAMPLES
            ),
            Sampling::PerKind(n) => format!(
                "are measured against the input with `lodkit compare`'s Metro sampling, symmetric, \
                 {n} samples of each kind"
            ),
        }
    }
}

/// `x` in the report's `{:.3e}` form, or `-` when not measured.
pub fn cell(x: Option<f64>) -> String {
    x.map_or_else(|| "-".to_string(), |v| format!("{v:.3e}"))
}

/// A product whose finest level has fewer triangles or particles than this
/// (and than half its input's samples) is degenerate: a handful of
/// primitives says the stage lost the input, whatever its size.
pub const FEWEST_PRIMITIVES: usize = 100;
/// A product whose finest level has fewer than this share of its input's
/// samples is degenerate: the stages aim at about the input's count (the
/// stream's leaves at its sample spacing, the octree's cubes at its
/// triangle size), so 1/20 means the detail was thrown away.
pub const SMALLEST_SHARE: f64 = 0.05;
/// A product whose finest level's measured mean error is above this share
/// of the input's bounding-box diagonal is degenerate: a full-resolution
/// level is off by a leaf cube (well under 1 %) where the stage worked.
pub const LARGEST_MEAN_ERROR: f64 = 0.05;

/// One product's finest level against its input, for the report's
/// detail table and the degenerate-product check.
#[derive(Clone, Debug)]
pub struct Detail {
    /// The product (`"stream NAME.pop"`, `"octree NAME.mco"`).
    pub product: String,
    /// Primitives of its finest level, and what they are (`"particles"`).
    pub count: usize,
    pub unit: &'static str,
    /// Triangles of its finest level (the stream's triangulation).
    pub triangles: usize,
    /// The input's samples this level is held against, and what they are
    /// (`"points"`, `"vertices"`, `"triangles"`).
    pub expected: usize,
    pub expected_unit: &'static str,
    /// Measured mean error of the finest level (object units).
    pub mean: Option<f64>,
}

impl Detail {
    /// Why the product is degenerate ([`FEWEST_PRIMITIVES`],
    /// [`SMALLEST_SHARE`], [`LARGEST_MEAN_ERROR`] against `diagonal`, the
    /// input's bounding-box diagonal), or `None` when it is not.
    pub fn degenerate(&self, diagonal: f64) -> Option<String> {
        let few = FEWEST_PRIMITIVES.min(self.expected / 2);
        if self.count < few || self.triangles < few {
            return Some(if self.unit == "triangles" {
                format!("its finest level has {} triangles", self.count)
            } else {
                format!(
                    "its finest level has {} {} and {} triangles",
                    self.count, self.unit, self.triangles
                )
            });
        }
        if (self.count as f64) < SMALLEST_SHARE * self.expected as f64 {
            return Some(format!(
                "its finest level has {} {} for the input's {} {} (under {} %)",
                self.count,
                self.unit,
                self.expected,
                self.expected_unit,
                SMALLEST_SHARE * 100.0
            ));
        }
        match self.mean {
            // A NaN error is degenerate too.
            Some(m) if diagonal > 0.0 && (m.is_nan() || m > LARGEST_MEAN_ERROR * diagonal) => {
                Some(format!(
                    "its finest level's mean error is {:.2} % of the input's diagonal (over {} %)",
                    100.0 * m / diagonal,
                    LARGEST_MEAN_ERROR * 100.0
                ))
            }
            _ => None,
        }
    }
}

/// The samples a model carries: a mesh's vertices, a cloud's finite
/// points, a range image's valid pixels.
pub fn sample_count(model: &lodkit_mesh::Model) -> (usize, &'static str) {
    match model {
        lodkit_mesh::Model::Mesh(m) => (m.positions.len(), "vertices"),
        lodkit_mesh::Model::Points(c) => (
            c.positions.iter().filter(|p| p.is_finite()).count(),
            "points",
        ),
        lodkit_mesh::Model::Range(r) => (r.valid_count(), "samples"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn detail(count: usize, expected: usize, mean: Option<f64>) -> Detail {
        Detail {
            product: "stream x.pop".into(),
            count,
            unit: "particles",
            triangles: 2 * count,
            expected,
            expected_unit: "points",
            mean,
        }
    }

    #[test]
    fn a_product_is_degenerate_for_a_handful_a_small_share_or_a_large_error() {
        // At the input's detail: fine.
        assert_eq!(detail(40_000, 50_000, Some(1e-3)).degenerate(1.0), None);
        // A handful of particles (the LMS400 cloud outer-thinned: 189).
        let why = detail(6, 22_000, Some(1e-3)).degenerate(1.0).unwrap();
        assert!(why.contains("6 particles and 12 triangles"), "{why}");
        // A tiny input may keep a tiny count.
        assert_eq!(detail(30, 40, Some(1e-3)).degenerate(1.0), None);
        // Under 5 % of the samples.
        let why = detail(189, 460_400, Some(1e-3)).degenerate(1.0).unwrap();
        assert!(why.contains("under 5 %"), "{why}");
        // A mean error over 5 % of the diagonal, or not a number.
        let why = detail(40_000, 50_000, Some(0.42)).degenerate(1.0).unwrap();
        assert!(why.contains("42.00 %"), "{why}");
        assert!(
            detail(40_000, 50_000, Some(f64::NAN))
                .degenerate(1.0)
                .is_some()
        );
        // Not measured (--no-measure): the counts alone decide.
        assert_eq!(detail(40_000, 50_000, None).degenerate(1.0), None);
    }
}
