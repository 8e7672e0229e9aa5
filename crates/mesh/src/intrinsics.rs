//! Pinhole intrinsics: the one camera-to-pixel mapping that the renderer's
//! cameras produce (`lodkit-render`), the calibration files carry (NeRF
//! `transforms.json`, COLMAP `cameras.txt`) and the silhouette carver reads
//! (`lodkit-particles`, which adds lens distortion). It lives here, the
//! lowest crate both depend on.

/// Pinhole intrinsics for a `width × height` image, in pixels, COLMAP's
/// convention: the top-left pixel's centre is at `(0.5, 0.5)`, `u` grows
/// right and `v` down, and a camera-frame point `(x, y, z)` (OpenCV axes:
/// +X right, +Y down, +Z forward) lands at `u = fx·x/z + cx`,
/// `v = fy·y/z + cy`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// Horizontal focal length in pixels.
    pub fx: f64,
    /// Vertical focal length in pixels.
    pub fy: f64,
    /// Principal point, horizontal, in pixels.
    pub cx: f64,
    /// Principal point, vertical, in pixels.
    pub cy: f64,
}

impl Intrinsics {
    /// Horizontal field of view in radians (NeRF's `camera_angle_x`).
    pub fn angle_x(&self) -> f64 {
        2.0 * (self.width as f64 / (2.0 * self.fx)).atan()
    }
}
