//! Memoryless quadric error metrics (HQMS §3.4, after Lindstrom & Turk 1999)
//! and their attribute extension (Garland & Heckbert 1998, Hoppe 1999).
//!
//! A vertex quadric is never stored: [`Quadric`]s are summed on the fly from
//! the *current* faces of a ring (eq. 4) each time a cost or a placement is
//! needed, so the whole-mesh quadric table of QSlim (40 B/vertex) does not
//! exist.
//!
//! Departures from the paper, and why:
//! - Face planes are weighted by the triangle's area (QSlim's choice; the
//!   paper uses unit weights), so a sliver does not count as much as a large
//!   face and costs stay meaningful as faces grow over the passes.
//! - Border edges add a plane through the edge perpendicular to its face,
//!   weighted by the squared edge length × [`BORDER_WEIGHT`]
//!   (Garland & Heckbert 1997 §6.1): without it, open rims erode.
//! - Everything is evaluated in `f64` relative to the ring's centre vertex,
//!   so far-from-origin scans lose no precision.
//! - When attributes are present the cost of moving a ring's vertex to a
//!   neighbour is the area-weighted squared distance, in the joint space
//!   (position, weighted attributes), from the moved point to each face's
//!   2-plane — the value of Garland–Heckbert's extended quadric, computed
//!   directly from the face instead of from a stored (3+k)² matrix.

use glam::DVec3;

/// Border planes weigh this many times the squared edge length: enough
/// that a rim vertex slides along the rim rather than inward (an open base,
/// like the bunny's, otherwise shrinks and dominates the max error). With
/// hole filling on, a hole therefore closes once the triangles around it
/// are larger than the hole: tiny scanner holes close early, openings the
/// size of the model stay until the last levels.
pub const BORDER_WEIGHT: f64 = 10.0;

/// A symmetric 4×4 quadric `vᵀ A v + 2 bᵀ v + c` stored as its 10
/// independent coefficients: `[a00 a01 a02 a11 a12 a22 b0 b1 b2 c]`.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Quadric {
    pub m: [f64; 10],
}

impl Quadric {
    pub const ZERO: Quadric = Quadric { m: [0.0; 10] };

    /// `w · (n·v + d)²` for the plane `n·v + d = 0` (`n` unit).
    #[cfg(test)]
    pub fn plane(n: DVec3, d: f64, w: f64) -> Quadric {
        let (a, b, c) = (n.x, n.y, n.z);
        Quadric {
            m: [
                w * a * a,
                w * a * b,
                w * a * c,
                w * b * b,
                w * b * c,
                w * c * c,
                w * a * d,
                w * b * d,
                w * c * d,
                w * d * d,
            ],
        }
    }

    /// Adds `w · (n·v + d)²` without building the intermediate quadric.
    #[inline]
    pub fn add_plane(&mut self, n: DVec3, d: f64, w: f64) {
        self.add_plane_through_origin(n, w);
        let (a, b, c) = (n.x * w, n.y * w, n.z * w);
        let m = &mut self.m;
        m[6] += a * d;
        m[7] += b * d;
        m[8] += c * d;
        m[9] += w * d * d;
    }

    /// [`add_plane`](Self::add_plane) with `d = 0`: only the quadratic
    /// part changes.
    #[inline]
    pub fn add_plane_through_origin(&mut self, n: DVec3, w: f64) {
        let (a, b, c) = (n.x * w, n.y * w, n.z * w);
        let m = &mut self.m;
        m[0] += a * n.x;
        m[1] += a * n.y;
        m[2] += a * n.z;
        m[3] += b * n.y;
        m[4] += b * n.z;
        m[5] += c * n.z;
    }

    /// Adds `other`, a quadric whose planes all pass through its frame's
    /// origin (linear and constant parts zero), after moving that origin
    /// to `o` in this quadric's frame: `other(v - o)` for every `v`.
    #[inline]
    pub fn add_translated_from_origin(&mut self, other: &Quadric, o: DVec3) {
        let a = &other.m;
        // A o, then b = -A o and c = oᵀ A o.
        let ao = DVec3::new(
            a[0] * o.x + a[1] * o.y + a[2] * o.z,
            a[1] * o.x + a[3] * o.y + a[4] * o.z,
            a[2] * o.x + a[4] * o.y + a[5] * o.z,
        );
        let m = &mut self.m;
        for i in 0..6 {
            m[i] += a[i];
        }
        m[6] -= ao.x;
        m[7] -= ao.y;
        m[8] -= ao.z;
        m[9] += o.dot(ao);
    }

    /// The quadric's value at `v` (eq. 3). Never negative in exact
    /// arithmetic; rounding can give tiny negatives, clamped to 0.
    #[inline]
    pub fn eval(&self, v: DVec3) -> f64 {
        let m = &self.m;
        let (x, y, z) = (v.x, v.y, v.z);
        let r = x * (m[0] * x + 2.0 * (m[1] * y + m[2] * z + m[6]))
            + y * (m[3] * y + 2.0 * (m[4] * z + m[7]))
            + z * (m[5] * z + 2.0 * m[8])
            + m[9];
        r.max(0.0)
    }

    /// [`eval`](Self::eval) of a quadric whose planes all pass through the
    /// origin (linear and constant parts zero, as in a ring's own frame):
    /// the same value from the quadratic part alone.
    #[inline]
    pub fn eval_through_origin(&self, v: DVec3) -> f64 {
        let m = &self.m;
        let (x, y, z) = (v.x, v.y, v.z);
        let r = x * (m[0] * x + 2.0 * (m[1] * y + m[2] * z))
            + y * (m[3] * y + 2.0 * (m[4] * z))
            + z * (m[5] * z);
        r.max(0.0)
    }

    /// The minimiser of the quadric, solving `A v = -b` (the gradient
    /// condition under eq. 5). `None` when `A` is singular relative to its
    /// own scale (flat or ridge-shaped neighbourhoods).
    pub fn optimum(&self) -> Option<DVec3> {
        let m = &self.m;
        let (a00, a01, a02, a11, a12, a22) = (m[0], m[1], m[2], m[3], m[4], m[5]);
        let c00 = a11 * a22 - a12 * a12;
        let c01 = a02 * a12 - a01 * a22;
        let c02 = a01 * a12 - a02 * a11;
        let det = a00 * c00 + a01 * c01 + a02 * c02;
        let scale = (a00 + a11 + a22) / 3.0;
        if !(det.abs() > 1e-6 * scale * scale * scale) || scale <= 0.0 {
            return None;
        }
        let c11 = a00 * a22 - a02 * a02;
        let c12 = a01 * a02 - a00 * a12;
        let c22 = a00 * a11 - a01 * a01;
        let (b0, b1, b2) = (-m[6], -m[7], -m[8]);
        let inv = 1.0 / det;
        let v = DVec3::new(
            (c00 * b0 + c01 * b1 + c02 * b2) * inv,
            (c01 * b0 + c11 * b1 + c12 * b2) * inv,
            (c02 * b0 + c12 * b1 + c22 * b2) * inv,
        );
        v.is_finite().then_some(v)
    }

    /// The minimiser on the segment `a + λ (b - a)`, `λ ∈ [0, 1]`, and its
    /// `λ`: a 1-D quadratic that always has a solution, used when
    /// [`optimum`](Self::optimum) is singular or rejected by eq. (9).
    pub fn segment_minimum(&self, a: DVec3, b: DVec3) -> (DVec3, f64) {
        let e = b - a;
        // q(λ) = q(a) + 2λ eᵀ(A a + b) + λ² eᵀ A e.
        let m = &self.m;
        let ae = DVec3::new(
            m[0] * e.x + m[1] * e.y + m[2] * e.z,
            m[1] * e.x + m[3] * e.y + m[4] * e.z,
            m[2] * e.x + m[4] * e.y + m[5] * e.z,
        );
        let eae = e.dot(ae);
        let grad = DVec3::new(
            m[0] * a.x + m[1] * a.y + m[2] * a.z + m[6],
            m[1] * a.x + m[3] * a.y + m[4] * a.z + m[7],
            m[2] * a.x + m[4] * a.y + m[5] * a.z + m[8],
        )
        .dot(e);
        let lambda = if eae > 0.0 {
            (-grad / eae).clamp(0.0, 1.0)
        } else if grad < 0.0 {
            1.0
        } else {
            0.0
        };
        let lambda = if lambda.is_finite() { lambda } else { 1.0 };
        (a + e * lambda, lambda)
    }
}

/// Unit normal, plane offset and area of the triangle `(a, b, c)` (any
/// frame). `None` for a zero-area triangle.
#[cfg(test)]
pub fn triangle_plane(a: DVec3, b: DVec3, c: DVec3) -> Option<(DVec3, f64, f64)> {
    let n = (b - a).cross(c - a);
    let len = n.length();
    if !(len > 0.0) {
        return None;
    }
    let n = n / len;
    Some((n, -n.dot(a), 0.5 * len))
}

/// Adds the border constraint plane of edge `a → b` of a face with unit
/// normal `n` (a plane through the edge, perpendicular to the face).
#[inline]
pub fn add_border_plane(q: &mut Quadric, a: DVec3, b: DVec3, n: DVec3, weight: f64) {
    let e = b - a;
    let len2 = e.length_squared();
    let p = e.cross(n);
    let pl = p.length();
    if !(pl > 0.0) {
        return;
    }
    let p = p / pl;
    q.add_plane(p, -p.dot(a), weight * len2);
}

/// Largest attribute vector a vertex can carry: normal (3) + RGBA (4) + UV (2).
pub const MAX_ATTR: usize = 9;
/// Dimension of the joint (position, attributes) space.
pub const MAX_DIM: usize = 3 + MAX_ATTR;

/// One face's extended-quadric frame in the joint space of dimension
/// `3 + k`: the corner `q0` and an orthonormal basis `e1, e2` of the
/// face's 2-plane (Garland–Heckbert 1998 §3).
#[derive(Debug, Clone, Copy)]
pub struct ExtendedFace {
    q0: [f64; MAX_DIM],
    e1: [f64; MAX_DIM],
    e2: [f64; MAX_DIM],
    area: f64,
}

impl ExtendedFace {
    /// Builds the frame from three joint-space points (first `dim`
    /// entries used) and the face's geometric area (the weight). `None`
    /// when the points are collinear in the joint space.
    pub fn new(p: [&[f64; MAX_DIM]; 3], dim: usize, area: f64) -> Option<ExtendedFace> {
        let mut e1 = [0.0; MAX_DIM];
        let mut e2 = [0.0; MAX_DIM];
        for i in 0..dim {
            e1[i] = p[1][i] - p[0][i];
            e2[i] = p[2][i] - p[0][i];
        }
        let l1 = dot(&e1, &e1, dim).sqrt();
        if !(l1 > 0.0) {
            return None;
        }
        for x in e1.iter_mut().take(dim) {
            *x /= l1;
        }
        let d = dot(&e1, &e2, dim);
        for i in 0..dim {
            e2[i] -= d * e1[i];
        }
        let l2 = dot(&e2, &e2, dim).sqrt();
        if !(l2 > 1e-12 * l1) {
            return None;
        }
        for x in e2.iter_mut().take(dim) {
            *x /= l2;
        }
        Some(ExtendedFace {
            q0: *p[0],
            e1,
            e2,
            area,
        })
    }

    /// `area × squared distance` from `x` to the face's 2-plane.
    #[inline]
    pub fn cost(&self, x: &[f64; MAX_DIM], dim: usize) -> f64 {
        let mut r = [0.0; MAX_DIM];
        for i in 0..dim {
            r[i] = x[i] - self.q0[i];
        }
        let a = dot(&r, &self.e1, dim);
        let b = dot(&r, &self.e2, dim);
        self.area * (dot(&r, &r, dim) - a * a - b * b).max(0.0)
    }
}

#[inline]
fn dot(a: &[f64; MAX_DIM], b: &[f64; MAX_DIM], dim: usize) -> f64 {
    let mut s = 0.0;
    for i in 0..dim {
        s += a[i] * b[i];
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plane_quadric_measures_squared_distance() {
        let q = Quadric::plane(DVec3::Z, -1.0, 2.0); // z = 1, weight 2
        assert!((q.eval(DVec3::new(5.0, -3.0, 4.0)) - 2.0 * 9.0).abs() < 1e-12);
        assert_eq!(q.eval(DVec3::new(0.3, 0.2, 1.0)), 0.0);
    }

    #[test]
    fn optimum_of_three_planes_is_their_intersection() {
        let mut q = Quadric::ZERO;
        q.add_plane(DVec3::X, -1.0, 1.0);
        q.add_plane(DVec3::Y, -2.0, 1.0);
        q.add_plane(DVec3::Z, -3.0, 1.0);
        let v = q.optimum().unwrap();
        assert!((v - DVec3::new(1.0, 2.0, 3.0)).length() < 1e-9);
    }

    #[test]
    fn flat_neighbourhood_is_singular_and_falls_back_to_the_segment() {
        let mut q = Quadric::ZERO;
        q.add_plane(DVec3::Z, 0.0, 1.0);
        q.add_plane(DVec3::Z, 0.0, 3.0);
        assert!(q.optimum().is_none());
        let (p, l) = q.segment_minimum(DVec3::new(0.0, 0.0, 1.0), DVec3::new(0.0, 0.0, -1.0));
        assert!((l - 0.5).abs() < 1e-12 && p.length() < 1e-12);
    }

    #[test]
    fn extended_face_without_attributes_matches_the_plane_quadric() {
        let (a, b, c) = (
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(2.0, 0.0, 0.5),
            DVec3::new(0.0, 1.0, 0.2),
        );
        let (n, d, area) = triangle_plane(a, b, c).unwrap();
        let q = Quadric::plane(n, d, area);
        let pt = |v: DVec3| {
            let mut p = [0.0; MAX_DIM];
            p[..3].copy_from_slice(&v.to_array());
            p
        };
        let f = ExtendedFace::new([&pt(a), &pt(b), &pt(c)], 3, area).unwrap();
        let x = DVec3::new(0.3, -0.7, 1.9);
        assert!((f.cost(&pt(x), 3) - q.eval(x)).abs() < 1e-9);
    }

    #[test]
    fn extended_face_charges_attribute_differences() {
        let mut p = [[0.0; MAX_DIM]; 3];
        p[1][0] = 1.0;
        p[2][1] = 1.0; // flat triangle in z = 0, attribute (index 3) = 0
        let f = ExtendedFace::new([&p[0], &p[1], &p[2]], 4, 0.5).unwrap();
        let mut x = [0.0; MAX_DIM];
        x[0] = 0.2;
        x[1] = 0.2;
        assert_eq!(f.cost(&x, 4), 0.0);
        x[3] = 2.0;
        assert!((f.cost(&x, 4) - 0.5 * 4.0).abs() < 1e-12);
    }
}
