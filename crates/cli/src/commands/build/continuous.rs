//! The continuous-LOD section: the marching cube octree (`NAME.mco`) and
//! its cuts at 50 / 10 / 1 % of full size, each measured against the input
//! next to HQMS simplifying the input to the same triangle count.
//!
//! A mesh input is first scanned from 8 virtual views (`scans/`, the
//! thesis's experiment) and rebuilt from the scans; a non-mesh input's own
//! reconstruction (see [`super::input`]) is the model.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use lodkit_mco::McoModel;
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::Reference;
use lodkit_simplify::{Options, Target};

use super::measure::{Measured, Sampling, cell};
use crate::ui::Ui;

/// The virtual scans of a mesh input: 8 views, alternately 30° above and
/// below the horizon, 300 × 300 samples each.
pub const BUILD_SCANS: lodkit_mco::ScanOptions = lodkit_mco::ScanOptions {
    views: 8,
    width: 300,
    height: 300,
    elevation_deg: 30.0,
    alternate: true,
    noise: 0.0,
    seed: 1,
};

/// Fractions of the full triangle count the report cuts, per cent.
const PERCENTS: [f64; 3] = [50.0, 10.0, 1.0];

/// One cut of the model, with the HQMS simplification of the same size.
pub struct Cut {
    pub percent: f64,
    pub lod: usize,
    pub mesh: TriMesh,
    pub mco: Option<Measured>,
    pub hqms: Option<Measured>,
}

/// What the section produced.
pub struct Continuous {
    pub cuts: Vec<Cut>,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

/// Builds (or takes) the model, writes it, measures its cuts, and appends
/// the section to `report`.
pub fn section(
    ui: &Ui,
    reference: &Reference,
    reconstruction: Option<&McoModel>,
    name: &str,
    out: &Path,
    sampling: Sampling,
    report: &mut String,
) -> Result<Continuous> {
    let mesh = reference.mesh();
    let mut files = Vec::new();
    let built;
    let model = match reconstruction {
        Some(m) => m,
        None => {
            let step = ui.spinner("scanning the input from 8 virtual views");
            let scans = lodkit_mco::scan_mesh(mesh, &BUILD_SCANS)?;
            let written = lodkit_mco::write_scans(&out.join("scans"), name, &scans)?;
            step.finish();
            for p in written {
                files.push(p.strip_prefix(out).unwrap_or(&p).display().to_string());
            }
            let step = ui.spinner("building the marching cube octree");
            built = lodkit_mco::build_from_range_images(&scans, &lodkit_mco::Options::default())?;
            step.finish();
            &built
        }
    };
    let mco_file = format!("{name}.mco");
    model.save(&out.join(&mco_file))?;
    files.push(mco_file.clone());
    let step = ui.spinner("measuring extractions");
    let full = model.full_triangles();
    let mut cuts = Vec::with_capacity(PERCENTS.len());
    let mut idx = Vec::new();
    for percent in PERCENTS {
        let target = ((full as f64 * percent / 100.0).round() as usize).max(1);
        let lod = model.extract_triangles(target, &mut idx);
        let cut = model.mesh_from_indices(&idx);
        if cut.faces.is_empty() {
            continue;
        }
        let mco = sampling.measure(reference, &cut)?;
        let s = lodkit_simplify::simplify(
            mesh,
            &Options {
                target: Target::Faces(cut.faces.len()),
                ..Options::DEFAULT
            },
        )
        .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
        let hqms = sampling.measure(reference, &s.mesh)?;
        cuts.push(Cut {
            percent,
            lod,
            mesh: cut,
            mco,
            hqms,
        });
    }
    step.finish();
    let origin = if reconstruction.is_some() {
        format!("The input's reconstruction (`{mco_file}`")
    } else {
        format!(
            "{} virtual range scans of the input ({}×{}, `scans/`, with `{name}.conf`) rebuilt as a \
             marching cube octree (`{mco_file}`",
            BUILD_SCANS.views, BUILD_SCANS.width, BUILD_SCANS.height
        )
    };
    writeln!(
        report,
        "## Continuous LOD (marching cube octree)\n\n{origin}: {} triangles at full resolution, LOD \
         numbers 0..={}). Any triangle budget is cut from it by referencing only; below, extractions \
         at fractions of full size, next to HQMS simplifying the input to the same count; errors {}.\n",
        model.full_triangles(),
        model.max_lod(),
        sampling.describe(),
    )?;
    writeln!(
        report,
        "| % of full | LOD | triangles | samples | MCO mean | MCO max | HQMS mean | HQMS max |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for c in &cuts {
        writeln!(
            report,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            c.percent,
            c.lod,
            c.mesh.faces.len(),
            c.mco.map_or("-".into(), |m| m.samples.to_string()),
            cell(c.mco.map(|m| m.mean)),
            cell(c.mco.map(|m| m.max)),
            cell(c.hqms.map(|m| m.mean)),
            cell(c.hqms.map(|m| m.max)),
        )?;
    }
    writeln!(report)?;
    Ok(Continuous { cuts, files })
}
