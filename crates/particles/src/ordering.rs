//! Progressive ordering of the ON leaves — §4.4 and §5.3 of Yemez & Schmitt.
//!
//! After thinning, every level keeps its ON cubes ("kept") and its phantom
//! nodes (eliminated cubes that still have ON descendants, §4.3). Each kept
//! cube `s^r` is specified by one ON leaf of its subtree (Definition 4),
//! found by the lexicographic path rule: descend to the kept child of
//! smallest code `C = cx + 2cy + 4cz` (eq. 1), i.e. the child closest to the
//! origin. A kept node therefore inherits the leaf of its parent when it is
//! that parent's first kept child; every other kept node brings a new leaf —
//! these are the difference sets `S^{R,r} \ S^{R,r-1}` and, with their
//! vertices, the particle sets `P^r` (Definition 6). Inside a level the new
//! particles are in Morton order, the order §7.1 codes them in.
//!
//! Phantom nodes carry no particle (§5.2) and never pass their leaf on, so
//! the path rule only walks through kept nodes; relabelling in
//! [`crate::thinning`] guarantees every kept node but the root has a kept
//! child. Departure: the root is never relabelled (§4.3 stops at level 1),
//! so when outer thinning eliminates all of level 1 the first phantom
//! below the root is kept again (and so on down), keeping the stream's
//! root particle well defined.
use crate::error::{Error, Result};
use crate::octree::{Label, Octree};

/// Marker for "no particle" (phantom nodes).
pub const NO_PARTICLE: u32 = u32::MAX;

/// One level of the thinned octree: the nodes the stream must describe.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct HLevel {
    /// Kept and phantom nodes, sorted Morton codes.
    pub cells: Vec<u64>,
    /// Whether each node is a phantom.
    pub phantom: Vec<bool>,
    /// The particle of each kept node ([`NO_PARTICLE`] for phantoms).
    pub particle: Vec<u32>,
}

impl HLevel {
    /// Number of kept (ON) nodes, `k_r` of Table 1.
    pub fn kept(&self) -> usize {
        self.phantom.iter().filter(|p| !**p).count()
    }
    /// Number of phantom nodes, `m_r` of Table 1.
    pub fn phantoms(&self) -> usize {
        self.phantom.iter().filter(|p| **p).count()
    }
}

/// The progressive octree: levels `0..=R` and the particles in stream order.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Hierarchy {
    pub depth: u8,
    pub levels: Vec<HLevel>,
    /// For each particle in stream order, the index of its leaf in
    /// `levels[R]` (whose nodes are all kept).
    pub particle_leaf: Vec<u32>,
    /// `P^r` is `particle_leaf[level_start[r]..level_start[r + 1]]`.
    pub level_start: Vec<usize>,
}

impl Hierarchy {
    /// Orders a thinned octree. `leaf_source[i]` maps leaf `i` of the result
    /// to its index among the octree's leaves (for attributes).
    pub fn from_thinned(tree: &Octree) -> Result<(Hierarchy, Vec<u32>)> {
        let depth = tree.depth as usize;
        // has_desc[r][i]: the node has a kept leaf below (or is one).
        let mut keep: Vec<Vec<bool>> = vec![Vec::new(); depth + 1];
        keep[depth] = tree.levels[depth]
            .label
            .iter()
            .map(|l| *l == Label::On)
            .collect();
        for r in (0..depth).rev() {
            let mut k = vec![false; tree.levels[r].cells.len()];
            for (i, &c) in tree.levels[r + 1].cells.iter().enumerate() {
                if keep[r + 1][i] {
                    k[tree.levels[r].find(c >> 3).expect("parent is ON")] = true;
                }
            }
            keep[r] = k;
        }
        if !keep[0].first().copied().unwrap_or(false) {
            return Err(Error::Input("thinning left no ON leaf".into()));
        }
        let mut levels = Vec::with_capacity(depth + 1);
        let mut leaf_source = Vec::new();
        for r in 0..=depth {
            let lv = &tree.levels[r];
            let mut h = HLevel::default();
            for (i, &c) in lv.cells.iter().enumerate() {
                if keep[r][i] {
                    h.cells.push(c);
                    // The root is never thinned (§4.3 stops at level 1).
                    h.phantom.push(r > 0 && lv.label[i] != Label::On);
                    if r == depth {
                        leaf_source.push(i as u32);
                    }
                }
            }
            h.particle = vec![NO_PARTICLE; h.cells.len()];
            levels.push(h);
        }
        if levels[depth].cells.is_empty() {
            return Err(Error::Input("thinning left no ON leaf".into()));
        }
        // Thinning never relabels the root, so when it eliminates every cube
        // of level 1 the root is a kept node without a kept child. Promote
        // the first present child back to kept, down the levels until a
        // kept child exists (phantoms always have kept leaves below).
        for r in 0..depth {
            let (upper, lower) = levels.split_at_mut(r + 1);
            let (parents, kids) = (&upper[r], &mut lower[0]);
            let mut j = 0usize;
            for p in 0..parents.cells.len() {
                let start = j;
                while j < kids.cells.len() && kids.cells[j] >> 3 == parents.cells[p] {
                    j += 1;
                }
                if !parents.phantom[p] && (start..j).all(|i| kids.phantom[i]) && start < j {
                    kids.phantom[start] = false;
                }
            }
        }
        // Representative leaf of every kept node, bottom-up (path rule).
        let mut rep: Vec<Vec<u32>> = vec![Vec::new(); depth + 1];
        rep[depth] = (0..levels[depth].cells.len() as u32).collect();
        for r in (0..depth).rev() {
            let mut v = vec![NO_PARTICLE; levels[r].cells.len()];
            let mut p = 0usize;
            for (i, &c) in levels[r + 1].cells.iter().enumerate() {
                while levels[r].cells[p] != c >> 3 {
                    p += 1;
                }
                if !levels[r + 1].phantom[i] && v[p] == NO_PARTICLE {
                    v[p] = rep[r + 1][i];
                }
            }
            for (i, &x) in v.iter().enumerate() {
                if !levels[r].phantom[i] && x == NO_PARTICLE {
                    return Err(Error::Input(format!(
                        "kept node without kept child at level {r}"
                    )));
                }
            }
            rep[r] = v;
        }
        // Particles top-down in stream order.
        let mut particle_leaf = vec![rep[0][0]];
        let mut level_start = vec![0, 1];
        levels[0].particle[0] = 0;
        for r in 1..=depth {
            let (upper, lower) = levels.split_at_mut(r);
            let parents = &upper[r - 1];
            let lv = &mut lower[0];
            let mut p = 0usize;
            let mut first_kept_seen = false;
            for i in 0..lv.cells.len() {
                let c = lv.cells[i];
                if parents.cells[p] != c >> 3 {
                    while parents.cells[p] != c >> 3 {
                        p += 1;
                    }
                    first_kept_seen = false;
                }
                if lv.phantom[i] {
                    continue;
                }
                let inherits = !first_kept_seen && !parents.phantom[p];
                first_kept_seen = true;
                lv.particle[i] = if inherits {
                    parents.particle[p]
                } else {
                    particle_leaf.push(rep[r][i]);
                    (particle_leaf.len() - 1) as u32
                };
            }
            level_start.push(particle_leaf.len());
        }
        Ok((
            Hierarchy {
                depth: tree.depth,
                levels,
                particle_leaf,
                level_start,
            },
            leaf_source,
        ))
    }

    /// Number of particles `n_r` in `P^r`.
    pub fn new_particles(&self, r: usize) -> usize {
        self.level_start[r + 1] - self.level_start[r]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octree::{BuildOptions, unmorton};
    use crate::thinning::{ThinningOptions, thin};

    #[test]
    fn difference_sets_add_up_to_the_leaves_and_follow_the_path_rule() {
        let mesh = lodkit_mesh::shapes::torus(1.0, 0.35, 48, 24);
        let mut t = Octree::from_mesh(
            &mesh,
            &BuildOptions {
                depth: Some(6),
                sidedness: None,
            },
        )
        .unwrap();
        thin(&mut t, &ThinningOptions::DEFAULT);
        let (h, src) = Hierarchy::from_thinned(&t).unwrap();
        assert_eq!(h.particle_leaf.len(), h.levels[6].cells.len());
        assert_eq!(src.len(), h.levels[6].cells.len());
        // k_r = k_{r-1} + n_r when no phantoms sit between (in general
        // k_r counts kept nodes; every kept node has exactly one particle).
        for r in 0..=6usize {
            let kept = h.levels[r].kept();
            let distinct: std::collections::BTreeSet<u32> = h.levels[r]
                .particle
                .iter()
                .copied()
                .filter(|&p| p != NO_PARTICLE)
                .collect();
            assert_eq!(
                distinct.len(),
                kept,
                "one particle per kept node at level {r}"
            );
            // Each kept node's particle leaf lies inside it.
            for (i, &c) in h.levels[r].cells.iter().enumerate() {
                if h.levels[r].phantom[i] {
                    continue;
                }
                let leaf =
                    h.levels[6].cells[h.particle_leaf[h.levels[r].particle[i] as usize] as usize];
                assert_eq!(leaf >> (3 * (6 - r)), c);
            }
        }
        // The root's leaf is the lexicographically first kept path: no kept
        // leaf lies in an earlier child at any level along it.
        let root_leaf = unmorton(h.levels[6].cells[h.particle_leaf[0] as usize]);
        assert!(root_leaf.iter().all(|&v| v < 64));
    }
}
