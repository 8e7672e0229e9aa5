//! Camera rings: views all around an object, and their calibration files
//! (NeRF's `transforms.json` and a COLMAP text model, written by
//! `lodkit_mesh::io::cameras`), in the layout described in the [crate
//! docs](crate#camera-ring-layout).

use lodkit_mesh::Aabb;
use lodkit_mesh::io::cameras::{CameraFiles, MAX_VIEWS, PosedView};

use crate::RenderError;
use crate::camera::Camera;

/// One view of a ring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RingView {
    /// Azimuth in degrees, as in [`Camera::orbit`].
    pub azimuth_deg: f32,
    /// Elevation in degrees, as in [`Camera::orbit`].
    pub elevation_deg: f32,
    /// The camera.
    pub camera: Camera,
}

/// Views all around an object, all at the same distance and field of
/// view, with the image size their calibration is written for.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraRing {
    /// The views, elevation by elevation (in the order given), azimuth
    /// `360° · i / per_ring` within each.
    pub views: Vec<RingView>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// The object's bounding box the cameras frame.
    pub bbox: Aabb,
}

impl CameraRing {
    /// `per_ring` views at each elevation of `elevations_deg`, framing
    /// `bbox` as [`Camera::orbit`] does, for `width × height` images.
    ///
    /// Errors if `per_ring` is 0, there is no elevation, the view count
    /// exceeds [`MAX_VIEWS`], the size is 0, or [`Camera::orbit`] refuses
    /// an angle, the box or the field of view.
    pub fn new(
        bbox: &Aabb,
        per_ring: u32,
        elevations_deg: &[f32],
        fov_y_deg: f32,
        width: u32,
        height: u32,
    ) -> Result<CameraRing, RenderError> {
        let total = per_ring as usize * elevations_deg.len();
        if total == 0 || total > MAX_VIEWS {
            return Err(RenderError::Options(format!(
                "{per_ring} views × {} elevations is outside 1..={MAX_VIEWS} views",
                elevations_deg.len()
            )));
        }
        if width == 0 || height == 0 {
            return Err(RenderError::Options(format!(
                "image size {width}x{height} is empty"
            )));
        }
        let aspect = width as f32 / height as f32;
        let mut views = Vec::with_capacity(total);
        for &el in elevations_deg {
            for i in 0..per_ring {
                let az = 360.0 * i as f32 / per_ring as f32;
                views.push(RingView {
                    azimuth_deg: az,
                    elevation_deg: el,
                    camera: Camera::orbit(bbox, az, el, fov_y_deg, aspect)?,
                });
            }
        }
        Ok(CameraRing {
            views,
            width,
            height,
            bbox: *bbox,
        })
    }

    /// File name of view `i` without folder: `NNN.png`, zero-padded to
    /// three digits or to the digits of the last index if more.
    pub fn file_name(&self, i: usize) -> String {
        let digits = (self.views.len().saturating_sub(1))
            .to_string()
            .len()
            .max(3);
        format!("{i:0digits$}.png")
    }

    /// The ring's calibration: every view's file name and pose through
    /// one shared pinhole, ready to write as NeRF `transforms.json` and a
    /// COLMAP text model ([`CameraFiles`], `lodkit_mesh::io::cameras`,
    /// whose reader takes them back).
    pub fn camera_files(&self) -> CameraFiles {
        CameraFiles {
            intrinsics: self.views[0].camera.intrinsics(self.width, self.height),
            bbox: self.bbox,
            views: self
                .views
                .iter()
                .enumerate()
                .map(|(i, v)| {
                    let m = v.camera.camera_to_world_gl();
                    let (q, t) = v.camera.world_to_camera_cv();
                    PosedView {
                        name: self.file_name(i),
                        azimuth_deg: v.azimuth_deg,
                        elevation_deg: v.elevation_deg,
                        // Row-major: [row][col].
                        camera_to_world_gl: [0, 1, 2, 3].map(|r| m.row(r).to_array()),
                        rotation_cv: [q.w, q.x, q.y, q.z],
                        translation_cv: t.to_array(),
                    }
                })
                .collect(),
        }
    }

    /// Every calibration file as (path relative to the ring's folder,
    /// contents), in a fixed order ([`CameraFiles::files`]).
    pub fn calibration_files(&self) -> Vec<(String, String)> {
        self.camera_files().files()
    }
}
