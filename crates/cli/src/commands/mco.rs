//! `lodkit mco build|extract|info`: the continuous-LOD model (marching cube
//! octree).
use std::path::{Path, PathBuf};

use anyhow::{Context, Result, bail};
use clap::{Args, Subcommand};
use lodkit_mco::{
    Camera, IncrementalBuilder, McoHeader, McoModel, McoStream, Options, densify_meshes, grid_for,
    samples_of,
};
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::io::{WriteOptions, save_mesh};
use lodkit_mesh::{Model, RangeImage};
use serde::Serialize;

use crate::ui::Ui;
use crate::ui::value::{self, Real};

#[derive(Subcommand)]
pub enum McoCommand {
    /// Build a model from range scans (.ply range grids, .conf alignments), meshes or point clouds.
    #[command(
        after_help = "Examples:\n  lodkit mco build bun.conf -o bunny.mco\n  lodkit mco build scan1.ply scan2.ply -o part.mco --resolution 200\n  lodkit mco build bunny.ply -o bunny.mco"
    )]
    Build {
        /// Inputs, added one at a time (a .conf adds each scan it lists, posed).
        #[arg(required = true)]
        inputs: Vec<PathBuf>,
        /// Output .mco file.
        #[arg(short, long, value_parser = value::output(&["mco"], "a continuous-LOD model"))]
        output: PathBuf,
        /// Leaf cubes along the longest axis, in 2..=512 (default: cube =
        /// twice the sample spacing).
        #[arg(long, value_parser = value::int(2u32, MAX_RESOLUTION))]
        resolution: Option<u32>,
        /// Print what was built as JSON.
        #[arg(long)]
        json: bool,
    },
    /// Write the mesh of one level of detail.
    #[command(
        after_help = "Examples:\n  lodkit mco extract bunny.mco --triangles 10000 -o bunny_10k.ply\n  lodkit mco extract bunny.mco --lod 500 -o lod500.ply\n  lodkit mco extract bunny.mco --view 0,0.1,0.4 --look-at 0,0.1,0 --tolerance 1 -o near.ply"
    )]
    Extract(ExtractArgs),
    /// Nodes and triangles per level, LOD-array length, input samples.
    Info {
        model: PathBuf,
        /// Refuse a file cut short (default: describe what its complete
        /// chunks hold and say where it stopped).
        #[arg(long)]
        strict: bool,
        /// Print as JSON.
        #[arg(long)]
        json: bool,
    },
}

#[derive(Args)]
#[command(group = clap::ArgGroup::new("select").required(true).args(["lod", "triangles", "view"]))]
pub struct ExtractArgs {
    /// The .mco model.
    pub model: PathBuf,
    /// Output mesh (.ply, .obj, .stl, .glb).
    #[arg(short, long, value_parser = value::output(value::MESH_OUT, "the extracted mesh"))]
    pub output: PathBuf,
    /// LOD number (0 = root only; `mco info` prints the highest).
    #[arg(long)]
    pub lod: Option<usize>,
    /// Triangle budget (the closest LOD number is used).
    #[arg(long)]
    pub triangles: Option<usize>,
    /// View-dependent: camera position X,Y,Z (finite numbers).
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true, value_parser = Real::FINITE.vec3())]
    pub view: Option<[f32; 3]>,
    /// Point the camera looks at (default: the model's centre).
    #[arg(
        long,
        value_name = "X,Y,Z",
        requires = "view",
        allow_hyphen_values = true,
        value_parser = Real::FINITE.vec3()
    )]
    pub look_at: Option<[f32; 3]>,
    /// Vertical field of view, degrees in (0, 180) (default 60).
    #[arg(long, requires = "view", value_parser = Real::open(0.0, 180.0).f32())]
    pub fov: Option<f32>,
    /// Viewport height, pixels in [1, 65536] (default 1080).
    #[arg(long, requires = "view", value_parser = Real::closed(1.0, 65536.0).f32())]
    pub viewport: Option<f32>,
    /// Largest projected error allowed, pixels (a finite number > 0; default 1).
    #[arg(long, requires = "view", value_parser = Real::POSITIVE.f32())]
    pub tolerance: Option<f32>,
    /// Refuse a file cut short (default: cut from its complete chunks,
    /// which serve the LOD numbers they cover, and say where it stopped).
    #[arg(long)]
    pub strict: bool,
    /// Print what was extracted as JSON.
    #[arg(long)]
    pub json: bool,
}

/// Largest `--resolution` of `mco build` (and `bench mco`): the library
/// takes up to [`lodkit_mco::MAX_RESOLUTION`], but memory grows with its
/// square on a surface that fills the lattice (an octahedron at 512 took
/// 250 MB on the 2-core build machine; 2000 on a small sphere took 6.8 GB).
pub const MAX_RESOLUTION: u32 = 512;

pub fn run(ui: &Ui, cmd: &McoCommand) -> Result<()> {
    match cmd {
        McoCommand::Build {
            inputs,
            output,
            resolution,
            json,
        } => build(ui, inputs, output, *resolution, *json),
        McoCommand::Extract(args) => extract(ui, args),
        McoCommand::Info {
            model,
            strict,
            json,
        } => info(ui, model, *strict, *json),
    }
}

/// Largest `.mco` file read (as `McoModel::load`).
const MAX_FILE_BYTES: u64 = 16 << 30;

/// Where a `.mco` file cut short stopped: what its complete chunks hold.
#[derive(Serialize, Clone, Copy)]
struct Cut {
    /// Bytes present.
    bytes: u64,
    /// Bytes the header announces.
    file_bytes: u64,
    /// Complete chunks read, of `total_chunks`.
    chunks: usize,
    total_chunks: u32,
    /// The highest LOD number served, of the whole file's `total_max_lod`.
    max_lod: usize,
    total_max_lod: u32,
}

/// Reads a `.mco` file. A version-2 file cut short (a partial download or
/// copy) gives the model of its complete chunks, which serve every LOD
/// number they cover as the whole file would, and one line on stderr says
/// where it stopped; `strict` refuses it. Errors name the file. Returns
/// the model, what was cut, and the file's bytes.
fn load_model(ui: &Ui, path: &Path, strict: bool) -> Result<(McoModel, Option<Cut>, Vec<u8>)> {
    let name = path.display().to_string();
    let len = std::fs::metadata(path).with_context(|| name.clone())?.len();
    if len > MAX_FILE_BYTES {
        bail!("{name}: {len} bytes is larger than the {MAX_FILE_BYTES}-byte limit");
    }
    let bytes = std::fs::read(path).with_context(|| name.clone())?;
    // A version-2 header that announces more bytes than the file holds: a
    // prefix. Anything else is read whole (and refused as the reader says).
    let mut probe = McoStream::new();
    let head = &bytes[..bytes.len().min(McoHeader::BYTES)];
    let header = match probe.push(head) {
        Ok(_) => probe.header().copied(),
        Err(_) => None,
    };
    let h = match header {
        Some(h) if len < h.file_bytes => h,
        _ => {
            let m = McoModel::from_bytes(&bytes).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
            return Ok((m, None, bytes));
        }
    };
    if strict {
        bail!(
            "{name}: cut short: {len} bytes, the header says {} (--strict refuses a file cut short)",
            h.file_bytes
        );
    }
    let mut s = McoStream::new();
    s.push(&bytes).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    if s.chunks().is_empty() {
        bail!(
            "{name}: cut short at byte {len} of {}, before chunk 0 (LOD number 0) is complete",
            h.file_bytes
        );
    }
    let p = McoModel::from_prefix(&bytes).map_err(|e| anyhow::anyhow!("{name}: {e}"))?;
    let cut = Cut {
        bytes: len,
        file_bytes: h.file_bytes,
        chunks: p.chunks,
        total_chunks: h.chunks,
        max_lod: p.max_lod,
        total_max_lod: h.max_lod,
    };
    ui.status(format!(
        "{name}: stopped at byte {} of {}, where chunk {} is incomplete; read the {} complete chunks of {} (LOD numbers 0..={} of 0..={}; --strict refuses a file cut short)",
        s.bytes_read(),
        h.file_bytes,
        p.chunks,
        p.chunks,
        h.chunks,
        p.max_lod,
        h.max_lod
    ));
    Ok((p.model, Some(cut), bytes))
}

/// Loads an input: a `.conf` expands to its posed scans.
fn load_inputs(ui: &Ui, path: &Path) -> Result<Vec<(String, Model)>> {
    if path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("conf"))
    {
        let step = ui.spinner(&format!("reading {}", path.display()));
        let scans = lodkit_mesh::io::conf::load_scans(path)?;
        step.finish();
        return Ok(scans
            .into_iter()
            .map(|(p, r): (PathBuf, RangeImage)| (p.display().to_string(), Model::Range(r)))
            .collect());
    }
    Ok(vec![(path.display().to_string(), super::load(ui, path)?)])
}

#[derive(Serialize)]
struct Added {
    input: String,
    samples: usize,
    cubes_recomputed: usize,
    surface_cubes: usize,
}

#[derive(Serialize)]
struct Built {
    output: String,
    resolution: u32,
    cube: f32,
    depth: u32,
    added: Vec<Added>,
    nodes: usize,
    lod_numbers: usize,
    full_triangles: usize,
    bytes: u64,
    seconds: f64,
}

fn build(
    ui: &Ui,
    inputs: &[PathBuf],
    output: &Path,
    resolution: Option<u32>,
    json: bool,
) -> Result<()> {
    let t0 = std::time::Instant::now();
    let mut models = Vec::new();
    for p in inputs {
        models.extend(load_inputs(ui, p)?);
    }
    let samples = models
        .iter()
        .map(|(name, m)| samples_of(m).with_context(|| name.clone()))
        .collect::<Result<Vec<_>>>()?;
    if samples.iter().all(|s| s.is_empty()) {
        let names: Vec<String> = models.iter().map(|(n, _)| n.clone()).collect();
        bail!("{}: no usable samples", names.join(", "));
    }
    let plain: Vec<Model> = models.iter().map(|(_, m)| m.clone()).collect();
    // One mesh keeps its detail: a lattice whose full cut has about its
    // triangle count, as `lodkit build` makes it (scans take the paper's
    // default, twice their sample spacing).
    let resolution = match (resolution, plain.as_slice()) {
        (None, [Model::Mesh(mesh)]) => {
            lodkit_mco::mesh_resolution(mesh, lodkit_mco::MAX_BUILD_BYTES / 4)
                .with_context(|| models[0].0.clone())?
        }
        (r, _) => r,
    };
    if let Some(r) = resolution {
        // A resolution the user chose that needs more memory than a build
        // may take is a bad option value (exit 2), not bad input.
        let bytes = lodkit_mco::estimate_build_bytes(&plain, &Options { resolution })?;
        if bytes > lodkit_mco::MAX_BUILD_BYTES {
            return Err(crate::ui::usage(format!(
                "--resolution {r}: the build would need about {:.1} GB of memory, more than its {:.1} GB limit; use a lower resolution",
                bytes as f64 / 1e9,
                lodkit_mco::MAX_BUILD_BYTES as f64 / 1e9
            )));
        }
    }
    let grid = grid_for(&plain, &samples, &Options { resolution })?;
    let samples = densify_meshes(&plain, samples, &grid);
    let status = |line: String| {
        if !json {
            ui.status(line)
        }
    };
    status(format!(
        "lattice: resolution {}, cube {:.6}, octree depth {}",
        grid.resolution(),
        grid.cube(),
        grid.depth()
    ));
    let mut builder = IncrementalBuilder::new(grid);
    // Scan data has edges: Hoppe's tangential rule (meshes build without it).
    if plain.iter().any(|m| !matches!(m, Model::Mesh(_))) {
        builder = builder.with_tangential_rule();
    } else if lodkit_mco::all_closed_meshes(&plain) {
        // Closed meshes give closed models (`band_edge_pruning.rs`).
        builder = builder.with_band_edge_pruning();
    }
    let mut added = Vec::new();
    for ((name, _), s) in models.iter().zip(&samples) {
        let r = builder.add(s);
        status(format!(
            "added {name}: {} samples, {} cubes recomputed, {} surface cubes",
            r.samples, r.cubes_recomputed, r.surface_cubes
        ));
        added.push(Added {
            input: name.clone(),
            samples: r.samples,
            cubes_recomputed: r.cubes_recomputed,
            surface_cubes: r.surface_cubes,
        });
    }
    let step = ui.spinner("building the octree");
    let model = builder.build()?;
    step.finish();
    let seconds = t0.elapsed().as_secs_f64();
    model.save(output)?;
    if json {
        let grid = &model.info().grid;
        return super::print_json(&Built {
            output: output.display().to_string(),
            resolution: grid.resolution(),
            cube: grid.cube(),
            depth: grid.depth(),
            added,
            nodes: model.info().nodes,
            lod_numbers: model.max_lod(),
            full_triangles: model.full_triangles(),
            bytes: std::fs::metadata(output).map_or(0, |m| m.len()),
            seconds,
        });
    }
    ui.status(format!(
        "wrote {} ({} nodes, {} LOD numbers, {} triangles at full resolution)",
        output.display(),
        model.info().nodes,
        model.max_lod(),
        model.full_triangles()
    ));
    ui.status(format!("built in {seconds:.3} s"));
    Ok(())
}

#[derive(Serialize)]
struct Extracted {
    model: String,
    output: String,
    /// What was cut: `LOD k`, a budget, or a view.
    cut: String,
    lod: Option<usize>,
    triangles: usize,
    vertices: usize,
    /// Where a file cut short stopped (`None`: the whole file was read).
    cut_short: Option<Cut>,
}

fn extract(ui: &Ui, a: &ExtractArgs) -> Result<()> {
    // The camera options mean nothing without a camera: refused, not
    // ignored (checked here too, as clap's `requires` does not fire
    // inside a satisfied group).
    if a.view.is_none() {
        for (given, name) in [
            (a.look_at.is_some(), "--look-at"),
            (a.fov.is_some(), "--fov"),
            (a.viewport.is_some(), "--viewport"),
            (a.tolerance.is_some(), "--tolerance"),
        ] {
            if given {
                return Err(crate::ui::usage(format!(
                    "{name} applies to a view-dependent cut: give --view X,Y,Z too"
                )));
            }
        }
    }
    let (fov, viewport, tolerance) = (
        a.fov.unwrap_or(60.0),
        a.viewport.unwrap_or(1080.0),
        a.tolerance.unwrap_or(1.0),
    );
    let (model, cut, _) = load_model(ui, &a.model, a.strict)?;
    let mut idx = Vec::new();
    let step = ui.spinner("extracting");
    let (what, lod) = if let Some(k) = a.lod {
        if k > model.max_lod() {
            return Err(crate::ui::usage(format!(
                "--lod {k} is outside 0..={}: the LOD numbers {} {}",
                model.max_lod(),
                if cut.is_some() {
                    "the complete chunks of"
                } else {
                    "of"
                },
                a.model.display()
            )));
        }
        model.extract_lod(k, &mut idx);
        (format!("LOD {k}"), Some(k))
    } else if let Some(n) = a.triangles {
        let k = model.extract_triangles(n, &mut idx);
        (format!("LOD {k} for a budget of {n} triangles"), Some(k))
    } else {
        let position = Vec3::from(a.view.expect("clap requires one of the three"));
        let (lo, hi) = model.bounds();
        let target = a.look_at.map_or((lo + hi) * 0.5, Vec3::from);
        if position == target {
            return Err(crate::ui::usage(
                "--view and --look-at are the same point: the camera has no direction",
            ));
        }
        let cam = Camera {
            vfov_deg: fov,
            viewport_height: viewport,
            ..Camera::looking_at(position, target)
        };
        let n = model.extract_view(&cam, tolerance, &mut idx);
        (format!("view-dependent cut ({n} nodes expanded)"), None)
    };
    step.finish();
    let mesh = model.mesh_from_indices(&idx);
    save_mesh(&a.output, &mesh, WriteOptions::default())?;
    if a.json {
        return super::print_json(&Extracted {
            model: a.model.display().to_string(),
            output: a.output.display().to_string(),
            cut: what,
            lod,
            triangles: mesh.faces.len(),
            vertices: mesh.positions.len(),
            cut_short: cut,
        });
    }
    ui.status(format!(
        "wrote {} ({what}: {} triangles, {} vertices)",
        a.output.display(),
        mesh.faces.len(),
        mesh.positions.len()
    ));
    Ok(())
}

#[derive(Serialize)]
struct LevelRow {
    level: usize,
    nodes: usize,
    triangles: usize,
}

#[derive(Serialize)]
struct ChunkRow {
    offset: u64,
    bytes: u64,
    first_lod: u32,
    last_lod: u32,
    nodes: u32,
    vertices: u32,
    triangles: u32,
}

#[derive(Serialize)]
struct Info {
    file: String,
    /// `.mco` format version (1: flat arrays, 2: LOD-ordered chunks).
    version: u32,
    file_bytes: u64,
    /// Where a file cut short stopped (`None`: the whole file was read);
    /// the rest describes its complete chunks.
    cut_short: Option<Cut>,
    /// Version 2: the chunks in file order (a prefix through chunk `c`
    /// serves LOD numbers up to its `last_lod`).
    chunks: Vec<ChunkRow>,
    resolution: u32,
    cube: f32,
    depth: u32,
    vertices: usize,
    nodes: usize,
    lod_array: usize,
    lod_numbers: usize,
    full_triangles: usize,
    crack_patches: usize,
    input_samples: u64,
    levels: Vec<LevelRow>,
}

/// `lodkit mco info FILE` (also what `lodkit info FILE.mco` prints): the
/// file's format, chunks, lattice, sizes and levels, as text or JSON; a
/// cut-short file is read up to its last complete chunk (refused with
/// `strict`).
pub fn info(ui: &Ui, path: &Path, strict: bool, json: bool) -> Result<()> {
    let (model, cut, bytes) = load_model(ui, path, strict)?;
    let m = model.info();
    let version = McoModel::file_version(&bytes).unwrap_or(0);
    let chunks = if version == 1 {
        Vec::new()
    } else {
        McoModel::chunk_table(&bytes)
            .with_context(|| path.display().to_string())?
            .into_iter()
            .map(|c| ChunkRow {
                offset: c.offset,
                bytes: c.bytes,
                first_lod: c.first_lod,
                last_lod: c.last_lod,
                nodes: c.nodes,
                vertices: c.vertices,
                triangles: c.triangle_indices / 3,
            })
            .collect()
    };
    let info = Info {
        file: path.display().to_string(),
        version,
        file_bytes: bytes.len() as u64,
        cut_short: cut,
        chunks,
        resolution: m.grid.resolution(),
        cube: m.grid.cube(),
        depth: m.grid.depth(),
        vertices: m.vertices,
        nodes: m.nodes,
        lod_array: m.lod_array,
        lod_numbers: m.lod_numbers,
        full_triangles: m.full_triangles,
        crack_patches: m.crack_patches,
        input_samples: m.input_samples,
        levels: m
            .levels
            .iter()
            .enumerate()
            .map(|(level, l)| LevelRow {
                level,
                nodes: l.nodes,
                triangles: l.triangles,
            })
            .collect(),
    };
    if json {
        return super::print_json(&info);
    }
    crate::outln!("file: {}", info.file)?;
    match &info.cut_short {
        Some(c) => crate::outln!(
            "format: version {}, cut short: {} of {} bytes, {} of {} chunks complete (LOD numbers 0..={} of 0..={}); below, what they hold",
            info.version,
            c.bytes,
            c.file_bytes,
            c.chunks,
            c.total_chunks,
            c.max_lod,
            c.total_max_lod
        )?,
        None => crate::outln!(
            "format: version {}, {} bytes{}",
            info.version,
            info.file_bytes,
            if info.chunks.is_empty() {
                String::new()
            } else {
                format!(" in {} chunks", info.chunks.len())
            }
        )?,
    }
    crate::outln!(
        "lattice: resolution {}, cube {:.6}, octree depth {}",
        info.resolution,
        info.cube,
        info.depth
    )?;
    crate::outln!(
        "vertices: {} (every level, {} crack-patch substitutions)",
        info.vertices,
        info.crack_patches
    )?;
    crate::outln!(
        "nodes: {}; LOD array: {} nodes in {} LOD numbers",
        info.nodes,
        info.lod_array,
        info.lod_numbers
    )?;
    crate::outln!("triangles at full resolution: {}", info.full_triangles)?;
    crate::outln!("built from {} samples", info.input_samples)?;
    crate::outln!("level  nodes  triangles (0 = leaf cubes)")?;
    for r in &info.levels {
        crate::outln!("{:>5}  {:>5}  {:>9}", r.level, r.nodes, r.triangles)?;
    }
    if !info.chunks.is_empty() {
        crate::outln!("chunk     offset     bytes  LOD numbers      nodes  vertices  triangles")?;
        for (i, c) in info.chunks.iter().enumerate() {
            crate::outln!(
                "{:>5} {:>10} {:>9}  {:>5}..={:<5} {:>8} {:>9} {:>10}",
                i,
                c.offset,
                c.bytes,
                c.first_lod,
                c.last_lod,
                c.nodes,
                c.vertices,
                c.triangles
            )?;
        }
    }
    Ok(())
}
