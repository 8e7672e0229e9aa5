//! The levels: one HQMS chain over the whole object, finest first, each
//! level cut into the tiles of its octree depth, each tile measured
//! against the input it stands for (`tile_error.rs`).
//!
//! Level `D` (the octree's depth) is the input. Level `k < D` is the
//! simplification of level `k + 1` (the whole mesh, as `lodkit simplify`
//! would do it: one global error order, borders and holes as in core) to
//! `ρₖ ×` its faces, where `ρₖ` is what the depth-`k` tiles ask for:
//! each internal node `N` wants `t(N) = min(leaf budget, ⌈c(N) / 2⌉)`
//! triangles, `c(N)` the faces of level `k + 1` in its cell, and
//! `ρₖ = Σ t(N) / Σ c(N)`. So a parent holds about half of what its
//! children hold, never more than one leaf's budget (on a surface about
//! four of eight children are occupied, so a parent of full children gets
//! about a quarter of them). Leaves are the input's own faces in their
//! cell, at full resolution, whatever their depth.
//!
//! Tiles of one level are cut from one mesh, so neighbours of the same
//! level share their border vertices exactly; where a client shows
//! neighbours of different levels the skirts cover the sliver (see
//! `skirts.rs` and the crate docs for why not locked borders). A level's
//! triangles do not spread evenly over the cells (the error order puts
//! them where the shape needs them): a tile over its budget is simplified
//! again on its own to the budget with its border locked, so it still
//! meets its same-level neighbours.

use lodkit_mesh::TriMesh;
use lodkit_simplify::{AttributeWeights, Options, Simplifier, Target};

use crate::octree_partition::{Octree, centroid};
use crate::tile_split::{TileMesh, border_edges, edge_bits, split};
use crate::{Error, Event, Phase, Result, tile_error};

/// Every node's tile (`None`: no content, a cell the level left empty)
/// and measured error (`tile_error::measure`, object units; 0 for
/// leaves), before the monotone pass.
pub struct Levels {
    /// Per node (indexed as [`Octree::nodes`]).
    pub tiles: Vec<Option<TileMesh>>,
    /// Per node: measured two-sided maximum distance.
    pub measured: Vec<f64>,
    /// Faces of each level's whole mesh, from the root's level (0) to the input's.
    pub level_faces: Vec<usize>,
    /// Tiles simplified again to their budget (border locked).
    pub refitted: usize,
    /// Seconds in simplification and in measurement.
    pub seconds: (f64, f64),
}

/// Builds every level of `tree` over `input` (which must have normals).
/// `groups` (one per input vertex, each face's corners in one group; or
/// empty) are materials: kept as seams through every simplification
/// (`Simplifier::simplify_grouped`) and carried into the tiles.
///
/// `derived_normals`: the input's normals were computed from its faces,
/// not scanned. They then play no part in the collapse costs (a level is
/// simplified on its geometry alone, as `lodkit simplify` does a file
/// without normals) and each level gets its own, computed from its faces
/// over the whole level, so neighbouring tiles shade alike.
pub fn build_levels(
    input: &TriMesh,
    groups: &[u32],
    tree: &Octree,
    leaf_budget: usize,
    derived_normals: bool,
    progress: &mut dyn FnMut(Event),
) -> Result<Levels> {
    let weights = if derived_normals {
        AttributeWeights {
            normal: 0.0,
            ..AttributeWeights::DEFAULT
        }
    } else {
        AttributeWeights::DEFAULT
    };
    let n = tree.nodes.len();
    let mut tiles: Vec<Option<TileMesh>> = vec![None; n];
    let mut measured = vec![0.0; n];
    let mut level_faces = vec![0; tree.depth as usize + 1];
    level_faces[tree.depth as usize] = input.faces.len();
    let (mut t_simplify, mut t_measure) = (0.0, 0.0);
    let mut refitted = 0;

    // Leaves: the input's faces, by leaf.
    let leaves: Vec<usize> = (0..n)
        .filter(|&i| tree.nodes[i].children.is_empty())
        .collect();
    let mut slot = vec![usize::MAX; n];
    for (s, &l) in leaves.iter().enumerate() {
        slot[l] = s;
    }
    for (s, t) in split(input, groups, leaves.len(), |f| {
        Some(slot[tree.leaf_of_face[f] as usize])
    })
    .into_iter()
    .enumerate()
    {
        tiles[leaves[s]] = Some(t);
    }

    let total_internal = n - leaves.len();
    let mut done = 0;
    let mut simplifier = Simplifier::new();
    let mut finer: Option<(TriMesh, Vec<u32>)> = None;
    for depth in (0..tree.depth).rev() {
        let internal: Vec<usize> = (0..n)
            .filter(|&i| tree.nodes[i].key.depth == depth && !tree.nodes[i].children.is_empty())
            .collect();
        let (source, source_groups) = finer
            .as_ref()
            .map_or((input, groups), |(m, g)| (m, g.as_slice()));
        let index: std::collections::HashMap<_, usize> = internal
            .iter()
            .enumerate()
            .map(|(s, &i)| (tree.nodes[i].key, s))
            .collect();
        let cell_slot = |m: &TriMesh, f: usize| {
            index
                .get(&tree.grid.cell_of(centroid(m, f), depth))
                .copied()
        };
        // What the depth's tiles ask of this level.
        let mut have = vec![0usize; internal.len()];
        for f in 0..source.faces.len() {
            if let Some(s) = cell_slot(source, f) {
                have[s] += 1;
            }
        }
        let want: usize = have.iter().map(|&c| leaf_budget.min(c.div_ceil(2))).sum();
        let asked: usize = have.iter().sum();
        let ratio = if asked == 0 {
            0.5
        } else {
            want as f64 / asked as f64
        };
        let goal = ((source.faces.len() as f64 * ratio).ceil() as usize).max(1);
        let t0 = std::time::Instant::now();
        let simplify_error = |e: lodkit_simplify::Error| Error::Simplify(e.to_string());
        let opts = Options {
            weights,
            ..Options::faces(goal)
        };
        let (mut level, level_groups) = if goal >= source.faces.len() {
            (source.clone(), source_groups.to_vec())
        } else if source_groups.is_empty() {
            let out = simplifier.simplify(source, &opts);
            (out.map_err(simplify_error)?.mesh, Vec::new())
        } else {
            let out = simplifier.simplify_grouped(source, source_groups, &opts);
            let (out, g) = out.map_err(simplify_error)?;
            (out.mesh, g)
        };
        if derived_normals && goal < source.faces.len() {
            level.normals = Some(lodkit_mesh::normals::vertex_normals(&level));
        }
        level_faces[depth as usize] = level.faces.len();
        let mut parts = split(&level, &level_groups, internal.len(), |f| {
            cell_slot(&level, f)
        });
        for part in parts.iter_mut() {
            if part.mesh.faces.len() > leaf_budget {
                refit(&mut simplifier, part, leaf_budget, weights)?;
                refitted += 1;
            }
        }
        t_simplify += t0.elapsed().as_secs_f64();

        // Measure each tile (see `tile_error.rs`): against the input near
        // its cell, and the cell's input against the level near it (its
        // tiles, and its faces in the cells of leaves above this depth).
        let t1 = std::time::Instant::now();
        let mut drawn = TriMesh::default();
        for part in &parts {
            append(&mut drawn, &part.mesh);
        }
        let in_leaves: Vec<u32> = (0..level.faces.len() as u32)
            .filter(|&f| {
                let key = tree.grid.cell_of(centroid(&level, f as usize), depth);
                !index.contains_key(&key) && tree.leaf_holding(key).is_some()
            })
            .collect();
        append(&mut drawn, &tile_error::gather(&level, &in_leaves));
        let slot_of = |k| index.get(&k).copied();
        let (own, input_near) =
            tile_error::faces_near(input, &tree.grid, depth, internal.len(), slot_of);
        let (_, drawn_near) =
            tile_error::faces_near(&drawn, &tree.grid, depth, internal.len(), slot_of);
        for (s, &node) in internal.iter().enumerate() {
            if !parts[s].mesh.faces.is_empty() {
                let near = tile_error::gather(input, &input_near[s]);
                // A cell with nothing near it (the root) measures its own
                // input against its level: one copy of it, not two.
                let region = (own[s].len() < input_near[s].len())
                    .then(|| tile_error::gather(input, &own[s]));
                measured[node] = tile_error::measure(
                    &parts[s].mesh,
                    region.as_ref().unwrap_or(&near),
                    &near,
                    &tile_error::gather(&drawn, &drawn_near[s]),
                )?;
            }
            done += 1;
            progress(Event::Progress {
                phase: Phase::Levels,
                done,
                total: total_internal,
            });
        }
        for (s, part) in parts.into_iter().enumerate() {
            if !part.mesh.faces.is_empty() {
                tiles[internal[s]] = Some(part);
            }
        }
        t_measure += t1.elapsed().as_secs_f64();
        finer = Some((level, level_groups));
    }
    Ok(Levels {
        tiles,
        measured,
        level_faces,
        refitted,
        seconds: (t_simplify, t_measure),
    })
}

/// Simplifies one tile to `budget` triangles with its border vertices
/// locked (so it still meets its same-level neighbours), keeping its cut
/// edges by their positions.
fn refit(
    simplifier: &mut Simplifier,
    part: &mut TileMesh,
    budget: usize,
    weights: AttributeWeights,
) -> Result<()> {
    let m = &part.mesh;
    let mut locked = vec![false; m.positions.len()];
    for [a, b] in border_edges(m) {
        locked[a as usize] = true;
        locked[b as usize] = true;
    }
    let cut_bits: std::collections::HashSet<_> =
        part.cuts.iter().map(|&c| edge_bits(m, c)).collect();
    let opts = Options {
        target: Target::Faces(budget),
        fill_holes: false,
        weights,
        ..Options::DEFAULT
    };
    let simplify_error = |e: lodkit_simplify::Error| Error::Simplify(e.to_string());
    let (out, groups) = if part.groups.is_empty() {
        let out = simplifier.simplify_locked(m, &locked, &opts);
        (out.map_err(simplify_error)?.mesh, Vec::new())
    } else {
        let out = simplifier.simplify_grouped_locked(m, &part.groups, &locked, &opts);
        let (out, g) = out.map_err(simplify_error)?;
        (out.mesh, g)
    };
    let cuts = border_edges(&out)
        .into_iter()
        .filter(|&e| cut_bits.contains(&edge_bits(&out, e)))
        .collect();
    *part = TileMesh {
        mesh: out,
        cuts,
        groups,
    };
    Ok(())
}

/// `b`'s triangles added to `a` (positions only: a measurement surface).
pub(crate) fn append(a: &mut TriMesh, b: &TriMesh) {
    let base = a.positions.len() as u32;
    a.positions.extend_from_slice(&b.positions);
    a.faces.extend(b.faces.iter().map(|f| f.map(|v| v + base)));
}
