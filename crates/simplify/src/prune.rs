//! Component pruning (`--prune`): not in the paper. Scans carry debris —
//! small floating pieces that cost triangles at every level and that edge
//! collapse cannot remove (it never erases a component). Pieces whose
//! bounding-box diagonal is below a fraction of the whole mesh's diagonal
//! are deleted before the first pass.

use glam::Vec3;
use lodkit_mesh::topology::UnionFind;

use crate::ring_table::DEAD;
use crate::work_mesh::WorkMesh;

/// Marks the faces of every vertex-connected component smaller than
/// `fraction × diagonal` as deleted. Returns the number of faces removed.
pub fn prune_small_components(m: &mut WorkMesh, fraction: f32) -> usize {
    let n = m.pos.len();
    if n == 0 || !(fraction > 0.0) {
        return 0;
    }
    let mut uf = UnionFind::new(n);
    for f in &m.faces {
        if f[0] != DEAD {
            uf.union(f[0], f[1]);
            uf.union(f[1], f[2]);
        }
    }
    let mut lo = vec![Vec3::splat(f32::INFINITY); n];
    let mut hi = vec![Vec3::splat(f32::NEG_INFINITY); n];
    let mut all_lo = Vec3::splat(f32::INFINITY);
    let mut all_hi = Vec3::splat(f32::NEG_INFINITY);
    for f in &m.faces {
        if f[0] == DEAD {
            continue;
        }
        let r = uf.find(f[0]) as usize;
        for &v in f {
            let p = m.pos[v as usize];
            lo[r] = lo[r].min(p);
            hi[r] = hi[r].max(p);
            all_lo = all_lo.min(p);
            all_hi = all_hi.max(p);
        }
    }
    let limit = (all_hi - all_lo).length() * fraction;
    let mut removed = 0;
    for fi in 0..m.faces.len() {
        let f = m.faces[fi];
        if f[0] == DEAD {
            continue;
        }
        let r = uf.find(f[0]) as usize;
        if (hi[r] - lo[r]).length() < limit {
            m.faces[fi] = [DEAD; 3];
            removed += 1;
        }
    }
    m.live_faces -= removed;
    removed
}
