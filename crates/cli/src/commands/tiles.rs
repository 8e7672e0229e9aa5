//! `lodkit tiles IN --out DIR`: a 3D Tiles 1.1 tileset of a mesh or a
//! point cloud; the job is `lodkit::tiles`.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit::tiles::{TilesJob, TilesReport};
use lodkit_tiles::{PointTilesOptions, TilesOptions};

use crate::ui::{Ui, value};

#[derive(Args, Debug)]
pub struct TilesArgs {
    /// Input mesh or point cloud (any format lodkit reads, LAS/LAZ
    /// included).
    pub input: PathBuf,
    /// Output folder: absent, empty, or one lodkit wrote (replaced whole).
    #[arg(long, value_name = "DIR")]
    pub out: PathBuf,
    /// Meshes: most input triangles per leaf tile, and most triangles per
    /// tile, in 64..=4000000.
    #[arg(long, value_name = "N", default_value_t = TilesOptions::DEFAULT_LEAF_TRIANGLES,
          value_parser = value::range(TilesOptions::LEAF_TRIANGLES))]
    pub leaf_triangles: usize,
    /// Point clouds: most points per leaf tile, in 256..=4000000.
    #[arg(long, value_name = "N", default_value_t = PointTilesOptions::DEFAULT_LEAF_POINTS,
          value_parser = value::range(PointTilesOptions::LEAF_POINTS))]
    pub leaf_points: usize,
    /// Plain tiles: no EXT_meshopt_compression, float normals (positions
    /// stay quantised on the tileset's shared grid). Tiles are compressed
    /// by default (EXT_meshopt_compression, KHR_mesh_quantization,
    /// octahedral normals).
    #[arg(long)]
    pub no_compress: bool,
    /// Compressed tiles (the default; kept for scripts that ask for it).
    #[arg(long, hide = true, conflicts_with = "no_compress")]
    pub compress: bool,
    /// No skirts under tile borders (slivers may show where tiles of
    /// different levels meet).
    #[arg(long)]
    pub no_skirts: bool,
    /// Memory budget, in 1M..=1P bytes (K, M, G, T, P: powers of 1024;
    /// e.g. 8G, 512M). A binary PLY mesh whose in-core tiling would need
    /// more (about 400 bytes per triangle) is tiled out of core: never
    /// loaded whole, staged beside --out (the same command resumes a
    /// failed run; the staging is removed after success). So is a cloud
    /// over it (a vertex-only binary PLY, LAS or LAZ; about 48 bytes per
    /// point), into the in-core bytes. Default: a third of the machine's memory.
    #[arg(long, value_name = "SIZE", value_parser = value::bytes(*lodkit::limits::MEMORY.start(), *lodkit::limits::MEMORY.end()))]
    pub memory: Option<u64>,
    /// Out of core: run the simplification blocks as Ray tasks (`local`,
    /// `auto` or HOST:PORT, as `simplify --ray`); the same bytes as without.
    #[arg(long, value_name = "ADDRESS", value_parser = value::ray_address)]
    pub ray: Option<String>,
}

pub fn run(ui: &Ui, args: &TilesArgs) -> Result<()> {
    let job = TilesJob {
        input: args.input.clone(),
        out: args.out.clone(),
        mesh: TilesOptions {
            leaf_triangles: args.leaf_triangles,
            compress: args.compress || (!args.no_compress && cfg!(feature = "compress")),
            skirts: !args.no_skirts,
        },
        points: PointTilesOptions {
            leaf_points: args.leaf_points,
            compress: args.compress || (!args.no_compress && cfg!(feature = "compress")),
        },
        scale: lodkit::plan::OutOfCore {
            memory: args.memory,
            ray: args.ray.clone(),
        },
    };
    let tileset = args.out.join("tileset.json");
    match ui.run(|events| lodkit::tiles::run(&job, events))? {
        TilesReport::Mesh(r) => {
            ui.status(format!(
                "wrote {}: {} tiles over {} levels, root error {:.4}, {} triangles per level, {}",
                tileset.display(),
                r.tiles,
                r.depth as usize + 1,
                r.root_error,
                r.level_triangles
                    .iter()
                    .map(|t| t.to_string())
                    .collect::<Vec<_>>()
                    .join(" / "),
                lodkit::progress::human_bytes(r.bytes)
            ));
            if ui.is_verbose() {
                let [p, s, m, w] = r.seconds;
                ui.status(format!(
                    "partition {p:.2} s, simplify {s:.2} s, measure {m:.2} s, write {w:.2} s; largest tile {} triangles, {} skirt triangles, {} tiles refitted",
                    r.max_tile_triangles, r.skirt_triangles, r.refitted_tiles
                ));
            }
        }
        TilesReport::Points(r, origin) => ui.status(format!(
            "wrote {}: {} point tiles over {} levels (ADD), {} points, largest tile {}, root error {:.4}{}, {}",
            tileset.display(),
            r.tiles,
            r.depth as usize + 1,
            r.input_points,
            r.max_tile_points,
            r.root_error,
            origin.map_or(String::new(), |o| format!(
                ", origin {:.2}, {:.2}, {:.2} (file units)",
                o[0], o[1], o[2]
            )),
            lodkit::progress::human_bytes(r.bytes)
        )),
    }
    Ok(())
}
