//! Cost computation and hole filling (HQMS §4.3.2, procedure
//! `CostComputation`).
//!
//! For the ring `r_i` of vertex `v_i` the memoryless vertex quadric `Q_i` is
//! summed from the ring's current faces, and every internal edge
//! `(v_i, v_j)` is rated by `Q_i(v_j)` — the cost of moving `v_i` onto its
//! neighbour. The cheapest edge becomes the ring's contraction record. The
//! optimal position is *not* solved here (two-stage optimisation: only the
//! records that are actually collapsed pay for it, in `collapse.rs`).
//!
//! Hole filling: when an internal edge has multiplicity 1 (a border edge of
//! the mesh), the ring is forced to collapse along one of those edges, as in
//! the paper's pseudo-code.
//!
//! Departures, and why:
//! - Rings on a border are restricted to border edges whether or not hole
//!   filling is on; with `fill_holes = false` the collapse stage then
//!   refuses to merge two border edges, so every hole survives. Without the
//!   restriction an open rim would be pulled inward.
//! - `lock_border` makes every border ring null (never contracted).
//! - With attributes the cost is the extended-quadric cost (see
//!   `quadric.rs`), the neighbour's attributes taken from its wedge in the
//!   first ring face that contains it.

use glam::DVec3;

use crate::options::Options;
use crate::quadric::{ExtendedFace, MAX_DIM, Quadric, add_border_plane, triangle_plane};
use crate::ring_table::{DEAD, Link, RingTable, gather_links, multiplicity};
use crate::rs_heap::Keyed;
use crate::work_mesh::WorkMesh;

/// A contraction record `(e_st, Q_s(v_t))`: collapse `s` onto `t`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Record {
    pub cost: f32,
    pub s: u32,
    pub t: u32,
}

impl Keyed for Record {
    #[inline]
    fn key(&self) -> f32 {
        self.cost
    }
}

/// Reusable buffers of the cost and collapse stages (no allocation per
/// ring once they have grown to the largest ring).
#[derive(Debug, Default)]
pub struct Scratch {
    pub links_s: Vec<Link>,
    pub links_t: Vec<Link>,
    pub shared: Vec<u32>,
    pub ext: Vec<ExtendedFace>,
    pub wedge_map: Vec<(u32, u32)>,
    pub samples: Vec<f32>,
}

#[inline]
pub fn dpos(m: &WorkMesh, v: u32) -> DVec3 {
    m.pos[v as usize].as_dvec3()
}

/// Adds the area-weighted planes of the live faces of `ring` (around
/// `center`, whose link is `links`) and the border planes of its border
/// edges to `q`, in a frame centred on `origin`. Returns the ring's area.
pub fn add_ring_quadric(
    m: &WorkMesh,
    ring: &[u32],
    center: u32,
    links: &[Link],
    origin: DVec3,
    q: &mut Quadric,
) -> f64 {
    let border = links.iter().any(|l| l.m == 1);
    let mut area = 0.0;
    for &f in ring {
        let tri = m.faces[f as usize];
        if tri[0] == DEAD {
            continue;
        }
        let p = tri.map(|v| dpos(m, v) - origin);
        let Some((n, d, a)) = triangle_plane(p[0], p[1], p[2]) else {
            continue;
        };
        q.add_plane(n, d, a);
        area += a;
        if border {
            let c = tri.iter().position(|&v| v == center).unwrap_or(0);
            for k in [1, 2] {
                let x = tri[(c + k) % 3];
                if multiplicity(links, x) == 1 {
                    add_border_plane(q, p[c], p[(c + k) % 3], n);
                }
            }
        }
    }
    area
}

/// Whether any attribute takes part in the cost.
#[inline]
pub fn attribute_cost_on(m: &WorkMesh) -> bool {
    m.layout.k > 0 && m.attr_scale[..m.layout.k].iter().any(|&s| s > 0.0)
}

/// The joint-space point of wedge `w` at position `p` (already relative).
#[inline]
pub fn joint_point(m: &WorkMesh, p: DVec3, w: u32) -> [f64; MAX_DIM] {
    let mut x = [0.0; MAX_DIM];
    x[0] = p.x;
    x[1] = p.y;
    x[2] = p.z;
    let k = m.layout.k;
    let a = &m.attr[w as usize * k..w as usize * k + k];
    for i in 0..k {
        x[3 + i] = a[i] as f64 * m.attr_scale[i] as f64;
    }
    x
}

/// `ComputeContractionCost(r_s)`: the cheapest valid contraction of the
/// ring of `s`, or `None` when the ring has none (null flag).
pub fn best_contraction(
    m: &WorkMesh,
    rings: &RingTable,
    opts: &Options,
    s: u32,
    sc: &mut Scratch,
) -> Option<Record> {
    let ring = rings.ring(s);
    if !gather_links(s, ring, &m.faces, &mut sc.links_s) {
        return None;
    }
    let border = sc.links_s.iter().any(|l| l.m == 1);
    if border && opts.lock_border {
        return None;
    }
    let ps = dpos(m, s);
    let links = &sc.links_s;
    let candidate = |l: &Link| !border || l.m == 1;

    let mut best: Option<(f64, u32)> = None;
    let mut consider = |cost: f64, t: u32| {
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, t));
        }
    };
    if !attribute_cost_on(m) {
        let mut q = Quadric::ZERO;
        add_ring_quadric(m, ring, s, links, ps, &mut q);
        for l in links.iter().filter(|l| candidate(l)) {
            consider(q.eval(dpos(m, l.v) - ps), l.v);
        }
    } else {
        // Geometry + attributes: one extended frame per face, border planes
        // as a plain quadric on top.
        let dim = 3 + m.layout.k;
        sc.ext.clear();
        let mut qb = Quadric::ZERO;
        for &f in ring {
            let tri = m.faces[f as usize];
            if tri[0] == DEAD {
                continue;
            }
            let p = tri.map(|v| dpos(m, v) - ps);
            let Some((n, _, a)) = triangle_plane(p[0], p[1], p[2]) else {
                continue;
            };
            let x: [[f64; MAX_DIM]; 3] =
                std::array::from_fn(|c| joint_point(m, p[c], m.wedge(f as usize, c)));
            if let Some(e) = ExtendedFace::new([&x[0], &x[1], &x[2]], dim, a) {
                sc.ext.push(e);
            }
            if border {
                let c = tri.iter().position(|&v| v == s).unwrap_or(0);
                for k in [1, 2] {
                    if multiplicity(links, tri[(c + k) % 3]) == 1 {
                        add_border_plane(&mut qb, p[c], p[(c + k) % 3], n);
                    }
                }
            }
        }
        for l in links.iter().filter(|l| candidate(l)) {
            let pt = dpos(m, l.v) - ps;
            let w = wedge_of_vertex_in_ring(m, ring, l.v);
            let x = joint_point(m, pt, w);
            let c: f64 = sc.ext.iter().map(|e| e.cost(&x, dim)).sum::<f64>() + qb.eval(pt);
            consider(c, l.v);
        }
    }
    let (cost, t) = best?;
    Some(Record {
        cost: cost as f32,
        s,
        t,
    })
}

/// The wedge of vertex `v` in the first live face of `ring` containing it.
pub fn wedge_of_vertex_in_ring(m: &WorkMesh, ring: &[u32], v: u32) -> u32 {
    if !m.has_wedges() {
        return v;
    }
    for &f in ring {
        let tri = m.faces[f as usize];
        if tri[0] == DEAD {
            continue;
        }
        if let Some(c) = tri.iter().position(|&x| x == v) {
            return m.wedges[f as usize][c];
        }
    }
    v
}
