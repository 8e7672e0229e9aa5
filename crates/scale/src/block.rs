//! One block, simplified in core: its soup welded, simplified with every
//! border vertex locked (the cut through the mesh is a border of the
//! block, so the vertices it shares with other blocks stay where they are,
//! bit for bit), and written back as a soup. This is the unit of work that
//! runs on a rayon thread or as a Ray task: its inputs are two paths and
//! the options, its output a file, nothing shared.
//!
//! The goal applies the ratio to the block's free part only. A locked
//! border vertex can never be removed, so a goal of `ratio × faces` would
//! make the interior pay for the border: a disk with `B` border and `I`
//! interior vertices has `2I + B − 2` faces, and with `B` fixed, reaching
//! `ratio × faces` takes the interior below `ratio` (at 1 % on blocks of
//! 77 k faces, a few interior vertices fanned out to the border: 20× the
//! in-core error). Keeping the `B` border vertices and `ratio` of the
//! interior (goal `⌈ratio × (faces − B)⌉ + B`) leaves the interior at the
//! density an in-core run gives it, and the excess the border holds,
//! about `(1 − ratio) × B` faces, to the final pass, where the seams are
//! free.

use std::path::Path;

use lodkit_mesh::TriMesh;
use lodkit_mesh::topology::edge_multiplicities;
use lodkit_simplify::{Options, Simplifier, Target};

use crate::soup::{self, Welder};

/// What [`simplify_block`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlockReport {
    /// Faces read.
    pub faces_in: u64,
    /// Faces written.
    pub faces_out: u64,
}

/// Simplifies the soup `input` to `ratio` of its faces (rounded up) with
/// `opts` (its target is replaced; `lock_border` forced on, `fill_holes` off) and writes the
/// soup `output` atomically. Deterministic: the same file and options give
/// the same bytes on any machine. Errors: I/O, or the simplifier refusing
/// the block (a message naming the file). Memory: about 100 bytes per face
/// of the block. Cost: linear in the block's faces.
pub fn simplify_block(
    input: &Path,
    output: &Path,
    ratio: f64,
    opts: &Options,
) -> Result<BlockReport, String> {
    let mut w = Welder::default();
    soup::for_each(input, |t| w.add(t)).map_err(|e| format!("{}: {e}", input.display()))?;
    let mesh = w.finish();
    let faces_in = mesh.faces.len() as u64;
    let border = border_vertices(&mesh) as u64;
    let free = faces_in.saturating_sub(border) as f64;
    let target = ((free * ratio.clamp(0.0, 1.0)).ceil() as u64 + border).min(faces_in) as usize;
    let o = Options {
        target: Target::Faces(target),
        lock_border: true,
        // A cut is a border of the block, not a hole: hole filling would
        // merge the two sides of a narrow strip of the block.
        fill_holes: false,
        ..opts.clone()
    };
    let out = Simplifier::new()
        .simplify(&mesh, &o)
        .map_err(|e| format!("{}: {e}", input.display()))?;
    soup::write_mesh(output, &out.mesh).map_err(|e| format!("{}: {e}", output.display()))?;
    Ok(BlockReport {
        faces_in,
        faces_out: out.mesh.faces.len() as u64,
    })
}

/// Vertices on a border edge (an edge of exactly one face) of `mesh`:
/// the vertices `lock_border` keeps. From the sorted edge list of
/// [`edge_multiplicities`], so the count is the same on every run.
fn border_vertices(mesh: &TriMesh) -> usize {
    let mut ends: Vec<u32> = edge_multiplicities(mesh)
        .into_iter()
        .filter(|e| e.count == 1)
        .flat_map(|e| [e.a, e.b])
        .collect();
    ends.sort_unstable();
    ends.dedup();
    ends.len()
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use lodkit_mesh::TriMesh;

    fn border_vertices(faces: &[[u32; 3]]) -> usize {
        super::border_vertices(&TriMesh::new(vec![Vec3::ZERO; 5], faces.to_vec()))
    }

    #[test]
    fn border_vertices_of_a_strip_and_a_closed_mesh() {
        // Two triangles sharing an edge: all four vertices on the border.
        assert_eq!(border_vertices(&[[0, 1, 2], [2, 1, 3]]), 4);
        // A fan of four around vertex 4: the centre is interior.
        let fan = [[4, 0, 1], [4, 1, 2], [4, 2, 3], [4, 3, 0]];
        assert_eq!(border_vertices(&fan), 4);
        // A tetrahedron is closed.
        let tet = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
        assert_eq!(border_vertices(&tet), 0);
    }
}
