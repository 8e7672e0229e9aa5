//! What a person checks in a render: the object is where the camera says,
//! its outline is the projected shape, colours show, bytes repeat, and a
//! ring's calibration files bring every surface point into its mask.

use glam::Vec3;
use lodkit_mesh::shapes;
use lodkit_render::{Camera, CameraRing, RenderOptions, colour_scale, render, render_points};

fn opts(w: u32, h: u32, s: u32) -> RenderOptions {
    RenderOptions {
        width: w,
        height: h,
        supersample: s,
        ..RenderOptions::DEFAULT
    }
}

#[test]
fn icosphere_silhouette_is_the_projected_sphere() {
    let mesh = shapes::icosphere(5);
    let bbox = mesh.bbox();
    let centre = bbox.center();
    let radius = mesh
        .positions
        .iter()
        .map(|p| p.distance(centre))
        .fold(0.0f32, f32::max);
    for (w, h, az, el) in [(200, 160, 0.0, 0.0), (257, 199, 47.0, -33.0)] {
        let cam = Camera::orbit(&bbox, az, el, 40.0, w as f32 / h as f32).unwrap();
        let img = render(&mesh, &cam, &opts(w, h, 1)).unwrap();
        let mask = img.mask();
        // The sphere's outline: a circle of angular radius asin(r / d)
        // about the image centre (the orbit looks at the centre).
        let d = cam.position.distance(centre);
        let k = cam.intrinsics(w, h);
        let r_px = k.fy * ((radius / d).asin() as f64).tan();
        let mut wrong = 0;
        for y in 0..h {
            for x in 0..w {
                let dx = x as f64 + 0.5 - k.cx;
                let dy = y as f64 + 0.5 - k.cy;
                let rr = (dx * dx + dy * dy).sqrt();
                let set = mask.get(x as i64, y as i64);
                if (rr < r_px - 1.5 && !set) || (rr > r_px + 1.5 && set) {
                    wrong += 1;
                }
            }
        }
        assert_eq!(wrong, 0, "{w}x{h} az {az} el {el}: r = {r_px:.1} px");
        let expected = std::f64::consts::PI * r_px * r_px / (w * h) as f64;
        let got = mask.coverage();
        assert!(
            (got - expected).abs() < 0.01,
            "coverage {got} vs {expected}"
        );
        // The framing promise: the sphere fills 90 % of the narrower side.
        assert!(r_px < 0.5 * w.min(h) as f64, "r = {r_px}");
        // A sphere is the loosest case of framing by the box's sphere.
        assert!(
            got > 0.12,
            "the object should fill a good part of the view: {got}"
        );
    }
}

#[test]
fn same_input_same_bytes_and_thread_count_does_not_matter() {
    let mesh = shapes::torus(1.0, 0.35, 48, 24);
    let cam = Camera::orbit(&mesh.bbox(), 30.0, 25.0, 35.0, 1.5).unwrap();
    let o = opts(300, 200, 3);
    let a = render(&mesh, &cam, &o).unwrap().to_png().unwrap();
    let b = render(&mesh, &cam, &o).unwrap().to_png().unwrap();
    assert_eq!(a, b);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let c = pool.install(|| render(&mesh, &cam, &o).unwrap().to_png().unwrap());
    assert_eq!(a, c);
    // PNG signature and no time chunk.
    assert_eq!(&a[..8], b"\x89PNG\r\n\x1a\n");
    assert!(!a.windows(4).any(|w| w == b"tIME" || w == b"tEXt"));
}

#[test]
fn vertex_colours_show_and_can_be_turned_off() {
    let mut mesh = shapes::icosphere(3);
    // Red on the +X half, blue on the −X half.
    mesh.colors = Some(
        mesh.positions
            .iter()
            .map(|p| {
                if p.x > 0.0 {
                    [255, 0, 0, 255]
                } else {
                    [0, 0, 255, 255]
                }
            })
            .collect(),
    );
    let cam = Camera::orbit(&mesh.bbox(), 0.0, 0.0, 40.0, 1.0).unwrap();
    let img = render(&mesh, &cam, &opts(100, 100, 1)).unwrap();
    // +X is right in the front view.
    let right = img.pixel(70, 50);
    let left = img.pixel(30, 50);
    assert!(right[0] > 100 && right[2] < 30, "{right:?}");
    assert!(left[2] > 100 && left[0] < 30, "{left:?}");
    assert_eq!(right[3], 255);
    assert_eq!(img.pixel(1, 1), [255, 255, 255, 0], "background");
    let grey = render(
        &mesh,
        &cam,
        &RenderOptions {
            vertex_colours: false,
            ..opts(100, 100, 1)
        },
    )
    .unwrap();
    let p = grey.pixel(70, 50);
    assert!(p[0].abs_diff(p[2]) < 30, "base colour expected: {p:?}");
}

#[test]
fn headlight_shades_the_centre_brighter_than_the_rim() {
    let mesh = shapes::icosphere(4);
    let cam = Camera::orbit(&mesh.bbox(), 0.0, 0.0, 40.0, 1.0).unwrap();
    let o = RenderOptions {
        normals: lodkit_render::Normals::Smooth,
        ..opts(200, 200, 1)
    };
    let img = render(&mesh, &cam, &o).unwrap();
    let centre = img.pixel(100, 100)[0];
    let rim = (0..200)
        .map(|x| img.pixel(x, 100))
        .find(|p| p[3] > 0)
        .unwrap()[0];
    assert!(centre > rim + 60, "centre {centre}, rim {rim}");
}

#[test]
fn a_camera_inside_the_mesh_is_clipped_not_refused() {
    let mesh = shapes::icosphere(3);
    let cam = Camera::look_at(Vec3::ZERO, Vec3::Z, Vec3::Y, 60.0).unwrap();
    let img = render(&mesh, &cam, &opts(64, 64, 1)).unwrap();
    // Inside a closed sphere every pixel sees its wall.
    assert_eq!(img.mask().coverage(), 1.0);
}

#[test]
fn point_clouds_render_as_splats() {
    let mesh = shapes::icosphere(4);
    let cloud = lodkit_mesh::PointCloud {
        positions: mesh.positions.clone(),
        normals: Some(mesh.positions.clone()),
        colors: None,
    };
    let cam = Camera::orbit(&cloud.bbox(), 10.0, 10.0, 40.0, 1.0).unwrap();
    let img = render_points(&cloud, &cam, &opts(128, 128, 2)).unwrap();
    let cov = img.mask().coverage();
    // The discs close the surface (no see-through) and overhang its
    // outline by about their radius.
    let solid = render(&mesh, &cam, &opts(128, 128, 2))
        .unwrap()
        .mask()
        .coverage();
    assert!(
        cov > solid && cov < 1.5 * solid,
        "splats {cov}, mesh {solid}"
    );
}

#[test]
fn bad_options_and_meshes_are_errors_not_panics() {
    let mesh = shapes::icosphere(1);
    let cam = Camera::orbit(&mesh.bbox(), 0.0, 0.0, 40.0, 1.0).unwrap();
    for o in [
        opts(0, 10, 1),
        opts(10, lodkit_render::MAX_SIZE + 1, 1),
        opts(10, 10, 0),
        opts(10, 10, 5),
    ] {
        assert!(render(&mesh, &cam, &o).is_err(), "{o:?}");
    }
    let mut broken = mesh.clone();
    broken.faces.push([0, 1, 9999]);
    let e = render(&broken, &cam, &opts(10, 10, 1))
        .unwrap_err()
        .to_string();
    assert!(e.contains("9999"), "{e}");
    let empty = lodkit_mesh::TriMesh::default();
    let img = render(&empty, &cam, &opts(8, 8, 1)).unwrap();
    assert_eq!(img.mask().coverage(), 0.0);
}

#[test]
fn colour_scale_runs_from_blue_to_red() {
    let lo = colour_scale(0.0);
    let hi = colour_scale(1.0);
    assert!(lo[2] > 150 && lo[0] < 80, "{lo:?}");
    assert!(hi[0] > 150 && hi[2] < 80, "{hi:?}");
}

/// The silhouette carver's contract, checked with a reader written from
/// the crate docs only: parse `transforms.json` and the COLMAP model,
/// project every surface vertex with each, and find it in its mask
/// (within one pixel, as documented).
#[test]
fn ring_calibration_projects_every_vertex_into_its_mask() {
    let mesh = shapes::torus(1.0, 0.4, 40, 20);
    let (w, h) = (96u32, 80u32);
    let ring = CameraRing::new(&mesh.bbox(), 8, &[-40.0, 0.0, 35.0, 90.0], 45.0, w, h).unwrap();
    assert_eq!(ring.views.len(), 32);
    assert_eq!(ring.file_name(7), "007.png");
    let masks: Vec<_> = ring
        .views
        .iter()
        .map(|v| render(&mesh, &v.camera, &opts(w, h, 2)).unwrap().mask())
        .collect();

    let t: serde_json::Value =
        serde_json::from_str(&ring.camera_files().transforms_json()).unwrap();
    let fx = t["fl_x"].as_f64().unwrap();
    let fy = t["fl_y"].as_f64().unwrap();
    let cx = t["cx"].as_f64().unwrap();
    let cy = t["cy"].as_f64().unwrap();
    assert_eq!(t["w"], w);
    assert_eq!(t["h"], h);
    let ax = t["camera_angle_x"].as_f64().unwrap();
    assert!((2.0 * (w as f64 / (2.0 * fx)).atan() - ax).abs() < 1e-9);
    let frames = t["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 32);
    assert_eq!(frames[3]["file_path"], "images/003.png");
    assert_eq!(frames[3]["mask_path"], "masks/003.png");

    let cams = ring.camera_files().colmap_cameras();
    let cam_line: Vec<&str> = cams
        .lines()
        .find(|l| !l.starts_with('#'))
        .unwrap()
        .split(' ')
        .collect();
    assert_eq!(&cam_line[..4], ["1", "PINHOLE", "96", "80"]);
    let k: Vec<f64> = cam_line[4..].iter().map(|s| s.parse().unwrap()).collect();
    assert_eq!(k, [fx, fy, cx, cy]);
    let images = ring.camera_files().colmap_images();
    let poses: Vec<Vec<&str>> = images
        .lines()
        .filter(|l| !l.starts_with('#') && !l.is_empty())
        .map(|l| l.split(' ').collect())
        .collect();
    assert_eq!(poses.len(), 32);
    // Two lines per image: the pose and an empty points line.
    assert_eq!(images.lines().filter(|l| l.is_empty()).count(), 32);

    let inside = |mask: &lodkit_render::Mask, u: f64, v: f64| {
        let (i, j) = (u.floor() as i64, v.floor() as i64);
        (-1..=1).any(|dy| (-1..=1).any(|dx| mask.get(i + dx, j + dy)))
    };
    for (view, mask) in masks.iter().enumerate() {
        // NeRF: camera-to-world, OpenGL axes, row-major.
        let m: Vec<Vec<f64>> = frames[view]["transform_matrix"]
            .as_array()
            .unwrap()
            .iter()
            .map(|r| {
                r.as_array()
                    .unwrap()
                    .iter()
                    .map(|x| x.as_f64().unwrap())
                    .collect()
            })
            .collect();
        assert_eq!(m[3], [0.0, 0.0, 0.0, 1.0]);
        // COLMAP: world-to-camera quaternion and translation, OpenCV axes.
        let p = &poses[view];
        assert_eq!(p[0], (view + 1).to_string());
        assert_eq!(p[9], ring.file_name(view));
        let q: Vec<f64> = p[1..5].iter().map(|s| s.parse().unwrap()).collect();
        let tr: Vec<f64> = p[5..8].iter().map(|s| s.parse().unwrap()).collect();
        assert!(q[0] >= 0.0);
        for x in &mesh.positions {
            let x = [x.x as f64, x.y as f64, x.z as f64];
            // NeRF: solve M · [g, 1] = [x, 1] for the camera-frame point g
            // (M's rotation part is orthonormal, so its inverse is its transpose).
            let d = [x[0] - m[0][3], x[1] - m[1][3], x[2] - m[2][3]];
            let g: Vec<f64> = (0..3)
                .map(|c| (0..3).map(|r| m[r][c] * d[r]).sum())
                .collect();
            assert!(g[2] < 0.0, "in front: looks along -Z");
            let (u1, v1) = (cx + fx * g[0] / -g[2], cy - fy * g[1] / -g[2]);
            // COLMAP: x_cam = R(q) · x + t, then the pinhole.
            let (w_, qx, qy, qz) = (q[0], q[1], q[2], q[3]);
            let r = [
                [
                    1.0 - 2.0 * (qy * qy + qz * qz),
                    2.0 * (qx * qy - w_ * qz),
                    2.0 * (qx * qz + w_ * qy),
                ],
                [
                    2.0 * (qx * qy + w_ * qz),
                    1.0 - 2.0 * (qx * qx + qz * qz),
                    2.0 * (qy * qz - w_ * qx),
                ],
                [
                    2.0 * (qx * qz - w_ * qy),
                    2.0 * (qy * qz + w_ * qx),
                    1.0 - 2.0 * (qx * qx + qy * qy),
                ],
            ];
            let c: Vec<f64> = (0..3)
                .map(|i| (0..3).map(|j| r[i][j] * x[j]).sum::<f64>() + tr[i])
                .collect();
            assert!(c[2] > 0.0);
            let (u2, v2) = (fx * c[0] / c[2] + cx, fy * c[1] / c[2] + cy);
            assert!(
                (u1 - u2).abs() < 1e-3 && (v1 - v2).abs() < 1e-3,
                "the two files agree"
            );
            assert!(
                inside(mask, u1, v1),
                "view {view}: vertex {x:?} at ({u1:.2}, {v1:.2}) is outside its mask"
            );
        }
        // And the mask is not everything: the background shows.
        assert!(mask.coverage() < 0.9);
    }
}
