//! The LOD chain of a binary PLY over the memory budget: the chain made by
//! [`lodkit_scale::lod_chain_file`]. Levels too big for the budget come
//! out of one block round each and are streamed to PLY from their blocks;
//! the first level that fits is made as `simplify` makes an out-of-core
//! result (blocks, then the final in-core pass), the rest in core from
//! it. Written: `<stem>_lodN.ply` per level, `<stem>_lods.glb` with the
//! in-core levels as an `MSFT_lod` chain (the input and the big levels
//! would not fit a GLB's 2 GB, nor a game engine), and `lods.json`, whose
//! measured errors are null (measuring needs the input in memory).
use std::path::Path;
use std::time::Instant;

use anyhow::Result;
use lodkit_mesh::io::gltf::{LodLevel, write_lod_glb};
use lodkit_mesh::io::{Format, WriteOptions, write_atomic};
use lodkit_mesh::{Model, TriMesh};
use lodkit_scale::{ChainLevel, ScaleOptions, lod_chain_file, write_soups_ply};
use lodkit_simplify::{Options, Target};

use super::job::{LodChainJob, LodChainReport};
use super::write::{level_coverages, level_extras};
use crate::plan::{Plan, kept, remove_staging};
use crate::progress::{Event, Progress, human_bytes};
use crate::report::{Level, Lods};

/// Runs the chain of `a` with `targets` and `opts` out of core (`plan`
/// says why and with which budget). The staging folder sits in the
/// output folder and is removed once `lods.json` is written; a failed or
/// interrupted run keeps it, and the same command resumes from it.
pub fn run(
    events: &Progress,
    a: &LodChainJob,
    stem: &str,
    targets: &[Target],
    opts: &Options,
    plan: &Plan,
) -> Result<LodChainReport> {
    std::fs::create_dir_all(&a.out)
        .map_err(|e| anyhow::anyhow!("{}: cannot create output directory: {e}", a.out.display()))?;
    let settings = format!("lods {targets:?} {opts:?}; memory {}", plan.memory);
    let chain = a.out.join(format!("{stem}_lods"));
    let staging = lodkit_scale::staging_dir(&a.input, &chain, &settings);
    for old in lodkit_scale::remove_abandoned(&chain, &staging) {
        if a.notes {
            events.status(format!(
                "removed {}, the staging folder an earlier run for this chain left",
                old.display()
            ));
        }
    }
    if a.notes {
        events.status(format!(
            "out of core: {} ({}) needs about {} in core ({} B per face), over --memory {}; \
             making the chain in blocks (levels are not measured)",
            a.input.display(),
            human_bytes(plan.file_bytes),
            human_bytes(plan.in_core),
            lodkit_scale::IN_CORE_BYTES_PER_FACE,
            human_bytes(plan.memory),
        ));
        if staging.exists() {
            events.status(format!(
                "resuming: {} blocks already done (in {})",
                lodkit_scale::finished_blocks(&staging),
                staging.display()
            ));
        }
    }
    let so = ScaleOptions {
        simplify: opts.clone(),
        memory: plan.memory,
        staging: staging.clone(),
        runner: a.scale.runner(),
    };
    let n = plan.faces as usize;
    let start = Instant::now();
    let mut levels: Vec<Level> = Vec::with_capacity(targets.len());
    // The in-core levels, for the GLB: (level, mesh, estimated error).
    let mut in_core: Vec<(usize, TriMesh, f32)> = Vec::new();
    let mut t_level = Instant::now();
    let result = lod_chain_file(
        &a.input,
        targets,
        &so,
        &|e| match e {
            lodkit_scale::Event::Phase(name, len) => events.emit(&Event::Phase { name, len }),
            lodkit_scale::Event::Advance(k) => events.emit(&Event::Advance(k)),
        },
        &mut |i, l| {
            let file = format!("{stem}_lod{}.ply", i + 1);
            let path = a.out.join(&file);
            let (triangles, vertices, estimated, stop) = match l {
                ChainLevel::Soups {
                    faces,
                    layout,
                    files,
                } => {
                    events.emit(&Event::Phase {
                        name: &format!("writing {file}"),
                        len: faces,
                    });
                    let (f, v) = write_soups_ply(files, layout, &path)?;
                    events.emit(&Event::Advance(faces));
                    (f, v, f32::NAN, "out of core: one block round".to_string())
                }
                ChainLevel::Resumed { faces } => {
                    let v = lodkit_mesh::io::ply::stream::PlyStream::open(&path)
                        .map_err(|e| {
                            format!(
                                "{e} (an earlier run made this level; remove {} to start over)",
                                staging.display()
                            )
                        })?
                        .vertex_count();
                    (faces, v, f32::NAN, "made by an earlier run".to_string())
                }
                ChainLevel::Mesh { mesh, report } => {
                    let bytes = a
                        .output
                        .encode(
                            Format::Ply,
                            &Model::Mesh(mesh.clone()),
                            WriteOptions::default(),
                        )
                        .map_err(|e| format!("{}: {e}", path.display()))?;
                    write_atomic(&path, &bytes).map_err(|e| e.to_string())?;
                    in_core.push((i + 1, mesh.clone(), report.estimated_error));
                    (
                        report.triangles as u64,
                        report.vertices as u64,
                        report.estimated_error,
                        report.stop.to_string(),
                    )
                }
            };
            let level = Level {
                level: i + 1,
                file,
                target_triangles: targets[i].faces(n),
                triangles: triangles as usize,
                vertices: vertices as usize,
                estimated_error: estimated,
                measured_mean_error: f64::NAN,
                measured_max_error: f64::NAN,
                seconds: t_level.elapsed().as_secs_f64(),
                stop,
            };
            t_level = Instant::now();
            if a.notes {
                events.emit(&Event::PhasesFinished);
                events.status(format!(
                    "level {}: {} triangles, {} vertices: {}",
                    level.level, level.triangles, level.vertices, level.stop
                ));
            }
            levels.push(level);
            Ok(())
        },
    );
    events.emit(&Event::PhasesFinished);
    let rep = result.map_err(|e| kept(&e, &staging))?;
    if let Some(line) = super::write::stopped_early(&levels, targets.len()) {
        events.status(line);
    }
    let glb = format!("{stem}_lods.glb");
    write_glb(&a.out.join(&glb), stem, &in_core, a).map_err(|e| kept(&e, &staging))?;
    let input_vertices = lodkit_mesh::io::ply::stream::PlyStream::open(&a.input)
        .map_or(0, |s| s.vertex_count() as usize);
    let lods = Lods {
        input: a.input.display().to_string(),
        input_triangles: rep.input_faces as usize,
        input_vertices,
        glb: glb.clone(),
        levels,
    };
    let json = serde_json::to_string_pretty(&lods)? + "\n";
    write_atomic(&a.out.join("lods.json"), json.as_bytes()).map_err(|e| kept(&e, &staging))?;
    remove_staging(events, &staging);
    let summary = format!(
        "wrote {} levels ({} out of core), {glb} ({} in-core levels) and lods.json to {} ({:.3} s)",
        lods.levels.len(),
        lods.levels.len() - in_core.len(),
        in_core.len(),
        a.out.display(),
        start.elapsed().as_secs_f64(),
    );
    Ok(LodChainReport { json, summary })
}

/// The GLB of the in-core levels, an `MSFT_lod` chain from the finest
/// (errors: the simplifier's estimates, which cover the in-core passes
/// only). No level in core: no GLB is written.
fn write_glb(
    path: &Path,
    stem: &str,
    in_core: &[(usize, TriMesh, f32)],
    a: &LodChainJob,
) -> Result<()> {
    let kept: Vec<&(usize, TriMesh, f32)> =
        in_core.iter().filter(|l| !l.1.faces.is_empty()).collect();
    if kept.is_empty() {
        return Ok(());
    }
    let diagonal = kept[0].1.bbox().diagonal() as f64;
    let with_normals: Vec<std::borrow::Cow<TriMesh>> = kept
        .iter()
        .map(|l| a.output.normals_for(&l.1, Format::Glb).apply(&l.1))
        .collect();
    let errors: Vec<f64> = kept.iter().map(|l| l.2 as f64).collect();
    let levels: Vec<LodLevel> = kept
        .iter()
        .zip(&with_normals)
        .zip(level_coverages(&errors, diagonal))
        .map(|((l, m), coverage)| LodLevel {
            name: format!("{stem}_LOD{}", l.0),
            mesh: m,
            extras: level_extras(l.0, None, l.2 as f64, diagonal),
            coverage,
        })
        .collect();
    let glb = write_lod_glb(&levels, &a.output.glb())
        .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
    write_atomic(path, &glb)?;
    Ok(())
}
