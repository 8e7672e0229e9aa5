//! The view cut on a model's [`ViewLayout`], in its three stages: the
//! search for the wanted inner nodes, their closure, and the emission of
//! the drawn children's triangles. The same expanded set and the same
//! triangles in the same order as [`ViewCut::cut_nodes`] (tests and the
//! `mco_view_cut` bench check it), on ranks.

use super::*;

/// All five planes of a [`Frustum`] still to test.
const ALL_PLANES: u32 = 0b1_1111;
/// Flags of a search stack entry, above its rank and planes: the rank's
/// certificate was read when it was pushed and said nothing (`CHECKED`),
/// or said it is wanted (`CERTIFIED`; no plane left to test).
const CHECKED: u64 = 1 << 37;
const CERTIFIED: u64 = 1 << 38;

/// What rank `r`'s certificate in `slack` (see `ViewCut::slack`) says at
/// `eye`, with `planes` still to test: `Some(false)`, its subtree holds
/// no wanted node; `Some(true)`, it is wanted; `None`, nothing (none, one
/// the eye has moved out of, or a wanted one while a plane is left).
#[inline(always)]
fn certificate(slack: &[[f32; 4]], eye: Vec3, r: u32, planes: u32) -> Option<bool> {
    let s = slack.get(r as usize)?;
    let m = s[3];
    // False on a NaN eye, and on no certificate (0).
    if (eye - Vec3::new(s[0], s[1], s[2])).length() < m.abs() {
        if m > 0.0 {
            return Some(false);
        }
        if planes == 0 {
            return Some(true);
        }
    }
    None
}

impl ViewCut {
    /// [`ViewCut::cut_into`] on a model's [`ViewLayout`].
    pub(super) fn cut_layout(
        &mut self,
        model: &McoModel,
        lay: &ViewLayout,
        camera: &Camera,
        tolerance_px: f32,
        out: &mut Vec<u32>,
    ) -> usize {
        // A kept state on a layered layout updates its last closure (see
        // `closure`); a one-shot cut, or any other layout, closes anew.
        let incremental = lay.incremental && !self.one_shot;
        if !incremental {
            let ranks = lay.ranks();
            self.bits.clear();
            self.bits.resize(ranks.div_ceil(64), 0);
            clear_listed(&mut self.group_seen, &self.groups, model.groups.len());
            self.groups.clear();
            self.inc_layout = 0;
        }
        self.queue.clear();
        let fr = Frustum::new(model, camera, tolerance_px);
        let count = if incremental && Self::frontier_applies(lay, &fr) {
            // A camera that sees the whole model: the searched tree kept
            // from the last cut, updated where the step changed it (see
            // `frontier`), and its changes into the closure.
            let kept = self.closure_state(model, lay);
            self.last_wanted = self.search_frontier(lay, &fr, kept);
            self.apply_closure_work(model, lay)
        } else {
            // The closure's wanted set now changes without the searched
            // tree: it is searched anew when next used.
            self.front.forget();
            self.last_wanted = self.search(model, lay, &fr);
            if incremental {
                self.close_incremental(model, lay)
            } else {
                self.close(model, lay)
            }
        };
        self.emit(model, lay, out);
        count
    }

    /// Every wanted rank onto `queue` (in no particular order: the closure
    /// makes the same set from any); returns how many.
    ///
    /// The walk tests a node's subtree bound before its own error: the
    /// bound covers the node itself (it is at least the node's error, on a
    /// cube that contains the node's), so a subtree whose bound does not
    /// show holds no wanted node, this one included, and one test rejects
    /// it. Each stack entry carries the frustum planes still to test
    /// (bits of `ALL_PLANES`, above the rank): a plane that contains a
    /// subtree's grown cube with [`Frustum::contains`]'s margin is met by
    /// every cube below it, so its test is left out there. The answers are
    /// those of [`Frustum::shows`] on every node.
    #[inline(never)]
    fn search(&mut self, model: &McoModel, lay: &ViewLayout, fr: &Frustum) -> usize {
        let ranks = lay.ranks();
        if ranks == 0 {
            return 0;
        }
        let wanted = &mut self.queue;
        let stack = &mut self.search;
        stack.clear();
        let meets = |lo: Vec3, hi: Vec3, planes: u32| {
            planes == 0 || (0..5).all(|k| planes >> k & 1 == 0 || fr.meets(k, lo, hi))
        };
        let shows = |lo: Vec3, hi: Vec3, e: f32, planes: u32| {
            fr.projects(lo, hi, e) && meets(lo, hi, planes)
        };
        // Planes that contain a subtree of `h`, given those still tested.
        let inner_planes = |h: &Hot, lo: Vec3, hi: Vec3, planes: u32| {
            if h.bound == f32::INFINITY {
                // Children that may lie outside the cube (see the module
                // docs): their ancestors' planes do not apply to them.
                return ALL_PLANES;
            }
            let mut left = planes;
            for k in 0..5 {
                if planes >> k & 1 != 0 && fr.contains(k, lo, hi) {
                    left &= !(1 << k);
                }
            }
            left
        };
        if self.last_wanted.saturating_mul(SCAN_SHARE) > model.nodes.len() {
            // A large cut: a scan of every rank in order costs less than
            // the search's jumps, and finds the same set. Every cube lies
            // in the root's, so the planes that contain the root's grown
            // cube are left out.
            let root = &lay.hot[0];
            let (lo, hi) = lay.cube(root);
            let (glo, ghi) = lay.grown(root, lo, hi);
            let planes = inner_planes(root, glo, ghi, ALL_PLANES);
            for (r, h) in lay.hot.iter().enumerate() {
                let (lo, hi) = lay.cube(h);
                if shows(lo, hi, h.err, planes) {
                    wanted.push(r as u32);
                }
            }
            return wanted.len();
        }
        // Subtrees the last cuts found far enough from their eye to hold
        // no wanted node (see `ViewCut::slack`) are skipped while the eye
        // stays within their margin of it. A one-shot cut keeps none.
        let key = (lay.id, fr.reach.to_bits(), fr.min_d.to_bits());
        if self.one_shot {
            self.slack.clear();
        } else if self.slack_key != key || self.slack.len() != ranks {
            self.slack.clear();
            self.slack.resize(ranks, [0.0; 4]);
            self.slack_key = key;
        }
        let slack = &mut self.slack;
        let eye = fr.eye;
        let eye_size = eye.abs().max_element();
        // A parent reads its children's certificates as it pushes them
        // (ranks consecutive, so their entries are too): a rejected
        // subtree is not pushed, and a pushed child carries what its
        // certificate said.
        let push_children = |stack: &mut Vec<u64>, slack: &[[f32; 4]], h: &Hot, planes: u32| {
            for c in h.inner_children() {
                match certificate(slack, eye, c, planes) {
                    Some(false) => {}
                    Some(true) => stack.push(CERTIFIED | c as u64),
                    None => stack.push(CHECKED | (planes as u64) << 32 | c as u64),
                }
            }
        };
        stack.push((ALL_PLANES as u64) << 32);
        while let Some(entry) = stack.pop() {
            let (r, planes) = (entry as u32, (entry >> 32) as u32 & ALL_PLANES);
            let certified = entry & CERTIFIED != 0
                || (entry & CHECKED == 0
                    && match certificate(slack, eye, r, planes) {
                        Some(false) => continue,
                        Some(w) => w,
                        None => false,
                    });
            if certified {
                // Still projects above the tolerance, and in view (no
                // plane left to test): wanted, and its subtree searched
                // (its bound is at least its error, on a cube around its
                // own), with no plane to test below (its bound is finite:
                // see the certificate).
                wanted.push(r);
                push_children(stack, slack, &lay.hot[r as usize], 0);
                continue;
            }
            let h = &lay.hot[r as usize];
            let (lo, hi) = lay.cube(h);
            let (glo, ghi) = lay.grown(h, lo, hi);
            if h.bound != f32::INFINITY {
                let (d, reach) = fr.distance_and_reach(glo, ghi, h.bound);
                // False on a NaN, as `projects` is.
                let may_project = reach > d;
                if !may_project {
                    if let Some(s) = slack.get_mut(r as usize) {
                        let size = glo.abs().max(ghi.abs()).max_element() + eye_size;
                        let spare = excess(d, reach, size);
                        // A spare under the rounding margin certifies
                        // nothing; recorded as negative, it would read as
                        // the certificate of a wanted node.
                        *s = if spare > 0.0 {
                            [eye.x, eye.y, eye.z, spare]
                        } else {
                            [0.0; 4]
                        };
                    }
                    continue;
                }
                if !meets(glo, ghi, planes) {
                    continue;
                }
            }
            if shows(lo, hi, h.err, planes) {
                wanted.push(r);
                if h.bound != f32::INFINITY
                    && let Some(s) = slack.get_mut(r as usize)
                {
                    // The certificate that the node keeps projecting
                    // above the tolerance.
                    let (d, reach) = fr.distance_and_reach(lo, hi, h.err);
                    let size = lo.abs().max(hi.abs()).max_element() + eye_size;
                    let margin = projecting_margin(d, reach, size);
                    *s = if margin > 0.0 {
                        [eye.x, eye.y, eye.z, -margin]
                    } else {
                        [0.0; 4]
                    };
                }
            }
            if h.inner_mask != 0 {
                push_children(stack, slack, h, inner_planes(h, glo, ghi, planes));
            }
        }
        wanted.len()
    }

    /// The closure of the wanted ranks in `queue` (parents, balance
    /// dependencies, groups), as bits; returns the expanded count. A rank
    /// already set is not pushed again, so each expanded rank is popped
    /// once from the wanted list or once per node that adds it first.
    #[inline(never)]
    pub(super) fn close(&mut self, model: &McoModel, lay: &ViewLayout) -> usize {
        let bits = &mut self.bits;
        let stack = &mut self.queue;
        let mut count = 0usize;
        while let Some(r) = stack.pop() {
            let (w, b) = ((r >> 6) as usize, 1u64 << (r & 63));
            if bits[w] & b != 0 {
                continue;
            }
            bits[w] |= b;
            count += 1;
            let c = lay.close[r as usize];
            for &x in &lay.links[c.links_start as usize..][..c.links_count as usize] {
                if !bit(bits, x) {
                    stack.push(x);
                }
            }
            let k = c.prio;
            if k != u32::MAX && !std::mem::replace(&mut self.group_seen[k as usize], true) {
                self.groups.push(k);
                let g = &model.groups;
                for &x in &lay.lod[g[k as usize - 1] as usize..g[k as usize] as usize] {
                    if !bit(bits, x) {
                        stack.push(x);
                    }
                }
            }
        }
        count
    }
}

impl ViewCut {
    /// The emission, in rank order (= node order): each expanded node's
    /// children that are not expanded ([`emit_node`]).
    ///
    /// Frame to frame, most nodes draw what they drew: a node's triangles
    /// depend only on which of the ranks it watches
    /// ([`ViewLayout::watchers`]) are expanded. So where the last cut was
    /// on the same layout, the ranks whose bit changed mark their watchers
    /// dirty, and every node expanded in both cuts and not dirty copies
    /// its triangles from the last cut's buffer, consecutive such nodes in
    /// one copy; the others are emitted anew. The buffer is the same
    /// either way, and the same as a fresh cut's.
    #[inline(never)]
    fn emit(&mut self, model: &McoModel, lay: &ViewLayout, out: &mut Vec<u32>) {
        let bits = &self.bits;
        if lay.ranks() == 0 || !bit(bits, 0) {
            emit_patched(model, lay, bits, 0, out);
            self.prev_layout = 0;
            return;
        }
        let words = bits.len();
        let reuse = self.prev_layout == lay.id && self.prev_bits.len() == words;
        let dirty = &mut self.dirty;
        dirty.clear();
        dirty.resize(words, 0);
        if reuse {
            for (w, (&now, &then)) in bits.iter().zip(&self.prev_bits).enumerate() {
                let mut x = now ^ then;
                while x != 0 {
                    let q = w << 6 | x.trailing_zeros() as usize;
                    x &= x - 1;
                    let range = lay.watch_off[q] as usize..lay.watch_off[q + 1] as usize;
                    for &r in &lay.watchers[range] {
                        dirty[(r >> 6) as usize] |= 1 << (r & 63);
                    }
                }
            }
        }
        self.seg.resize(lay.ranks(), [0, 0]);
        let tris = lay.tris(model);
        let prev = &self.prev;
        // The pending range of `prev` to copy, `a..b`.
        let (mut a, mut b) = (0u32, 0u32);
        for (w, &word) in bits.iter().enumerate() {
            let mut x = word;
            let kept = if reuse {
                self.prev_bits[w] & !dirty[w]
            } else {
                0
            };
            while x != 0 {
                let j = x.trailing_zeros();
                x &= x - 1;
                let r = (w as u32) << 6 | j;
                if kept >> j & 1 != 0 {
                    let [s, l] = self.seg[r as usize];
                    if s != b {
                        out.extend_from_slice(&prev[a as usize..b as usize]);
                        a = s;
                    }
                    b = s + l;
                    self.seg[r as usize] = [(out.len() + (s - a) as usize) as u32, l];
                } else {
                    out.extend_from_slice(&prev[a as usize..b as usize]);
                    a = b;
                    let start = out.len();
                    emit_node(model, lay, tris, bits, r, out);
                    self.seg[r as usize] = [start as u32, (out.len() - start) as u32];
                }
            }
        }
        out.extend_from_slice(&prev[a as usize..b as usize]);
        if self.one_shot {
            self.prev_layout = 0;
            return;
        }
        // The caller makes `prev` this cut's buffer (`ViewCut::update`
        // by a swap, `ViewCut::update_into` by a copy).
        self.prev_layout = lay.id;
        self.prev_bits.clear();
        self.prev_bits.extend_from_slice(bits);
    }
}

/// Rank `r`'s (expanded) children that are not expanded, in order: runs
/// without an active crack patch copied as one triangle range. Only the
/// children that break a run (an expanded one, or one with crack patches,
/// which breaks it only while a patch is active) are visited, found from
/// bit masks.
#[inline(always)]
fn emit_node(
    model: &McoModel,
    lay: &ViewLayout,
    tris: &[u32],
    bits: &[u64],
    r: u32,
    out: &mut Vec<u32>,
) {
    let toff = &lay.toff;
    let copy = |out: &mut Vec<u32>, a: u32, b: u32| {
        if a < b {
            out.extend_from_slice(&tris[a as usize..b as usize]);
        }
    };
    let h = &lay.hot[r as usize];
    let fc = lay.close[r as usize].first_child;
    // Bit `j`: child `fc + j` is expanded (the inner children's ranks are
    // `first_inner..`, in child order).
    let mut expanded = 0u32;
    let mut inner = h.inner_mask as u32;
    let mut e = bit_run(bits, h.first_inner, inner.count_ones());
    while inner != 0 {
        expanded |= (e & 1) << inner.trailing_zeros();
        e >>= 1;
        inner &= inner - 1;
    }
    let mut breaks = expanded | h.patch_mask as u32;
    let mut run = toff[fc as usize];
    while breaks != 0 {
        let j = breaks.trailing_zeros();
        breaks &= breaks - 1;
        let c = (fc + j) as usize;
        if expanded >> j & 1 != 0 {
            copy(out, run, toff[c]);
            run = toff[c + 1];
            continue;
        }
        let ps = &lay.patches[lay.poff[c] as usize..lay.poff[c + 1] as usize];
        let Some(first) = ps.iter().position(|p| patch_applies(bits, p)) else {
            continue;
        };
        // The run and the child's own triangles are one range; the
        // child's end of it is then patched in place.
        let own = (toff[c + 1] - toff[c]) as usize;
        copy(out, run, toff[c + 1]);
        let at = out.len() - own;
        apply_patches(model, lay, bits, c, &ps[first..], &mut out[at..]);
        run = toff[c + 1];
    }
    copy(out, run, toff[(fc + h.child_count as u32) as usize]);
}

/// The `k <= 8` bits of `bits` from bit `r` on, as the low bits.
#[inline(always)]
fn bit_run(bits: &[u64], r: u32, k: u32) -> u32 {
    if k == 0 {
        return 0;
    }
    let (w, off) = ((r >> 6) as usize, r & 63);
    let mut v = bits[w] >> off;
    if off + k > 64 {
        v |= bits[w + 1] << (64 - off);
    }
    (v & ((1u64 << k) - 1)) as u32
}

/// Whether a crack patch applies: its coarse neighbour is not expanded.
#[inline(always)]
fn patch_applies(bits: &[u64], p: &[u32; 3]) -> bool {
    p[0] == u32::MAX || !bit(bits, p[0])
}

/// Appends node `c`'s triangles, crack-patched against every coarse
/// neighbour not expanded: [`McoModel::emit`] on the layout.
fn emit_patched(model: &McoModel, lay: &ViewLayout, bits: &[u64], c: u32, out: &mut Vec<u32>) {
    let c = c as usize;
    let start = out.len();
    out.extend_from_slice(&lay.tris(model)[lay.toff[c] as usize..lay.toff[c + 1] as usize]);
    let ps = &lay.patches[lay.poff[c] as usize..lay.poff[c + 1] as usize];
    apply_patches(model, lay, bits, c, ps, &mut out[start..]);
}

/// Applies those of `ps` (node `c`'s patches, or a tail of them) that
/// apply, in order, to `own` (a copy of `c`'s triangles): each from its
/// prepared writes, or, for a node whose patches interact, by the scan of
/// its substitutions (as [`McoModel::emit`]).
#[inline(always)]
fn apply_patches(
    model: &McoModel,
    lay: &ViewLayout,
    bits: &[u64],
    c: usize,
    ps: &[[u32; 3]],
    own: &mut [u32],
) {
    let scan = lay.scan[c >> 6] >> (c & 63) & 1 != 0;
    for p in ps {
        if !patch_applies(bits, p) {
            continue;
        }
        if scan {
            let subs = &model.subs[p[1] as usize..][..p[2] as usize];
            for idx in own.iter_mut() {
                for s in subs {
                    if *idx == s[0] {
                        *idx = s[1];
                    }
                }
            }
        } else {
            for e in &lay.edits[p[1] as usize..][..p[2] as usize] {
                own[e[0] as usize] = e[1];
            }
        }
    }
}
