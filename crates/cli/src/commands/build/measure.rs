//! How `build` measures each level against its input: Metro distances
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
                lodkit_mesh::metrics::reference::LEVEL_SAMPLES_PER_FACE,
                lodkit_mesh::metrics::reference::MIN_LEVEL_SAMPLES,
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
