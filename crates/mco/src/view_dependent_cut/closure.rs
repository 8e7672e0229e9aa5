//! The closure of a kept [`ViewCut`], updated from the last cut's instead
//! of made anew: only around the ranks whose wanted state changed.
//!
//! On a layout whose closure is layered ([`ViewLayout::incremental`]),
//! call a *unit* a LOD group (its ranks expand together) or a rank in no
//! group. A unit is expanded exactly when its *support* is positive: the
//! number of its ranks that are wanted, plus, for every expanded rank,
//! how many of its links (parent, balance dependencies) fall in the unit.
//! Links go to strictly coarser ranks and a unit is one level, so the
//! supports are well founded (a unit's depends only on finer units'), and
//! the expanded set they define is the least set that holds the wanted
//! ranks and is closed under links and groups: the closure
//! [`ViewCut::close`] makes from scratch.
//!
//! A cut applies the changes of the wanted set as `±1` to their units'
//! supports; a unit whose support crosses zero sets or clears its ranks'
//! bits and passes `±1` on to their links' units. The worklist may apply
//! a unit's changes in any order (a support can dip below zero on the
//! way): each crossing of zero changes the bits with the support's sign
//! and passes on exactly the links' share, so once the list is empty
//! every support counts again what it defines, and the bits are the
//! closure. The work is proportional to the units that change state and
//! their links, not to the expanded set.

use super::*;

impl ViewCut {
    /// Makes the incremental closure's state fit `lay`: kept when it is
    /// this layout's (returns true), else reset to nothing wanted and
    /// nothing expanded (false).
    pub(super) fn closure_state(&mut self, model: &McoModel, lay: &ViewLayout) -> bool {
        let ranks = lay.ranks();
        let words = ranks.div_ceil(64);
        if self.inc_layout == lay.id && self.want.len() == words {
            return true;
        }
        for v in [&mut self.bits, &mut self.want] {
            v.clear();
            v.resize(words, 0);
        }
        self.support.clear();
        self.support.resize(ranks, 0);
        self.gsupport.clear();
        self.gsupport.resize(model.groups.len(), 0);
        self.inc_count = 0;
        self.inc_layout = lay.id;
        false
    }

    /// The closure of the wanted ranks in `queue`, from the last cut's
    /// state where it is kept for this layout (else from nothing); the bits
    /// are left in `bits`, and the expanded count is returned.
    #[inline(never)]
    pub(super) fn close_incremental(&mut self, model: &McoModel, lay: &ViewLayout) -> usize {
        self.closure_state(model, lay);
        let now = &mut self.new_want;
        now.clear();
        now.resize(self.want.len(), 0);
        for &r in &self.queue {
            now[(r >> 6) as usize] |= 1 << (r & 63);
        }
        self.work.clear();
        self.want_changes();
        self.apply_closure_work(model, lay)
    }

    /// Onto `work`, the changes from `want` to `new_want` (see
    /// `apply_closure_work`); `new_want` becomes `want`.
    pub(super) fn want_changes(&mut self) {
        let work = &mut self.work;
        for (w, (&n, &o)) in self.new_want.iter().zip(&self.want).enumerate() {
            let mut x = n ^ o;
            while x != 0 {
                let j = x.trailing_zeros();
                x &= x - 1;
                work.push(((w as u64) << 6 | j as u64) | (n >> j & 1) << 32);
            }
        }
        std::mem::swap(&mut self.want, &mut self.new_want);
    }

    /// Applies the wanted set's changes in `work` (a rank, and above it 1
    /// for a unit of support gained, 0 for one lost) to the closure kept
    /// for `lay` (`closure_state`); returns the expanded count.
    #[inline(never)]
    pub(super) fn apply_closure_work(&mut self, model: &McoModel, lay: &ViewLayout) -> usize {
        let work = &mut self.work;
        let bits = &mut self.bits;
        let mut count = self.inc_count as isize;
        let g = &model.groups;
        while let Some(e) = work.pop() {
            let r = e as u32;
            let gain = e >> 32 != 0;
            let k = lay.close[r as usize].prio;
            let s = if k == u32::MAX {
                &mut self.support[r as usize]
            } else {
                &mut self.gsupport[k as usize]
            };
            let before = *s > 0;
            *s += if gain { 1 } else { -1 };
            if (*s > 0) == before {
                continue;
            }
            let one = [r];
            let members: &[u32] = if k == u32::MAX {
                &one
            } else {
                &lay.lod[g[k as usize - 1] as usize..g[k as usize] as usize]
            };
            for &m in members {
                bits[(m >> 6) as usize] ^= 1 << (m & 63);
                count += if gain { 1 } else { -1 };
                let c = lay.close[m as usize];
                let links = &lay.links[c.links_start as usize..][..c.links_count as usize];
                work.extend(links.iter().map(|&x| x as u64 | (gain as u64) << 32));
            }
        }
        self.inc_count = count as usize;
        self.inc_count
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pipeline::{Options, build_from_mesh};
    use lodkit_mesh::shapes;

    /// The closure a kept state updates, along a sequence of wanted sets
    /// that change by a few ranks, by many, and by all (from and to
    /// nothing), equals the closure made from scratch at every step.
    #[test]
    fn the_incremental_closure_equals_the_closure_from_scratch() {
        let m = build_from_mesh(
            &shapes::blob(20_000),
            &Options {
                resolution: Some(40),
            },
        )
        .unwrap();
        let ViewData::Layout(lay) = m.view_data() else {
            panic!("a built model gets the layout");
        };
        assert!(lay.incremental, "a built model's closure is layered");
        assert!(m.groups.len() > 1);
        let ranks = lay.ranks() as u32;
        let mut kept = ViewCut::new();
        let mut wanted: Vec<bool> = vec![false; ranks as usize];
        let mut seed = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            seed
        };
        for step in 0..200 {
            let flips = match step % 10 {
                0 => ranks as u64,
                1 | 2 => 200,
                _ => 1 + next() % 12,
            };
            for _ in 0..flips {
                let r = (next() % ranks as u64) as usize;
                wanted[r] = !wanted[r];
            }
            if step % 50 == 49 {
                wanted.iter_mut().for_each(|w| *w = false);
            }
            let list: Vec<u32> = (0..ranks).filter(|&r| wanted[r as usize]).collect();
            kept.queue.clear();
            kept.queue.extend_from_slice(&list);
            let count = kept.close_incremental(&m, lay);
            let mut fresh = ViewCut::new();
            fresh.bits.resize(lay.ranks().div_ceil(64), 0);
            fresh.group_seen.resize(m.groups.len(), false);
            fresh.queue.extend_from_slice(&list);
            assert_eq!(count, fresh.close(&m, lay), "step {step}: count");
            assert_eq!(kept.bits, fresh.bits, "step {step}: expanded ranks");
        }
    }
}
