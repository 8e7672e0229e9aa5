//! The compare job (`lodkit compare A B`): Metro-style distances between
//! two meshes, and optionally B written coloured by each vertex's distance
//! to A (a heat map).
use std::path::{Path, PathBuf};

use anyhow::Result;
use lodkit_mesh::metrics::{CompareOptions, compare};

use crate::progress::Progress;

/// One comparison: what [`run`] reads and writes.
#[derive(Debug, Clone)]
pub struct CompareJob {
    /// First mesh (e.g. the original).
    pub a: PathBuf,
    /// Second mesh (e.g. the simplified one).
    pub b: PathBuf,
    /// Samples and seed; `samples: None` is 10 per face of the larger
    /// mesh, at least 1M, capped at [`crate::limits::MAX_SAMPLES`].
    pub options: CompareOptions,
    /// Also write B coloured by distance here (.ply, .obj or .glb).
    pub heatmap: Option<PathBuf>,
}

/// What [`run`] measured.
#[derive(Debug, serde::Serialize)]
pub struct CompareReport {
    #[serde(flatten)]
    pub report: lodkit_mesh::metrics::CompareReport,
    /// The heat map written, if asked for.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub heatmap: Option<Scale>,
}

/// Measures `job.b` against `job.a` (both loaded as meshes; sample counts
/// bounded by [`crate::limits::SAMPLES`], said in a note when the default
/// would exceed it) and writes the heat map atomically when asked.
/// Errors: either mesh named with what is wrong. Cost: about 100 bytes
/// and one nearest-point query a sample.
pub fn run(job: &CompareJob, events: &Progress) -> Result<CompareReport> {
    let a = crate::input::load_mesh(events, &job.a)?;
    let b = crate::input::load_mesh(events, &job.b)?;
    let names = (job.a.display().to_string(), job.b.display().to_string());
    let report = measure(&a, &b, (&names.0, &names.1), &job.options, events)?;
    let heatmap = match &job.heatmap {
        Some(out) => Some(write_heatmap(&a, &b, &job.a, out)?),
        None => None,
    };
    Ok(CompareReport { report, heatmap })
}

/// Measures `b` against `a` in memory, as [`run`] does (sample counts
/// bounded by [`crate::limits::SAMPLES`], said in a note when the default
/// would exceed it); `names` are how errors call the two meshes. Errors:
/// a mesh the metric refuses, named. Cost: about 100 bytes and one
/// nearest-point query a sample.
pub fn measure(
    a: &lodkit_mesh::TriMesh,
    b: &lodkit_mesh::TriMesh,
    names: (&str, &str),
    options: &CompareOptions,
    events: &Progress,
) -> Result<lodkit_mesh::metrics::CompareReport> {
    let n = options.resolved_samples(a.faces.len(), b.faces.len());
    if n > crate::limits::MAX_SAMPLES {
        events.status(format!(
            "sampling {} per kind rather than the default {n} (10 per face): the most --samples allows",
            crate::limits::MAX_SAMPLES
        ));
    }
    // The default grows with the meshes; the memory it sizes is bounded
    // like an explicit count.
    let n = n.min(crate::limits::MAX_SAMPLES);
    let opts = CompareOptions {
        samples: Some(n),
        ..*options
    };
    let step = events.stage(&format!("measuring ({n} samples of each kind per mesh)"));
    // The metric names the meshes "A" and "B"; the caller knows their names.
    let report = compare(a, b, &opts).map_err(|e| {
        let msg = e
            .to_string()
            .replace("mesh A", names.0)
            .replace("mesh B", names.1);
        anyhow::anyhow!("comparing {} with {}: {msg}", names.0, names.1)
    })?;
    step.finish();
    Ok(report)
}

use lodkit_mesh::io::{Format, WriteOptions, encode, write_atomic};
use lodkit_mesh::metrics::SurfaceIndex;
use lodkit_mesh::{Model, TriMesh};
use lodkit_render::colour_scale;

/// The colour scale written, for people and for `--json`.
#[derive(Debug, serde::Serialize)]
pub struct Scale {
    pub file: String,
    pub vertices: usize,
    /// Distance shown blue (object units).
    pub min: f32,
    /// Distance shown red: the largest of B's referenced vertices.
    pub max: f32,
    /// `max` as a percentage of A's bounding-box diagonal.
    pub max_percent_of_diagonal: f64,
    pub colours: &'static str,
}

impl Scale {
    pub fn line(&self) -> String {
        format!(
            "heat map: 0 (blue) … {:.6e} (red) object units, {:.4} % of the diagonal of A's bounding box",
            self.max, self.max_percent_of_diagonal
        )
    }
}

/// Whether `path` can hold a heat map (vertex colours and faces: .ply,
/// .obj or .glb); the CLI refuses anything else before running.
pub fn holds_heatmap(path: &Path) -> bool {
    matches!(
        Format::from_path(path),
        Some(Format::Ply | Format::Obj | Format::Glb)
    )
}

/// Writes `b` coloured by each vertex's distance to `a` as `out`.
fn write_heatmap(a: &TriMesh, b: &TriMesh, a_path: &Path, out: &Path) -> Result<Scale> {
    let index = SurfaceIndex::new(a)?;
    let d = index.distances(&b.positions);
    let mut used = vec![false; b.positions.len()];
    for f in &b.faces {
        for &v in f {
            used[v as usize] = true;
        }
    }
    let max = d
        .iter()
        .zip(&used)
        .filter(|(_, u)| **u)
        .map(|(d, _)| *d)
        .fold(0.0f32, f32::max);
    let colours = d
        .iter()
        .map(|&x| {
            let t = if max > 0.0 { x / max } else { 0.0 };
            let [r, g, b] = colour_scale(t);
            [r, g, b, 255]
        })
        .collect();
    let mesh = TriMesh {
        colors: Some(colours),
        ..b.clone()
    };
    let diagonal = index.bbox().diagonal() as f64;
    let scale = Scale {
        file: out.display().to_string(),
        vertices: b.positions.len(),
        min: 0.0,
        max,
        max_percent_of_diagonal: if diagonal > 0.0 {
            max as f64 / diagonal * 100.0
        } else {
            0.0
        },
        colours: "blue (0) → cyan → green → yellow → red (max), lodkit_render::colour_scale",
    };
    let format = Format::from_path(out)
        .filter(|_| holds_heatmap(out))
        .ok_or_else(|| {
            crate::usage::usage(format!(
                "{}: a heat map needs a format with vertex colours and faces: .ply, .obj or .glb",
                out.display()
            ))
        })?;
    let mut bytes = encode(format, &Model::Mesh(mesh), WriteOptions::default())
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.display()))?;
    let note = format!(
        "{}; per-vertex distance to {}",
        scale.line(),
        a_path.display()
    )
    // PLY and OBJ headers are ASCII lines.
    .replace('…', "...")
    .replace(['\n', '\r'], " ");
    match format {
        // After the `format` line, where PLY allows comments.
        Format::Ply => {
            let at = bytes
                .iter()
                .enumerate()
                .filter(|(_, c)| **c == b'\n')
                .nth(1)
                .map_or(0, |(i, _)| i + 1);
            bytes.splice(at..at, format!("comment {note}\n").into_bytes());
        }
        Format::Obj => {
            bytes.splice(0..0, format!("# {note}\n").into_bytes());
        }
        // GLB has no comment; the printed line and --json state the scale.
        _ => {}
    }
    write_atomic(out, &bytes)?;
    Ok(scale)
}
