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

use glam::{DVec3, Vec3A};

use crate::options::Options;
use crate::quadric::{ExtendedFace, MAX_DIM, Quadric, add_border_plane};
use crate::ring_table::{
    DEAD, Flag, Link, RingEntry, RingTable, entry_corner, entry_face, multiplicity,
};
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
    const NULL: Record = Record {
        cost: f32::INFINITY,
        s: u32::MAX,
        t: u32::MAX,
    };
    #[inline]
    fn key(&self) -> f32 {
        self.cost
    }
}

/// One live face of a scanned ring: the face, the centre's corner, the two
/// other vertices in winding order with their positions, and the face's
/// plane (unit normal `n`, offset `d`, area; area 0 = degenerate), all in
/// the scan's frame. Single precision: coordinates are relative to a
/// vertex of the ring, so they are small and exact differences of the
/// stored `f32` positions; quadrics are summed in `f64`.
#[derive(Debug, Clone, Copy)]
pub struct RingFace {
    pub f: u32,
    pub corner: u8,
    pub a: u32,
    pub b: u32,
    pub pa: Vec3A,
    pub pb: Vec3A,
    pub n: Vec3A,
    pub d: f32,
    pub area: f32,
}

/// A ring read once: its link with edge multiplicities and its live faces
/// with their planes, in a frame centred on a chosen origin. Every stage
/// that needs a ring (cost, collapse checks, placement, error) reads this
/// instead of walking the face table again.
#[derive(Debug, Default)]
pub struct RingScan {
    pub center: u32,
    /// Centre position in the frame.
    pub pc: Vec3A,
    pub links: Vec<Link>,
    pub faces: Vec<RingFace>,
    /// The ring's area-weighted face planes (eq. 4) in the frame, summed
    /// while scanning; [`add_quadric`](Self::add_quadric) adds the border
    /// planes.
    pub planes: Quadric,
    /// Whether an internal edge has multiplicity 1 (set by the scan).
    pub border: bool,
    /// Sum of the live faces' areas.
    pub area: f64,
}

impl RingScan {
    /// Reads the ring of `center` (ring table entries `ring`, whose corners
    /// must be current) in the frame centred on `origin`. Returns false
    /// when the ring has no live face.
    pub fn scan(&mut self, m: &WorkMesh, ring: &[RingEntry], center: u32, origin: Vec3A) -> bool {
        let pc = fpos(m, center) - origin;
        // In the centre's own frame every face plane passes through the
        // origin: the plane offsets and the quadric's linear and constant
        // parts are zero, and that loop skips them.
        if pc == Vec3A::ZERO {
            self.scan_in::<true>(m, ring, center, pc, origin)
        } else {
            self.scan_in::<false>(m, ring, center, pc, origin)
        }
    }

    #[inline(always)]
    fn scan_in<const CENTRED: bool>(
        &mut self,
        m: &WorkMesh,
        ring: &[RingEntry],
        center: u32,
        pc: Vec3A,
        origin: Vec3A,
    ) -> bool {
        self.links.clear();
        self.faces.clear();
        self.center = center;
        self.pc = pc;
        let mut planes = Quadric::ZERO;
        let mut ring_area = 0.0;
        // One bit per link vertex (by the id's low bits): a vertex whose
        // bit is clear is not in the list yet and is pushed without the
        // search — every link's first occurrence, the search that runs
        // to the end of the list.
        let mut seen = 0u64;
        for &e in ring {
            let f = entry_face(e);
            let tri = m.faces[f as usize];
            if tri[0] == DEAD {
                continue;
            }
            let corner = entry_corner(e);
            debug_assert_eq!(tri[corner], center);
            // The other two corners in winding order, without branches.
            let (a, b) = (tri[NEXT[corner]], tri[NEXT[NEXT[corner]]]);
            // Exact counts (the collapse's topology checks rely on them).
            add_link(&mut self.links, &mut seen, a);
            add_link(&mut self.links, &mut seen, b);
            let pa = fpos(m, a) - origin;
            let pb = fpos(m, b) - origin;
            let (n, d, area) = if CENTRED {
                plane_through_origin(pa, pb)
            } else {
                plane(pc, pa, pb)
            };
            if area > 0.0 {
                if CENTRED {
                    planes.add_plane_through_origin(n.as_dvec3(), area as f64);
                } else {
                    planes.add_plane(n.as_dvec3(), d as f64, area as f64);
                }
                ring_area += area as f64;
            }
            self.faces.push(RingFace {
                f,
                corner: corner as u8,
                a,
                b,
                pa,
                pb,
                n,
                d,
                area,
            });
        }
        self.planes = planes;
        self.area = ring_area;
        self.border = self.links.iter().any(|l| l.m == 1);
        !self.links.is_empty()
    }

    /// Whether the ring has an internal edge of multiplicity 1 (the vertex
    /// is on a border of the mesh).
    #[inline]
    pub fn border(&self) -> bool {
        self.border
    }

    /// Multiplicity of the internal edge to `w` (0 = not a neighbour).
    #[inline]
    pub fn m(&self, w: u32) -> u32 {
        multiplicity(&self.links, w)
    }

    /// Adds the ring's memoryless vertex quadric (eq. 4: area-weighted face
    /// planes) and its border planes to `q`.
    pub fn add_quadric(&self, m: &WorkMesh, q: &mut Quadric) {
        for (x, y) in q.m.iter_mut().zip(&self.planes.m) {
            *x += y;
        }
        if !self.border() {
            return;
        }
        let pc = self.pc.as_dvec3();
        for rf in &self.faces {
            if rf.area <= 0.0 {
                continue;
            }
            let n = rf.n.as_dvec3();
            if self.m(rf.a) == 1 {
                add_border_plane(q, pc, rf.pa.as_dvec3(), n, m.border_weight);
            }
            if self.m(rf.b) == 1 {
                add_border_plane(q, pc, rf.pb.as_dvec3(), n, m.border_weight);
            }
        }
    }
}

/// The next corner in winding order (index 3 is never a corner; it keeps
/// the lookup in bounds for any two-bit value).
const NEXT: [usize; 4] = [1, 2, 0, 0];

/// Unit normal, offset and area of the triangle `(c, a, b)` in its frame
/// (zeros for a degenerate one). One square root and one division: the
/// hot spot of the whole simplifier.
#[inline]
pub fn plane(c: Vec3A, a: Vec3A, b: Vec3A) -> (Vec3A, f32, f32) {
    let nn = (a - c).cross(b - c);
    let len2 = nn.length_squared();
    if len2 > 0.0 {
        let len = len2.sqrt();
        let n = nn * (1.0 / len);
        (n, -n.dot(c), 0.5 * len)
    } else {
        (Vec3A::ZERO, 0.0, 0.0)
    }
}

/// [`plane`] for a triangle `(0, a, b)`: the same values (the offset is
/// zero) without the offset's dot product.
#[inline]
fn plane_through_origin(a: Vec3A, b: Vec3A) -> (Vec3A, f32, f32) {
    let nn = a.cross(b);
    let len2 = nn.length_squared();
    if len2 > 0.0 {
        let len = len2.sqrt();
        (nn * (1.0 / len), 0.0, 0.5 * len)
    } else {
        (Vec3A::ZERO, 0.0, 0.0)
    }
}

/// Counts one more face on the internal edge to `w`; `seen` has the bit
/// `w & 63` set for every vertex already in `links`.
#[inline]
fn add_link(links: &mut Vec<Link>, seen: &mut u64, w: u32) {
    let bit = 1u64 << (w & 63);
    if *seen & bit == 0 {
        *seen |= bit;
        links.push(Link { v: w, m: 1 });
        return;
    }
    // Almost surely in the list: count it without an early exit (whose
    // position is data-dependent and mispredicted).
    let mut hit = 0;
    for l in links.iter_mut() {
        let e = (l.v == w) as u32;
        l.m += e;
        hit |= e;
    }
    if hit == 0 {
        links.push(Link { v: w, m: 1 });
    }
}

/// Reusable buffers of the cost and collapse stages (no allocation per
/// ring once they have grown to the largest ring).
#[derive(Debug, Default)]
pub struct Scratch {
    pub scan_s: RingScan,
    pub scan_t: RingScan,
    pub ext: Vec<ExtendedFace>,
    pub wedge_map: Vec<(u32, u32)>,
    pub samples: Vec<f32>,
    /// Third vertices of the faces on a collapsing edge.
    pub opp: Vec<u32>,
    /// Common neighbours of a collapsing edge's two ends.
    pub common: Vec<u32>,
}

#[inline]
pub fn dpos(m: &WorkMesh, v: u32) -> DVec3 {
    m.pos[v as usize].as_dvec3()
}

#[inline]
pub fn fpos(m: &WorkMesh, v: u32) -> Vec3A {
    Vec3A::from(m.pos[v as usize])
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

/// Departure (the record key): a geometry-only cost is `Q_s(v_t)` divided
/// by the area of `r_s`, the area-weighted mean squared distance of the
/// moved vertex to the ring's planes, as meshoptimizer normalises its
/// errors. Reason: the plain sum grows with the faces' size, so small sharp
/// features (the bunny's ears) would look cheap next to large flat faces
/// and go first. Finite and never NaN (overflow saturates at `f32::MAX`).
#[inline]
fn normalised_cost(cost: f64, area: f64) -> f32 {
    let c = if area > 0.0 { cost / area } else { cost };
    let c = c as f32;
    if c <= f32::MAX { c } else { f32::MAX }
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
    let psf = fpos(m, s);
    let attributes = attribute_cost_on(m);
    // The full read, in the frame of v_s: the collapse stage reuses it when
    // this record is collapsed at once (see `pass.rs`).
    if !sc.scan_s.scan(m, rings.ring(s), s, psf) {
        return None;
    }
    let border = sc.scan_s.border();
    if (border && opts.lock_border) || m.is_locked(s) {
        return None;
    }
    let scan = &sc.scan_s;
    // Only edges the collapse stage could accept: border rings along border
    // edges, never onto a ring that is already dirty or gone (Strategy I
    // would refuse it; a cheaper-but-dead target would waste the record).
    let candidate = |l: &Link| {
        (!border || l.m == 1) && !matches!(m.flags[l.v as usize], Flag::Dirty | Flag::Removed)
    };
    if !attributes {
        // Geometry only: the ring quadric (face planes through v_s, border
        // planes) at each candidate, divided by the ring's area.
        let mut with_border = Quadric::ZERO;
        let q = if border {
            scan.add_quadric(m, &mut with_border);
            &with_border
        } else {
            &scan.planes
        };
        let mut best_cost = f64::INFINITY;
        let mut best_t = u32::MAX;
        for l in scan.links.iter().filter(|l| candidate(l)) {
            // Every plane of the ring passes through v_s, the origin.
            let c = q.eval_through_origin((fpos(m, l.v) - psf).as_dvec3());
            if c < best_cost {
                best_cost = c;
                best_t = l.v;
            }
        }
        // `eval` is finite, so a candidate always replaces +∞.
        return (best_t != u32::MAX).then_some(Record {
            cost: normalised_cost(best_cost, scan.area),
            s,
            t: best_t,
        });
    }
    // Geometry + attributes: one extended frame per face (the scan's
    // frame is centred on v_s), border planes as a plain quadric on top.
    let ps = dpos(m, s);
    let mut best: Option<(f64, u32)> = None;
    let mut consider = |cost: f64, t: u32| {
        if best.is_none_or(|(c, _)| cost < c) {
            best = Some((cost, t));
        }
    };
    {
        let dim = 3 + m.layout.k;
        sc.ext.clear();
        let mut qb = Quadric::ZERO;
        for rf in &scan.faces {
            if rf.area <= 0.0 {
                continue;
            }
            let c = rf.corner as usize;
            let f = rf.f as usize;
            let x = [
                joint_point(m, scan.pc.as_dvec3(), m.wedge(f, c)),
                joint_point(m, rf.pa.as_dvec3(), m.wedge(f, (c + 1) % 3)),
                joint_point(m, rf.pb.as_dvec3(), m.wedge(f, (c + 2) % 3)),
            ];
            if let Some(e) = ExtendedFace::new([&x[0], &x[1], &x[2]], dim, rf.area as f64) {
                sc.ext.push(e);
            }
            if border {
                let (pc, n) = (scan.pc.as_dvec3(), rf.n.as_dvec3());
                if scan.m(rf.a) == 1 {
                    add_border_plane(&mut qb, pc, rf.pa.as_dvec3(), n, m.border_weight);
                }
                if scan.m(rf.b) == 1 {
                    add_border_plane(&mut qb, pc, rf.pb.as_dvec3(), n, m.border_weight);
                }
            }
        }
        for l in scan.links.iter().filter(|l| candidate(l)) {
            let pt = dpos(m, l.v) - ps;
            let w = wedge_of_vertex_in_ring(m, rings.ring(s), l.v);
            let x = joint_point(m, pt, w);
            let c: f64 = sc.ext.iter().map(|e| e.cost(&x, dim)).sum::<f64>() + qb.eval(pt);
            consider(c, l.v);
        }
    }
    let (cost, t) = best?;
    // Finite keys only: +∞ is the heap's null record.
    Some(Record {
        cost: (cost as f32).min(f32::MAX),
        s,
        t,
    })
}

/// The wedge of vertex `v` in the first live face of `ring` containing it.
pub fn wedge_of_vertex_in_ring(m: &WorkMesh, ring: &[RingEntry], v: u32) -> u32 {
    if !m.has_wedges() {
        return v;
    }
    for &e in ring {
        let f = entry_face(e);
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;

    #[test]
    fn ring_scan_counts_internal_edge_multiplicity_and_planes() {
        // A fan of two faces around 0: edge 0-2 inner (m = 2), 0-1 and 0-3 border.
        let m = WorkMesh {
            pos: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            faces: vec![[0, 1, 2], [0, 2, 3]],
            live_faces: 2,
            flags: vec![Flag::Valid; 4],
            err: vec![0.0; 4],
            border_weight: 1.0,
            ..Default::default()
        };
        let mut scan = RingScan::default();
        // Entries: faces 0 and 1, centre at corner 0 of both.
        assert!(scan.scan(&m, &[0 << 2, 1 << 2], 0, Vec3A::ZERO));
        assert_eq!((scan.m(2), scan.m(1), scan.m(3), scan.m(9)), (2, 1, 1, 0));
        assert!(scan.border());
        for rf in &scan.faces {
            assert!((rf.n - Vec3A::Z).length() < 1e-6 && (rf.area - 0.5).abs() < 1e-6);
        }
        // The quadric vanishes on the plane, away from the border lines.
        let mut q = Quadric::ZERO;
        scan.add_quadric(&m, &mut q);
        assert!(q.eval(DVec3::new(0.0, 0.0, 0.0)) < 1e-12);
        assert!(q.eval(DVec3::new(0.0, 0.0, 1.0)) > 0.9);
    }
}
