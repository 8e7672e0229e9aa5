//! Point-cloud tilesets: an octree whose every node keeps an even
//! subsample of the points that reach it, refined by adding its children
//! (3D Tiles `ADD`), so every point is stored once.
//!
//! A node at depth `d` lays a grid of [`PointTilesOptions::CELLS`]³ cells
//! over its cube (cell edge `h = size / (2^d · CELLS)`) and keeps, in each
//! occupied cell, the point nearest the cell's centre (ties: the lower
//! input index). The other points go on to the child octant that holds
//! them; a node with at most [`PointTilesOptions::leaf_points`] points (or
//! at [`MAX_DEPTH`]) keeps them all. Every point a node passes on lies in
//! a cell that holds a kept point, so drawing the node without its
//! subtree leaves no point farther than the cell's diagonal `h·√3` from a
//! drawn one: that is the node's `geometricError` (a bound, in object
//! units), halving at each depth; leaves have only their quantisation
//! grid's rounding.
//!
//! Colours and normals go with their points. Contents are glTF `POINTS`
//! (y-up, as the mesh tiles). Cost: `O(N × depth)` time; the points'
//! indices once in all (8 bytes a point) plus one hash slot per occupied
//! cell of the node being split.

use std::path::Path;

use glam::{DVec3, Vec3};
use lodkit_mesh::{Aabb, PointCloud};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::octree_partition::{CellKey, Grid, MAX_DEPTH, Node, Octree};
use crate::tileset_json::{NodeInfo, Refine};
use crate::{Error, Event, Phase, Result};

/// Options of a point tileset.
#[derive(Clone, Debug, PartialEq)]
pub struct PointTilesOptions {
    /// Most points a leaf holds. Range [`PointTilesOptions::LEAF_POINTS`].
    pub leaf_points: usize,
    /// Quantised, meshopt-compressed tiles (needs the `meshopt` feature).
    pub compress: bool,
}

impl PointTilesOptions {
    /// Allowed `leaf_points`.
    pub const LEAF_POINTS: std::ops::RangeInclusive<usize> = 256..=4_000_000;
    /// 64k points: about 1 MB a tile with colours, one request each.
    pub const DEFAULT_LEAF_POINTS: usize = 65_536;
    /// Subsampling cells per axis of a node's cube: on a surface, about
    /// `CELLS²` points a node (16k at 128).
    pub const CELLS: u32 = 128;
    /// Defaults: 64k-point leaves, no compression.
    pub const DEFAULT: PointTilesOptions = PointTilesOptions {
        leaf_points: Self::DEFAULT_LEAF_POINTS,
        compress: false,
    };
}

impl Default for PointTilesOptions {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// What a point tileset build made.
#[derive(Clone, Debug, PartialEq)]
pub struct PointTilesReport {
    /// Input points.
    pub input_points: usize,
    /// Tiles (every node holds points).
    pub tiles: usize,
    /// Octree depth.
    pub depth: u8,
    /// Most points in one tile.
    pub max_tile_points: usize,
    /// The root tile's `geometricError` (object units).
    pub root_error: f64,
    /// Seconds: subsampling, writing (0 until written).
    pub seconds: [f64; 2],
    /// Bytes written (0 until written).
    pub bytes: u64,
}

/// A point tileset in memory.
pub struct PointTileset {
    tree: Octree,
    tiles: Vec<PointCloud>,
    info: Vec<NodeInfo>,
    report: PointTilesReport,
}

impl PointTileset {
    /// The build's report.
    pub fn report(&self) -> &PointTilesReport {
        &self.report
    }

    /// Every tile: `(name "D-X-Y-Z", depth, geometricError, points)`, in
    /// breadth-first order.
    pub fn tiles(&self) -> impl Iterator<Item = (String, u8, f64, &PointCloud)> {
        self.tree
            .nodes
            .iter()
            .zip(&self.tiles)
            .zip(&self.info)
            .map(|((n, t), i)| (n.key.name(), n.key.depth, i.error, t))
    }
}

/// The points of `cloud` at `idx`, with their colours and normals.
fn gather(cloud: &PointCloud, idx: &[u32]) -> PointCloud {
    PointCloud {
        positions: idx.iter().map(|&i| cloud.positions[i as usize]).collect(),
        normals: cloud
            .normals
            .as_ref()
            .map(|n| idx.iter().map(|&i| n[i as usize]).collect()),
        colors: cloud
            .colors
            .as_ref()
            .map(|c| idx.iter().map(|&i| c[i as usize]).collect()),
    }
}

/// The cell of the node `key`'s [`PointTilesOptions::CELLS`]³ grid that
/// holds `p` (clamped into it, `(z · CELLS + y) · CELLS + x`) and the
/// squared distance from `p` to the cell's centre in cell units: the
/// one computation behind a node's choice, in core and out of core, so
/// both choose the same points bit for bit.
pub(crate) fn cell_and_distance(grid: &Grid, key: CellKey, p: glam::Vec3) -> (u32, f64) {
    let cells = PointTilesOptions::CELLS;
    let n = f64::from(1u32 << key.depth) * f64::from(cells);
    let h = grid.size / n;
    let base = DVec3::new(
        f64::from(key.xyz[0]),
        f64::from(key.xyz[1]),
        f64::from(key.xyz[2]),
    ) * f64::from(cells);
    let rel = (p.as_dvec3() - grid.origin) / h - base;
    // `floor` then clamped to the grid; a truncating cast gives the same
    // cell (it differs from `floor` only below 0, where both clamp to 0)
    // without a libm call per axis.
    let top = cells - 1;
    let c = DVec3::new(
        f64::from((rel.x as i64).clamp(0, i64::from(top)) as u32),
        f64::from((rel.y as i64).clamp(0, i64::from(top)) as u32),
        f64::from((rel.z as i64).clamp(0, i64::from(top)) as u32),
    );
    let d = (rel - c - DVec3::splat(0.5)).length_squared();
    ((c.z as u32 * cells + c.y as u32) * cells + c.x as u32, d)
}

/// The octant of the child of a node at `depth` that holds `p`: the
/// in-core rule's `grid.cell_of(p, depth + 1)`, its low bits. Computed
/// as `cell_of` computes the cell, with a truncating cast for its
/// `floor` (they differ only below 0, where both give cell 0), so without
/// a libm call per axis.
pub(crate) fn octant(grid: &Grid, p: Vec3, depth: u8) -> u8 {
    let n = 1u64 << (depth + 1);
    let rel = (p.as_dvec3() - grid.origin) / grid.size * n as f64;
    let c = |v: f64| ((v as u64).min(n - 1) & 1) as u8;
    c(rel.x) | (c(rel.y) << 1) | (c(rel.z) << 2)
}

/// The `geometricError` of a node at `depth` that passes points on: its
/// cell's diagonal `h·√3`.
pub(crate) fn cell_diagonal(grid: &Grid, depth: u8) -> f64 {
    grid.size / (f64::from(1u32 << depth) * f64::from(PointTilesOptions::CELLS)) * 3f64.sqrt()
}

/// Splits `idx` (the points reaching the node `key`) into the points the
/// node keeps and the rest: one per occupied cell of its
/// [`PointTilesOptions::CELLS`]³ grid, the nearest the cell's centre.
fn subsample(cloud: &PointCloud, grid: &Grid, key: CellKey, idx: Vec<u32>) -> (Vec<u32>, Vec<u32>) {
    let mut best: FxHashMap<u32, (f64, u32)> = FxHashMap::default();
    for &i in &idx {
        let (cell, d) = cell_and_distance(grid, key, cloud.positions[i as usize]);
        let e = best.entry(cell).or_insert((d, i));
        if d < e.0 || (d == e.0 && i < e.1) {
            *e = (d, i);
        }
    }
    let mut kept: Vec<u32> = best.values().map(|&(_, i)| i).collect();
    kept.sort_unstable();
    let mut rest = Vec::with_capacity(idx.len() - kept.len());
    let mut k = 0;
    for i in idx {
        if k < kept.len() && kept[k] == i {
            k += 1;
        } else {
            rest.push(i);
        }
    }
    (kept, rest)
}

/// The nodes below (and including) one node, made by the in-core rule.
pub(crate) struct Subtree {
    /// Breadth-first from the node given, children in octant order
    /// (indices into this vector).
    pub nodes: Vec<Node>,
    /// Per node: the points it keeps, in input order.
    pub tiles: Vec<PointCloud>,
    /// Per node: its `geometricError` before rounding (0 for a leaf).
    pub errors: Vec<f64>,
    /// The deepest node's depth.
    pub depth: u8,
}

/// Applies the rule of the module docs to `cloud`, the points (in input
/// order) that reach the node `root` of the octree on `grid`; `placed`
/// hears the points placed so far. The whole cloud at [`CellKey::ROOT`]
/// is the in-core tileset; any node's reaching points give that node's
/// subtree of it exactly (ties break by input order, which a subset
/// keeps).
pub(crate) fn subdivide(
    cloud: &PointCloud,
    grid: &Grid,
    root: CellKey,
    leaf_points: usize,
    placed: &mut dyn FnMut(usize),
) -> Subtree {
    let mut nodes = vec![Node {
        key: root,
        children: Vec::new(),
        input_faces: cloud.positions.len(),
    }];
    let mut tiles: Vec<PointCloud> = vec![PointCloud::default()];
    let mut errors = vec![0f64];
    // Breadth-first a level at a time, the nodes of a level on every
    // thread; children are numbered in the order of their parents, so
    // the tree is the one a queue would make whatever the thread count.
    let mut level = vec![(
        0usize,
        root,
        (0..cloud.positions.len() as u32).collect::<Vec<u32>>(),
    )];
    let (mut depth, mut done) = (root.depth, 0usize);
    while !level.is_empty() {
        let made: Vec<_> = level
            .into_par_iter()
            .map(|(n, key, idx)| {
                if idx.len() <= leaf_points || key.depth >= MAX_DEPTH {
                    return (n, key, gather(cloud, &idx), 0.0, idx.len(), None);
                }
                let (kept, rest) = subsample(cloud, grid, key, idx);
                // Nothing passed on (every point in a cell of its own): a leaf.
                let error = if rest.is_empty() {
                    0.0
                } else {
                    cell_diagonal(grid, key.depth)
                };
                let mut parts: [Vec<u32>; 8] = Default::default();
                for i in rest {
                    let o = octant(grid, cloud.positions[i as usize], key.depth);
                    parts[o as usize].push(i);
                }
                (n, key, gather(cloud, &kept), error, kept.len(), Some(parts))
            })
            .collect();
        let mut next = Vec::new();
        for (n, key, tile, error, placed_here, parts) in made {
            depth = depth.max(key.depth);
            done += placed_here;
            tiles[n] = tile;
            errors[n] = error;
            for (o, part) in parts.into_iter().flatten().enumerate() {
                if part.is_empty() {
                    continue;
                }
                let id = nodes.len();
                nodes.push(Node {
                    key: key.child(o),
                    children: Vec::new(),
                    input_faces: part.len(),
                });
                nodes[n].children.push(id);
                tiles.push(PointCloud::default());
                errors.push(0.0);
                next.push((id, key.child(o), part));
            }
        }
        placed(done);
        level = next;
    }
    Subtree {
        nodes,
        tiles,
        errors,
        depth,
    }
}

/// Every node's tileset entry from its tile's box ([`Aabb::EMPTY`]: no
/// points) and its error: boxes grown to hold the subtree's, then each
/// depth's quantisation rounding added (in core and out of core alike).
pub(crate) fn node_info(nodes: &[Node], boxes: &[Aabb], errors: &[f64]) -> Vec<NodeInfo> {
    let mut info: Vec<NodeInfo> = boxes
        .iter()
        .zip(errors)
        .map(|(b, &error)| NodeInfo {
            bbox: *b,
            error,
            content: b.min.x <= b.max.x,
        })
        .collect();
    for i in (0..nodes.len()).rev() {
        for &c in &nodes[i].children {
            info[i].bbox = info[i].bbox.union(&info[c].bbox);
        }
    }
    crate::tile_content::add_rounding(&mut info, |i| nodes[i].key.depth);
    info
}

/// Builds the point tileset of `cloud` (y-up, object units) in memory:
/// see the module docs.
///
/// Errors: an empty or invalid cloud ([`Error::Input`]), `leaf_points`
/// outside its range ([`Error::Usage`]). Cost: see the module docs.
pub fn tileset_from_points(
    cloud: &PointCloud,
    opts: &PointTilesOptions,
    progress: &mut dyn FnMut(Event),
) -> Result<PointTileset> {
    crate::check_option(
        "leaf points",
        opts.leaf_points,
        &PointTilesOptions::LEAF_POINTS,
    )?;
    cloud.validate().map_err(|e| Error::Input(e.to_string()))?;
    if cloud.positions.is_empty() {
        return Err(Error::Input("the cloud has no points to tile".into()));
    }
    if cloud.positions.len() > u32::MAX as usize {
        return Err(Error::Input(format!(
            "{} points: at most {} in one tileset",
            cloud.positions.len(),
            u32::MAX
        )));
    }
    let t0 = std::time::Instant::now();
    let grid = Grid::around(&cloud.bbox());
    let total = cloud.positions.len();
    let Subtree {
        nodes,
        tiles,
        errors,
        depth,
    } = subdivide(cloud, &grid, CellKey::ROOT, opts.leaf_points, &mut |done| {
        progress(Event::Progress {
            phase: Phase::Levels,
            done,
            total,
        })
    });
    let boxes: Vec<Aabb> = tiles
        .iter()
        .map(|t| {
            if t.positions.is_empty() {
                Aabb::EMPTY
            } else {
                t.bbox()
            }
        })
        .collect();
    let info = node_info(&nodes, &boxes, &errors);
    let report = PointTilesReport {
        input_points: cloud.positions.len(),
        tiles: tiles.iter().filter(|t| !t.positions.is_empty()).count(),
        depth,
        max_tile_points: tiles.iter().map(|t| t.positions.len()).max().unwrap_or(0),
        root_error: info[0].error,
        seconds: [t0.elapsed().as_secs_f64(), 0.0],
        bytes: 0,
    };
    let leaf_of_face = Vec::new();
    Ok(PointTileset {
        tree: Octree {
            grid,
            nodes,
            leaf_of_face,
            depth,
        },
        tiles,
        info,
        report,
    })
}

/// Writes `tileset` into the folder `out`, atomically and never over a
/// user's files, as [`crate::write_tileset`] does (same layout, `ADD`
/// refinement). `origin`: where the cloud's coordinates are relative to
/// (in the tileset's z-up frame, e.g. a LAS file's offset), written as
/// the root `transform` so clients see the file's coordinates exactly.
///
/// Errors as [`crate::write_tileset`].
pub fn write_point_tileset(
    tileset: &PointTileset,
    out: &Path,
    input: Option<&Path>,
    opts: &PointTilesOptions,
    origin: Option<[f64; 3]>,
    progress: &mut dyn FnMut(Event),
) -> Result<PointTilesReport> {
    let t0 = std::time::Instant::now();
    let tiles: Vec<(String, u8, &PointCloud)> = tileset
        .tiles()
        .filter(|(_, _, _, cloud)| !cloud.positions.is_empty())
        .map(|(name, depth, _, cloud)| (name, depth, cloud))
        .collect();
    let names: Vec<(String, u8)> = tiles.iter().map(|(n, d, _)| (n.clone(), *d)).collect();
    let bytes = crate::tileset_folder::write_folder(
        out,
        input,
        (&tileset.tree, &tileset.info),
        (Refine::Add, origin),
        &names,
        crate::tileset_folder::MAX_WRITERS,
        &|k, grid| {
            let (name, _, cloud) = &tiles[k];
            crate::tile_content::encode_point_tile(name, cloud, opts.compress, grid)
        },
        &mut crate::written(crate::Phase::Write, names.len(), progress),
    )?;
    let mut report = tileset.report.clone();
    report.bytes = bytes;
    report.seconds[1] = t0.elapsed().as_secs_f64();
    Ok(report)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    fn cloud(n: usize) -> PointCloud {
        // A wavy sheet with colours: deterministic, no randomness.
        let side = (n as f64).sqrt() as usize;
        let mut positions = Vec::new();
        let mut colors = Vec::new();
        for i in 0..n {
            let (u, v) = (
                (i % side) as f32 / side as f32,
                (i / side) as f32 / side as f32,
            );
            positions.push(Vec3::new(u, 0.1 * (6.0 * u).sin() * (4.0 * v).cos(), v));
            colors.push([(u * 255.0) as u8, (v * 255.0) as u8, 128, 255]);
        }
        PointCloud {
            positions,
            normals: None,
            colors: Some(colors),
        }
    }

    #[test]
    fn every_point_is_stored_once_and_errors_bound_the_gaps() {
        let c = cloud(200_000);
        let opts = PointTilesOptions {
            leaf_points: 5_000,
            ..PointTilesOptions::DEFAULT
        };
        let t = tileset_from_points(&c, &opts, &mut |_| {}).unwrap();
        let mut all: Vec<[u32; 3]> = t
            .tiles()
            .flat_map(|(_, _, _, p)| p.positions.iter().map(|v| v.to_array().map(f32::to_bits)))
            .collect();
        all.sort_unstable();
        let mut want: Vec<[u32; 3]> = c
            .positions
            .iter()
            .map(|v| v.to_array().map(f32::to_bits))
            .collect();
        want.sort_unstable();
        assert_eq!(all, want, "every point exactly once");
        assert!(t.report().depth >= 1);
        // A node's error bounds the distance from each point of its
        // subtree to the nearest point it keeps.
        for (i, node) in t.tree.nodes.iter().enumerate() {
            if node.children.is_empty() {
                assert!(t.info[i].error > 0.0 && t.info[i].error < 1e-4);
                continue;
            }
            let own = &t.tiles[i].positions;
            let mut stack = node.children.clone();
            while let Some(s) = stack.pop() {
                for p in t.tiles[s].positions.iter().step_by(97) {
                    let d = own
                        .iter()
                        .map(|q| q.distance(*p) as f64)
                        .fold(f64::INFINITY, f64::min);
                    assert!(
                        d <= t.info[i].error * (1.0 + 1e-6),
                        "node {i}: {d} > {}",
                        t.info[i].error
                    );
                }
                stack.extend(t.tree.nodes[s].children.iter().copied());
            }
            for &ch in &node.children {
                assert!(t.info[ch].error <= t.info[i].error);
            }
        }
    }
}
