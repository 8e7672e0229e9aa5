//! Same-level face neighbours of the octree's nodes, found once per level
//! from the sorted node keys (no hashing).
//!
//! Crack patching and the expand-together search ([`crate::crack_patch`])
//! ask, for most nodes, which node sits across each face one level up or
//! on the same level. A hash map lookup per question was a cache miss per
//! question on large models (the maps outgrow the caches), and those two
//! stages were a fifth of the build at a million points.
//!
//! A level's keys ([`crate::lattice::pack`]: `x | y << 20 | z <<
//! 40`) are sorted, so the keys of the `+axis` neighbours, `key + stride`,
//! are sorted too: one merge of the level with itself per axis finds every
//! `+axis` neighbour (and so every `−axis` one) in linear time, reading
//! both sequences front to back.

use crate::lattice::KEY_BITS;
#[cfg(test)]
use crate::lattice::unpack;

/// Marks a face without a neighbour in [`FaceNeighbours`].
pub const NO_NODE: u32 = u32::MAX;

/// Per node of one level: the index of the node across each face,
/// `2 · axis + side` (`side` 1 = towards `+axis`), or [`NO_NODE`].
pub type FaceNeighbours = [u32; 6];

/// The face neighbours of every key of `keys` (sorted, distinct packed
/// cube keys of one level).
pub fn face_neighbours(keys: &[u64]) -> Vec<FaceNeighbours> {
    let mut out = vec![[NO_NODE; 6]; keys.len()];
    let limit = (1u64 << KEY_BITS) - 1;
    for axis in 0..3 {
        let shift = axis as u32 * KEY_BITS;
        let stride = 1u64 << shift;
        let mut j = 0usize;
        for (i, &k) in keys.iter().enumerate() {
            if k >> shift & limit == limit {
                continue; // no lattice cell past the last one
            }
            let t = k + stride;
            while j < keys.len() && keys[j] < t {
                j += 1;
            }
            if j == keys.len() {
                break;
            }
            if keys[j] == t {
                out[i][2 * axis + 1] = j as u32;
                out[j][2 * axis] = i as u32;
            }
        }
    }
    out
}

/// The node of `keys` (sorted) at `cell`, if any, by binary search: for
/// the rare lookups the face tables do not answer.
pub fn find(keys: &[u64], cell: [u32; 3]) -> Option<u32> {
    let k = crate::lattice::pack(cell[0], cell[1], cell[2]);
    keys.binary_search(&k).ok().map(|i| i as u32)
}

/// Coordinates of node `i` of `keys`.
#[inline]
#[cfg(test)]
pub fn cell(keys: &[u64], i: u32) -> [u32; 3] {
    unpack(keys[i as usize])
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::pack;
    use rand_xoshiro::Xoshiro256PlusPlus;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};
    use std::collections::HashMap;

    #[test]
    fn merge_finds_the_same_neighbours_as_a_map() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x2545_f491_4f6c_dd1d);
        let mut next = |m: u64| (rng.next_u64() % m) as u32;
        let mut keys: Vec<u64> = (0..3000)
            .map(|_| pack(next(20), next(20), next(20)))
            .collect();
        // The top cell of the key field has no `+` neighbour.
        keys.push(pack((1 << KEY_BITS) - 1, 3, 3));
        keys.push(pack(0, 3, 4));
        keys.sort_unstable();
        keys.dedup();
        let index: HashMap<u64, u32> = keys
            .iter()
            .enumerate()
            .map(|(i, &k)| (k, i as u32))
            .collect();
        let table = face_neighbours(&keys);
        let mut found = 0;
        for (i, &k) in keys.iter().enumerate() {
            let c = unpack(k);
            assert_eq!(find(&keys, c), Some(i as u32));
            assert_eq!(cell(&keys, i as u32), c);
            for axis in 0..3 {
                for side in 0..2 {
                    let mut n = c;
                    let expect = if side == 1 {
                        n[axis] += 1;
                        if n[axis] >> KEY_BITS != 0 {
                            None
                        } else {
                            index.get(&pack(n[0], n[1], n[2])).copied()
                        }
                    } else if n[axis] == 0 {
                        None
                    } else {
                        n[axis] -= 1;
                        index.get(&pack(n[0], n[1], n[2])).copied()
                    };
                    assert_eq!(table[i][2 * axis + side], expect.unwrap_or(NO_NODE));
                    found += expect.is_some() as usize;
                }
            }
        }
        assert!(found > 1000, "the random keys have neighbours ({found})");
        assert_eq!(find(&keys, [25, 25, 25]), None);
    }
}
