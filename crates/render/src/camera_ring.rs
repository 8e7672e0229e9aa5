//! Camera rings and their calibration files: NeRF's `transforms.json` and
//! a COLMAP text model, in the layout described in the [crate
//! docs](crate#camera-ring-layout).

use std::fmt::Write as _;

use lodkit_mesh::Aabb;
use serde::Serialize;

use crate::RenderError;
use crate::camera::Camera;

/// Folder of the RGBA views, relative to the ring's folder.
pub const IMAGES_DIR: &str = "images";
/// Folder of the 8-bit masks.
pub const MASKS_DIR: &str = "masks";
/// The NeRF-convention calibration file.
pub const TRANSFORMS_FILE: &str = "transforms.json";
/// Folder of the COLMAP text model (`cameras.txt`, `images.txt`,
/// `points3D.txt`), COLMAP's own `sparse/0` layout.
pub const COLMAP_DIR: &str = "sparse/0";
/// Most views in one ring (azimuths × elevations).
pub const MAX_VIEWS: usize = 10_000;

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

#[derive(Serialize)]
struct Transforms {
    camera_model: &'static str,
    camera_angle_x: f64,
    camera_angle_y: f64,
    fl_x: f64,
    fl_y: f64,
    cx: f64,
    cy: f64,
    w: u32,
    h: u32,
    object_bbox: BboxJson,
    frames: Vec<Frame>,
}

#[derive(Serialize)]
struct BboxJson {
    min: [f32; 3],
    max: [f32; 3],
}

#[derive(Serialize)]
struct Frame {
    file_path: String,
    mask_path: String,
    azimuth_deg: f32,
    elevation_deg: f32,
    transform_matrix: [[f32; 4]; 4],
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

    /// `transforms.json` (NeRF / nerfstudio convention, see the crate
    /// docs). Deterministic text.
    pub fn transforms_json(&self) -> String {
        let k = self.views[0].camera.intrinsics(self.width, self.height);
        let t = Transforms {
            camera_model: "PINHOLE",
            camera_angle_x: k.angle_x(),
            camera_angle_y: 2.0 * (k.height as f64 / (2.0 * k.fy)).atan(),
            fl_x: k.fx,
            fl_y: k.fy,
            cx: k.cx,
            cy: k.cy,
            w: k.width,
            h: k.height,
            object_bbox: BboxJson {
                min: self.bbox.min.to_array(),
                max: self.bbox.max.to_array(),
            },
            frames: (0..self.views.len())
                .map(|i| {
                    let v = &self.views[i];
                    let m = v.camera.camera_to_world_gl();
                    Frame {
                        file_path: format!("{IMAGES_DIR}/{}", self.file_name(i)),
                        mask_path: format!("{MASKS_DIR}/{}", self.file_name(i)),
                        azimuth_deg: v.azimuth_deg,
                        elevation_deg: v.elevation_deg,
                        // Row-major: transform_matrix[row][col].
                        transform_matrix: [0, 1, 2, 3]
                            .map(|r| m.row(r).to_array().map(|x| x + 0.0)),
                    }
                })
                .collect(),
        };
        let mut s = serde_json::to_string_pretty(&t).expect("plain data serialises");
        s.push('\n');
        s
    }

    /// COLMAP `cameras.txt`: one PINHOLE camera (id 1) shared by every view.
    pub fn colmap_cameras(&self) -> String {
        let k = self.views[0].camera.intrinsics(self.width, self.height);
        format!(
            "# Camera list with one line of data per camera:\n\
             #   CAMERA_ID, MODEL, WIDTH, HEIGHT, PARAMS[]\n\
             # Number of cameras: 1\n\
             1 PINHOLE {} {} {} {} {} {}\n",
            k.width, k.height, k.fx, k.fy, k.cx, k.cy
        )
    }

    /// COLMAP `images.txt`: per view `IMAGE_ID QW QX QY QZ TX TY TZ
    /// CAMERA_ID NAME` (world-to-camera, OpenCV axes; ids from 1; `NAME`
    /// relative to `images/`), then an empty line of 2-D points.
    pub fn colmap_images(&self) -> String {
        let mut s = format!(
            "# Image list with two lines of data per image:\n\
             #   IMAGE_ID, QW, QX, QY, QZ, TX, TY, TZ, CAMERA_ID, NAME\n\
             #   POINTS2D[] as (X, Y, POINT3D_ID)\n\
             # Number of images: {}, mean observations per image: 0\n",
            self.views.len()
        );
        for (i, v) in self.views.iter().enumerate() {
            let (q, t) = v.camera.world_to_camera_cv();
            // `+ 0.0` writes −0 as 0.
            let n = [q.w, q.x, q.y, q.z, t.x, t.y, t.z].map(|x| x + 0.0);
            let _ = writeln!(
                s,
                "{} {} {} {} {} {} {} {} 1 {}\n",
                i + 1,
                n[0],
                n[1],
                n[2],
                n[3],
                n[4],
                n[5],
                n[6],
                self.file_name(i)
            );
        }
        s
    }

    /// COLMAP `points3D.txt` with no points (the ring knows no features).
    pub fn colmap_points3d(&self) -> String {
        "# 3D point list with one line of data per point:\n\
         #   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n\
         # Number of points: 0, mean track length: 0\n"
            .to_string()
    }

    /// Every calibration file as (path relative to the ring's folder,
    /// contents), in a fixed order.
    pub fn calibration_files(&self) -> Vec<(String, String)> {
        vec![
            (TRANSFORMS_FILE.to_string(), self.transforms_json()),
            (format!("{COLMAP_DIR}/cameras.txt"), self.colmap_cameras()),
            (format!("{COLMAP_DIR}/images.txt"), self.colmap_images()),
            (format!("{COLMAP_DIR}/points3D.txt"), self.colmap_points3d()),
        ]
    }
}
