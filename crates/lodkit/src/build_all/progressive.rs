//! The progressive-stream section: the input as octree particles
//! (`NAME.pop`, entropy mode) and, per level, the bytes a reader needs so
//! far, the particles, the triangles of the direct triangulation and their
//! error against the input.
//!
//! **Depth.** A mesh's octree depth is the particles crate's own (a leaf
//! about its mean edge). A reconstructed input (point cloud, range images)
//! is encoded from its reconstructed surface, at the depth whose leaves
//! number about the input's samples ([`surface_depth`]): the stream keeps
//! the input's detail, and its levels triangulate without the holes a
//! direct triangulation of raw points at one sample a leaf has (on a
//! 21k-point stereo cloud: mean error 5.0e-4 from the surface, 1.1e-2
//! from the points).
//!
//! **Thinning** (Yemez & Schmitt §4.3): inner thinning always; outer
//! thinning only for a closed surface (and carved particles, closed by
//! construction). Outer thinning drops every cube with no IN face
//! neighbour, and the paper assumes a closed surface whose inside is known
//! (§8.1.2). A one-sided sampling — a point cloud, a range image, an open
//! scan — has no inside its flood fill or normals can find reliably:
//! nearly every cube lacks an IN neighbour, and outer thinning left a few
//! hundred particles of a 460,000-point scan.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::io::write_atomic;
use lodkit_mesh::metrics::Reference;
use lodkit_mesh::{Model, TriMesh};
use lodkit_particles::{
    EncodeOptions, Encoded, ThinningOptions, TriangulateOptions, encode, progressive_levels,
};

use super::input::{BuildInput, InputPath};
use crate::measure::{Measured, Sampling, cell};
use crate::progress::Progress;

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

/// How a stream is encoded: its octree depth (`None`: the encoder's own)
/// and whether outer thinning applies.
#[derive(Clone, Copy, Debug)]
pub struct Plan {
    pub depth: Option<u8>,
    pub outer: bool,
}

/// The plan for `input` (see the module docs): a mesh at the encoder's
/// depth, a reconstructed surface at [`surface_depth`], carved particles
/// at the carving's depth with outer thinning (a closed shell); outer
/// thinning for closed surfaces only.
pub fn plan(input: &BuildInput) -> Plan {
    let closed = is_closed_mesh(&input.stream_source);
    match input.path {
        InputPath::Mesh => Plan {
            depth: None,
            outer: closed,
        },
        InputPath::Reconstructed(_) => Plan {
            depth: surface_depth(&input.surface, input.samples.0),
            outer: closed,
        },
        // Every carved particle is a cell of the carving's depth.
        InputPath::Carved(_, depth) => Plan {
            depth: Some(depth),
            outer: true,
        },
    }
}

/// Encodes `source` with `opts`; when `opts` sets a depth and the finest
/// level's particles fall outside `[samples / 2, 2 · samples]`, one level
/// deeper (too few) or shallower (too many) is tried too, and the encoding
/// whose count is nearer `samples` (by ratio) kept. [`surface_depth`]'s
/// estimate of the occupied leaves is good to a factor of about 1.5 (flat
/// axis-aligned tables occupy fewer leaves than curved surfaces), and a
/// level is 4 times the one above it: the count decides. Errors as
/// [`encode`]'s. Cost: one or two encodings.
pub(crate) fn encode_near(source: &Model, opts: &EncodeOptions, samples: usize) -> Result<Encoded> {
    let first = encode(source, opts)?;
    let Some(depth) = opts.depth else {
        return Ok(first);
    };
    let n = first.report.particles;
    let next = if 2 * n < samples && depth < DEEPEST {
        depth + 1
    } else if n > 2 * samples && depth > 1 {
        depth - 1
    } else {
        return Ok(first);
    };
    let off = |e: &Encoded| {
        (e.report.particles.max(1) as f64 / samples.max(1) as f64)
            .ln()
            .abs()
    };
    match encode(
        source,
        &EncodeOptions {
            depth: Some(next),
            ..*opts
        },
    ) {
        Ok(second) if off(&second) < off(&first) => Ok(second),
        _ => Ok(first),
    }
}

/// Occupied leaves per leaf² of surface area: about 1.5 (`|nx| + |ny| +
/// |nz|` averaged over orientations).
const LEAVES_PER_AREA: f64 = 1.5;
/// The deepest octree [`surface_depth`] picks: 12, the most `lodkit pop
/// encode --depth` takes.
const DEEPEST: u8 = 12;

/// The octree depth at which `surface` occupies about `samples` leaves:
/// a leaf edge of `sqrt(LEAVES_PER_AREA · area / samples)` in the
/// encoder's cube (the longest side of the box, plus 1/1024), rounded to
/// the nearest level (so within 2× of `samples` before thinning), in
/// `1..=`[`DEEPEST`]. `None` without area or samples. Cost: one pass over
/// the faces.
pub fn surface_depth(surface: &TriMesh, samples: usize) -> Option<u8> {
    let area = surface.area_f64();
    let size = f64::from(surface.bbox().size().max_element()) * (1.0 + 1.0 / 1024.0);
    if !(area > 0.0 && size > 0.0) || samples == 0 {
        return None;
    }
    let leaf = (LEAVES_PER_AREA * area / samples as f64).sqrt();
    Some((size / leaf).log2().round().clamp(1.0, f64::from(DEEPEST)) as u8)
}

/// Encodes `input`'s stream source as [`plan`] says, writes it, measures every level, and appends the
/// section to `report`.
pub fn section(
    events: &Progress,
    reference: &Reference,
    input: &BuildInput,
    out: &Path,
    sampling: Sampling,
    report: &mut String,
) -> Result<Progressive> {
    let (source, plan, name) = (&input.stream_source, plan(input), input.name.as_str());
    let step = events.spinner("encoding the progressive particle stream");
    let opts = EncodeOptions {
        depth: plan.depth,
        thinning: ThinningOptions {
            outer: plan.outer,
            ..ThinningOptions::DEFAULT
        },
        ..EncodeOptions::DEFAULT
    };
    // The plan can still fail (outer thinning leaving nothing of a thin
    // part, a depth over the mesh's sample limit): the crate's defaults
    // then, and the report says so.
    let (enc, planned) = match encode_near(source, &opts, input.samples.0) {
        Ok(e) => (e, true),
        Err(_) => (
            encode(source, &EncodeOptions::DEFAULT).map_err(|e| anyhow::anyhow!("{name}: {e}"))?,
            false,
        ),
    };
    let outer = planned && plan.outer;
    let file = format!("{name}.pop");
    write_atomic(&out.join(&file), &enc.bytes)?;
    step.finish();
    let step = events.spinner("decoding and measuring every level");
    let decoded = progressive_levels(&enc.bytes, &TriangulateOptions::DEFAULT)
        .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
    let from = if matches!(input.path, InputPath::Reconstructed(_)) {
        " from the reconstructed surface, its depth set so its leaves number about the input's samples"
    } else {
        ""
    };
    writeln!(
        report,
        "## Progressive stream (octree particles)\n\n`{file}` ({} bytes, entropy-coded{from}, {}{}): \
         a reader that has the first *bytes so far* can show level *r*, triangulated directly from its \
         particles, with *N* bits per coordinate (the level chunks alone give N = R; the refinement \
         layers that follow them bring the finest level to the stream's full precision); errors {}.\n",
        enc.bytes.len(),
        match (outer, planned) {
            (true, _) => "inner and outer thinning (a closed surface)",
            (false, true) => "inner thinning only (outer thinning is for closed surfaces)",
            (false, false) =>
                "the encoder's own depth and inner thinning (the planned encoding failed)",
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

/// Whether `model` is a mesh with faces and no boundary edge (every edge
/// shared by two or more faces). Cost: one sort of its edges.
fn is_closed_mesh(model: &Model) -> bool {
    matches!(model, Model::Mesh(m) if !m.faces.is_empty()
        && lodkit_mesh::topology::edge_multiplicities(m).iter().all(|e| e.count != 1))
}
