//! The last stage: a tileset's folder, written atomically under the
//! output-folder rule (`lodkit_mesh::io::out_folder`), every tile's GLB
//! on its depth's grid (`tile_content::depth_grid`), then the tileset
//! files. Mesh and point tilesets, in core and out of core, all write
//! through it.
//!
//! Tiles are written by several threads at once: each tile's write ends
//! in a sync, and a sync waits on the disk: one at a time they took half
//! of an out-of-core point run (about 5 ms a tile on the development
//! machine, 3,300 tiles at 5·10⁷ points), while the disk serves several
//! at once. Encoding runs on the same threads, so it is spread over the
//! cores too. The bytes do not depend on the thread count.

use std::path::Path;
use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use lodkit_mesh::io::gltf::QuantGrid;
use lodkit_mesh::io::out_folder;

use crate::octree_partition::Octree;
use crate::tile_content::depth_grid;
use crate::tileset_json::{self, NodeInfo, Refine};
use crate::{Error, Result};

/// Tiles in flight at most: enough syncs at once to keep the disk busy
/// (more than 8 gained nothing measurable), each holding one tile's
/// points and its GLB.
pub(crate) const MAX_WRITERS: usize = 8;

/// Writes the folder `out` (see [`crate::write_tileset`]'s layout; `out`
/// absent, empty or lodkit's, and not holding `input`): each tile `(name,
/// depth)` of `tiles` encoded by `encode` (its index in `tiles`, its
/// depth's grid) and written atomically, on `writers` threads (at least
/// one, at most [`MAX_WRITERS`]: each holds one tile and its GLB), then
/// the tileset files; `done` hears each tile written (on the calling
/// thread). Returns the bytes written. Errors: the first tile's error in
/// `tiles` order among those that failed (the others stop at their next
/// tile), else the folder's; on any error the staged folder is removed
/// and `out` is untouched.
#[allow(clippy::too_many_arguments)]
pub(crate) fn write_folder(
    out: &Path,
    input: Option<&Path>,
    (tree, info): (&Octree, &[NodeInfo]),
    (refine, origin): (Refine, Option<[f64; 3]>),
    tiles: &[(String, u8)],
    writers: usize,
    encode: &(dyn Fn(usize, &QuantGrid) -> Result<Vec<u8>> + Sync),
    done: &mut dyn FnMut(),
) -> Result<u64> {
    let staging = out_folder::Staging::new(out, input)?;
    let dir = staging.dir().to_path_buf();
    let tiles_dir = dir.join("tiles");
    std::fs::create_dir(&tiles_dir).map_err(|source| Error::Io {
        path: tiles_dir.clone(),
        source,
    })?;
    let bounds = info[0].bbox;
    let next = AtomicUsize::new(0);
    let stop = AtomicBool::new(false);
    let bytes = AtomicUsize::new(0);
    let failed: Mutex<Option<(usize, Error)>> = Mutex::new(None);
    let (tx, rx) = std::sync::mpsc::channel::<()>();
    std::thread::scope(|s| {
        for _ in 0..writers.clamp(1, MAX_WRITERS) {
            let tx = tx.clone();
            let (next, stop, bytes, failed, tiles_dir) =
                (&next, &stop, &bytes, &failed, &tiles_dir);
            s.spawn(move || {
                while !stop.load(Ordering::Relaxed) {
                    let i = next.fetch_add(1, Ordering::Relaxed);
                    let Some((name, depth)) = tiles.get(i) else {
                        return;
                    };
                    let written = encode(i, &depth_grid(&bounds, *depth)).and_then(|glb| {
                        let path = tiles_dir.join(format!("{name}.glb"));
                        lodkit_mesh::io::write_atomic(&path, &glb)?;
                        Ok(glb.len())
                    });
                    match written {
                        Ok(n) => {
                            bytes.fetch_add(n, Ordering::Relaxed);
                            let _ = tx.send(());
                        }
                        Err(e) => {
                            let mut f = failed.lock().unwrap_or_else(|p| p.into_inner());
                            if f.as_ref().is_none_or(|(at, _)| i < *at) {
                                *f = Some((i, e));
                            }
                            stop.store(true, Ordering::Relaxed);
                        }
                    }
                }
            });
        }
        drop(tx);
        for () in rx {
            done();
        }
    });
    if let Some((_, e)) = failed.into_inner().unwrap_or_else(|p| p.into_inner()) {
        return Err(e);
    }
    let mut bytes = bytes.into_inner() as u64;
    // The error of drawing nothing: at least the root cube's diagonal.
    let top = (tree.grid.size * 3f64.sqrt()).max(info[0].error);
    for (path, json) in tileset_json::tileset_files_with(tree, info, top, refine, origin) {
        lodkit_mesh::io::write_atomic(&dir.join(&path), &json)?;
        bytes += json.len() as u64;
    }
    staging.commit()?;
    Ok(bytes)
}
