//! The mesh being simplified, and the input stage that builds it.
//!
//! The paper's input is an indexed mesh whose vertices are the topology's
//! vertices (§4). Real `TriMesh`es are not always like that: a UV or normal
//! seam stores one vertex per side, and STL-style soups store one per
//! corner. Collapsing such a mesh as-is tears seams open and cannot
//! simplify soups at all. So before the first pass (a departure from the
//! paper, outside its stages) positions are welded exactly:
//! - the *vertices* of the working mesh are the distinct positions; rings,
//!   costs, collapses and flags all work on them;
//! - when the input has attributes and seams, each face corner also keeps
//!   its *wedge* — the input vertex that carried its attributes (Hoppe
//!   1999's wedges) — so both sides of a seam move together and keep their
//!   own normals / UVs (see `collapse.rs` for the seam rules);
//! - without seams, wedges and vertices coincide and no corner table exists;
//! - without attributes, duplicates are simply merged;
//! - with *groups* (one id per input vertex, e.g. a material: see
//!   [`Simplifier::simplify_grouped`](crate::Simplifier::simplify_grouped)),
//!   the group is part of the wedge key like an attribute value, so a
//!   border between groups is a seam: both sides move together and no
//!   wedge ever takes another group's id. Each wedge keeps its group
//!   (`group`), which is never interpolated.
//!
//! Memory: positions 12 B, flags 1 B and accumulated error 4 B per vertex,
//! faces 12 B each, plus 12 B per face of corner wedges only for meshes
//! with attribute seams.

use rustc_hash::FxHashMap;

use glam::Vec3;
use lodkit_mesh::TriMesh;

use crate::Error;
use crate::options::AttributeWeights;
use crate::quadric::MAX_ATTR;
use crate::ring_table::{DEAD, Flag};

/// Offsets of each attribute inside a wedge's attribute vector.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct AttrLayout {
    pub normal: Option<usize>,
    pub color: Option<usize>,
    pub uv: Option<usize>,
    /// Total components per wedge (0 = no attributes).
    pub k: usize,
}

#[derive(Debug, Clone, Default)]
pub struct WorkMesh {
    pub pos: Vec<Vec3>,
    pub faces: Vec<[u32; 3]>,
    pub live_faces: usize,
    pub flags: Vec<Flag>,
    /// Estimated object-space distance from the input, per vertex,
    /// accumulated over collapses and levels.
    pub err: Vec<f32>,
    pub layout: AttrLayout,
    /// Raw attribute values (colours in [0, 1]), `layout.k` per wedge.
    pub attr: Vec<f32>,
    /// Per-component cost scale (`weight × extent`).
    pub attr_scale: [f32; MAX_ATTR],
    /// Corner wedges, parallel to `faces`; empty when every vertex is its
    /// own only wedge.
    pub wedges: Vec<[u32; 3]>,
    /// Group id per wedge (per vertex when there are no wedges); empty
    /// when the input has no groups.
    pub group: Vec<u32>,
    /// Per vertex: never contracted, and never moved by a collapse onto
    /// it (see [`Simplifier::simplify_locked`](crate::Simplifier::simplify_locked));
    /// empty when no vertex is locked this way.
    pub locked: Vec<bool>,
    /// Weight of border planes (see `quadric::BORDER_WEIGHT`).
    pub border_weight: f64,
    /// The working frame: `pos` and `err` are the input's object-space
    /// values times `2^scale_exp` ([`WorkMesh::unit`]), chosen at load so
    /// the bounding box's largest side lies in `[1, 2)`. A power of two
    /// scales every float exactly, so the collapses made are the same at
    /// any scale (the input's own rounding aside) and no cross product,
    /// area or squared distance underflows or overflows `f32` for tiny or
    /// huge models; values are scaled back on the way out.
    pub scale_exp: i32,
}

impl WorkMesh {
    /// The wedge (attribute vertex) of corner `c` of face `f`.
    #[inline]
    pub fn wedge(&self, f: usize, c: usize) -> u32 {
        if self.wedges.is_empty() {
            self.faces[f][c]
        } else {
            self.wedges[f][c]
        }
    }

    #[inline]
    pub fn has_wedges(&self) -> bool {
        !self.wedges.is_empty()
    }

    /// Loads `mesh`: validates, welds positions, lays out attributes.
    /// Faces that repeat a vertex (by index, or by position after welding)
    /// carry no area and no topology: they are dropped.
    pub fn load(
        &mut self,
        mesh: &TriMesh,
        weights: &AttributeWeights,
        groups: Option<&[u32]>,
        locked: Option<&[bool]>,
        scratch: &mut Vec<u32>,
    ) -> Result<(), Error> {
        let n = mesh.positions.len();
        if groups.is_some_and(|g| g.len() != n) || locked.is_some_and(|l| l.len() != n) {
            return Err(Error::AttributeLength);
        }
        if n >= u32::MAX as usize - 1 {
            return Err(Error::TooLarge(n));
        }
        if mesh.faces.len() >= crate::ring_table::MAX_FACES {
            return Err(Error::TooManyFaces(mesh.faces.len()));
        }
        if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
            return Err(Error::NonFinite(i));
        }
        for (fi, f) in mesh.faces.iter().enumerate() {
            if let Some(&v) = f.iter().find(|&&v| v as usize >= n) {
                return Err(Error::BadIndex {
                    face: fi,
                    index: v,
                    vertices: n,
                });
            }
        }
        let attr_len_ok = |len: Option<usize>| len.is_none_or(|l| l == n);
        if !attr_len_ok(mesh.normals.as_ref().map(Vec::len))
            || !attr_len_ok(mesh.colors.as_ref().map(Vec::len))
            || !attr_len_ok(mesh.uvs.as_ref().map(Vec::len))
        {
            return Err(Error::AttributeLength);
        }

        // The working frame (see `scale_exp`), then attribute layout and
        // cost scales in it.
        let bbox = mesh.bbox();
        self.scale_exp = frame_exponent(
            bbox.size().max_element(),
            bbox.min.abs().max(bbox.max.abs()).max_element(),
        );
        let unit = self.unit();
        let extent = (bbox.size().max_element() * unit).max(f32::MIN_POSITIVE);
        let mut layout = AttrLayout::default();
        let mut scale = [0.0f32; MAX_ATTR];
        let mut add = |len: usize, w: f32, slot: &mut Option<usize>| {
            *slot = Some(layout.k);
            for s in &mut scale[layout.k..layout.k + len] {
                *s = w.max(0.0) * extent;
            }
            layout.k += len;
        };
        if mesh.normals.is_some() {
            add(3, weights.normal, &mut layout.normal);
        }
        if mesh.colors.is_some() {
            add(4, weights.color, &mut layout.color);
        }
        if mesh.uvs.is_some() {
            add(2, weights.uv, &mut layout.uv);
        }
        self.layout = layout;
        self.attr_scale = scale;

        // Exact position weld: remap[v] = welded id (first occurrence wins).
        let remap = scratch;
        // n + 1: the same buffer becomes the ring offsets (one per vertex
        // plus one) without growing.
        remap.clear();
        remap.reserve_exact(n + 1);
        let welded = weld_exact(&mesh.positions, remap);
        let has_dups = welded < n;
        // A welded vertex is locked if any of its copies is.
        self.locked.clear();
        if let Some(l) = locked {
            self.locked.reserve_exact(welded);
            self.locked.resize(welded, false);
            for (&w, &k) in remap.iter().zip(l) {
                self.locked[w as usize] |= k;
            }
        }

        self.faces.clear();
        self.wedges.clear();
        self.attr.clear();
        self.pos.clear();
        self.group.clear();
        // Wedges are needed where attributes or groups may differ at a
        // shared position.
        let keyed = layout.k > 0 || groups.is_some();
        // Exact capacities: the working arrays are most of the peak memory.
        self.faces.reserve_exact(mesh.faces.len());
        if !has_dups {
            self.pos.reserve_exact(n);
            self.pos.extend_from_slice(&mesh.positions);
            self.faces.extend(
                mesh.faces
                    .iter()
                    .filter(|f| f[0] != f[1] && f[1] != f[2] && f[0] != f[2]),
            );
            if layout.k > 0 {
                self.attr.reserve_exact(n * layout.k);
                for v in 0..n {
                    push_attrs(mesh, v, &mut self.attr);
                }
            }
            if let Some(g) = groups {
                self.group.extend_from_slice(g);
            }
        } else {
            self.pos.reserve_exact(welded);
            self.pos.resize(welded, Vec3::ZERO);
            for (v, &w) in remap.iter().enumerate() {
                self.pos[w as usize] = mesh.positions[v];
            }
            // Wedges: duplicates that also agree on every attribute are
            // one wedge (an unwelded but smooth mesh has no seams).
            let mut wedge_of: Vec<u32> = Vec::new();
            if keyed {
                let mut seen: FxHashMap<Vec<u32>, u32> = FxHashMap::default();
                let mut key = Vec::with_capacity(1 + layout.k);
                let mut a = Vec::with_capacity(layout.k);
                wedge_of.reserve(n);
                for (v, &rv) in remap.iter().enumerate() {
                    a.clear();
                    push_attrs(mesh, v, &mut a);
                    key.clear();
                    key.push(rv);
                    if let Some(g) = groups {
                        key.push(g[v]);
                    }
                    key.extend(a.iter().map(|x| if *x == 0.0 { 0 } else { x.to_bits() }));
                    let id = *seen.entry(key.clone()).or_insert(v as u32);
                    if id == v as u32 {
                        let w = match groups {
                            Some(g) => {
                                self.group.push(g[v]);
                                self.group.len() - 1
                            }
                            None => self.attr.len() / layout.k,
                        };
                        wedge_of.push(w as u32);
                        self.attr.extend_from_slice(&a);
                    } else {
                        wedge_of.push(wedge_of[id as usize]);
                    }
                }
            }
            for f in &mesh.faces {
                let g = [
                    remap[f[0] as usize],
                    remap[f[1] as usize],
                    remap[f[2] as usize],
                ];
                if g[0] == g[1] || g[1] == g[2] || g[0] == g[2] {
                    continue;
                }
                self.faces.push(g);
                if keyed {
                    self.wedges.push(f.map(|v| wedge_of[v as usize]));
                }
            }
        }
        if unit != 1.0 {
            self.pos.iter_mut().for_each(|p| *p *= unit);
        }
        let nv = self.pos.len();
        self.live_faces = self.faces.len();
        self.flags.clear();
        self.flags.reserve_exact(nv);
        self.flags.resize(nv, Flag::Valid);
        self.err.clear();
        self.err.reserve_exact(nv);
        self.err.resize(nv, 0.0);
        Ok(())
    }

    /// Number of wedges (attribute vertices).
    pub fn wedge_count(&self) -> usize {
        if self.has_wedges() && !self.group.is_empty() {
            return self.group.len();
        }
        self.attr.len().checked_div(self.layout.k).unwrap_or(0)
    }

    /// Bytes held by the arrays (capacity), for exact memory accounting.
    pub fn heap_bytes(&self) -> usize {
        self.pos.capacity() * 12
            + self.faces.capacity() * 12
            + self.flags.capacity()
            + self.err.capacity() * 4
            + self.attr.capacity() * 4
            + self.wedges.capacity() * 12
            + self.group.capacity() * 4
            + self.locked.capacity()
    }

    /// Whether vertex `v` is locked ([`WorkMesh::locked`]).
    #[inline]
    pub fn is_locked(&self, v: u32) -> bool {
        !self.locked.is_empty() && self.locked[v as usize]
    }

    /// `2^scale_exp`: one object-space unit in the working frame.
    pub fn unit(&self) -> f32 {
        pow2(self.scale_exp)
    }

    /// Largest accumulated error over live vertices, in object space.
    pub fn max_error(&self) -> f32 {
        self.max_working_error() / self.unit()
    }

    /// Largest accumulated error over live vertices, in the working frame.
    fn max_working_error(&self) -> f32 {
        let mut e = 0.0f32;
        for f in &self.faces {
            if f[0] == DEAD {
                continue;
            }
            for &v in f {
                e = e.max(self.err[v as usize]);
            }
        }
        e
    }
}

/// `2^e` exactly, for `e` in `-126..=127`.
fn pow2(e: i32) -> f32 {
    f32::from_bits(((127 + e.clamp(-126, 127)) as u32) << 23)
}

/// The exponent `e` that brings `extent` (the largest bounding-box side)
/// into `[1, 2)` once scaled by `2^e`; 0 for an empty or single-point box.
/// Bounded so the largest coordinate magnitude `reach` stays below `2^64`
/// (a far, tiny model keeps the frame where its squares still fit).
fn frame_exponent(extent: f32, reach: f32) -> i32 {
    if !(extent > 0.0 && extent.is_finite()) {
        return 0;
    }
    let e = -(extent.log2().floor() as i32);
    // `log2` may round at exact powers of two; settle on [1, 2) exactly.
    let mut e = e.clamp(-120, 120);
    while e > -120 && extent * pow2(e) >= 2.0 {
        e -= 1;
    }
    while e < 120 && extent * pow2(e) < 1.0 {
        e += 1;
    }
    while e > -120 && reach.is_finite() && f64::from(reach) * f64::from(pow2(e)) >= 2f64.powi(64) {
        e -= 1;
    }
    e
}

fn push_attrs(mesh: &TriMesh, v: usize, out: &mut Vec<f32>) {
    if let Some(n) = &mesh.normals {
        out.extend_from_slice(&n[v].to_array());
    }
    if let Some(c) = &mesh.colors {
        out.extend(c[v].iter().map(|&x| x as f32 / 255.0));
    }
    if let Some(t) = &mesh.uvs {
        out.extend_from_slice(&t[v].to_array());
    }
}

/// Exact weld by bit pattern (`-0.0 == 0.0`) with an open-addressing table
/// (deterministic: the first vertex with a position is its representative,
/// and welded ids follow first occurrence). Fills `remap` and returns the
/// number of distinct positions.
pub fn weld_exact(positions: &[Vec3], remap: &mut Vec<u32>) -> usize {
    let n = positions.len();
    remap.clear();
    remap.resize(n, 0);
    if n == 0 {
        return 0;
    }
    let cap = (n * 2).next_power_of_two();
    let mask = cap - 1;
    // table holds input vertex indices (u32::MAX = empty).
    let mut table = vec![u32::MAX; cap];
    let key = |p: Vec3| {
        let c = |x: f32| if x == 0.0 { 0u32 } else { x.to_bits() };
        [c(p.x), c(p.y), c(p.z)]
    };
    let mut next = 0u32;
    for (i, p) in positions.iter().enumerate() {
        let k = key(*p);
        let mut h = (k[0].wrapping_mul(0x8da6_b343)
            ^ k[1].wrapping_mul(0xd816_3841)
            ^ k[2].wrapping_mul(0xcb1a_b31f)) as usize;
        loop {
            h &= mask;
            let slot = table[h];
            if slot == u32::MAX {
                table[h] = i as u32;
                remap[i] = next;
                next += 1;
                break;
            }
            if key(positions[slot as usize]) == k {
                remap[i] = remap[slot as usize];
                break;
            }
            h += 1;
        }
    }
    next as usize
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weld_merges_equal_positions_in_first_seen_order() {
        let p = [
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, -0.0, 2.0),
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(5.0, 5.0, 5.0),
        ];
        let mut remap = Vec::new();
        assert_eq!(weld_exact(&p, &mut remap), 3);
        assert_eq!(remap, vec![0, 1, 0, 1, 2]);
    }
}
