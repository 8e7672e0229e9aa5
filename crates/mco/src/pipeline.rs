//! From input models to a built octree: the library entry points, and the
//! incremental builder (range images added one at a time).
//!
//! Stages, in order: oriented samples ([`crate::normals_estimation`]) →
//! lattice ([`crate::lattice`]) → signed-distance band ([`crate::signed_distance`]) → leaf marching cubes
//! ([`crate::marching_cubes`]) → octree ([`crate::octree_build`]) →
//! priority numbering ([`crate::priority_numbering`]) → crack patches
//! ([`crate::crack_patch`]).
//!
//! **Default resolution** (§4.4): the thesis found that cubes finer than
//! the data's sampling leave holes, and that "the double is proper". Read
//! here as: the cube edge is twice the input's sample spacing, so the
//! resolution (cubes along the longest axis) is `longest / (2 · spacing)`,
//! clamped to 8..=1024. The spacing is the median distance between lattice
//! neighbours for range images, the median edge length for meshes, and the
//! median distance to the fourth-nearest neighbour for point clouds
//! ([`CLOUD_SPACING_NEIGHBOUR`]: the same points give about the same
//! spacing as a cloud as they do as a mesh or a range image).
//!
//! An unorganised cloud's cube is 1.5 spacings ([`CLOUD_CUBE_SPACINGS`]),
//! not 2: a surface of area `A` sampled at spacing `h` holds about `A/h²`
//! points, and cubes of `2h` give its full cut about `1.5 · A / (2h)²`
//! vertices, a third of the points; cubes of `1.5h` give about two
//! thirds, so the octree keeps the cloud's detail. A range image's grid
//! orders its samples, so its cubes stay at twice its step; a cloud has
//! no such order and its surface must come from the samples alone. On the
//! LMS400 laser scan (460,400 points) the finer lattice keeps the
//! surface's area (3.43 → 3.36 m², −2 %) and adds only specks (components
//! of under 20 vertices) where the far, sparse part of the scan thins out.
//!
//! **Incremental** (§4.4: "the range data of uncompleted area are added to
//! continue reconstructing the model"): [`IncrementalBuilder::add`] stamps
//! new samples into the band and recomputes only the leaf cubes around the
//! lattice vertices whose value changed; the octree above the leaves is
//! rebuilt by [`IncrementalBuilder::build`] (bottom-up, `O(n log n)`).

use std::num::NonZero;
use std::path::Path;

use kiddo::{ImmutableKdTree, SquaredEuclidean};
use lodkit_mesh::{Aabb, Model, PointCloud, RangeImage, TriMesh};

use crate::lattice::{BRICK, BRICK_BITS, BRICK_VOLUME, Grid, local_index, normalising_scale, pack};
use crate::marching_cubes::{BandSigns, BrickMasks, brick_configs, leaf_config_in};
use crate::model::McoModel;
use crate::normals_estimation::{mesh_samples, point_cloud_samples, range_image_samples};
use crate::signed_distance::SignedDistanceField;
use crate::{Error, Result};

/// Build options.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Options {
    /// Leaf cubes along the longest axis of the inputs' bounding box,
    /// `2..=`[`crate::MAX_RESOLUTION`]; `None` (the default) = a cube
    /// edge of twice the inputs' sample spacing (1.5 for point clouds), clamped to 8..=1024 (see
    /// the module docs). Memory and time grow with the surface's area in
    /// cubes, about the square of the resolution.
    pub resolution: Option<u32>,
}

impl Options {
    /// The defaults: the resolution from the inputs' sample spacing.
    pub const DEFAULT: Options = Options { resolution: None };
}

impl Default for Options {
    fn default() -> Self {
        Options::DEFAULT
    }
}

/// Oriented samples of any model: positions with unit outward normals
/// (always `Some`) and the model's colours if it has them, as the build
/// adds them. Range images: Fig. 4.2 normals from the lattice
/// neighbours, pose applied; meshes: the referenced vertices with
/// area-weighted normals; point clouds: their own normals, else PCA
/// normals oriented consistently. Samples without a usable normal are
/// dropped. Errors: a point cloud without normals that has too few points
/// to estimate them. `O(n log n)` for bare point clouds, `O(n)` otherwise.
pub fn samples_of(model: &Model) -> Result<PointCloud> {
    input_samples(Input::from(model))
}

/// The upper median of the finite positive values of `v`.
///
/// A radix select: positive finite floats order as their bit patterns, so
/// one pass counts the values per high 16 bits, and only the values in the
/// median's bucket (about 1% of edge lengths) are selected among. Same
/// result as sorting, in two linear passes.
fn median(v: Vec<f32>) -> Option<f32> {
    let mut hist = vec![0u32; 1 << 16];
    let mut n = 0usize;
    for x in &v {
        if x.is_finite() && *x > 0.0 {
            hist[(x.to_bits() >> 16) as usize] += 1;
            n += 1;
        }
    }
    if n == 0 {
        return None;
    }
    let mid = n / 2;
    let mut below = 0usize;
    let mut bucket = 0u32;
    for (h, &count) in hist.iter().enumerate() {
        if below + count as usize > mid {
            bucket = h as u32;
            break;
        }
        below += count as usize;
    }
    let mut low: Vec<u32> = v
        .iter()
        .filter(|x| x.is_finite() && **x > 0.0 && x.to_bits() >> 16 == bucket)
        .map(|x| x.to_bits() & 0xFFFF)
        .collect();
    let rank = mid - below;
    low.select_nth_unstable(rank);
    Some(f32::from_bits(bucket << 16 | low[rank]))
}

/// Which neighbour's distance measures a point cloud's sample spacing
/// (1 = the nearest other point).
///
/// The fourth: the same points should give the same lattice whatever form
/// they come in. On a square lattice (a cloud taken from a range image) the
/// four nearest are the lattice neighbours, so this is the lattice step —
/// the range-image rule. On irregular samples it is close to the median
/// edge of their triangulation — the mesh rule. The nearest neighbour
/// alone is the shortest of a point's edges, which would build a finer
/// lattice for a cloud than for the mesh of the same points, no better
/// closed and slower.
pub(crate) const CLOUD_SPACING_NEIGHBOUR: usize = 4;

/// An unorganised cloud's default cube edge in sample spacings: 1.5 (see
/// the module docs; meshes and range images take 2).
pub(crate) const CLOUD_CUBE_SPACINGS: f32 = 1.5;

/// A borrowed input model: what the build reads, without copying a mesh
/// into a [`Model`].
#[derive(Debug, Clone, Copy)]
enum Input<'a> {
    Mesh(&'a TriMesh),
    Points(&'a PointCloud),
    Range(&'a RangeImage),
}

impl<'a> From<&'a Model> for Input<'a> {
    fn from(m: &'a Model) -> Self {
        match m {
            Model::Mesh(m) => Input::Mesh(m),
            Model::Points(p) => Input::Points(p),
            Model::Range(r) => Input::Range(r),
        }
    }
}

fn input_samples(input: Input) -> Result<PointCloud> {
    match input {
        Input::Mesh(m) => Ok(mesh_samples(m)),
        Input::Points(p) => point_cloud_samples(p),
        Input::Range(r) => Ok(range_image_samples(r)),
    }
}

/// The spacing the default lattice is made from (cubes of twice it): a
/// mesh's median edge, a range image's median step, a cloud's median
/// distance to its fourth neighbour times `CLOUD_CUBE_SPACINGS / 2`.
fn spacing_of(input: Input) -> Option<f32> {
    match input {
        Input::Mesh(m) => {
            // Squared lengths: the median's square root is the median
            // length, with one square root instead of one per edge.
            // Far from unit size, the lengths are taken in a frame scaled
            // by a power of two (exact), so that their squares neither
            // overflow nor go subnormal.
            let nv = m.positions.len();
            let s = normalising_scale(m.bbox().size().max_element() / 256.0);
            let mut sq = Vec::with_capacity(3 * m.faces.len());
            for f in &m.faces {
                if f.iter().all(|&i| (i as usize) < nv) {
                    let p = f.map(|i| m.positions[i as usize] * s);
                    for k in 0..3 {
                        sq.push(p[k].distance_squared(p[(k + 1) % 3]));
                    }
                }
            }
            median(sq).map(|x| x.sqrt() / s)
        }
        Input::Range(r) => median(range_spacings(r)),
        Input::Points(p) => {
            if p.positions.len() < 2 {
                return None;
            }
            let step = (p.positions.len() / 20_000).max(1);
            // The query point itself is its own nearest (distance 0).
            let k = CLOUD_SPACING_NEIGHBOUR.min(p.positions.len() - 1);
            // `default_resolution` makes cubes of two spacings: a cloud's
            // is reported scaled so that its cube is `CLOUD_CUBE_SPACINGS`.
            let scale = CLOUD_CUBE_SPACINGS / 2.0;
            if let Some(d) = crate::cloud_spacing::kth_neighbour_distances(&p.positions, step, k) {
                return median(d).map(|h| h * scale);
            }
            // Data the grid does not suit: the same distances from a kd-tree.
            let pts: Vec<[f32; 3]> = p.positions.iter().map(|v| v.to_array()).collect();
            let tree: ImmutableKdTree<f32, 3> = ImmutableKdTree::new_from_slice(&pts).ok()?;
            let n = NonZero::new(k + 1).expect("k + 1 > 0");
            median(
                pts.iter()
                    .step_by(step)
                    .filter_map(|q| {
                        let r = tree
                            .query(q)
                            .nearest_n::<SquaredEuclidean<f32>>(n)
                            .execute();
                        r.get(k).map(|x| x.distance.sqrt())
                    })
                    .collect(),
            )
            .map(|h| h * scale)
        }
    }
}

fn range_spacings(r: &RangeImage) -> Vec<f32> {
    let mut out = Vec::new();
    for row in 0..r.rows {
        for col in 0..r.cols.saturating_sub(1) {
            if let (Some(a), Some(b)) = (r.cell(row, col), r.cell(row, col + 1)) {
                out.push(a.distance(b));
            }
        }
    }
    out
}

/// The default resolution for samples in `bbox` spaced `spacing` apart.
pub(crate) fn default_resolution(bbox: Aabb, spacing: f32) -> u32 {
    let longest = bbox.size().max_element();
    if spacing.is_nan() || spacing <= 0.0 || !longest.is_finite() {
        return 64;
    }
    ((longest / (2.0 * spacing)).ceil() as u32).clamp(8, 1024)
}

/// What one [`IncrementalBuilder::add`] changed.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct AddReport {
    /// Samples in the batch (the points of the cloud passed in).
    pub samples: usize,
    /// Lattice vertices whose signed distance changed.
    pub vertices_changed: usize,
    /// Leaf cubes recomputed (those around the changed vertices).
    pub cubes_recomputed: usize,
    /// Leaf cubes with a surface after the addition.
    pub surface_cubes: usize,
}

/// Builds a model from oriented samples added one batch (e.g. one range
/// image) at a time on a fixed lattice (§4.4's incremental
/// reconstruction): each [`IncrementalBuilder::add`] recomputes only the
/// leaf cubes around what it changed, and [`IncrementalBuilder::build`]
/// makes a model of everything added so far (and may be called again
/// after more adds). Adding batches one at a time gives the same model as
/// adding them together.
///
/// The usual sequence, as `lodkit mco build` runs it: [`samples_of`] each
/// input, [`grid_for`] all of them, [`densify_meshes`], then
/// [`IncrementalBuilder::new`] (with [`IncrementalBuilder::with_tangential_rule`]
/// when some input is a scan or a point cloud), one `add` per input, and
/// `build`. [`build_from_models`] does exactly that.
///
/// Leaf configurations are kept beside the band's bricks: leaf cube
/// `(x, y, z)` lives in the brick of its lowest corner `(x, y, z)`, one
/// byte per cube (0 = no surface or not in the band).
#[derive(Debug, Clone)]
pub struct IncrementalBuilder {
    field: SignedDistanceField,
    /// `BRICK_VOLUME` leaf configurations per brick of the field.
    configs: Vec<u8>,
    surface_cubes: usize,
    samples: u64,
    has_colors: Option<bool>,
    /// The band's sides when the last add computed them (a first add).
    signs: Option<BandSigns>,
    /// The lattice as given; `field` works on it scaled by `scale`.
    grid: Grid,
    /// The power of two the samples are multiplied by (1 for lattices of
    /// ordinary size; see [`normalising_scale`]).
    scale: f32,
    /// Whether [`IncrementalBuilder::build`] prunes band-edge sheets.
    prune_band_edges: bool,
}

/// `grid` with its lengths multiplied by `s` (a power of two: exact).
fn scaled_grid(grid: Grid, s: f32) -> Grid {
    Grid {
        origin: grid.origin * s,
        cube: grid.cube * s,
        ..grid
    }
}

/// Leaf cubes with a surface of `field`, from its per-brick
/// configurations (`BRICK_VOLUME` a brick), `(key, configuration)` in key
/// order; `surface` sizes the output.
fn leaves_of(field: &SignedDistanceField, configs: &[u8], surface: usize) -> Vec<(u64, u8)> {
    let mut out = Vec::with_capacity(surface);
    for (b, cfgs) in configs.chunks_exact(BRICK_VOLUME).enumerate() {
        let [bx, by, bz] = field.brick_coords(b).map(|c| c << BRICK_BITS);
        for (li, &cfg) in cfgs.iter().enumerate() {
            if cfg != 0 {
                let li = li as u32;
                let (x, y, z) = (
                    bx + (li & (BRICK - 1)),
                    by + (li >> BRICK_BITS & (BRICK - 1)),
                    bz + (li >> (2 * BRICK_BITS)),
                );
                out.push((pack(x, y, z), cfg));
            }
        }
    }
    out.sort_unstable_by_key(|l| l.0);
    out
}

impl IncrementalBuilder {
    /// Turns on Hoppe's tangential rule (`TANGENTIAL_LIMIT`
    /// = 1.5 cubes): a lattice vertex counts only where its closest
    /// sample's tangent plane is a fair estimate, so scans and point
    /// clouds get no spurious sheets past their edges. For scan data; closed
    /// meshes build without it (it opens holes at thin features). Call
    /// before adding samples.
    pub fn with_tangential_rule(mut self) -> Self {
        self.field.tangential_limit =
            crate::signed_distance::TANGENTIAL_LIMIT * self.field.grid.cube;
        self
    }

    /// An empty builder on `grid` (from [`grid_for`] or [`Grid::new`]).
    pub fn new(grid: Grid) -> Self {
        let scale = normalising_scale(grid.cube);
        IncrementalBuilder {
            field: SignedDistanceField::new(scaled_grid(grid, scale)),
            configs: Vec::new(),
            surface_cubes: 0,
            samples: 0,
            has_colors: None,
            signs: None,
            grid,
            scale,
            prune_band_edges: false,
        }
    }

    /// Turns on band-edge pruning (`band_edge_pruning.rs`): before the
    /// octree is built, band vertices far from the data whose sign would
    /// open a small bubble at the band's edge are dropped, so the leaf
    /// surface is closed. For closed meshes only; a scan's or an open
    /// mesh's surface ends at the band's edge by design.
    pub fn with_band_edge_pruning(mut self) -> Self {
        self.prune_band_edges = true;
        self
    }

    /// The lattice this builder works on.
    pub fn grid(&self) -> Grid {
        self.grid
    }

    /// Leaf cubes with a surface, `(key, configuration)` in key order.
    pub(crate) fn leaves(&self) -> Vec<(u64, u8)> {
        leaves_of(&self.field, &self.configs, self.surface_cubes)
    }

    /// Adds a batch of oriented samples (a [`samples_of`] result: unit
    /// normals present; a cloud without normals adds nothing). Samples
    /// outside the lattice are clamped into its border cubes; non-finite
    /// ones are skipped. Only the leaf cubes around lattice vertices whose
    /// value changed are recomputed. Cost: `O(samples)` stamping (64
    /// lattice vertices each) plus the recomputed cubes.
    pub fn add(&mut self, s: &PointCloud) -> AddReport {
        if self.scale != 1.0 {
            let scaled = PointCloud {
                positions: s.positions.iter().map(|&p| p * self.scale).collect(),
                normals: s.normals.clone(),
                colors: s.colors.clone(),
            };
            return self.add_scaled(&scaled);
        }
        self.add_scaled(s)
    }

    /// [`IncrementalBuilder::add`] of samples already in the field's frame.
    fn add_scaled(&mut self, s: &PointCloud) -> AddReport {
        let colors = s.colors.is_some();
        self.has_colors = Some(self.has_colors.unwrap_or(colors) && colors);
        self.samples += s.len() as u64;
        let fresh = self.configs.is_empty();
        let changed = self.field.add(s);
        let field = &self.field;
        let bricks = field.brick_count();
        self.configs.resize(bricks * BRICK_VOLUME, 0);
        if fresh {
            // The first add changed every vertex it reached: every cube of
            // every brick is recomputed, a brick slice at a time from bit
            // masks (the same configurations as cube by cube below).
            let masks: Vec<BrickMasks> = (0..bricks).map(|b| field.brick_masks(b)).collect();
            let mut recomputed = 0usize;
            for (b, out) in self.configs.chunks_exact_mut(BRICK_VOLUME).enumerate() {
                let (touched, surface) = brick_configs(field, &masks, b, out);
                recomputed += touched;
                self.surface_cubes += surface;
            }
            self.signs = Some(BandSigns::from_masks(masks));
            return AddReport {
                samples: s.len(),
                vertices_changed: changed,
                cubes_recomputed: recomputed,
                surface_cubes: self.surface_cubes,
            };
        }
        // The cubes around changed vertices: one bit per cube, in the
        // brick of the cube's lowest corner.
        let cells = field.grid.cells();
        let mut dirty = vec![[0u64; BRICK_VOLUME / 64]; bricks];
        for b in 0..bricks {
            field.for_each_changed(b, |x, y, z| {
                let low =
                    (x & (BRICK - 1)) != 0 && (y & (BRICK - 1)) != 0 && (z & (BRICK - 1)) != 0;
                for c in 0..8u32 {
                    let (dx, dy, dz) = (c & 1, c >> 1 & 1, c >> 2);
                    if x < dx || y < dy || z < dz {
                        continue;
                    }
                    let (cx, cy, cz) = (x - dx, y - dy, z - dz);
                    if cx >= cells || cy >= cells || cz >= cells {
                        continue;
                    }
                    // A cube whose lowest corner has no brick is not in the band.
                    let Some(cb) = (if low || c == 0 {
                        Some(b)
                    } else {
                        field.brick_of(cx, cy, cz)
                    }) else {
                        continue;
                    };
                    let li = local_index(cx, cy, cz);
                    dirty[cb][li / 64] |= 1 << (li % 64);
                }
            });
        }
        self.signs = None;
        let mut recomputed = 0usize;
        for (b, words) in dirty.iter().enumerate() {
            let [bx, by, bz] = field.brick_coords(b).map(|c| c << BRICK_BITS);
            for (w, &word) in words.iter().enumerate() {
                let mut m = word;
                while m != 0 {
                    let li = (w * 64) as u32 + m.trailing_zeros();
                    m &= m - 1;
                    let cube = [
                        bx + (li & (BRICK - 1)),
                        by + (li >> BRICK_BITS & (BRICK - 1)),
                        bz + (li >> (2 * BRICK_BITS)),
                    ];
                    let cfg = match leaf_config_in(field, b, cube) {
                        Some(cfg) if cfg != 0 && cfg != 255 => cfg,
                        _ => 0,
                    };
                    let slot = &mut self.configs[b * BRICK_VOLUME + li as usize];
                    self.surface_cubes =
                        self.surface_cubes + (cfg != 0) as usize - (*slot != 0) as usize;
                    *slot = cfg;
                    recomputed += 1;
                }
            }
        }
        AddReport {
            samples: s.len(),
            vertices_changed: changed,
            cubes_recomputed: recomputed,
            surface_cubes: self.surface_cubes,
        }
    }

    /// Adds one posed range image ([`samples_of`]'s Fig. 4.2 normals,
    /// pose applied).
    pub fn add_range_image(&mut self, r: &RangeImage) -> AddReport {
        self.add(&range_image_samples(r))
    }

    /// Builds the model from everything added so far: octree, priority
    /// numbering, crack patches and extraction tables. Errors
    /// ([`Error::Input`]): nothing added reached the lattice, or no leaf
    /// cube holds a surface. Cost: `O(n log n)` in the surface cubes.
    pub fn build(&self) -> Result<McoModel> {
        // A band whose edge a sign change reaches is pruned first, so the
        // leaf surface is closed (`band_edge_pruning.rs`); an untouched
        // band builds from the configurations kept since the last add.
        let pruned = if self.prune_band_edges {
            crate::band_edge_pruning::pruned(&self.field)
        } else {
            None
        };
        let (field, leaves, signs) = match &pruned {
            None => (
                &self.field,
                self.leaves(),
                self.signs
                    .clone()
                    .unwrap_or_else(|| BandSigns::new(&self.field)),
            ),
            Some(f) => {
                let masks: Vec<BrickMasks> =
                    (0..f.brick_count()).map(|b| f.brick_masks(b)).collect();
                let mut configs = vec![0u8; f.brick_count() * BRICK_VOLUME];
                let mut surface = 0;
                for (b, out) in configs.chunks_exact_mut(BRICK_VOLUME).enumerate() {
                    surface += brick_configs(f, &masks, b, out).1;
                }
                (
                    f,
                    leaves_of(f, &configs, surface),
                    BandSigns::from_masks(masks),
                )
            }
        };
        let mut tree = crate::octree_build::build_levels_with(field, signs, &leaves)?;
        let mut model = crate::octree_build::assemble(&mut tree);
        // Every marching-cubes vertex on the position grid a `.mco` file
        // stores (at most 1/1024 of a leaf cube away): the file then holds
        // the model exactly at little cost, and a loaded model cuts as the
        // built one.
        for p in &mut tree.vertices.positions {
            *p = crate::mco_file::snapped_position(&field.grid, *p);
        }
        let together = crate::crack_patch::expand_together(&tree);
        let rank = crate::octree_build::expansion_rank(&model, &tree.vertices.positions);
        crate::priority_numbering::number(&mut model, &together, &rank);
        crate::crack_patch::patch(&tree, &mut model);
        model.vertices = tree.vertices;
        model.prepare_extraction();
        model.has_colors = self.has_colors.unwrap_or(false);
        model.stats.input_samples = self.samples;
        if self.scale != 1.0 {
            // Back to object units, exactly (a power of two); a metric (an
            // area) past f32's range saturates.
            let back = 1.0 / self.scale;
            model.grid = self.grid;
            model.vertices.positions.iter_mut().for_each(|p| *p *= back);
            for x in &mut model.metric {
                *x = (*x * back * back).min(f32::MAX);
            }
        }
        // The normals a `.mco` file stores (octahedral, 2 × 16 bits): the
        // model and the model read from its file cut alike, bit for bit.
        for n in &mut model.vertices.normals {
            *n = crate::mco_file::stored_normal(*n);
        }
        Ok(model)
    }
}

/// The lattice for several inputs: the union box of their `samples`
/// (`samples[i]` = [`samples_of`]`(&models[i])`) and the resolution of
/// `opts` (default: from the inputs' median sample spacing). Errors: no
/// finite sample, a box without extent, a resolution outside
/// `2..=`[`crate::MAX_RESOLUTION`], or a lattice whose build would need
/// more than [`MAX_BUILD_BYTES`] ([`estimate_build_bytes`]; checked here,
/// before anything is sized by the lattice, so a caller that builds step
/// by step is refused as early as the one-call builds).
pub fn grid_for(models: &[Model], samples: &[PointCloud], opts: &Options) -> Result<Grid> {
    let inputs: Vec<Input> = models.iter().map(Input::from).collect();
    grid_for_inputs(&inputs, samples, opts)
}

fn grid_for_inputs(inputs: &[Input], samples: &[PointCloud], opts: &Options) -> Result<Grid> {
    let grid = lattice_of(inputs, samples, opts)?;
    check_estimate(estimate_inputs_bytes(inputs, samples, &grid), &grid)?;
    Ok(grid)
}

/// [`grid_for_inputs`] without the memory check.
fn lattice_of(inputs: &[Input], samples: &[PointCloud], opts: &Options) -> Result<Grid> {
    let bbox = samples.iter().fold(Aabb::EMPTY, |b, s| b.union(&s.bbox()));
    let resolution = match opts.resolution {
        Some(r) => r,
        None => {
            let spacing = median(inputs.iter().filter_map(|&i| spacing_of(i)).collect());
            default_resolution(bbox, spacing.unwrap_or(0.0))
        }
    };
    Grid::new(bbox, resolution)
}

/// Bytes a build holds per input sample at its peak (the sample itself,
/// its place in the signed-distance stamping). With the next constant, an
/// upper figure: the estimate is 1.0–1.2 × the peak resident size measured
/// on spheres (resolution 200–800) and blobs (`examples/build_memory.rs`).
const BYTES_PER_SAMPLE: u64 = 64;
/// Bytes a build holds per leaf cube of surface at its peak (band vertices,
/// leaf configurations, octree nodes, triangles, crack patches, extraction
/// tables), an upper figure measured likewise.
const BYTES_PER_SURFACE_CUBE: u64 = 600;
/// Surface cubes counted per sample of an input without faces (a sample
/// touches the cubes around it; more samples than that per cube only add
/// to cubes already counted).
const CUBES_PER_POINT_SAMPLE: u64 = 8;

/// Builds whose [`estimate_build_bytes`] is above this are refused before
/// anything sized by the lattice is allocated (8 GiB: a sphere at
/// resolution 1,400, far finer than any input's sampling warrants; the
/// default resolution of the inputs lodkit ships needs well under 1 GiB).
pub const MAX_BUILD_BYTES: u64 = 8 << 30;

/// Full-cut triangles per lattice cube of surface area: a surface crosses
/// about 1.5 leaf cubes per cube² of its area (`|nx| + |ny| + |nz|`
/// averaged over orientations) and marching cubes puts about 2 triangles
/// in each. With it, [`mesh_resolution`] picks the cube whose full cut has
/// about the input's triangle count.
const CUT_TRIANGLES_PER_AREA: f64 = 3.0;

/// The lattice resolution (cubes along the longest axis) that keeps a
/// mesh's detail in its octree: a cube edge of `sqrt(3 · area /
/// triangles)`, so the full-resolution cut has about the input's triangle
/// count, clamped to `8..=`[`MAX_RESOLUTION`](crate::MAX_RESOLUTION) and
/// lowered by quarters while [`estimate_build_bytes`] is above
/// `max_bytes`. `None` when the mesh has no area (the default resolution
/// then decides). `lodkit build` and `lodkit mco build` of one mesh use
/// it; the paper's default (twice the sample spacing, [`Options`]) suits
/// scans, whose samples carry noise, not a mesh's own triangles.
/// Errors as [`estimate_build_bytes`]. Cost: one pass over the faces, plus
/// one estimate (`O(input)`) per try.
pub fn mesh_resolution(mesh: &TriMesh, max_bytes: u64) -> Result<Option<u32>> {
    let area = mesh.area_f64();
    let longest = f64::from(mesh.bbox().size().max_element());
    if !(area > 0.0 && longest > 0.0) || mesh.faces.is_empty() {
        return Ok(None);
    }
    let cube = (CUT_TRIANGLES_PER_AREA * area / mesh.faces.len() as f64).sqrt();
    let mut r = (longest / cube)
        .ceil()
        .clamp(8.0, f64::from(crate::MAX_RESOLUTION)) as u32;
    let model = [Model::Mesh(mesh.clone())];
    while r > 8 {
        let opts = Options {
            resolution: Some(r),
        };
        if estimate_build_bytes(&model, &opts)? <= max_bytes {
            break;
        }
        r = (r * 3 / 4).max(8);
    }
    Ok(Some(r))
}

/// An upper estimate of the memory (bytes) a build of `models` with `opts`
/// needs at its peak, from the counts that drive it, computed without
/// making any of them: the input samples (vertices, range pixels, points),
/// the samples densification will add on long mesh edges (counted, each
/// repeated face once), and the leaf cubes the surface crosses (a mesh's
/// area in cubes; 8 per sample for inputs without faces). The build
/// refuses to start above [`MAX_BUILD_BYTES`]; a caller can compare it
/// with its own budget first. Errors as [`grid_for`]. Cost: `O(input)`
/// (the samples' positions and normals are computed, as the build does).
pub fn estimate_build_bytes(models: &[Model], opts: &Options) -> Result<u64> {
    let inputs: Vec<Input> = models.iter().map(Input::from).collect();
    let samples: Vec<PointCloud> = inputs
        .iter()
        .map(|&i| input_samples(i))
        .collect::<Result<_>>()?;
    let grid = lattice_of(&inputs, &samples, opts)?;
    Ok(estimate_inputs_bytes(&inputs, &samples, &grid))
}

fn estimate_inputs_bytes(inputs: &[Input], samples: &[PointCloud], grid: &Grid) -> u64 {
    let cube = grid.cube as f64;
    let mut n_samples = 0u64;
    let mut cubes = 0f64;
    for (input, s) in inputs.iter().zip(samples) {
        n_samples += s.positions.len() as u64;
        if let Input::Mesh(m) = input {
            n_samples += crate::normals_estimation::densify_count(m, grid.cube);
            let mut seen: rustc_hash::FxHashSet<[u32; 3]> = Default::default();
            let area: f64 = m
                .faces
                .iter()
                .filter(|f| f.iter().all(|&i| (i as usize) < m.positions.len()))
                .filter(|f| {
                    let mut k = **f;
                    k.sort_unstable();
                    seen.insert(k)
                })
                .map(|f| {
                    let [a, b, c] = f.map(|i| m.positions[i as usize].as_dvec3());
                    0.5 * (b - a).cross(c - a).length()
                })
                .filter(|x| x.is_finite())
                .sum();
            // A surface crosses at most a few cubes per cube of its area;
            // 2 covers the slanted and curved parts.
            cubes += 2.0 * area / (cube * cube) + s.positions.len() as f64;
        } else {
            cubes += (CUBES_PER_POINT_SAMPLE * s.positions.len() as u64) as f64;
        }
    }
    let cubes = cubes.min(u64::MAX as f64 / 2.0) as u64;
    n_samples
        .saturating_mul(BYTES_PER_SAMPLE)
        .saturating_add(cubes.saturating_mul(BYTES_PER_SURFACE_CUBE))
}

/// The refusal of a build estimated above [`MAX_BUILD_BYTES`].
fn check_estimate(bytes: u64, grid: &Grid) -> Result<()> {
    if bytes > MAX_BUILD_BYTES {
        return Err(Error::Input(format!(
            "resolution {}: the build would need about {:.1} GB of memory, more than its {:.1} GB limit; use a lower resolution",
            grid.resolution,
            bytes as f64 / 1e9,
            MAX_BUILD_BYTES as f64 / 1e9
        )));
    }
    Ok(())
}

/// Mesh samples made dense enough for `grid`: a mesh's triangles with an
/// edge longer than a cube get samples on a half-cube barycentric grid,
/// normals interpolated (without them, long edges leave holes); other
/// inputs' samples are kept. `samples[i]` must be
/// [`samples_of`]`(&models[i])`.
pub fn densify_meshes(models: &[Model], samples: Vec<PointCloud>, grid: &Grid) -> Vec<PointCloud> {
    let inputs: Vec<Input> = models.iter().map(Input::from).collect();
    densify_inputs(&inputs, samples, grid)
}

fn densify_inputs(inputs: &[Input], samples: Vec<PointCloud>, grid: &Grid) -> Vec<PointCloud> {
    inputs
        .iter()
        .zip(samples)
        .map(|(i, mut s)| {
            if let Input::Mesh(mesh) = i {
                crate::normals_estimation::densify_mesh_samples_of(mesh, grid.cube, &mut s);
            }
            s
        })
        .collect()
}

/// Builds a model from several inputs (posed range images, meshes, point
/// clouds, in any mix), on one lattice (see [`Options::resolution`]),
/// adding them one at a time as [`IncrementalBuilder`] does; Hoppe's
/// tangential rule is on when any input is not a mesh.
///
/// Guarantees: deterministic (same inputs and options, same model and
/// `.mco` bytes); every cut of the model is crack-free. Errors
/// ([`Error::Input`], one line): no usable sample, a bounding box without
/// extent, a resolution out of range, no surface crossing the lattice.
/// Cost: roughly linear in the samples and the surface cubes (about 1 M
/// input points per second per core at the default resolution; the
/// `mco_build` bench); memory about 12 bytes per lattice vertex of the
/// band.
pub fn build_from_models(models: &[Model], opts: &Options) -> Result<McoModel> {
    let inputs: Vec<Input> = models.iter().map(Input::from).collect();
    build_from_inputs(&inputs, opts)
}

fn build_from_inputs(inputs: &[Input], opts: &Options) -> Result<McoModel> {
    // Meshes' vertex normals are computed once, for the vertex samples and
    // again for the triangle samples that densify them.
    let mut mesh_normals: Vec<Option<Vec<glam::Vec3>>> = Vec::with_capacity(inputs.len());
    let mut samples: Vec<PointCloud> = Vec::with_capacity(inputs.len());
    for &input in inputs {
        if let Input::Mesh(m) = input {
            let normals = crate::normals_estimation::vertex_normals(m);
            samples.push(crate::normals_estimation::mesh_samples_with(m, &normals));
            mesh_normals.push(Some(normals));
        } else {
            samples.push(input_samples(input)?);
            mesh_normals.push(None);
        }
    }
    if samples.iter().all(PointCloud::is_empty) {
        return Err(Error::Input("the input has no usable samples".into()));
    }
    let grid = grid_for_inputs(inputs, &samples, opts)?;
    for ((input, s), normals) in inputs.iter().zip(&mut samples).zip(&mesh_normals) {
        if let (Input::Mesh(m), Some(normals)) = (input, normals) {
            crate::normals_estimation::densify_mesh_samples(m, normals, grid.cube, s);
        }
    }
    let mut b = IncrementalBuilder::new(grid);
    if inputs.iter().any(|i| !matches!(i, Input::Mesh(_))) {
        b = b.with_tangential_rule();
    } else if inputs
        .iter()
        .all(|i| matches!(i, Input::Mesh(m) if is_closed(m)))
    {
        b = b.with_band_edge_pruning();
    }
    for s in &samples {
        b.add(s);
    }
    b.build()
}

/// Whether every edge of `mesh` is shared by two or more faces (no
/// boundary edge).
fn is_closed(mesh: &TriMesh) -> bool {
    !mesh.faces.is_empty()
        && lodkit_mesh::topology::edge_multiplicities(mesh)
            .iter()
            .all(|e| e.count != 1)
}

/// Whether every model is a closed mesh (no boundary edge): the inputs
/// whose builder takes [`IncrementalBuilder::with_band_edge_pruning`], as
/// [`build_from_models`] does. Cost: one sort of each mesh's edges.
pub fn all_closed_meshes(models: &[Model]) -> bool {
    !models.is_empty()
        && models
            .iter()
            .all(|m| matches!(m, Model::Mesh(mesh) if is_closed(mesh)))
}

/// Builds a model from a triangle mesh (object units; faces
/// counter-clockwise seen from outside): its vertices with area-weighted
/// normals (§4.3.1), densified on triangles longer than a cube. A closed
/// mesh gives a closed model at every cut. Otherwise as
/// [`build_from_models`].
pub fn build_from_mesh(mesh: &TriMesh, opts: &Options) -> Result<McoModel> {
    build_from_inputs(&[Input::Mesh(mesh)], opts)
}

/// Builds a model from posed range images (e.g. the scans a Stanford
/// `.conf` lists, or [`crate::scan_mesh`]'s), with Hoppe's tangential
/// rule. Otherwise as [`build_from_models`].
pub fn build_from_range_images(images: &[RangeImage], opts: &Options) -> Result<McoModel> {
    let inputs: Vec<Input> = images.iter().map(Input::Range).collect();
    build_from_inputs(&inputs, opts)
}

/// Builds a model from a point cloud: its own normals when it has them
/// (one per point, need not be unit length), else PCA normals over the 12
/// nearest neighbours, oriented consistently; Hoppe's tangential rule is
/// on. Errors also when normals must be estimated from fewer than 3
/// points. Otherwise as [`build_from_models`].
pub fn build_from_points(cloud: &PointCloud, opts: &Options) -> Result<McoModel> {
    build_from_inputs(&[Input::Points(cloud)], opts)
}

/// Builds a model from the range scans a Stanford `.conf` lists (range-grid
/// PLY files beside it, each posed as the `.conf` says), as
/// [`build_from_range_images`]. Errors name the file that cannot be read.
pub fn build_from_conf(conf: &Path, opts: &Options) -> Result<McoModel> {
    let images: Vec<RangeImage> = lodkit_mesh::io::conf::load_scans(conf)?
        .into_iter()
        .map(|(_, r)| r)
        .collect();
    build_from_range_images(&images, opts)
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand_xoshiro::Xoshiro256PlusPlus;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};

    /// The median as sorting finds it.
    fn sorted_median(mut v: Vec<f32>) -> Option<f32> {
        v.retain(|x| x.is_finite() && *x > 0.0);
        v.sort_by(f32::total_cmp);
        v.get(v.len() / 2).copied()
    }

    #[test]
    fn radix_median_equals_the_sorted_median() {
        let mut rng = Xoshiro256PlusPlus::seed_from_u64(0x2545_f491_4f6c_dd1d);
        let mut next = || rng.next_u64();
        for n in [1usize, 2, 3, 10, 1001, 20_000] {
            // Lengths around one value (one bucket) and spread widely, with
            // duplicates, zeros, negatives and non-finite values mixed in.
            let v: Vec<f32> = (0..n)
                .map(|i| match next() % 9 {
                    0 => 0.0,
                    1 => -1.0,
                    2 => f32::NAN,
                    3 => f32::INFINITY,
                    4 => 0.01,
                    5 => f32::from_bits((next() >> 33) as u32 & 0x7F7F_FFFF),
                    _ => 0.01 + (i % 97) as f32 * 1e-7,
                })
                .collect();
            assert_eq!(median(v.clone()), sorted_median(v), "n = {n}");
        }
        assert_eq!(median(vec![0.0, f32::NAN, -2.0]), None);
        assert_eq!(median(Vec::new()), None);
    }
}
