//! `lodkit tiles IN --out DIR`: a 3D Tiles 1.1 tileset of a mesh or a
//! point cloud. The job is `lodkit_tiles`'s; this file parses the options
//! and draws progress.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit_mesh::{Model, PointCloud};
use lodkit_tiles::{Event, Phase, PointTilesOptions, TilesOptions};

use crate::ui::{Ui, human_bytes, usage, value};

#[derive(Args, Debug)]
pub struct TilesArgs {
    /// Input mesh or point cloud (any format lodkit reads, LAS/LAZ
    /// included).
    pub input: PathBuf,
    /// Output folder: absent, empty, or one lodkit wrote (replaced whole).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Most input triangles per leaf tile, and most triangles per tile,
    /// in 64..=4000000.
    #[arg(long, value_name = "N", default_value_t = TilesOptions::DEFAULT_LEAF_TRIANGLES,
          value_parser = value::int(*TilesOptions::LEAF_TRIANGLES.start(), *TilesOptions::LEAF_TRIANGLES.end()))]
    pub leaf_triangles: usize,
    /// Compressed tiles: EXT_meshopt_compression with KHR_mesh_quantization
    /// (needs lodkit built with `--features compress`).
    #[arg(long)]
    pub compress: bool,
    /// No skirts under tile borders (slivers may show where tiles of
    /// different levels meet).
    #[arg(long)]
    pub no_skirts: bool,
    /// Point clouds: most points per leaf tile, in 256..=4000000.
    #[arg(long, value_name = "N", default_value_t = PointTilesOptions::DEFAULT_LEAF_POINTS,
          value_parser = value::int(*PointTilesOptions::LEAF_POINTS.start(), *PointTilesOptions::LEAF_POINTS.end()))]
    pub leaf_points: usize,
}

/// A LAS/LAZ cloud (z-up, positions relative to `origin`) in the y-up
/// frame tile contents are written in: `(x, y, z) ↦ (x, z, −y)`, which
/// the clients' y-up → z-up turn undoes.
fn z_up_to_y_up(mut c: PointCloud) -> PointCloud {
    let turn = |v: &mut lodkit_mesh::glam::Vec3| *v = lodkit_mesh::glam::Vec3::new(v.x, v.z, -v.y);
    c.positions.iter_mut().for_each(turn);
    if let Some(n) = &mut c.normals {
        n.iter_mut().for_each(turn);
    }
    c
}

pub fn run(ui: &Ui, args: &TilesArgs) -> Result<()> {
    let opts = TilesOptions {
        leaf_triangles: args.leaf_triangles,
        compress: args.compress,
        skirts: !args.no_skirts,
    };
    let step = ui.spinner(&format!("reading {}", args.input.display()));
    let located = lodkit_mesh::io::load_located(&args.input)?;
    step.finish();
    let mesh = match located.model {
        Model::Mesh(m) => m,
        Model::Points(p) => return run_points(ui, args, p, located.origin),
        Model::Range(r) => return run_points(ui, args, r.to_point_cloud(), located.origin),
    };
    let bars = ui.phases();
    let mut draw = |e: Event| {
        let Event::Progress { phase, done, total } = e;
        if done == 1 {
            let name = match phase {
                Phase::Levels => "levels: simplify, cut and measure",
                Phase::Write => "writing tiles",
            };
            bars.phase(name, total as u64);
        }
        bars.advance(1);
    };
    let map = |e: lodkit_tiles::Error| match e {
        lodkit_tiles::Error::Usage(m) => usage(m),
        e => anyhow::anyhow!("{}: {e}", args.input.display()),
    };
    let tileset = lodkit_tiles::tileset_from_mesh(&mesh, &opts, &mut draw).map_err(map)?;
    let report =
        lodkit_tiles::write_tileset(&tileset, &args.out, Some(&args.input), &opts, &mut draw)
            .map_err(|e| match e {
                lodkit_tiles::Error::Usage(m) => usage(m),
                e => anyhow::anyhow!("{e}"),
            })?;
    bars.finish();
    ui.status(format!(
        "wrote {}: {} tiles over {} levels, root error {:.4} ({}), {}",
        args.out.join("tileset.json").display(),
        report.tiles,
        report.depth as usize + 1,
        report.root_error,
        report
            .level_triangles
            .iter()
            .map(|t| t.to_string())
            .collect::<Vec<_>>()
            .join(" / ")
            + " triangles per level",
        human_bytes(report.bytes)
    ));
    if ui.is_verbose() {
        let [p, s, m, w] = report.seconds;
        ui.status(format!(
            "partition {p:.2} s, simplify {s:.2} s, measure {m:.2} s, write {w:.2} s; largest tile {} triangles, {} skirt triangles, {} tiles refitted",
            report.max_tile_triangles, report.skirt_triangles, report.refitted_tiles
        ));
    }
    Ok(())
}

/// The point-cloud tileset (`ADD` refinement); a LAS/LAZ cloud keeps its
/// file coordinates through the root transform.
fn run_points(
    ui: &Ui,
    args: &TilesArgs,
    cloud: PointCloud,
    origin: Option<[f64; 3]>,
) -> Result<()> {
    let opts = PointTilesOptions {
        leaf_points: args.leaf_points,
        compress: args.compress,
    };
    let cloud = if origin.is_some() {
        z_up_to_y_up(cloud)
    } else {
        cloud
    };
    let bars = ui.phases();
    let (mut last, mut shown) = (None, 0);
    let mut draw = |e: Event| {
        let Event::Progress { phase, done, total } = e;
        if last != Some(phase) {
            last = Some(phase);
            shown = 0;
            let name = match phase {
                Phase::Levels => "subsampling points",
                Phase::Write => "writing tiles",
            };
            bars.phase(name, total as u64);
        }
        bars.advance(done.saturating_sub(shown) as u64);
        shown = shown.max(done);
    };
    let map = |e: lodkit_tiles::Error| match e {
        lodkit_tiles::Error::Usage(m) => usage(m),
        e => anyhow::anyhow!("{}: {e}", args.input.display()),
    };
    let tileset = lodkit_tiles::tileset_from_points(&cloud, &opts, &mut draw).map_err(map)?;
    let report = lodkit_tiles::write_point_tileset(
        &tileset,
        &args.out,
        Some(&args.input),
        &opts,
        origin,
        &mut draw,
    )
    .map_err(|e| match e {
        lodkit_tiles::Error::Usage(m) => usage(m),
        e => anyhow::anyhow!("{e}"),
    })?;
    bars.finish();
    ui.status(format!(
        "wrote {}: {} point tiles over {} levels (ADD), {} points, largest tile {}, root error {:.4}{}, {}",
        args.out.join("tileset.json").display(),
        report.tiles,
        report.depth as usize + 1,
        report.input_points,
        report.max_tile_points,
        report.root_error,
        origin.map_or(String::new(), |o| format!(
            ", origin {:.2}, {:.2}, {:.2} (file units)",
            o[0], o[1], o[2]
        )),
        human_bytes(report.bytes)
    ));
    Ok(())
}
