//! The writers: views sharing one pinhole → NeRF `transforms.json` and
//! a COLMAP text model, in the conventions of the [module](super) and the
//! layout that [`read`](super::read) takes back.
use std::fmt::Write as _;

use serde::Serialize;

use super::{COLMAP_DIR, IMAGES_DIR, MASKS_DIR, TRANSFORMS_FILE};
use crate::{Aabb, Intrinsics};

/// One view to write: its file name and pose, in the numbers a renderer
/// keeps (`f32`, written in Rust's shortest round-trip form).
#[derive(Debug, Clone, PartialEq)]
pub struct PosedView {
    /// The image's file name inside [`IMAGES_DIR`] (its mask has the same
    /// name inside [`MASKS_DIR`]).
    pub name: String,
    /// Azimuth in degrees (a lodkit extra of `transforms.json`).
    pub azimuth_deg: f32,
    /// Elevation in degrees (a lodkit extra of `transforms.json`).
    pub elevation_deg: f32,
    /// Camera-to-world matrix, OpenGL axes, row-major
    /// (`camera_to_world_gl[row][col]`): NeRF's `transform_matrix`.
    pub camera_to_world_gl: [[f32; 4]; 4],
    /// World-to-camera rotation, OpenCV axes, as the unit quaternion
    /// `[w, x, y, z]` with `w ≥ 0` (COLMAP's `QW QX QY QZ`).
    pub rotation_cv: [f32; 4],
    /// World-to-camera translation, OpenCV axes (`T = −R·C`).
    pub translation_cv: [f32; 3],
}

/// Views all seen through one pinhole, with the object box they frame:
/// what a camera ring writes.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraFiles {
    /// The pinhole every view shares (COLMAP camera 1).
    pub intrinsics: Intrinsics,
    /// The object's box (`object_bbox`, a lodkit extra).
    pub bbox: Aabb,
    /// The views, in order (COLMAP image ids from 1).
    pub views: Vec<PosedView>,
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

impl CameraFiles {
    /// `transforms.json` (NeRF / nerfstudio convention): `camera_model`
    /// `"PINHOLE"`, the full fields of view `camera_angle_x` and
    /// `camera_angle_y` (radians), `fl_x`, `fl_y`, `cx`, `cy`, `w`, `h`,
    /// `object_bbox`, and per frame `file_path`, `mask_path`,
    /// `azimuth_deg`, `elevation_deg`, `transform_matrix`. Deterministic
    /// text (−0 written as 0).
    pub fn transforms_json(&self) -> String {
        let k = &self.intrinsics;
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
            frames: self
                .views
                .iter()
                .map(|v| Frame {
                    file_path: format!("{IMAGES_DIR}/{}", v.name),
                    mask_path: format!("{MASKS_DIR}/{}", v.name),
                    azimuth_deg: v.azimuth_deg,
                    elevation_deg: v.elevation_deg,
                    transform_matrix: v.camera_to_world_gl.map(|row| row.map(|x| x + 0.0)),
                })
                .collect(),
        };
        let mut s = serde_json::to_string_pretty(&t).expect("plain data serialises");
        s.push('\n');
        s
    }

    /// COLMAP `cameras.txt`: one PINHOLE camera (id 1) shared by every view.
    pub fn colmap_cameras(&self) -> String {
        let k = &self.intrinsics;
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
            let [qw, qx, qy, qz] = v.rotation_cv;
            let [tx, ty, tz] = v.translation_cv;
            // `+ 0.0` writes −0 as 0.
            let n = [qw, qx, qy, qz, tx, ty, tz].map(|x| x + 0.0);
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
                v.name
            );
        }
        s
    }

    /// COLMAP `points3D.txt` with no points (a ring knows no features).
    pub fn colmap_points3d(&self) -> String {
        "# 3D point list with one line of data per point:\n\
         #   POINT3D_ID, X, Y, Z, R, G, B, ERROR, TRACK[] as (IMAGE_ID, POINT2D_IDX)\n\
         # Number of points: 0, mean track length: 0\n"
            .to_string()
    }

    /// Every calibration file as (path relative to the ring's folder,
    /// contents), in a fixed order: `transforms.json`, then
    /// `sparse/0/{cameras,images,points3D}.txt`.
    pub fn files(&self) -> Vec<(String, String)> {
        vec![
            (TRANSFORMS_FILE.to_string(), self.transforms_json()),
            (format!("{COLMAP_DIR}/cameras.txt"), self.colmap_cameras()),
            (format!("{COLMAP_DIR}/images.txt"), self.colmap_images()),
            (format!("{COLMAP_DIR}/points3D.txt"), self.colmap_points3d()),
        ]
    }
}
