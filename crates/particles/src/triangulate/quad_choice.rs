//! Construction rules of the planar configurations — §6.1.3 of Yemez &
//! Schmitt.
//!
//! `C_1–C_3` give their triangle. `C_4, C_5` (quads) pick the diagonal
//! with the smaller dihedral angle, or, when the particles carry normals,
//! the one whose triangles agree best with them ([`choose_quad`]). A planar
//! configuration lying on a face of its neighbourhood has one owner: the
//! neighbourhood that sees it on its lower face, unless the neighbourhood
//! across that face is a solid (`C_6+`) configuration, whose disc then
//! covers the face alone ([`defer_face`]; the paper leaves this implicit:
//! without it every flat patch would be emitted twice, and a patch shared
//! with an ambiguous neighbourhood covered twice).
use glam::Vec3;

use super::window::Window;
use crate::triangulation_table::Table;

/// Whether a planar configuration lying on a face of its neighbourhood
/// leaves that face to the neighbourhood on the other side: always when it
/// is the upper face (the other side sees it as its lower face), and when
/// the other side is a solid configuration, whose disc choice then covers
/// the face alone (two owners would cover it twice).
/// `face`: [`Compact::face`], not 0.
#[inline]
pub(super) fn defer_face(t: &Table, w: &Window, o: [usize; 3], face: u8) -> bool {
    if face == 1 {
        return true;
    }
    let mut across = o;
    across[usize::from(face - 2) % 3] -= 1;
    let m = w.mask(across);
    t.solid[usize::from(m >> 6)] & (1 << (m & 63)) != 0
}

/// The two triangulations of a quad `a b c d`; returns the better one.
#[inline]
pub(super) fn choose_quad(q: [u8; 4], p: [Vec3; 4], n: Option<[Vec3; 4]>) -> ([u8; 3], [u8; 3]) {
    let ac = ([q[0], q[1], q[2]], [q[0], q[2], q[3]]);
    let bd = ([q[0], q[1], q[3]], [q[1], q[2], q[3]]);
    let (s_ac, s_bd) = match n {
        Some(_) => (
            quad_split_score(&p, n.as_ref(), [0, 1, 2], [0, 2, 3]),
            quad_split_score(&p, n.as_ref(), [0, 1, 3], [1, 2, 3]),
        ),
        None => quad_dihedral_scores(&p),
    };
    // Picked without a branch: the comparison waits on a square root and
    // a division, and a mispredicted guess would throw that wait away.
    let m = 0u8.wrapping_sub(u8::from(s_ac <= s_bd));
    let pick = |a: [u8; 3], b: [u8; 3]| [0, 1, 2].map(|k| (a[k] & m) | (b[k] & !m));
    (pick(ac.0, bd.0), pick(ac.1, bd.1))
}

/// [`quad_split_score`] without normals for both splits at once: the four
/// triangle normals (unnormalised) side by side in the lanes of `Vec4`s,
/// with each lane's operations those of the scalar code in the same order
/// (`Vec3::cross`, `Vec3::dot`), so the scores have the same bits.
#[inline(always)]
pub(super) fn quad_dihedral_scores(p: &[Vec3; 4]) -> (f32, f32) {
    use glam::Vec4;
    // Lanes: triangles 0 1 2 and 0 2 3 (split a–c), 0 1 3 and 1 2 3 (b–d);
    // edge vectors `a = p[t1] − p[t0]`, `b = p[t2] − p[t0]`.
    let lanes = |c: fn(Vec3) -> f32| {
        let (p0, p1, p2, p3) = (c(p[0]), c(p[1]), c(p[2]), c(p[3]));
        let origin = Vec4::new(p0, p0, p0, p1);
        (
            Vec4::new(p1, p2, p1, p2) - origin,
            Vec4::new(p2, p3, p3, p3) - origin,
        )
    };
    let (ax, bx) = lanes(|v| v.x);
    let (ay, by) = lanes(|v| v.y);
    let (az, bz) = lanes(|v| v.z);
    let nx = ay * bz - by * az;
    let ny = az * bx - bz * ax;
    let nz = ax * by - bx * ay;
    // Each lane times its partner (0 with 1, 2 with 3).
    let partner = |v: Vec4| Vec4::new(v.y, v.x, v.w, v.z);
    let squared = nx * nx + ny * ny + nz * nz;
    let dots = nx * partner(nx) + ny * partner(ny) + nz * partner(nz);
    let l = (squared * partner(squared)).sqrt();
    let score = |k: usize| {
        if l[k] > 0.0 { -dots[k] / l[k] } else { 0.0 }
    };
    (score(0), score(2))
}

/// How badly the triangles `t0`, `t1` of a quad split fit: their
/// disagreement with the particle normals, or without normals their
/// dihedral angle (its cosine, negated: same order, no `acos`; one square
/// root).
#[inline(always)]
pub(super) fn quad_split_score(
    p: &[Vec3; 4],
    n: Option<&[Vec3; 4]>,
    t0: [usize; 3],
    t1: [usize; 3],
) -> f32 {
    let cross = |t: [usize; 3]| (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
    let (m1, m2) = (cross(t0), cross(t1));
    match n {
        Some(vn) => {
            let (n1, n2) = (m1.normalize_or_zero(), m2.normalize_or_zero());
            let s1: f32 = t0.iter().map(|&i| 1.0 - n1.dot(vn[i]).abs()).sum();
            let s2: f32 = t1.iter().map(|&i| 1.0 - n2.dot(vn[i]).abs()).sum();
            s1 + s2
        }
        None => {
            let l = (m1.length_squared() * m2.length_squared()).sqrt();
            if l > 0.0 { -m1.dot(m2) / l } else { 0.0 }
        }
    }
}
