//! Settling — a departure from Yemez & Schmitt's §6.2.
//!
//! The §6.2 choice is local: a disc's interior edge can still be a
//! neighbour's rim edge (three triangles on it), and a hull left whole is
//! non-manifold by construction. So the ambiguous solids — those left
//! whole, those with a first choice on trial, and the resolved ones of
//! every class but `C_6` — are built last: each takes the subset of its
//! hull triangles that best fits what the rest of the level built (no hull
//! edge used once, every cube in a triangle, fewest surplus edge uses), in
//! scan order, two sweeps ([`settle`]). The whole hull is always a
//! candidate, so this opens no hole. Resolved `C_6`s are built at once:
//! settling them too changes nothing measurable and costs several times
//! the triangulation.
use std::collections::HashMap;

use super::window::{BRICK_BITS, BrickIndex};
use super::{NONE, TriangulationStats, edge_key};
use crate::octree::{MortonMap, unmorton};
use crate::triangulation_table::{Shape, table};

/// What the scan built: the triangles of every neighbourhood it could
/// settle alone, and the ambiguous solids left for [`settle`].
pub(super) struct Scanned {
    /// Triangles, as vertex indices of the surface.
    pub(super) faces: Vec<[u32; 3]>,
    /// §6.3's merged cube pairs (empty without decimation).
    pub(super) merges: Vec<(u32, u32)>,
    /// Indices into `faces` (increasing) of the triangles solid
    /// configurations built on a face of their neighbourhood: the only
    /// ones two neighbourhoods can both build.
    pub(super) from_solids: Vec<u32>,
    /// The ambiguous solids, in scan order.
    pub(super) trials: Vec<Trial>,
    /// First face each brick built, plus the end (see
    /// [`settle_ranges`]).
    pub(super) brick_faces: Vec<u32>,
    /// Configuration counts, and the solids resolved or left whole so far.
    pub(super) stats: TriangulationStats,
}

/// An ambiguous solid whose triangles are chosen once the level is
/// scanned ([`settle`]).
pub(super) struct Trial {
    /// Vertex of each corner (NONE where not ON).
    pub(super) vs: [u32; 8],
    pub(super) mask: u8,
    /// The triangles built, as bits over the configuration's hull.
    pub(super) keep: u16,
}

/// The bits of `n` triangles.
#[inline]
pub(super) fn all_bits(n: usize) -> u16 {
    ((1u32 << n.min(16)) - 1) as u16
}

/// Hulls with more triangles than this keep their first choice: the
/// subsets tried grow as `2^n`.
pub(super) const SETTLE_MAX_TRIANGLES: usize = 12;

/// Resolved neighbourhoods of this class are built at once.
pub(super) const SETTLE_SKIP_CLASS: u8 = 6;

/// Sweeps over the trials; a second lets the first ones see the later.
pub(super) const SETTLE_SWEEPS: usize = 2;

#[inline]
pub(super) fn sorted_tri(t: [u32; 3]) -> [u32; 3] {
    let (a, b) = (t[0].min(t[1]), t[0].max(t[1]));
    [a.min(t[2]), a.max(b.min(t[2])), b.max(t[2])]
}

/// Whether the corners of a hull triangle share a coordinate: it lies on a
/// face of the neighbourhood, and the solid across may build it too.
#[inline]
pub(super) fn on_face(tri: &[u8; 3]) -> bool {
    !((tri[0] ^ tri[1]) | (tri[0] ^ tri[2])) & 7 != 0
}

/// Edge and vertex use by the distinct triangles around the trials. Only
/// triangles on a neighbourhood face can be built twice (by the solids on
/// both sides; [`dedupe_face_triangles`] later keeps one copy), so only
/// those are counted by key.
pub(super) struct Uses {
    pub(super) face_tris: HashMap<[u32; 3], u32, rustc_hash::FxBuildHasher>,
    /// The trials' hull edges (by key) → their slot in `edge_uses`.
    pub(super) edges: MortonMap<u32>,
    pub(super) edge_uses: Vec<u32>,
    pub(super) vertices: Vec<u32>,
}

/// Where a triangle's edges are counted: looked up by key (a triangle of
/// the level), or the slots of a trial's hull triangle, found once.
#[derive(Clone, Copy)]
pub(super) enum EdgeSlots {
    Lookup,
    Known([u32; 3]),
}

impl Uses {
    #[inline]
    pub(super) fn add(&mut self, t: [u32; 3], face: bool, slots: EdgeSlots) {
        if face {
            let n = self.face_tris.entry(sorted_tri(t)).or_insert(0);
            *n += 1;
            if *n > 1 {
                return;
            }
        }
        self.touch(t, 1, slots);
    }
    #[inline]
    pub(super) fn remove(&mut self, t: [u32; 3], face: bool, slots: EdgeSlots) {
        if face {
            let key = sorted_tri(t);
            let Some(n) = self.face_tris.get_mut(&key) else {
                return;
            };
            *n -= 1;
            if *n > 0 {
                return;
            }
            self.face_tris.remove(&key);
        }
        self.touch(t, -1, slots);
    }
    /// Whether a face triangle is built.
    pub(super) fn built(&self, t: [u32; 3]) -> bool {
        self.face_tris.contains_key(&sorted_tri(t))
    }
    pub(super) fn touch(&mut self, t: [u32; 3], d: i32, slots: EdgeSlots) {
        for k in 0..3 {
            let slot = match slots {
                EdgeSlots::Lookup => self.edges.get(&edge_key(t[k], t[(k + 1) % 3])).copied(),
                EdgeSlots::Known(s) => Some(s[k]),
            };
            if let Some(slot) = slot {
                let n = &mut self.edge_uses[slot as usize];
                *n = n.wrapping_add_signed(d);
            }
            let v = &mut self.vertices[t[k] as usize];
            *v = v.wrapping_add_signed(d);
        }
    }
}

/// The ranges of `faces` (increasing, disjoint) that hold every triangle
/// on a vertex of a trial. A triangle is built by the brick that scans its
/// neighbourhood: the brick of the neighbourhood's origin or, when that
/// one is empty, an occupied brick the neighbourhood reaches ([`owns`]).
/// A neighbourhood holding cube `v` has its origin in `v`'s brick or, where
/// `v` is on the brick's lower face, in the brick below; it reaches the
/// brick above only where its origin is on an upper face, i.e. where `v`
/// is on the brick's lower face (the brick of `v`) or its upper face (the
/// brick above). So the bricks `v`'s brick plus, per axis, −1 or 0 where
/// `v` is on the lower face, 0 or +1 on the upper face, 0 elsewhere, scan
/// every triangle on `v`: only their triangles, a fraction of the
/// level's, are read (`brick_faces`: the first triangle of each brick,
/// plus the end). `cells` in Morton order, vertex `i` = cell `i`.
#[inline]
pub(super) fn settle_ranges(
    trials: &[Trial],
    cells: &[u64],
    index: &BrickIndex,
    brick_faces: &[u32],
) -> Vec<(u32, u32)> {
    let mut marked = vec![false; brick_faces.len() - 1];
    for t in trials {
        for (j, &v) in t.vs.iter().enumerate() {
            if t.mask & (1 << j) == 0 {
                continue;
            }
            let c = cells[v as usize];
            let b = unmorton(c >> (3 * BRICK_BITS)).map(i64::from);
            let local = unmorton(c & 511);
            // Per axis, the offsets of the bricks to scan.
            let offsets = local.map(|l| match l {
                0 => [-1, 0],
                7 => [0, 1],
                _ => [0, 0],
            });
            for d in 0..8 {
                let n = index.get([
                    b[0] + offsets[0][d & 1],
                    b[1] + offsets[1][(d >> 1) & 1],
                    b[2] + offsets[2][d >> 2],
                ]);
                if n != NONE {
                    marked[n as usize] = true;
                }
            }
        }
    }
    let mut ranges: Vec<(u32, u32)> = Vec::new();
    for (n, _) in marked.iter().enumerate().filter(|(_, m)| **m) {
        let (start, end) = (brick_faces[n], brick_faces[n + 1]);
        match ranges.last_mut() {
            Some(last) if last.1 == start => last.1 = end,
            _ => ranges.push((start, end)),
        }
    }
    ranges
}

/// Chooses, for each ambiguous solid (a hull §6.2 leaves whole, a disc on
/// trial, a resolved solid of a class other than `C_6`), the subset of its
/// hull triangles that best fits what the rest of the level built: in this
/// order, fewest hull edges used by one triangle (holes), fewest of its
/// cubes left in no triangle, fewest surplus uses of its hull edges
/// (non-manifold edges), its current choice, fewest triangles. The whole
/// hull leaves no hull edge used once, and a trial's choice changes the use
/// of its own hull edges only, so settling opens no hole the whole hulls
/// would not. Trials are settled in scan order, twice over: deterministic.
#[inline]
pub(super) fn settle(
    faces: &[[u32; 3]],
    ranges: &[(u32, u32)],
    from_solids: &[u32],
    trials: &mut [Trial],
    vertices: usize,
) {
    if trials.is_empty() {
        return;
    }
    let hull = |t: &Trial| match &table().configs[t.mask as usize].shape {
        Shape::Solid(tris) => tris.as_slice(),
        _ => &[],
    };
    // Trial vertices, as a bit set (the scan below reads it for every
    // triangle of the level; bits keep it in the first-level cache).
    let mut near = vec![0u64; vertices.div_ceil(64)];
    let mut uses = Uses {
        face_tris: HashMap::default(),
        edges: MortonMap::default(),
        edge_uses: Vec::new(),
        vertices: vec![0; vertices],
    };
    // The edge slots of every hull triangle of every trial, trial by trial
    // (`first[i]`: trial `i`'s first), so that the sweeps count a trial's
    // edges without hashing.
    let mut first = Vec::with_capacity(trials.len());
    let mut hull_slots: Vec<[u32; 3]> = Vec::new();
    uses.edges.reserve(trials.len() * 12);
    for t in trials.iter() {
        first.push(hull_slots.len());
        for tri in hull(t) {
            let mut slots = [0u32; 3];
            for k in 0..3 {
                let (a, b) = (t.vs[tri[k] as usize], t.vs[tri[(k + 1) % 3] as usize]);
                near[(a >> 6) as usize] |= 1 << (a & 63);
                let next = uses.edges.len() as u32;
                slots[k] = *uses.edges.entry(edge_key(a, b)).or_insert(next);
            }
            hull_slots.push(slots);
        }
    }
    uses.edge_uses = vec![0; uses.edges.len()];
    // Every triangle that can hold a trial vertex is tested: three bits,
    // or-ed without a branch each; whether a near one came from a solid is
    // read off the sorted `from_solids` with a cursor.
    let bit = |v: u32| (near[(v >> 6) as usize] >> (v & 63)) & 1;
    let mut solid = from_solids.iter().map(|&i| i as usize).peekable();
    for &(start, end) in ranges {
        for i in start as usize..end as usize {
            let f = faces[i];
            if bit(f[0]) | bit(f[1]) | bit(f[2]) != 0 {
                while solid.next_if(|&j| j < i).is_some() {}
                uses.add(f, solid.peek() == Some(&i), EdgeSlots::Lookup);
            }
        }
    }
    let tri_of = |t: &Trial, tri: &[u8; 3]| tri.map(|j| t.vs[j as usize]);
    for (n, t) in trials.iter().enumerate() {
        for (i, tri) in hull(t).iter().enumerate() {
            if t.keep & (1 << i) != 0 {
                let slots = EdgeSlots::Known(hull_slots[first[n] + i]);
                uses.add(tri_of(t, tri), on_face(tri), slots);
            }
        }
    }
    for _ in 0..SETTLE_SWEEPS {
        for (n, t) in trials.iter_mut().enumerate() {
            let tris = hull(t);
            if tris.len() > SETTLE_MAX_TRIANGLES {
                continue;
            }
            let slots = &hull_slots[first[n]..first[n] + tris.len()];
            for (i, tri) in tris.iter().enumerate() {
                if t.keep & (1 << i) != 0 {
                    uses.remove(tri_of(t, tri), on_face(tri), EdgeSlots::Known(slots[i]));
                }
            }
            // Hull edges (as corner pairs), their use by the others, and
            // each triangle's edges among them; face triangles the others
            // built already add nothing.
            let mut edges = [(0u8, 0u8); 18];
            let mut n_edges = 0;
            let mut base = [0u32; 18];
            let mut tri_edges = [[0usize; 3]; 16];
            let mut built = [false; 16];
            for (i, tri) in tris.iter().enumerate() {
                for k in 0..3 {
                    let (a, b) = (tri[k].min(tri[(k + 1) % 3]), tri[k].max(tri[(k + 1) % 3]));
                    tri_edges[i][k] = match edges[..n_edges].iter().position(|&e| e == (a, b)) {
                        Some(p) => p,
                        None => {
                            base[n_edges] = uses.edge_uses[slots[i][k] as usize];
                            edges[n_edges] = (a, b);
                            n_edges += 1;
                            n_edges - 1
                        }
                    };
                }
                built[i] = on_face(tri) && uses.built(tri_of(t, tri));
            }
            // Cubes in no other triangle.
            let mut bare = 0u8;
            for j in 0..8u8 {
                if t.mask & (1 << j) != 0 && uses.vertices[t.vs[j as usize] as usize] == 0 {
                    bare |= 1 << j;
                }
            }
            let score = |sub: u16| {
                let mut count = base;
                let mut covered = 0u8;
                for (i, tri) in tris.iter().enumerate() {
                    if sub & (1 << i) == 0 {
                        continue;
                    }
                    for &j in tri {
                        covered |= 1 << j;
                    }
                    if !built[i] {
                        for &e in &tri_edges[i] {
                            count[e] += 1;
                        }
                    }
                }
                let used = &count[..n_edges];
                let holes = used.iter().filter(|&&c| c == 1).count() as u32;
                let surplus: u32 = used.iter().map(|&c| c.saturating_sub(2)).sum();
                let uncovered = (bare & !covered).count_ones();
                (holes, uncovered, surplus)
            };
            // A choice with no hole, no bare cube and no surplus use is
            // the best there is: kept without trying the others.
            if score(t.keep) != (0, 0, 0) {
                t.keep = best_subset(
                    tris,
                    &tri_edges[..tris.len()],
                    &built[..tris.len()],
                    &base[..n_edges],
                    bare,
                    t.keep,
                );
            }
            for (i, tri) in tris.iter().enumerate() {
                if t.keep & (1 << i) != 0 {
                    uses.add(tri_of(t, tri), on_face(tri), EdgeSlots::Known(slots[i]));
                }
            }
        }
    }
}

/// The subset of `tris` that [`settle`] keeps: the least, in this order,
/// hull edges used once (`base`: their use by the other triangles),
/// cubes of `bare` left in no triangle, surplus edge uses, differing from
/// `keep`, triangles, and the subset's bits. Every subset is visited in
/// Gray-code order, one triangle added or removed per step, so each costs
/// the update of three edge counts instead of a recount. Out of line: its
/// loop then keeps its state in registers (inlined in the scan, it spilled).
#[inline(never)]
pub(super) fn best_subset(
    tris: &[[u8; 3]],
    tri_edges: &[[usize; 3]],
    built: &[bool],
    base: &[u32],
    bare: u8,
    keep: u16,
) -> u16 {
    // A power of two long: an edge index masked needs no bounds check.
    let mut count = [0u32; 32];
    count[..base.len()].copy_from_slice(base);
    let mut holes = base.iter().filter(|&&c| c == 1).count() as u32;
    let mut surplus: u32 = base.iter().map(|&c| c.saturating_sub(2)).sum();
    // Triangles on each corner, a 4-bit count per corner (a corner is in
    // at most `SETTLE_MAX_TRIANGLES` < 16 triangles), added and removed a
    // triangle at a time with one addition: each triangle's corners as
    // ones in their counts.
    debug_assert!(tris.len() <= SETTLE_MAX_TRIANGLES && SETTLE_MAX_TRIANGLES < 16);
    let mut corners = 0u32;
    let mut ones = [0u32; 16];
    for (n, t) in ones.iter_mut().zip(tris) {
        *n = t.iter().fold(0, |n, &j| n | (1 << (4 * j)));
    }
    // `bare` with a one in each of its corners' counts.
    let bare = (0..8).fold(0u32, |b, j| b | (u32::from((bare >> j) & 1) << (4 * j)));
    // Bare cubes in no triangle: the bare counts that are zero, summed
    // into the top count by a multiplication (at most 8: no carry).
    let uncovered = |corners: u32| {
        let some = (corners | (corners >> 1) | (corners >> 2) | (corners >> 3)) & 0x1111_1111;
        (bare & !some).wrapping_mul(0x1111_1111) >> 28
    };
    // The key, packed in a word whose order is the tuple's: holes (≤ 18),
    // bare cubes left (≤ 8), surplus (< 2^20: at most 18 edges of a few
    // dozen triangles each), differing from `keep`, triangles (≤ 16), the
    // subset. A minimum without a branch per subset, and no `count_ones`
    // (software on the baseline x86-64 target): the triangles are counted
    // as they come and go.
    let key = |sub: u16, ntri: u32, holes: u32, surplus: u32, corners: u32| {
        debug_assert!(holes < 32 && surplus < 1 << 20 && ntri < 32);
        (u64::from(holes) << 46)
            | (u64::from(uncovered(corners)) << 42)
            | (u64::from(surplus) << 22)
            | (u64::from(sub != keep) << 21)
            | (u64::from(ntri) << 16)
            | u64::from(sub)
    };
    let (mut sub, mut ntri) = (0u16, 0u32);
    let mut best = key(sub, ntri, holes, surplus, corners);
    for g in 1..=u32::from(all_bits(tris.len())) {
        let i = g.trailing_zeros() as usize;
        sub ^= 1 << i;
        let add = sub & (1 << i) != 0;
        // +1 or −1.
        let d = if add { 1 } else { u32::MAX };
        ntri = ntri.wrapping_add(d);
        corners = corners.wrapping_add(ones[i].wrapping_mul(d));
        if !built[i] {
            for &e in &tri_edges[i] {
                let e = e & 31;
                let old = count[e];
                let new = old.wrapping_add(d);
                count[e] = new;
                holes = holes + u32::from(new == 1) - u32::from(old == 1);
                surplus = surplus + new.saturating_sub(2) - old.saturating_sub(2);
            }
        }
        best = best.min(key(sub, ntri, holes, surplus, corners));
    }
    best as u16
}

/// Builds the settled trials' triangles after the scan's, counting each
/// as resolved or left whole.
#[inline]
pub(super) fn build_trials(built: &mut Scanned, mut trace: Option<&mut Vec<u8>>) {
    let Scanned {
        faces,
        from_solids,
        trials,
        stats,
        ..
    } = built;
    for t in trials.iter() {
        let Shape::Solid(tris) = &table().configs[t.mask as usize].shape else {
            continue;
        };
        let whole = t.keep == all_bits(tris.len());
        if whole {
            stats.fallbacks += 1;
        } else {
            stats.disambiguated += 1;
        }
        for (i, tri) in tris.iter().enumerate() {
            if t.keep & (1 << i) != 0 {
                faces.push(tri.map(|j| t.vs[j as usize]));
                if on_face(tri) {
                    from_solids.push(faces.len() as u32 - 1);
                }
            }
        }
        if let Some(tr) = trace.as_deref_mut() {
            let class = table().configs[t.mask as usize].class;
            tr.resize(faces.len(), class | if whole { 0x80 } else { 0 });
        }
    }
}
