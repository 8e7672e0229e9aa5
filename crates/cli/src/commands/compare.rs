//! `lodkit compare A B`: Metro-style distances.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit_mesh::metrics::{CompareOptions, compare};

use crate::ui::Ui;
use crate::ui::value;

#[derive(Args)]
pub struct CompareArgs {
    /// First mesh (e.g. the original).
    pub a: PathBuf,
    /// Second mesh (e.g. the simplified one).
    pub b: PathBuf,
    /// Samples of each kind (vertex, edge, face) per mesh, MeshLab's
    /// `SampleNum`, in 1..=10000000 (default: max(10 × faces of the larger
    /// mesh, 1M), at most 10000000).
    #[arg(long, value_parser = value::range(lodkit::limits::SAMPLES))]
    pub samples: Option<usize>,
    /// Seed of the sample positions (same seed → identical numbers).
    #[arg(long, default_value_t = lodkit_mesh::metrics::DEFAULT_SEED)]
    pub seed: u64,
    /// Skip vertex samples.
    #[arg(long)]
    pub no_vertex_samples: bool,
    /// Skip edge samples.
    #[arg(long)]
    pub no_edge_samples: bool,
    /// Skip face samples.
    #[arg(long)]
    pub no_face_samples: bool,
    /// Print the report as JSON.
    #[arg(long)]
    pub json: bool,
    /// Also write B with per-vertex colours from each vertex's distance to
    /// A (blue = 0 to red = the largest), as .ply, .obj or .glb.
    #[arg(long, value_name = "OUT", value_parser = heatmap::parse_output)]
    pub heatmap: Option<PathBuf>,
}

pub fn run(ui: &Ui, args: &CompareArgs) -> Result<()> {
    let a = super::load_mesh(ui, &args.a)?;
    let b = super::load_mesh(ui, &args.b)?;
    let opts = CompareOptions {
        samples: args.samples,
        seed: args.seed,
        vertex_samples: !args.no_vertex_samples,
        edge_samples: !args.no_edge_samples,
        face_samples: !args.no_face_samples,
    };
    let n = opts.resolved_samples(a.faces.len(), b.faces.len());
    if n > lodkit::limits::MAX_SAMPLES {
        ui.status(format!(
            "sampling {} per kind rather than the default {n} (10 per face): the most --samples allows",
            lodkit::limits::MAX_SAMPLES
        ));
    }
    // The default grows with the meshes; the memory it sizes is bounded
    // like an explicit `--samples`.
    let opts = CompareOptions {
        samples: Some(n.min(lodkit::limits::MAX_SAMPLES)),
        ..opts
    };
    let n = n.min(lodkit::limits::MAX_SAMPLES);
    let step = ui.stage(&format!("measuring ({n} samples of each kind per mesh)"));
    // The library names the meshes "A" and "B"; the user knows their paths.
    let report = compare(&a, &b, &opts).map_err(|e| {
        let msg = e
            .to_string()
            .replace("mesh A", &args.a.display().to_string())
            .replace("mesh B", &args.b.display().to_string());
        anyhow::anyhow!(
            "comparing {} with {}: {msg}",
            args.a.display(),
            args.b.display()
        )
    })?;
    step.finish();
    let heat = match &args.heatmap {
        Some(out) => Some(heatmap::write(&a, &b, &args.a, out)?),
        None => None,
    };
    if args.json {
        #[derive(serde::Serialize)]
        struct WithHeatmap<'a> {
            #[serde(flatten)]
            report: &'a lodkit_mesh::metrics::CompareReport,
            heatmap: &'a heatmap::Scale,
        }
        return match &heat {
            Some(h) => super::print_json(&WithHeatmap {
                report: &report,
                heatmap: h,
            }),
            None => super::print_json(&report),
        };
    }
    crate::outln!("A: {}\nB: {}", args.a.display(), args.b.display())?;
    crate::outln!("{report}")?;
    if let Some(h) = &heat {
        crate::outln!("{}", h.line())?;
        ui.status(format!(
            "wrote {} (B's {} vertices coloured by their distance to A)",
            h.file, h.vertices
        ));
    }
    Ok(())
}

/// `--heatmap`: B coloured by the distance of each vertex to A.
mod heatmap {
    use std::path::{Path, PathBuf};

    use anyhow::Result;
    use lodkit_mesh::io::{Format, WriteOptions, encode, write_atomic};
    use lodkit_mesh::metrics::SurfaceIndex;
    use lodkit_mesh::{Model, TriMesh};
    use lodkit_render::colour_scale;

    /// The colour scale written, for people and for `--json`.
    #[derive(serde::Serialize)]
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

    /// The output must hold vertex colours: refused otherwise (exit 2).
    pub fn parse_output(s: &str) -> std::result::Result<PathBuf, String> {
        let p = PathBuf::from(s);
        match Format::from_path(&p) {
            Some(Format::Ply | Format::Obj | Format::Glb) => Ok(p),
            _ => Err(format!(
                "{s}: a heat map needs a format with vertex colours and faces: .ply, .obj or .glb"
            )),
        }
    }

    pub fn write(a: &TriMesh, b: &TriMesh, a_path: &Path, out: &Path) -> Result<Scale> {
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
        let format = Format::from_path(out).expect("checked by the option's parser");
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
}
