//! The progressive-stream section: the input as octree particles
//! (`NAME.pop`, entropy mode) and, per level, the bytes a reader needs so
//! far, the particles, the triangles of the direct triangulation and their
//! error against the input.
//!
//! **Depth.** A mesh's octree depth is the particles crate's own (a leaf
//! about its mean edge). Points and range samples get the shallowest depth
//! whose occupied leaves number at least half their distinct samples
//! ([`points_depth`]): a leaf at the sample spacing, so the finest level
//! keeps about the input's sample count. The crate's automatic depth aims
//! at three samples a leaf, a third of the detail or less.
//!
//! **Thinning** (Yemez & Schmitt §4.3): inner thinning always; outer
//! thinning only for a closed mesh. Outer thinning drops every cube with
//! no IN face neighbour, and the paper assumes a closed surface whose
//! inside is known (§8.1.2). A one-sided sampling — a point cloud, a range
//! image, an open scan — has no inside its flood fill or normals can find
//! reliably: nearly every cube lacks an IN neighbour, and outer thinning
//! left a few hundred particles of a 460,000-point scan.

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
    let closed = is_closed_mesh(source);
    // Outer thinning keeps non-manifold triangles rare (see crates/particles).
    let opts = EncodeOptions {
        depth: points_depth(source),
        thinning: ThinningOptions {
            outer: closed,
            ..ThinningOptions::DEFAULT
        },
        ..EncodeOptions::DEFAULT
    };
    // Outer thinning can still leave nothing of a thin part; such an input
    // is encoded with inner thinning only, and the report says so.
    let (enc, outer) = match encode(source, &opts) {
        Ok(e) => (e, closed),
        Err(_) if closed => (
            encode(
                source,
                &EncodeOptions {
                    thinning: ThinningOptions::DEFAULT,
                    ..opts
                },
            )
            .map_err(|e| anyhow::anyhow!("{name}: {e}"))?,
            false,
        ),
        Err(e) => return Err(anyhow::anyhow!("{name}: {e}")),
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
        match (outer, closed) {
            (true, _) => "inner and outer thinning (a closed mesh)",
            (false, true) => "inner thinning (outer thinning left no particle of this input)",
            (false, false) => "inner thinning only (outer thinning is for closed surfaces)",
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

/// The deepest octree [`points_depth`] picks: 12, the most `lodkit pop
/// encode --depth` takes (a leaf of 1/4096 of the model's cube).
const DEEPEST: u8 = 12;
/// Bits per coordinate of [`lodkit_particles::Frame::quantise`]: a leaf of
/// level `r` is the top `r` of them.
const QUANTISE_BITS: u32 = 16;

/// The octree depth of a stream of points or range samples: the shallowest
/// level `r` (1..=[`DEEPEST`]) whose occupied leaves
/// number at least half the samples' distinct leaves at level
/// [`DEEPEST`], in the octree's own frame ([`lodkit_particles::Frame`]),
/// so the finest level keeps between half and all of the input's distinct
/// samples. `None` for a mesh (the encoder's depth from its edges) or
/// when no sample is finite. Cost: `O(n log n)`, a sort per tried level
/// (a binary search over the levels).
pub fn points_depth(model: &Model) -> Option<u8> {
    let cloud;
    let points: &[lodkit_mesh::glam::Vec3] = match model {
        Model::Mesh(_) => return None,
        Model::Points(c) => &c.positions,
        Model::Range(r) => {
            cloud = r.to_point_cloud();
            &cloud.positions
        }
    };
    let finite: Vec<lodkit_mesh::glam::Vec3> =
        points.iter().copied().filter(|p| p.is_finite()).collect();
    if finite.is_empty() {
        return None;
    }
    let bbox = lodkit_mesh::Aabb::from_points(&finite);
    let frame = lodkit_particles::Frame::around(bbox.min, bbox.max);
    let q: Vec<[u32; 3]> = finite.iter().map(|&p| frame.quantise(p)).collect();
    let mut keys = Vec::with_capacity(q.len());
    let mut occupied = |r: u8| -> usize {
        let s = QUANTISE_BITS - u32::from(r);
        keys.clear();
        keys.extend(q.iter().map(|c| {
            (u64::from(c[0] >> s) << 32) | (u64::from(c[1] >> s) << 16) | u64::from(c[2] >> s)
        }));
        keys.sort_unstable();
        keys.dedup();
        keys.len()
    };
    let (mut lo, mut hi) = (1u8, DEEPEST);
    let goal = occupied(hi).div_ceil(2);
    // The occupied count grows with the level: the first level at the goal.
    while lo < hi {
        let mid = lo + (hi - lo) / 2;
        if occupied(mid) >= goal {
            hi = mid;
        } else {
            lo = mid + 1;
        }
    }
    Some(lo)
}
