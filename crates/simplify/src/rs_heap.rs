//! The constant-size replacement-selection min-heap (HQMS §3.5, after
//! Knuth vol. 3 §5.4.1).
//!
//! One array of `capacity` records holds two parts: positions
//! `0..=tcr` are a binary min-heap of *current-run* records; positions
//! after the trailing-current-run pointer (`tcr`) hold *next-run* records,
//! which form heap-ordered subtrees under the same index arithmetic (every
//! child of a position past `tcr` is also past `tcr`). When the current
//! part empties, the pointer jumps back to the end and the whole array is a
//! heap again: a new sorted run starts.
//!
//! The three stages of the paper map onto one operation, [`RsHeap::replace`]
//! (delete the root, insert a record):
//! - *initial*: the heap starts full of null records (key +∞). Replacing a
//!   null root with a valid record sends the record to the next-run part,
//!   so after `capacity` insertions the heap is full of valid records;
//! - *operation*: each insertion is compared with the record just deleted —
//!   smaller goes to the next-run part, otherwise to the root (current run);
//! - *finale*: [`RsHeap::drain`] inserts null records into the next-run
//!   part until every valid record has come out.
//!
//! Departure: the paper moves the TCR record to the root and sifts the new
//! record down; it does not say that the moved record must then be sifted
//! down in the current part too — we do both, or the heap order breaks.
//!
//! Output is sorted within each run; an input in which no record has
//! `capacity` or more larger records before it comes out fully sorted.
//! Every operation is O(log capacity): O(1) for the constant capacity.

/// A heap record: a key and a payload. Records are compared by key only.
/// Valid records have keys below +∞; [`Keyed::NULL`] is the null record
/// (key +∞) that fills empty slots, so a slot costs no more than a record.
pub trait Keyed: Copy {
    const NULL: Self;
    fn key(&self) -> f32;
    #[inline]
    fn is_null(&self) -> bool {
        self.key() == f32::INFINITY
    }
}

/// The replacement-selection heap.
#[derive(Debug, Clone)]
pub struct RsHeap<T: Keyed> {
    slots: Vec<T>,
    /// Index of the last current-run record; `capacity - 1` when the whole
    /// array is one heap.
    tcr: usize,
    /// Key of the most recently deleted valid record (+∞ before any).
    last: f32,
    valid: usize,
}

#[inline]
fn less<T: Keyed>(a: &T, b: &T) -> bool {
    a.key() < b.key()
}

impl<T: Keyed> RsHeap<T> {
    /// A heap of `capacity` records (at least 1), full of null records.
    pub fn new(capacity: usize) -> Self {
        let capacity = capacity.max(1);
        RsHeap {
            slots: vec![T::NULL; capacity],
            tcr: capacity - 1,
            last: f32::INFINITY,
            valid: 0,
        }
    }

    /// Empties the heap and sets its capacity, keeping the allocation
    /// when it is large enough.
    pub fn reset(&mut self, capacity: usize) {
        let capacity = capacity.max(1);
        self.slots.clear();
        self.slots.resize(capacity, T::NULL);
        self.tcr = capacity - 1;
        self.last = f32::INFINITY;
        self.valid = 0;
    }

    pub fn capacity(&self) -> usize {
        self.slots.len()
    }

    /// Whether no valid (non-null) record is held.
    #[cfg(test)]
    pub fn is_empty(&self) -> bool {
        self.valid == 0
    }

    /// Deletes the root and inserts `rec` (`HeapDeleteRoot` followed by
    /// `HeapInsert`). Returns the deleted root; `None` while the initial
    /// stage is still removing null records.
    pub fn replace(&mut self, rec: T) -> Option<T> {
        debug_assert!(rec.key() < f32::INFINITY, "valid keys are finite");
        let out = std::mem::replace(&mut self.slots[0], T::NULL);
        let out = (!out.is_null()).then_some(out);
        if let Some(o) = &out {
            self.last = o.key();
            self.valid -= 1;
        }
        self.valid += 1;
        // A NaN key would break the order: it goes to the next run.
        let k = rec.key();
        if k >= self.last && !k.is_nan() {
            self.slots[0] = rec;
            self.sift_down(0, self.tcr);
        } else {
            self.insert_next_run(rec);
        }
        out
    }

    /// Finale stage: deletes the root and inserts a null record into the
    /// next-run part. Returns `None` once no valid record is left.
    pub fn drain(&mut self) -> Option<T> {
        if self.valid == 0 {
            return None;
        }
        // A null root with valid records left means the current part holds
        // only nulls (the initial stage was cut short): push nulls into the
        // next-run part until the run changes and a valid record rises.
        while self.slots[0].is_null() {
            self.slots[0] = T::NULL;
            self.insert_next_run(T::NULL);
        }
        let out = std::mem::replace(&mut self.slots[0], T::NULL);
        self.last = out.key();
        self.valid -= 1;
        self.insert_next_run(T::NULL);
        Some(out)
    }

    /// The paper's next-run insertion: move the TCR record to the (empty)
    /// root, put the new record where it was, shrink the current part,
    /// restore both parts' heap order.
    fn insert_next_run(&mut self, rec: T) {
        let t = self.tcr;
        if t == 0 {
            // The current part was only the (deleted) root: the new record
            // starts the next run, which now spans the whole array.
            self.slots[0] = rec;
            self.tcr = self.slots.len() - 1;
            self.last = f32::INFINITY;
            self.sift_down(0, self.tcr);
            return;
        }
        self.slots[0] = self.slots[t];
        self.slots[t] = rec;
        self.tcr = t - 1;
        let end = self.slots.len() - 1;
        self.sift_down(t, end);
        self.sift_down(0, self.tcr);
    }

    /// Sifts position `i` down within positions `..=end`: the record is
    /// held aside while smaller children move up into the hole (one copy
    /// per level instead of a swap).
    #[inline]
    fn sift_down(&mut self, mut i: usize, end: usize) {
        let s = &mut self.slots[..=end];
        let rec = s[i];
        loop {
            let l = 2 * i + 1;
            if l > end {
                break;
            }
            let r = l + 1;
            let c = if r <= end && less(&s[r], &s[l]) { r } else { l };
            if less(&s[c], &rec) {
                s[i] = s[c];
                i = c;
            } else {
                break;
            }
        }
        s[i] = rec;
    }

    /// Key of the root (+∞ for a null root).
    #[cfg(test)]
    pub fn peek_key(&self) -> f32 {
        self.slots[0].key()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[derive(Debug, Clone, Copy, PartialEq)]
    struct R(f32, u32);
    impl Keyed for R {
        const NULL: R = R(f32::INFINITY, u32::MAX);
        fn key(&self) -> f32 {
            self.0
        }
    }

    /// Runs the three stages over `input` and returns what came out.
    fn run(input: &[f32], cap: usize) -> Vec<R> {
        let mut h = RsHeap::new(cap);
        let mut out = Vec::new();
        for (i, &k) in input.iter().enumerate() {
            if let Some(r) = h.replace(R(k, i as u32)) {
                out.push(r);
            }
        }
        while let Some(r) = h.drain() {
            out.push(r);
        }
        assert!(h.is_empty());
        out
    }

    /// Maximal non-decreasing runs of the output.
    fn runs(out: &[R]) -> usize {
        1 + out.windows(2).filter(|w| w[1].0 < w[0].0).count()
    }

    proptest! {
        #[test]
        fn output_is_a_permutation_of_the_input(
            input in proptest::collection::vec(-1000.0f32..1000.0, 0..600),
            cap in 1usize..40,
        ) {
            let out = run(&input, cap);
            let mut ids: Vec<u32> = out.iter().map(|r| r.1).collect();
            ids.sort_unstable();
            prop_assert_eq!(ids, (0..input.len() as u32).collect::<Vec<_>>());
        }

        #[test]
        fn input_no_larger_than_the_heap_comes_out_sorted(
            input in proptest::collection::vec(-1000.0f32..1000.0, 0..64),
        ) {
            let out: Vec<f32> = run(&input, 64).iter().map(|r| r.0).collect();
            let mut sorted = input.clone();
            sorted.sort_by(f32::total_cmp);
            prop_assert_eq!(out, sorted);
        }

        #[test]
        fn nearly_sorted_input_comes_out_sorted(
            mut input in proptest::collection::vec(0.0f32..1.0e6, 0..500),
            blocks in proptest::collection::vec(any::<bool>(), 0..63),
        ) {
            // Sorted, then some disjoint 8-record blocks reversed: no record
            // has 8 or more larger records before it, so a 16-record heap
            // sorts it in one run.
            input.sort_by(f32::total_cmp);
            for (b, rev) in blocks.iter().enumerate() {
                let lo = b * 8;
                if *rev && lo < input.len() {
                    let hi = (lo + 8).min(input.len());
                    input[lo..hi].reverse();
                }
            }
            let out: Vec<f32> = run(&input, 16).iter().map(|r| r.0).collect();
            let mut sorted = input.clone();
            sorted.sort_by(f32::total_cmp);
            prop_assert_eq!(out, sorted);
        }

        #[test]
        fn runs_are_sorted_and_match_a_sort_of_each_run(
            input in proptest::collection::vec(-1000.0f32..1000.0, 1..800),
            cap in 1usize..32,
        ) {
            let out = run(&input, cap);
            // Within each maximal run the keys are sorted by construction;
            // what must hold is that there are no more runs than a
            // replacement selection can produce: at most one per `cap`
            // input records (each run holds at least `cap` records, except
            // the last two).
            let r = runs(&out);
            prop_assert!(r <= input.len() / cap + 2, "{} runs for {} records", r, input.len());
            // And the multiset of keys matches the sorted input.
            let mut a: Vec<f32> = out.iter().map(|r| r.0).collect();
            let mut b = input.clone();
            a.sort_by(f32::total_cmp);
            b.sort_by(f32::total_cmp);
            prop_assert_eq!(a, b);
        }
    }

    #[test]
    fn random_input_runs_average_about_twice_the_heap() {
        // Knuth: replacement selection makes runs of ~2× the heap size on
        // uniform random input. Seeded, so the test is deterministic.
        use rand_xoshiro::SplitMix64;
        use rand_xoshiro::rand_core::{Rng, SeedableRng};
        let mut rng = SplitMix64::seed_from_u64(12345);
        let input: Vec<f32> = (0..200_000)
            .map(|_| (rng.next_u64() >> 40) as f32)
            .collect();
        let out = run(&input, 512);
        let mean = input.len() as f64 / runs(&out) as f64;
        assert!((900.0..1150.0).contains(&mean), "mean run {mean}");
    }

    #[test]
    fn reset_keeps_working() {
        let mut h = RsHeap::new(4);
        h.replace(R(3.0, 0));
        h.reset(8);
        assert!(h.is_empty());
        assert_eq!(h.capacity(), 8);
        assert_eq!(h.peek_key(), f32::INFINITY);
    }
}
