//! Octree carving — §8.1.1 of Yemez & Schmitt after Szeliski (1993) and
//! Schmitt & Yemez (1999); the visual hull of Laurentini (1994).
//!
//! The root cube is classified, then the unresolved cubes level by level
//! down to `R`: a cube whose footprint holds no object pixel in one view
//! is OUT, a cube whose footprint is object pixels only in every view is
//! IN, any other is subdivided; the unresolved cubes at level `R` are the
//! surface (ON). Each cube is classified in parallel (rayon), each test
//! is four reads of the view's summed-area table ([`Sat`]).
//!
//! **Conservative footprint.** The cube's 8 corners are projected
//! (pinhole), their bounding rectangle in normalised coordinates is
//! inflated by the lens's largest distortion displacement over it
//! ([`Lens::displacement_bound`]), mapped to pixels and inflated by the
//! silhouette margin (one pixel by default: a rendered mask's edge can
//! pass a point by up to a pixel), and covers pixels `⌊u0⌋..=⌊u1⌋`. The
//! pinhole image of a cube in front of the camera is the convex hull of
//! its corners' images, so the rectangle holds every pixel the cube
//! reaches: a cube is never called OUT while any part of it projects into
//! every silhouette. A cube with a corner closer than the near plane is
//! never carved by that view (nor IN); one wholly behind it is OUT (the
//! object must lie in front of every camera). Pixels outside an image are
//! background (the object must lie inside every view).
//!
//! **Consequence.** An IN and an OUT cube never touch: a shared point
//! projects into a pixel both rectangles hold, which cannot be object in
//! every view and background in one. So every cube that was subdivided
//! but kept no ON descendant is wholly IN or wholly OUT, and the labels
//! give the existing thinning (§4.3) a consistent IN/OUT/ON octree with
//! no flood fill (the paper's point about volumetric inputs, §8.1.2).
//!
//! **Departure: leaf refinement.** The rectangle over-estimates the
//! footprint by up to a cube's projected width, which would leave a band
//! of ON leaves outside the hull. Each ON leaf is therefore sampled at
//! 4×4×4 points, each tested against every silhouette (point tests, one
//! SAT read each): a leaf none of whose points lies in the hull is OUT.
//! The points are also the hull samples the particle's vertex is the
//! centre of gravity of ([`super::attributes`]).
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::octree::{Frame, Label, MortonMap, morton, unmorton};
use crate::silhouette::sat::Sat;
use lodkit_mesh::io::cameras::View;

/// Points per axis of a leaf's refinement sampling (64 points: one `u64`).
pub const SUB: usize = 4;

/// The classification of one cube.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Class {
    /// Wholly outside one silhouette's cone.
    Out,
    /// Wholly inside every cone.
    In,
    /// Neither: subdivided, or ON at level `R`.
    Partial,
}

/// The views and their tables, as the carver tests them.
pub struct Carver<'a> {
    /// Calibrated views.
    pub views: &'a [View],
    /// One table per view.
    pub sats: &'a [Sat],
    /// Footprint inflation in pixels.
    pub margin: f64,
    /// Near-plane depth, world units.
    pub near: f64,
}

impl Carver<'_> {
    /// Classifies the box `[lo, hi]`.
    pub fn classify(&self, lo: DVec3, hi: DVec3) -> Class {
        let mut inside_all = true;
        for (v, sat) in self.views.iter().zip(self.sats) {
            match self.classify_in(v, sat, lo, hi) {
                Class::Out => return Class::Out,
                Class::Partial => inside_all = false,
                Class::In => {}
            }
        }
        if inside_all {
            Class::In
        } else {
            Class::Partial
        }
    }

    pub(crate) fn classify_in(&self, v: &View, sat: &Sat, lo: DVec3, hi: DVec3) -> Class {
        let mut behind = 0;
        let mut near = false;
        let (mut x0, mut x1, mut y0, mut y1) = (f64::MAX, f64::MIN, f64::MAX, f64::MIN);
        for k in 0..8 {
            let p = DVec3::new(
                if k & 1 == 0 { lo.x } else { hi.x },
                if k & 2 == 0 { lo.y } else { hi.y },
                if k & 4 == 0 { lo.z } else { hi.z },
            );
            let c = v.to_camera(p);
            behind += usize::from(c.z <= 0.0);
            if c.z < self.near {
                near = true;
                continue;
            }
            let (x, y) = (c.x / c.z, c.y / c.z);
            x0 = x0.min(x);
            x1 = x1.max(x);
            y0 = y0.min(y);
            y1 = y1.max(y);
        }
        if behind == 8 {
            return Class::Out;
        }
        if near {
            return Class::Partial;
        }
        let l = &v.lens;
        let (dx, dy) = if l.distorted() {
            l.displacement_bound(x0, x1, y0, y1)
        } else {
            (0.0, 0.0)
        };
        let u0 = l.fx * (x0 - dx) + l.cx - self.margin;
        let u1 = l.fx * (x1 + dx) + l.cx + self.margin;
        let v0 = l.fy * (y0 - dy) + l.cy - self.margin;
        let v1 = l.fy * (y1 + dy) + l.cy + self.margin;
        // `as` saturates: far-off rectangles stay far off.
        let (i0, i1, j0, j1) = (
            u0.floor() as i64,
            u1.floor() as i64,
            v0.floor() as i64,
            v1.floor() as i64,
        );
        let n = sat.count(i0, j0, i1, j1);
        if n == 0 {
            return Class::Out;
        }
        let (w, h) = (i64::from(sat.width()), i64::from(sat.height()));
        if i0 < 0 || j0 < 0 || i1 >= w || j1 >= h {
            return Class::Partial;
        }
        let area = ((i1 - i0 + 1) * (j1 - j0 + 1)) as u64;
        if n == area { Class::In } else { Class::Partial }
    }

    /// Whether a point lies in view `k`'s silhouette (dilated by the margin).
    pub fn contains_in(&self, k: usize, p: DVec3) -> bool {
        let m = self.margin.ceil() as i64;
        let Some((u, w)) = self.views[k].project(p) else {
            return false;
        };
        if !(u.is_finite() && w.is_finite()) {
            return false;
        }
        let (i, j) = (u.floor() as i64, w.floor() as i64);
        self.sats[k].count(i - m, j - m, i + m, j + m) > 0
    }
}

/// The box of cell `m` at level `r` of `frame`, world units.
pub fn cell_box(frame: &Frame, r: u8, m: u64) -> (DVec3, DVec3) {
    let c = unmorton(m);
    let s = f64::from(frame.size) / (1u64 << r) as f64;
    let o = frame.origin.as_dvec3();
    let lo = o + DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) * s;
    (lo, lo + DVec3::splat(s))
}

/// What carving leaves: the ON leaves with their refinement samples, and
/// the IN/OUT label of every classified cube.
pub struct Carved {
    /// Octree resolution.
    pub depth: u8,
    /// Sorted Morton codes of the ON leaves.
    pub leaves: Vec<u64>,
    /// Per leaf: bit `i + 4j + 16k` set when refinement point `(i, j, k)`
    /// lies in the hull.
    pub inside: Vec<u64>,
    /// Per level: the cubes found IN or OUT there.
    pub decided: Vec<MortonMap<Label>>,
    /// Cubes classified per level (the carving's work).
    pub tested: Vec<usize>,
}

impl Carved {
    /// Label of a cube at level `r` that is not ON: its own, or (for one
    /// subdivided that kept no ON leaf, wholly IN or OUT by the module's
    /// argument) that of its first child, recursively.
    pub fn label(&self, r: u8, m: u64) -> Label {
        let (mut r, mut m) = (r as usize, m);
        loop {
            if let Some(&l) = self.decided[r].get(&m) {
                return l;
            }
            if r >= self.depth as usize {
                return Label::Out;
            }
            r += 1;
            m <<= 3;
        }
    }
}

/// Most work one carving may do, in units of about 40 ns on one core (a
/// few seconds): a cube tested against a view costs [`CUBE_TEST_COST`], a
/// leaf's 64 refinement points against a view [`LEAF_TEST_COST`] (every
/// view counted, an upper bound). 8 views of 128² carve to depth 7 in
/// about 3 s; depth 8 (13 s of carving) is refused, as is finding the
/// common view of 10,000 views. The work is counted before each level is
/// allocated, so the time and the memory of the frontier stay bounded.
pub const MAX_CARVE_TESTS: u64 = 1 << 27;
/// What testing one cube against one view costs (its 8 corners
/// projected, the lens's distortion bound, four table reads).
pub const CUBE_TEST_COST: u64 = 4;
/// What the refinement of one leaf against one view costs (64 points).
pub const LEAF_TEST_COST: u64 = 16;

/// Carves the cube of `frame` to level `depth`. Errors: the tests it
/// would make, once they would pass [`MAX_CARVE_TESTS`] (checked before
/// each level is allocated), with the level it had reached.
pub fn carve(c: &Carver<'_>, frame: &Frame, depth: u8) -> Result<Carved, (u64, u8)> {
    let mut decided: Vec<MortonMap<Label>> = vec![MortonMap::default(); depth as usize + 1];
    let mut tested = Vec::with_capacity(depth as usize + 1);
    let mut frontier: Vec<u64> = vec![0];
    let mut partial: Vec<u64> = Vec::new();
    let views = c.views.len() as u64;
    let mut work = 0u64;
    let mut spend = |tests: u64, r: u8| {
        work = work.saturating_add(tests);
        if work > MAX_CARVE_TESTS {
            Err((work, r))
        } else {
            Ok(())
        }
    };
    for r in 0..=depth {
        tested.push(frontier.len());
        let classes: Vec<Class> = frontier
            .par_iter()
            .map(|&m| {
                let (lo, hi) = cell_box(frame, r, m);
                c.classify(lo, hi)
            })
            .collect();
        partial.clear();
        let d = &mut decided[r as usize];
        for (&m, cl) in frontier.iter().zip(&classes) {
            match cl {
                Class::Out => {
                    d.insert(m, Label::Out);
                }
                Class::In => {
                    d.insert(m, Label::In);
                }
                Class::Partial => partial.push(m),
            }
        }
        if r < depth {
            spend(
                (partial.len() as u64 * 8).saturating_mul(views * CUBE_TEST_COST),
                r + 1,
            )?;
            frontier = partial
                .iter()
                .flat_map(|&p| (0..8).map(move |k| (p << 3) | k))
                .collect();
        }
    }
    spend(
        (partial.len() as u64).saturating_mul(views * LEAF_TEST_COST),
        depth,
    )?;
    // Leaf refinement (see the module docs). Only the views whose own
    // footprint test left the leaf unresolved are asked about its points:
    // a view that holds the whole rectangle holds every point's window.
    let inside: Vec<u64> = partial
        .par_iter()
        .map(|&m| {
            let (lo, hi) = cell_box(frame, depth, m);
            let mut open = Vec::new();
            for (k, (v, sat)) in c.views.iter().zip(c.sats).enumerate() {
                match c.classify_in(v, sat, lo, hi) {
                    Class::Out => return 0,
                    Class::Partial => open.push(k),
                    Class::In => {}
                }
            }
            let mut bits = 0u64;
            for k in 0..SUB {
                for j in 0..SUB {
                    for i in 0..SUB {
                        let t = DVec3::new(i as f64, j as f64, k as f64) + 0.5;
                        let p = lo + (hi - lo) * t / SUB as f64;
                        if open.iter().all(|&v| c.contains_in(v, p)) {
                            bits |= 1 << (i + SUB * j + SUB * SUB * k);
                        }
                    }
                }
            }
            bits
        })
        .collect();
    let mut leaves = Vec::with_capacity(partial.len());
    let mut kept = Vec::with_capacity(partial.len());
    for (&m, &b) in partial.iter().zip(&inside) {
        if b == 0 {
            decided[depth as usize].insert(m, Label::Out);
        } else {
            leaves.push(m);
            kept.push(b);
        }
    }
    Ok(Carved {
        depth,
        leaves,
        inside: kept,
        decided,
        tested,
    })
}

/// The box of the cubes not carved at level `level` of `frame`, one cube
/// wider on every side, or `None` when every cube was carved. Also says
/// whether that box touches the cube's boundary (the common view is not
/// bounded inside it).
///
/// Errors: the cube tests, once they would pass [`MAX_CARVE_TESTS`], with
/// the level reached (as [`carve`]).
#[allow(clippy::type_complexity)]
pub fn hull_box(
    c: &Carver<'_>,
    frame: &Frame,
    level: u8,
) -> Result<Option<((Vec3, Vec3), bool)>, (u64, u8)> {
    let carved = carve_coarse(c, frame, level)?;
    let side = 1u32 << level;
    let mut lo = [u32::MAX; 3];
    let mut hi = [0u32; 3];
    for m in carved {
        let p = unmorton(m);
        for a in 0..3 {
            lo[a] = lo[a].min(p[a]);
            hi[a] = hi[a].max(p[a]);
        }
    }
    if lo[0] == u32::MAX {
        return Ok(None);
    }
    let touches = (0..3).any(|a| lo[a] == 0 || hi[a] == side - 1);
    let s = frame.size / side as f32;
    let min = frame.origin + Vec3::new(lo[0] as f32, lo[1] as f32, lo[2] as f32) * s - s;
    let max = frame.origin
        + Vec3::new(hi[0] as f32 + 1.0, hi[1] as f32 + 1.0, hi[2] as f32 + 1.0) * s
        + s;
    Ok(Some(((min, max), touches)))
}

/// Cubes at `level` that are not OUT (IN cubes of coarser levels are
/// expanded), without leaf refinement.
fn carve_coarse(c: &Carver<'_>, frame: &Frame, level: u8) -> Result<Vec<u64>, (u64, u8)> {
    let mut keep = Vec::new();
    let mut frontier: Vec<u64> = vec![0];
    let views = c.views.len() as u64;
    let mut work = 0u64;
    for r in 0..=level {
        work = work.saturating_add((frontier.len() as u64).saturating_mul(views * CUBE_TEST_COST));
        if work > MAX_CARVE_TESTS {
            return Err((work, r));
        }
        let classes: Vec<Class> = frontier
            .par_iter()
            .map(|&m| {
                let (lo, hi) = cell_box(frame, r, m);
                c.classify(lo, hi)
            })
            .collect();
        let mut next = Vec::new();
        for (&m, cl) in frontier.iter().zip(&classes) {
            match cl {
                Class::Out => {}
                Class::In => {
                    // Its extreme corners suffice for the box.
                    let s = level - r;
                    let p = unmorton(m);
                    let far = (1u32 << s) - 1;
                    keep.push(morton(p.map(|v| v << s)));
                    keep.push(morton(p.map(|v| (v << s) + far)));
                }
                Class::Partial if r == level => keep.push(m),
                Class::Partial => next.extend((0..8).map(|k| (m << 3) | k)),
            }
        }
        frontier = next;
    }
    Ok(keep)
}
