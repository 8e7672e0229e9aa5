//! Duplicate face triangles: two solids on both sides of a neighbourhood
//! face may both build the same triangle on it; one copy is kept.
use super::NONE;
use super::settle::sorted_tri;

/// Drops the second of two identical triangles among `candidates` (solid
/// triangles on a face of their neighbourhood); returns the indices
/// dropped, in increasing order.
#[inline]
pub(super) fn dedupe_face_triangles(faces: &mut Vec<[u32; 3]>, candidates: &[u32]) -> Vec<u32> {
    // Candidates come in increasing order (pushed as the faces grow), so
    // the first one seen of each vertex set is the lowest index: keep it,
    // drop later copies. An open-addressed set of candidates, keyed by the
    // sorted vertices, replaces a sort of all candidates; the keys are
    // gathered first, in one forward pass, so that a probe reads this
    // small array instead of a random place of `faces`.
    debug_assert!(candidates.windows(2).all(|w| w[0] < w[1]));
    let mut dropped = Vec::new();
    if candidates.len() > 1 {
        let keys: Vec<[u32; 3]> = candidates
            .iter()
            .map(|&i| sorted_tri(faces[i as usize]))
            .collect();
        let bits = (2 * candidates.len()).next_power_of_two().trailing_zeros();
        let mask = (1usize << bits) - 1;
        let mut slots = vec![NONE; mask + 1];
        for (p, k) in keys.iter().enumerate() {
            let h = (u64::from(k[0]) | (u64::from(k[1]) << 21) | (u64::from(k[2]) << 42))
                .wrapping_mul(0x9e37_79b9_7f4a_7c15);
            let mut at = (h >> (64 - bits)) as usize;
            loop {
                let q = slots[at];
                if q == NONE {
                    slots[at] = p as u32;
                    break;
                }
                if keys[q as usize] == *k {
                    dropped.push(candidates[p]);
                    break;
                }
                at = (at + 1) & mask;
            }
        }
    }
    remove_sorted(faces, &dropped);
    dropped
}

/// Removes the elements at the increasing indices `drop` from `v`: the
/// runs between them move down, those before the first stay put (a
/// `retain` tested every element, a few drops among all the faces).
#[inline]
pub(super) fn remove_sorted<T: Copy>(v: &mut Vec<T>, drop: &[u32]) {
    let Some(&first) = drop.first() else {
        return;
    };
    let mut to = first as usize;
    for (k, &d) in drop.iter().enumerate() {
        let end = drop.get(k + 1).map_or(v.len(), |&n| n as usize);
        v.copy_within(d as usize + 1..end, to);
        to += end - d as usize - 1;
    }
    v.truncate(to);
}
