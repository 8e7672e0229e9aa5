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

use rustc_hash::FxHashMap;

/// Shards of the map: enough that two threads offering a chunk each
/// rarely want the same one at once, few enough that a chunk's offers to
/// one shard are a run of work under its lock.
const SHARDS: usize = 64;

/// A point's claim on one cell: its squared distance to the centre (in
/// cells), its input index, and the child octant it would go to.
#[derive(Clone, Copy, Debug)]
pub(super) struct Winner {
    pub(super) d: f64,
    pub(super) index: u32,
    pub(super) octant: u8,
}

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

impl Winners {
    pub(super) fn new() -> Winners {
        Winners {
            shards: (0..SHARDS)
                .map(|_| Mutex::new(FxHashMap::default()))
                .collect(),
        }
    }

    /// Offers every claim of `found` (one chunk's, any order): each key
    /// keeps the claim that beats all others. Cost: a sort of the claims
    /// by shard, then one lock per shard they touch.
    pub(super) fn offer(&self, mut found: Vec<(u64, Winner)>) {
        found.sort_unstable_by_key(|&(k, _)| shard(k));
        for run in found.chunk_by(|a, b| shard(a.0) == shard(b.0)) {
            let mut map = self.shards[shard(run[0].0)]
                .lock()
                .unwrap_or_else(|p| p.into_inner());
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
                let key = (x >> 60) << 32 | (x >> 40) % 500;
                let w = Winner {
                    d: ((x >> 20) % 4) as f64,
                    index: i,
                    octant: (x % 8) as u8,
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
    }
}
