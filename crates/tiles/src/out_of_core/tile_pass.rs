//! The tile pass of the out-of-core tiler: one depth's tiles made from
//! their cells' spills, two at a time, each welded, refitted to the leaf
//! budget when over it, given normals and cuts, measured (see the parent
//! module's docs, steps 3–5) and staged to its file.

use std::path::{Path, PathBuf};

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::Reference;
use lodkit_scale::soup::Layout;
use lodkit_simplify::{Options, Simplifier, Target};

use super::{Staged, bbox_of};
use crate::cell_spill::{Spill, StagedTile};
use crate::octree_partition::{CellKey, Grid, Octree};
use crate::tile_split::welded_edges;
use crate::{Error, Result};

/// Tiles staged at once in the tile pass.
pub(super) const IN_FLIGHT: usize = 2;

pub(super) fn tile_file(dir: &Path, node: usize) -> PathBuf {
    dir.join(format!("{node}.tile"))
}

/// What making one tile reads: the tree, the staged children, the folders.
pub(super) struct TileCtx<'a> {
    pub(super) tree: &'a Octree,
    pub(super) staged: &'a [Option<Staged>],
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
    /// budget when over it, normals, cuts, its error (see the module
    /// docs), staged to its file. `None` for an empty cell; the flag says
    /// whether it was refitted.
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
        let mut error = 0.0f64;
        if !is_leaf(i) {
            let child_error = tree.nodes[i]
                .children
                .iter()
                .filter_map(|&c| self.staged[c].map(|s| s.error))
                .fold(0.0f64, f64::max);
            let direct = (tree.nodes[i].input_faces as u64) <= self.direct_faces;
            // The input of this cell (its leaves' tiles) when it fits the
            // measurement room, as in core; else the children's tiles,
            // which stand for it up to their own error.
            let mut region = TriMesh::default();
            let mut stack = tree.nodes[i].children.clone();
            while let Some(c) = stack.pop() {
                if direct && !is_leaf(c) {
                    stack.extend(tree.nodes[c].children.iter().rev());
                } else if self.staged[c].is_some() {
                    let tile = StagedTile::read(&tile_file(self.tiles_dir, c))?;
                    append(&mut region, &tile.mesh);
                }
            }
            if !region.faces.is_empty() {
                let reference = Reference::new(&region)?;
                error = reference.compare_level(&mesh, None)?.symmetric.max;
            }
            error = if direct {
                error.max(child_error)
            } else {
                error + child_error
            };
        }
        let normals = mesh.normals.as_deref().unwrap_or_default();
        let s = Staged {
            error,
            bbox: bbox_of(&mesh.positions),
            normals: bbox_of(cuts.iter().flatten().map(|&v| &normals[v as usize])),
            faces: mesh.faces.len(),
            cuts: cuts.len(),
        };
        StagedTile { mesh, cuts }.write(&tile_file(self.tiles_dir, i))?;
        Ok(Some((s, refitted)))
    }
}

/// `b`'s triangles added to `a` (positions only: a measurement region).
fn append(a: &mut TriMesh, b: &TriMesh) {
    let base = a.positions.len() as u32;
    a.positions.extend_from_slice(&b.positions);
    a.faces.extend(b.faces.iter().map(|f| f.map(|v| v + base)));
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
    let side = grid.size / (1u64 << cell.depth) as f64;
    let lo = grid.origin + glam::DVec3::from_array(cell.xyz.map(f64::from)) * side;
    let hi = lo + glam::DVec3::splat(side);
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
