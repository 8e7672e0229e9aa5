//! `io::cameras`: what `CameraFiles` writes (NeRF `transforms.json` and a
//! COLMAP text model) reads back through `cameras::read` as the same
//! views: intrinsics, poses, image and mask paths.
#![cfg(feature = "images")]

use glam::{DVec3, Mat3, Quat, Vec3};
use lodkit_mesh::Aabb;
use lodkit_mesh::Intrinsics;
use lodkit_mesh::io::cameras::{
    self, COLMAP_DIR, CameraFiles, IMAGES_DIR, MASKS_DIR, PosedView, TRANSFORMS_FILE,
};

/// A view at `centre` looking at the origin with +Y up, in the numbers a
/// renderer keeps.
fn view(name: &str, centre: Vec3) -> PosedView {
    let back = centre.normalize();
    let right = Vec3::Y.cross(back).normalize();
    let up = back.cross(right);
    // OpenCV world-to-camera: rows right, −up, −back.
    let r = Mat3::from_cols(right, -up, -back).transpose();
    let mut q = Quat::from_mat3(&r).normalize();
    if q.w < 0.0 {
        q = -q;
    }
    let t = -(r * centre);
    let gl = [
        [right.x, up.x, back.x, centre.x],
        [right.y, up.y, back.y, centre.y],
        [right.z, up.z, back.z, centre.z],
        [0.0, 0.0, 0.0, 1.0],
    ];
    PosedView {
        name: name.into(),
        azimuth_deg: 0.0,
        elevation_deg: 0.0,
        camera_to_world_gl: gl,
        rotation_cv: [q.w, q.x, q.y, q.z],
        translation_cv: t.to_array(),
    }
}

fn files() -> CameraFiles {
    CameraFiles {
        intrinsics: Intrinsics {
            width: 64,
            height: 48,
            fx: 70.0,
            fy: 70.0,
            cx: 32.0,
            cy: 24.0,
        },
        bbox: Aabb {
            min: Vec3::splat(-1.0),
            max: Vec3::splat(1.0),
        },
        views: vec![
            view("000.png", Vec3::new(0.0, 0.5, 4.0)),
            view("001.png", Vec3::new(4.0, -1.0, 0.5)),
            view("002.png", Vec3::new(-2.0, 3.0, -3.0)),
        ],
    }
}

fn write(dir: &std::path::Path, f: &CameraFiles) {
    for sub in [IMAGES_DIR, MASKS_DIR, COLMAP_DIR] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    for (path, text) in f.files() {
        std::fs::write(dir.join(path), text).unwrap();
    }
}

#[test]
fn both_layouts_read_back_as_the_views_written() {
    let dir = tempfile::tempdir().unwrap();
    let f = files();
    write(dir.path(), &f);
    for file in [
        TRANSFORMS_FILE.to_string(),
        format!("{COLMAP_DIR}/cameras.txt"),
    ] {
        let path = dir.path().join(&file);
        assert!(cameras::is_calibration(&path), "{file}");
        let cal = cameras::read(&path).unwrap();
        assert_eq!(cal.views.len(), f.views.len(), "{file}");
        let k = &cal.views[0].lens.intrinsics;
        assert_eq!(
            (k.width, k.height, k.fx, k.fy, k.cx, k.cy),
            (64, 48, 70.0, 70.0, 32.0, 24.0),
            "{file}"
        );
        for (read, written) in cal.views.iter().zip(&f.views) {
            assert!(!read.lens.distorted());
            assert!(
                read.image
                    .ends_with(format!("{IMAGES_DIR}/{}", written.name)),
                "{file}: {:?}",
                read.image
            );
            // NeRF names the mask; COLMAP finds it in the layout's mask folder.
            let mask = dir.path().join(MASKS_DIR).join(&written.name);
            if file == TRANSFORMS_FILE {
                assert!(
                    read.mask
                        .as_ref()
                        .unwrap()
                        .ends_with(format!("{MASKS_DIR}/{}", written.name))
                );
            } else {
                assert!(read.mask.is_none() || read.mask.as_deref() == Some(mask.as_path()));
            }
            let c = written.camera_to_world_gl;
            let centre = DVec3::new(c[0][3] as f64, c[1][3] as f64, c[2][3] as f64);
            assert!(
                read.centre().distance(centre) < 1e-5,
                "{file}: {} vs {centre}",
                read.centre()
            );
            // The origin is straight ahead of every camera, at its distance.
            let ahead = read.to_camera(DVec3::ZERO);
            assert!(
                ahead.x.abs() < 1e-5 && ahead.y.abs() < 1e-5,
                "{file}: {ahead}"
            );
            assert!((ahead.z - centre.length()).abs() < 1e-5, "{file}: {ahead}");
            let (u, v) = read.project(DVec3::ZERO).unwrap();
            assert!((u - 32.0).abs() < 1e-4 && (v - 24.0).abs() < 1e-4);
        }
        let bbox = cal.bbox;
        if file == TRANSFORMS_FILE {
            assert_eq!(bbox, Some((DVec3::splat(-1.0), DVec3::splat(1.0))));
        }
    }
}

#[test]
fn the_writer_is_deterministic_and_writes_no_negative_zero() {
    let a = files().files();
    assert_eq!(a, files().files());
    assert_eq!(
        a.iter().map(|(p, _)| p.as_str()).collect::<Vec<_>>(),
        [
            "transforms.json",
            "sparse/0/cameras.txt",
            "sparse/0/images.txt",
            "sparse/0/points3D.txt"
        ]
    );
    for (path, text) in &a {
        assert!(
            !text.contains("-0 ") && !text.contains("-0,") && !text.contains("-0.0,"),
            "{path}"
        );
    }
}

#[test]
fn a_bad_calibration_is_one_line_naming_the_file_and_camera() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), &files());
    let images = dir.path().join(COLMAP_DIR).join("images.txt");
    let text = std::fs::read_to_string(&images).unwrap();
    std::fs::write(&images, text.replace("1 000.png", "1 ../../../outside.png")).unwrap();
    let e = cameras::read(&dir.path().join(COLMAP_DIR).join("cameras.txt"))
        .unwrap_err()
        .to_string();
    assert!(!e.contains('\n'), "{e}");
    assert!(e.contains("images.txt") && e.contains("image 1"), "{e}");
}
