//! One block, simplified in core: its soup welded, simplified with every
//! border vertex locked (the cut through the mesh is a border of the
//! block, so the vertices it shares with other blocks stay where they are,
//! bit for bit), and written back as a soup. This is the unit of work that
//! runs on a rayon thread or as a Ray task: its inputs are two paths and
//! the options, its output a file, nothing shared.

use std::path::Path;

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
    let target = (faces_in as f64 * ratio.clamp(0.0, 1.0)).ceil() as usize;
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
