//! `lodkit::input::load_input` tells every input kind apart: a mesh, a
//! point cloud, a range image, a scene, a scan set (`.conf`) and a
//! calibrated image set (`transforms.json`, COLMAP `cameras.txt`); bad
//! input of each kind is one line naming the file.
use std::path::Path;

use lodkit::Progress;
use lodkit::input::{Input, carve, load_input};
use lodkit_mesh::io::{WriteOptions, save, save_scene};
use lodkit_mesh::{Model, PointCloud, Scene, TriMesh};
use lodkit_particles::EncodeOptions;
use lodkit_particles::silhouette::{SilhouetteOptions, SilhouetteSource};
use lodkit_render::{CameraRing, RenderOptions, render};

fn load(path: &Path, keeps: bool) -> anyhow::Result<Input> {
    load_input(&Progress::silent(), path, keeps)
}

/// The error's text: one line, naming `file`.
fn one_line_naming(e: anyhow::Error, file: &Path) -> String {
    let msg = format!("{e:#}");
    assert!(!msg.contains('\n'), "not one line: {msg}");
    let name = file.file_name().unwrap().to_string_lossy();
    assert!(msg.contains(&*name), "{msg} does not name {name}");
    msg
}

fn sphere() -> TriMesh {
    lodkit_mesh::shapes::icosphere(2)
}

#[test]
fn a_mesh_and_a_point_cloud_are_models() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dir.path().join("sphere.ply");
    save(&mesh, &Model::Mesh(sphere()), WriteOptions::default()).unwrap();
    assert!(
        matches!(load(&mesh, true).unwrap(), Input::Model(Model::Mesh(m)) if m.faces.len() == sphere().faces.len())
    );
    let cloud = dir.path().join("points.xyz");
    let points = PointCloud {
        positions: sphere().positions,
        ..PointCloud::default()
    };
    save(&cloud, &Model::Points(points), WriteOptions::default()).unwrap();
    let back = load(&cloud, false).unwrap();
    assert_eq!(back.kind(), "point cloud");
    assert!(matches!(back, Input::Model(Model::Points(_))));
}

#[test]
fn a_scene_with_two_meshes_is_kept_when_the_output_holds_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("two.glb");
    let mut moved = sphere();
    for p in &mut moved.positions {
        p.x += 3.0;
    }
    let mut scene = Scene::from_mesh(sphere());
    scene.meshes.push(lodkit_mesh::SceneMesh {
        name: Some("second".into()),
        face_materials: scene.meshes[0].face_materials.clone(),
        mesh: moved,
    });
    let mut second = scene.nodes[0].clone();
    second.mesh = Some(1);
    scene.nodes.push(second);
    scene.roots.push(1);
    scene.validate().unwrap();
    save_scene(&path, &scene, WriteOptions::default()).unwrap();
    let kept = load(&path, true).unwrap();
    assert_eq!(kept.kind(), "scene");
    let Input::Scene(s) = kept else {
        unreachable!()
    };
    assert_eq!(s.meshes.len(), 2);
    assert!(matches!(
        load(&path, false).unwrap(),
        Input::Model(Model::Mesh(_))
    ));
}

#[test]
fn a_conf_is_a_scan_set_of_posed_range_images_and_a_scan_alone_a_range_image() {
    let dir = tempfile::tempdir().unwrap();
    let opts = lodkit_mco::ScanOptions {
        views: 3,
        width: 24,
        height: 24,
        ..lodkit_mco::ScanOptions::DEFAULT
    };
    let scans = lodkit_mco::scan_mesh(&sphere(), &opts).unwrap();
    let paths = lodkit_mco::write_scans(dir.path(), "sphere", &scans).unwrap();
    let conf = paths.last().unwrap();
    let Input::Scans(set) = load(conf, true).unwrap() else {
        panic!("a .conf is a scan set")
    };
    assert_eq!(&set.conf, conf);
    assert_eq!(set.scans.len(), 3);
    for ((path, range), written) in set.scans.iter().zip(&paths) {
        assert_eq!(path, written);
        assert!(range.valid_count() > 0);
    }
    assert_eq!(set.scans[1].1.pose, scans[1].pose);
    assert_eq!(load(&paths[0], false).unwrap().kind(), "range image");
}

#[test]
fn a_bad_scan_set_is_one_line_naming_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let conf = dir.path().join("bad.conf");
    std::fs::write(&conf, "bmesh ../outside.ply 0 0 0 0 0 0 1\n").unwrap();
    let msg = one_line_naming(load(&conf, false).err().unwrap(), &conf);
    assert!(msg.contains("outside.ply"), "{msg}");
    let missing = dir.path().join("missing.conf");
    one_line_naming(load(&missing, false).err().unwrap(), &missing);
}

/// Renders a small camera ring of a sphere into `dir` (images, masks and
/// both calibrations).
fn write_ring(dir: &Path) {
    let mesh = sphere();
    let size = 32;
    let ring = CameraRing::new(&mesh.bbox(), 4, &[-30.0, 30.0], 35.0, size, size).unwrap();
    let opts = RenderOptions {
        width: size,
        height: size,
        ..RenderOptions::DEFAULT
    };
    for sub in ["images", "masks", "sparse/0"] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    for (i, v) in ring.views.iter().enumerate() {
        let img = render(&mesh, &v.camera, &opts).unwrap();
        let name = ring.file_name(i);
        std::fs::write(dir.join("images").join(&name), img.to_png().unwrap()).unwrap();
        std::fs::write(dir.join("masks").join(&name), img.mask().to_png().unwrap()).unwrap();
    }
    for (p, text) in ring.calibration_files() {
        std::fs::write(dir.join(p), text).unwrap();
    }
}

#[test]
fn a_calibration_is_a_calibrated_image_set_and_carves() {
    let dir = tempfile::tempdir().unwrap();
    write_ring(dir.path());
    for file in [
        "transforms.json",
        "sparse/0/cameras.txt",
        "sparse/0/images.txt",
    ] {
        let input = load(&dir.path().join(file), true).unwrap();
        assert_eq!(input.kind(), "calibrated image set", "{file}");
        let Input::Silhouettes(cal) = input else {
            unreachable!()
        };
        assert_eq!(cal.views.len(), 8, "{file}");
    }
    let Input::Silhouettes(cal) = load(&dir.path().join("transforms.json"), false).unwrap() else {
        unreachable!()
    };
    let opts = EncodeOptions {
        depth: Some(4),
        ..EncodeOptions::DEFAULT
    };
    let carved = carve(
        &Progress::silent(),
        cal,
        SilhouetteSource::Auto,
        &SilhouetteOptions::DEFAULT,
        &opts,
    )
    .unwrap();
    assert!(!carved.particles().positions.is_empty());
}

#[test]
fn a_bad_calibration_is_one_line_naming_its_file() {
    let dir = tempfile::tempdir().unwrap();
    let json = dir.path().join("transforms.json");
    std::fs::write(&json, "{\"frames\": [ {\"file_path\": 3} ]").unwrap();
    one_line_naming(load(&json, false).err().unwrap(), &json);
    write_ring(dir.path());
    std::fs::remove_file(dir.path().join("images/000.png")).unwrap();
    let Input::Silhouettes(cal) = load(&json, false).unwrap() else {
        unreachable!()
    };
    let e = carve(
        &Progress::silent(),
        cal,
        SilhouetteSource::Auto,
        &SilhouetteOptions::DEFAULT,
        &EncodeOptions::DEFAULT,
    )
    .err()
    .unwrap();
    let msg = one_line_naming(e, &json);
    assert!(msg.contains("000.png"), "{msg}");
}
