//! Calibrated cameras in the two layouts people have — NeRF's
//! `transforms.json` and a COLMAP text model (`cameras.txt`,
//! `images.txt`, `points3D.txt`) — read and written in one place: the
//! renderer writes camera rings in them (`lodkit-render`), the silhouette
//! carver reads them back (`lodkit-particles`).
//!
//! - [`read`] (feature `images`: a NeRF file without an image size is
//!   completed from the first image's header): a file or folder →
//!   [`Calibration`], [`View`]s with the image (and mask) path, pinhole
//!   intrinsics with radial-tangential distortion ([`Lens`]) and the
//!   world-to-camera pose in the OpenCV frame.
//! - [`CameraFiles`]: views with one shared pinhole → the text of every
//!   calibration file ([`CameraFiles::files`]), deterministic.
//!
//! **Conventions**, shared by both sides: OpenCV camera axes (+X right,
//! +Y down, +Z forward) for COLMAP poses, OpenGL axes (+X right, +Y up,
//! looking along −Z) for NeRF's row-major camera-to-world
//! `transform_matrix`; COLMAP's pixel convention, the top-left pixel's
//! centre at `(0.5, 0.5)` (nerfstudio's too). **Layout**: a ring's folder
//! holds [`IMAGES_DIR`], [`MASKS_DIR`], [`TRANSFORMS_FILE`] and the COLMAP
//! model in [`COLMAP_DIR`]; the readers look for masks and images there.
use std::path::{Path, PathBuf};

use glam::{DMat3, DVec3};

use crate::Intrinsics;

#[cfg(feature = "images")]
mod read;
mod write;

#[cfg(feature = "images")]
pub use read::{parse_for_fuzzing, read};
pub use write::{CameraFiles, PosedView};

/// Folder of the RGBA views, relative to the ring's folder.
pub const IMAGES_DIR: &str = "images";
/// Folder of the 8-bit masks (nerfstudio's `mask_path` points there).
pub const MASKS_DIR: &str = "masks";
/// The NeRF-convention calibration file.
pub const TRANSFORMS_FILE: &str = "transforms.json";
/// Folder of the COLMAP text model (`cameras.txt`, `images.txt`,
/// `points3D.txt`), COLMAP's own `sparse/0` layout.
pub const COLMAP_DIR: &str = "sparse/0";
/// Most views one calibration may list, read or written.
pub const MAX_VIEWS: usize = 10_000;

/// Whether `path` names a calibration file by its name only
/// (`transforms.json`, `cameras.txt`, `images.txt`): what an input loader
/// takes as a calibrated image set.
pub fn is_calibration(path: &Path) -> bool {
    let name = path
        .file_name()
        .map(|n| n.to_string_lossy().to_ascii_lowercase());
    matches!(
        name.as_deref(),
        Some("transforms.json" | "cameras.txt" | "images.txt")
    )
}

/// Pinhole intrinsics ([`Intrinsics`], the renderer's type: COLMAP's
/// convention, in pixels) with OpenCV's radial (`k1`, `k2`) and
/// tangential (`p1`, `p2`) distortion. The pinhole's fields read through
/// (`lens.fx` is `lens.intrinsics.fx`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Lens {
    /// Image size, focal lengths and principal point.
    pub intrinsics: Intrinsics,
    /// Radial distortion coefficients.
    pub k1: f64,
    /// See `k1`.
    pub k2: f64,
    /// Tangential distortion coefficients.
    pub p1: f64,
    /// See `p1`.
    pub p2: f64,
}

impl std::ops::Deref for Lens {
    type Target = Intrinsics;
    fn deref(&self) -> &Intrinsics {
        &self.intrinsics
    }
}

impl Lens {
    /// Distorts normalised image coordinates `(x, y)` (OpenCV's model).
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let s = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
        (
            x * s + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x),
            y * s + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y,
        )
    }

    /// Whether any distortion coefficient is non-zero.
    pub fn distorted(&self) -> bool {
        self.k1 != 0.0 || self.k2 != 0.0 || self.p1 != 0.0 || self.p2 != 0.0
    }

    /// Largest displacement `|distort(p) − p|` (per axis) over the
    /// normalised rectangle `[x0, x1] × [y0, y1]`: a bound from the
    /// triangle inequality on each term of [`Lens::distort`].
    pub fn displacement_bound(&self, x0: f64, x1: f64, y0: f64, y1: f64) -> (f64, f64) {
        let ax = x0.abs().max(x1.abs());
        let ay = y0.abs().max(y1.abs());
        let r2 = ax * ax + ay * ay;
        let radial = self.k1.abs() * r2 + self.k2.abs() * r2 * r2;
        let dx = ax * radial + 2.0 * self.p1.abs() * ax * ay + self.p2.abs() * (r2 + 2.0 * ax * ax);
        let dy = ay * radial + self.p1.abs() * (r2 + 2.0 * ay * ay) + 2.0 * self.p2.abs() * ax * ay;
        (dx, dy)
    }
}

/// One calibrated view.
#[derive(Debug, Clone, PartialEq)]
pub struct View {
    /// How errors name the camera: `frame 3 (images/003.png)` or
    /// `image 4 (003.png)`.
    pub label: String,
    /// The image file.
    pub image: PathBuf,
    /// A separate mask image, if the calibration names one or the layout's
    /// mask folder holds one.
    pub mask: Option<PathBuf>,
    /// Intrinsics.
    pub lens: Lens,
    /// World-to-camera rotation, OpenCV axes.
    pub rotation: DMat3,
    /// World-to-camera translation: `x_cam = rotation · x + translation`.
    pub translation: DVec3,
}

impl View {
    /// Camera centre in world coordinates.
    pub fn centre(&self) -> DVec3 {
        -(self.rotation.transpose() * self.translation)
    }

    /// A world point in the camera frame (OpenCV axes; `z` = depth).
    pub fn to_camera(&self, p: DVec3) -> DVec3 {
        self.rotation * p + self.translation
    }

    /// Pixel position of a world point, or `None` behind the camera.
    pub fn project(&self, p: DVec3) -> Option<(f64, f64)> {
        let c = self.to_camera(p);
        if c.z <= 0.0 {
            return None;
        }
        let (x, y) = self.lens.distort(c.x / c.z, c.y / c.z);
        Some((
            self.lens.fx * x + self.lens.cx,
            self.lens.fy * y + self.lens.cy,
        ))
    }
}

/// Views read from one calibration file.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The file read (`transforms.json` or `cameras.txt`), for messages.
    pub file: PathBuf,
    /// The views, in the file's order.
    pub views: Vec<View>,
    /// The object box the file states (lodkit's `object_bbox` extra), if any.
    pub bbox: Option<(DVec3, DVec3)>,
}
