//! The `tiles` job: a 3D Tiles 1.1 tileset of any mesh or point cloud
//! lodkit reads, through `lodkit-tiles`.
//!
//! A mesh gives a `REPLACE`-refined tileset: leaves hold the input at full
//! resolution, each level above the whole object simplified (HQMS) and cut
//! by an octree, every tile's `geometricError` measured; a textured mesh
//! (OBJ + MTL, glTF, a PLY naming its texture) keeps its materials, each
//! tile carrying the texels its faces use, halved per level up
//! (`lodkit_tiles::tileset_from_scene`). A point cloud or
//! range image gives an `ADD`-refined point tileset (an even subsample per
//! node). A LAS/LAZ cloud is z-up with positions relative to an `f64`
//! origin: it is turned into the y-up frame tile contents use (the
//! clients turn it back) and its origin becomes the root `transform`, so a
//! client sees the file's own coordinates.

use std::path::{Path, PathBuf};

use anyhow::Result;
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::{Model, PointCloud};
use lodkit_tiles::{Event as TilesEvent, Phase, PointTilesOptions, TilesOptions};

use crate::plan::{OutOfCore, kept};
use crate::progress::{Event, Progress, human_bytes};
use crate::usage::usage;

/// What to tile and how.
#[derive(Clone, Debug)]
pub struct TilesJob {
    /// The input file (any format lodkit reads, LAS/LAZ included).
    pub input: PathBuf,
    /// The output folder: absent, empty, or one lodkit wrote (replaced
    /// whole); never one holding a user's files.
    pub out: PathBuf,
    /// Options of a mesh's tileset.
    pub mesh: TilesOptions,
    /// Options of a point cloud's tileset.
    pub points: PointTilesOptions,
    /// `--memory` and `--ray`: a binary PLY mesh whose in-core tiling
    /// would exceed the budget ([`lodkit_tiles::IN_CORE_BYTES_PER_FACE`]
    /// per face) is tiled out of core, staged beside `out` (resumed by
    /// the same command after a failure, removed after success); so is a
    /// vertex-only binary PLY cloud
    /// ([`lodkit_tiles::IN_CORE_BYTES_PER_POINT`] per point; the in-core
    /// bytes, its staging removed after the run).
    pub scale: OutOfCore,
}

/// What a tiles job wrote.
#[derive(Clone, Debug)]
pub enum TilesReport {
    /// A mesh's tileset.
    Mesh(lodkit_tiles::TilesReport),
    /// A point cloud's tileset, and the origin its root transform holds.
    Points(lodkit_tiles::PointTilesReport, Option<[f64; 3]>),
}

/// Runs the job: reads the input, builds the tileset in memory, writes it
/// into `out` atomically. A binary PLY mesh whose in-core tiling would
/// exceed `job.scale.memory` is tiled out of core instead
/// (`lodkit_tiles::tileset_out_of_core`: never loaded whole; its staging
/// folder beside `out` is kept after a failure, so the same job resumes,
/// and removed after success).
///
/// Errors: an unreadable input or one with nothing to tile (one line
/// naming the file); an output folder that is not lodkit's, or an option
/// out of range ([`crate::usage::Usage`]). Cost: see `lodkit-tiles` (about
/// one `simplify` of a mesh plus one distance measurement per tile; a
/// cloud in `O(points × depth)`; out of core, about `--memory`).
pub fn run(job: &TilesJob, events: &Progress) -> Result<TilesReport> {
    if let Some((memory, in_core, cloud)) = out_of_core_memory(job, events) {
        events.status(format!(
            "out of core: {} needs about {} to tile in core, over --memory {}; tiling in bounded memory",
            job.input.display(),
            human_bytes(in_core),
            human_bytes(memory)
        ));
        return if cloud {
            points_out_of_core(job, events, memory)
        } else {
            mesh_out_of_core(job, events, memory)
        };
    }
    let step = events.spinner(&format!("reading {}", job.input.display()));
    let located = lodkit_mesh::io::load_located(&job.input)?;
    step.finish();
    match located.model {
        Model::Mesh(mesh) => {
            let scene = materials_of(events, &job.input, mesh)?;
            let mut draw = phases(events, "levels: simplify, cut and measure");
            let tileset = match &scene {
                Ok(scene) => lodkit_tiles::tileset_from_scene(scene, &job.mesh, &mut draw),
                Err(mesh) => lodkit_tiles::tileset_from_mesh(mesh, &job.mesh, &mut draw),
            }
            .map_err(|e| error(e, &job.input))?;
            let report = lodkit_tiles::write_tileset(
                &tileset,
                &job.out,
                Some(&job.input),
                &job.mesh,
                &mut draw,
            )
            .map_err(|e| error(e, &job.out))?;
            events.emit(&Event::PhasesFinished);
            Ok(TilesReport::Mesh(report))
        }
        Model::Points(p) => points(job, events, p, located.origin),
        Model::Range(r) => points(job, events, r.to_point_cloud(), located.origin),
    }
}

/// The input as a scene when it has materials (OBJ + MTL, glTF, a PLY
/// naming its texture), its base-colour textures within the run's pixel
/// budget (checked from their headers); else the mesh as read. Warnings
/// of the scene reader are said as status lines.
fn materials_of(
    events: &Progress,
    input: &Path,
    mesh: lodkit_mesh::TriMesh,
) -> Result<std::result::Result<lodkit_mesh::Scene, lodkit_mesh::TriMesh>> {
    use lodkit_mesh::io::Format;
    let scene = match Format::from_path(input) {
        Some(Format::Ply) => lodkit_mesh::io::ply_scene(input, mesh.clone()),
        Some(Format::Obj | Format::Gltf | Format::Glb) => lodkit_mesh::io::load_scene(input)?,
        _ => return Ok(Err(mesh)),
    };
    if scene.is_plain_mesh() || !lodkit_mesh::io::has_materials(&scene) {
        return Ok(Err(mesh));
    }
    for w in &scene.warnings {
        events.status(format!("warning: {}: {w}", input.display()));
    }
    crate::materials::texture_budget(&input.display().to_string(), &scene)?;
    Ok(Ok(scene))
}

/// The budget, the in-core estimate and whether the input is a cloud,
/// when `job.input` is tiled out of core: a binary `.ply` of vertices
/// only, or a LAS/LAZ file, whose points times
/// [`lodkit_tiles::IN_CORE_BYTES_PER_POINT`] exceed `--memory`; a `.ply` mesh whose in-core tiling (estimated from
/// its size) exceeds `--memory` and that the stream reader accepts
/// (binary, vertices then faces). A `.ply` too big but not streamable is
/// tiled in core, with one line saying so.
fn out_of_core_memory(job: &TilesJob, events: &Progress) -> Option<(u64, u64, bool)> {
    use lodkit_mesh::io::Format;
    let format = Format::from_path(&job.input);
    if format == Some(Format::Las) {
        let memory = job
            .scale
            .memory
            .unwrap_or_else(lodkit_scale::default_memory);
        let points = lodkit_mesh::io::LasStream::header_count(&job.input)?;
        let in_core = points.saturating_mul(lodkit_tiles::IN_CORE_BYTES_PER_POINT);
        return (in_core > memory).then_some((memory, in_core, true));
    }
    if format != Some(Format::Ply) {
        return None;
    }
    let meta = std::fs::metadata(&job.input).ok().filter(|m| m.is_file())?;
    let memory = job
        .scale
        .memory
        .unwrap_or_else(lodkit_scale::default_memory);
    if let Ok(s) = lodkit_mesh::io::ply::stream::PlyStream::open_points(&job.input)
        && s.face_records() == 0
    {
        let in_core = s
            .vertex_count()
            .saturating_mul(lodkit_tiles::IN_CORE_BYTES_PER_POINT);
        return (in_core > memory).then_some((memory, in_core, true));
    }
    let faces = meta.len() / lodkit_scale::PLY_BYTES_PER_FACE;
    let in_core = faces.saturating_mul(lodkit_tiles::IN_CORE_BYTES_PER_FACE);
    if in_core <= memory {
        return None;
    }
    match lodkit_mesh::io::ply::stream::PlyStream::open(&job.input) {
        Ok(s) if s.face_records() > 0 => Some((memory, in_core, false)),
        Ok(_) => None,
        Err(e) => {
            events.status(format!(
                "note: {} needs about {} to tile in core, over --memory {}, but cannot be streamed ({e}); tiling in core",
                job.input.display(),
                human_bytes(in_core),
                human_bytes(memory)
            ));
            None
        }
    }
}

/// The staging folder beside `job.out` for these `settings` (keyed by the
/// input and them), after removing any an earlier run for this output
/// abandoned under other settings (each named in a status line).
fn staging_for(job: &TilesJob, events: &Progress, settings: &str) -> PathBuf {
    let staging = lodkit_scale::staging_dir(&job.input, &job.out, settings);
    for old in lodkit_scale::remove_abandoned(&job.out, &staging) {
        events.status(format!(
            "removed {}, the staging folder an earlier run for this output left",
            old.display()
        ));
    }
    staging
}

/// The mesh tileset of a binary PLY built out of core in `memory` bytes
/// (`lodkit_tiles::tileset_out_of_core`), its staging folder beside `out`.
fn mesh_out_of_core(job: &TilesJob, events: &Progress, memory: u64) -> Result<TilesReport> {
    let settings = format!("tiles {:?}; memory {memory}", job.mesh);
    let staging = staging_for(job, events, &settings);
    if staging.exists() {
        events.status(format!("resuming from {}", staging.display()));
    }
    let o = lodkit_tiles::OutOfCoreOptions {
        memory,
        staging: staging.clone(),
        runner: job.scale.runner(),
    };
    let report =
        lodkit_tiles::tileset_out_of_core(&job.input, &job.out, &job.mesh, &o, &|e| match e {
            lodkit_scale::Event::Phase(name, len) => events.emit(&Event::Phase { name, len }),
            lodkit_scale::Event::Advance(k) => events.emit(&Event::Advance(k)),
        })
        .map_err(|e| match e {
            lodkit_tiles::Error::Usage(m) => usage(m),
            e => kept(&error(e, &job.input), &staging),
        })?;
    events.emit(&Event::PhasesFinished);
    Ok(TilesReport::Mesh(report))
}

/// The point tileset of a vertex-only binary PLY or a LAS/LAZ file built out of core in
/// `memory` bytes (`lodkit_tiles::point_tileset_out_of_core`: the
/// in-core bytes), its staging folder beside `out`, removed after the run.
fn points_out_of_core(job: &TilesJob, events: &Progress, memory: u64) -> Result<TilesReport> {
    let settings = format!("points {:?}; memory {memory}", job.points);
    let staging = staging_for(job, events, &settings);
    let o = lodkit_tiles::PointsOutOfCoreOptions { memory, staging };
    let (report, origin) = lodkit_tiles::point_tileset_out_of_core(
        &job.input,
        &job.out,
        &job.points,
        &o,
        &|e| match e {
            lodkit_scale::Event::Phase(name, len) => events.emit(&Event::Phase { name, len }),
            lodkit_scale::Event::Advance(k) => events.emit(&Event::Advance(k)),
        },
    )
    .map_err(|e| error(e, &job.input))?;
    events.emit(&Event::PhasesFinished);
    Ok(TilesReport::Points(report, origin))
}

fn points(
    job: &TilesJob,
    events: &Progress,
    cloud: PointCloud,
    origin: Option<[f64; 3]>,
) -> Result<TilesReport> {
    let cloud = if origin.is_some() {
        z_up_to_y_up(cloud)
    } else {
        cloud
    };
    let mut draw = phases(events, "subsampling points");
    let tileset = lodkit_tiles::tileset_from_points(&cloud, &job.points, &mut draw)
        .map_err(|e| error(e, &job.input))?;
    let report = lodkit_tiles::write_point_tileset(
        &tileset,
        &job.out,
        Some(&job.input),
        &job.points,
        origin,
        &mut draw,
    )
    .map_err(|e| error(e, &job.out))?;
    events.emit(&Event::PhasesFinished);
    Ok(TilesReport::Points(report, origin))
}

/// A LAS/LAZ cloud (z-up) in the y-up frame tile contents are written in:
/// `(x, y, z) ↦ (x, z, −y)`, which the clients' y-up → z-up turn undoes.
fn z_up_to_y_up(mut c: PointCloud) -> PointCloud {
    let turn = |v: &mut Vec3| *v = Vec3::new(v.x, v.z, -v.y);
    c.positions.iter_mut().for_each(turn);
    if let Some(n) = &mut c.normals {
        n.iter_mut().for_each(turn);
    }
    c
}

/// The tiler's progress as library events: a phase per tiler phase
/// (`levels` named `first`), advanced as it counts.
fn phases<'a>(events: &'a Progress<'a>, first: &'a str) -> impl FnMut(TilesEvent) + 'a {
    let (mut last, mut shown) = (None, 0usize);
    move |e: TilesEvent| {
        let TilesEvent::Progress { phase, done, total } = e;
        if last != Some(phase) {
            last = Some(phase);
            shown = 0;
            let name = match phase {
                Phase::Levels => first,
                Phase::Write => "writing tiles",
            };
            events.emit(&Event::Phase {
                name,
                len: total as u64,
            });
        }
        events.emit(&Event::Advance(done.saturating_sub(shown) as u64));
        shown = shown.max(done);
    }
}

/// A tiler error as the job's: usage errors stay usage errors; the rest
/// name `path` unless they already name a file.
fn error(e: lodkit_tiles::Error, path: &Path) -> anyhow::Error {
    match e {
        lodkit_tiles::Error::Usage(m) => usage(m),
        e @ (lodkit_tiles::Error::Io { .. } | lodkit_tiles::Error::Mesh(_)) => {
            anyhow::anyhow!("{e}")
        }
        e => anyhow::anyhow!("{}: {e}", path.display()),
    }
}
