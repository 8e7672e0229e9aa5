//! Node priority numbering, the LOD array and the accumulation table
//! (thesis §5.2, §5.4.3, §6.1).
//!
//! Starting from the root, the expandable node ranked highest is expanded
//! next and appended to the LOD array. The thesis ranks by its LOD metric,
//! the area difference between a node's triangles and its children's;
//! here the rank is the node's geometric error times its area
//! (`octree_build::expansion_rank`), which keeps thin parts from being cut
//! off until late. A blocked node lends its rank to the node it waits on
//! (its parent or a balance dependency), so the few expansions that a
//! node with much error needs come with it. A node is expandable only
//! when every same-level neighbour is already *marked* (its parent has been
//! expanded), so neighbouring drawn nodes never differ by two levels or
//! more. The thesis also allows a neighbour that "is none"; here a missing
//! neighbour cube still requires the lowest existing node covering it to be
//! expanded, because a coarse node can draw surface into an octant where it
//! has no child (its corner signs come from the Fig. 5.2 rule), and that
//! surface would meet a finer neighbour two levels down. Nodes that draw
//! nothing but have children (all corners on one side) go first.
//!
//! The thesis scans a sorted list for the first expandable node. Here a
//! binary heap holds the candidates; a candidate found blocked waits on the
//! first unexpanded node it depends on, which enters the heap with the
//! larger of the two ranks, and re-enters the heap when that node is
//! expanded. `O(n log n)` overall. Ties break on the node number, so
//! numbering is deterministic.
//!
//! **Expanding together.** Three interfaces cannot be patched by moving
//! fine vertices onto coarse segments (Fig. 5.6): a face whose fine
//! chains do not join the same crossings as its coarse segments (the
//! coarse level crosses it nowhere while the finer level does — a bump
//! thinner than the coarse cube —, an ambiguous face the children join
//! the other way round, or a closed fine loop on the face), and a coarse
//! edge whose fine crossings are not exactly its own crossing (two fine
//! crossings where the coarse edge has none, or a coarse crossing that
//! fell back to a midpoint). The fine polyline there has nothing, or the
//! wrong point, to be moved onto, and two coarse neighbours would pull a
//! shared fine vertex two ways. The
//! same-level nodes around such a face or edge are expanded in the same LOD
//! step (a union-find class, found by
//! [`crate::crack_patch::expand_together`]), so that interface only ever
//! appears fine on both sides. All other LOD steps expand one node, as in
//! the thesis.
//!
//! The accumulation table `acc[k]` is the triangle count drawn at LOD number
//! `k` (`k` nodes expanded); [`lod_for_triangles`] inverts it.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use lodkit_mesh::topology::UnionFind;

use crate::lattice::KeyMap;
use crate::model::McoModel;

/// Fills `model.lod`, `model.groups`, `model.prio` and `model.acc` from
/// the nodes, metrics and balance dependencies. `together` lists node
/// pairs that must expand in the same LOD step (see the module docs).
pub fn number(model: &mut McoModel, together: &[(u32, u32)], rank: &[f32]) {
    let n = model.nodes.len();
    // Union-find over `together` (each class's root is its smallest
    // member); each class lists its members in order.
    let mut uf = UnionFind::new(n);
    for &(a, b) in together {
        uf.union(a, b);
    }
    let mut members: KeyMap<Vec<u32>> = KeyMap::default();
    for i in 0..n as u32 {
        let r = uf.find(i);
        if r != i {
            members.entry(r as u64).or_insert_with(|| vec![r]).push(i);
        }
    }
    let mut expanded = vec![false; n];
    let mut waiting: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut prio = vec![u32::MAX; n];
    let mut lod = Vec::new();
    let mut groups = vec![0u32];
    let mut heap: BinaryHeap<(u32, Reverse<u32>)> = BinaryHeap::new();
    let key = |m: &McoModel, i: u32| {
        let nd = &m.nodes[i as usize];
        // A node that draws nothing but has a surface below goes first.
        let metric = if crate::octree_build::is_null(nd.config) {
            f32::INFINITY
        } else {
            rank.get(i as usize)
                .copied()
                .unwrap_or(m.metric[i as usize])
                .max(0.0)
        };
        (metric.to_bits(), Reverse(i))
    };
    if n > 0 && model.nodes[0].child_count > 0 {
        heap.push(key(model, 0));
    }
    while let Some((bits, Reverse(i))) = heap.pop() {
        if expanded[i as usize] {
            continue;
        }
        let root = uf.find(i);
        let group: Vec<u32> = members
            .get(&(root as u64))
            .cloned()
            .unwrap_or_else(|| vec![i]);
        // Every member must be in the cut (parent expanded) and have its
        // balance dependencies expanded.
        let blocker = group.iter().find_map(|&x| {
            let nd = model.nodes[x as usize];
            if nd.parent != u32::MAX && !expanded[nd.parent as usize] {
                return Some(nd.parent);
            }
            model.deps[nd.deps_start as usize..][..nd.deps_count as usize]
                .iter()
                .copied()
                .find(|&d| !expanded[d as usize] && !group.contains(&d))
        });
        if let Some(b) = blocker {
            waiting[b as usize].push(i);
            // The blocker inherits the waiting node's metric, so a node
            // with much error pulls the few nodes it waits on in with it
            // rather than waiting for their own small metrics.
            let (own, _) = key(model, b);
            heap.push((own.max(bits), Reverse(b)));
            continue;
        }
        let number = groups.len() as u32;
        for &x in &group {
            expanded[x as usize] = true;
            lod.push(x);
            prio[x as usize] = number;
        }
        groups.push(lod.len() as u32);
        for &x in &group {
            for c in model.children(x) {
                if model.nodes[c as usize].child_count > 0 {
                    heap.push(key(model, c));
                }
            }
            for w in std::mem::take(&mut waiting[x as usize]) {
                heap.push(key(model, w));
            }
        }
    }
    let mut acc = Vec::with_capacity(groups.len());
    let mut t = model.nodes.first().map_or(0, |r| r.tri_count as i64);
    acc.push(t as u32);
    for k in 1..groups.len() {
        for &i in &lod[groups[k - 1] as usize..groups[k] as usize] {
            t -= model.nodes[i as usize].tri_count as i64;
            for c in model.children(i) {
                t += model.nodes[c as usize].tri_count as i64;
            }
        }
        acc.push(t as u32);
    }
    model.lod = lod;
    model.groups = groups;
    model.prio = prio;
    model.acc = acc;
}

/// The LOD number whose triangle count is closest to `target` from the
/// accumulation table. The table is not strictly monotone (an expansion can
/// lower the count), so the search runs over its running maximum: the first
/// `k` whose running maximum reaches `target` is compared with `k − 1`.
/// The result is off by at most one expansion's triangles.
pub fn lod_for_triangles(acc: &[u32], target: usize) -> usize {
    if acc.is_empty() {
        return 0;
    }
    let target = target.min(u32::MAX as usize) as u32;
    // Running maxima are monotone, so binary-search them lazily: `k` is
    // the first index where some acc[..=k] >= target.
    let mut best = 0u32;
    let mut first = None;
    for (k, &a) in acc.iter().enumerate() {
        best = best.max(a);
        if best >= target {
            first = Some(k);
            break;
        }
    }
    let Some(k) = first else {
        return acc.len() - 1;
    };
    if k == 0 {
        return 0;
    }
    let (hi, lo) = (acc[k].abs_diff(target), acc[k - 1].abs_diff(target));
    if lo < hi { k - 1 } else { k }
}
