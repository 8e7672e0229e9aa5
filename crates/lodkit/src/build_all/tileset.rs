//! The build's 3D Tiles tileset: the surface the other products are made
//! from (materials and textures kept when the input has them), tiled by
//! `lodkit_tiles` with its default options into `tiles/`, the folder
//! `lodkit serve` lists and the viewer opens.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::Result;
use lodkit_tiles::TilesOptions;

use super::{BuildJob, input::BuildInput};
use crate::progress::Progress;

/// The tileset's entry file, relative to the build folder.
pub const TILESET: &str = "tiles/tileset.json";

/// Tiles `input`'s surface into `dir/tiles` and adds its section to
/// `report`; returns the report's one sentence on it (tiles, bytes,
/// levels). Errors: the tiler's, naming the build's input. Cost: that of
/// `lodkit tiles` on the surface (about one `simplify` plus one distance
/// measurement per internal tile).
pub fn section(
    events: &Progress,
    input: &BuildInput,
    args: &BuildJob,
    dir: &Path,
    report: &mut String,
) -> Result<String> {
    let opts = TilesOptions {
        compress: args.output.compress,
        ..TilesOptions::DEFAULT
    };
    let name = &input.name;
    let fail = |e: lodkit_tiles::Error| anyhow::anyhow!("{name}: tiles: {e}");
    let step = events.spinner("3D Tiles: levels, errors, tiles");
    let tileset = match &input.scene {
        Some(scene) => lodkit_tiles::tileset_from_scene(scene, &opts, &mut |_| {}),
        None => lodkit_tiles::tileset_from_mesh(&input.surface, &opts, &mut |_| {}),
    }
    .map_err(fail)?;
    let out = dir.join(Path::new(TILESET).parent().unwrap_or(Path::new("tiles")));
    let r = lodkit_tiles::write_tileset(&tileset, &out, None, &opts, &mut |_| {}).map_err(fail)?;
    step.finish();
    let sentence = format!(
        "3D Tiles: `{TILESET}`, {} tiles in {} levels, {} bytes (root error {:.3e}, object units).",
        r.tiles,
        r.depth as usize + 1,
        r.bytes,
        r.root_error
    );
    writeln!(
        report,
        "## 3D Tiles\n\n{sentence} Leaves hold the input at full resolution ({} triangles at \
         most); each level above, the whole surface simplified and cut by an octree, its \
         `geometricError` measured; `lodkit serve` lists it and its viewer opens it.\n",
        opts.leaf_triangles
    )?;
    Ok(sentence)
}
