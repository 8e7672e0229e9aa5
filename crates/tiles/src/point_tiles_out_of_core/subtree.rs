//! One subtree of an out-of-core point tileset tiled in core: its spill
//! read back, subdivided by the in-core rule, its tiles staged into one
//! file.

use std::path::{Path, PathBuf};

use super::*;

/// A subtree tiled in core ([`tile_subtree`]): its nodes breadth-first,
/// its root first.
pub(super) struct TiledSubtree {
    pub(super) staged: PathBuf,
    pub(super) nodes: Vec<TiledNode>,
}

/// A node of a [`TiledSubtree`].
pub(super) struct TiledNode {
    pub(super) node: Node,
    /// Its tile's byte range in the subtree's staged file (none when it
    /// keeps no point).
    pub(super) range: Option<(u64, u64)>,
    pub(super) bbox: Aabb,
    pub(super) error: f64,
    pub(super) points: usize,
}

/// The subtree of the node `key` from the spill file of `slot` (which
/// must hold `count` points; removed after it is read), its tiles staged
/// into one file of `tiles` named for the slot (one file per subtree,
/// not per tile: creating files is what costs).
pub(super) fn tile_subtree(
    (spill_dir, tiles_dir): (&Path, &Path),
    layout: Layout,
    grid: &Grid,
    leaf_points: usize,
    (slot, count, key): (usize, u64, CellKey),
) -> Result<TiledSubtree> {
    let path = Spill::file(spill_dir, slot);
    let cloud = layout.read(&path, None)?;
    if cloud.positions.len() as u64 != count {
        return Err(Error::Input("the input changed while it was read".into()));
    }
    let Subtree {
        nodes,
        tiles,
        errors,
        ..
    } = subdivide(&cloud, grid, key, leaf_points, &mut |_| {});
    drop(cloud);
    let _ = std::fs::remove_file(&path);
    let staged = tiles_dir.join(format!("{slot}.pts"));
    let file = std::fs::File::create(&staged).map_err(io_err(&staged))?;
    let mut file = std::io::BufWriter::new(file);
    let mut bytes = Vec::new();
    let mut at = 0u64;
    let mut out = Vec::with_capacity(nodes.len());
    for ((node, tile), error) in nodes.into_iter().zip(tiles).zip(errors) {
        bytes.clear();
        layout.append(&tile, &mut bytes);
        std::io::Write::write_all(&mut file, &bytes).map_err(io_err(&staged))?;
        let range = (!tile.positions.is_empty()).then_some((at, bytes.len() as u64));
        at += bytes.len() as u64;
        let bbox = bbox_of(tile.positions.iter().copied());
        out.push(TiledNode {
            node,
            range,
            bbox,
            error,
            points: tile.positions.len(),
        });
    }
    std::io::Write::flush(&mut file).map_err(io_err(&staged))?;
    Ok(TiledSubtree { staged, nodes: out })
}
