//! Octree construction and ON / IN / OUT labelling — §4.1, §4.2 and §8.1.2
//! of Yemez & Schmitt.
//!
//! The octree space is the bounding cube of the input with one corner at the
//! origin of a `2^R × 2^R × 2^R` grid (§4.1). A cell of level `r` is named by
//! its integer corner `(x, y, z)` closest to the origin, stored as a Morton
//! code whose low three bits are the child code `C = cx + 2cy + 4cz` of
//! eq. (1); so sorting Morton codes is the lexicographic order of §4.4 and
//! `code >> 3` is the parent.
//!
//! **Construction (§8.1.2).** Every sample is quantised once to a 16-bit
//! grid ([`QBITS`]); its leaf is the top `R` bits of each coordinate, so
//! the mean of a leaf's samples (the particle vertex of §5.5) quantised to
//! any `N ≥ R` bits lies in the same leaf. Meshes are sampled on a
//! barycentric lattice whose spacing is half the leaf size, which puts
//! samples in every leaf cube a triangle crosses (the paper oversampled its
//! meshes in the same spirit).
//!
//! **Bounded sampling.** A triangle inside the root cube has no edge longer
//! than `√3 · size`, so its lattice has at most
//! `k = ⌈2√3 · 2^R⌉` steps per edge and `(k+1)(k+2)/2` samples
//! ([`max_lattice_steps`]); the whole mesh may take at most
//! [`mesh_sample_limit`] samples (`max(2^20, 256 × faces)`). The count is
//! computed before sampling:
//! an explicit depth that needs more is refused (naming the deepest depth
//! that fits), the automatic depth is lowered until it fits. Edge lengths
//! are measured in `f64`, so the lattice, and with it the particles, is
//! the same at any scale `f32` can hold (a mesh at 1e-10 and one at 1e15
//! give the same octree).
//!
//! **Labels (§4.1, §8.1.2).** The paper assumes IN/OUT next to the surface
//! is known. Closed inputs get it from a flood fill of the outside at each
//! level; rather than a dense `8^r` grid we label only the *band* (the empty
//! children of ON parents) and let every other empty cell inherit its
//! parent's label, which is exact for OUT (the children of a connected run
//! of empty parents are connected). Departure: a band component that meets
//! no OUT cell is IN even when a finer leak would join it to the outside in
//! a dense fill — only leaky "closed" inputs can tell the difference.
//! Open inputs use the normals (the second option §8.1.2 mentions): an
//! empty band cell is OUT when it lies on the positive side of the
//! adjacent ON cells' mean sample planes.
use std::collections::HashMap;

use glam::{DVec3, Vec3};
use lodkit_mesh::{Model, PointCloud, TriMesh};

use crate::error::{Error, Result};

/// Bits of the one quantisation every sample goes through; the highest
/// precision `N` a stream can carry (§7.2 lets it go to 16).
pub const QBITS: u32 = 16;
/// Deepest octree accepted: leaves are the top `R` of the [`QBITS`] bits.
pub const MAX_DEPTH: u8 = 16;
/// Depth used when the sampling density says nothing (a handful of points).
const FALLBACK_DEPTH: u8 = 6;
/// Mean samples per occupied leaf the automatic depth aims at for point
/// clouds: fewer and the leaves of a uniform scan start to miss samples.
const POINTS_PER_LEAF: usize = 3;

/// Mesh samples one octree build may take, at least: 2^20 (about a
/// million). A leaf holds about 4 to 8 samples, and encoding costs about
/// 10 µs per particle, so a file of a few triangles can never ask for more
/// than a few seconds and a couple of hundred MB, whatever the depth.
/// Meshes with many faces get [`SAMPLES_PER_FACE`] per face instead
/// ([`mesh_sample_limit`]).
pub const MAX_MESH_SAMPLES: u64 = 1 << 20;
/// Samples per face a mesh may take: 256. The lattice of a face no larger
/// than a leaf has 3 to 10 points; the shipped bunny takes 97 per face at
/// R = 9 and 333 at R = 10, so R = 9 is the deepest it may be encoded at,
/// and an 81,920-face icosphere about 66 at R = 9.
pub const SAMPLES_PER_FACE: u64 = 256;

/// The most samples [`Octree::from_mesh`] takes from a mesh of `faces`
/// faces: `max(MAX_MESH_SAMPLES, SAMPLES_PER_FACE × faces)`, so the cost
/// of sampling stays proportional to the input (or a fixed few seconds).
pub fn mesh_sample_limit(faces: usize) -> u64 {
    MAX_MESH_SAMPLES.max(SAMPLES_PER_FACE.saturating_mul(faces as u64))
}

/// The most lattice steps per edge a triangle inside the root cube can
/// need at depth `r`: `⌈2√3 · 2^r⌉` (longest edge `√3 · size`, spacing
/// half a leaf, `size / 2^(r+1)`).
pub fn max_lattice_steps(r: u8) -> u32 {
    (2.0 * 3f64.sqrt() * (1u64 << r) as f64).ceil() as u32
}

/// A hash map keyed by Morton code (Fx hashing: the keys are not
/// adversarial, and SipHash costs more than the work the maps serve; no
/// map is iterated in hash order where the order reaches an output).
pub type MortonMap<V> = HashMap<u64, V, rustc_hash::FxBuildHasher>;

fn spread(v: u32) -> u64 {
    let mut x = u64::from(v) & 0xffff;
    x = (x | (x << 16)) & 0x0000_ff00_00ff;
    x = (x | (x << 8)) & 0x00f0_0f00_f00f;
    x = (x | (x << 4)) & 0x0c30_c30c_30c3;
    x = (x | (x << 2)) & 0x2492_4924_9249;
    x
}

fn compact(mut x: u64) -> u32 {
    x &= 0x2492_4924_9249;
    x = (x | (x >> 2)) & 0x0c30_c30c_30c3;
    x = (x | (x >> 4)) & 0x00f0_0f00_f00f;
    x = (x | (x >> 8)) & 0x0000_ff00_00ff;
    x = (x | (x >> 16)) & 0xffff;
    x as u32
}

/// Morton code of cell `(x, y, z)`: x in the lowest bit of each triple, so
/// the low three bits are eq. (1)'s child code. Coordinates up to 16 bits.
pub fn morton(c: [u32; 3]) -> u64 {
    spread(c[0]) | (spread(c[1]) << 1) | (spread(c[2]) << 2)
}

/// Inverse of [`morton`].
pub fn unmorton(m: u64) -> [u32; 3] {
    [compact(m), compact(m >> 1), compact(m >> 2)]
}

/// Face neighbour of a cell at a level with `side` cells per axis, or
/// `None` outside the grid.
pub fn offset(c: [u32; 3], d: [i32; 3], side: u32) -> Option<[u32; 3]> {
    let mut o = [0u32; 3];
    for a in 0..3 {
        let v = c[a] as i64 + d[a] as i64;
        if v < 0 || v >= side as i64 {
            return None;
        }
        o[a] = v as u32;
    }
    Some(o)
}

/// The six face directions.
pub const FACES: [[i32; 3]; 6] = [
    [-1, 0, 0],
    [1, 0, 0],
    [0, -1, 0],
    [0, 1, 0],
    [0, 0, -1],
    [0, 0, 1],
];

/// Where the octree cube sits in object space.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Frame {
    /// Corner of the cube closest to −∞ on every axis.
    pub origin: Vec3,
    /// Edge length of the root cube.
    pub size: f32,
}

impl Frame {
    /// The cube around `bbox` with a small margin (so no sample sits on the
    /// far faces), in f64 to stay deterministic across inputs.
    pub fn around(min: Vec3, max: Vec3) -> Frame {
        // Any positive extent is kept, so a model at 1e-10 fills the cube
        // as it does at 1; only a single point (extent 0) gets a nominal
        // cube, tiny enough not to matter and large enough that its cells
        // are normal floats.
        let ext = (max - min).max_element().max(1e-30);
        let size = ext * (1.0 + 1.0 / 1024.0);
        let centre = (min + max) * 0.5;
        Frame {
            origin: centre - Vec3::splat(size * 0.5),
            size,
        }
    }

    /// 16-bit grid coordinates of `p`, clamped into the cube.
    pub fn quantise(&self, p: Vec3) -> [u32; 3] {
        let s = f64::from(1u32 << QBITS) / f64::from(self.size);
        let d = (p.as_dvec3() - self.origin.as_dvec3()) * s;
        let max = f64::from((1u32 << QBITS) - 1);
        [
            d.x.floor().clamp(0.0, max) as u32,
            d.y.floor().clamp(0.0, max) as u32,
            d.z.floor().clamp(0.0, max) as u32,
        ]
    }

    /// Object-space centre of the cell of `bits`-bit coordinates `q`.
    pub fn cell_centre(&self, q: [u32; 3], bits: u32) -> Vec3 {
        let cell = f64::from(self.size) / f64::from(1u32 << bits);
        let o = self.origin.as_dvec3();
        (o + (DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64) + 0.5) * cell).as_vec3()
    }

    /// Edge length of a cube at level `r`.
    pub fn cube(&self, r: u8) -> f32 {
        self.size / (1u64 << r) as f32
    }
}

/// ON / IN / OUT of §4.1.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Label {
    On,
    In,
    Out,
}

/// How IN and OUT are told apart next to the surface (§8.1.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Sidedness {
    /// Flood fill of the outside at each level (closed inputs).
    FloodFill,
    /// Sign of the offset along the particles' normals (open inputs).
    Normals,
}

/// One level of the octree: the ON cells (sorted Morton codes), their
/// labels (changed by thinning) and the labels of the empty band cells.
#[derive(Debug, Default, Clone)]
pub struct Level {
    pub cells: Vec<u64>,
    pub label: Vec<Label>,
    pub band: MortonMap<Label>,
    index: MortonMap<u32>,
}

impl Level {
    pub(crate) fn new(cells: Vec<u64>) -> Level {
        let mut index = MortonMap::default();
        index.reserve(cells.len());
        for (i, &c) in cells.iter().enumerate() {
            index.insert(c, i as u32);
        }
        Level {
            label: vec![Label::On; cells.len()],
            cells,
            band: MortonMap::default(),
            index,
        }
    }

    /// Position of cell `m` among the ON cells.
    pub fn find(&self, m: u64) -> Option<usize> {
        self.index.get(&m).map(|&i| i as usize)
    }
}

/// Samples accumulated per leaf.
#[derive(Debug, Clone, Default)]
pub struct LeafAttributes {
    /// Vertex: mean of the leaf's samples on the 16-bit grid (§5.5).
    pub q: Vec<[u32; 3]>,
    /// Mean sample normal, unit length (zero when the samples cancel).
    pub normal: Option<Vec<Vec3>>,
    /// Mean sample colour.
    pub colour: Option<Vec<[u8; 3]>>,
}

/// The full octree of §4.1: levels `0..=R`, leaf attributes, and labels.
#[derive(Debug, Clone)]
pub struct Octree {
    pub depth: u8,
    pub frame: Frame,
    pub levels: Vec<Level>,
    pub leaves: LeafAttributes,
    #[cfg_attr(not(feature = "internals"), allow(dead_code))] // the bench drivers read it
    pub sidedness: Sidedness,
}

/// Options of [`Octree::build`].
#[derive(Debug, Clone, Copy)]
pub struct BuildOptions {
    /// Octree resolution `R`; `None` picks it from the sampling density.
    pub depth: Option<u8>,
    /// Force a labelling; `None` floods closed meshes, uses normals when
    /// the input is open and has them, floods otherwise.
    pub sidedness: Option<Sidedness>,
}

impl BuildOptions {
    /// The defaults: depth and labelling chosen from the input.
    pub const DEFAULT: BuildOptions = BuildOptions {
        depth: None,
        sidedness: None,
    };
}

impl Default for BuildOptions {
    fn default() -> Self {
        BuildOptions::DEFAULT
    }
}

#[derive(Default, Clone, Copy)]
struct Acc {
    q: [u64; 3],
    n: u64,
    normal: DVec3,
    colour: [u64; 3],
}

impl Octree {
    /// Builds the octree of any model (meshes are sampled, point clouds and
    /// range images used as they are).
    pub fn build(model: &Model, opts: &BuildOptions) -> Result<Octree> {
        match model {
            Model::Mesh(m) => Octree::from_mesh(m, opts),
            Model::Points(p) => Octree::from_points(p, opts),
            Model::Range(r) => Octree::from_points(&r.to_point_cloud(), opts),
        }
    }

    /// §8.1.2 for a point cloud: every leaf holding a point is ON.
    pub fn from_points(pc: &PointCloud, opts: &BuildOptions) -> Result<Octree> {
        let pts: Vec<Vec3> = pc
            .positions
            .iter()
            .copied()
            .filter(|p| p.is_finite())
            .collect();
        if pts.is_empty() {
            return Err(Error::Input("the point cloud has no finite point".into()));
        }
        let bbox = lodkit_mesh::Aabb::from_points(&pts);
        let frame = Frame::around(bbox.min, bbox.max);
        let depth = match opts.depth {
            Some(d) => check_depth(d)?,
            None => depth_from_points(&frame, &pts),
        };
        let mut acc: MortonMap<Acc> = MortonMap::default();
        for (i, p) in pc.positions.iter().enumerate() {
            if !p.is_finite() {
                continue;
            }
            let n = pc.normals.as_ref().map(|n| n[i]);
            let c = pc.colors.as_ref().map(|c| c[i]);
            add_sample(&mut acc, &frame, depth, *p, n, c);
        }
        let sidedness = opts.sidedness.unwrap_or(if pc.normals.is_some() {
            Sidedness::Normals
        } else {
            Sidedness::FloodFill
        });
        Ok(Octree::finish(
            depth,
            frame,
            acc,
            pc.normals.is_some(),
            pc.colors.is_some(),
            sidedness,
        ))
    }

    /// §8.1.2 for a mesh: the surface is sampled on a lattice of half the
    /// leaf size (see the module docs), normals are the face normals,
    /// colours interpolated from the vertices.
    pub fn from_mesh(mesh: &TriMesh, opts: &BuildOptions) -> Result<Octree> {
        mesh.validate().map_err(|e| Error::Input(e.to_string()))?;
        if mesh.faces.is_empty() {
            return Err(Error::Input("the mesh has no faces".into()));
        }
        let bbox = lodkit_mesh::metrics::surface_bbox(mesh);
        if bbox.is_empty() {
            return Err(Error::Input("the mesh has no finite vertex".into()));
        }
        let frame = Frame::around(bbox.min, bbox.max);
        let limit = mesh_sample_limit(mesh.faces.len());
        let depth = match opts.depth {
            Some(d) => {
                let d = check_depth(d)?;
                let n = mesh_sample_count(&frame, mesh, d);
                if n > limit {
                    let fits = (1..d)
                        .rev()
                        .find(|&r| mesh_sample_count(&frame, mesh, r) <= limit);
                    let hint = match fits {
                        Some(r) => format!("; depth {r} or less fits"),
                        None => String::new(),
                    };
                    return Err(Error::Input(format!(
                        "sampling this mesh at depth {d} takes {n} samples, over the limit of \
                         {limit} (max({MAX_MESH_SAMPLES}, {SAMPLES_PER_FACE} per face)){hint}"
                    )));
                }
                d
            }
            None => {
                let mut d = depth_from_mesh(&frame, mesh);
                while d > 1 && mesh_sample_count(&frame, mesh, d) > limit {
                    d -= 1;
                }
                d
            }
        };
        let spacing = f64::from(frame.cube(depth)) * 0.5;
        let max_k = max_lattice_steps(depth);
        let mut acc: MortonMap<Acc> = MortonMap::default();
        for f in &mesh.faces {
            let [a, b, c] = f.map(|i| mesh.positions[i as usize]);
            if !(a.is_finite() && b.is_finite() && c.is_finite()) {
                continue;
            }
            let mut normal = (b - a).cross(c - a).normalize_or_zero();
            if normal == Vec3::ZERO {
                // The f32 cross product underflows (or overflows) at
                // extreme scales; f64 holds it.
                let [a, b, c] = [a, b, c].map(Vec3::as_dvec3);
                normal = (b - a).cross(c - a).normalize_or_zero().as_vec3();
            }
            let cols = mesh.colors.as_ref().map(|cs| f.map(|i| cs[i as usize]));
            let k = lattice_steps([a, b, c], spacing, max_k);
            for i in 0..=k {
                for j in 0..=(k - i) {
                    let u = i as f32 / k as f32;
                    let v = j as f32 / k as f32;
                    let p = a + (b - a) * u + (c - a) * v;
                    let col = cols.map(|cs| {
                        let w = [1.0 - u - v, u, v];
                        let mut o = [0u8; 4];
                        for (ch, out) in o.iter_mut().enumerate() {
                            let s: f32 = (0..3).map(|t| w[t] * f32::from(cs[t][ch])).sum();
                            *out = s.round().clamp(0.0, 255.0) as u8;
                        }
                        o
                    });
                    add_sample(&mut acc, &frame, depth, p, Some(normal), col);
                }
            }
        }
        let closed = lodkit_mesh::topology::topology_stats(mesh).boundary_edges == 0;
        let sidedness = opts.sidedness.unwrap_or(if closed {
            Sidedness::FloodFill
        } else {
            Sidedness::Normals
        });
        Ok(Octree::finish(
            depth,
            frame,
            acc,
            true,
            mesh.colors.is_some(),
            sidedness,
        ))
    }

    fn finish(
        depth: u8,
        frame: Frame,
        acc: MortonMap<Acc>,
        has_normals: bool,
        has_colours: bool,
        sidedness: Sidedness,
    ) -> Octree {
        let mut leaves: Vec<(u64, Acc)> = acc.into_iter().collect();
        leaves.sort_unstable_by_key(|(m, _)| *m);
        let mut attrs = LeafAttributes {
            q: Vec::with_capacity(leaves.len()),
            normal: has_normals.then(Vec::new),
            colour: has_colours.then(Vec::new),
        };
        for (_, a) in &leaves {
            // Integer mean of points inside one leaf stays inside it.
            attrs.q.push(a.q.map(|s| (s / a.n) as u32));
            if let Some(n) = attrs.normal.as_mut() {
                n.push(a.normal.normalize_or_zero().as_vec3());
            }
            if let Some(c) = attrs.colour.as_mut() {
                c.push(a.colour.map(|s| ((s + a.n / 2) / a.n).min(255) as u8));
            }
        }
        let mut levels = Vec::with_capacity(depth as usize + 1);
        let mut cells: Vec<u64> = leaves.iter().map(|(m, _)| *m).collect();
        levels.push(Level::new(cells.clone()));
        for _ in 0..depth {
            cells = cells.iter().map(|m| m >> 3).collect();
            cells.dedup();
            levels.push(Level::new(cells.clone()));
        }
        levels.reverse();
        let mut tree = Octree {
            depth,
            frame,
            levels,
            leaves: attrs,
            sidedness,
        };
        match sidedness {
            Sidedness::FloodFill => tree.label_by_flood_fill(),
            Sidedness::Normals => tree.label_by_normals(),
        }
        tree
    }

    /// Label of any cell at level `r` (ON cells: their current label;
    /// band cells: theirs; others: inherited from the first labelled
    /// ancestor; outside the grid: OUT).
    pub fn label(&self, r: u8, c: [u32; 3]) -> Label {
        let mut r = r as usize;
        let mut m = morton(c);
        loop {
            let lv = &self.levels[r];
            if let Some(i) = lv.find(m) {
                return lv.label[i];
            }
            if let Some(&l) = lv.band.get(&m) {
                return l;
            }
            if r == 0 {
                return Label::Out;
            }
            r -= 1;
            m >>= 3;
        }
    }

    /// Label of `c + d` at level `r`, OUT outside the grid.
    pub fn neighbour_label(&self, r: u8, c: [u32; 3], d: [i32; 3]) -> Label {
        match offset(c, d, 1u32 << r) {
            Some(n) => self.label(r, n),
            None => Label::Out,
        }
    }

    /// The empty children of ON parents at level `r ≥ 1`.
    fn band_cells(&self, r: usize) -> Vec<u64> {
        let lv = &self.levels[r];
        let mut band = Vec::new();
        for &p in &self.levels[r - 1].cells {
            for code in 0..8 {
                let c = (p << 3) | code;
                if lv.find(c).is_none() {
                    band.push(c);
                }
            }
        }
        band
    }

    fn label_by_flood_fill(&mut self) {
        for r in 1..=self.depth as usize {
            let band = self.band_cells(r);
            let side = 1u32 << r;
            let mut comp: MortonMap<u32> = MortonMap::default();
            for (i, &c) in band.iter().enumerate() {
                comp.insert(c, i as u32);
            }
            let mut seen = vec![false; band.len()];
            let mut labels: MortonMap<Label> = MortonMap::default();
            let mut stack = Vec::new();
            let mut members = Vec::new();
            for start in 0..band.len() {
                if seen[start] {
                    continue;
                }
                seen[start] = true;
                stack.push(start);
                members.clear();
                let mut out = false;
                while let Some(i) = stack.pop() {
                    members.push(band[i]);
                    let c = unmorton(band[i]);
                    for d in FACES {
                        let Some(n) = offset(c, d, side) else {
                            out = true;
                            continue;
                        };
                        let nm = morton(n);
                        if let Some(&j) = comp.get(&nm) {
                            if !seen[j as usize] {
                                seen[j as usize] = true;
                                stack.push(j as usize);
                            }
                        } else if self.levels[r].find(nm).is_none()
                            && self.label(r as u8 - 1, unmorton(nm >> 3)) == Label::Out
                        {
                            out = true;
                        }
                    }
                }
                let l = if out { Label::Out } else { Label::In };
                for &m in &members {
                    labels.insert(m, l);
                }
            }
            self.levels[r].band = labels;
        }
    }

    fn label_by_normals(&mut self) {
        // Mean sample position and normal of every ON cell at every level.
        let d = self.depth as usize;
        let mut sums: Vec<Vec<(DVec3, DVec3, u64)>> = vec![Vec::new(); d + 1];
        sums[d] = (0..self.levels[d].cells.len())
            .map(|i| {
                let q = self.leaves.q[i];
                let p = DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64)
                    / f64::from(1u32 << (QBITS - u32::from(self.depth)));
                let n = self
                    .leaves
                    .normal
                    .as_ref()
                    .map_or(DVec3::ZERO, |n| n[i].as_dvec3());
                (p, n, 1)
            })
            .collect();
        for r in (0..d).rev() {
            let mut s = vec![(DVec3::ZERO, DVec3::ZERO, 0u64); self.levels[r].cells.len()];
            for (i, &c) in self.levels[r + 1].cells.iter().enumerate() {
                let p = self.levels[r]
                    .find(c >> 3)
                    .expect("parent of an ON cell is ON");
                let (cp, cn, k) = sums[r + 1][i];
                s[p].0 += cp * 0.5 * k as f64;
                s[p].1 += cn;
                s[p].2 += k;
            }
            for e in &mut s {
                e.0 /= e.2 as f64;
            }
            sums[r] = s;
        }
        for r in 1..=d {
            let band = self.band_cells(r);
            let side = 1u32 << r;
            let mut labels: MortonMap<Label> = MortonMap::default();
            for &b in &band {
                let c = unmorton(b);
                let centre = DVec3::new(c[0] as f64, c[1] as f64, c[2] as f64) + 0.5;
                let mut vote = 0.0f64;
                for dz in -1..=1 {
                    for dy in -1..=1 {
                        for dx in -1..=1 {
                            let Some(n) = offset(c, [dx, dy, dz], side) else {
                                continue;
                            };
                            if let Some(i) = self.levels[r].find(morton(n)) {
                                let (p, nrm, _) = sums[r][i];
                                let w = if dx.abs() + dy.abs() + dz.abs() == 1 {
                                    4.0
                                } else {
                                    1.0
                                };
                                vote += w * (centre - p).dot(nrm.normalize_or_zero());
                            }
                        }
                    }
                }
                labels.insert(b, if vote >= 0.0 { Label::Out } else { Label::In });
            }
            self.levels[r].band = labels;
        }
    }
}

/// Lattice steps per edge of triangle `t`: enough that neighbouring
/// lattice points are at most `spacing` apart, at most `max_k`
/// ([`max_lattice_steps`]; only reached by rounding at the cube's diagonal).
fn lattice_steps(t: [Vec3; 3], spacing: f64, max_k: u32) -> u32 {
    let [a, b, c] = t;
    let longest = edge_length(a, b)
        .max(edge_length(b, c))
        .max(edge_length(c, a));
    ((longest / spacing).ceil() as u64).clamp(1, u64::from(max_k)) as u32
}

/// `|a − b|`: the `f32` length where it is exact enough (so results on
/// ordinary data stay bit-for-bit what they were), the `f64` one where the
/// squared `f32` length would underflow or overflow.
fn edge_length(a: Vec3, b: Vec3) -> f64 {
    let l = (a - b).length();
    if l.is_finite() && (l >= 1e-15 || l == 0.0 && a == b) && l <= 1e15 {
        f64::from(l)
    } else {
        a.as_dvec3().distance(b.as_dvec3())
    }
}

/// Samples [`Octree::from_mesh`] takes at depth `r`, saturating; a pass
/// over the faces without sampling.
fn mesh_sample_count(frame: &Frame, mesh: &TriMesh, r: u8) -> u64 {
    let spacing = f64::from(frame.cube(r)) * 0.5;
    let max_k = max_lattice_steps(r);
    let mut total = 0u64;
    for f in &mesh.faces {
        let t = f.map(|i| mesh.positions[i as usize]);
        if !t.iter().all(|p| p.is_finite()) {
            continue;
        }
        let k = u64::from(lattice_steps(t, spacing, max_k));
        total = total.saturating_add((k + 1) * (k + 2) / 2);
    }
    total
}

fn add_sample(
    acc: &mut MortonMap<Acc>,
    frame: &Frame,
    depth: u8,
    p: Vec3,
    normal: Option<Vec3>,
    colour: Option<[u8; 4]>,
) {
    let q = frame.quantise(p);
    let shift = QBITS - u32::from(depth);
    let leaf = morton(q.map(|v| v >> shift));
    let a = acc.entry(leaf).or_default();
    for k in 0..3 {
        a.q[k] += u64::from(q[k]);
    }
    a.n += 1;
    if let Some(n) = normal {
        a.normal += n.as_dvec3();
    }
    if let Some(c) = colour {
        for k in 0..3 {
            a.colour[k] += u64::from(c[k]);
        }
    }
}

fn check_depth(d: u8) -> Result<u8> {
    if (1..=MAX_DEPTH).contains(&d) {
        Ok(d)
    } else {
        Err(Error::Input(format!(
            "depth {d} is outside 1..={MAX_DEPTH}"
        )))
    }
}

/// The deepest level whose occupied leaves still hold
/// [`POINTS_PER_LEAF`] points on average.
fn depth_from_points(frame: &Frame, pts: &[Vec3]) -> u8 {
    let mut codes: Vec<u64> = pts.iter().map(|p| morton(frame.quantise(*p))).collect();
    codes.sort_unstable();
    let mut best = FALLBACK_DEPTH.min(2);
    for r in 2..=12u8 {
        let shift = 3 * (QBITS - u32::from(r));
        let mut occupied = 0usize;
        let mut last = u64::MAX;
        for &c in &codes {
            if c >> shift != last {
                occupied += 1;
                last = c >> shift;
            }
        }
        if occupied * POINTS_PER_LEAF <= pts.len() {
            best = r;
        } else {
            break;
        }
    }
    best
}

/// A leaf about as large as the mesh's mean edge: the resolution of the
/// original data (§8.1.2).
fn depth_from_mesh(frame: &Frame, mesh: &TriMesh) -> u8 {
    let mut total = 0.0f64;
    let mut n = 0usize;
    for f in &mesh.faces {
        for k in 0..3 {
            let a = mesh.positions[f[k] as usize];
            let b = mesh.positions[f[(k + 1) % 3] as usize];
            let l = edge_length(a, b);
            if l.is_finite() && l > 0.0 {
                total += l;
                n += 1;
            }
        }
    }
    if n == 0 {
        return FALLBACK_DEPTH;
    }
    let mean = total / n as f64;
    let r = (f64::from(frame.size) / mean).log2().round();
    r.clamp(2.0, 12.0) as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_round_trips_and_orders_children_by_eq1() {
        for c in [[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1], [65535, 3, 777]] {
            assert_eq!(unmorton(morton(c)), c);
        }
        assert_eq!(morton([1, 1, 1]) & 7, 7);
        assert_eq!(morton([1, 0, 1]) & 7, 1 + 4);
        assert_eq!(morton([6, 3, 2]) >> 3, morton([3, 1, 1]));
    }

    #[test]
    fn flood_fill_marks_the_inside_of_a_closed_sphere() {
        let m = lodkit_mesh::shapes::icosphere(3);
        let t = Octree::from_mesh(
            &m,
            &BuildOptions {
                depth: Some(5),
                sidedness: None,
            },
        )
        .unwrap();
        assert_eq!(t.sidedness, Sidedness::FloodFill);
        assert_eq!(t.label(5, [16, 16, 16]), Label::In);
        assert_eq!(t.label(5, [0, 0, 0]), Label::Out);
    }

    #[test]
    fn normals_mark_the_inside_of_a_sphere_too() {
        let m = lodkit_mesh::shapes::icosphere(3);
        let opts = BuildOptions {
            depth: Some(5),
            sidedness: Some(Sidedness::Normals),
        };
        let t = Octree::from_mesh(&m, &opts).unwrap();
        assert_eq!(t.label(5, [16, 16, 16]), Label::In);
        assert_eq!(t.label(5, [0, 0, 0]), Label::Out);
    }

    fn scaled(m: &TriMesh, k: f32) -> TriMesh {
        let mut m = m.clone();
        m.positions.iter_mut().for_each(|p| *p *= k);
        m
    }

    /// The octree of a mesh does not depend on its scale: a sphere at 1e-10,
    /// 1 and 1e15 gives the same depth and the same leaves.
    #[test]
    fn the_octree_is_the_same_at_any_scale() {
        let m = lodkit_mesh::shapes::icosphere(3);
        let auto = BuildOptions::default();
        let one = Octree::from_mesh(&m, &auto).unwrap();
        assert!(one.leaves.q.len() > 100, "{}", one.leaves.q.len());
        for k in [1e-10, 1e-20, 1e15] {
            let t = Octree::from_mesh(&scaled(&m, k), &auto).unwrap();
            assert_eq!(t.depth, one.depth, "scale {k}");
            // The same leaves up to float rounding of the scaled
            // positions (a sample on a leaf's face may change sides).
            let (a, b) = (t.leaves.q.len() as f64, one.leaves.q.len() as f64);
            assert!(
                (a - b).abs() <= 0.01 * b,
                "scale {k}: {a} leaves against {b}"
            );
        }
    }

    /// Sampling is bounded before it starts: an explicit depth that needs
    /// more than the limit is refused (naming one that fits), the automatic
    /// depth is lowered, and one giant triangle never takes 1e8 samples.
    #[test]
    fn sample_counts_are_bounded_by_the_depth_and_the_limit() {
        let tri = TriMesh::new(
            vec![
                Vec3::ZERO,
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(0.0, 1.0, 1.0),
            ],
            vec![[0, 1, 2]],
        );
        let frame = Frame::around(Vec3::ZERO, Vec3::ONE);
        let k = u64::from(max_lattice_steps(16));
        assert!(mesh_sample_count(&frame, &tri, 16) <= (k + 1) * (k + 2) / 2);
        let e = Octree::from_mesh(
            &tri,
            &BuildOptions {
                depth: Some(16),
                sidedness: None,
            },
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("at depth 16 takes")
                && e.contains("over the limit of 1048576")
                && e.contains("depth 8 or less fits"),
            "{e}"
        );
        // Many small triangles and one giant one: the mean edge asks for a
        // deep tree, the giant triangle would need too many samples there.
        let mut m = lodkit_mesh::shapes::icosphere(5);
        m.normals = None;
        m.positions.iter_mut().for_each(|p| *p *= 1e-3);
        let n = m.positions.len() as u32;
        m.positions.extend([
            Vec3::splat(-1.0),
            Vec3::new(1.0, -1.0, 1.0),
            Vec3::new(-1.0, 1.0, 1.0),
        ]);
        m.faces.push([n, n + 1, n + 2]);
        let frame = Frame::around(Vec3::splat(-1.0), Vec3::ONE);
        let wanted = depth_from_mesh(&frame, &m);
        let limit = mesh_sample_limit(m.faces.len());
        assert!(
            mesh_sample_count(&frame, &m, wanted) > limit,
            "depth {wanted}"
        );
        let t = Octree::from_mesh(&m, &BuildOptions::default()).unwrap();
        assert!(t.depth < wanted);
        assert!(mesh_sample_count(&t.frame, &m, t.depth) <= limit);
    }
}
