//! The render entry points: mesh and point cloud to an RGBA image.
//!
//! Stages: camera-space vertices → triangle setup (`clip`)
//! → binning into horizontal bands → per band, in parallel:
//! rasterisation (`raster`), shading of the visible
//! samples ([`shade`](crate::shade)) and the box filter from samples to
//! pixels. Bands are independent and joined in order, so the image does
//! not depend on the thread count.

use glam::Vec3;
use lodkit_mesh::{Aabb, PointCloud, TriMesh};
use rayon::prelude::*;

use crate::RenderError;
use crate::camera::Camera;
use crate::clip::{ScreenTri, clip_planes, setup_triangle};
use crate::image::Image;
use crate::raster::{Band, EMPTY};
use crate::shade::{Surface, shade};
use crate::texture::Materials;

/// Largest image side accepted, in pixels.
pub const MAX_SIZE: u32 = 8192;
/// Largest supersampling factor (samples per pixel side).
pub const MAX_SUPERSAMPLE: u32 = 4;
/// Samples in one band's buffers (about 20 MB at 20 bytes a sample): what
/// bounds the renderer's working memory per thread at any image size.
const BAND_SAMPLES: usize = 1 << 20;

/// Which normals shade a mesh.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Normals {
    /// The mesh's own vertex normals when it has them, else flat faces.
    Auto,
    /// Each face's geometric normal (faceted look), even if the mesh has normals.
    Flat,
    /// The mesh's vertex normals, or area-weighted ones computed from the
    /// faces ([`lodkit_mesh::normals::vertex_normals`]) when it has none.
    Smooth,
}

/// Options of [`render`] and [`render_points`]; [`RenderOptions::DEFAULT`]
/// documents the defaults.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RenderOptions {
    /// Image width in pixels, `1..=MAX_SIZE`.
    pub width: u32,
    /// Image height in pixels, `1..=MAX_SIZE`.
    pub height: u32,
    /// RGB of pixels the object does not cover (their alpha is 0).
    pub background: [u8; 3],
    /// Colour of a surface without vertex colours (or with them disabled).
    pub base_colour: [u8; 3],
    /// Samples per pixel side, `1..=MAX_SUPERSAMPLE` (`s²` samples a
    /// pixel, box-filtered): anti-aliased edges, and alpha = coverage.
    pub supersample: u32,
    /// Use the mesh's or cloud's vertex colours when it has them.
    pub vertex_colours: bool,
    /// Which normals shade a mesh.
    pub normals: Normals,
    /// Radius of a point's splat in object units; `None` picks one from
    /// the cloud's density (its bounding box's area over the point count).
    pub point_radius: Option<f32>,
}

impl RenderOptions {
    /// 1024 × 1024, white background, a light clay base colour, 3 × 3
    /// samples a pixel, vertex colours on, [`Normals::Auto`], automatic
    /// splat size.
    pub const DEFAULT: RenderOptions = RenderOptions {
        width: 1024,
        height: 1024,
        background: [255, 255, 255],
        base_colour: [214, 206, 194],
        supersample: 3,
        vertex_colours: true,
        normals: Normals::Auto,
        point_radius: None,
    };

    fn check(&self) -> Result<(), RenderError> {
        if !(1..=MAX_SIZE).contains(&self.width) || !(1..=MAX_SIZE).contains(&self.height) {
            return Err(RenderError::Options(format!(
                "image size {}x{} is outside 1..={MAX_SIZE} on a side",
                self.width, self.height
            )));
        }
        if !(1..=MAX_SUPERSAMPLE).contains(&self.supersample) {
            return Err(RenderError::Options(format!(
                "supersampling {} is outside 1..={MAX_SUPERSAMPLE}",
                self.supersample
            )));
        }
        if let Some(r) = self.point_radius
            && !(r.is_finite() && r > 0.0)
        {
            return Err(RenderError::Options(format!(
                "point radius {r} is not a positive number"
            )));
        }
        Ok(())
    }
}

impl Default for RenderOptions {
    fn default() -> Self {
        RenderOptions::DEFAULT
    }
}

/// Renders `mesh` seen by `camera` into a `width × height` RGBA image.
///
/// Guarantees: the same mesh, camera and options give the same pixels (and
/// so the same [`Image::to_png`] bytes), whatever the thread count. Alpha
/// is the fraction of each pixel's samples the mesh covers (0 or 255 with
/// `supersample == 1`); [`Image::mask`] is the object silhouette. Both
/// windings are drawn; faces behind the camera or beyond the near plane
/// are clipped, not dropped whole. Vertex colours are interpolated when
/// present and enabled; textures are drawn by [`render_textured`].
///
/// Errors: options out of range ([`RenderError::Options`]), a face index
/// out of range, a non-finite vertex or an attribute of the wrong length
/// ([`RenderError::Mesh`]). A mesh with no faces gives an empty
/// (background) image.
///
/// Cost: `O(V + F + W·H·s²)` time, spread over the rayon pool; memory
/// about 100 bytes a face plus one band of 2²⁰ samples per thread, on top
/// of the image.
pub fn render(mesh: &TriMesh, camera: &Camera, opts: &RenderOptions) -> Result<Image, RenderError> {
    render_mesh(mesh, None, camera, opts)
}

/// [`render`] with materials: each face coloured by its material's base
/// colour factor and texture at the interpolated UV (the factor alone
/// when the mesh has no UVs), times the vertex colour when there is one
/// ([`crate::texture`]); faces with [`Materials::NONE`] are drawn as
/// [`render`] draws them.
///
/// Guarantees and cost as [`render`], plus one bilinear texture lookup a
/// covered sample. Errors as [`render`], and [`RenderError::Mesh`] when
/// `materials` does not fit the mesh (a face count, material or texture
/// index, or pixel buffer that disagrees; UVs of the wrong length).
pub fn render_textured(
    mesh: &TriMesh,
    materials: &Materials,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    materials
        .check(mesh.faces.len())
        .map_err(RenderError::Mesh)?;
    render_mesh(mesh, Some(materials), camera, opts)
}

fn render_mesh(
    mesh: &TriMesh,
    materials: Option<&Materials>,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    opts.check()?;
    check_mesh(mesh)?;
    let s = opts.supersample;
    let k = camera.intrinsics(opts.width * s, opts.height * s);
    let cam: Vec<Vec3> = mesh
        .positions
        .par_iter()
        .map(|&p| camera.to_camera_cv(p))
        .collect();
    let planes = clip_planes(&k, near_plane(camera, &mesh.bbox()));
    let tris: Vec<ScreenTri> = mesh
        .faces
        .par_chunks(4096)
        .enumerate()
        .map(|(c, faces)| {
            let mut out = Vec::with_capacity(faces.len());
            for (i, f) in faces.iter().enumerate() {
                let p = [cam[f[0] as usize], cam[f[1] as usize], cam[f[2] as usize]];
                setup_triangle((c * 4096 + i) as u32, p, &planes, &k, &mut out);
            }
            out
        })
        .flatten()
        .collect();
    let computed;
    let vertex_normals = match (opts.normals, &mesh.normals) {
        (Normals::Flat, _) => None,
        (_, Some(n)) => Some(n.as_slice()),
        (Normals::Auto, None) => None,
        (Normals::Smooth, None) => {
            computed = lodkit_mesh::normals::vertex_normals(mesh);
            Some(computed.as_slice())
        }
    };
    let surface = Surface::Mesh {
        mesh,
        vertex_normals,
        face_normals: if vertex_normals.is_some() {
            Vec::new()
        } else {
            lodkit_mesh::normals::face_normals(mesh)
        },
        colours: colours(&mesh.colors, opts),
        materials,
    };
    let layout = Layout::new(opts);
    let bins = layout.bin(tris.iter().map(|t| t.rows()));
    Ok(layout.run(camera, opts, &surface, &bins, |band, i| {
        band.triangle(&tris[i as usize])
    }))
}

/// Renders `cloud` as discs ("splats") of [`RenderOptions::point_radius`]
/// object units facing the camera, shaded by the point normals when the
/// cloud has them (else unlit, darkened with depth) and coloured by its colours when present.
///
/// Guarantees, errors and cost as [`render`] (with points for faces); an
/// empty cloud gives a background image.
pub fn render_points(
    cloud: &PointCloud,
    camera: &Camera,
    opts: &RenderOptions,
) -> Result<Image, RenderError> {
    opts.check()?;
    check_points(cloud)?;
    let s = opts.supersample;
    let k = camera.intrinsics(opts.width * s, opts.height * s);
    let bbox = cloud.bbox();
    let radius = opts
        .point_radius
        .unwrap_or_else(|| auto_radius(&bbox, cloud.len()));
    let near = near_plane(camera, &bbox);
    // (centre x, centre y, radius) in samples, inverse depth; None off-view.
    let splats: Vec<Option<(f32, f32, f32, f32)>> = cloud
        .positions
        .par_iter()
        .map(|&p| {
            let c = camera.to_camera_cv(p);
            if c.z <= near {
                return None;
            }
            let u = (k.fx * c.x as f64 / c.z as f64 + k.cx) as f32;
            let v = (k.fy * c.y as f64 / c.z as f64 + k.cy) as f32;
            let r = (k.fy * radius as f64 / c.z as f64) as f32;
            let (w, h) = (k.width as f32, k.height as f32);
            (u + r >= 0.0 && v + r >= 0.0 && u - r <= w && v - r <= h).then_some((
                u,
                v,
                r,
                1.0 / c.z,
            ))
        })
        .collect();
    let inv_z_range = splats
        .iter()
        .flatten()
        .fold((0.0f32, f32::INFINITY), |(n, f), s| {
            (n.max(s.3), f.min(s.3))
        });
    let surface = Surface::Points {
        normals: cloud.normals.as_deref(),
        colours: colours(&cloud.colors, opts),
        inv_z_range,
    };
    let layout = Layout::new(opts);
    let bins = layout.bin(splats.iter().map(|sp| match sp {
        Some((_, v, r, _)) => {
            let r = r.max(std::f32::consts::FRAC_1_SQRT_2);
            ((v - r - 0.5).floor() as i64, (v + r - 0.5).ceil() as i64)
        }
        None => (1, 0),
    }));
    Ok(layout.run(camera, opts, &surface, &bins, |band, i| {
        if let Some((u, v, r, iz)) = splats[i as usize] {
            band.splat(i, u, v, r, iz);
        }
    }))
}

/// A splat radius from the cloud's density: the points are taken as
/// spread over half the area of their bounding box's faces, and each disc
/// as large as its share of it.
fn auto_radius(bbox: &Aabb, n: usize) -> f32 {
    let d = bbox.size();
    let area = (d.x * d.y + d.y * d.z + d.z * d.x).max(f32::MIN_POSITIVE);
    let r = (area / n.max(1) as f32).sqrt() * 0.6;
    if r.is_finite() && r > 0.0 { r } else { 1e-3 }
}

/// The near clipping distance: small against the scene's extent from the
/// camera, so nothing in view is cut, yet far from 0 so inverse depths
/// stay finite.
fn near_plane(camera: &Camera, bbox: &Aabb) -> f32 {
    let extent = if bbox.is_empty() {
        1.0
    } else {
        camera.position.distance(bbox.center()) + bbox.diagonal()
    };
    (extent * 1e-5).max(f32::MIN_POSITIVE * 1e6)
}

fn colours<'a>(c: &'a Option<Vec<[u8; 4]>>, opts: &RenderOptions) -> Option<&'a [[u8; 4]]> {
    if opts.vertex_colours {
        c.as_deref()
    } else {
        None
    }
}

/// How the sample buffer splits into bands of whole pixel rows.
struct Layout {
    s: usize,
    width: usize,
    height: usize,
    rows_per_band: usize,
}

impl Layout {
    fn new(opts: &RenderOptions) -> Layout {
        let s = opts.supersample as usize;
        let (width, height) = (opts.width as usize, opts.height as usize);
        let rows_per_band = (BAND_SAMPLES / (width * s * s)).clamp(1, height);
        Layout {
            s,
            width,
            height,
            rows_per_band,
        }
    }

    fn bands(&self) -> usize {
        self.height.div_ceil(self.rows_per_band)
    }

    /// For each band, the elements (in input order) whose inclusive sample
    /// row range `(lo, hi)` meets it.
    fn bin(&self, rows: impl Iterator<Item = (i64, i64)>) -> Vec<Vec<u32>> {
        let per = (self.rows_per_band * self.s) as i64;
        let last = self.bands() as i64 - 1;
        let mut bins = vec![Vec::new(); self.bands()];
        for (i, (lo, hi)) in rows.enumerate() {
            if hi < 0 || lo > hi {
                continue;
            }
            let b0 = lo.max(0) / per;
            let b1 = (hi / per).min(last);
            for b in b0..=b1 {
                bins[b as usize].push(i as u32);
            }
        }
        bins
    }

    /// Draws each band's elements with `draw`, shades and filters it, and
    /// joins the bands into the image.
    fn run(
        &self,
        camera: &Camera,
        opts: &RenderOptions,
        surface: &Surface<'_>,
        bins: &[Vec<u32>],
        draw: impl Fn(&mut Band, u32) + Sync,
    ) -> Image {
        let s = self.s;
        let light = camera.rotation.z_axis;
        let base = Vec3::from_array(opts.base_colour.map(|c| c as f32));
        let bg = opts.background;
        let parts: Vec<Vec<u8>> = bins
            .par_iter()
            .enumerate()
            .map(|(b, items)| {
                let y0 = b * self.rows_per_band;
                let rows = self.rows_per_band.min(self.height - y0);
                let mut band = Band::new(self.width * s, y0 * s, rows * s);
                for &i in items {
                    draw(&mut band, i);
                }
                let mut out = vec![0u8; rows * self.width * 4];
                for py in 0..rows {
                    for px in 0..self.width {
                        let mut sum = Vec3::ZERO;
                        let mut n = 0u32;
                        for sy in 0..s {
                            let row = (py * s + sy) * band.width;
                            for sx in 0..s {
                                let i = row + px * s + sx;
                                if band.id[i] != EMPTY {
                                    sum += shade(
                                        surface,
                                        band.id[i],
                                        band.bary[i],
                                        band.inv_z[i],
                                        light,
                                        base,
                                    );
                                    n += 1;
                                }
                            }
                        }
                        let o = (py * self.width + px) * 4;
                        if n == 0 {
                            out[o..o + 3].copy_from_slice(&bg);
                        } else {
                            let c = sum / n as f32;
                            for (k, v) in c.to_array().iter().enumerate() {
                                out[o + k] = v.round().clamp(0.0, 255.0) as u8;
                            }
                            let total = (s * s) as u32;
                            out[o + 3] = ((255 * n + total / 2) / total) as u8;
                        }
                    }
                }
                out
            })
            .collect();
        Image {
            width: self.width as u32,
            height: self.height as u32,
            pixels: parts.concat(),
        }
    }
}

fn check_mesh(mesh: &TriMesh) -> Result<(), RenderError> {
    let n = mesh.positions.len();
    if n > u32::MAX as usize || mesh.faces.len() >= u32::MAX as usize {
        return Err(RenderError::Mesh("more than 2³² vertices or faces".into()));
    }
    if let Some(i) = mesh.positions.iter().position(|p| !p.is_finite()) {
        return Err(RenderError::Mesh(format!("vertex {i} is not finite")));
    }
    for (what, len) in [
        ("normals", mesh.normals.as_ref().map(Vec::len)),
        ("colours", mesh.colors.as_ref().map(Vec::len)),
        ("UVs", mesh.uvs.as_ref().map(Vec::len)),
    ] {
        if let Some(l) = len
            && l != n
        {
            return Err(RenderError::Mesh(format!("{l} {what} for {n} vertices")));
        }
    }
    if let Some(normals) = &mesh.normals
        && let Some(i) = normals.iter().position(|p| !p.is_finite())
    {
        return Err(RenderError::Mesh(format!("normal {i} is not finite")));
    }
    if let Some((i, f)) = mesh
        .faces
        .iter()
        .enumerate()
        .find(|(_, f)| f.iter().any(|&v| v as usize >= n))
    {
        return Err(RenderError::Mesh(format!(
            "face {i} ({} {} {}) has an index beyond the {n} vertices",
            f[0], f[1], f[2]
        )));
    }
    Ok(())
}

fn check_points(cloud: &PointCloud) -> Result<(), RenderError> {
    let n = cloud.positions.len();
    if n > u32::MAX as usize - 1 {
        return Err(RenderError::Mesh("more than 2³² − 1 points".into()));
    }
    if let Some(i) = cloud.positions.iter().position(|p| !p.is_finite()) {
        return Err(RenderError::Mesh(format!("point {i} is not finite")));
    }
    for (what, len) in [
        ("normals", cloud.normals.as_ref().map(Vec::len)),
        ("colours", cloud.colors.as_ref().map(Vec::len)),
    ] {
        if let Some(l) = len
            && l != n
        {
            return Err(RenderError::Mesh(format!("{l} {what} for {n} points")));
        }
    }
    Ok(())
}
