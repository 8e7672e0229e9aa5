//! The output stage (HQMS §4.4, `OutputLOD`): compaction of the surviving
//! vertices and faces through the vertex index table `V^i`, and export of a
//! level as a `TriMesh`.
//!
//! As in the paper, the compacted mesh is both the level's output and the
//! next pass's input. We compact in place (no second mesh in memory): the
//! index table is a scratch `u32` per vertex, reused for the wedges.
//! Unreferenced input vertices disappear at the first compaction.

use glam::{Vec2, Vec3};
use lodkit_mesh::TriMesh;

use crate::ring_table::{DEAD, Flag};
use crate::work_mesh::WorkMesh;

const NONE: u32 = u32::MAX;

/// Drops deleted faces and vertices, renumbers in the old order, resets
/// every contraction flag to valid for the next pass.
#[allow(clippy::needless_range_loop)] // one index drives several arrays
pub fn compact(m: &mut WorkMesh, index: &mut Vec<u32>) {
    // Faces (and their corner wedges) in place, marking the vertices they
    // use in the vertex index table V^i as they move.
    let has_wedges = m.has_wedges();
    let n = m.pos.len();
    // One slot more than the vertices: a deleted face marks it (DEAD
    // clamps to `n`), so the loop has no branch on the face's state —
    // after a pass the deleted faces are scattered and that branch
    // mispredicted.
    index.clear();
    index.resize(n + 1, NONE);
    let mut w = 0;
    // Plain slices in the hot loops: their bounds stay in registers.
    let (faces, idx) = (&mut m.faces[..], &mut index[..]);
    for r in 0..faces.len() {
        let f = faces[r];
        for v in f {
            idx[(v as usize).min(n)] = 0;
        }
        // Written in any case, kept only if live.
        faces[w] = f;
        if has_wedges {
            m.wedges[w] = m.wedges[r];
        }
        w += (f[0] != DEAD) as usize;
    }
    m.faces.truncate(w);
    if has_wedges {
        m.wedges.truncate(w);
    }
    m.live_faces = w;

    // Number the marked vertices in their old order.
    let mut next = 0u32;
    let (idx, pos, err) = (&mut index[..n], &mut m.pos[..n], &mut m.err[..n]);
    let locked = !m.locked.is_empty();
    for v in 0..n {
        // Branch-free too: `next <= v`, so the copy is always in bounds
        // and an unmarked vertex's copy is overwritten or cut.
        let used = idx[v] != NONE;
        idx[v] = if used { next } else { NONE };
        pos[next as usize] = pos[v];
        err[next as usize] = err[v];
        next += used as u32;
    }
    if locked {
        for v in 0..n {
            let i = index[v];
            if i != NONE {
                m.locked[i as usize] = m.locked[v];
            }
        }
        m.locked.truncate(next as usize);
    }
    let k = m.layout.k;
    if k > 0 && !has_wedges {
        for v in 0..n {
            let i = index[v];
            if i != NONE && i as usize != v {
                m.attr.copy_within(v * k..v * k + k, i as usize * k);
            }
        }
        m.attr.truncate(next as usize * k);
    }
    if !m.group.is_empty() && !has_wedges {
        for v in 0..n {
            let i = index[v];
            if i != NONE {
                m.group[i as usize] = m.group[v];
            }
        }
        m.group.truncate(next as usize);
    }
    let idx = &index[..];
    for f in &mut m.faces {
        for v in f.iter_mut() {
            *v = idx[*v as usize];
        }
    }
    m.pos.truncate(next as usize);
    m.err.truncate(next as usize);
    m.flags.clear();
    m.flags.resize(next as usize, Flag::Valid);

    // Wedge index table.
    if has_wedges {
        let nw = m.wedge_count();
        index.clear();
        index.resize(nw, NONE);
        for f in &m.wedges {
            for &x in f {
                index[x as usize] = 0;
            }
        }
        let mut next = 0u32;
        for x in 0..nw {
            if index[x] != NONE {
                index[x] = next;
                if next as usize != x {
                    m.attr.copy_within(x * k..x * k + k, next as usize * k);
                    if !m.group.is_empty() {
                        m.group[next as usize] = m.group[x];
                    }
                }
                next += 1;
            }
        }
        m.attr.truncate(next as usize * k);
        if !m.group.is_empty() {
            m.group.truncate(next as usize);
        }
        for f in &mut m.wedges {
            for x in f.iter_mut() {
                *x = index[*x as usize];
            }
        }
    }
}

/// The compacted working mesh as a `TriMesh` (copies).
pub fn export(m: &WorkMesh) -> TriMesh {
    if !m.has_wedges() {
        let mut out = TriMesh::new(m.pos.clone(), m.faces.clone());
        to_object_space(m, &mut out.positions);
        write_attrs(m, m.pos.len(), &mut out);
        return out;
    }
    let nw = m.wedge_count();
    let mut positions = vec![Vec3::ZERO; nw];
    for (f, wf) in m.faces.iter().zip(&m.wedges) {
        for c in 0..3 {
            positions[wf[c] as usize] = m.pos[f[c] as usize];
        }
    }
    to_object_space(m, &mut positions);
    let mut out = TriMesh::new(positions, m.wedges.clone());
    write_attrs(m, nw, &mut out);
    out
}

/// Working-frame positions back to object space (exact: a power of two).
fn to_object_space(m: &WorkMesh, positions: &mut [Vec3]) {
    let unit = m.unit();
    if unit != 1.0 {
        positions.iter_mut().for_each(|p| *p /= unit);
    }
}

/// Moves the compacted working mesh out as a `TriMesh` without copying the
/// vertex and face arrays when there are no wedges (the working mesh is
/// left empty).
pub fn take(m: &mut WorkMesh) -> TriMesh {
    if m.has_wedges() {
        return export(m);
    }
    let mut pos = std::mem::take(&mut m.pos);
    let mut faces = std::mem::take(&mut m.faces);
    pos.shrink_to_fit();
    faces.shrink_to_fit();
    let n = pos.len();
    to_object_space(m, &mut pos);
    let mut out = TriMesh::new(pos, faces);
    write_attrs(m, n, &mut out);
    m.live_faces = 0;
    out
}

fn write_attrs(m: &WorkMesh, n: usize, out: &mut TriMesh) {
    let k = m.layout.k;
    if k == 0 {
        return;
    }
    let a = |i: usize, o: usize| m.attr[i * k + o];
    if let Some(o) = m.layout.normal {
        out.normals = Some(
            (0..n)
                .map(|i| {
                    let v = Vec3::new(a(i, o), a(i, o + 1), a(i, o + 2));
                    v.try_normalize().unwrap_or(v)
                })
                .collect(),
        );
    }
    if let Some(o) = m.layout.color {
        out.colors = Some(
            (0..n)
                .map(|i| {
                    std::array::from_fn(|c| (a(i, o + c).clamp(0.0, 1.0) * 255.0).round() as u8)
                })
                .collect(),
        );
    }
    if let Some(o) = m.layout.uv {
        out.uvs = Some((0..n).map(|i| Vec2::new(a(i, o), a(i, o + 1))).collect());
    }
}
