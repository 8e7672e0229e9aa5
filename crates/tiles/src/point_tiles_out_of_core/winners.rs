//! The winner of each occupied cell of the nodes a choosing pass decides,
//! filled from every thread at once: the in-core rule's winner (the
//! point nearest the cell's centre, ties by the lower input index) is the
//! least `(distance, index)` of the cell, so any split of the points
//! between threads and any order of offers give the same winners as one
//! pass in input order.
//!
//! The map is split into [`SHARDS`] maps by a hash of the key, each behind
//! its own lock, so threads rarely wait on each other; one copy of each
//! winner is held whatever the thread count, so the memory is that of one
//! map.

use std::sync::Mutex;
use std::sync::atomic::{AtomicBool, AtomicU64, Ordering};

use rustc_hash::FxHashMap;

/// Shards of the map: enough that two threads offering a chunk each
/// rarely want the same one at once, few enough that a chunk's offers to
/// one shard are a run of work under its lock.
const SHARDS: usize = 64;

/// A point's claim on one cell: its squared distance to the centre (in
/// cells), its input index, the child octant it would go to and the
/// octant below that (the grandchild's, within the child).
#[derive(Clone, Copy, Debug)]
pub(super) struct Winner {
    pub(super) d: f64,
    pub(super) index: u32,
    pub(super) octant: u8,
    pub(super) next: u8,
}

/// No claim (the second place of a cell one point claimed).
const NONE: Winner = Winner {
    d: f64::INFINITY,
    index: u32::MAX,
    octant: 0,
    next: 0,
};

impl Winner {
    /// Whether `self` wins the cell over `other`.
    fn beats(&self, other: &Winner) -> bool {
        self.d < other.d || (self.d == other.d && self.index < other.index)
    }
}

/// The winners by key (`node << 32 | cell`, the node's place in its
/// group and its cell).
pub(super) struct Winners {
    shards: Vec<Mutex<FxHashMap<u64, Winner>>>,
}

fn shard(key: u64) -> usize {
    (key.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 58) as usize % SHARDS
}

/// `found` grouped by shard (a counting sort: two passes, no compares),
/// with each shard's run.
fn by_shard(found: &[(u64, Winner)]) -> (Vec<(u64, Winner)>, [usize; SHARDS + 1]) {
    let mut start = [0usize; SHARDS + 1];
    for &(k, _) in found {
        start[shard(k) + 1] += 1;
    }
    for s in 0..SHARDS {
        start[s + 1] += start[s];
    }
    let mut at = start;
    let mut out = vec![(0u64, NONE); found.len()];
    for &(k, w) in found {
        let s = shard(k);
        out[at[s]] = (k, w);
        at[s] += 1;
    }
    (out, start)
}

impl Winners {
    pub(super) fn new() -> Winners {
        Winners {
            shards: (0..SHARDS)
                .map(|_| Mutex::new(FxHashMap::default()))
                .collect(),
        }
    }

    /// Offers every claim of `found` (one chunk's, any order): each key
    /// keeps the claim that beats all others. Cost: a counting sort of
    /// the claims by shard, then one lock per shard they touch.
    pub(super) fn offer(&self, found: Vec<(u64, Winner)>) {
        let (found, start) = by_shard(&found);
        for s in 0..SHARDS {
            let run = &found[start[s]..start[s + 1]];
            if run.is_empty() {
                continue;
            }
            let mut map = self.shards[s].lock().unwrap_or_else(|p| p.into_inner());
            for &(key, w) in run {
                map.entry(key)
                    .and_modify(|old| {
                        if w.beats(old) {
                            *old = w;
                        }
                    })
                    .or_insert(w);
            }
        }
    }

    /// Every key and its winner (in no particular order).
    pub(super) fn into_iter(self) -> impl Iterator<Item = (u64, Winner)> {
        self.shards
            .into_iter()
            .flat_map(|m| m.into_inner().unwrap_or_else(|p| p.into_inner()))
    }
}

/// The best two claims of each key, in at most `limit` keys: what
/// decides a node's children in the pass that decides the node (a child's
/// cell lies in one cell of its parent's, which keeps at most one point:
/// the child's winner is the best of its two claims that the parent did
/// not keep). Past `limit` keys it gives up (frees its maps and takes no
/// more claims): the children then get a pass of their own.
pub(super) struct Runners {
    shards: Vec<Mutex<FxHashMap<u64, [Winner; 2]>>>,
    held: AtomicU64,
    limit: u64,
    over: AtomicBool,
}

impl Runners {
    pub(super) fn new(limit: u64) -> Runners {
        Runners {
            shards: (0..SHARDS)
                .map(|_| Mutex::new(FxHashMap::default()))
                .collect(),
            held: AtomicU64::new(0),
            limit,
            over: AtomicBool::new(false),
        }
    }

    /// Offers every claim of `found` (one chunk's, any order): each key
    /// keeps its two best.
    pub(super) fn offer(&self, found: Vec<(u64, Winner)>) {
        if self.over.load(Ordering::Relaxed) {
            return;
        }
        let (found, start) = by_shard(&found);
        for s in 0..SHARDS {
            let run = &found[start[s]..start[s + 1]];
            if run.is_empty() {
                continue;
            }
            let mut map = self.shards[s].lock().unwrap_or_else(|p| p.into_inner());
            let before = map.len();
            for &(key, w) in run {
                let two = map.entry(key).or_insert([NONE; 2]);
                if w.beats(&two[0]) {
                    two[1] = two[0];
                    two[0] = w;
                } else if w.beats(&two[1]) {
                    two[1] = w;
                }
            }
            let added = (map.len() - before) as u64;
            if self.held.fetch_add(added, Ordering::Relaxed) + added > self.limit {
                self.over.store(true, Ordering::Relaxed);
                *map = FxHashMap::default();
                drop(map);
                for m in &self.shards {
                    *m.lock().unwrap_or_else(|p| p.into_inner()) = FxHashMap::default();
                }
                return;
            }
        }
    }

    /// Every key and its best claim that `taken` (the parents' kept
    /// points) does not hold (none: the cell has no other claim), or
    /// `None` when the limit was passed. A key whose two claims both are
    /// `taken` cannot be decided from them: `undecided` hears it.
    pub(super) fn winners(
        self,
        taken: &dyn Fn(u32) -> bool,
        undecided: &mut dyn FnMut(u64),
    ) -> Option<Vec<(u64, Winner)>> {
        if self.over.into_inner() {
            return None;
        }
        let mut out = Vec::new();
        for m in self.shards {
            for (key, [a, b]) in m.into_inner().unwrap_or_else(|p| p.into_inner()) {
                if !taken(a.index) {
                    out.push((key, a));
                } else if b.index == u32::MAX {
                } else if !taken(b.index) {
                    out.push((key, b));
                } else {
                    undecided(key);
                }
            }
        }
        Some(out)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Winners offered in chunks, in any order, are those of one pass in
    /// input order (strictly nearer wins; ties keep the first).
    #[test]
    fn chunks_in_any_order_give_the_sequential_winners() {
        let mut x = 7u64;
        let claims: Vec<(u64, Winner)> = (0..20_000u32)
            .map(|i| {
                x = x
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                // Few distinct distances: many ties.
                let key = ((x >> 60) << 32) | ((x >> 40) % 500);
                let w = Winner {
                    d: ((x >> 20) % 4) as f64,
                    index: i,
                    octant: (x % 8) as u8,
                    next: 0,
                };
                (key, w)
            })
            .collect();
        let mut want: FxHashMap<u64, Winner> = FxHashMap::default();
        for &(k, w) in &claims {
            let e = want.entry(k).or_insert(w);
            if w.d < e.d {
                *e = w;
            }
        }
        let winners = Winners::new();
        let chunks: Vec<_> = claims.chunks(777).collect();
        for c in chunks.iter().rev() {
            winners.offer(c.to_vec());
        }
        let got: FxHashMap<u64, Winner> = winners.into_iter().collect();
        assert_eq!(got.len(), want.len());
        for (k, w) in &want {
            assert_eq!(got[k].index, w.index);
        }
        // The best two: the winner once the first is taken.
        let mut second: FxHashMap<u64, Winner> = FxHashMap::default();
        for &(k, w) in &claims {
            if w.index == want[&k].index {
                continue;
            }
            let e = second.entry(k).or_insert(w);
            if w.d < e.d {
                *e = w;
            }
        }
        let runners = Runners::new(u64::MAX);
        for c in chunks.iter().rev() {
            runners.offer(c.to_vec());
        }
        let taken = |i: u32| want.values().any(|w| w.index == i);
        let got = runners
            .winners(&taken, &mut |_| panic!("no key undecided"))
            .unwrap();
        assert_eq!(got.len(), second.len());
        for (k, w) in got {
            assert_eq!(second[&k].index, w.index);
        }
        // Past its limit it gives up.
        let runners = Runners::new(10);
        runners.offer(claims.clone());
        assert!(runners.winners(&taken, &mut |_| {}).is_none());
    }
}
