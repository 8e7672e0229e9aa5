//! `lodkit mco build|extract|info`: the continuous-LOD model (marching cube
//! octree).
use std::path::{Path, PathBuf};

use anyhow::{Result, bail};
use clap::{Args, Subcommand};
use lodkit_mco::Camera;
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::io::{WriteOptions, save_mesh};
use lodkit_mesh::{Model, RangeImage};
use serde::Serialize;

use super::Input;
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
        #[arg(long, value_parser = value::range(lodkit::limits::MCO_RESOLUTION))]
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
    #[arg(long, requires = "view", value_parser = lodkit::limits::VIEW_FOV.f32())]
    pub fov: Option<f32>,
    /// Viewport height, pixels in [1, 65536] (default 1080).
    #[arg(long, requires = "view", value_parser = lodkit::limits::VIEWPORT.f32())]
    pub viewport: Option<f32>,
    /// Largest projected error allowed, pixels (a finite number > 0; default 1).
    #[arg(long, requires = "view", value_parser = lodkit::limits::TOLERANCE.f32())]
    pub tolerance: Option<f32>,
    /// Refuse a file cut short (default: cut from its complete chunks,
    /// which serve the LOD numbers they cover, and say where it stopped).
    #[arg(long)]
    pub strict: bool,
    /// Print what was extracted as JSON.
    #[arg(long)]
    pub json: bool,
}

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
        } => {
            let info = ui.run(|events| lodkit::info::mco_file(events, model, *strict))?;
            if *json {
                return super::print_json(&info);
            }
            Ok(crate::out!("{info}")?)
        }
    }
}

/// Loads an input ([`lodkit::input::load_input`]): a scan set expands to
/// its posed scans; meshes, clouds and range images are taken as read.
fn load_inputs(ui: &Ui, path: &Path) -> Result<Vec<(String, Model)>> {
    match super::load_input(ui, path, false)? {
        Input::Scans(set) => Ok(set
            .scans
            .into_iter()
            .map(|(p, r): (PathBuf, RangeImage)| (p.display().to_string(), Model::Range(r)))
            .collect()),
        Input::Model(m) => Ok(vec![(path.display().to_string(), m)]),
        other => bail!(
            "{}: holds a {}; mco build reads meshes, point clouds, range images and scan sets (.conf)",
            path.display(),
            other.kind()
        ),
    }
}

#[derive(Serialize)]
struct Built {
    output: String,
    resolution: u32,
    cube: f32,
    depth: u32,
    added: Vec<lodkit::mco_build::Added>,
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
    // With --json the lines the build says are left out (stdout is JSON).
    let sink = |e: &lodkit::Event<'_>| {
        if !(json && matches!(e, lodkit::Event::Note(_))) {
            ui.draw(e)
        }
    };
    let (model, added) =
        lodkit::mco_build::build_model(&models, resolution, &lodkit::Progress::new(&sink))?;
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
    cut_short: Option<lodkit::info::McoCut>,
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
    let (model, cut, _) = ui.run(|events| lodkit::info::load_mco(events, &a.model, a.strict))?;
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
        let cam = Camera::looking_at(position, target);
        let cam = Camera {
            vfov_deg: a.fov.unwrap_or(cam.vfov_deg),
            viewport_height: a.viewport.unwrap_or(cam.viewport_height),
            ..cam
        };
        let tolerance = a.tolerance.unwrap_or(lodkit::limits::DEFAULT_TOLERANCE);
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
