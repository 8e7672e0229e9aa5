//! One block, simplified in core: its soup welded, simplified with every
//! vertex that may lie on a cut locked (the cut through the mesh is a
//! border of the block, so the vertices it shares with other blocks stay
//! where they are, bit for bit), and written back as a soup. This is the
//! unit of work that runs on a rayon thread or as a Ray task: its inputs
//! are two paths and the options, its output a file, nothing shared.
//!
//! Only the border vertices the round's [`Cuts`] say may be shared are
//! locked; the rest of the block's border is the mesh's own (a scan's
//! rim, a hole's edge) and simplifies as in core. Locking it too would
//! leave the rim at full density for the final pass, which then thins it
//! from a coarse neighbourhood: on a scan's open base that gave 2.8× the
//! in-core maximum error (a 20 M-triangle subdivided bunny at 1 %).
//!
//! The goal applies the ratio to the block's free part only. A locked
//! vertex can never be removed, so a goal of `ratio × faces` would
//! make the interior pay for the cut: a disk with `B` locked and `I`
//! other vertices has about `2I + B` faces, and with `B` fixed, reaching
//! `ratio × faces` takes the interior below `ratio` (at 1 % on blocks of
//! 77 k faces, a few interior vertices fanned out to the border: 20× the
//! in-core error). Keeping the `B` locked vertices and `ratio` of the
//! rest (goal `⌈ratio × (faces − B)⌉ + B`) leaves the interior at the
//! density an in-core run gives it, and the excess the cut holds,
//! about `(1 − ratio) × B` faces, to the final pass, where the seams are
//! free.

use std::path::Path;

use lodkit_mesh::TriMesh;
use lodkit_mesh::topology::edge_multiplicities;
use lodkit_simplify::{Options, Simplifier, Target};

use crate::partition::Cuts;
use crate::soup::{self, Layout, Welder};

/// What [`simplify_block`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct BlockReport {
    /// Faces read.
    pub faces_in: u64,
    /// Faces written.
    pub faces_out: u64,
}

/// How far a block goes ([`simplify_block`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Goal {
    /// `⌈ratio × (faces − B)⌉ + B`, `B` the block's locked vertices: the
    /// interior ends at the density an in-core run gives it and the
    /// border's excess is left to a later pass (the block rounds before
    /// a final in-core pass).
    Interior(f64),
    /// `⌈ratio × faces⌉`, but at least `B`: the round's total is `ratio`
    /// of its input (the out-of-core levels of a chain, which are outputs
    /// themselves; with blocks of millions of faces the border is well
    /// under 1 % of a block, so the interior's extra share is small).
    Total(f64),
}

impl Goal {
    /// The ratio, whichever the rule.
    pub fn ratio(self) -> f64 {
        match self {
            Goal::Interior(r) | Goal::Total(r) => r,
        }
    }
}

/// Simplifies the soup `input` to `goal` with `opts` (its target is
/// replaced, `fill_holes` off: a cut is a border of the block, not a
/// hole), every border vertex that may lie on one of `cuts` locked, and
/// writes the soup `output` atomically. Deterministic: the same file and options give
/// the same bytes on any machine. Errors: I/O, or the simplifier refusing
/// the block (a message naming the file). Memory: about 100 bytes per face
/// of the block. Cost: linear in the block's faces.
pub fn simplify_block(
    input: &Path,
    output: &Path,
    goal: Goal,
    cuts: &Cuts,
    opts: &Options,
    layout: Layout,
) -> Result<BlockReport, String> {
    let mut w = Welder::new(layout);
    soup::for_each(input, layout, |t| w.add(t)).map_err(|e| format!("{}: {e}", input.display()))?;
    let mesh = w.finish();
    let faces_in = mesh.faces.len() as u64;
    let mut locked = border_flags(&mesh);
    for (l, &p) in locked.iter_mut().zip(&mesh.positions) {
        *l = *l && cuts.may_cross(p);
    }
    let held = locked.iter().filter(|&&l| l).count() as u64;
    let target = match goal {
        Goal::Interior(ratio) => {
            let free = faces_in.saturating_sub(held) as f64;
            (free * ratio.clamp(0.0, 1.0)).ceil() as u64 + held
        }
        Goal::Total(ratio) => ((faces_in as f64 * ratio.clamp(0.0, 1.0)).ceil() as u64).max(held),
    }
    .min(faces_in) as usize;
    let o = Options {
        target: Target::Faces(target),
        lock_border: false,
        // A cut is a border of the block, not a hole: hole filling would
        // merge the two sides of a narrow strip of the block.
        fill_holes: false,
        ..opts.clone()
    };
    let out = Simplifier::new()
        .simplify_locked(&mesh, &locked, &o)
        .map_err(|e| format!("{}: {e}", input.display()))?;
    soup::write_mesh(output, layout, &out.mesh)
        .map_err(|e| format!("{}: {e}", output.display()))?;
    Ok(BlockReport {
        faces_in,
        faces_out: out.mesh.faces.len() as u64,
    })
}

/// Per vertex of `mesh`, whether it is on a border edge (an edge of
/// exactly one face), from [`edge_multiplicities`].
pub(crate) fn border_flags(mesh: &TriMesh) -> Vec<bool> {
    let mut flags = vec![false; mesh.positions.len()];
    for e in edge_multiplicities(mesh) {
        if e.count == 1 {
            flags[e.a as usize] = true;
            flags[e.b as usize] = true;
        }
    }
    flags
}

#[cfg(test)]
mod tests {
    use glam::Vec3;
    use lodkit_mesh::TriMesh;

    fn border_vertices(faces: &[[u32; 3]]) -> usize {
        let m = TriMesh::new(vec![Vec3::ZERO; 5], faces.to_vec());
        super::border_flags(&m).iter().filter(|&&b| b).count()
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
