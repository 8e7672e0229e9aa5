//! The progressive-stream section: the input as octree particles
//! (`NAME.pop`, entropy mode, outer thinning) and, per level, the bytes a
//! reader needs so far, the particles, the triangles of the direct
//! triangulation and their error against the input.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::io::write_atomic;
use lodkit_mesh::metrics::Reference;
use lodkit_mesh::{Model, TriMesh};
use lodkit_particles::{
    EncodeOptions, ThinningOptions, TriangulateOptions, encode, progressive_levels,
};

use super::measure::{Measured, Sampling, cell};
use crate::ui::Ui;

/// One decodable level of the stream.
pub struct StreamLevel {
    pub level: usize,
    pub precision: u8,
    pub bytes_so_far: u64,
    pub particles: usize,
    pub mesh: TriMesh,
    pub measured: Option<Measured>,
}

/// What the section produced.
pub struct Progressive {
    pub file: String,
    pub bytes: usize,
    pub levels: Vec<StreamLevel>,
}

/// Encodes `source`, writes it, measures every level, and appends the
/// section to `report`.
pub fn section(
    ui: &Ui,
    reference: &Reference,
    source: &Model,
    name: &str,
    out: &Path,
    sampling: Sampling,
    report: &mut String,
) -> Result<Progressive> {
    let step = ui.spinner("encoding the progressive particle stream");
    // Outer thinning keeps non-manifold triangles rare (see crates/particles).
    let opts = EncodeOptions {
        thinning: ThinningOptions {
            outer: true,
            ..ThinningOptions::DEFAULT
        },
        ..EncodeOptions::DEFAULT
    };
    // Outer thinning can leave nothing of a thin, one-sided sampling (a
    // single range image); such an input is encoded with the default
    // thinning instead, and the report says so.
    let (enc, outer) = match encode(source, &opts) {
        Ok(e) => (e, true),
        Err(_) => (
            encode(source, &EncodeOptions::DEFAULT).map_err(|e| anyhow::anyhow!("{name}: {e}"))?,
            false,
        ),
    };
    let file = format!("{name}.pop");
    write_atomic(&out.join(&file), &enc.bytes)?;
    step.finish();
    let step = ui.spinner("decoding and measuring every level");
    let decoded = progressive_levels(&enc.bytes, &TriangulateOptions::DEFAULT)
        .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
    let from = match source {
        Model::Mesh(_) => "",
        _ => " from the input's points",
    };
    writeln!(
        report,
        "## Progressive stream (octree particles)\n\n`{file}` ({} bytes, entropy-coded{from}, {}{}): \
         a reader that has the first *bytes so far* can show level *r*, triangulated directly from its \
         particles, with *N* bits per coordinate (the level chunks alone give N = R; the refinement \
         layers that follow them bring the finest level to the stream's full precision); errors {}.\n",
        enc.bytes.len(),
        if outer {
            "outer thinning"
        } else {
            "default thinning (outer thinning left no particle of this input)"
        },
        enc.report.relax_below.map_or(String::new(), |l| format!(
            " relaxed below level {l}, the level chosen for this object"
        )),
        sampling.describe(),
    )?;
    writeln!(
        report,
        "| level | N | bytes so far | particles | triangles | samples | mean error | max error |\n\
         |---:|---:|---:|---:|---:|---:|---:|---:|"
    )?;
    let mut levels = Vec::with_capacity(decoded.len());
    for l in decoded {
        let measured = sampling.measure(reference, &l.mesh)?;
        writeln!(
            report,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            l.level,
            l.precision,
            l.bytes_so_far,
            l.particles,
            l.mesh.faces.len(),
            measured.map_or("-".into(), |m| m.samples.to_string()),
            cell(measured.map(|m| m.mean)),
            cell(measured.map(|m| m.max)),
        )?;
        levels.push(StreamLevel {
            level: l.level as usize,
            precision: l.precision,
            bytes_so_far: l.bytes_so_far as u64,
            particles: l.particles,
            mesh: l.mesh,
            measured,
        });
    }
    writeln!(report)?;
    step.finish();
    Ok(Progressive {
        file,
        bytes: enc.bytes.len(),
        levels,
    })
}
