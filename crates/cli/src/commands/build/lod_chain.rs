//! The discrete LOD chain (HQMS): each level simplified from the previous
//! one, measured against the input through the shared [`Reference`], and
//! written as `lods/NAME_lodN.ply`, `lods/NAME_lods.glb` and
//! `lods/lods.json` (the files and layout of `lodkit lods`).

use std::path::Path;

use anyhow::{Context, Result};
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

/// Simplifies the reference's mesh into one level per target (each from
/// the previous level, with `opts`), measures each with `sampling`, and
/// writes `<stem>_lodN.ply`, `<stem>_lods.glb` and `lods.json` into `out`
/// (`input` is what `lods.json` names as the input, and what errors
/// name). `on_level` sees each level as soon as it is measured and
/// written, so a long chain can report one line per level as it goes.
/// `build` and `lodkit lods` both write their chains here.
#[allow(clippy::too_many_arguments)]
pub fn write_chain(
    ui: &Ui,
    reference: &Reference,
    input: &str,
    stem: &str,
    out: &Path,
    targets: &[Target],
    opts: &Options,
    sampling: Sampling,
    on_level: &mut dyn FnMut(&Level),
) -> Result<Chain> {
    let mesh = reference.mesh();
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output directory", out.display()))?;
    let step = ui.spinner("simplifying");
    let chain = Simplifier::new()
        .lod_chain(mesh, opts, targets)
        .map_err(|e| anyhow::anyhow!("{input}: {e}"))?;
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
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.join(&file).display()))?;
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
        on_level(levels.last().expect("just pushed"));
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
    let glb =
        write_glb(&named).map_err(|e| anyhow::anyhow!("{}: {e}", out.join(&glb_name).display()))?;
    write_atomic(&out.join(&glb_name), &glb)?;
    let lods = Lods {
        input: input.to_string(),
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
