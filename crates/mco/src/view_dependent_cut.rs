//! View-dependent extraction (beyond the thesis: its §8.2 future work,
//! "simplify only the viewing area", where it claims `O(log n)` view
//! dependency for the octree).
//!
//! A node is *wanted* expanded when it has children, its cube intersects
//! the view frustum and its geometric error, projected to the screen,
//! exceeds the pixel tolerance. The geometric error of a node is `sqrt(M)`,
//! the square root of its LOD metric: the largest distance between its
//! triangles and its children's, saturated up the tree (object units; see
//! `octree_build::lod_metric`), zero on flat regions, so flat areas stay
//! coarse. The projected size of
//! a length `e` at distance `d` (from the eye to the nearest point of the
//! cube) with vertical field of view `fov` on a viewport `h` pixels high is
//! `e · h / (2 d tan(fov/2))`.
//!
//! The wanted set is then closed so that the cut stays valid and balanced:
//! an expanded node's parent is expanded, and so is every node in its
//! balance dependencies (the parents of its same-level neighbours, §5.2)
//! and every node that must expand in the same LOD step (its group, see
//! [`crate::priority_numbering`]). The closure only ever adds coarser or
//! same-level nodes already drawn, so it terminates, and the crack patches
//! (§5.3) apply to the resulting cut unchanged.
//!
//! **Cost proportional to the cut, not the tree.** The LOD metric is not
//! monotone down the tree (a child can have a larger error than its
//! parent), so the wanted set is not found by stopping at the first node
//! that fails the test. Each node instead carries a *subtree bound*: the
//! largest error of any inner node below it (built once per model,
//! `O(nodes)`, on the first cut). A child's cube lies inside its parent's,
//! so it is no nearer to the eye and no more visible; a subtree whose cube
//! is outside the frustum, or whose bound projects to at most the
//! tolerance, holds no wanted node and is skipped. The search walks down
//! from the root through the subtrees that may hold one, testing only inner
//! nodes (leaves are never wanted). The float rounding of the cubes'
//! corners is covered by testing each subtree against its cube grown by
//! 2⁻¹⁸ of its coordinates' magnitude (the corners of a child, computed on
//! their own, can differ from the parent's by a few units in the last
//! place); every projection is computed with the same operations as the
//! node's own test, and IEEE rounding is monotone, so the bound never
//! projects below a node it covers. A node whose children are not the
//! eight octants of its cube one level down (possible only in a
//! hand-made model) gets an infinite bound: its subtree is always
//! searched. The result is therefore exactly the set a scan of every node
//! finds (tested against that scan). The expanded nodes then draw their
//! children that are not expanded, in node order (the list sorted, or for
//! a large set the flags read in blocks), so the whole cut costs
//! `O(expanded nodes · log + nodes tested + output)`, and gives the scan's
//! triangles in the scan's order.
//!
//! [`ViewCut`] keeps the per-node flags and work lists between cuts (the
//! flags set by one cut are cleared through its own list of expanded
//! nodes at the next), so a cut allocates nothing in the steady state.
//!
//! **Frame to frame** (a kept [`ViewCut`] on a model's compact layout, see
//! `compact_cut`): a viewer's camera moves a little between frames, and
//! its expanded set changes in a few hundred nodes. While the camera sees
//! the whole model, the searched part of the tree is kept from cut to cut
//! and only the nodes whose last test the eye's path may have overturned
//! are tested again (see `frontier`); otherwise the search skips a
//! subtree it last rejected on its bound's projection while the eye stays
//! nearer than the distance that rejection had to spare (the distance to
//! a box moves no faster than the eye). The closure is updated from the
//! last one, only around the wanted nodes that changed (see `closure`);
//! the emission copies, from the last cut's buffer, the triangles of every
//! node whose children and crack patches' coarse neighbours kept their
//! state. None of these changes the result: the same triangles in the
//! same order as a fresh cut.

use glam::Vec3;

use crate::model::McoModel;

mod closure;
mod compact_cut;
mod frontier;
mod layout;
pub(crate) mod view_data;
use layout::*;
use view_data::*;

/// A perspective camera, in the model's object units. Only what decides
/// which nodes are refined: where it is, where it looks, and how many
/// pixels a length covers.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Eye position (object units).
    pub position: Vec3,
    /// View direction (need not be unit length).
    pub direction: Vec3,
    /// Up hint (need not be orthogonal to `direction`).
    pub up: Vec3,
    /// Vertical field of view in degrees.
    pub vfov_deg: f32,
    /// Viewport height in pixels.
    pub viewport_height: f32,
    /// Viewport width / height (1 = square).
    pub aspect: f32,
}

impl Camera {
    /// A camera at `position` looking at `target`, 60° field of view, a
    /// 1080-pixel square viewport.
    pub fn looking_at(position: Vec3, target: Vec3) -> Camera {
        Camera {
            position,
            direction: target - position,
            up: Vec3::Y,
            vfov_deg: 60.0,
            viewport_height: 1080.0,
            aspect: 1.0,
        }
    }

    fn frame(&self) -> (Vec3, Vec3, Vec3) {
        let f = self.direction.normalize_or(Vec3::NEG_Z);
        let mut r = f.cross(self.up);
        if r.length_squared() < 1e-12 {
            r = f.any_orthonormal_vector();
        }
        let r = r.normalize();
        (f, r, r.cross(f))
    }
}

/// The per-cut test: frustum planes through the eye and the projection of
/// a length to pixels.
struct Frustum {
    eye: Vec3,
    /// Inward normals of the four side planes and the near plane (through
    /// the eye).
    planes: [Vec3; 5],
    tan_v: f32,
    height: f32,
    tol: f32,
    /// Distances below this count as this (a node around the eye).
    min_d: f32,
    /// `height / (2 tan_v tol)` grown by 2⁻¹² (far above its rounding):
    /// a length `e` at distance `d` covers more than the tolerance only if
    /// `e · reach > d` (see [`Frustum::distance_and_reach`]).
    reach: f32,
}

impl Frustum {
    fn new(model: &McoModel, camera: &Camera, tolerance_px: f32) -> Frustum {
        let (f, r, u) = camera.frame();
        let tan_v = (camera.vfov_deg.to_radians() * 0.5).tan().max(1e-6);
        let tan_h = tan_v * camera.aspect.max(1e-6);
        let tol = tolerance_px.max(1e-6);
        let reach = camera.viewport_height / (2.0 * tan_v * tol) * (1.0 + 1.0 / 4096.0);
        Frustum {
            eye: camera.position,
            planes: [
                r + f * tan_h,
                -r + f * tan_h,
                u + f * tan_v,
                -u + f * tan_v,
                f,
            ],
            tan_v,
            height: camera.viewport_height,
            tol,
            min_d: model.grid.cube * 1e-3,
            reach,
        }
    }

    /// Whether the box `lo..hi` (absolute) is not entirely outside the
    /// frustum, and the pixels the length `e` covers at its nearest point
    /// exceed the tolerance.
    ///
    /// The two tests are pure, so their order does not change the answer:
    /// the projected error goes first, as it is the cheaper one and the one
    /// that rejects most of the nodes a search tests (a camera that sees
    /// the whole model has every node in its frustum).
    #[inline]
    fn shows(&self, lo: Vec3, hi: Vec3, e: f32) -> bool {
        self.projects(lo, hi, e) && (0..5).all(|k| self.meets(k, lo, hi))
    }

    /// The first half of [`Frustum::shows`]: whether the length `e` at the
    /// nearest point of the box `lo..hi` covers more than the tolerance.
    #[inline(always)]
    fn projects(&self, lo: Vec3, hi: Vec3, e: f32) -> bool {
        let lo = lo - self.eye;
        let hi = hi - self.eye;
        // `clamp` without its debug check: a NaN camera gives NaN corners
        // here (and no node shows).
        let closest = Vec3::ZERO.max(lo).min(hi);
        let d = closest.length().max(self.min_d);
        let px = e * self.height / (2.0 * d * self.tan_v);
        px > self.tol
    }

    /// A conservative [`Frustum::projects`] for subtree bounds, without
    /// its division: `(d, r)`, the distance `projects` computes for the box
    /// `lo..hi` (the same operations) and the reach of the length `e`;
    /// `r > d` wherever `projects` is true, as `reach`'s margin covers the
    /// rounding of both (a few units in the last place of the quotient and
    /// of `reach`).
    #[inline(always)]
    fn distance_and_reach(&self, lo: Vec3, hi: Vec3, e: f32) -> (f32, f32) {
        let closest = Vec3::ZERO.max(lo - self.eye).min(hi - self.eye);
        (closest.length().max(self.min_d), e * self.reach)
    }

    /// The second half of [`Frustum::shows`], for plane `k`: whether the
    /// box `lo..hi` is not entirely outside it.
    #[inline(always)]
    fn meets(&self, k: usize, lo: Vec3, hi: Vec3) -> bool {
        let p = self.planes[k];
        let v = Vec3::select(p.cmpge(Vec3::ZERO), hi - self.eye, lo - self.eye);
        p.dot(v) >= 0.0
    }

    /// Whether the box `lo..hi` lies inside plane `k` by a margin that
    /// covers the rounding of [`Frustum::meets`] on any box inside it up
    /// to a few units in the last place of its coordinates: then `meets`
    /// holds for every such box (the cubes of a subtree, see the module
    /// docs), and a search need not test the plane below.
    ///
    /// The margin is 2⁻¹⁶ of `|p|₁ · (|v|∞ + |box|∞)`, where the rounding
    /// of `meets` (two subtractions and a dot product in `f32`) is under
    /// 2⁻²¹ of `|p|₁ · |v|∞`, and a box sticking out by `u` units in the
    /// last place moves the dot product by at most `u · 2⁻²³ · |p|₁ ·
    /// |box|∞`. A NaN anywhere makes it false.
    #[inline(always)]
    fn contains(&self, k: usize, lo: Vec3, hi: Vec3) -> bool {
        let p = self.planes[k];
        let (a, b) = (lo - self.eye, hi - self.eye);
        let v = Vec3::select(p.cmpge(Vec3::ZERO), a, b);
        let size = a.abs().max(b.abs()).max_element() + lo.abs().max(hi.abs()).max_element();
        let margin = p.abs().element_sum() * size * (1.0 / 65536.0);
        p.dot(v) >= margin
    }
}

/// How far the eye may move while `a > b` holds, for `a` and `b` a
/// distance and a reach as [`Frustum::distance_and_reach`] computes them
/// (either way round): their difference less the rounding of both, a
/// relative 2⁻¹⁶ of the lengths and of `size`, the coordinates'
/// magnitude (the box's plus the eye's). Not positive: no margin. The
/// certificates of a kept [`ViewCut`] (`ViewCut::slack`, and the
/// frontier's expiries) are made of it.
#[inline(always)]
fn excess(a: f32, b: f32, size: f32) -> f32 {
    a - b - (a + b + size) * (1.0 / 65536.0)
}

/// How far the eye may move while [`Frustum::projects`] stays true for a
/// box at distance `d` whose error reaches `reach` (`distance_and_reach`):
/// [`excess`] less 2⁻¹¹ of the reach, far above the 2⁻¹² growth the
/// reach carries and the rounding of the quotient in `projects`.
#[inline(always)]
fn projecting_margin(d: f32, reach: f32, size: f32) -> f32 {
    excess(reach * (1.0 - 1.0 / 2048.0), d, size)
}

/// A node's geometric error: the square root of its LOD metric (object
/// units; a negative or NaN metric counts as 0).
#[inline]
fn node_error(model: &McoModel, n: u32) -> f32 {
    model
        .metric
        .get(n as usize)
        .copied()
        .unwrap_or(0.0)
        .max(0.0)
        .sqrt()
}

/// A [`ViewCut`] whose last cut wanted more than `1 / SCAN_SHARE` of the
/// nodes finds the next cut's wanted set by a scan instead of the search: the search tests about 4.5 inner nodes per wanted
/// one, in jumps that cost several times a scan's sequential reads, so past
/// one wanted node in 40 the scan of every node is the cheaper way to the
/// same set (`mco_view_cut` bench: the two cross near a 100k-triangle cut
/// of a 1M-triangle model).
const SCAN_SHARE: usize = 40;

/// Relative growth of a subtree's cube for its bound test (see the module
/// docs): 64 units in the last place of an `f32`, far above the few that
/// separate a child's corners from its parent's.
const BOUND_GROWTH: f32 = 1.0 / (1 << 18) as f32;

/// Per node, the largest error of an inner node in its subtree (its own
/// included; 0 for a leaf), or infinity where the subtree must always be
/// searched (children not inside the node's cube, or a cube that is not
/// finite). Children follow their parent in node order (the loaders check
/// it), so one reverse pass suffices.
/// `O(nodes)`.
pub(crate) fn view_subtree_bounds(model: &McoModel) -> Vec<f32> {
    let n = model.nodes.len();
    let mut b = vec![0.0f32; n];
    for i in (0..n).rev() {
        let nd = model.nodes[i];
        if nd.child_count == 0 {
            continue;
        }
        let (lo, hi) = model.node_box(i as u32);
        let mut x = node_error(model, i as u32);
        if !(lo.is_finite() && hi.is_finite()) {
            x = f32::INFINITY;
        }
        for c in model.children(i as u32) {
            let Some(cn) = model.nodes.get(c as usize) else {
                x = f32::INFINITY;
                continue;
            };
            let inside = c as usize > i
                && cn.level as u32 + 1 == nd.level as u32
                && (0..3).all(|a| cn.coord[a] >> 1 == nd.coord[a]);
            x = if inside {
                x.max(b[c as usize])
            } else {
                f32::INFINITY
            };
        }
        b[i] = x;
    }
    b
}

impl McoModel {
    /// The view arrays, built on the first call (thread-safe).
    fn view_data(&self) -> &ViewData {
        self.view_bounds.0.get_or_init(|| {
            let bounds = view_subtree_bounds(self);
            match ViewLayout::build(self, &bounds) {
                Some(l) => ViewData::Layout(Box::new(l)),
                None => ViewData::Bounds(bounds),
            }
        })
    }
}

/// Reusable state for view-dependent cuts of a model: keep one per model
/// (or per view of it) and call [`ViewCut::update`] every frame.
///
/// - Contract: [`ViewCut::update`] gives exactly the cut
///   [`McoModel::extract_view`] gives for the same model, camera and
///   tolerance — the same triangles in the same order —, whatever cuts
///   came before (the state holds only scratch space, never part of a
///   result). A `ViewCut` may be used with different models in turn.
/// - Cost of a cut: proportional to the cut (its expanded nodes, the inner
///   nodes tested around them, and its output), not to the tree: the
///   per-node flags are allocated once (one byte per node) and cleared
///   through the previous cut's list of expanded nodes. After a cut that
///   wanted more than a 40th of the nodes, the next one scans the nodes
///   instead of searching (cheaper at that size; the same set), unless a
///   kept state updates its searched tree (a camera that sees the whole
///   model: the cost is then that of what the step changed). The first
///   cut of a model also builds its compact layout (`O(nodes + triangles)`,
///   kept in the model). From one cut to the next of a moving camera, a
///   kept state re-tests only the nodes whose answer the eye's move may
///   have changed, updates the closure only around the wanted nodes that
///   changed, and re-emits only the nodes whose neighbourhood changed
///   (the rest is copied from the last cut, kept here: one more index
///   buffer, about 40 bytes per inner node and 4 per LOD step).
#[derive(Debug, Clone, Default)]
pub struct ViewCut {
    /// Per node: expanded in the current cut. True exactly for `expanded`.
    flags: Vec<bool>,
    /// The nodes the current cut expands.
    expanded: Vec<u32>,
    /// Per LOD number: its group was already added to the closure.
    group_seen: Vec<bool>,
    /// The LOD numbers whose `group_seen` is set.
    groups: Vec<u32>,
    /// Work list of the search and of the closure.
    stack: Vec<u32>,
    /// Work list of the search on a [`ViewLayout`]: a rank, and above it
    /// the frustum planes its subtree still tests.
    search: Vec<u64>,
    /// The wanted list, then the emission order.
    queue: Vec<u32>,
    /// Wanted nodes of the last cut (0 before the first): picks the search
    /// or the scan for the next (see [`SCAN_SHARE`]).
    last_wanted: usize,
    /// Per rank of a [`ViewLayout`]: expanded in the current cut.
    bits: Vec<u64>,
    /// Nodes the current cut expands.
    count: usize,
    /// What the last cut on a [`ViewLayout`] left for the next one's
    /// emission (see `compact_cut`): its layout's id (0: none), its
    /// expanded ranks, its index buffer (the last cut's, on any path:
    /// [`ViewCut::indices`]), and per rank expanded there, its triangles'
    /// `[start, length]` in that buffer.
    prev_layout: u64,
    prev_bits: Vec<u64>,
    prev: Vec<u32>,
    seg: Vec<[u32; 2]>,
    /// Per rank: its triangles may differ from the last cut's.
    dirty: Vec<u64>,
    /// A cut made once (`extract_view`): nothing kept for a next one.
    one_shot: bool,
    /// Per rank of a [`ViewLayout`], `[eye x, y, z, margin]`: the
    /// certificate the last cut that tested the rank made at its eye. While
    /// the eye stays nearer than `|margin|` to that eye, the rank's subtree
    /// holds no wanted node (`margin > 0`: it projects its bound below the
    /// tolerance), or the rank projects its own error above the tolerance
    /// (`margin < 0`; whether it is in view is tested apart): the distance
    /// to a box moves no faster than the eye, and the margin is the
    /// distance's excess over the reach (or the reach's over the
    /// distance), less a relative 2⁻¹⁶ of the lengths and coordinates for
    /// the rounding of both; a test whose excess does not cover that
    /// rounding records no certificate (0). Valid for the layout, reach and
    /// minimum distance in `slack_key` (the tolerance, the field of view
    /// and the viewport height enter the reach), whatever the direction.
    slack: Vec<[f32; 4]>,
    slack_key: (u64, u32, u32),
    /// The incremental closure's state (see `closure`), valid for the
    /// layout `inc_layout` (0: none) and the bits in `bits`: the wanted
    /// ranks, per rank outside every group and per LOD group its support,
    /// and the expanded count. `new_want` and `work` are its scratch.
    inc_layout: u64,
    /// The subtree bounds [`ViewCut::update_by_nodes`] searches with
    /// ([`view_subtree_bounds`] of its model, built at its first call).
    node_bounds: Vec<f32>,
    want: Vec<u64>,
    new_want: Vec<u64>,
    support: Vec<i32>,
    gsupport: Vec<i32>,
    inc_count: usize,
    work: Vec<u64>,
    /// The searched tree a kept cut updates while the camera sees the
    /// whole model (see `frontier`); it keeps `want` as its wanted set.
    front: frontier::Frontier,
    /// The buffer the next [`ViewCut::update`] emits into (the one before
    /// the last cut's, its allocation reused).
    spare: Vec<u32>,
}

impl ViewCut {
    /// Empty state (allocates nothing until the first cut).
    pub fn new() -> ViewCut {
        ViewCut::default()
    }

    /// Re-cuts `model` for `camera` at `tolerance_px` and returns the cut's
    /// index buffer (3 `u32` per triangle into [`McoModel::positions`]),
    /// also kept as [`ViewCut::indices`] until the next update. Same
    /// inputs, units and guarantees as [`McoModel::extract_view`]; the
    /// cost is in the type's docs. The buffer is the one the next cut
    /// copies its unchanged triangles from, so no copy of it is made.
    pub fn update(&mut self, model: &McoModel, camera: &Camera, tolerance_px: f32) -> &[u32] {
        let mut out = std::mem::take(&mut self.spare);
        self.cut_into(model, camera, tolerance_px, &mut out);
        // `prev` (the last cut's buffer, read by the emission) becomes the
        // spare, and this cut's buffer the one the next cut reads.
        self.spare = std::mem::replace(&mut self.prev, out);
        &self.prev
    }

    /// [`ViewCut::update`] into the caller's buffer: the cut's index
    /// buffer goes into `out` (cleared; its allocation reused), and the
    /// expanded node count is returned; [`ViewCut::indices`] holds a copy
    /// (the buffer the next cut copies its unchanged triangles from). Same
    /// guarantees and cost as [`ViewCut::update`], plus that copy.
    pub fn update_into(
        &mut self,
        model: &McoModel,
        camera: &Camera,
        tolerance_px: f32,
        out: &mut Vec<u32>,
    ) -> usize {
        let n = self.cut_into(model, camera, tolerance_px, out);
        self.prev.clear();
        self.prev.extend_from_slice(out);
        n
    }

    /// The same cut as [`ViewCut::update_into`] by the search on the node
    /// arrays that every model without a compact layout gets: for the
    /// bench's paired comparison of the two on one model (not a stable
    /// API). Keep one `ViewCut` per model for it: the subtree bounds are
    /// built at the first call (`O(nodes)`) and kept.
    #[doc(hidden)]
    pub fn update_by_nodes(
        &mut self,
        model: &McoModel,
        camera: &Camera,
        tolerance_px: f32,
        out: &mut Vec<u32>,
    ) -> usize {
        out.clear();
        if model.nodes.is_empty() {
            self.count = 0;
            return 0;
        }
        if self.node_bounds.len() != model.nodes.len() {
            self.node_bounds = view_subtree_bounds(model);
        }
        let bounds = std::mem::take(&mut self.node_bounds);
        self.count = self.cut_nodes(model, &bounds, camera, tolerance_px, out);
        self.node_bounds = bounds;
        self.count
    }

    /// The index buffer of the last [`ViewCut::update`] or
    /// [`ViewCut::update_into`] (empty before).
    pub fn indices(&self) -> &[u32] {
        &self.prev
    }

    /// Triangles of the last cut.
    pub fn triangles(&self) -> usize {
        self.prev.len() / 3
    }

    /// Whether the last cut searched through a kept frontier (tests).
    #[cfg(test)]
    pub(crate) fn used_frontier(&self) -> bool {
        self.front.kept()
    }

    /// Nodes the last cut expanded (0: the root alone is drawn).
    pub fn expanded_nodes(&self) -> usize {
        self.count
    }

    /// Clears the previous cut's flags (through its list) and sizes the
    /// per-node and per-LOD arrays for `model`.
    fn reset(&mut self, model: &McoModel) {
        clear_listed(&mut self.flags, &self.expanded, model.nodes.len());
        clear_listed(&mut self.group_seen, &self.groups, model.groups.len());
        self.expanded.clear();
        self.groups.clear();
        self.stack.clear();
        self.queue.clear();
    }

    /// The cut into `out` (cleared); returns the expanded node count.
    fn cut_into(
        &mut self,
        model: &McoModel,
        camera: &Camera,
        tolerance_px: f32,
        out: &mut Vec<u32>,
    ) -> usize {
        out.clear();
        if model.nodes.is_empty() {
            self.prev_layout = 0;
            self.count = 0;
            return 0;
        }
        // Only a cut on a layout leaves `prev` for the next one's emission
        // (the caller makes `prev` this cut's buffer, whatever the path).
        self.count = match model.view_data() {
            ViewData::Layout(l) => self.cut_layout(model, l, camera, tolerance_px, out),
            ViewData::Bounds(b) => {
                self.prev_layout = 0;
                self.cut_nodes(model, b, camera, tolerance_px, out)
            }
        };
        self.count
    }

    /// [`ViewCut::cut_into`] on the node arrays (any model).
    fn cut_nodes(
        &mut self,
        model: &McoModel,
        bounds: &[f32],
        camera: &Camera,
        tolerance_px: f32,
        out: &mut Vec<u32>,
    ) -> usize {
        self.reset(model);
        let fr = Frustum::new(model, camera, tolerance_px);
        // The search: every wanted node onto `wanted`, through the subtrees
        // whose bound may show.
        let mut wanted: Vec<u32> = std::mem::take(&mut self.queue);
        if self.last_wanted.saturating_mul(SCAN_SHARE) > model.nodes.len() {
            // A large cut: a scan of every inner node in order costs less
            // than the search's jumps, and finds the same set.
            for n in 0..model.nodes.len() as u32 {
                if model.nodes[n as usize].child_count > 0 {
                    let (lo, hi) = model.node_box(n);
                    if fr.shows(lo, hi, node_error(model, n)) {
                        wanted.push(n);
                    }
                }
            }
        } else if model.nodes[0].child_count > 0 {
            self.stack.push(0);
        }
        while let Some(n) = self.stack.pop() {
            let (lo, hi) = model.node_box(n);
            let descend = if fr.shows(lo, hi, node_error(model, n)) {
                wanted.push(n);
                true
            } else {
                let b = bounds[n as usize];
                b == f32::INFINITY || {
                    let m = lo.abs().max(hi.abs()).max_element() * BOUND_GROWTH;
                    let g = Vec3::splat(m + f32::MIN_POSITIVE);
                    fr.shows(lo - g, hi + g, b)
                }
            };
            if descend {
                for c in model.children(n) {
                    if model.nodes[c as usize].child_count > 0 {
                        self.stack.push(c);
                    }
                }
            }
        }
        self.last_wanted = wanted.len();
        // The closure (parents, balance dependencies, groups).
        self.stack.append(&mut wanted);
        self.queue = wanted;
        while let Some(i) = self.stack.pop() {
            if std::mem::replace(&mut self.flags[i as usize], true) {
                continue;
            }
            self.expanded.push(i);
            let nd = model.nodes[i as usize];
            if nd.parent != u32::MAX {
                self.stack.push(nd.parent);
            }
            self.stack
                .extend_from_slice(&model.deps[nd.deps_start as usize..][..nd.deps_count as usize]);
            // Nodes that expand together (crack-free only as a group),
            // added once per group so the closure stays linear.
            let k = model.prio[i as usize];
            if k != u32::MAX && !std::mem::replace(&mut self.group_seen[k as usize], true) {
                self.groups.push(k);
                self.stack.extend_from_slice(model.group(k as usize));
            }
        }
        // The emission: each expanded node, in node order, draws its
        // children that are not expanded. Node order keeps the reads of
        // the node, triangle and patch arrays moving forward (children
        // are numbered after their parent, in blocks), which a walk from
        // the root does not in a file's LOD-ordered numbering; it also
        // makes the order of the triangles a function of the set alone.
        let flags = &self.flags;
        let is = |q: u32| flags[q as usize];
        if !flags[0] {
            model.emit(0, out, &is);
            return self.expanded.len();
        }
        let order = &mut self.queue;
        order.clear();
        if self.expanded.len() * 32 > flags.len() {
            // A large set: reading the flags in blocks costs less than
            // sorting the list.
            for (b, block) in flags.chunks(64).enumerate() {
                if block.iter().any(|&f| f) {
                    let base = (64 * b) as u32;
                    order.extend(
                        (0..block.len() as u32)
                            .filter(|&j| block[j as usize])
                            .map(|j| base + j),
                    );
                }
            }
        } else {
            order.extend_from_slice(&self.expanded);
            order.sort_unstable();
        }
        for &n in order.iter() {
            for c in model.children(n) {
                if !flags[c as usize] {
                    model.emit(c, out, &is);
                }
            }
        }
        self.expanded.len()
    }
}

/// Makes `flags` `len` falses: through `set` (the indices the last cut
/// set) when it already has that length, so a steady-state cut costs its
/// own size, not the model's; reallocated for another model.
fn clear_listed(flags: &mut Vec<bool>, set: &[u32], len: usize) {
    if flags.len() == len {
        for &i in set {
            flags[i as usize] = false;
        }
    } else {
        flags.clear();
        flags.resize(len, false);
    }
}

/// Whether `model`'s cuts use the compact [`ViewLayout`].
#[cfg(test)]
pub(crate) fn has_layout(model: &McoModel) -> bool {
    matches!(model.view_data(), ViewData::Layout(_))
}

/// Per-node expanded flags for `camera` and a tolerance in pixels, by a
/// scan of every node: the definition [`ViewCut`]'s search is tested
/// against (`O(nodes)`).
#[cfg(test)]
pub(crate) fn select(model: &McoModel, camera: &Camera, tolerance_px: f32) -> Vec<bool> {
    let n = model.nodes.len();
    let mut expanded = vec![false; n];
    if n == 0 {
        return expanded;
    }
    let fr = Frustum::new(model, camera, tolerance_px);
    let mut stack: Vec<u32> = Vec::new();
    let mut group_pushed = vec![false; model.groups.len()];
    for i in 0..n as u32 {
        if model.nodes[i as usize].child_count == 0 {
            continue;
        }
        let (lo, hi) = model.node_box(i);
        if fr.shows(lo, hi, node_error(model, i)) {
            stack.push(i);
        }
    }
    while let Some(i) = stack.pop() {
        if expanded[i as usize] {
            continue;
        }
        expanded[i as usize] = true;
        let nd = model.nodes[i as usize];
        if nd.parent != u32::MAX {
            stack.push(nd.parent);
        }
        stack.extend_from_slice(&model.deps[nd.deps_start as usize..][..nd.deps_count as usize]);
        let k = model.prio[i as usize];
        if k != u32::MAX && !std::mem::replace(&mut group_pushed[k as usize], true) {
            stack.extend_from_slice(model.group(k as usize));
        }
    }
    expanded
}

/// Tolerances at which a subtree's bound, seen from `camera`, reaches a
/// hair (under the rounding margin of [`ViewCut::slack`]) short of the
/// distance to its grown cube: the search rejects the subtree, but with
/// too little to spare to certify anything. Up to `n`, for ranks spread
/// over the layout.
#[cfg(test)]
pub(crate) fn hairline_tolerances(model: &McoModel, camera: &Camera, n: usize) -> Vec<f32> {
    let ViewData::Layout(lay) = model.view_data() else {
        return Vec::new();
    };
    let mut out = Vec::new();
    let step = (lay.ranks() / (4 * n.max(1))).max(1);
    for r in (1..lay.ranks()).step_by(step) {
        let h = &lay.hot[r];
        if h.bound == f32::INFINITY || h.bound <= 0.0 {
            continue;
        }
        let (lo, hi) = lay.cube(h);
        let (glo, ghi) = lay.grown(h, lo, hi);
        let probe = Frustum::new(model, camera, 1.0);
        let (d, reach) = probe.distance_and_reach(glo, ghi, h.bound);
        // `reach` scales as 1 / tolerance: start where it meets `d`, then
        // raise the tolerance by units in the last place until it falls
        // short.
        let mut tol = reach / d;
        for _ in 0..64 {
            let (d, reach) = Frustum::new(model, camera, tol).distance_and_reach(glo, ghi, h.bound);
            if reach <= d {
                out.push(tol);
                break;
            }
            tol = f32::from_bits(tol.to_bits() + 1);
        }
        if out.len() == n {
            break;
        }
    }
    out
}

impl McoModel {
    /// The view-dependent cut for `camera`: nodes inside the view frustum
    /// whose geometric error would cover more than `tolerance_px` pixels
    /// on screen are refined, the rest stay coarse; the cut's index
    /// buffer goes into `out` (cleared; its allocation reused). Returns
    /// the number of expanded nodes.
    ///
    /// - `tolerance_px`: the largest projected error allowed, in pixels of
    ///   a viewport [`Camera::viewport_height`] high (1.0 is a good
    ///   default; values below 1e-6 count as 1e-6). A node's error is the
    ///   square root of its LOD metric (object units), projected at the
    ///   distance from the eye to the nearest point of its cube.
    /// - Guarantees: crack-free (the expanded set is closed under parents,
    ///   balance dependencies and groups that must expand together, so the
    ///   crack patches apply unchanged); each part of the surface is drawn
    ///   once, at one level; every index is below `positions().len()`;
    ///   deterministic: the triangles are those of the drawn nodes, in
    ///   node order. Nothing in view (a camera
    ///   looking away, a NaN position) leaves the model at its coarsest:
    ///   the root cube's triangles.
    /// - Cost: proportional to the cut, not the model (see [`ViewCut`]),
    ///   plus one byte per node allocated and zeroed per call; a renderer
    ///   cutting every frame keeps a [`ViewCut`] instead, which gives the
    ///   same cut without that allocation.
    ///
    /// The buffer may hold triangles with two equal indices, where crack
    /// patching collapsed a fine edge onto a coarse segment's end: they
    /// have no area and draw nothing (an incremental cut copies runs of
    /// the previous buffer, so they are kept in place);
    /// [`McoModel::mesh_from_indices`] leaves them out.
    pub fn extract_view(&self, camera: &Camera, tolerance_px: f32, out: &mut Vec<u32>) -> usize {
        let mut cut = ViewCut {
            one_shot: true,
            ..ViewCut::default()
        };
        cut.cut_into(self, camera, tolerance_px, out)
    }
}
