//! # lodkit-render
//!
//! A small deterministic software renderer for lodkit's meshes and point
//! clouds: pictures for reports, heat maps of errors, and calibrated
//! camera rings (images, object masks and camera files) for shape from
//! silhouette.
//!
//! ```no_run
//! use lodkit_render::{Camera, RenderOptions, render};
//! let mesh = lodkit_mesh::shapes::icosphere(4);
//! let opts = RenderOptions { width: 640, height: 480, ..RenderOptions::DEFAULT };
//! let cam = Camera::orbit(&mesh.bbox(), 30.0, 20.0, 35.0, 640.0 / 480.0).unwrap();
//! let png = render(&mesh, &cam, &opts).unwrap().over(opts.background).to_png().unwrap();
//! ```
//!
//! The stages read in the file names: `camera.rs` (pose and pinhole,
//! [`Camera`]) → `clip.rs` (near-plane and guard-band clipping, fixed-point
//! snapping) → `raster.rs` (edge functions, top-left rule, depth buffer) →
//! `shade.rs` (ambient + Lambert headlight) → `render.rs` (bands, box
//! filter, [`render`]) → `image.rs` (RGBA, mask, PNG: [`Image`], [`Mask`]);
//! `colour_scale.rs` maps numbers to heat-map colours ([`colour_scale`]);
//! `camera_ring.rs` writes camera rings ([`CameraRing`]). Every public item
//! is at the crate root.
//!
//! Why hand-written: the kept Rust software rasteriser, `euc` (0.5), is a
//! generic shader pipeline over its own vector library (`vek`, a second
//! one beside glam) and documents neither its fill rule nor exact
//! coverage; a silhouette carver needs both, and the whole renderer here
//! is smaller than the glue it would take. `tiny-skia` and `raqote` are
//! 2-D only (no depth buffer).
//!
//! # Guarantees
//! - **Deterministic**: the same input, camera and options give the same
//!   pixels and PNG bytes, whatever the thread count (bands are rendered
//!   independently and joined in order; ties in depth go to the face that
//!   comes first). PNG bytes use a fixed DEFLATE level and filter and hold
//!   no time or text chunk.
//! - **Watertight**: vertex positions are snapped to 1/256 sample and the
//!   edge functions are exact integers, so a closed mesh has no cracks
//!   and no sample is drawn twice by neighbouring faces.
//! - **Bounded memory**: one band of 2²⁰ samples per thread whatever the
//!   image size, plus about 100 bytes a face.
//!
//! Colour: vertex colours, or a clay base colour; [`render_textured`] adds
//! materials (base colour factors and decoded textures, [`Materials`]).
//!
//! # Conventions
//!
//! **World.** The mesh's own object space and units, right-handed, nothing
//! rescaled or re-centred. [`Camera::orbit`] takes **+Y as up**; azimuth
//! turns about +Y from +Z towards +X, elevation lifts towards +Y.
//!
//! **Pixels.** Origin at the top-left corner of the image, `u` to the
//! right, `v` down; pixel `(i, j)` covers `[i, i+1) × [j, j+1)`, so its
//! centre is `(i + ½, j + ½)` (COLMAP's convention). The principal point
//! is the image centre `(w/2, h/2)`; pixels are square (`fx = fy`).
//!
//! **Camera frames.**
//! - *OpenGL / Blender* (NeRF `transform_matrix`, [`Camera::rotation`]):
//!   +X right, +Y up, the camera looks along **−Z**.
//! - *OpenCV / COLMAP* (`images.txt`): +X right, +Y **down**, the camera
//!   looks along **+Z**. The same camera in both: `x_cv = (x_gl, −y_gl, −z_gl)`.
//!
//! **Projection** of a world point `X`: `x = R·X + t` with COLMAP's
//! world-to-camera `R`, `t` ([`Camera::world_to_camera_cv`]); then
//! `u = fx·x/z + cx`, `v = fy·y/z + cy` (visible only if `z > 0`).
//! Equivalently with NeRF's camera-to-world `M` (OpenGL): `[xg, yg, zg] =
//! M⁻¹·X`, `u = cx + fx·xg/(−zg)`, `v = cy − fy·yg/(−zg)`.
//!
//! # Camera ring layout
//!
//! [`CameraRing`] and `lodkit render MESH --ring N --out DIR` write:
//!
//! ```text
//! DIR/images/NNN.png     RGBA8, alpha = coverage (0 = background); RGB straight
//! DIR/masks/NNN.png      8-bit grey: 255 where the object covers any sample of the pixel
//! DIR/transforms.json    NeRF / nerfstudio convention
//! DIR/sparse/0/cameras.txt   COLMAP text model: one PINHOLE camera
//! DIR/sparse/0/images.txt    one pose per view
//! DIR/sparse/0/points3D.txt  no points
//! ```
//!
//! Views are numbered from 000 (three digits, more if there are over a
//! thousand views), elevation by elevation in the order given, azimuths
//! `360°·i/N` within each; every view has the same intrinsics and the same
//! distance to the bounding-box centre (the box's bounding sphere fills
//! 90 % of the narrower field of view, so the whole object is in every
//! image).
//!
//! `transforms.json` keys: `camera_model` (`"PINHOLE"`), `camera_angle_x`
//! and `camera_angle_y` (full fields of view, radians), `fl_x`, `fl_y`,
//! `cx`, `cy` (pixels, the convention above), `w`, `h`, `object_bbox`
//! (`min`, `max`: the world box the ring frames, a lodkit extra), and
//! `frames`: `file_path` (`images/NNN.png`), `mask_path`
//! (`masks/NNN.png`, nerfstudio's key), `azimuth_deg`, `elevation_deg`
//! (lodkit extras) and `transform_matrix`, the 4×4 camera-to-world matrix
//! in the OpenGL frame, **row-major** (`transform_matrix[row][col]`; the
//! last column is the camera position, the last row `0 0 0 1`). Readers
//! that cast rays through pixel corners (the original NeRF code) are half
//! a pixel off; nerfstudio casts through centres, as here.
//!
//! `cameras.txt`: `1 PINHOLE W H fx fy cx cy`. `images.txt`: for view
//! `NNN` the line `ID QW QX QY QZ TX TY TZ 1 NNN.png` (`ID` = index + 1;
//! the name is relative to `images/`) followed by an empty line (no 2-D
//! points). `(QW, QX, QY, QZ)` is the Hamilton unit quaternion of the
//! world-to-camera rotation `R` in the OpenCV frame, with `QW ≥ 0`; `T =
//! −R·C` for the camera centre `C`. All numbers are written in Rust's
//! shortest round-trip form.
//!
//! **Silhouette accuracy.** A mask pixel is set when the object covers any
//! of its `s × s` samples (`s` = [`RenderOptions::supersample`]). A point
//! of the surface projects inside the mask, or within one pixel of it
//! where the silhouette passes between samples; a carver that must never
//! cut the object away dilates each mask by one pixel.

#![forbid(unsafe_code)]
#![deny(missing_docs)]

mod camera;
mod camera_ring;
mod clip;
mod colour_scale;
mod image;
mod raster;
mod render;
mod shade;
mod texture;

pub use camera::{Camera, FRAMING_MARGIN, Intrinsics};
pub use camera_ring::{CameraRing, RingView};
pub use colour_scale::colour_scale;
pub use image::{Image, Mask, PNG_DEFLATE_LEVEL};
pub use render::{
    MAX_SIZE, MAX_SUPERSAMPLE, Normals, RenderOptions, render, render_points, render_textured,
};
pub use shade::{AMBIENT, DIFFUSE, FAR_POINT_BRIGHTNESS};
pub use texture::{Look, Materials, TextureImage, Wrap};

/// What can go wrong when rendering.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum RenderError {
    /// An option is out of range (the message names it and the range).
    #[error("{0}")]
    Options(String),
    /// A camera cannot be built from the given values.
    #[error("camera: {0}")]
    Camera(String),
    /// The mesh or cloud breaks its type invariant.
    #[error("{0}")]
    Mesh(String),
    /// The PNG encoder failed.
    #[error("PNG encoding: {0}")]
    Png(String),
}
