//! Node priority numbering, the LOD array and the accumulation table
//! (thesis §5.2, §5.4.3, §6.1).
//!
//! Starting from the root, the expandable node with the largest LOD metric
//! (the area difference between a node's triangles and its children's) is
//! expanded next and appended to the LOD array. A node is expandable only
//! when every same-level neighbour is already *marked* (its parent has been
//! expanded) or does not exist, so neighbouring drawn nodes never differ by
//! two levels or more.
//!
//! The thesis scans a sorted list for the first expandable node. Here a
//! binary heap holds the candidates; a candidate found blocked waits on the
//! first unexpanded node it depends on and re-enters the heap when that node
//! is expanded. That picks the same node as the scan (the largest-metric
//! expandable one) in `O(n log n)` overall. Ties break on the node number,
//! so numbering is deterministic.
//!
//! The accumulation table `acc[k]` is the triangle count drawn at LOD number
//! `k` (`k` nodes expanded); [`lod_for_triangles`] inverts it.

use std::cmp::Reverse;
use std::collections::BinaryHeap;

use crate::model::McoModel;

/// Fills `model.lod`, `model.prio` and `model.acc` from the nodes,
/// metrics and balance dependencies.
pub fn number(model: &mut McoModel) {
    let n = model.nodes.len();
    let mut expanded = vec![false; n];
    let mut waiting: Vec<Vec<u32>> = vec![Vec::new(); n];
    let mut prio = vec![u32::MAX; n];
    let mut lod = Vec::new();
    let mut heap: BinaryHeap<(u32, Reverse<u32>)> = BinaryHeap::new();
    let key = |m: &McoModel, i: u32| (m.metric[i as usize].max(0.0).to_bits(), Reverse(i));
    if n > 0 && model.nodes[0].child_count > 0 {
        heap.push(key(model, 0));
    }
    while let Some((_, Reverse(i))) = heap.pop() {
        let nd = model.nodes[i as usize];
        let deps =
            &model.deps[nd.deps_start as usize..nd.deps_start as usize + nd.deps_count as usize];
        if let Some(&blocker) = deps.iter().find(|&&d| !expanded[d as usize]) {
            waiting[blocker as usize].push(i);
            continue;
        }
        expanded[i as usize] = true;
        lod.push(i);
        prio[i as usize] = lod.len() as u32;
        for c in model.children(i) {
            if model.nodes[c as usize].child_count > 0 {
                heap.push(key(model, c));
            }
        }
        for w in std::mem::take(&mut waiting[i as usize]) {
            heap.push(key(model, w));
        }
    }
    let mut acc = Vec::with_capacity(lod.len() + 1);
    let mut t = model.nodes.first().map_or(0, |r| r.tri_count as i64);
    acc.push(t as u32);
    for &i in &lod {
        t -= model.nodes[i as usize].tri_count as i64;
        for c in model.children(i) {
            t += model.nodes[c as usize].tri_count as i64;
        }
        acc.push(t as u32);
    }
    model.lod = lod;
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
