//! Octree surface thinning — §4.3 of Yemez & Schmitt.
//!
//! Levels are processed from `R` up to 1. At each level every ON cube is
//! tested in lexicographic (Morton) order, sequentially, and the pass is
//! repeated until nothing changes:
//!
//! * **inner thinning** (always): a cube with no OUT face neighbour is
//!   occluded and relabelled IN;
//! * **outer thinning** (optional, only at levels `r ≥ relax_below`, a
//!   level chosen per object by default — [`choose_relax_level`]): a
//!   cube with no IN face neighbour is relabelled OUT, unless the
//!   3×3×3 test says its removal would join two OUT regions that are
//!   separate (six-connected, inside the 26-neighbourhood) — the
//!   artificial hole of Fig. 4.
//!
//! After each elimination the ancestors are relabelled: a parent left with
//! no ON child is eliminated too (the dotted crosses of Fig. 3). Departure:
//! the paper relabels such a parent IN; when outer thinning emptied it (all
//! its children OUT) we relabel it OUT, which is what the flood fill would
//! have said and keeps the next level's occlusion test honest.
//!
//! Eliminated nodes that still have ON descendants are the phantom nodes of
//! §4.3/§7.1; see [`crate::ordering`].
//!
//! **Invariant.** The passes reach the fixed point §4.3 asks for: at an
//! outer-thinned level no kept cube lacks an IN face neighbour (none is
//! held by the topology test) and no 2×2×2 block holds six or more cubes
//! (`lodkit-bench`'s `pop_probe` with `POP_PROBE_THIN=1` checks a model).
//! Every kept cube then separates IN from OUT along a face, which a
//! stricter rule could not remove without making IN and OUT
//! face-adjacent; the four-cube tetrahedra (`C_6`) are the staircases of a
//! curved, noisy surface at this resolution, not cubes left behind, and
//! the triangulation's settling handles the non-manifold triangles they
//! cause ([`crate::triangulate`](mod@crate::triangulate)).
use crate::octree::{FACES, Label, Octree, offset, unmorton};

/// Options of [`thin`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ThinningOptions {
    /// Also thin the outer boundary (with the hole-preventing topology test).
    pub outer: bool,
    /// Outer thinning is relaxed (not applied) below this level — the
    /// paper relaxed it at `r = 4` for its objects; [`Self::AUTO_RELAX`]
    /// chooses it per object.
    pub relax_below: u8,
}

impl ThinningOptions {
    /// Inner thinning only; outer thinning, when asked for, relaxed below a
    /// level chosen per object ([`choose_relax_level`]). Outer thinning
    /// makes smaller streams with fewer particles, but it loses features
    /// thinner than a cube at coarse levels, so it stays an option. The
    /// relax level is object-dependent (§8.2) and decides the coarse
    /// levels' non-manifold triangles; the chosen one keeps every level
    /// under 1 % on the shipped models (a test pins it), which inner
    /// thinning alone does not.
    pub const DEFAULT: ThinningOptions = ThinningOptions {
        outer: false,
        relax_below: ThinningOptions::AUTO_RELAX,
    };

    /// `relax_below` value asking [`choose_relax_level`] to pick the level
    /// for the object (a level of 0 or 1 would both mean "never relaxed":
    /// level 0 is the root, never thinned, so 0 is free for this).
    pub const AUTO_RELAX: u8 = 0;
}

impl Default for ThinningOptions {
    fn default() -> Self {
        ThinningOptions::DEFAULT
    }
}

/// Counts of eliminated cubes per level (Table 1's "eliminated nodes"):
/// cubes relabelled by their own occlusion test, plus parents relabelled
/// because they lost every ON child.
#[cfg_attr(not(any(test, feature = "internals")), allow(dead_code))] // tests, bench drivers
pub fn thin(tree: &mut Octree, opts: &ThinningOptions) -> Vec<usize> {
    thin_choosing(tree, opts).0
}

/// [`thin`], also returning the relax level used: `opts.relax_below`, or
/// with [`ThinningOptions::AUTO_RELAX`] (and outer thinning on) the level
/// [`choose_relax_level`] documents.
pub fn thin_choosing(tree: &mut Octree, opts: &ThinningOptions) -> (Vec<usize>, u8) {
    let depth = tree.depth as usize;
    let mut st = Thinning::new(tree);
    if !(opts.outer && opts.relax_below == ThinningOptions::AUTO_RELAX) {
        st.levels(tree, opts, 1..=depth);
        return (st.eliminated, opts.relax_below);
    }
    let top = usize::from(MAX_AUTO_RELAX).min(depth);
    let outer = |relax_below: u8| ThinningOptions {
        outer: true,
        relax_below,
    };
    // Levels `top..=R` are thinned alike for every candidate.
    st.levels(tree, &outer(1), top.max(1)..=depth);
    if top <= 1 {
        return (st.eliminated, 1);
    }
    let labels: Vec<Vec<Label>> = (0..top).map(|r| tree.levels[r].label.clone()).collect();
    let saved = st.clone();
    // Back to the shared state, then the coarse levels relaxed below `l`.
    let thin_coarse = |tree: &mut Octree, st: &mut Thinning, l: u8| {
        for (r, lab) in labels.iter().enumerate() {
            tree.levels[r].label.clone_from(lab);
        }
        st.clone_from(&saved);
        st.levels(tree, &outer(l), 1..=top - 1);
    };
    let mut best: Option<(f64, u8)> = None;
    let mut surfaced: Vec<bool> = Vec::new();
    for l in (1..=top as u8).rev() {
        thin_coarse(tree, &mut st, l);
        let (share, triangles) = coarse_non_manifold_share(tree, top - 1);
        // The least thinned candidate (the first) says which levels have
        // a surface; one that thinning emptied (a torus's tube thinner
        // than a level-3 cube, a model's coarsest levels thinned away) has
        // no non-manifold triangle left to count against it.
        if surfaced.is_empty() {
            surfaced = triangles.iter().map(|&n| n > 0).collect();
        }
        if triangles
            .iter()
            .zip(&surfaced)
            .any(|(&n, &had)| had && n == 0)
        {
            continue;
        }
        if best.is_none_or(|(b, _)| share < b) {
            best = Some((share, l));
        }
    }
    let l = best.map_or(1, |(_, l)| l);
    thin_coarse(tree, &mut st, l);
    (st.eliminated, l)
}

/// Highest relax level [`choose_relax_level`] tries.
pub const MAX_AUTO_RELAX: u8 = 6;

/// The level below which outer thinning is relaxed, chosen for this object
/// as §8.2 says it must be ("depends mainly on the object complexity and
/// has been determined experimentally"): lodkit runs that experiment.
/// Levels from [`MAX_AUTO_RELAX`] (or `R`) up are thinned the same way
/// for every candidate, so they are thinned once; then each candidate
/// `L = MAX..1` thins the coarser levels. A candidate that empties a level
/// `L = MAX` leaves a surface on (outer thinning eroding a part thinner
/// than a cube) is out; the others' surfaces are triangulated (vertices at the leaf particles' means, as
/// the baseline codes them) and scored by their worst share of
/// non-manifold triangles (edges used more than twice). The lowest score
/// wins; a tie goes to the higher `L`, which thins less and keeps more of
/// the coarse shapes.
#[cfg(test)]
pub fn choose_relax_level(tree: &Octree) -> u8 {
    let mut t = tree.clone();
    thin_choosing(
        &mut t,
        &ThinningOptions {
            outer: true,
            relax_below: ThinningOptions::AUTO_RELAX,
        },
    )
    .1
}

/// Worst share of non-manifold triangles over levels `1..=last` of a
/// thinned octree, vertices at each particle's leaf mean, and each
/// level's triangle count.
fn coarse_non_manifold_share(tree: &Octree, last: usize) -> (f64, Vec<usize>) {
    use crate::level_surface::LevelSurface;
    use crate::stats::non_manifold_triangles;
    use crate::triangulate::{TriangulateOptions, triangulate};
    let Ok((h, leaf_source)) = crate::ordering::Hierarchy::from_thinned(tree) else {
        return (f64::INFINITY, Vec::new());
    };
    let bits = crate::octree::QBITS;
    let mut worst = 0.0f64;
    let mut triangles = Vec::with_capacity(last);
    for r in 1..=last {
        let lv = &h.levels[r];
        let mut cells = Vec::with_capacity(lv.cells.len());
        let mut positions = Vec::with_capacity(lv.cells.len());
        for (i, &c) in lv.cells.iter().enumerate() {
            if lv.phantom[i] {
                continue;
            }
            let leaf = h.particle_leaf[lv.particle[i] as usize] as usize;
            let q = tree.leaves.q[leaf_source[leaf] as usize];
            cells.push(c);
            positions.push(tree.frame.cell_centre(q, bits));
        }
        let s = LevelSurface {
            level: r as u8,
            frame: tree.frame,
            cells,
            positions,
            colours: None,
            normals: None,
        };
        let t = triangulate(&s, &TriangulateOptions::DEFAULT);
        let n = t.mesh.faces.len();
        if n > 0 {
            worst = worst.max(non_manifold_triangles(&t.mesh) as f64 / n as f64);
        }
        triangles.push(n);
    }
    (worst, triangles)
}

/// The state sequential thinning carries from level to level.
#[derive(Debug, Clone)]
struct Thinning {
    /// ON children left under every node of levels `0..R-1`.
    on_children: Vec<Vec<u8>>,
    /// Nodes eliminated per level.
    eliminated: Vec<usize>,
}

impl Thinning {
    fn new(tree: &Octree) -> Thinning {
        let depth = tree.depth as usize;
        let mut on_children: Vec<Vec<u8>> = (0..depth)
            .map(|r| vec![0u8; tree.levels[r].cells.len()])
            .collect();
        for r in 1..=depth {
            for &c in &tree.levels[r].cells {
                let p = tree.levels[r - 1].find(c >> 3).expect("parent is ON");
                on_children[r - 1][p] += 1;
            }
        }
        Thinning {
            on_children,
            eliminated: vec![0usize; depth + 1],
        }
    }

    /// Thins `levels`, finest first.
    fn levels(
        &mut self,
        tree: &mut Octree,
        opts: &ThinningOptions,
        levels: std::ops::RangeInclusive<usize>,
    ) {
        for r in levels.rev() {
            let n = tree.levels[r].cells.len();
            loop {
                let mut changed = false;
                for i in 0..n {
                    if tree.levels[r].label[i] != Label::On {
                        continue;
                    }
                    let c = unmorton(tree.levels[r].cells[i]);
                    let (mut outs, mut ins) = (0, 0);
                    for d in FACES {
                        match tree.neighbour_label(r as u8, c, d) {
                            Label::Out => outs += 1,
                            Label::In => ins += 1,
                            Label::On => {}
                        }
                    }
                    let new = if outs == 0 {
                        Label::In
                    } else if opts.outer
                        && r >= opts.relax_below as usize
                        && ins == 0
                        && !would_open_hole(tree, r as u8, c)
                    {
                        Label::Out
                    } else {
                        continue;
                    };
                    tree.levels[r].label[i] = new;
                    self.eliminated[r] += 1;
                    changed = true;
                    relabel_ancestors(tree, &mut self.on_children, &mut self.eliminated, r, i);
                }
                if !changed {
                    break;
                }
            }
        }
    }
}

/// A parent whose last ON child went is eliminated too, up to level 1.
fn relabel_ancestors(
    tree: &mut Octree,
    on_children: &mut [Vec<u8>],
    eliminated: &mut [usize],
    mut r: usize,
    mut i: usize,
) {
    while r > 1 {
        let c = tree.levels[r].cells[i];
        let p = tree.levels[r - 1].find(c >> 3).expect("parent is ON");
        on_children[r - 1][p] -= 1;
        if on_children[r - 1][p] > 0 || tree.levels[r - 1].label[p] != Label::On {
            return;
        }
        let first = (c >> 3) << 3;
        let any_in = (0..8).any(|k| {
            tree.levels[r]
                .find(first | k)
                .is_some_and(|j| tree.levels[r].label[j] == Label::In)
        });
        tree.levels[r - 1].label[p] = if any_in { Label::In } else { Label::Out };
        eliminated[r - 1] += 1;
        r -= 1;
        i = p;
    }
}

/// The topology test of §4.3 (Fig. 4): label the six-connected OUT regions
/// of the 26-neighbourhood (centre excluded); removing the centre makes it
/// OUT and joins every region touching one of its faces, so it opens a
/// hole when its OUT face neighbours lie in two or more regions.
pub fn would_open_hole(tree: &Octree, r: u8, c: [u32; 3]) -> bool {
    let side = 1u32 << r;
    let idx = |x: usize, y: usize, z: usize| x + 3 * y + 9 * z;
    let mut out = [false; 27];
    for z in 0..3 {
        for y in 0..3 {
            for x in 0..3 {
                if (x, y, z) == (1, 1, 1) {
                    continue;
                }
                let d = [x as i32 - 1, y as i32 - 1, z as i32 - 1];
                out[idx(x, y, z)] = match offset(c, d, side) {
                    Some(n) => tree.label(r, n) == Label::Out,
                    None => true,
                };
            }
        }
    }
    let mut region = [u8::MAX; 27];
    let mut next = 0u8;
    let mut stack = Vec::with_capacity(27);
    for s in 0..27 {
        if !out[s] || region[s] != u8::MAX {
            continue;
        }
        region[s] = next;
        stack.push(s);
        while let Some(k) = stack.pop() {
            let (x, y, z) = (k % 3, (k / 3) % 3, k / 9);
            for d in FACES {
                let (nx, ny, nz) = (x as i32 + d[0], y as i32 + d[1], z as i32 + d[2]);
                if !(0..3).contains(&nx) || !(0..3).contains(&ny) || !(0..3).contains(&nz) {
                    continue;
                }
                let nk = idx(nx as usize, ny as usize, nz as usize);
                if out[nk] && region[nk] == u8::MAX {
                    region[nk] = next;
                    stack.push(nk);
                }
            }
        }
        next += 1;
    }
    let mut first = None;
    for d in FACES {
        let k = idx(
            (d[0] + 1) as usize,
            (d[1] + 1) as usize,
            (d[2] + 1) as usize,
        );
        if out[k] {
            match first {
                None => first = Some(region[k]),
                Some(f) if f != region[k] => return true,
                _ => {}
            }
        }
    }
    false
}

#[cfg(test)]
fn m(c: [u32; 3]) -> u64 {
    crate::octree::morton(c)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::octree::{BuildOptions, Octree};

    fn sphere_tree(depth: u8) -> Octree {
        let mesh = lodkit_mesh::shapes::icosphere(4);
        Octree::from_mesh(
            &mesh,
            &BuildOptions {
                depth: Some(depth),
                sidedness: None,
            },
        )
        .unwrap()
    }

    #[test]
    fn inner_thinning_leaves_every_kept_cube_facing_outside() {
        let mut t = sphere_tree(6);
        let before = t.levels[6].cells.len();
        let elim = thin(&mut t, &ThinningOptions::DEFAULT);
        assert!(
            elim[6] > 0,
            "a sampled sphere shell is more than one cube thick"
        );
        let kept: Vec<usize> = (0..before)
            .filter(|&i| t.levels[6].label[i] == Label::On)
            .collect();
        assert!(kept.len() < before);
        for &i in &kept {
            let c = unmorton(t.levels[6].cells[i]);
            assert!(
                FACES
                    .iter()
                    .any(|&d| t.neighbour_label(6, c, d) == Label::Out)
            );
        }
        // Ancestors of kept leaves keep a kept child or are eliminated.
        for r in 1..6usize {
            for (p, &pc) in t.levels[r].cells.iter().enumerate() {
                if t.levels[r].label[p] != Label::On {
                    continue;
                }
                let has = (0..8).any(|k| {
                    t.levels[r + 1]
                        .find((pc << 3) | k)
                        .is_some_and(|j| t.levels[r + 1].label[j] == Label::On)
                });
                assert!(has, "kept node without kept child at level {r}");
            }
        }
    }

    #[test]
    fn the_automatic_relax_level_is_the_best_candidate_and_thins_as_that_level() {
        let torus = lodkit_mesh::shapes::torus(1.0, 0.35, 96, 48);
        let tree = Octree::from_mesh(
            &torus,
            &BuildOptions {
                depth: Some(7),
                sidedness: None,
            },
        )
        .unwrap();
        let mut auto = tree.clone();
        let auto_opts = ThinningOptions {
            outer: true,
            relax_below: ThinningOptions::AUTO_RELAX,
        };
        let (elim, l) = thin_choosing(&mut auto, &auto_opts);
        assert!((1..=MAX_AUTO_RELAX).contains(&l));
        assert_eq!(choose_relax_level(&tree), l);
        let score = |l: u8| {
            let mut t = tree.clone();
            let e = thin(
                &mut t,
                &ThinningOptions {
                    outer: true,
                    relax_below: l,
                },
            );
            (coarse_non_manifold_share(&t, 5), e, t)
        };
        let ((best, _), fixed_elim, fixed) = score(l);
        // Same labels and counts as thinning with that level from scratch.
        assert_eq!(fixed_elim, elim);
        for r in 0..=7 {
            assert_eq!(fixed.levels[r].label, auto.levels[r].label, "level {r}");
        }
        let surfaced = score(MAX_AUTO_RELAX).0.1;
        let mut eroding = 0;
        for other in 1..=MAX_AUTO_RELAX {
            let (s, triangles) = score(other).0;
            if triangles
                .iter()
                .zip(&surfaced)
                .any(|(&n, &had)| had > 0 && n == 0)
            {
                // Outer thinning from here erodes the tube (thinner than a
                // level-3 cube) away: ruled out whatever its score.
                eroding += 1;
                continue;
            }
            assert!(
                best < s || (best == s && l >= other),
                "level {other} scores {s}, the chosen {l} {best}"
            );
        }
        assert!(eroding > 0, "the torus's tube is eroded at low levels");
        // Inner thinning alone ignores the automatic level.
        let mut inner = tree.clone();
        let (_, l) = thin_choosing(
            &mut inner,
            &ThinningOptions {
                outer: false,
                ..auto_opts
            },
        );
        assert_eq!(l, ThinningOptions::AUTO_RELAX);
    }

    #[test]
    fn topology_test_refuses_to_cut_a_one_cube_wall() {
        // A plane of points splits the cube into two OUT half-spaces; every
        // wall cube has no IN neighbour, yet removing one would join them.
        let mut pts = Vec::new();
        for y in 0..=64 {
            for z in 0..=64 {
                pts.push(glam::Vec3::new(0.5, y as f32 / 64.0, z as f32 / 64.0));
            }
        }
        let pc = lodkit_mesh::PointCloud {
            positions: pts,
            ..Default::default()
        };
        let opts = BuildOptions {
            depth: Some(3),
            sidedness: Some(crate::octree::Sidedness::FloodFill),
        };
        let mut t = Octree::from_points(&pc, &opts).unwrap();
        assert_eq!(t.levels[3].cells.len(), 64);
        assert!(would_open_hole(&t, 3, [4, 4, 4]));
        // At the wall's rim the two sides meet around it (outside the grid
        // is OUT), so the local test lets that cube go: sequential outer
        // thinning erodes open sheets from their border, as in the paper.
        assert!(!would_open_hole(&t, 3, [4, 0, 0]));
        let elim = thin(
            &mut t,
            &ThinningOptions {
                outer: false,
                relax_below: 1,
            },
        );
        assert_eq!(elim[3], 0, "inner thinning keeps cubes that face OUT");
        assert_eq!(m([4, 4, 4]) >> 3, m([2, 2, 2]));
    }

    #[test]
    fn outer_thinning_stops_only_where_the_topology_test_says_so() {
        // The fixed point of §4.3: at a strictly thinned level no kept cube
        // is removable, i.e. each faces OUT and faces IN or would open a
        // hole; and below the relax level outer thinning left cubes alone.
        let torus = lodkit_mesh::shapes::torus(1.0, 0.3, 96, 48);
        let mut t = Octree::from_mesh(
            &torus,
            &BuildOptions {
                depth: Some(7),
                sidedness: None,
            },
        )
        .unwrap();
        let opts = ThinningOptions {
            outer: true,
            relax_below: 5,
        };
        let before: Vec<usize> = t.levels.iter().map(|l| l.cells.len()).collect();
        let elim = thin(&mut t, &opts);
        let mut blocked = 0;
        for r in 1..=7u8 {
            let lv = &t.levels[r as usize];
            let mut kept = 0;
            for i in 0..lv.cells.len() {
                if lv.label[i] != Label::On {
                    continue;
                }
                kept += 1;
                let c = unmorton(lv.cells[i]);
                let faces = FACES.map(|d| t.neighbour_label(r, c, d));
                assert!(faces.contains(&Label::Out), "r={r}: occluded cube kept");
                if r >= opts.relax_below && !faces.contains(&Label::In) {
                    assert!(would_open_hole(&t, r, c), "r={r}: removable cube kept");
                    blocked += 1;
                }
            }
            assert_eq!(kept + elim[r as usize], before[r as usize], "r={r}");
            if r >= opts.relax_below {
                // Thinned: about one cube thick, as in Table 1 (k_r about
                // the eliminated count or more).
                assert!(elim[r as usize] * 10 >= before[r as usize] * 3, "r={r}");
            }
        }
        // A smooth torus well inside the resolution needs no hole guard.
        assert!(
            blocked * 100 <= before[7],
            "{blocked} cubes kept by the test"
        );
    }
}
