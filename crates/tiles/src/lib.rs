//! 3D Tiles 1.1 tilesets from triangle meshes: an octree of levels of
//! detail whose leaves are the input at full resolution, each parent the
//! HQMS simplification of what its children show, each tile's
//! `geometricError` measured, not estimated.
//!
//! # The pipeline, one file per stage
//! 1. `octree_partition.rs`: an octree over the input's bounding cube,
//!    cells split while they hold more than
//!    [`TilesOptions::leaf_triangles`] input faces (by centroid). Leaves
//!    are the input's faces in their cell.
//! 2. `level_chain.rs`: level `D` is the input; level `k` is the whole of
//!    level `k + 1` simplified (`lodkit-simplify`, one global error order)
//!    to what depth `k`'s tiles ask: each internal node
//!    `min(leaf budget, ½ × the faces of level k + 1 in its cell)`. Level
//!    `k` is then cut by the depth-`k` cells (`tile_split.rs`); a tile
//!    still over the budget is simplified again alone, its border locked.
//!    The root is the whole object at about one tile's budget, never
//!    empty.
//! 3. Errors (`tile_error.rs`): each internal tile's surface against the
//!    input near its cell, and the input of its cell against its level
//!    near the cell (the maximum of both directions over Metro samples,
//!    object units; near: within an eighth of the cell's side, which only
//!    ever overestimates). A tile's `geometricError` is the largest of
//!    its own and its descendants' (monotone), and at least what its
//!    depth's quantisation grid rounds (`tile_content::add_rounding`; a
//!    leaf's whole error); the tileset's is the root cube's diagonal.
//! 4. `skirts.rs`: a strip under every cut edge of a tile.
//! 5. `tile_textures.rs` (a textured input, [`tileset_from_scene`]):
//!    materials kept as seams through every level, each tile's texture
//!    cropped to its UVs and halved per level above the leaves.
//! 6. `tile_content.rs` (GLB bytes), `tileset_json.rs` (`tileset.json`,
//!    external tilesets every [`tileset_json::SUBTREE_LEVELS`] depths,
//!    boxes in the z-up frame), then `lodkit_mesh::io::out_folder` (the
//!    whole folder or nothing, never over a user's files).
//!
//! # Cracks: why skirts, not locked borders
//! A client refines where it likes, so any tile may sit beside any level
//! of its neighbour's subtree, down to the neighbour's full-resolution
//! leaves. For borders to match exactly at every such cut, the border
//! between two cells must be the same in every level of both subtrees,
//! so at full resolution in all of them: a parent's seams would then grow
//! as the square root of the input (measured on a 10⁶-face blob with
//! 32k-face leaves: the root's cut planes alone carry several thousand
//! full-resolution vertices), which is the frozen-border cost the
//! budget forbids. Partitions that shift between levels (lodkit-scale's
//! chains, Nexus) and borders released after one level (clusterlod) make
//! levels that meet their *own* neighbours, but in a tree any two levels
//! may meet. So: tiles of one level are cut from one mesh and share
//! their borders bit for bit; where levels differ, each tile's cut edges
//! carry a skirt hung inwards along the normals by twice the largest of
//! its own and its parent's `geometricError` and longest face on a cut
//! (a level's faces go to the cell of their centroid, so the sliver
//! between two levels' borders is about as wide as the coarser one's
//! faces there), at most a quarter of its cell, wound both ways (clients
//! cull back faces, and where the surface curves the strip leans over the
//! neighbour). Skirts add four triangles per cut edge at the tile's own
//! resolution, so they scale with the tile, not with the input (about
//! 8 % of the triangles with 32k-triangle tiles). They are not part of
//! the measured error (they hang below the surface). Measured by casting
//! rays at random cuts of closed meshes (`tests/cracks.rs`): of the rays
//! that pass through slivers without skirts, 0 of 582 still do on a blob
//! (five cuts) and 0 of 209 on the closed bunny (two cuts). Skirts hang
//! inwards, so a part thinner than a skirt's depth may show the skirt's
//! tip on its far side.
//!
//! # Contract
//! Same input and options → the same bytes in every file. Cost (in
//! core): the input, each level's mesh (about 1.4 × the input in all),
//! and while measuring a depth its level once more and lists of the
//! faces near each cell; time about one `simplify` of the input plus one
//! distance measurement of every internal tile.

mod cell_spill;
mod level_chain;
mod octree_partition;
mod out_of_core;
mod point_tiles;
mod point_tiles_out_of_core;
mod skirts;
mod tile_content;
mod tile_error;
mod tile_split;
mod tile_textures;
mod tileset_folder;
pub mod tileset_json;

use std::path::{Path, PathBuf};

use lodkit_mesh::{Aabb, TriMesh};

use lodkit_mesh::io::out_folder;
pub use lodkit_mesh::io::out_folder::MANIFEST;
pub use octree_partition::{CellKey, MAX_DEPTH};
pub use out_of_core::{
    IN_CORE_BYTES_PER_FACE, OutOfCoreEvent, OutOfCoreOptions, tileset_out_of_core,
};
pub use point_tiles::{
    PointTilesOptions, PointTilesReport, PointTileset, tileset_from_points, write_point_tileset,
};
pub use point_tiles_out_of_core::{
    IN_CORE_BYTES_PER_POINT, PointsOutOfCoreOptions, point_tileset_out_of_core,
};
pub use tile_content::{depth_grid, encode_point_tile, encode_tile};
pub use tile_textures::{MARGIN_TEXELS, tileset_from_scene};

/// Errors of a tileset build; each displays as one line.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A bad option or an output folder that may not be replaced (the
    /// CLI's exit 2).
    #[error("{0}")]
    Usage(String),
    /// The input cannot be tiled (no faces, invalid mesh).
    #[error("{0}")]
    Input(String),
    /// Simplification failed.
    #[error("simplify: {0}")]
    Simplify(String),
    /// The out-of-core level chain failed; the message names the cause (a
    /// block runner that cannot start, a staging file, a simplification).
    #[error("{0}")]
    Chain(String),
    /// A tile could not be encoded.
    #[error("{0}")]
    Encode(String),
    /// Reading or writing a file.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file or folder.
        path: PathBuf,
        /// What the operating system said.
        source: std::io::Error,
    },
    /// An error of `lodkit-mesh` (measurement, writing).
    #[error(transparent)]
    Mesh(#[from] lodkit_mesh::Error),
}

impl From<out_folder::FolderError> for Error {
    fn from(e: out_folder::FolderError) -> Self {
        match e {
            out_folder::FolderError::Refused(m) => Error::Usage(m),
            out_folder::FolderError::Io { path, source } => Error::Io { path, source },
            out_folder::FolderError::Write(e) => Error::Mesh(e),
        }
    }
}

/// The crate's result.
pub type Result<T, E = Error> = std::result::Result<T, E>;

/// Options of a tileset build.
#[derive(Clone, Debug, PartialEq)]
pub struct TilesOptions {
    /// Most input triangles a leaf holds, and most triangles any tile
    /// holds (skirts aside). Range [`TilesOptions::LEAF_TRIANGLES`].
    pub leaf_triangles: usize,
    /// Quantised, meshopt-compressed tiles (needs the `meshopt` feature).
    pub compress: bool,
    /// Hang skirts under the tiles' cut edges (see the crate docs).
    /// `false` leaves slivers where neighbours of different levels meet.
    pub skirts: bool,
}

impl TilesOptions {
    /// Allowed `leaf_triangles`: small enough tiles stream, large enough
    /// that a tree stays shallow.
    pub const LEAF_TRIANGLES: std::ops::RangeInclusive<usize> = 64..=4_000_000;
    /// 32k triangles: about 1 MB uncompressed per tile, what both clients
    /// load in one request without stalling a frame.
    pub const DEFAULT_LEAF_TRIANGLES: usize = 32_768;
    /// Defaults: 32k-triangle leaves, no compression, skirts.
    pub const DEFAULT: TilesOptions = TilesOptions {
        leaf_triangles: Self::DEFAULT_LEAF_TRIANGLES,
        compress: false,
        skirts: true,
    };
}

impl Default for TilesOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// The phases a build reports.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Phase {
    /// Simplifying, cutting and measuring the levels (counts internal tiles).
    Levels,
    /// Writing tiles (counts tiles).
    Write,
}

/// Progress of a build, for a front-end to draw.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Event {
    /// `done` of `total` units of `phase`.
    Progress {
        /// The phase.
        phase: Phase,
        /// Units done.
        done: usize,
        /// Units in all.
        total: usize,
    },
}

/// A tileset in memory: the octree, every tile's mesh (skirts included)
/// and its `geometricError`.
pub struct Tileset {
    tree: octree_partition::Octree,
    /// Per node: its content (with skirts), if any.
    tiles: Vec<Option<TriMesh>>,
    /// Per node: the material of each content vertex (textured tilesets).
    groups: Vec<Vec<u32>>,
    /// The materials and decoded textures of a textured input.
    textures: Option<tile_textures::Textures>,
    info: Vec<tileset_json::NodeInfo>,
    report: TilesReport,
}

/// What a build made.
#[derive(Clone, Debug, PartialEq)]
pub struct TilesReport {
    /// Input triangles.
    pub input_triangles: usize,
    /// Tiles with content.
    pub tiles: usize,
    /// Octree depth (0: the root is the only tile).
    pub depth: u8,
    /// Triangles of each level's whole mesh, root level first (the last is
    /// the input).
    pub level_triangles: Vec<usize>,
    /// Largest tile, skirts aside (≤ `leaf_triangles` unless a leaf at
    /// [`MAX_DEPTH`] holds more).
    pub max_tile_triangles: usize,
    /// Skirt triangles over all tiles.
    pub skirt_triangles: usize,
    /// Tiles simplified again alone to their budget.
    pub refitted_tiles: usize,
    /// The root tile's `geometricError` (object units).
    pub root_error: f64,
    /// Seconds: partition, simplification, measurement, writing (0 until
    /// written).
    pub seconds: [f64; 4],
    /// Bytes written (0 until written).
    pub bytes: u64,
}

impl Tileset {
    /// The build's report.
    pub fn report(&self) -> &TilesReport {
        &self.report
    }

    /// Every tile: `(name "D-X-Y-Z", depth, geometricError, mesh with
    /// skirts)`, in breadth-first order.
    pub fn tiles(&self) -> impl Iterator<Item = (String, u8, f64, &TriMesh)> {
        self.tree.nodes.iter().enumerate().filter_map(|(i, n)| {
            self.tiles[i]
                .as_ref()
                .map(|m| (n.key.name(), n.key.depth, self.info[i].error, m))
        })
    }
}

/// Builds the tileset of `mesh` (y-up, object units) in memory: see the
/// crate docs for the levels, the errors and the skirts.
///
/// Errors: a mesh with no faces or that breaks the `TriMesh` invariant
/// ([`Error::Input`]), `leaf_triangles` outside its range
/// ([`Error::Usage`]), a failed simplification or measurement. Cost: see
/// the crate docs.
pub fn tileset_from_mesh(
    mesh: &TriMesh,
    opts: &TilesOptions,
    progress: &mut dyn FnMut(Event),
) -> Result<Tileset> {
    build_tileset(mesh, Vec::new(), opts, progress)
}

/// [`tileset_from_mesh`] with one group (material) per vertex of `mesh`
/// (or none), kept through every level and carried into each tile.
pub(crate) fn build_tileset(
    mesh: &TriMesh,
    groups: Vec<u32>,
    opts: &TilesOptions,
    progress: &mut dyn FnMut(Event),
) -> Result<Tileset> {
    check_option(
        "leaf triangles",
        opts.leaf_triangles,
        &TilesOptions::LEAF_TRIANGLES,
    )?;
    mesh.validate().map_err(|e| Error::Input(e.to_string()))?;
    if mesh.faces.is_empty() {
        return Err(Error::Input("the mesh has no faces to tile".into()));
    }
    let t0 = std::time::Instant::now();
    let mut input = mesh.clone();
    let derived_normals = input.normals.is_none();
    if derived_normals {
        input.normals = Some(lodkit_mesh::normals::vertex_normals(&input));
    }
    let tree = octree_partition::Octree::build(&input, opts.leaf_triangles);
    let t_partition = t0.elapsed().as_secs_f64();
    let levels = level_chain::build_levels(
        &input,
        &groups,
        &tree,
        opts.leaf_triangles,
        derived_normals,
        progress,
    )?;

    // Monotone errors, children before parents (breadth-first order backwards).
    let n = tree.nodes.len();
    let mut error = levels.measured.clone();
    for i in (0..n).rev() {
        for &c in &tree.nodes[i].children {
            error[i] = error[i].max(error[c]);
        }
    }
    let mut parent = vec![usize::MAX; n];
    for (i, node) in tree.nodes.iter().enumerate() {
        for &c in &node.children {
            parent[c] = i;
        }
    }
    let reach: Vec<f64> = levels
        .tiles
        .iter()
        .map(|t| {
            t.as_ref()
                .map_or(0.0, |t| skirts::border_reach(&t.mesh, &t.cuts))
        })
        .collect();
    let mut tiles = Vec::with_capacity(n);
    let mut tile_groups = vec![Vec::new(); n];
    let (mut max_tile, mut skirt_triangles, mut count) = (0, 0, 0);
    for (i, t) in levels.tiles.into_iter().enumerate() {
        tiles.push(t.map(|mut t| {
            max_tile = max_tile.max(t.mesh.faces.len());
            count += 1;
            let depth = if i == 0 || !opts.skirts {
                0.0
            } else {
                skirts::skirt_depth(
                    [error[i], error[parent[i]], reach[i], reach[parent[i]]],
                    tree.grid.side(tree.nodes[i].key.depth),
                )
            };
            let m = skirts::with_skirts(&t.mesh, &t.cuts, depth as f32, &mut t.groups);
            tile_groups[i] = t.groups;
            skirt_triangles += m.faces.len() - t.mesh.faces.len();
            m
        }));
    }
    let mut info: Vec<tileset_json::NodeInfo> = (0..n)
        .map(|i| tileset_json::NodeInfo {
            bbox: tiles[i]
                .as_ref()
                .map_or(Aabb::EMPTY, |m: &TriMesh| m.bbox()),
            error: if tree.nodes[i].children.is_empty() {
                0.0
            } else {
                error[i]
            },
            content: tiles[i].is_some(),
        })
        .collect();
    for i in (0..n).rev() {
        for c in tree.nodes[i].children.clone() {
            info[i].bbox = info[i].bbox.union(&info[c].bbox);
        }
    }
    tile_content::add_rounding(&mut info, |i| tree.nodes[i].key.depth);
    let report = TilesReport {
        input_triangles: mesh.faces.len(),
        tiles: count,
        depth: tree.depth,
        level_triangles: levels.level_faces,
        max_tile_triangles: max_tile,
        skirt_triangles,
        refitted_tiles: levels.refitted,
        root_error: info[0].error,
        seconds: [t_partition, levels.seconds.0, levels.seconds.1, 0.0],
        bytes: 0,
    };
    Ok(Tileset {
        tree,
        tiles,
        groups: tile_groups,
        textures: None,
        info,
        report,
    })
}

/// Writes `tileset` into the folder `out`, atomically: every file goes
/// into a hidden sibling folder that replaces `out` when complete. `out`
/// must be absent, empty, or a folder lodkit wrote (its [`MANIFEST`]
/// lists exactly its files), and must not hold `input` (when given).
/// Layout: `out/tileset.json`, `out/tiles/D-X-Y-Z.glb` per tile and
/// `out/tiles/D-X-Y-Z.json` per external tileset, and the manifest.
///
/// Errors: [`Error::Usage`] for a folder that is not lodkit's (nothing is
/// written), an encoding or I/O error (`out` is left as it was). Returns
/// the report with the bytes written and the writing time.
pub fn write_tileset(
    tileset: &Tileset,
    out: &Path,
    input: Option<&Path>,
    opts: &TilesOptions,
    progress: &mut dyn FnMut(Event),
) -> Result<TilesReport> {
    let t0 = std::time::Instant::now();
    let nodes = &tileset.tree.nodes;
    let heights =
        tile_textures::heights(&nodes.iter().map(|n| n.children.clone()).collect::<Vec<_>>());
    let ids: Vec<usize> = (0..nodes.len())
        .filter(|&i| tileset.tiles[i].is_some())
        .collect();
    let names: Vec<(String, u8)> = ids
        .iter()
        .map(|&i| (nodes[i].key.name(), nodes[i].key.depth))
        .collect();
    let bytes = tileset_folder::write_folder(
        out,
        input,
        (&tileset.tree, &tileset.info),
        (tileset_json::Refine::Replace, None),
        &names,
        tileset_folder::MAX_WRITERS,
        &|k, grid| {
            let (i, name) = (ids[k], &names[k].0);
            let mesh = tileset.tiles[i].as_ref().expect("a tile with content");
            match &tileset.textures {
                None => encode_tile(name, mesh, opts.compress, grid),
                Some(t) => {
                    let groups = &tileset.groups[i];
                    t.encode(name, mesh, groups, heights[i], opts.compress, grid)
                }
            }
        },
        &mut written(Phase::Write, ids.len(), progress),
    )?;
    let mut report = tileset.report.clone();
    report.bytes = bytes;
    report.seconds[3] = t0.elapsed().as_secs_f64();
    Ok(report)
}

/// A `done` callback for [`tileset_folder::write_folder`] that reports
/// `Event::Progress` of `phase` to `progress`.
pub(crate) fn written<'a>(
    phase: Phase,
    total: usize,
    progress: &'a mut dyn FnMut(Event),
) -> impl FnMut() + 'a {
    let mut done = 0;
    move || {
        done += 1;
        progress(Event::Progress { phase, done, total });
    }
}

/// `value` of the option `what` within `range`, else [`Error::Usage`].
pub(crate) fn check_option(
    what: &str,
    value: usize,
    range: &std::ops::RangeInclusive<usize>,
) -> Result<()> {
    if range.contains(&value) {
        Ok(())
    } else {
        Err(Error::Usage(format!(
            "{what} {value}: must be in {}..={}",
            range.start(),
            range.end()
        )))
    }
}
