//! View-dependent extraction (beyond the thesis: its §8.2 future work,
//! "simplify only the viewing area").
//!
//! A node is *wanted* expanded when its cube intersects the view frustum and
//! its geometric error, projected to the screen, exceeds the pixel
//! tolerance. The geometric error of a node is `sqrt(M)`, the square root
//! of the thesis's LOD metric (the area difference to its children): a
//! length that is zero on flat regions, so flat areas stay coarse exactly
//! as in the LOD-array ordering. The projected size of a length `e` at
//! distance `d` with vertical field of view `fov` on a viewport `h` pixels
//! high is `e · h / (2 d tan(fov/2))`.
//!
//! The wanted set is then closed so that the cut stays valid and balanced:
//! an expanded node's parent is expanded, and so is every node in its
//! balance dependencies (the parents of its same-level neighbours, §5.2).
//! The closure only ever adds coarser nodes, so it terminates, and the
//! crack patches (§5.3) apply to the resulting cut unchanged.

use glam::Vec3;

use crate::model::McoModel;

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

/// Per-node expanded flags for `camera` and a tolerance in pixels.
pub(crate) fn select(model: &McoModel, camera: &Camera, tolerance_px: f32) -> Vec<bool> {
    let n = model.nodes.len();
    let mut expanded = vec![false; n];
    if n == 0 {
        return expanded;
    }
    let (f, r, u) = camera.frame();
    let tan_v = (camera.vfov_deg.to_radians() * 0.5).tan().max(1e-6);
    let tan_h = tan_v * camera.aspect.max(1e-6);
    let planes = [
        r + f * tan_h,
        -r + f * tan_h,
        u + f * tan_v,
        -u + f * tan_v,
        f,
    ];
    let tol = tolerance_px.max(1e-6);
    let mut stack: Vec<u32> = Vec::new();
    // A group is pushed once (by its first member to expand), so the
    // closure is linear even for a group of many nodes (a hostile file).
    let mut group_pushed = vec![false; model.groups.len()];
    for i in 0..n as u32 {
        if model.nodes[i as usize].child_count == 0 {
            continue;
        }
        let (lo, hi) = model.node_box(i);
        let lo = lo - camera.position;
        let hi = hi - camera.position;
        let visible = planes.iter().all(|p| {
            let v = Vec3::select(p.cmpge(Vec3::ZERO), hi, lo);
            p.dot(v) >= 0.0
        });
        if !visible {
            continue;
        }
        let closest = Vec3::ZERO.clamp(lo, hi);
        let d = closest.length().max(model.grid.cube * 1e-3);
        let e = model.metric[i as usize].max(0.0).sqrt();
        let px = e * camera.viewport_height / (2.0 * d * tan_v);
        if px > tol {
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
        // Nodes that expand together (crack-free only as a group).
        let k = model.prio[i as usize];
        if k != u32::MAX && !std::mem::replace(&mut group_pushed[k as usize], true) {
            stack.extend_from_slice(model.group(k as usize));
        }
    }
    expanded
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
    ///   deterministic. A camera looking away from
    ///   the model gives a coarse cut, never an empty one (unless the
    ///   model is empty).
    /// - Cost: `O(nodes)` per call (one pass over the nodes, then the
    ///   closure), and one `Vec<bool>` of `nodes` flags allocated per call.
    pub fn extract_view(&self, camera: &Camera, tolerance_px: f32, out: &mut Vec<u32>) -> usize {
        let flags = select(self, camera, tolerance_px);
        self.extract_expanded(&flags, out);
        flags.iter().filter(|&&e| e).count()
    }
}
