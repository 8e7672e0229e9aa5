//! The discrete LOD chain (HQMS): each level simplified from the previous
//! one, measured against the input through the shared [`Reference`], and
//! written as `lods/NAME_lodN.ply`, `lods/NAME_lods.glb` and
//! `lods/lods.json` (the files and layout of `lodkit lods`).

use std::path::Path;

use anyhow::Result;
use lodkit_mesh::io::{Format, WriteOptions, encode, gltf::write_glb, write_atomic};
use lodkit_mesh::metrics::Reference;
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::{Options, Simplifier, Target};

use super::measure::{Measured, Sampling};
use crate::commands::lods::{Level, Lods};
use crate::ui::Ui;

/// The chain as written, with each level's mesh and measurement.
pub struct Chain {
    pub lods: Lods,
    pub meshes: Vec<TriMesh>,
    pub measured: Vec<Option<Measured>>,
}

/// Simplifies the reference's mesh into one level per target, measures
/// each with `sampling`, and writes the files into `out`.
pub fn write_chain(
    ui: &Ui,
    reference: &Reference,
    stem: &str,
    out: &Path,
    targets: &[Target],
    sampling: Sampling,
) -> Result<Chain> {
    let mesh = reference.mesh();
    std::fs::create_dir_all(out)?;
    let step = ui.spinner("simplifying");
    let opts = Options {
        target: Target::Ratio(1.0),
        ..Options::DEFAULT
    };
    let chain = Simplifier::new()
        .lod_chain(mesh, &opts, targets)
        .map_err(|e| anyhow::anyhow!("{stem}: {e}"))?;
    step.finish();
    let mut levels = Vec::with_capacity(chain.len());
    let mut meshes = Vec::with_capacity(chain.len());
    let mut measured = Vec::with_capacity(chain.len());
    for (i, l) in chain.into_iter().enumerate() {
        let file = format!("{stem}_lod{}.ply", i + 1);
        let step = ui.spinner(&format!("measuring level {}", i + 1));
        let m = sampling.measure(reference, &l.mesh)?;
        step.finish();
        let bytes = encode(
            Format::Ply,
            &Model::Mesh(l.mesh.clone()),
            WriteOptions::default(),
        )
        .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
        write_atomic(&out.join(&file), &bytes)?;
        levels.push(Level {
            level: i + 1,
            file,
            target_triangles: l.report.target_faces,
            triangles: l.report.triangles,
            vertices: l.report.vertices,
            estimated_error: l.report.estimated_error,
            measured_mean_error: m.map_or(f64::NAN, |m| m.mean),
            measured_max_error: m.map_or(f64::NAN, |m| m.max),
            seconds: l.report.seconds,
            stop: l.report.stop.to_string(),
        });
        meshes.push(l.mesh);
        measured.push(m);
    }
    let glb_name = format!("{stem}_lods.glb");
    let names: Vec<String> = (1..=meshes.len())
        .map(|i| format!("{stem}_lod{i}"))
        .collect();
    let named: Vec<(&str, &TriMesh)> = names
        .iter()
        .zip(&meshes)
        .filter(|(_, m)| !m.faces.is_empty())
        .map(|(n, m)| (n.as_str(), m))
        .collect();
    let glb = write_glb(&named).map_err(|e| anyhow::anyhow!("{glb_name}: {e}"))?;
    write_atomic(&out.join(&glb_name), &glb)?;
    let lods = Lods {
        input: stem.to_string(),
        input_triangles: mesh.faces.len(),
        input_vertices: mesh.positions.len(),
        glb: glb_name,
        levels,
    };
    let json = serde_json::to_string_pretty(&lods)? + "\n";
    write_atomic(&out.join("lods.json"), json.as_bytes())?;
    Ok(Chain {
        lods,
        meshes,
        measured,
    })
}
