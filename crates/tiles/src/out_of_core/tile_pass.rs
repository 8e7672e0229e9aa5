//! The tile pass of the out-of-core tiler: one depth's tiles made from
//! their cells' spills, two at a time, each welded, refitted to the leaf
//! budget when over it, given normals and cuts and staged to its file;
//! then, once the whole depth is staged, each internal tile measured
//! against its neighbourhood (see the parent module's docs, steps 3–5).

use std::path::{Path, PathBuf};

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_scale::soup::Layout;
use lodkit_simplify::{Options, Simplifier, Target};

use super::{Staged, bbox_of};
use crate::cell_spill::{Spill, StagedTile};
use crate::level_chain::append;
use crate::octree_partition::{CellKey, Grid, Octree};
use crate::tile_split::welded_edges;
use crate::{Error, Result, tile_error};

/// Tiles staged at once in the tile pass.
pub(super) const IN_FLIGHT: usize = 2;

pub(super) fn tile_file(dir: &Path, node: usize) -> PathBuf {
    dir.join(format!("{node}.tile"))
}

/// What making and measuring a tile read: the tree and the folders.
pub(super) struct TileCtx<'a> {
    pub(super) tree: &'a Octree,
    pub(super) leaves_dir: &'a Path,
    pub(super) cells: &'a Path,
    pub(super) tiles_dir: &'a Path,
    pub(super) layout: Layout,
    pub(super) leaf: usize,
    /// Most input faces a tile is measured against directly.
    pub(super) direct_faces: u64,
}

impl TileCtx<'_> {
    /// Node `i`'s tile: its cell's faces welded, refitted to the leaf
    /// budget when over it, normals, cuts, staged to its file (its error
    /// is 0 until [`Self::measure`]). `None` for an empty cell; the flag
    /// says whether it was refitted.
    pub(super) fn make(
        &self,
        i: usize,
        simplifier: &mut Simplifier,
    ) -> Result<Option<(Staged, bool)>> {
        let tree = self.tree;
        let is_leaf = |n: usize| tree.nodes[n].children.is_empty();
        let k = tree.nodes[i].key.depth;
        let dir = if is_leaf(i) {
            self.leaves_dir.to_path_buf()
        } else {
            self.cells.join(format!("d{k}"))
        };
        let mut mesh = Spill::read(&dir, i, self.layout)?;
        if mesh.faces.is_empty() {
            return Ok(None);
        }
        let refitted = !is_leaf(i) && mesh.faces.len() > self.leaf;
        if refitted {
            mesh = refit(simplifier, &mesh, self.leaf)?;
        }
        if mesh.normals.is_none() {
            mesh.normals = Some(lodkit_mesh::normals::vertex_normals(&mesh));
        }
        let cuts = cut_edges(&mesh, &tree.grid, tree.nodes[i].key);
        let normals = mesh.normals.as_deref().unwrap_or_default();
        let s = Staged {
            error: 0.0,
            reach: crate::skirts::border_reach(&mesh, &cuts),
            bbox: bbox_of(&mesh.positions),
            normals: bbox_of(cuts.iter().flatten().map(|&v| &normals[v as usize])),
            faces: mesh.faces.len(),
            cuts: cuts.len(),
        };
        StagedTile { mesh, cuts }.write(&tile_file(self.tiles_dir, i))?;
        Ok(Some((s, refitted)))
    }
}

impl TileCtx<'_> {
    /// Internal node `i`'s error, once every tile of its depth is staged
    /// (see `tile_error.rs` and the parent module's docs, step 5): its
    /// tile against the reference near its cell, and the reference in
    /// its cell against the depth's tiles near it. The reference is the
    /// input (its leaves' tiles) when the cell's input fits the
    /// measurement room, else the tiles one depth down, which stand for
    /// the input up to their own errors (added). At least its children's
    /// errors.
    pub(super) fn measure(&self, i: usize, staged: &[Option<Staged>]) -> Result<f64> {
        let tree = self.tree;
        let node = &tree.nodes[i];
        let tile = StagedTile::read(&tile_file(self.tiles_dir, i))?.mesh;
        let children_error = node
            .children
            .iter()
            .filter_map(|&c| staged[c].map(|s| s.error))
            .fold(0.0f64, f64::max);
        // The neighbourhood holds about (1 + 2 × margin)² of the cell's
        // surface; the leaves read whole before cropping add to it.
        let direct = (node.input_faces as u64).saturating_mul(2) <= self.direct_faces;
        let reference_depth = if direct {
            crate::MAX_DEPTH + 1
        } else {
            node.key.depth + 1
        };
        let (reference, region, reference_error) =
            self.surface_near(node.key, reference_depth, staged)?;
        let (drawn, _, _) = self.surface_near(node.key, node.key.depth, staged)?;
        let e = tile_error::measure(&tile, &region, &reference, &drawn)?;
        Ok(if direct {
            e.max(children_error)
        } else {
            e + reference_error.max(children_error)
        })
    }

    /// A surface near `cell`, cropped to the faces whose centroid lies in
    /// `cell` grown by `tile_error::MARGIN`, with its part inside `cell`
    /// whole and the largest error among the tiles used. With `stop` at
    /// `cell`'s depth: that depth's level (its staged tiles, and its
    /// faces spilled under the leaves at or above it). Deeper: the staged
    /// tiles of depth `stop` and the input of the leaves above it (the
    /// reference).
    fn surface_near(
        &self,
        cell: CellKey,
        stop: u8,
        staged: &[Option<Staged>],
    ) -> Result<(TriMesh, TriMesh, f64)> {
        let tree = self.tree;
        let grid = &tree.grid;
        let m = grid.side(cell.depth) * tile_error::MARGIN;
        let (lo, hi) = (
            grid.corner(cell) - m,
            grid.corner(cell) + grid.side(cell.depth) + m,
        );
        let (mut near, mut inside, mut error) = (TriMesh::default(), TriMesh::default(), 0.0f64);
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let key = tree.nodes[n].key;
            let (a, b) = (grid.corner(key), grid.corner(key) + grid.side(key.depth));
            if (0..3).any(|x| a[x] > hi[x] || b[x] < lo[x]) {
                continue;
            }
            let leaf = tree.nodes[n].children.is_empty();
            if !leaf && key.depth < stop {
                stack.extend(tree.nodes[n].children.iter().rev());
                continue;
            }
            let mesh = if leaf && stop == cell.depth {
                // The level's own faces in a leaf's cell.
                Spill::read(&self.cells.join(format!("d{stop}")), n, self.layout)?
            } else if let Some(s) = staged[n] {
                error = error.max(s.error);
                StagedTile::read(&tile_file(self.tiles_dir, n))?.mesh
            } else if leaf && key.depth < cell.depth {
                // A leaf above this depth: its tile is made later, its
                // input is still spilled.
                Spill::read(self.leaves_dir, n, self.layout)?
            } else {
                continue;
            };
            let within = key.depth >= cell.depth
                && key.xyz.map(|v| v >> (key.depth - cell.depth)) == cell.xyz;
            if within {
                // Its faces lie in `cell` (by centroid): all near it.
                append(&mut inside, &mesh);
                append(&mut near, &mesh);
            } else {
                append(&mut near, &tile_error::crop_near(&mesh, grid, cell));
            }
        }
        Ok((near, inside, error))
    }
}

/// Simplifies one tile to `budget` triangles with its border vertices
/// locked, so it still meets its same-level neighbours (as in core).
fn refit(simplifier: &mut Simplifier, mesh: &TriMesh, budget: usize) -> Result<TriMesh> {
    let mut locked = vec![false; mesh.positions.len()];
    for [a, b] in crate::tile_split::border_edges(mesh) {
        locked[a as usize] = true;
        locked[b as usize] = true;
    }
    let opts = Options {
        target: Target::Faces(budget),
        fill_holes: false,
        ..Options::DEFAULT
    };
    Ok(simplifier
        .simplify_locked(mesh, &locked, &opts)
        .map_err(|e| Error::Simplify(e.to_string()))?
        .mesh)
}

/// The border edges of a tile (one face side, vertices welded by
/// position) that lie within twice their face's longest edge of the
/// boundary of `cell`: the cuts (see the module docs).
fn cut_edges(mesh: &TriMesh, grid: &Grid, cell: CellKey) -> Vec<[u32; 2]> {
    let (remap, counts) = welded_edges(mesh);
    let lo = grid.corner(cell);
    let hi = lo + grid.side(cell.depth);
    let to_boundary = |p: Vec3| {
        let p = p.as_dvec3();
        let inside = (p - lo).min(hi - p);
        inside.min_element().max(0.0)
    };
    let mut out = Vec::new();
    for tri in &mesh.faces {
        let pos = tri.map(|v| mesh.positions[v as usize]);
        let longest = (0..3)
            .map(|k| pos[k].distance(pos[(k + 1) % 3]))
            .fold(0.0f32, f32::max) as f64;
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let (x, y) = (remap[a as usize], remap[b as usize]);
            if counts.get(&(x.min(y), x.max(y))) == Some(&1) {
                let mid = (pos[k] + pos[(k + 1) % 3]) * 0.5;
                if to_boundary(mid) <= 2.0 * longest {
                    out.push([a, b]);
                }
            }
        }
    }
    out
}
