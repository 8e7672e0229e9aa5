//! The Hamiltonian split of an ambiguous solid — §6.2 of Yemez & Schmitt.
//!
//! For `C_i, i ≥ 6`, the edges of `G_i` that also belong to the graph of
//! an overlapping neighbourhood ([`super::shared_edges`]) are tested: if
//! they form one Hamiltonian cycle through every ON cube, the cycle cuts
//! the hull into two discs and the one with the smaller mean dihedral angle
//! is emitted ([`smoother_disc`]). Otherwise all of `T_i` is emitted:
//! hole-free, non-manifold.
//!
//! Departure: when the shared edges hold exactly one Hamiltonian cycle
//! plus edges inside one of its discs, each in the graphs of two or more
//! neighbours, the other disc is emitted — its interior edges are nobody
//! else's, and the neighbours keep the ones it leaves ([`split_by_cycle`];
//! this resolves many of the neighbourhoods the paper's test leaves whole,
//! with no new boundary edge). When an edge inside one disc is in one
//! neighbour's graph only, that disc is the first choice (leaving the edge
//! would risk a hole), settled later ([`super::settle`]).
use glam::Vec3;

use crate::triangulation_table::pair;

#[inline]
pub(super) fn tri_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    (b - a).cross(c - a).normalize_or_zero()
}

/// [`hull_normal`] of four triangles at once, as the `x`, `y` and `z`
/// of each: the triangles side by side in the lanes of `Vec4`s, each
/// lane's operations those of the scalar code in the same order
/// (`Vec3::cross`, `Vec3::normalize_or_zero`), so the normals have the
/// same bits.
#[inline(always)]
pub(super) fn hull_normals4(tris: [[u8; 3]; 4], pos: &impl Fn(u8) -> Vec3) -> [[f32; 4]; 3] {
    use glam::Vec4;
    let mut p = [[Vec3::ZERO; 3]; 4];
    for (pt, t) in p.iter_mut().zip(tris) {
        for (v, j) in pt.iter_mut().zip(t) {
            *v = pos(j);
        }
    }
    // Corner `c` of the four triangles, coordinate `f`.
    let lane =
        |c: usize, f: fn(Vec3) -> f32| Vec4::new(f(p[0][c]), f(p[1][c]), f(p[2][c]), f(p[3][c]));
    let edge = |c: usize, f: fn(Vec3) -> f32| lane(c, f) - lane(0, f);
    let (ax, ay, az) = (edge(1, |v| v.x), edge(1, |v| v.y), edge(1, |v| v.z));
    let (bx, by, bz) = (edge(2, |v| v.x), edge(2, |v| v.y), edge(2, |v| v.z));
    let nx = ay * bz - by * az;
    let ny = az * bx - bz * ax;
    let nz = ax * by - bx * ay;
    let rcp = Vec4::ONE / ((nx * nx) + (ny * ny) + (nz * nz)).sqrt();
    let ok = rcp.is_finite_mask() & rcp.cmpgt(Vec4::ZERO);
    let unit = |n: Vec4| Vec4::select(ok, n * rcp, Vec4::ZERO).to_array();
    [unit(nx), unit(ny), unit(nz)]
}

/// Unit normal of the hull triangle `t` (corners), `pos` giving the
/// corners' positions. A function rather than a closure so that it can be
/// forced inline (LLVM had left such a closure out of line).
#[inline(always)]
pub(super) fn hull_normal(t: [u8; 3], pos: &impl Fn(u8) -> Vec3) -> Vec3 {
    tri_normal(pos(t[0]), pos(t[1]), pos(t[2]))
}

/// How §6.2 resolves an ambiguous configuration.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Split {
    /// No usable cycle: build the whole hull (hole-free, non-manifold).
    Whole,
    /// The shared edges are exactly one Hamiltonian cycle (the paper's
    /// case): either disc (bit `i`: triangle `i`; the other disc is the
    /// complement); the smoother one is built.
    Either(u16),
    /// The shared edges hold exactly one Hamiltonian cycle plus edges
    /// interior to one of its discs: the other disc is built, whose
    /// interior edges no neighbour uses.
    Only(u16),
    /// As `Only`, but a shared edge inside the other disc is in one
    /// neighbour's graph only, so leaving it would open a hole: the disc
    /// holding it is built, provided the neighbours close its rim (the
    /// cycle, second field) and no neighbour's triangle uses an edge inside
    /// the disc left out; checked once the level is scanned.
    Holding(u16, u32),
}

/// §6.2's disambiguation of the solid `tris` of configuration `mask`,
/// `shared` being the edges of `G_i` that overlapping neighbourhoods also
/// have. The paper accepts the shared edges when they form one Hamiltonian
/// cycle. Departure: when they hold exactly one Hamiltonian cycle and more
/// (the frequent failure on thinned surfaces: five of a tetrahedron's six
/// edges), the cycle still cuts the hull in two discs, and the disc whose
/// interior edges are all unshared is built: the other one, or the whole
/// hull, would put a third triangle on a shared edge.
#[inline]
pub(super) fn split_by_cycle(mask: u8, shared: u32, twice: u32, tris: &[[u8; 3]]) -> Split {
    debug_assert!(tris.len() <= 16);
    let Some(cycle) = unique_hamiltonian_cycle(mask, shared) else {
        return Split::Whole;
    };
    let on_cycle = |a: u8, b: u8| cycle & (1 << pair(a, b)) != 0;
    // Flood the triangles without crossing the cycle.
    let mut disc = 1u16;
    let mut stack = [0u8; 16];
    let mut top = 1;
    let edge_of = |t: &[u8; 3], k: usize| (t[k], t[(k + 1) % 3]);
    while top > 0 {
        top -= 1;
        let i = stack[top] as usize;
        for k in 0..3 {
            let (a, b) = edge_of(&tris[i], k);
            if on_cycle(a, b) {
                continue;
            }
            for (j, tj) in tris.iter().enumerate() {
                if disc & (1 << j) == 0 && (0..3).any(|m| edge_of(tj, m) == (b, a)) {
                    disc |= 1 << j;
                    stack[top] = j as u8;
                    top += 1;
                }
            }
        }
    }
    let all = ((1u32 << tris.len()) - 1) as u16;
    if disc == all {
        return Split::Whole;
    }
    // The shared edges inside a disc (off the cycle).
    let interior_shared = |d: u16| {
        let mut e = 0u32;
        for (i, t) in tris.iter().enumerate() {
            for k in 0..3 {
                let (a, b) = edge_of(t, k);
                if d & (1 << i) != 0 && !on_cycle(a, b) {
                    e |= shared & (1 << pair(a, b));
                }
            }
        }
        e
    };
    // A disc may be left out when the shared edges inside it keep two
    // neighbours' triangles each: leaving them to the neighbours opens no
    // hole there.
    let leave = |e: u32| e & !twice == 0;
    // Otherwise the disc holding them is built, on trial: the edges inside
    // it carry its two triangles plus the neighbours' (non-manifold, as the
    // whole hull would make them), but the rest of the hull gains none; its
    // rim, the cycle, must be closed by the neighbours, which `triangulate`
    // checks afterwards, adding the other disc where one is not.
    let other = all & !disc;
    match (interior_shared(disc), interior_shared(other)) {
        (0, 0) => Split::Either(disc),
        (0, e) if leave(e) => Split::Only(disc),
        (e, 0) if leave(e) => Split::Only(other),
        (0, _) => Split::Holding(other, cycle),
        (_, 0) => Split::Holding(disc, cycle),
        _ => Split::Whole,
    }
}

/// The Hamiltonian cycle through the ON cubes of `mask` made of `shared`
/// edges (as pair bits), if there is exactly one.
#[inline]
pub(super) fn unique_hamiltonian_cycle(mask: u8, shared: u32) -> Option<u32> {
    let n = mask.count_ones() as usize;
    if n < 3 || (shared.count_ones() as usize) < n {
        return None;
    }
    let mut search = CycleSearch {
        mask,
        shared,
        n,
        path: [mask.trailing_zeros() as u8; 8],
        found: None,
        count: 0,
    };
    search.walk(1);
    if search.count == 1 {
        search.found
    } else {
        None
    }
}

/// Depth-first search over the simple paths of shared edges from the
/// first ON cube; each cycle is met twice (once per direction).
pub(super) struct CycleSearch {
    pub(super) mask: u8,
    pub(super) shared: u32,
    pub(super) n: usize,
    pub(super) path: [u8; 8],
    pub(super) found: Option<u32>,
    pub(super) count: usize,
}

impl CycleSearch {
    pub(super) fn has(&self, a: u8, b: u8) -> bool {
        a != b && self.shared & (1 << pair(a, b)) != 0
    }

    pub(super) fn walk(&mut self, len: usize) {
        let last = self.path[len - 1];
        if len == self.n {
            if self.has(last, self.path[0]) {
                let mut c = 1u32 << pair(last, self.path[0]);
                for k in 1..self.n {
                    c |= 1 << pair(self.path[k - 1], self.path[k]);
                }
                if self.found != Some(c) {
                    self.count += 1;
                }
                self.found = Some(c);
            }
            return;
        }
        for b in 0..8u8 {
            if self.mask & (1 << b) != 0 && !self.path[..len].contains(&b) && self.has(last, b) {
                self.path[len] = b;
                self.walk(len + 1);
                if self.count > 1 {
                    return;
                }
            }
        }
    }
}

/// Whether the disc `disc` of `tris` (bit `i`: triangle `i`) has a mean
/// dihedral angle over its interior edges no larger than its complement's
/// (§6.2's choice). `adjacent` lists the hull's pairs of triangles that
/// share an edge ([`crate::triangulation_table::Config::adjacent`]); an
/// interior edge of a disc is one whose two triangles are both in it.
/// Discs with one interior edge each (`C_6`, the frequent case) compare
/// cosines, no `acos` needed.
#[inline]
pub(super) fn smoother_disc(
    tris: &[[u8; 3]],
    adjacent: &[(u8, u8)],
    disc: u16,
    pos: &impl Fn(u8) -> Vec3,
) -> bool {
    // A tetrahedron (`C_6`, the frequent case) splits into two discs of
    // two triangles each, one interior edge apiece: the general count
    // below, with its 16-slot arrays, comes down to two dihedral cosines
    // (the same products in the same order, so the same bits).
    // (`count_ones` is a dozen instructions without the popcnt
    // extension, which the baseline x86-64 target lacks.)
    let two_bits = |d: u16| {
        let rest = d & d.wrapping_sub(1);
        (rest != 0) & (rest & rest.wrapping_sub(1) == 0)
    };
    if (tris.len() == 4) & two_bits(disc) {
        let [x, y, z] = hull_normals4([tris[0], tris[1], tris[2], tris[3]], pos);
        // `Vec3::dot`'s order.
        let cosine = |d: u16| {
            let (i, j) = (
                d.trailing_zeros() as usize & 3,
                (15 - d.leading_zeros()) as usize & 3,
            );
            ((x[i] * x[j]) + (y[i] * y[j]) + (z[i] * z[j])).clamp(-1.0, 1.0)
        };
        return cosine(disc & 15) >= cosine(!disc & 15);
    }
    let mut normals = [Vec3::ZERO; 16];
    for (i, t) in tris.iter().enumerate().take(16) {
        normals[i] = hull_normal(*t, pos);
    }
    // Cosines of the interior edges of each side.
    let mut cos = [[0.0f32; 16]; 2];
    let mut n = [0usize; 2];
    for &(i, j) in adjacent {
        let (i, j) = (usize::from(i), usize::from(j));
        let side = usize::from(disc & (1 << i) == 0);
        if usize::from(disc & (1 << j) == 0) != side || n[side] == 16 {
            continue;
        }
        cos[side][n[side]] = normals[i].dot(normals[j]).clamp(-1.0, 1.0);
        n[side] += 1;
    }
    if n == [1, 1] {
        return cos[0][0] >= cos[1][0];
    }
    let mean = |c: &[f32]| {
        if c.is_empty() {
            0.0
        } else {
            c.iter().map(|x| x.acos()).sum::<f32>() / c.len() as f32
        }
    };
    mean(&cos[0][..n[0]]) <= mean(&cos[1][..n[1]])
}
