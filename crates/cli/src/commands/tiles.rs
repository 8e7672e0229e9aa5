//! `lodkit tiles IN --out DIR`: a 3D Tiles 1.1 tileset of a mesh. The job
//! is `lodkit_tiles`'s; this file parses the options and draws progress.
use std::path::PathBuf;

use anyhow::Result;
use clap::Args;
use lodkit_tiles::{Event, Phase, TilesOptions};

use crate::ui::{Ui, human_bytes, usage, value};

#[derive(Args, Debug)]
pub struct TilesArgs {
    /// Input mesh (any format lodkit reads).
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
}

pub fn run(ui: &Ui, args: &TilesArgs) -> Result<()> {
    let opts = TilesOptions {
        leaf_triangles: args.leaf_triangles,
        compress: args.compress,
        skirts: !args.no_skirts,
    };
    let mesh = super::load_mesh(ui, &args.input)?;
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
