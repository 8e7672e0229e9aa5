//! The pinhole camera: pose, field of view, projection, and the two matrix
//! conventions the calibration files use (see the [crate docs](crate#conventions)).

use glam::{Mat3, Mat4, Quat, Vec2, Vec3};
use lodkit_mesh::Aabb;

use crate::RenderError;

/// Extra room around the model's bounding sphere when [`Camera::orbit`]
/// frames it: the sphere fills 90 % of the narrower field of view, so a
/// silhouette never touches the image border (a carver needs the whole
/// object inside every view).
pub const FRAMING_MARGIN: f32 = 1.0 / 0.9;

/// A perspective pinhole camera with square pixels and the principal point
/// at the image centre.
///
/// `rotation` is camera-to-world in the OpenGL/Blender camera frame: its
/// columns are the camera's right (+X), up (+Y) and back (+Z) axes in
/// world coordinates; the camera looks along −Z (`-rotation.z_axis`).
/// The image size is not part of the camera: [`Camera::intrinsics`] gives
/// the pinhole parameters for any size, keeping the vertical field of view.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Camera {
    /// Centre of projection, world (object) units.
    pub position: Vec3,
    /// Camera-to-world rotation (orthonormal, determinant +1), OpenGL axes.
    pub rotation: Mat3,
    /// Vertical field of view in degrees, in `(0, 180)`.
    pub fov_y_deg: f32,
}

/// Pinhole intrinsics (the type is `lodkit_mesh::Intrinsics`, shared with
/// the silhouette calibration's lens): a [`Camera`]'s for a
/// `width × height` image ([`Camera::intrinsics`]) have square pixels
/// (`fx = fy`) and the principal point at the image centre.
pub use lodkit_mesh::Intrinsics;

fn check_fov(fov_y_deg: f32) -> Result<(), RenderError> {
    if fov_y_deg.is_finite() && fov_y_deg > 0.0 && fov_y_deg < 180.0 {
        Ok(())
    } else {
        Err(RenderError::Camera(format!(
            "field of view {fov_y_deg}° is outside (0, 180)"
        )))
    }
}

impl Camera {
    /// A camera at `eye` looking at `target`, rolled so that `up` projects
    /// upwards in the image. Errors if an input is not finite, `eye ==
    /// target`, `up` is parallel to the viewing direction, or `fov_y_deg`
    /// is outside `(0, 180)`.
    pub fn look_at(
        eye: Vec3,
        target: Vec3,
        up: Vec3,
        fov_y_deg: f32,
    ) -> Result<Camera, RenderError> {
        check_fov(fov_y_deg)?;
        if !(eye.is_finite() && target.is_finite() && up.is_finite()) {
            return Err(RenderError::Camera(
                "eye, target and up must be finite".into(),
            ));
        }
        let back = (eye - target)
            .try_normalize()
            .ok_or_else(|| RenderError::Camera("eye and target coincide".into()))?;
        let right = up
            .cross(back)
            .try_normalize()
            .ok_or_else(|| RenderError::Camera("up is parallel to the viewing direction".into()))?;
        let cam_up = back.cross(right);
        Ok(Camera {
            position: eye,
            rotation: Mat3::from_cols(right, cam_up, back),
            fov_y_deg,
        })
    }

    /// A camera on a sphere around `bbox`, looking at its centre, at a
    /// distance where the box's bounding sphere fills 90 % of the narrower
    /// field of view ([`FRAMING_MARGIN`]) for images of `aspect = width /
    /// height`: every view of a ring sees the whole model, at the same
    /// distance.
    ///
    /// World +Y is up. `azimuth_deg` turns about +Y from +Z towards +X
    /// (0° looks from +Z at the front, 90° from +X); `elevation_deg` in
    /// `[-90, 90]` lifts the camera towards +Y. The camera position is
    /// `centre + d·(cos el·sin az, sin el, cos el·cos az)`; its right axis
    /// is `(cos az, 0, −sin az)`, so the image is upright for every
    /// elevation, the poles included (no degenerate up vector).
    ///
    /// Errors if the box is empty or not finite, an angle is not finite,
    /// the elevation is outside `[-90, 90]`, the aspect is not positive or
    /// `fov_y_deg` is outside `(0, 180)`. A box of zero size (one point) is
    /// framed as a sphere of radius 1.
    pub fn orbit(
        bbox: &Aabb,
        azimuth_deg: f32,
        elevation_deg: f32,
        fov_y_deg: f32,
        aspect: f32,
    ) -> Result<Camera, RenderError> {
        check_fov(fov_y_deg)?;
        if bbox.is_empty() || !bbox.min.is_finite() || !bbox.max.is_finite() {
            return Err(RenderError::Camera(
                "the model's bounding box is empty".into(),
            ));
        }
        if !azimuth_deg.is_finite() || !elevation_deg.is_finite() {
            return Err(RenderError::Camera("view angles must be finite".into()));
        }
        if !(-90.0..=90.0).contains(&elevation_deg) {
            return Err(RenderError::Camera(format!(
                "elevation {elevation_deg}° is outside [-90, 90]"
            )));
        }
        if !(aspect.is_finite() && aspect > 0.0) {
            return Err(RenderError::Camera(format!(
                "aspect {aspect} is not positive"
            )));
        }
        let (sa, ca) = azimuth_deg.to_radians().sin_cos();
        let (se, ce) = elevation_deg.to_radians().sin_cos();
        let back = Vec3::new(ce * sa, se, ce * ca);
        let right = Vec3::new(ca, 0.0, -sa);
        let up = back.cross(right);
        let half_y = (fov_y_deg.to_radians() * 0.5).tan();
        let half_min = half_y.min(half_y * aspect).atan();
        let mut radius = bbox.diagonal() * 0.5;
        if radius <= 0.0 {
            radius = 1.0;
        }
        let distance = radius * FRAMING_MARGIN / half_min.sin();
        Ok(Camera {
            position: bbox.center() + back * distance,
            rotation: Mat3::from_cols(right, up, back),
            fov_y_deg,
        })
    }

    /// A camera looking from the direction of [`Camera::orbit`] at the
    /// centre of the bounding box of `points`, at the nearest distance at
    /// which every point projects inside the central 90 % of the image
    /// ([`FRAMING_MARGIN`]): the tightest picture of one view. The distance
    /// depends on the view, so a ring uses [`Camera::orbit`] instead.
    /// Errors as [`Camera::orbit`] (no points: an empty box). Cost `O(n)`.
    pub fn frame(
        points: &[Vec3],
        azimuth_deg: f32,
        elevation_deg: f32,
        fov_y_deg: f32,
        aspect: f32,
    ) -> Result<Camera, RenderError> {
        let bbox = Aabb::from_points(points);
        let mut cam = Camera::orbit(&bbox, azimuth_deg, elevation_deg, fov_y_deg, aspect)?;
        if bbox.diagonal() <= 0.0 {
            return Ok(cam);
        }
        let c = bbox.center();
        let [right, up, back] = [
            cam.rotation.x_axis,
            cam.rotation.y_axis,
            cam.rotation.z_axis,
        ];
        let ty = (fov_y_deg.to_radians() * 0.5).tan() / FRAMING_MARGIN;
        let tx = ty * aspect;
        // A point at offset p from the centre has depth d − back·p and
        // must keep |right·p| ≤ tx·depth and |up·p| ≤ ty·depth; the nearest
        // plane stays a hundredth of the box diagonal in front of the camera.
        let mut d = bbox.diagonal() * 0.01;
        for &q in points {
            let p = q - c;
            let along = p.dot(back);
            d = d
                .max(along + p.dot(right).abs() / tx)
                .max(along + p.dot(up).abs() / ty)
                .max(along + bbox.diagonal() * 0.01);
        }
        cam.position = c + back * d;
        Ok(cam)
    }

    /// The pinhole parameters for a `width × height` image (see
    /// [`Intrinsics`]): `fy = fx = (height / 2) / tan(fov_y / 2)`.
    pub fn intrinsics(&self, width: u32, height: u32) -> Intrinsics {
        let f = (height as f64 * 0.5) / ((self.fov_y_deg as f64).to_radians() * 0.5).tan();
        Intrinsics {
            width,
            height,
            fx: f,
            fy: f,
            cx: width as f64 * 0.5,
            cy: height as f64 * 0.5,
        }
    }

    /// The direction the camera looks along (world, unit): `−rotation.z_axis`.
    pub fn forward(&self) -> Vec3 {
        -self.rotation.z_axis
    }

    /// Camera-to-world 4×4 in the OpenGL/Blender camera frame (+X right,
    /// +Y up, looking along −Z): columns right, up, back, position. This is
    /// NeRF's `transform_matrix`.
    pub fn camera_to_world_gl(&self) -> Mat4 {
        Mat4::from_cols(
            self.rotation.x_axis.extend(0.0),
            self.rotation.y_axis.extend(0.0),
            self.rotation.z_axis.extend(0.0),
            self.position.extend(1.0),
        )
    }

    /// World-to-camera rotation in the OpenCV/COLMAP camera frame (+X
    /// right, +Y down, +Z forward): rows right, −up, −back.
    pub fn world_to_camera_cv_rotation(&self) -> Mat3 {
        Mat3::from_cols(
            self.rotation.x_axis,
            -self.rotation.y_axis,
            -self.rotation.z_axis,
        )
        .transpose()
    }

    /// COLMAP's image pose: the world-to-camera rotation (OpenCV axes) as a
    /// unit quaternion with `w ≥ 0`, and the translation `t = −R·position`,
    /// so that `x_cam = R·x_world + t`.
    pub fn world_to_camera_cv(&self) -> (Quat, Vec3) {
        let r = self.world_to_camera_cv_rotation();
        let mut q = Quat::from_mat3(&r).normalize();
        if q.w < 0.0 {
            q = -q;
        }
        (q, -(r * self.position))
    }

    /// A world point in the OpenCV camera frame (`z` = depth along the
    /// viewing direction, positive in front of the camera).
    pub fn to_camera_cv(&self, p: Vec3) -> Vec3 {
        let d = p - self.position;
        Vec3::new(
            d.dot(self.rotation.x_axis),
            -d.dot(self.rotation.y_axis),
            -d.dot(self.rotation.z_axis),
        )
    }

    /// Where world point `p` lands in a `width × height` image, in the
    /// pixel coordinates of [`Intrinsics`] (pixel `(i, j)` covers
    /// `[i, i+1) × [j, j+1)`); `None` when `p` is not in front of the
    /// camera. The point may land outside the image.
    pub fn project(&self, p: Vec3, width: u32, height: u32) -> Option<Vec2> {
        let c = self.to_camera_cv(p);
        if c.z <= 0.0 {
            return None;
        }
        let k = self.intrinsics(width, height);
        Some(Vec2::new(
            (k.fx * c.x as f64 / c.z as f64 + k.cx) as f32,
            (k.fy * c.y as f64 / c.z as f64 + k.cy) as f32,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box() -> Aabb {
        Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        }
    }

    #[test]
    fn orbit_front_view_looks_down_minus_z_and_centre_projects_to_the_middle() {
        let cam = Camera::orbit(&unit_box(), 0.0, 0.0, 40.0, 1.0).unwrap();
        assert!(cam.position.x.abs() < 1e-6 && cam.position.z > 1.0);
        assert!((cam.forward() - Vec3::NEG_Z).length() < 1e-6);
        let c = cam.project(Vec3::ZERO, 200, 100).unwrap();
        assert!((c - Vec2::new(100.0, 50.0)).length() < 1e-3);
        // +Y is up in the image (smaller v), +X right (larger u).
        assert!(cam.project(Vec3::Y * 0.5, 200, 100).unwrap().y < 50.0);
        assert!(cam.project(Vec3::X * 0.5, 200, 100).unwrap().x > 100.0);
    }

    #[test]
    fn orbit_at_the_poles_is_well_defined() {
        for el in [-90.0, 90.0] {
            let cam = Camera::orbit(&unit_box(), 30.0, el, 40.0, 1.0).unwrap();
            let r = cam.rotation;
            assert!((r.determinant() - 1.0).abs() < 1e-5);
            assert!((r.transpose() * r - Mat3::IDENTITY).abs_diff_eq(Mat3::ZERO, 1e-5));
        }
        assert!(Camera::orbit(&unit_box(), 0.0, 91.0, 40.0, 1.0).is_err());
        assert!(Camera::orbit(&unit_box(), f32::NAN, 0.0, 40.0, 1.0).is_err());
        assert!(Camera::orbit(&Aabb::EMPTY, 0.0, 0.0, 40.0, 1.0).is_err());
    }

    #[test]
    fn frame_fits_the_box_corners_inside_the_view() {
        let b = Aabb {
            min: Vec3::new(-2.0, -0.5, -0.3),
            max: Vec3::new(2.0, 0.5, 0.3),
        };
        let (w, h) = (300, 200);
        let loose = Camera::orbit(&b, 20.0, 15.0, 40.0, 1.5).unwrap();
        let corners: Vec<Vec3> = (0..8)
            .map(|i| {
                Vec3::new(
                    if i & 1 == 0 { b.min.x } else { b.max.x },
                    if i & 2 == 0 { b.min.y } else { b.max.y },
                    if i & 4 == 0 { b.min.z } else { b.max.z },
                )
            })
            .collect();
        let tight = Camera::frame(&corners, 20.0, 15.0, 40.0, 1.5).unwrap();
        assert!(tight.position.distance(b.center()) < loose.position.distance(b.center()));
        let mut touches = false;
        for &p in &corners {
            let q = tight.project(p, w, h).unwrap();
            assert!(
                q.x >= 14.9 && q.x <= 285.1 && q.y >= 9.9 && q.y <= 190.1,
                "{q}"
            );
            touches |= q.x < 15.1 || q.x > 284.9 || q.y < 10.1 || q.y > 189.9;
        }
        assert!(
            touches,
            "the nearest distance: some corner is on the 90 % frame"
        );
    }

    #[test]
    fn colmap_pose_and_gl_matrix_agree() {
        let cam = Camera::orbit(&unit_box(), 37.0, 21.0, 50.0, 1.5).unwrap();
        let (q, t) = cam.world_to_camera_cv();
        let c2w = cam.camera_to_world_gl();
        let p = Vec3::new(0.3, -0.2, 0.7);
        let cv = q * p + t;
        assert!((cv - cam.to_camera_cv(p)).length() < 1e-5);
        // GL camera frame = CV frame with Y and Z negated.
        let gl = c2w.inverse().transform_point3(p);
        assert!((gl - Vec3::new(cv.x, -cv.y, -cv.z)).length() < 1e-5);
    }
}
