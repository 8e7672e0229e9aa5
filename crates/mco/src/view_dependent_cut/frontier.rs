//! The search of a kept [`ViewCut`] while the camera sees the whole
//! model: the searched part of the tree is kept from the last cut, and
//! only the ranks whose last test may have changed are tested again,
//! instead of a walk from the root.
//!
//! With every frustum plane containing the root's grown cube, every cube
//! of the tree is in view (the grown cube holds them all, see the module
//! docs of `view_dependent_cut`), so a rank is wanted exactly when its own
//! error projects above the tolerance, and what a test says depends on the
//! eye's position alone. The kept state is the *searched tree*: the root,
//! and the inner children of every searched rank whose subtree bound may
//! project (it *passes*); a searched rank that does not pass holds no
//! wanted rank below it. Each searched rank carries an *expiry*: how far
//! the eye may travel, from where its test was made, before either of its
//! answers (passes, wanted) may change — the least of the two margins,
//! each the distance's excess over the reach or the reach's over the
//! distance less their rounding, as for `ViewCut::slack` (the distance to
//! a box moves no faster than the eye). Distances travelled are summed
//! along the eye's path (`path`), which is never less than how far the
//! eye is from any earlier position, so a rank whose expiry the path has
//! not passed gives the answers of its last test.
//!
//! A cut then adds the eye's step to the path and tests again the ranks
//! the path has passed, found in buckets by expiry (so finding them costs
//! their number, not the tree's); where a rank's pass changes, its
//! children join the searched tree (tested at once, and so on down) or
//! its searched subtree leaves it. Each change of a wanted flag goes to
//! the closure as a change (`closure`), so a cut costs what the step
//! changed, not what the cut holds. The wanted set is a fresh search's:
//! every rank outside the searched tree lies below a rank whose subtree
//! holds no wanted rank, and every searched rank's flag is its test's at
//! the current eye or one its expiry vouches for.

use super::*;

/// Buckets of the expiry queue ([`Frontier::ring`]), and their width in
/// root cube sizes: the ring spans 16 root sizes of path; a viewer's
/// step between frames (a few hundredths of the model's size to a few
/// tenths) takes a few to a few hundred buckets.
const RING: usize = 4096;
const WIDTH_ROOTS: f32 = 1.0 / 256.0;

/// The path (object units) past which expiries are re-based to 0, in
/// root cube sizes: keeps an `f32` expiry within 2⁻¹⁸ of the root's size
/// of the path it was computed from.
const REBASE_ROOTS: f32 = 64.0;

/// The kept searched tree of [`ViewCut::search_frontier`] (see the
/// module docs).
#[derive(Debug, Clone, Default)]
pub(super) struct Frontier {
    /// Layout id (0: no state), reach and minimum distance bits of the
    /// cut it was made for: the answers depend on these and the eye.
    key: (u64, u32, u32),
    /// Per rank: its expiry as a path length (never above the true one),
    /// or infinity for a rank not searched.
    expiry: Vec<f32>,
    /// Per rank: searched and passes (its inner children are searched).
    pass: Vec<u64>,
    /// The eye's path since the state was made or last re-based.
    path: f64,
    /// The eye of the last cut.
    eye: Vec3,
    /// Wanted ranks (the set bits of `ViewCut::want`).
    wanted: usize,
    /// The expiry queue. An entry is a rank and, above it, the bits of
    /// the expiry it was queued with; it is stale once the rank's expiry
    /// differs (tested again, or removed). Bucket `k` holds the expiries
    /// in `[k, k + 1) · width`; `ring[k % RING]` holds bucket `k` for
    /// `next ≤ k < next + RING`, `far` those beyond, and `soon` those
    /// below `next` (buckets already taken) not yet passed.
    ring: Vec<Vec<u64>>,
    far: Vec<u64>,
    soon: Vec<u64>,
    width: f64,
    /// `1 / width`, and the path rounded down to an `f32`.
    per_width: f32,
    path_lo: f32,
    /// The first bucket not taken: every bucket below starts before the
    /// path.
    next: u32,
    /// The bucket at which `far` is next sorted out.
    far_check: u32,
    /// Ranks to add to the searched tree, and to remove from it.
    add: Vec<u32>,
    drop: Vec<u32>,
    /// Per rank: its expiry is passed (to test again, in rank order).
    due: Vec<u64>,
    /// An empty list, its allocation kept.
    scratch: Vec<u64>,
}

/// Rank `r`'s test at `fr`'s eye on a camera that sees the whole model:
/// whether its subtree may hold a wanted rank (the search's bound test),
/// whether it is wanted, and how far the eye may travel before either may
/// change (not positive: it may change at any step). The same booleans as
/// the search's tests of `compact_cut`, with no plane left to test.
#[inline(always)]
fn test(lay: &ViewLayout, fr: &Frustum, eye_size: f32, r: u32) -> (bool, bool, f32) {
    let h = &lay.hot[r as usize];
    let (lo, hi) = lay.cube(h);
    let (glo, ghi) = lay.grown(h, lo, hi);
    // The coordinates' magnitude for the rounding allowances, from the
    // growth (2⁻¹⁸ of the cube's magnitude, see `Hot::grow`): at least
    // that of the grown cube, and so of the cube.
    let size = h.grow * (262_144.0 + 16.0) + eye_size;
    let (d, reach) = fr.distance_and_reach(glo, ghi, h.bound);
    // False on a NaN, as in the search.
    let may_project = reach > d;
    if !may_project {
        return (false, false, excess(d, reach, size));
    }
    let passes = excess(reach, d, size);
    let wanted = fr.projects(lo, hi, h.err);
    let (d, reach) = fr.distance_and_reach(lo, hi, h.err);
    let own = if wanted {
        projecting_margin(d, reach, size)
    } else {
        // `reach ≤ d` rules `projects` out (see `distance_and_reach`).
        excess(d, reach, size)
    };
    (true, wanted, passes.min(own))
}

/// `x` rounded to an `f32` not above it.
#[inline(always)]
fn down(x: f64) -> f32 {
    let f = x as f32;
    if f as f64 > x { f.next_down() } else { f }
}

/// What a frontier update tests against and writes to: the cut's
/// layout and frustum, the wanted set, and the closure's changes
/// (recorded only when `record`).
struct Update<'a> {
    lay: &'a ViewLayout,
    fr: &'a Frustum,
    eye_size: f32,
    want: &'a mut [u64],
    work: &'a mut Vec<u64>,
    record: bool,
}

impl Frontier {
    /// Queues rank `r` with expiry `e`, one bucket early (against the
    /// rounding of the bucket's number).
    #[inline(always)]
    fn queue(&mut self, r: u32, e: f32) {
        let entry = r as u64 | (e.to_bits() as u64) << 32;
        // Saturates (a negative `e`, re-based past, gives 0).
        let k = ((e * self.per_width) as u32).saturating_sub(1);
        if k < self.next || e < 0.0 {
            self.soon.push(entry);
        } else if k < self.next + RING as u32 {
            self.ring[k as usize % RING].push(entry);
        } else {
            self.far.push(entry);
        }
    }

    /// Marks due the live entries of `list` the path passed (`passed`:
    /// the path rounded up to an `f32`), queues the other live ones
    /// again, and drops the stale ones; `list` is left empty.
    fn sort_out(&mut self, list: &mut Vec<u64>, passed: f32) {
        for entry in list.drain(..) {
            let (r, bits) = (entry as u32, (entry >> 32) as u32);
            if self.expiry[r as usize].to_bits() != bits {
                continue;
            }
            let e = f32::from_bits(bits);
            if e < passed {
                self.due[(r >> 6) as usize] |= 1 << (r & 63);
            } else {
                self.queue(r, e);
            }
        }
    }

    /// Tests again every searched rank whose expiry the path passed (and
    /// a few more: an expiry under the path rounded up to an `f32`, and
    /// the buckets' rounding), in rank order: a parent before its
    /// children (a rank its ancestor removed is not tested), and the
    /// layout's records read forward.
    fn retest_due(&mut self, u: &mut Update) {
        let passed = {
            let p = self.path as f32;
            if p as f64 >= self.path {
                p
            } else {
                p.next_up()
            }
        };
        let mut list = std::mem::take(&mut self.scratch);
        std::mem::swap(&mut list, &mut self.soon);
        self.sort_out(&mut list, passed);
        // Every bucket that starts before the path; past a whole ring,
        // every ring bucket once, and `far` at once.
        let end = (self.path / self.width).ceil() as u32;
        let mut far_now = false;
        if end > self.next + RING as u32 {
            self.next = end - RING as u32;
            far_now = true;
        }
        while self.next < end {
            std::mem::swap(&mut list, &mut self.ring[self.next as usize % RING]);
            self.next += 1;
            self.sort_out(&mut list, passed);
        }
        if far_now || self.next >= self.far_check {
            std::mem::swap(&mut list, &mut self.far);
            self.sort_out(&mut list, passed);
            self.far_check = self.next + RING as u32 / 2;
        }
        self.scratch = list;
        for w in 0..self.due.len() {
            let mut x = std::mem::take(&mut self.due[w]);
            while x != 0 {
                let r = (w as u32) << 6 | x.trailing_zeros();
                x &= x - 1;
                // Removed with an ancestor tested before it.
                if self.expiry[r as usize] != f32::INFINITY && self.visit(u, r) {
                    self.settle(u);
                }
            }
        }
    }

    /// Drops the state: the next [`ViewCut::search_frontier`] searches
    /// anew.
    pub(super) fn forget(&mut self) {
        self.key.0 = 0;
    }

    /// Whether the last cut kept a searched tree (for tests).
    #[cfg(test)]
    pub(crate) fn kept(&self) -> bool {
        self.key.0 != 0
    }

    /// Tests rank `r` (searched, or being added) at the current eye and
    /// records its answers: the wanted flag in `u.want` (a change also
    /// onto `u.work` when recorded), its expiry, and where its pass
    /// changes, its children onto `add` or `drop` (then returns true:
    /// [`Frontier::settle`] is due).
    #[inline(always)]
    fn visit(&mut self, u: &mut Update, r: u32) -> bool {
        let (passes, wanted, margin) = test(u.lay, u.fr, u.eye_size, r);
        // Rounded below the sum: a product with `1 - 2⁻²³` falls at
        // least one unit in the last place below the rounded sum.
        let e = (self.path_lo + margin.max(0.0)) * (1.0 - f32::EPSILON);
        self.expiry[r as usize] = e;
        self.queue(r, e);
        let (w, bit) = ((r >> 6) as usize, 1u64 << (r & 63));
        if (u.want[w] & bit != 0) != wanted {
            u.want[w] ^= bit;
            if wanted {
                self.wanted += 1;
            } else {
                self.wanted -= 1;
            }
            if u.record {
                u.work.push(r as u64 | (wanted as u64) << 32);
            }
        }
        if (self.pass[w] & bit != 0) != passes {
            self.pass[w] ^= bit;
            let h = &u.lay.hot[r as usize];
            let children = h.inner_children();
            if passes {
                self.add.extend(children);
            } else {
                self.drop.extend(children);
            }
            return true;
        }
        false
    }

    /// Adds the ranks on `add` and below (as far as they pass) to the
    /// searched tree, and removes those on `drop` and their searched
    /// subtrees, recording wanted flags as [`Frontier::visit`].
    #[inline(never)]
    fn settle(&mut self, u: &mut Update) {
        while let Some(r) = self.drop.pop() {
            self.expiry[r as usize] = f32::INFINITY;
            let (w, bit) = ((r >> 6) as usize, 1u64 << (r & 63));
            if u.want[w] & bit != 0 {
                u.want[w] ^= bit;
                self.wanted -= 1;
                if u.record {
                    u.work.push(r as u64);
                }
            }
            if self.pass[w] & bit != 0 {
                self.pass[w] ^= bit;
                let h = &u.lay.hot[r as usize];
                self.drop.extend(h.inner_children());
            }
        }
        // A rank added is not searched: neither wanted nor passing, so
        // its visit only adds (onto `add`, taken by this loop).
        while let Some(r) = self.add.pop() {
            self.visit(u, r);
        }
    }
}

impl ViewCut {
    /// Whether [`ViewCut::search_frontier`] applies to this cut on `lay`:
    /// every subtree bound is finite and every frustum plane contains the
    /// root's grown cube (so every node is in view; false on a NaN eye).
    pub(super) fn frontier_applies(lay: &ViewLayout, fr: &Frustum) -> bool {
        if !lay.finite || lay.ranks() == 0 || !fr.eye.is_finite() {
            return false;
        }
        let root = &lay.hot[0];
        let (lo, hi) = lay.cube(root);
        let (glo, ghi) = lay.grown(root, lo, hi);
        (0..5).all(|k| fr.contains(k, glo, ghi))
    }

    /// The wanted ranks for `fr` (where [`ViewCut::frontier_applies`]),
    /// from the searched tree kept from the last cut when it was made for
    /// the same layout, reach and minimum distance and the closure's state
    /// is `kept` (else searched anew): `want` is left as the wanted set,
    /// `work` with its changes for `apply_closure_work`. Returns how many
    /// ranks are wanted.
    #[inline(never)]
    pub(super) fn search_frontier(&mut self, lay: &ViewLayout, fr: &Frustum, kept: bool) -> usize {
        let ranks = lay.ranks();
        let key = (lay.id, fr.reach.to_bits(), fr.min_d.to_bits());
        let eye = fr.eye;
        let eye_size = eye.abs().max_element();
        let root_size = lay.sizes[lay.hot[0].level as usize];
        let f = &mut self.front;
        self.work.clear();
        if !kept || f.key != key || f.expiry.len() != ranks {
            // A new searched tree from the root, into `new_want`; the
            // closure gets its difference from the last wanted set.
            f.key = key;
            f.expiry.clear();
            f.expiry.resize(ranks, f32::INFINITY);
            f.pass.clear();
            f.pass.resize(ranks.div_ceil(64), 0);
            f.due.clear();
            f.due.resize(ranks.div_ceil(64), 0);
            f.ring.resize_with(RING, Vec::new);
            f.width = (root_size * WIDTH_ROOTS) as f64;
            f.per_width = (1.0 / f.width) as f32;
            f.restart_path();
            f.eye = eye;
            f.wanted = 0;
            f.drop.clear();
            f.add.clear();
            f.add.push(0);
            let now = &mut self.new_want;
            now.clear();
            now.resize(self.want.len(), 0);
            f.settle(&mut Update {
                lay,
                fr,
                eye_size,
                want: now,
                work: &mut self.work,
                record: false,
            });
            self.want_changes();
            return self.front.wanted;
        }
        // The eye's step onto the path; any step, however small, moves
        // the path on, so a test made at the last eye is not trusted at
        // another.
        if eye != f.eye {
            let step = (eye.as_dvec3() - f.eye.as_dvec3()).length();
            f.path = (f.path + step).max(f.path.next_up());
            f.eye = eye;
        }
        if f.path > (REBASE_ROOTS * root_size) as f64 {
            // Expiries from 0 again, and the queue made anew from them.
            let base = f.path;
            f.restart_path();
            for r in 0..ranks {
                let e = f.expiry[r];
                if e.is_finite() {
                    let e = down(e as f64 - base);
                    f.expiry[r] = e;
                    f.queue(r as u32, e);
                }
            }
        }
        f.path_lo = down(f.path);
        f.retest_due(&mut Update {
            lay,
            fr,
            eye_size,
            want: &mut self.want,
            work: &mut self.work,
            record: true,
        });
        f.wanted
    }
}

impl Frontier {
    /// The path at 0 and the queue empty.
    fn restart_path(&mut self) {
        self.path = 0.0;
        self.path_lo = 0.0;
        self.ring.iter_mut().for_each(Vec::clear);
        self.far.clear();
        self.soon.clear();
        self.next = 0;
        self.far_check = RING as u32 / 2;
    }
}
