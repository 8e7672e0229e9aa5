//! The sparse band of signed distances at the lattice's vertices
//! ([`crate::lattice`]), stamped sample by sample.
//!
//! Follows the thesis's §4.2 (after Hoppe et al. 1992): the signed distance
//! of a cube vertex `v` is its distance to the tangent plane of the closest
//! sample, `f(v) = (v − oᵢ) · nᵢ`, with `oᵢ` the sample and `nᵢ` its normal.
//!
//! Departures, and why:
//! - **Sign convention.** The thesis calls inside `+1`; here a vertex is
//!   *inside* when `f(v) < 0` (normals point outwards, the usual convention
//!   of meshes and scanners). Only the naming differs.
//! - **Sparse band, no search structure.** Each sample *stamps* the 4×4×4
//!   lattice vertices of its cube and the 26 cubes around it, and a vertex
//!   keeps the closest sample seen, so the field is a band about two cubes
//!   wide around the data (never a dense n³ grid). The 26 neighbours are
//!   needed: a cube the surface merely clips often holds no sample, and
//!   stamping only a sample's own 8 corners leaves such cubes with a
//!   missing corner, hence holes. Every sample within one cube size of a
//!   vertex is a candidate — the only ones the thesis's "closest range
//!   point" can sensibly be for a vertex that marching cubes will use.
//!   Stamping needs no kd-tree and makes adding a new range image touch
//!   only the cubes around its samples (the incremental API).
//! - **Storage: a sparse grid of dense 8³ bricks** (see
//!   [`SignedDistanceField`]): 1–8 map lookups per sample instead of one
//!   per lattice vertex (64), and the 64 updates become array writes. A
//!   sample's 4 vertices of a brick row are compared at once (one SSE2
//!   window, [`stamp_window`]), and a window the sample wins is updated
//!   with blends.
//! - **Ties** (two samples at exactly the same distance) keep the sample
//!   added first, so the field does not depend on hash order and adding
//!   scans one at a time gives the same field as adding them together.

use glam::Vec3;
use lodkit_mesh::PointCloud;

use crate::lattice::{
    BRICK, BRICK_BITS, BRICK_VOLUME, Grid, KeyMap, LOCAL_MASK, brick_key, local_index, pack, unpack,
};

/// One lattice vertex of the band: its closest sample's data.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg(test)]
pub struct FieldVertex {
    /// Squared distance to the closest sample (selection key).
    pub dist2: f32,
    /// Signed distance to that sample's tangent plane (negative = inside).
    pub distance: f32,
    /// The closest sample's normal.
    pub normal: Vec3,
    /// The closest sample's colour (opaque grey without colours).
    pub color: [u8; 4],
}

/// Largest offset along the tangent plane, in cubes, for a band vertex to
/// be defined when the rule is on (see [`SignedDistanceField::slot_defined`]). The
/// default cube is 1.5 to 2 sample spacings, so on continuous data some
/// sample is always within half a cube tangentially; 1.5 leaves room for
/// irregular sampling. On scans the rule removes the spurious sheets past
/// their edges; on closed meshes it would open holes at thin features, so
/// mesh inputs build without it.
pub const TANGENTIAL_LIMIT: f32 = 1.5;

/// Neutral colour for inputs without colours.
pub const NO_COLOR: [u8; 4] = [200, 200, 200, 255];

/// One band vertex as stored: the selection key, the signed distance and
/// the winning sample (its normal and colour are looked up on demand).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Slot {
    pub dist2: f32,
    pub distance: f32,
    /// Index into the field's samples; `u32::MAX` = no sample reached the
    /// vertex (then `dist2` is `+∞`).
    pub sample: u32,
}

impl Slot {
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.sample == u32::MAX
    }
}

/// One brick's columns of [`Slot`]s, for the stamping.
struct BrickColumns<'a> {
    dist2: &'a mut [f32],
    distance: &'a mut [f32],
    sample: &'a mut [u32],
}

/// One stamp of a sample into a 4-vertex window of a brick row: the
/// window's squared distances `(x2[t] + y2) + z2` and signed distances
/// `(xd[t] + yd) + zd` for lanes `t = 0..4`.
#[derive(Clone, Copy)]
struct Stamp<'a> {
    x2: &'a [f32; 4],
    y2: f32,
    z2: f32,
    xd: &'a [f32; 4],
    yd: f32,
    zd: f32,
    id: u32,
}

/// Stamps sample `st.id` into the 4-vertex window at `row` of a brick (a
/// window inside one brick row): lanes whose squared distance is below the
/// stored one take the sample. Returns the mask of those lanes and how
/// many of them no sample had reached.
///
/// On x86_64 this is [`stamp_window_sse2`] (SSE2 is part of that target's
/// baseline, so no run-time detection); elsewhere, wasm32 included,
/// [`stamp_window_scalar`]. Both do the same IEEE single-precision
/// operations in the same order, so they give the same bits (the test
/// `sse2_and_scalar_stamping_agree` runs both on the same inputs).
#[inline(always)]
fn stamp_window(brick: &mut BrickColumns, row: usize, st: Stamp) -> (u32, u32) {
    #[cfg(target_arch = "x86_64")]
    {
        stamp_window_sse2(brick, row, st)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        stamp_window_scalar(brick, row, st)
    }
}

/// [`stamp_window`], one lane at a time.
#[inline(always)]
#[cfg_attr(target_arch = "x86_64", allow(dead_code))]
fn stamp_window_scalar(brick: &mut BrickColumns, row: usize, st: Stamp) -> (u32, u32) {
    let dist2 = &mut brick.dist2[row..row + 4];
    let distance = &mut brick.distance[row..row + 4];
    let sample = &mut brick.sample[row..row + 4];
    let (mut wins, mut reached) = (0u32, 0u32);
    for t in 0..4 {
        let d = (st.x2[t] + st.y2) + st.z2;
        if d < dist2[t] {
            dist2[t] = d;
            distance[t] = (st.xd[t] + st.yd) + st.zd;
            reached += (sample[t] == u32::MAX) as u32;
            sample[t] = st.id;
            wins |= 1 << t;
        }
    }
    (wins, reached)
}

/// [`stamp_window`] with SSE2: the four lanes compared at once, and a
/// window the sample wins updated with blends.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
#[allow(unsafe_code)]
fn stamp_window_sse2(brick: &mut BrickColumns, row: usize, st: Stamp) -> (u32, u32) {
    use std::arch::x86_64::{
        __m128, __m128i, _mm_add_ps, _mm_and_ps, _mm_and_si128, _mm_andnot_ps, _mm_andnot_si128,
        _mm_castps_si128, _mm_castsi128_ps, _mm_cmpeq_epi32, _mm_cmplt_ps, _mm_loadu_ps,
        _mm_loadu_si128, _mm_movemask_ps, _mm_or_ps, _mm_or_si128, _mm_set1_epi32, _mm_set1_ps,
        _mm_storeu_ps, _mm_storeu_si128,
    };
    let dist2 = &mut brick.dist2[row..row + 4];
    let distance = &mut brick.distance[row..row + 4];
    let sample = &mut brick.sample[row..row + 4];
    // SAFETY: SSE2 is part of the x86_64 baseline, so the intrinsics are
    // available; every load and store is an unaligned access to the 4
    // lanes of a slice of length 4 (bounds checked by the slicing above),
    // and stores go through mutable borrows.
    unsafe {
        let d = _mm_add_ps(
            _mm_add_ps(_mm_loadu_ps(st.x2.as_ptr()), _mm_set1_ps(st.y2)),
            _mm_set1_ps(st.z2),
        );
        let old = _mm_loadu_ps(dist2.as_ptr());
        let m = _mm_cmplt_ps(d, old);
        let wins = _mm_movemask_ps(m) as u32;
        if wins == 0 {
            return (0, 0);
        }
        let blend = |new: __m128, old: __m128| _mm_or_ps(_mm_and_ps(m, new), _mm_andnot_ps(m, old));
        _mm_storeu_ps(dist2.as_mut_ptr(), blend(d, old));
        let dn = _mm_add_ps(
            _mm_add_ps(_mm_loadu_ps(st.xd.as_ptr()), _mm_set1_ps(st.yd)),
            _mm_set1_ps(st.zd),
        );
        let od = _mm_loadu_ps(distance.as_ptr());
        _mm_storeu_ps(distance.as_mut_ptr(), blend(dn, od));
        let mi = _mm_castps_si128(m);
        let os = _mm_loadu_si128(sample.as_ptr() as *const __m128i);
        let empty = _mm_movemask_ps(_mm_castsi128_ps(_mm_cmpeq_epi32(os, _mm_set1_epi32(-1))));
        let ns = _mm_or_si128(
            _mm_and_si128(mi, _mm_set1_epi32(st.id as i32)),
            _mm_andnot_si128(mi, os),
        );
        _mm_storeu_si128(sample.as_mut_ptr() as *mut __m128i, ns);
        (wins, (wins & empty as u32).count_ones())
    }
}

/// The sparse signed-distance band, stored as a sparse grid of dense bricks.
///
/// **Layout.** The lattice is cut into `8³`-vertex bricks; a brick exists
/// once a sample stamps one of its vertices and then holds all 512 of its
/// vertices densely (12 bytes each: `dist2`, `distance`, winning sample).
/// A small map finds a brick by its key. Stamping a sample's `4³` block
/// touches 1–8 bricks, so the map is consulted a few
/// times per sample instead of 64 times, and the 64 vertex updates are
/// plain array writes. The winning sample's normal and colour are kept
/// once per sample and read only for the vertices marching cubes uses.
/// The band of a surface fills about a third of its bricks.
///
/// **Changes.** Each brick has a bit per vertex set when the vertex's
/// value changed during the last [`SignedDistanceField::add`]; the
/// incremental builder recomputes the cubes around those vertices only.
#[derive(Debug, Clone)]
pub struct SignedDistanceField {
    pub grid: Grid,
    /// Hoppe's tangential rule in object units (`f32::INFINITY` = off).
    pub tangential_limit: f32,
    /// Brick key ([`brick_key`]) → brick number.
    bricks: KeyMap<u32>,
    /// Brick number → brick coordinates (brick units).
    brick_coords: Vec<[u32; 3]>,
    /// Per vertex, `BRICK_VOLUME` per brick, brick after brick (columns of
    /// [`Slot`], kept apart so a brick row's 8 `dist2` are contiguous):
    /// squared distance to the closest sample (`+∞` = not reached yet) …
    dist2: Vec<f32>,
    /// … signed distance to its tangent plane …
    distance: Vec<f32>,
    /// … and its number (`u32::MAX` = not reached yet).
    sample: Vec<u32>,
    /// Per brick: one bit per vertex, set if it changed in the last add.
    changed: Vec<[u64; BRICK_VOLUME / 64]>,
    /// Normal and colour of every sample ever added.
    normals: Vec<Vec3>,
    colors: Vec<[u8; 4]>,
    /// Vertices reached by some sample.
    defined: usize,
}

impl SignedDistanceField {
    pub fn new(grid: Grid) -> Self {
        SignedDistanceField {
            grid,
            tangential_limit: f32::INFINITY,
            bricks: KeyMap::default(),
            brick_coords: Vec::new(),
            dist2: Vec::new(),
            distance: Vec::new(),
            sample: Vec::new(),
            changed: Vec::new(),
            normals: Vec::new(),
            colors: Vec::new(),
            defined: 0,
        }
    }

    /// The brick number of brick key `bk`, creating the brick if needed.
    fn brick_or_insert(&mut self, bk: u64, coords: [u32; 3]) -> usize {
        let next = self.brick_coords.len() as u32;
        let b = *self.bricks.entry(bk).or_insert(next);
        if b == next {
            self.brick_coords.push(coords);
            let n = self.dist2.len() + BRICK_VOLUME;
            self.dist2.resize(n, f32::INFINITY);
            self.distance.resize(n, 0.0);
            self.sample.resize(n, u32::MAX);
            self.changed.push([0; BRICK_VOLUME / 64]);
        }
        b as usize
    }

    /// Stamps `samples` into the band; returns how many lattice vertices
    /// changed value (their keys: [`SignedDistanceField::changed_keys`]).
    /// PointCloud outside the lattice are clamped into its border cubes.
    /// Non-finite samples are skipped.
    ///
    /// Each sample stamps the `4³` lattice vertices of its cube and the 26
    /// cubes around it; a vertex keeps the closest sample, ties to the
    /// sample added first (samples are visited in order, and a later one
    /// wins only when strictly closer).
    pub fn add(&mut self, samples: &PointCloud) -> usize {
        for c in &mut self.changed {
            *c = [0; BRICK_VOLUME / 64];
        }
        // A first guess of the bricks this add creates, so the columns are
        // not copied over and over as they grow (a dense surface scan makes
        // about one brick per 180 samples; untouched capacity costs no
        // memory).
        let guess = samples.len() / 128 * BRICK_VOLUME;
        self.dist2.reserve(guess);
        self.distance.reserve(guess);
        self.sample.reserve(guess);
        self.normals.reserve(samples.len());
        self.colors.reserve(samples.len());
        let g = self.grid;
        let mut defined = 0usize;
        let normals = samples.normals.as_deref().unwrap_or_default();
        for (i, (&p, &n)) in samples.positions.iter().zip(normals).enumerate() {
            if !p.is_finite() || !n.is_finite() {
                continue;
            }
            let Ok(id) = u32::try_from(self.normals.len()) else {
                break; // 2³² samples: far beyond any memory this runs in
            };
            if id == u32::MAX {
                break;
            }
            self.normals.push(n);
            self.colors
                .push(samples.colors.as_ref().map_or(NO_COLOR, |c| c[i]));
            let [cx, cy, cz] = g.cell_of(p);
            // The 4×4×4 vertices of the sample's cube and its 26 neighbours
            // (those at negative coordinates do not exist).
            let lo = [cx.max(1) - 1, cy.max(1) - 1, cz.max(1) - 1];
            let hi = [cx + 2, cy + 2, cz + 2];
            // Per axis: the offset from the sample, its square and its
            // product with the normal, with exactly the arithmetic of
            // `g.position(key) - p`, `distance_squared` and `dot` (each
            // component is rounded on its own, sums left to right).
            let mut off = [[0f32; 4]; 3];
            let mut sq = [[0f32; 4]; 3];
            let mut dn = [[0f32; 4]; 3];
            for a in 0..3 {
                for k in 0..=(hi[a] - lo[a]) as usize {
                    let v = g.origin[a] + (lo[a] + k as u32) as f32 * g.cube;
                    off[a][k] = v - p[a];
                    sq[a][k] = off[a][k] * off[a][k];
                    dn[a][k] = off[a][k] * n[a];
                }
            }
            for bz in lo[2] >> BRICK_BITS..=hi[2] >> BRICK_BITS {
                for by in lo[1] >> BRICK_BITS..=hi[1] >> BRICK_BITS {
                    for bx in lo[0] >> BRICK_BITS..=hi[0] >> BRICK_BITS {
                        let b = self.brick_or_insert(pack(bx, by, bz), [bx, by, bz]);
                        let base = [bx << BRICK_BITS, by << BRICK_BITS, bz << BRICK_BITS];
                        // This brick's part of the block, as inclusive ranges.
                        let r = |a: usize| (lo[a].max(base[a]), hi[a].min(base[a] + LOCAL_MASK));
                        let ((xa, xb), (ya, yb), (za, zb)) = (r(0), r(1), r(2));
                        // A 4-vertex window of each brick row covers the
                        // block's part (at most 4 vertices): lanes outside
                        // the part get +∞ and never win.
                        let p0 = (xa - base[0]).min(BRICK - 4);
                        let mut xsq = [f32::INFINITY; 4];
                        let mut xdn = [0f32; 4];
                        for t in 0..4 {
                            let x = base[0] + p0 + t as u32;
                            if (xa..=xb).contains(&x) {
                                xsq[t] = sq[0][(x - lo[0]) as usize];
                                xdn[t] = dn[0][(x - lo[0]) as usize];
                            }
                        }
                        let first = b * BRICK_VOLUME;
                        let mut brick = BrickColumns {
                            dist2: &mut self.dist2[first..][..BRICK_VOLUME],
                            distance: &mut self.distance[first..][..BRICK_VOLUME],
                            sample: &mut self.sample[first..][..BRICK_VOLUME],
                        };
                        let changed = &mut self.changed[b];
                        for z in za..=zb {
                            let k = (z - lo[2]) as usize & 3;
                            for y in ya..=yb {
                                let j = (y - lo[1]) as usize & 3;
                                let row = local_index(0, y, z) + p0 as usize;
                                let (wins, reached) = stamp_window(
                                    &mut brick,
                                    row,
                                    Stamp {
                                        x2: &xsq,
                                        y2: sq[1][j],
                                        z2: sq[2][k],
                                        xd: &xdn,
                                        yd: dn[1][j],
                                        zd: dn[2][k],
                                        id,
                                    },
                                );
                                if wins != 0 {
                                    defined += reached as usize;
                                    // The window lies in one 8-vertex row, so
                                    // in one word of the bit set.
                                    changed[row / 64] |= (wins as u64) << (row % 64);
                                }
                            }
                        }
                    }
                }
            }
        }
        self.defined += defined;
        self.changed
            .iter()
            .flatten()
            .map(|w| w.count_ones() as usize)
            .sum()
    }

    /// Keys of the lattice vertices changed by the last
    /// [`SignedDistanceField::add`], sorted.
    #[cfg(test)]
    pub fn changed_keys(&self) -> Vec<u64> {
        let mut out = Vec::new();
        for b in 0..self.brick_count() {
            self.for_each_changed(b, |x, y, z| out.push(pack(x, y, z)));
        }
        out.sort_unstable();
        out
    }

    /// Calls `f(x, y, z)` for every vertex of brick `b` changed by the last
    /// add.
    #[inline]
    pub fn for_each_changed(&self, b: usize, mut f: impl FnMut(u32, u32, u32)) {
        let [bx, by, bz] = self.brick_coords[b].map(|c| c << BRICK_BITS);
        for (w, &word) in self.changed[b].iter().enumerate() {
            let mut m = word;
            while m != 0 {
                let li = (w * 64) as u32 + m.trailing_zeros();
                m &= m - 1;
                f(
                    bx + (li & LOCAL_MASK),
                    by + (li >> BRICK_BITS & LOCAL_MASK),
                    bz + (li >> (2 * BRICK_BITS)),
                );
            }
        }
    }

    /// Brick `b`'s vertices as bit masks, one word per `z` slice (bit
    /// `x + 8y`): which are defined ([`SignedDistanceField::slot_defined`]),
    /// which have a negative signed distance (inside), and which a sample
    /// has reached.
    pub fn brick_masks(&self, b: usize) -> [[u64; BRICK as usize]; 3] {
        let first = b * BRICK_VOLUME;
        let dist2 = &self.dist2[first..][..BRICK_VOLUME];
        let distance = &self.distance[first..][..BRICK_VOLUME];
        let sample = &self.sample[first..][..BRICK_VOLUME];
        let limit = self.tangential_limit;
        let [mut defined, mut inside, mut reached] = [[0u64; BRICK as usize]; 3];
        for (z, ((d, n), r)) in defined
            .iter_mut()
            .zip(&mut inside)
            .zip(&mut reached)
            .enumerate()
        {
            for bit in 0..64 {
                let li = z * 64 + bit;
                let s = Slot {
                    dist2: dist2[li],
                    distance: distance[li],
                    sample: sample[li],
                };
                let ok = !s.is_empty()
                    && (limit == f32::INFINITY
                        || s.dist2 - s.distance * s.distance <= limit * limit);
                *d |= (ok as u64) << bit;
                *n |= ((s.distance < 0.0) as u64) << bit;
                *r |= (!s.is_empty() as u64) << bit;
            }
        }
        [defined, inside, reached]
    }

    /// Makes vertex `(x, y, z)` of brick `b` unreached, as if no sample
    /// had stamped it ([`crate::band_edge_pruning`] drops band-edge
    /// vertices whose sign is a guess).
    pub fn clear(&mut self, b: usize, x: u32, y: u32, z: u32) {
        let i = b * BRICK_VOLUME + local_index(x, y, z);
        if self.sample[i] != u32::MAX {
            self.defined -= 1;
        }
        self.dist2[i] = f32::INFINITY;
        self.distance[i] = 0.0;
        self.sample[i] = u32::MAX;
    }

    /// Number of bricks.
    pub fn brick_count(&self) -> usize {
        self.brick_coords.len()
    }

    /// The brick number holding lattice vertex `(x, y, z)`, if it exists.
    #[inline]
    pub fn brick_of(&self, x: u32, y: u32, z: u32) -> Option<usize> {
        self.bricks.get(&brick_key(x, y, z)).map(|&b| b as usize)
    }

    /// Coordinates (brick units) of brick `b`.
    #[inline]
    pub fn brick_coords(&self, b: usize) -> [u32; 3] {
        self.brick_coords[b]
    }

    /// The stored slot of vertex `(x, y, z)` in brick `b` (which must hold
    /// it), defined or not and before the tangential rule.
    #[inline]
    pub fn slot_in(&self, b: usize, x: u32, y: u32, z: u32) -> Slot {
        self.slot_at(b * BRICK_VOLUME + local_index(x, y, z))
    }

    #[inline]
    fn slot_at(&self, i: usize) -> Slot {
        Slot {
            dist2: self.dist2[i],
            distance: self.distance[i],
            sample: self.sample[i],
        }
    }

    /// Whether a stored slot is a defined value: reached, and (when the
    /// rule is on, for scan data) its closest sample's tangent plane is a
    /// fair estimate there — Hoppe et al.'s rule: the vertex's offset
    /// *along* the tangent plane from the sample is at most
    /// [`TANGENTIAL_LIMIT`] cubes. Beyond that the vertex is beside the
    /// data (past a scan's edge, or across a thin feature) rather than
    /// above or below it, and its sign is a guess that would draw a
    /// spurious sheet.
    #[inline]
    pub fn slot_defined(&self, s: &Slot) -> bool {
        let limit = self.tangential_limit;
        !s.is_empty()
            && (limit == f32::INFINITY || s.dist2 - s.distance * s.distance <= limit * limit)
    }

    /// The defined slot of lattice vertex `key`, if any.
    #[inline]
    pub fn slot(&self, key: u64) -> Option<Slot> {
        let [x, y, z] = unpack(key);
        let b = self.brick_of(x, y, z)?;
        let s = self.slot_in(b, x, y, z);
        self.slot_defined(&s).then_some(s)
    }

    /// The normal of sample `i` (a [`Slot::sample`]).
    #[inline]
    pub fn sample_normal(&self, i: u32) -> Vec3 {
        self.normals[i as usize]
    }

    /// The colour of sample `i` (a [`Slot::sample`]).
    #[inline]
    pub fn sample_color(&self, i: u32) -> [u8; 4] {
        self.colors[i as usize]
    }

    /// The full value of a stored slot.
    #[inline]
    #[cfg(test)]
    pub fn vertex_of(&self, s: &Slot) -> FieldVertex {
        FieldVertex {
            dist2: s.dist2,
            distance: s.distance,
            normal: self.normals[s.sample as usize],
            color: self.colors[s.sample as usize],
        }
    }

    /// Sets lattice vertex `key` to `v` directly, as if a sample with `v`'s
    /// normal and colour had been stamped there (for tests and synthetic
    /// fields). Marks it changed.
    #[cfg(test)]
    pub fn set(&mut self, key: u64, v: FieldVertex) {
        let [x, y, z] = unpack(key);
        let id = self.normals.len() as u32;
        self.normals.push(v.normal);
        self.colors.push(v.color);
        let b = self.brick_or_insert(brick_key(x, y, z), [x, y, z].map(|c| c >> BRICK_BITS));
        let li = local_index(x, y, z);
        let i = b * BRICK_VOLUME + li;
        if self.sample[i] == u32::MAX {
            self.defined += 1;
        }
        self.dist2[i] = v.dist2;
        self.distance[i] = v.distance;
        self.sample[i] = id;
        self.changed[b][li / 64] |= 1 << (li % 64);
    }

    /// Every stored (reached) vertex and its value, before the tangential
    /// rule, in brick order.
    #[cfg(test)]
    pub fn iter(&self) -> impl Iterator<Item = (u64, FieldVertex)> + '_ {
        (0..self.brick_count()).flat_map(move |b| {
            let [bx, by, bz] = self.brick_coords[b].map(|c| c << BRICK_BITS);
            (0..BRICK_VOLUME as u32).filter_map(move |li| {
                let s = self.slot_at(b * BRICK_VOLUME + li as usize);
                (!s.is_empty()).then(|| {
                    let key = pack(
                        bx + (li & LOCAL_MASK),
                        by + (li >> BRICK_BITS & LOCAL_MASK),
                        bz + (li >> (2 * BRICK_BITS)),
                    );
                    (key, self.vertex_of(&s))
                })
            })
        })
    }

    /// Number of lattice vertices in the band.
    #[cfg(test)]
    pub fn len(&self) -> usize {
        self.defined
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use lodkit_mesh::Aabb;
    use rand_xoshiro::Xoshiro256PlusPlus;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};
    use std::collections::HashMap;

    /// The stamping rule written plainly: every sample visits its 64
    /// vertices, a vertex keeps the strictly closest sample, first wins ties.
    fn reference_field(g: &Grid, s: &PointCloud) -> HashMap<u64, (f32, f32, u32)> {
        let mut out: HashMap<u64, (f32, f32, u32)> = HashMap::new();
        for (i, (&p, &n)) in s
            .positions
            .iter()
            .zip(s.normals.as_deref().unwrap())
            .enumerate()
        {
            let [cx, cy, cz] = g.cell_of(p);
            for corner in 0..64u32 {
                let (dx, dy, dz) = (corner & 3, corner >> 2 & 3, corner >> 4);
                if cx + dx < 1 || cy + dy < 1 || cz + dz < 1 {
                    continue;
                }
                let key = pack(cx + dx - 1, cy + dy - 1, cz + dz - 1);
                let v = g.position(key);
                let d2 = v.distance_squared(p);
                let e = out.entry(key).or_insert((f32::INFINITY, 0.0, u32::MAX));
                if d2 < e.0 {
                    *e = (d2, (v - p).dot(n), i as u32);
                }
            }
        }
        out
    }

    fn random_samples(rng: &mut Xoshiro256PlusPlus, count: usize, size: f32) -> PointCloud {
        let mut next = || (rng.next_u64() >> 40) as f32 / (1u64 << 24) as f32;
        let mut s = PointCloud::default();
        for _ in 0..count {
            let p = Vec3::new(next(), next(), next()) * size;
            let n = Vec3::new(next() - 0.5, next() - 0.5, next() - 0.5).normalize_or(Vec3::Z);
            s.positions.push(p);
            s.normals.get_or_insert_default().push(n);
        }
        s
    }

    #[test]
    fn bricks_hold_exactly_the_closest_sample_of_every_vertex() {
        let mut seed = Xoshiro256PlusPlus::seed_from_u64(0x9e37_79b9_7f4a_7c15);
        // Spread over several bricks (20 cubes ≈ 3 bricks a side), with
        // duplicates so that ties occur.
        let mut s = random_samples(&mut seed, 3000, 1.0);
        let dup = s.positions[..200].to_vec();
        s.positions.extend(dup);
        let normals = s.normals.as_mut().unwrap();
        let dupn: Vec<Vec3> = normals[..200].iter().map(|n| -*n).collect();
        normals.extend(dupn);
        let g = Grid::new(s.bbox(), 20).unwrap();
        let mut f = SignedDistanceField::new(g);
        assert_eq!(f.add(&s), f.len());
        let reference = reference_field(&g, &s);
        assert_eq!(f.len(), reference.len());
        for (k, v) in f.iter() {
            let (d2, distance, i) = reference[&k];
            assert_eq!(
                (v.dist2, v.distance),
                (d2, distance),
                "vertex {:?}",
                unpack(k)
            );
            assert_eq!(v.normal, s.normals.as_ref().unwrap()[i as usize]);
        }
        // Adding in two batches gives the same field and reports as
        // changed exactly the vertices the second batch improved.
        let (a, b) = s.positions.split_at(1700);
        let (na, nb) = s.normals.as_deref().unwrap().split_at(1700);
        let part = |p: &[Vec3], n: &[Vec3]| PointCloud {
            positions: p.to_vec(),
            normals: Some(n.to_vec()),
            colors: None,
        };
        let mut two = SignedDistanceField::new(g);
        two.add(&part(a, na));
        let before: HashMap<u64, FieldVertex> = two.iter().collect();
        let changed = two.add(&part(b, nb));
        let after: HashMap<u64, FieldVertex> = two.iter().collect();
        let expect: Vec<u64> = {
            let mut v: Vec<u64> = after
                .iter()
                .filter(|(k, v)| before.get(k) != Some(v))
                .map(|(k, _)| *k)
                .collect();
            v.sort_unstable();
            v
        };
        assert_eq!(two.changed_keys(), expect);
        assert_eq!(changed, expect.len());
        let one: HashMap<u64, FieldVertex> = f.iter().collect();
        assert_eq!(after, one);
    }

    /// The SSE2 window and its scalar twin, on the same windows: random
    /// distances (infinite lanes included, as outside a block's part),
    /// stored values half beaten and half not, reached and empty lanes, and
    /// ties (equal distances never win).
    #[cfg(target_arch = "x86_64")]
    #[test]
    fn sse2_and_scalar_stamping_agree() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x0123_4567_89ab_cdef);
        let mut next = move || rng.next_u64();
        let mut f = move || (next() >> 40) as f32 / (1u64 << 24) as f32;
        for round in 0..20_000u32 {
            let mut dist2: Vec<f32> = (0..8).map(|_| 3.0 * f()).collect();
            let mut distance: Vec<f32> = (0..8).map(|_| f() - 0.5).collect();
            let sample: Vec<u32> = (0..8)
                .map(|i| if (round >> i) & 1 == 0 { u32::MAX } else { i })
                .collect();
            for t in 0..8 {
                if sample[t] == u32::MAX {
                    (dist2[t], distance[t]) = (f32::INFINITY, 0.0);
                }
            }
            let mut x2 = [f(), f(), f(), f()];
            if round % 5 == 0 {
                x2[(round / 5 % 4) as usize] = f32::INFINITY;
            }
            let xd = [f() - 0.5, f() - 0.5, f() - 0.5, f() - 0.5];
            let (y2, z2, yd, zd) = (f(), f(), f() - 0.5, f() - 0.5);
            let row = (round % 5) as usize;
            if round % 7 == 0 {
                dist2[row] = (x2[0] + y2) + z2; // a tie: the stored sample stays
            }
            let st = Stamp {
                x2: &x2,
                y2,
                z2,
                xd: &xd,
                yd,
                zd,
                id: 1000 + round,
            };
            let (mut a, mut b) = (
                (dist2.clone(), distance.clone(), sample.clone()),
                (dist2, distance, sample),
            );
            let ra = stamp_window_sse2(
                &mut BrickColumns {
                    dist2: &mut a.0,
                    distance: &mut a.1,
                    sample: &mut a.2,
                },
                row,
                st,
            );
            let rb = stamp_window_scalar(
                &mut BrickColumns {
                    dist2: &mut b.0,
                    distance: &mut b.1,
                    sample: &mut b.2,
                },
                row,
                st,
            );
            assert_eq!(ra, rb, "round {round}");
            let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&a.0), bits(&b.0), "round {round}");
            assert_eq!(bits(&a.1), bits(&b.1), "round {round}");
            assert_eq!(a.2, b.2, "round {round}");
        }
    }

    #[test]
    fn plane_samples_give_signed_distances_to_the_plane() {
        let b = Aabb {
            min: Vec3::ZERO,
            max: Vec3::ONE,
        };
        let g = Grid::new(b, 10).unwrap();
        let mut s = PointCloud::default();
        for i in 0..30 {
            for j in 0..30 {
                s.positions
                    .push(Vec3::new(i as f32 / 29.0, j as f32 / 29.0, 0.53));
                s.normals.get_or_insert_default().push(Vec3::Z);
            }
        }
        let mut f = SignedDistanceField::new(g);
        let changed = f.add(&s);
        assert_eq!(changed, f.len());
        assert_eq!(f.changed_keys().len(), f.len());
        for (k, v) in f.iter() {
            let p = g.position(k);
            assert!((v.distance - (p.z - 0.53)).abs() < 1e-5);
        }
        // Adding the same samples again changes nothing.
        assert_eq!(f.add(&s), 0);
        assert!(f.changed_keys().is_empty());
    }
}
