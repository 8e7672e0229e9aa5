//! Skirts: a strip hung from each cut edge of a tile, inwards along the
//! vertex normals, so that where a client shows neighbours of different
//! levels the sliver between their borders shows the strip, not the
//! background (quantized-mesh terrain's remedy, on a surface of any
//! orientation).
//!
//! Each cut edge `a → b` (the tile's face on its left, seen from outside)
//! gets the quad `a b b′ a′`, `v′ = v − depth × n(v)`, as four triangles:
//! both windings, because clients cull back faces and a ray through a
//! sliver may meet the strip from either side (the normals lean it over
//! the neighbour where the surface curves: one-sided strips left more
//! holes than none on the closed bunny). Skirt vertices copy their edge's
//! attributes. Borders of the input itself (a
//! scan's rim) are not cuts and get none.

use lodkit_mesh::TriMesh;

/// `mesh` with a skirt of `depth` (object units, > 0) on each of `cuts`.
/// Adds two vertices and four triangles per cut; `mesh` must have normals
/// (a vertex without one hangs its skirt nowhere: zero-length normal).
/// `groups` (one per vertex, or empty) gets one entry per added vertex,
/// its edge vertex's.
pub fn with_skirts(
    mesh: &TriMesh,
    cuts: &[[u32; 2]],
    depth: f32,
    groups: &mut Vec<u32>,
) -> TriMesh {
    let mut out = mesh.clone();
    if cuts.is_empty() || depth <= 0.0 {
        return out;
    }
    let normals = mesh.normals.clone().unwrap_or_default();
    // One skirt vertex per border vertex, made on first use.
    let mut low = vec![u32::MAX; mesh.positions.len()];
    let mut lowered = |v: u32, out: &mut TriMesh| -> u32 {
        if low[v as usize] == u32::MAX {
            let n = normals.get(v as usize).copied().unwrap_or_default();
            let i = v as usize;
            out.positions.push(mesh.positions[i] - n * depth);
            if let Some(ns) = out.normals.as_mut() {
                ns.push(n);
            }
            if let Some(c) = out.colors.as_mut() {
                c.push(mesh.colors.as_ref().map(|c| c[i]).unwrap_or_default());
            }
            if let Some(u) = out.uvs.as_mut() {
                u.push(mesh.uvs.as_ref().map(|u| u[i]).unwrap_or_default());
            }
            if let Some(&g) = groups.get(i) {
                groups.push(g);
            }
            low[i] = out.positions.len() as u32 - 1;
        }
        low[v as usize]
    };
    for &[a, b] in cuts {
        let la = lowered(a, &mut out);
        let lb = lowered(b, &mut out);
        out.faces.push([b, a, la]);
        out.faces.push([b, la, lb]);
        // The same strip wound the other way: seen from either side.
        out.faces.push([a, b, la]);
        out.faces.push([la, b, lb]);
    }
    out
}
