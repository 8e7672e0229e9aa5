//! The view cut on a model's [`ViewLayout`], in its three stages: the
//! search for the wanted inner nodes, their closure, and the emission of
//! the drawn children's triangles. The same expanded set and the same
//! triangles in the same order as [`ViewCut::cut_nodes`] (tests and the
//! `mco_view_cut` bench check it), on ranks.

use super::*;

/// All five planes of a [`Frustum`] still to test.
const ALL_PLANES: u32 = 0b1_1111;

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
        let ranks = lay.ranks();
        self.bits.clear();
        self.bits.resize(ranks.div_ceil(64), 0);
        clear_listed(&mut self.group_seen, &self.groups, model.groups.len());
        self.groups.clear();
        self.queue.clear();
        let fr = Frustum::new(model, camera, tolerance_px);
        self.last_wanted = self.search(model, lay, &fr);
        let count = self.close(model, lay);
        emit(model, lay, &self.bits, out);
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
        stack.push((ALL_PLANES as u64) << 32);
        while let Some(entry) = stack.pop() {
            let (r, planes) = (entry as u32, (entry >> 32) as u32);
            let h = &lay.hot[r as usize];
            let (lo, hi) = lay.cube(h);
            let (glo, ghi) = lay.grown(h, lo, hi);
            let may_show = h.bound == f32::INFINITY
                || (fr.may_project(glo, ghi, h.bound) && meets(glo, ghi, planes));
            if !may_show {
                continue;
            }
            if shows(lo, hi, h.err, planes) {
                wanted.push(r);
            }
            let k = h.inner_mask.count_ones();
            if k > 0 {
                let below = (inner_planes(h, glo, ghi, planes) as u64) << 32;
                stack.extend((h.first_inner..h.first_inner + k).map(|c| below | c as u64));
            }
        }
        wanted.len()
    }

    /// The closure of the wanted ranks in `queue` (parents, balance
    /// dependencies, groups), as bits; returns the expanded count. A rank
    /// already set is not pushed again, so each expanded rank is popped
    /// once from the wanted list or once per node that adds it first.
    #[inline(never)]
    fn close(&mut self, model: &McoModel, lay: &ViewLayout) -> usize {
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

/// The emission, in rank order (= node order): each expanded node's
/// children that are not expanded, runs without an active crack patch
/// copied as one triangle range. Only the children that break a run (an
/// expanded one, or one with crack patches, which breaks it only while a
/// patch is active) are visited, found from bit masks.
#[inline(never)]
fn emit(model: &McoModel, lay: &ViewLayout, bits: &[u64], out: &mut Vec<u32>) {
    let tris = lay.tris(model);
    let toff = &lay.toff;
    if lay.ranks() == 0 || !bit(bits, 0) {
        emit_patched(model, lay, bits, 0, out);
        return;
    }
    let copy = |out: &mut Vec<u32>, a: u32, b: u32| {
        if a < b {
            out.extend_from_slice(&tris[a as usize..b as usize]);
        }
    };
    for (w, &word) in bits.iter().enumerate() {
        let mut x = word;
        while x != 0 {
            let r = (w as u32) << 6 | x.trailing_zeros();
            x &= x - 1;
            let h = &lay.hot[r as usize];
            let fc = lay.close[r as usize].first_child;
            // Bit `j`: child `fc + j` is expanded (the inner children's
            // ranks are `first_inner..`, in child order).
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
                let c = fc + j;
                let drawn = expanded >> j & 1 == 0;
                if drawn && !patch_active(lay, bits, c) {
                    continue;
                }
                copy(out, run, toff[c as usize]);
                if drawn {
                    emit_patched(model, lay, bits, c, out);
                }
                run = toff[c as usize + 1];
            }
            copy(out, run, toff[(fc + h.child_count as u32) as usize]);
        }
    }
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

/// Whether drawing node `c` now applies one of its crack patches (a coarse
/// neighbour is not expanded).
#[inline(always)]
fn patch_active(lay: &ViewLayout, bits: &[u64], c: u32) -> bool {
    let (a, b) = (lay.poff[c as usize], lay.poff[c as usize + 1]);
    lay.patches[a as usize..b as usize]
        .iter()
        .any(|p| p[0] == u32::MAX || !bit(bits, p[0]))
}

/// Appends node `c`'s triangles, crack-patched against every coarse
/// neighbour not expanded: [`McoModel::emit`] on the layout, each patch
/// written from its prepared edits (or, for a node whose patches interact,
/// by the scan of its substitutions).
fn emit_patched(model: &McoModel, lay: &ViewLayout, bits: &[u64], c: u32, out: &mut Vec<u32>) {
    let tris = lay.tris(model);
    let start = out.len();
    out.extend_from_slice(&tris[lay.toff[c as usize] as usize..lay.toff[c as usize + 1] as usize]);
    let (a, b) = (lay.poff[c as usize], lay.poff[c as usize + 1]);
    let own = &mut out[start..];
    let scan = lay.scan[(c >> 6) as usize] >> (c & 63) & 1 != 0;
    for p in &lay.patches[a as usize..b as usize] {
        if p[0] != u32::MAX && bit(bits, p[0]) {
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
