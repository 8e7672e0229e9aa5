//! Octree particles from calibrated photographs: shape from silhouette,
//! §8.1.1 of Yemez & Schmitt (feature `silhouettes`).
//!
//! The paper's own statuettes were captured this way: a calibrated camera
//! turning around the object, the octree carved from the silhouettes
//! (the visual hull of Laurentini 1994, carved as an octree after Szeliski
//! 1993 and Schmitt & Yemez 1999), each particle coloured from the images.
//!
//! Stages, one file each: the calibration (COLMAP text model, NeRF
//! `transforms.json`, read by `lodkit_mesh::io::cameras`) → `images` (PNG/JPEG, silhouettes from masks,
//! alpha or a colour key) → `sat` (summed-area tables) → `carve`
//! (IN/OUT/ON octree to level `R`) → the existing thinning (§4.3) →
//! `attributes` (vertex, normal, colour) → the existing ordering,
//! coding and container, unchanged.
//!
//! ```no_run
//! use lodkit_particles::silhouette::{ImageSet, SilhouetteOptions, encode_silhouettes};
//! use lodkit_particles::EncodeOptions;
//! let set = ImageSet::load(std::path::Path::new("ring/transforms.json"), Default::default()).unwrap();
//! let opts = EncodeOptions { depth: Some(8), ..EncodeOptions::DEFAULT };
//! let (pop, report) = encode_silhouettes(&set, &SilhouetteOptions::DEFAULT, &opts).unwrap();
//! ```
pub(crate) mod attributes;
pub(crate) mod carve;
pub(crate) mod images;
pub(crate) mod sat;

use std::path::Path;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::encode::{EncodeOptions, Encoded, encode_thinned};
use crate::error::{Error, Result};
use crate::octree::{Frame, LeafAttributes, Level, MAX_DEPTH, Octree, Sidedness};
use crate::thinning::thin_choosing;
pub use images::{SilhouetteSource, ViewImage};
use lodkit_mesh::image::PixelBudget;
use lodkit_mesh::io::cameras::{self, Calibration, View};
use sat::Sat;

/// Level of the coarse carvings that find the box of the cameras' common
/// view (two passes, the second inside the first's box).
const BOX_LEVEL: u8 = 6;
/// Deepest automatic depth.
const MAX_AUTO_DEPTH: u8 = 10;
/// Views are decoded in parallel batches of about this many pixels, so
/// the decoders' working memory (some 16 bytes a pixel) stays bounded.
pub const DECODE_BATCH_PIXELS: u64 = 1 << 23;

/// A calibration with its decoded images and silhouette tables.
pub struct ImageSet {
    /// The views.
    pub calibration: Calibration,
    /// One image per view, in the same order.
    pub images: Vec<ViewImage>,
    sats: Vec<Sat>,
}

impl ImageSet {
    /// Reads the calibration at `path` (`lodkit_mesh::io::cameras::read`) and every
    /// image and silhouette (in parallel).
    ///
    /// Errors: one line naming the calibration file and the camera — a
    /// malformed line or key, an image missing, unreadable or not of the
    /// intrinsics' size (checked from its header, before decoding), no
    /// silhouette source, an empty silhouette; the views' pixels together
    /// over `lodkit_mesh::image::MAX_RUN_PIXELS` (checked from the calibration,
    /// before any image is read). Memory: 8 bytes a pixel of every view,
    /// plus some 16 bytes a pixel of the views being decoded (at most
    /// [`DECODE_BATCH_PIXELS`] at once).
    pub fn load(path: &Path, source: SilhouetteSource) -> Result<ImageSet> {
        let calibration = cameras::read(path).map_err(|e| Error::Input(e.to_string()))?;
        ImageSet::from_calibration(calibration, source)
    }

    /// Reads every image and silhouette of a calibration already read
    /// (in parallel): [`ImageSet::load`] without reading the calibration
    /// file again. Errors and memory as [`ImageSet::load`].
    pub fn from_calibration(
        calibration: Calibration,
        source: SilhouetteSource,
    ) -> Result<ImageSet> {
        let file = calibration.file.clone();
        let mut budget = PixelBudget::run();
        for v in &calibration.views {
            budget.charge(v.lens.width, v.lens.height).map_err(|e| {
                Error::Input(format!(
                    "{}: {}: {e}; {} views of {}x{} in all",
                    file.display(),
                    v.label,
                    calibration.views.len(),
                    v.lens.width,
                    v.lens.height
                ))
            })?;
        }
        // Decoded in parallel, in batches of bounded pixels; the first
        // failing view in file order is reported, whatever the thread
        // count.
        let mut images: Vec<ViewImage> = Vec::with_capacity(calibration.views.len());
        let mut start = 0;
        while start < calibration.views.len() {
            let mut end = start;
            let mut px = 0u64;
            while end < calibration.views.len() && (end == start || px < DECODE_BATCH_PIXELS) {
                let l = &calibration.views[end].lens;
                px += u64::from(l.width) * u64::from(l.height);
                end += 1;
            }
            let loaded: Vec<Result<ViewImage>> = calibration.views[start..end]
                .par_iter()
                .map(|v| images::load(&file, v, source))
                .collect();
            for r in loaded {
                images.push(r?);
            }
            start = end;
        }
        let mut sats = Vec::with_capacity(images.len());
        for (v, img) in calibration.views.iter().zip(&images) {
            let s = Sat::new(img.width, img.height, &img.silhouette);
            if s.total() == 0 {
                return Err(Error::Input(format!(
                    "{}: {}: the silhouette is empty (no object pixel)",
                    file.display(),
                    v.label
                )));
            }
            sats.push(s);
        }
        Ok(ImageSet {
            calibration,
            images,
            sats,
        })
    }

    /// Object pixels of view `i` over its pixel count.
    pub fn coverage(&self, i: usize) -> f64 {
        let s = &self.sats[i];
        s.total() as f64 / (f64::from(s.width()) * f64::from(s.height()))
    }

    fn carver(&self, margin: f64, near: f64) -> carve::Carver<'_> {
        carve::Carver {
            views: &self.calibration.views,
            sats: &self.sats,
            margin,
            near,
        }
    }

    fn err<T>(&self, msg: impl std::fmt::Display) -> Result<T> {
        Err(Error::Input(format!(
            "{}: {msg}",
            self.calibration.file.display()
        )))
    }
}

/// Options of the carving.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SilhouetteOptions {
    /// The box to carve (world units); `None`: the cameras' common view.
    pub bbox: Option<(Vec3, Vec3)>,
    /// Footprint inflation in pixels, `0..=16` (default 1: a rendered
    /// mask's edge passes a surface point by up to a pixel).
    pub margin: f32,
}

impl SilhouetteOptions {
    /// The common view's box, a one-pixel margin.
    pub const DEFAULT: SilhouetteOptions = SilhouetteOptions {
        bbox: None,
        margin: 1.0,
    };
}

impl Default for SilhouetteOptions {
    fn default() -> Self {
        SilhouetteOptions::DEFAULT
    }
}

/// What the carving did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct CarveReport {
    /// Views used.
    pub views: usize,
    /// The carved box (world units), before it is made a cube.
    pub bbox: [[f32; 3]; 2],
    /// Octree resolution `R`.
    pub depth: u8,
    /// Cubes classified at each level `0..=R`.
    pub tested: Vec<usize>,
    /// ON leaves the carving left (before thinning).
    pub surface_leaves: usize,
    /// Leaves kept by thinning (the particles).
    pub particles: usize,
}

/// The carved octree with its attributes, thinned, ready to encode.
pub struct CarvedOctree {
    /// The octree (levels, labels, leaf attributes).
    pub(crate) tree: Octree,
    /// Cubes eliminated by thinning per level.
    pub(crate) eliminated: Vec<usize>,
    /// Level below which outer thinning was relaxed.
    pub(crate) relax_below: u8,
    /// What the carving did.
    pub report: CarveReport,
}

impl CarvedOctree {
    /// World positions, unit normals and colours of the particles (the kept
    /// ON leaves), in Morton order: the carved hull as a point cloud.
    pub fn particles(&self) -> lodkit_mesh::PointCloud {
        let t = &self.tree;
        let r = t.depth as usize;
        let mut pc = lodkit_mesh::PointCloud::default();
        let mut normals = Vec::new();
        let mut colours = Vec::new();
        for (i, l) in t.levels[r].label.iter().enumerate() {
            if *l != crate::octree::Label::On {
                continue;
            }
            pc.positions
                .push(t.frame.cell_centre(t.leaves.q[i], crate::octree::QBITS));
            if let Some(n) = &t.leaves.normal {
                normals.push(n[i]);
            }
            if let Some(c) = &t.leaves.colour {
                colours.push([c[i][0], c[i][1], c[i][2], 255]);
            }
        }
        pc.normals = (!normals.is_empty()).then_some(normals);
        pc.colors = (!colours.is_empty()).then_some(colours);
        pc
    }
}

/// The box to carve: `opts.bbox`, or the common view of the cameras (two
/// coarse carvings of a cube around the point nearest every optical axis,
/// twice as large as the cameras' spread). Errors name the camera the
/// object lies behind, or say the common view is empty or unbounded.
fn carve_box(set: &ImageSet, opts: &SilhouetteOptions) -> Result<(Vec3, Vec3)> {
    let views = &set.calibration.views;
    let margin = f64::from(opts.margin);
    let in_front = |p: DVec3| -> Result<()> {
        for v in views {
            if v.to_camera(p).z <= 0.0 {
                return set.err(format!(
                    "{}: the object lies behind this camera (it looks away from the other views' common view)",
                    v.label
                ));
            }
        }
        Ok(())
    };
    if let Some((lo, hi)) = opts.bbox {
        in_front(((lo + hi) * 0.5).as_dvec3())?;
        return Ok((lo, hi));
    }
    // The least-squares point nearest every optical axis.
    let mut a = glam::DMat3::ZERO;
    let mut b = DVec3::ZERO;
    for v in views {
        let d = v.rotation.row(2);
        let m = glam::DMat3::IDENTITY - glam::DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        a += m;
        b += m * v.centre();
    }
    let det = a.determinant();
    let centre = if det.abs() > 1e-9 * views.len().pow(3) as f64 {
        a.inverse() * b
    } else {
        // Parallel axes: the point a unit ahead of the mean camera.
        let c: DVec3 = views.iter().map(View::centre).sum::<DVec3>() / views.len() as f64;
        let d: DVec3 = views.iter().map(|v| v.rotation.row(2)).sum::<DVec3>();
        c + d.normalize_or_zero()
    };
    if !centre.is_finite() {
        return set.err("the cameras give no point they all look towards");
    }
    in_front(centre)?;
    let spread = views
        .iter()
        .map(|v| v.centre().distance(centre))
        .fold(0.0f64, f64::max)
        .max(1e-6);
    let half = (2.0 * spread) as f32;
    let mut frame = Frame {
        origin: centre.as_vec3() - Vec3::splat(half),
        size: 2.0 * half,
    };
    let mut found = None;
    for pass in 0..2 {
        let near = f64::from(frame.size) * 1e-6;
        let c = set.carver(margin, near);
        let found_box = carve::hull_box(&c, &frame, BOX_LEVEL).or_else(|(tests, r)| {
            set.err(format!(
                "finding the common view takes over {} units of work against the {} views \
                 (reached {tests} at level {r}); give --bbox or fewer views",
                carve::MAX_CARVE_TESTS,
                views.len()
            ))
        })?;
        match found_box {
            None => {
                return set.err(
                    "the silhouettes have no common view: every part of the space is outside some view's silhouette",
                );
            }
            Some(((lo, hi), touches)) => {
                if touches && pass == 0 {
                    return set.err("the cameras' common view is unbounded (do they surround the object?); give --bbox");
                }
                found = Some((lo, hi));
                frame = Frame::around(lo, hi);
            }
        }
    }
    let (lo, hi) = found.expect("two passes ran");
    in_front(((lo + hi) * 0.5).as_dvec3())?;
    Ok((lo, hi))
}

/// The carving box's width in pixels as each view sees it (at the box's
/// centre, the larger focal length).
fn projected_widths<'a>(set: &'a ImageSet, frame: &'a Frame) -> impl Iterator<Item = f64> + 'a {
    let centre = (frame.origin + Vec3::splat(frame.size * 0.5)).as_dvec3();
    set.calibration.views.iter().map(move |v| {
        let z = v.to_camera(centre).z.max(1e-12);
        v.lens.fx.max(v.lens.fy) * f64::from(frame.size) / z
    })
}

/// The depth whose leaves project to about one pixel in the median view:
/// `log2` of the box's projected width, in `4..=10`.
fn auto_depth(set: &ImageSet, frame: &Frame) -> u8 {
    let mut px: Vec<f64> = projected_widths(set, frame).collect();
    px.sort_by(f64::total_cmp);
    let median = px[px.len() / 2];
    (median.max(1.0).log2().round() as u8).clamp(4, MAX_AUTO_DEPTH)
}

/// The deepest level whose leaves still project to half a pixel or more
/// in some view: `1 + ⌈log2⌉` of the box's largest projected width (at
/// least [`BOX_LEVEL`]). A finer carving only multiplies the work.
fn finest_depth(set: &ImageSet, frame: &Frame) -> u8 {
    let px = projected_widths(set, frame).fold(1.0f64, f64::max);
    let d = px.min(f64::from(1u32 << 30)).log2().ceil() as u8 + 1;
    d.clamp(BOX_LEVEL, MAX_DEPTH)
}

/// Carves the image set's octree to `opts.depth` (`None`: leaves of about
/// a pixel, [`auto_depth`]), thins it with `opts.thinning` and computes
/// the particle attributes (see `attributes`).
///
/// Errors: a depth outside `1..=16` or finer than the images resolve
/// (leaves under half a pixel in every view), a carving past
/// [`carve::MAX_CARVE_TESTS`], a camera the object lies behind, an
/// empty or unbounded common view, or a carving that leaves no surface.
/// Cost: the cubes classified (about the surface's leaves times 8, each
/// `O(views)`), 64 point tests per surface leaf, and a few rays a particle
/// through a `256³` occupancy grid; memory some 50 bytes a classified cube.
pub fn carve_octree(
    set: &ImageSet,
    sil: &SilhouetteOptions,
    opts: &EncodeOptions,
) -> Result<CarvedOctree> {
    if !(sil.margin.is_finite() && (0.0..=16.0).contains(&sil.margin)) {
        return Err(Error::Input(format!(
            "silhouette margin {} is outside 0..=16 pixels",
            sil.margin
        )));
    }
    if let Some((lo, hi)) = sil.bbox
        && !(lo.is_finite() && hi.is_finite() && lo.cmplt(hi).all())
    {
        return Err(Error::Input(format!(
            "box {lo} .. {hi} is not a finite box with min < max on every axis"
        )));
    }
    let (lo, hi) = carve_box(set, sil)?;
    let frame = Frame::around(lo, hi);
    let depth = match opts.depth {
        Some(d) if (1..=MAX_DEPTH).contains(&d) => d,
        Some(d) => {
            return Err(Error::Input(format!(
                "depth {d} is outside 1..={MAX_DEPTH}"
            )));
        }
        None => auto_depth(set, &frame),
    };
    let finest = finest_depth(set, &frame);
    if depth > finest {
        return set.err(format!(
            "depth {depth} is finer than the images resolve (its leaves would be under half a \
             pixel in every view); depth {finest} or less fits"
        ));
    }
    let near = f64::from(frame.size) * 1e-6;
    let c = set.carver(f64::from(sil.margin), near);
    let carved = carve::carve(&c, &frame, depth).or_else(|(tests, r)| {
        set.err(format!(
            "carving to depth {depth} takes over {} units of work against the {} views \
             (reached {tests} at level {r}); give a smaller --depth or fewer views",
            carve::MAX_CARVE_TESTS,
            set.calibration.views.len()
        ))
    })?;
    if carved.leaves.is_empty() {
        return set
            .err("carving left no surface: the silhouettes have no common view inside the box");
    }
    // The octree: ON cells are the surface leaves and their ancestors;
    // the empty children of ON cells take the carving's label.
    let mut levels = Vec::with_capacity(depth as usize + 1);
    let mut cells = carved.leaves.clone();
    levels.push(Level::new(cells.clone()));
    for _ in 0..depth {
        cells = cells.iter().map(|m| m >> 3).collect();
        cells.dedup();
        levels.push(Level::new(cells.clone()));
    }
    levels.reverse();
    for r in 1..=depth as usize {
        let mut band = crate::octree::MortonMap::default();
        for &p in &levels[r - 1].cells {
            for k in 0..8 {
                let m = (p << 3) | k;
                if levels[r].find(m).is_none() {
                    band.insert(m, carved.label(r as u8, m));
                }
            }
        }
        levels[r].band = band;
    }
    let mut tree = Octree {
        depth,
        frame,
        levels,
        leaves: LeafAttributes::default(),
        sidedness: Sidedness::FloodFill,
    };
    // Thinning reads the labels (and, choosing where outer thinning is
    // relaxed, positions: the leaf centres stand in); the attributes are
    // then computed for the leaves it keeps.
    let all = vec![false; carved.leaves.len()];
    tree.leaves.q = attributes::vertices_and_normals(&tree, &carved, &all).0;
    let (eliminated, relax_below) = thin_choosing(&mut tree, &opts.thinning);
    let d = depth as usize;
    let kept: Vec<bool> = tree.levels[d]
        .label
        .iter()
        .map(|l| *l == crate::octree::Label::On)
        .collect();
    let (q, normals) = attributes::vertices_and_normals(&tree, &carved, &kept);
    tree.leaves = LeafAttributes {
        q,
        normal: Some(normals),
        colour: None,
    };
    let points: Vec<DVec3> = tree
        .leaves
        .q
        .iter()
        .map(|&q| {
            let o = frame.origin.as_dvec3();
            let s = f64::from(frame.size) / f64::from(1u32 << crate::octree::QBITS);
            o + (DVec3::new(q[0] as f64, q[1] as f64, q[2] as f64) + 0.5) * s
        })
        .collect();
    let normals = tree.leaves.normal.as_ref().expect("set above");
    let colours = attributes::colours(
        &tree,
        &set.calibration.views,
        &set.images,
        &points,
        normals,
        &kept,
    );
    tree.leaves.colour = Some(colours);
    let report = CarveReport {
        views: set.calibration.views.len(),
        bbox: [lo.to_array(), hi.to_array()],
        depth,
        tested: carved.tested.clone(),
        surface_leaves: carved.leaves.len(),
        particles: kept.iter().filter(|&&k| k).count(),
    };
    Ok(CarvedOctree {
        tree,
        eliminated,
        relax_below,
        report,
    })
}

/// Carves the image set ([`carve_octree`]) and encodes the particles as a
/// `.pop` stream, exactly as [`crate::encode`] codes a mesh's octree:
/// deterministic (the same images, calibration and options give the same
/// bytes, whatever the thread count).
pub fn encode_silhouettes(
    set: &ImageSet,
    sil: &SilhouetteOptions,
    opts: &EncodeOptions,
) -> Result<(Encoded, CarveReport)> {
    let c = carve_octree(set, sil, opts)?;
    Ok((encode_carved(&c, opts)?, c.report))
}

/// Encodes an octree [`carve_octree`] made.
pub fn encode_carved(c: &CarvedOctree, opts: &EncodeOptions) -> Result<Encoded> {
    let mut e = encode_thinned(&c.tree, &c.eliminated, opts)?;
    e.report.relax_below = opts.thinning.outer.then_some(c.relax_below);
    Ok(e)
}
