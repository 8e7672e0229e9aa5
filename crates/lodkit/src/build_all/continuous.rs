//! The continuous-LOD section: the marching cube octree (`NAME.mco`) and
//! its cuts at 50 / 10 / 1 % of full size, each measured against the input
//! next to HQMS simplifying the input to the same triangle count.
//!
//! A mesh input is built into the octree from the mesh itself (as `lodkit
//! mco build MESH` does, [`lodkit_mco::build_from_mesh`]) on a lattice
//! fine enough that the full-resolution cut has about as many triangles
//! as the input ([`lodkit_mco::mesh_resolution`]); a non-mesh input's own
//! reconstruction (see [`super::input`]) is the model.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use lodkit_mco::McoModel;
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::Reference;
use lodkit_simplify::{Options, Target};

use crate::measure::{Measured, Sampling, cell};
use crate::progress::Progress;

/// Largest memory (bytes) the octree of a mesh input may plan for: a
/// quarter of [`lodkit_mco::MAX_BUILD_BYTES`], so `build` stays well inside
/// the library's limit on a machine doing other work; a finer lattice is
/// coarsened until its estimate fits.
const MESH_BUILD_BYTES: u64 = lodkit_mco::MAX_BUILD_BYTES / 4;

/// The lattice resolution for the octree of `mesh`
/// ([`lodkit_mco::mesh_resolution`] within [`MESH_BUILD_BYTES`]).
pub fn mesh_resolution(mesh: &TriMesh) -> Result<Option<u32>> {
    Ok(lodkit_mco::mesh_resolution(mesh, MESH_BUILD_BYTES)?)
}

/// Fractions of the full triangle count the report cuts, per cent (the
/// full cut first: it is the product's finest level).
const PERCENTS: [f64; 4] = [100.0, 50.0, 10.0, 1.0];

/// One cut of the model, with the HQMS simplification of the same size.
pub struct Cut {
    pub percent: f64,
    pub lod: usize,
    pub mesh: TriMesh,
    pub mco: Option<Measured>,
    pub hqms: Option<Measured>,
}

impl Cut {
    /// The cut's measured mean error over HQMS's at the same size, when
    /// both were measured and HQMS's is not zero.
    pub fn mean_ratio(&self) -> Option<f64> {
        match (self.mco, self.hqms) {
            (Some(m), Some(h)) if h.mean > 0.0 => Some(m.mean / h.mean),
            _ => None,
        }
    }
}

/// What the section produced.
pub struct Continuous {
    pub cuts: Vec<Cut>,
    /// The `.mco` file, relative to the output folder.
    pub file: String,
    /// Triangles of the full-resolution cut.
    pub full_triangles: usize,
    /// Files written, relative to the output folder.
    pub files: Vec<String>,
}

/// Builds (or takes) the model, writes it, measures its cuts, and appends
/// the section to `report`.
pub fn section(
    events: &Progress,
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
            let step = events.spinner("building the marching cube octree from the mesh");
            let opts = lodkit_mco::Options {
                resolution: mesh_resolution(mesh).map_err(|e| anyhow::anyhow!("{name}: {e}"))?,
            };
            built = lodkit_mco::build_from_mesh(mesh, &opts)
                .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
            step.finish();
            &built
        }
    };
    let mco_file = format!("{name}.mco");
    model.save(&out.join(&mco_file))?;
    files.push(mco_file.clone());
    let step = events.spinner("measuring extractions");
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
        // The full cut is the product's finest level, held against the
        // input itself (the detail check); HQMS at about the input's size
        // is the input, nothing to compare.
        let hqms = if percent < 100.0 && cut.faces.len() < mesh.faces.len() {
            let s = lodkit_simplify::simplify(
                mesh,
                &Options {
                    target: Target::Faces(cut.faces.len()),
                    ..Options::DEFAULT
                },
            )
            .map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
            sampling.measure(reference, &s.mesh)?
        } else {
            None
        };
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
            "The input mesh built into a marching cube octree (`{mco_file}`, lattice resolution {}, \
             cube {:.3e}, chosen so the full cut keeps about the input's triangle count",
            model.grid().resolution(),
            model.grid().cube()
        )
    };
    writeln!(
        report,
        "## Continuous LOD (marching cube octree)\n\n{origin}: {} triangles at full resolution, LOD \
         numbers 0..={}). Any triangle budget is cut from it by referencing only; below, extractions \
         at fractions of full size, next to HQMS simplifying the input to the same count (*ratio*: \
         MCO mean ÷ HQMS mean); errors {}.\n",
        model.full_triangles(),
        model.max_lod(),
        sampling.describe(),
    )?;
    writeln!(
        report,
        "| % of full | LOD | triangles | samples | MCO mean | MCO max | HQMS mean | HQMS max | ratio |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    for c in &cuts {
        writeln!(
            report,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            c.percent,
            c.lod,
            c.mesh.faces.len(),
            c.mco.map_or("-".into(), |m| m.samples.to_string()),
            cell(c.mco.map(|m| m.mean)),
            cell(c.mco.map(|m| m.max)),
            cell(c.hqms.map(|m| m.mean)),
            cell(c.hqms.map(|m| m.max)),
            c.mean_ratio().map_or("-".into(), |r| format!("{r:.2}")),
        )?;
    }
    writeln!(report)?;
    Ok(Continuous {
        cuts,
        file: mco_file,
        full_triangles: full,
        files,
    })
}
