//! The full edge collapse (HQMS §3.3 and §4.3.3, procedure `EdgeCollapse`)
//! with the dependency check of §4.3.1 (Strategy I) and two-stage
//! placement.
//!
//! `collapse(s → t)`: `I = r_s ∩ r_t` is deleted, `s` is replaced by `t` in
//! `S = r_s − I`, both rings become dirty, and `t` moves to the optimum of
//! the memoryless `Q_s + Q_t` (eq. 5) — solved only now that the collapse
//! is chosen — unless eq. (9) says the optimum lies outside the ball on
//! `v_s v_t` (numerical garbage), in which case the paper falls back to
//! `v_t`.
//!
//! Departures, and why (the paper has no validity tests at all):
//! - Fall-back placement: when the system is singular (flat or ridge
//!   neighbourhoods) or eq. (9) rejects the optimum, we minimise the quadric
//!   on the segment `v_s v_t` (a 1-D problem that always has a solution and
//!   contains `v_t`) instead of taking `v_t` outright; `v_t` stays the last
//!   resort.
//! - A placement is rejected if it flips the normal of any surviving face
//!   of `r_s ∪ r_t` or makes one degenerate; if every placement is rejected
//!   the collapse is refused (no fold-overs).
//! - Link condition: a collapse that would give an edge more than two faces
//!   (where it had at most two), merge two faces into duplicates, pinch two
//!   border vertices across an interior edge, or erase a whole component is
//!   refused. Two border edges may merge into one interior edge only with
//!   hole filling on (that is how holes close).
//! - Wedges (seams): each attribute wedge of `s` next to the edge is merged
//!   into the wedge of `t` across the same face of `I`. The collapse is
//!   refused when that mapping is ambiguous (a seam crossing the edge at
//!   `t`) or when `s` has a wedge away from the edge (a seam through `s`
//!   that does not follow the edge): seams then only shorten along
//!   themselves and both sides always stay welded.
//! - The object-space error of the new vertex is the larger of the two
//!   endpoints' accumulated errors plus the largest distance from the new
//!   position to the planes of the old faces of both rings; `max_error`
//!   refuses collapses above the bound.

use glam::{DVec3, Vec3A};

use crate::cost::{RingScan, Scratch, dpos, fpos};
use crate::options::Options;
use crate::quadric::Quadric;
use crate::ring_table::{DEAD, Flag, RingTable};
use crate::work_mesh::WorkMesh;

/// Why a record was not collapsed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Reject {
    /// A ring is dirty or gone (Strategy I), or the edge no longer exists.
    Dependency,
    /// Link condition, border rules or duplicate faces.
    Topology,
    /// Every placement flips or degenerates a face.
    Flip,
    /// Seam rules.
    Seam,
    /// Over `max_error`.
    MaxError,
}

/// Performs the collapse of `s` onto `t` if it is valid. Returns the number
/// of faces removed. With `scanned`, `sc.scan_s` already holds the current
/// ring of `s` in the frame of `v_s` (the cost stage's read, when the
/// record is collapsed right after it was costed); otherwise it is read
/// here.
pub fn collapse(
    m: &mut WorkMesh,
    rings: &RingTable,
    opts: &Options,
    s: u32,
    t: u32,
    sc: &mut Scratch,
    scanned: bool,
) -> Result<usize, Reject> {
    // Dependency check (Strategy I): dirty rings are not contracted.
    if m.flags[s as usize] != Flag::Valid
        || matches!(m.flags[t as usize], Flag::Dirty | Flag::Removed)
    {
        return Err(Reject::Dependency);
    }
    // Both rings read once, each in its own centre's frame (every face
    // plane of a ring passes through its centre there, see `cost.rs`);
    // the collapse works in the frame of v_s.
    let (ps, pt) = (dpos(m, s), dpos(m, t));
    let (psf, ptf) = (fpos(m, s), fpos(m, t));
    // v_t in the frame of v_s, from the same f32 difference the scans use.
    let ltf = ptf - psf;
    if !scanned {
        sc.scan_s.scan(m, rings.ring(s), s, psf);
    }
    debug_assert!(sc.scan_s.center == s && sc.scan_s.pc == Vec3A::ZERO);
    let m_st = sc.scan_s.m(t);
    if m_st == 0 {
        return Err(Reject::Dependency);
    }
    sc.scan_t.scan(m, rings.ring(t), t, ptf);
    let (ss, st) = (&sc.scan_s, &sc.scan_t);

    // Border rules.
    let s_border = ss.border();
    let t_border = st.border();
    if (s_border && (opts.lock_border || m_st != 1)) || m.is_locked(s) {
        return Err(Reject::Topology);
    }

    // The faces of I = r_s ∩ r_t, by their third vertex.
    sc.opp.clear();
    for rf in &ss.faces {
        if rf.a == t {
            sc.opp.push(rf.b);
        } else if rf.b == t {
            sc.opp.push(rf.a);
        }
    }
    // Link condition on every other neighbour w of s: c = faces of I that
    // contain w. The common neighbours are kept for the duplicate check.
    sc.common.clear();
    // One bit per neighbour of t (by the id's low bits): most neighbours of
    // s are not neighbours of t and skip the search of t's link.
    let bit = |v: u32| 1u64 << (v & 63);
    let t_links = st.links.iter().fold(0u64, |acc, l| acc | bit(l.v));
    for l in &ss.links {
        if l.v == t || t_links & bit(l.v) == 0 {
            continue;
        }
        let mt = st.m(l.v);
        if mt == 0 {
            continue;
        }
        sc.common.push(l.v);
        let c = sc.opp.iter().filter(|&&o| o == l.v).count() as u32;
        let new_m = l.m + mt - 2 * c;
        if c == 0 {
            // Two separate edges (s, w) and (t, w) would become one.
            let closes_hole = l.m == 1 && mt == 1;
            if !(closes_hole && opts.fill_holes) {
                return Err(Reject::Topology);
            }
        }
        if new_m > 2 && new_m > l.m.max(mt) {
            return Err(Reject::Topology);
        }
    }

    // Something must survive (the faces of r_s and r_t outside I), and no
    // two survivors may coincide — which needs both of a survivor's other
    // corners to be common neighbours.
    let m_ts = st.m(s) as usize;
    if ss.faces.len() - sc.opp.len() + st.faces.len() - m_ts == 0 {
        return Err(Reject::Topology);
    }
    let common = &sc.common;
    // The same 64-bit filter as above, over the common neighbours.
    let c_bits = common.iter().fold(0u64, |acc, &v| acc | bit(v));
    for x in ss.faces.iter().filter(|rf| rf.a != t && rf.b != t) {
        if c_bits & bit(x.a) == 0 || c_bits & bit(x.b) == 0 {
            continue;
        }
        if !(common.contains(&x.a) && common.contains(&x.b)) {
            continue;
        }
        if st.faces.iter().any(|y| {
            y.a != s && y.b != s && ((y.a == x.a && y.b == x.b) || (y.a == x.b && y.b == x.a))
        }) {
            return Err(Reject::Topology);
        }
    }

    // Wedge mapping (seams).
    if m.has_wedges() && !wedge_map(m, t, sc) {
        return Err(Reject::Seam);
    }
    let (ss, st) = (&sc.scan_s, &sc.scan_t);

    // Second stage of the two-stage optimisation: placement, in the frame
    // of v_s (so v_s is the origin).
    let (ls, lt) = (DVec3::ZERO, ltf.as_dvec3());
    let mut q = Quadric::ZERO;
    ss.add_quadric(m, &mut q);
    let mut qt = Quadric::ZERO;
    st.add_quadric(m, &mut qt);
    q.add_translated_from_origin(&qt, lt);
    let mut candidates = [DVec3::ZERO; 2];
    let mut n_cand = 0;
    // Border placement: a border edge's vertex stays on the old border
    // polyline (the segment); an interior vertex collapsing onto a border
    // vertex leaves it where it is. Otherwise the free optimum.
    let t_fixed = (t_border && (opts.lock_border || !s_border)) || m.is_locked(t);
    if s_border && !t_fixed {
        candidates[n_cand] = q.segment_minimum(ls, lt).0;
        n_cand += 1;
    } else if !t_fixed {
        let opt = q.optimum().filter(|&o| {
            // Eq. (9): keep the optimum only inside the ball on v_s v_t.
            (ls - o).length_squared() + (o - lt).length_squared() < (ls - lt).length_squared()
        });
        candidates[n_cand] = match opt {
            Some(o) => o,
            None => q.segment_minimum(ls, lt).0,
        };
        n_cand += 1;
    }
    if n_cand == 0 || candidates[0] != lt {
        candidates[n_cand] = lt;
        n_cand += 1;
    }
    // The first placement that flips no face, and the error estimate there:
    // the distance from the new vertex to the old planes (one walk over
    // each ring for both).
    let Some((local, d)) = candidates[..n_cand].iter().find_map(|&v| {
        let vf = v.as_vec3a();
        let ds = unflipped_distance(ss, t, vf)?;
        let dt = unflipped_distance(st, s, vf - ltf)?;
        Some((v, ds.max(dt)))
    }) else {
        return Err(Reject::Flip);
    };
    let new_err = m.err[s as usize].max(m.err[t as usize]) + d;
    // `err` is in the working frame (`WorkMesh::scale_exp`).
    if opts.max_error.is_some_and(|e| new_err > e * m.unit()) {
        return Err(Reject::MaxError);
    }
    // Staying at v_t keeps its stored position bit for bit.
    let vn = if local == lt { pt } else { local + ps };

    // Attributes: interpolate along the edge at the projection of v_n.
    let k = m.layout.k;
    if k > 0 {
        let e = pt - ps;
        let lambda = if e.length_squared() > 0.0 {
            ((vn - ps).dot(e) / e.length_squared()).clamp(0.0, 1.0)
        } else {
            1.0
        } as f32;
        let lerp = |attr: &mut Vec<f32>, a: u32, b: u32| {
            for i in 0..k {
                let (x, y) = (attr[a as usize * k + i], attr[b as usize * k + i]);
                attr[b as usize * k + i] = x + (y - x) * lambda;
            }
        };
        if m.has_wedges() {
            for &(a, b) in &sc.wedge_map {
                lerp(&mut m.attr, a, b);
            }
        } else {
            lerp(&mut m.attr, s, t);
        }
    }

    // Apply: delete I, re-point S at t, move t, flag both rings.
    let mut removed = 0;
    for rf in &sc.scan_s.faces {
        let fi = rf.f as usize;
        if rf.a == t || rf.b == t {
            m.faces[fi] = [DEAD; 3];
            removed += 1;
            continue;
        }
        let c = rf.corner as usize;
        m.faces[fi][c] = t;
        if m.has_wedges() {
            let a = m.wedges[fi][c];
            if let Some(&(_, b)) = sc.wedge_map.iter().find(|(x, _)| *x == a) {
                m.wedges[fi][c] = b;
            }
        }
    }
    m.live_faces -= removed;
    m.pos[t as usize] = vn.as_vec3();
    m.err[t as usize] = new_err;
    m.flags[s as usize] = Flag::Removed;
    m.flags[t as usize] = Flag::Dirty;
    Ok(removed)
}

/// Moving the centre of `scan` to `v` (scan frame): `None` if that flips
/// or degenerates one of its faces that survive the collapse (those not
/// containing `other`, the edge's other end), else the largest distance
/// from `v` to the planes of all its faces (a degenerate face's plane is
/// zero and counts 0).
#[inline]
fn unflipped_distance(scan: &RingScan, other: u32, v: Vec3A) -> Option<f32> {
    let mut d = 0.0f32;
    for rf in &scan.faces {
        let e = (rf.n.dot(v) + rf.d).abs();
        if e > d {
            d = e;
        }
        if rf.a == other || rf.b == other || rf.area <= 0.0 {
            // Deleted by the collapse, or already degenerate.
            continue;
        }
        let n1 = (rf.pa - v).cross(rf.pb - v);
        // rf.n is unit and rf.area = |n0| / 2.
        let dot = rf.n.dot(n1);
        if dot <= 0.0 || n1.length_squared() <= 1e-10 * (4.0 * rf.area * rf.area) {
            return None;
        }
    }
    Some(d)
}

/// Builds `sc.wedge_map` (wedge of `s` → wedge of `t`) from the faces of
/// `I`; false when the seam rules refuse the collapse.
fn wedge_map(m: &WorkMesh, t: u32, sc: &mut Scratch) -> bool {
    sc.wedge_map.clear();
    for rf in &sc.scan_s.faces {
        if rf.a != t && rf.b != t {
            continue;
        }
        let fi = rf.f as usize;
        let cs = rf.corner as usize;
        let ct = if rf.a == t {
            (cs + 1) % 3
        } else {
            (cs + 2) % 3
        };
        let (a, b) = (m.wedges[fi][cs], m.wedges[fi][ct]);
        match sc.wedge_map.iter().find(|(x, _)| *x == a) {
            Some(&(_, y)) if y != b => return false, // seam crosses at t
            Some(_) => {}
            None => {
                if sc.wedge_map.iter().any(|&(_, y)| y == b) {
                    return false; // two wedges of s would merge
                }
                sc.wedge_map.push((a, b));
            }
        }
    }
    // Every wedge of s must be next to the edge.
    for rf in &sc.scan_s.faces {
        let a = m.wedges[rf.f as usize][rf.corner as usize];
        if !sc.wedge_map.iter().any(|(x, _)| *x == a) {
            return false;
        }
    }
    true
}
