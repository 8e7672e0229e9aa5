//! The discrete LOD chain (HQMS): each level simplified from the previous
//! one, measured against the input through the shared [`Reference`], and
//! written as `lods/NAME_lodN.ply`, `lods/NAME_lods.glb` and
//! `lods/lods.json` (the files and layout of `lodkit lods`).
//!
//! The GLB is the chain as engines read it: level 0 (the input) is the
//! scene's node `NAME_LOD0` and carries `MSFT_lod` over `NAME_LOD1 …
//! NAME_LODn` (the suffix Unity's and Unreal's importers group by), with
//! `MSFT_screencoverage` from each level's error ([`coverage`]); every
//! level node's `extras.error` holds its measured error in object units
//! and in % of the input's diagonal ([`level_extras`]).

use std::path::Path;

use anyhow::{Context, Result};
use lodkit_mesh::io::gltf::{LodLevel, write_lod_glb};
use lodkit_mesh::io::{Format, WriteOptions, write_atomic};
use lodkit_mesh::metrics::Reference;
use lodkit_mesh::{Model, TriMesh};
use lodkit_simplify::{Options, Simplifier, Target};
use serde_json::{Map, Value, json};

use crate::measure::{Measured, Sampling};
use crate::output::OutputOptions;
use crate::progress::Progress;
use crate::report::{Level, Lods};

/// The screen coverage below which an error projects to at most a pixel
/// on a 1080-line screen (the one rule, shared with pylodkit's chains).
pub use lodkit_mesh::io::gltf::error_coverage as coverage;

/// The screen coverage each level of a chain is shown down to, from each
/// level's error (object units, level 0 first): level k is shown down to
/// the coverage at which level k + 1 becomes good enough ([`coverage`],
/// [`significant`]); the coarsest stays down to 0. The GLB writer then
/// makes them strictly decrease by the levels' sizes
/// (`lodkit_mesh::io::gltf::screen_coverages`).
pub fn level_coverages(errors: &[f64], diagonal: f64) -> Vec<f64> {
    (0..errors.len())
        .map(|k| {
            errors
                .get(k + 1)
                .map_or(0.0, |&e| significant(coverage(e, diagonal)))
        })
        .collect()
}

/// `x` to 4 significant digits: what the errors and coverages are good for
/// (sampling noise is larger), and a tenth of the chain GLB's JSON.
pub fn significant(x: f64) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return x;
    }
    format!("{x:.3e}").parse().unwrap_or(x)
}

/// A level node's extras: `lod` (its number; 0 is the input) and `error`:
/// `measured` (whether Metro distances were taken), `mean` / `max` (object
/// units) and `mean_percent_of_diagonal` / `max_percent_of_diagonal` when
/// measured, and always `estimated` (the simplifier's own estimate, object
/// units) with `estimated_percent_of_diagonal`. Under `--no-measure` only
/// the estimate is written, with `measured: false`. Numbers have 4
/// significant digits ([`significant`]).
pub fn level_extras(
    lod: usize,
    measured: Option<(f64, f64)>,
    estimated: f64,
    diagonal: f64,
) -> Map<String, Value> {
    let pct = |x: f64| {
        if diagonal > 0.0 {
            x / diagonal * 100.0
        } else {
            0.0
        }
    };
    let finite = |x: f64| {
        if x.is_finite() {
            json!(significant(x))
        } else {
            Value::Null
        }
    };
    let mut error = Map::new();
    error.insert("measured".into(), json!(measured.is_some()));
    if let Some((mean, max)) = measured {
        error.insert("mean".into(), finite(mean));
        error.insert("max".into(), finite(max));
        error.insert("mean_percent_of_diagonal".into(), finite(pct(mean)));
        error.insert("max_percent_of_diagonal".into(), finite(pct(max)));
    }
    error.insert("estimated".into(), finite(estimated));
    error.insert(
        "estimated_percent_of_diagonal".into(),
        finite(pct(estimated)),
    );
    let mut e = Map::new();
    e.insert("lod".into(), json!(lod));
    e.insert("error".into(), Value::Object(error));
    e
}

/// One level of a chain GLB ([`chain_glb`]).
pub struct GlbLevel<'a> {
    /// Its number; 0 is the input.
    pub lod: usize,
    pub mesh: &'a TriMesh,
    /// Its measured (mean, max) distance to the input, object units, when
    /// measured (the input's is `(0, 0)`).
    pub measured: Option<(f64, f64)>,
    /// The simplifier's estimate, object units.
    pub estimated: f64,
}

/// The chain GLB of `levels` (level 0, the input, first; each a node
/// `STEM_LODk` with [`level_extras`]), each level shown down to the
/// coverage at which the next one's error (its measured maximum, else its
/// estimate) is a pixel ([`level_coverages`] on `diagonal`, the input's
/// bounding-box diagonal); normals and compression as `output` says.
/// `lodkit lods`, `build` and pylodkit's batch all write their chain GLBs
/// here. Errors: no level. Cost: one pass over the meshes.
pub fn chain_glb(
    stem: &str,
    levels: &[GlbLevel],
    diagonal: f64,
    output: &OutputOptions,
) -> Result<Vec<u8>, lodkit_mesh::ParseError> {
    let with_normals: Vec<std::borrow::Cow<TriMesh>> = levels
        .iter()
        .map(|l| output.normals_for(l.mesh, Format::Glb).apply(l.mesh))
        .collect();
    let errors: Vec<f64> = levels
        .iter()
        .map(|l| l.measured.map_or(l.estimated, |(_, max)| max))
        .collect();
    let glb_levels: Vec<LodLevel> = levels
        .iter()
        .zip(&with_normals)
        .zip(level_coverages(&errors, diagonal))
        .map(|((l, m), coverage)| LodLevel {
            name: format!("{stem}_LOD{}", l.lod),
            mesh: m,
            extras: level_extras(l.lod, l.measured, l.estimated, diagonal),
            coverage,
        })
        .collect();
    write_lod_glb(&glb_levels, &output.glb())
}

/// The chain as written, with each level's mesh and measurement.
pub struct Chain {
    pub lods: Lods,
    pub meshes: Vec<TriMesh>,
    pub measured: Vec<Option<Measured>>,
    /// A scene's chain: each level's face materials (indices into the
    /// input scene's materials, as `meshes` order the faces).
    pub face_materials: Option<Vec<Vec<u32>>>,
}

/// Simplifies the reference's mesh into one level per target (each from
/// the previous level, with `opts`), measures each with `sampling`, and
/// writes `<stem>_lodN.ply`, `<stem>_lods.glb` and `lods.json` into `out`
/// (`input` is what `lods.json` names as the input, and what errors
/// name). `on_level` sees each level as soon as it is measured and
/// written, so a long chain can report one line per level as it goes.
/// `build` and `lodkit lods` both write their chains here; `output`
/// carries `--normals` (applied to what is written, after measuring) and
/// `--compress` (the GLB).
#[allow(clippy::too_many_arguments)]
pub(super) fn write_mesh_chain(
    events: &Progress,
    reference: &Reference,
    input: &str,
    stem: &str,
    out: &Path,
    targets: &[Target],
    opts: &Options,
    sampling: Sampling,
    output: &OutputOptions,
    on_level: &mut dyn FnMut(&Level),
) -> Result<Chain> {
    let mesh = reference.mesh();
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output directory", out.display()))?;
    let step = events.spinner("simplifying");
    let chain = Simplifier::new()
        .lod_chain(mesh, opts, targets)
        .map_err(|e| anyhow::anyhow!("{input}: {e}"))?;
    step.finish();
    let mut levels = Vec::with_capacity(chain.len());
    let mut meshes = Vec::with_capacity(chain.len());
    let mut measured = Vec::with_capacity(chain.len());
    for (i, l) in chain.into_iter().enumerate() {
        let file = format!("{stem}_lod{}.ply", i + 1);
        let step = events.spinner(&format!("measuring level {}", i + 1));
        let m = sampling.measure(reference, &l.mesh)?;
        step.finish();
        let bytes = output
            .encode(
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
    let diagonal = mesh.bbox().diagonal() as f64;
    // Level 0 is the input; then each non-empty level.
    let mut written = vec![GlbLevel {
        lod: 0,
        mesh,
        measured: Some((0.0, 0.0)),
        estimated: 0.0,
    }];
    for (l, (m, me)) in levels.iter().zip(meshes.iter().zip(&measured)) {
        if m.faces.is_empty() {
            continue;
        }
        written.push(GlbLevel {
            lod: l.level,
            mesh: m,
            measured: me.map(|x| (x.mean, x.max)),
            estimated: l.estimated_error as f64,
        });
    }
    let glb = chain_glb(stem, &written, diagonal, output)
        .map_err(|e| anyhow::anyhow!("{}: {e}", out.join(&glb_name).display()))?;
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
        face_materials: None,
    })
}

/// The line saying why a chain has fewer levels than asked: the chain
/// ends at the first level that would remove no triangle from the one
/// before ([`lodkit_simplify::lod_chain`]), rather than write it twice.
/// `None` when every level was made.
pub fn stopped_early(levels: &[Level], asked: usize) -> Option<String> {
    let last = levels.last()?;
    if levels.len() >= asked {
        return None;
    }
    let why = if last.stop == lodkit_simplify::StopReason::Reached.to_string() {
        String::new()
    } else {
        format!(" (level {}: {})", last.level, last.stop)
    };
    Some(format!(
        "note: stopped at level {} of {}: level {} would remove no triangle from level {}'s {}{why}",
        last.level,
        asked,
        last.level + 1,
        last.level,
        last.triangles
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extras_say_what_was_measured_and_coverage_falls_with_error() {
        let m = level_extras(2, Some((1e-4, 2.5e-3)), 1.234_567e-4, 0.25);
        assert_eq!(m["lod"], 2);
        let e = &m["error"];
        assert_eq!(e["measured"], true);
        assert_eq!(e["max"], 2.5e-3);
        assert_eq!(e["max_percent_of_diagonal"], 1.0);
        assert_eq!(e["estimated"], 1.235e-4);
        // --no-measure: the estimate only.
        let m = level_extras(1, None, 1e-4, 0.25);
        assert_eq!(m["error"]["measured"], false);
        assert!(m["error"].get("max").is_none());
        assert!(
            m["error"]["estimated_percent_of_diagonal"]
                .as_f64()
                .unwrap()
                > 0.0
        );
        // Zero error: full coverage; more error: less coverage.
        assert_eq!(coverage(0.0, 1.0), 1.0);
        assert!(coverage(1e-3, 1.0) > coverage(1e-2, 1.0));
        assert_eq!(coverage(1e-2, 1.0), (1.0f64 / 1e-2 / 1080.0).powi(2));
    }
}
