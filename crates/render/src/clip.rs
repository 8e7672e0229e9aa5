//! Triangle setup: camera-space vertices, clipping against the near plane
//! and a guard band, projection and snapping to fixed point.
//!
//! Clipping happens in camera space, where the planes are linear, so the
//! clipped polygon is exact up to `f32`; every clipped vertex carries its
//! barycentric coordinates in the *original* face, which lets the shader
//! look attributes up by face and barycentrics whether or not the face was
//! clipped. The guard band (one image size beyond each border) keeps the
//! snapped coordinates small enough that the edge functions of
//! [`raster`](crate::raster) are exact in `i64`.

use glam::{Vec3, Vec4};

use crate::camera::Intrinsics;

/// Sub-pixel precision of snapped vertex coordinates: 1/256 of a sample.
pub(crate) const SUBPIXEL_BITS: u32 = 8;
/// One sample in fixed-point units.
pub(crate) const ONE: i64 = 1 << SUBPIXEL_BITS;

/// A triangle ready for the edge functions: snapped screen positions (in
/// sample units × [`ONE`]; sample `(i, j)` has its centre at
/// `((i + ½)·ONE, (j + ½)·ONE)`), inverse depths, and each corner's
/// barycentric coordinates in the source face `face`.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ScreenTri {
    pub face: u32,
    pub x: [i64; 3],
    pub y: [i64; 3],
    pub inv_z: [f32; 3],
    pub bary: [Vec3; 3],
}

impl ScreenTri {
    /// First and last sample rows the triangle can touch (inclusive,
    /// unclamped).
    pub fn rows(&self) -> (i64, i64) {
        let lo = self.y.iter().min().copied().unwrap_or(0);
        let hi = self.y.iter().max().copied().unwrap_or(0);
        (
            (lo - ONE / 2).div_euclid(ONE),
            (hi - ONE / 2).div_euclid(ONE) + 1,
        )
    }
}

/// The clip planes, as `a·x + b·y + c·z + d ≥ 0` in OpenCV camera
/// coordinates, for intrinsics `k` (already scaled to sample units).
pub(crate) fn clip_planes(k: &Intrinsics, near: f32) -> [Vec4; 5] {
    let (w, h) = (k.width as f32, k.height as f32);
    let (fx, fy, cx, cy) = (k.fx as f32, k.fy as f32, k.cx as f32, k.cy as f32);
    // Guard band: one image size beyond each border.
    let (gx, gy) = (w, h);
    [
        Vec4::new(0.0, 0.0, 1.0, -near),
        Vec4::new(fx, 0.0, cx + gx, 0.0),
        Vec4::new(-fx, 0.0, w + gx - cx, 0.0),
        Vec4::new(0.0, fy, cy + gy, 0.0),
        Vec4::new(0.0, -fy, h + gy - cy, 0.0),
    ]
}

#[inline]
fn side(plane: Vec4, p: Vec3) -> f32 {
    plane.truncate().dot(p) + plane.w
}

/// Projects a camera-space point (in front of the near plane) to snapped
/// sample coordinates.
#[inline]
pub(crate) fn snap(k: &Intrinsics, p: Vec3) -> (i64, i64) {
    let u = k.fx * p.x as f64 / p.z as f64 + k.cx;
    let v = k.fy * p.y as f64 / p.z as f64 + k.cy;
    (
        (u * ONE as f64).round() as i64,
        (v * ONE as f64).round() as i64,
    )
}

/// Clips the camera-space triangle `cam` (face `face`) and appends the
/// resulting screen triangles (none, one, or a fan of up to six) to `out`.
pub(crate) fn setup_triangle(
    face: u32,
    cam: [Vec3; 3],
    planes: &[Vec4; 5],
    k: &Intrinsics,
    out: &mut Vec<ScreenTri>,
) {
    let mut all_inside = true;
    for &pl in planes {
        let s = [side(pl, cam[0]), side(pl, cam[1]), side(pl, cam[2])];
        if s.iter().all(|&v| v < 0.0) {
            return;
        }
        all_inside &= s.iter().all(|&v| v >= 0.0);
    }
    let corners = [Vec3::X, Vec3::Y, Vec3::Z];
    if all_inside {
        push(face, &cam, &corners, k, out);
        return;
    }
    // Sutherland–Hodgman against each plane in turn; a triangle clipped by
    // five planes has at most eight corners.
    let mut poly: Vec<(Vec3, Vec3)> = (0..3).map(|i| (cam[i], corners[i])).collect();
    let mut next = Vec::with_capacity(8);
    for &pl in planes {
        next.clear();
        for i in 0..poly.len() {
            let (a, ba) = poly[i];
            let (b, bb) = poly[(i + 1) % poly.len()];
            let (sa, sb) = (side(pl, a), side(pl, b));
            if sa >= 0.0 {
                next.push((a, ba));
            }
            if (sa >= 0.0) != (sb >= 0.0) {
                let t = sa / (sa - sb);
                next.push((a + (b - a) * t, ba + (bb - ba) * t));
            }
        }
        std::mem::swap(&mut poly, &mut next);
        if poly.len() < 3 {
            return;
        }
    }
    for i in 1..poly.len() - 1 {
        let p = [poly[0].0, poly[i].0, poly[i + 1].0];
        let b = [poly[0].1, poly[i].1, poly[i + 1].1];
        push(face, &p, &b, k, out);
    }
}

fn push(face: u32, p: &[Vec3; 3], bary: &[Vec3; 3], k: &Intrinsics, out: &mut Vec<ScreenTri>) {
    let s = [snap(k, p[0]), snap(k, p[1]), snap(k, p[2])];
    out.push(ScreenTri {
        face,
        x: [s[0].0, s[1].0, s[2].0],
        y: [s[0].1, s[1].1, s[2].1],
        inv_z: [1.0 / p[0].z, 1.0 / p[1].z, 1.0 / p[2].z],
        bary: *bary,
    });
}
