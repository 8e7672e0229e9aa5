//! Shape from silhouette (§8.1.1) on camera rings `lodkit-render` makes
//! of shipped shapes, written in the standard layout (images/, masks/,
//! transforms.json, sparse/0/) and read back through the reader a user's
//! photographs go through.

use std::path::{Path, PathBuf};

use glam::{DVec3, Vec3};
use lodkit_mesh::TriMesh;
use lodkit_mesh::io::cameras::{COLMAP_DIR, IMAGES_DIR, MASKS_DIR};
use lodkit_particles::silhouette::{
    ImageSet, SilhouetteOptions, SilhouetteSource, carve_octree, encode_carved, encode_silhouettes,
};
use lodkit_particles::{DecodeOptions, EncodeOptions, decode};
use lodkit_render::{CameraRing, RenderOptions, render};

/// Writes a ring of `per_ring` views at each elevation, `size` pixels.
fn write_ring(mesh: &TriMesh, dir: &Path, per_ring: u32, elevations: &[f32], size: u32) {
    let r = CameraRing::new(&mesh.bbox(), per_ring, elevations, 35.0, size, size).unwrap();
    for sub in [IMAGES_DIR, MASKS_DIR, COLMAP_DIR] {
        std::fs::create_dir_all(dir.join(sub)).unwrap();
    }
    let opts = RenderOptions {
        width: size,
        height: size,
        ..RenderOptions::DEFAULT
    };
    for (i, v) in r.views.iter().enumerate() {
        let img = render(mesh, &v.camera, &opts).unwrap();
        let name = r.file_name(i);
        std::fs::write(dir.join(IMAGES_DIR).join(&name), img.to_png().unwrap()).unwrap();
        std::fs::write(
            dir.join(MASKS_DIR).join(&name),
            img.mask().to_png().unwrap(),
        )
        .unwrap();
    }
    for (p, text) in r.calibration_files() {
        std::fs::write(dir.join(p), text).unwrap();
    }
}

/// The finest decoded level's particle positions.
fn finest_points(bytes: &[u8]) -> Vec<Vec3> {
    let d = decode(bytes, &DecodeOptions::default()).unwrap();
    d.surface(d.finest_level()).unwrap().positions
}

/// Largest distance of the visual hull of the unit sphere from it, for
/// cameras at `centres` looking at its centre, each silhouette widened by
/// `slack` radians: along each of many directions from the centre, the
/// hull (an intersection of cones, star-shaped from the centre) ends where
/// the first cone does; the ray leaves cone `c` (apex `C`, distance `D`,
/// half-angle `asin(1/D) + slack`) where its angle to the axis reaches the
/// half-angle, found by bisection.
fn sphere_hull_error(centres: &[DVec3], slack: f64) -> f64 {
    let mut worst = 0.0f64;
    let n = 4000;
    for i in 0..n {
        // Fibonacci sphere directions.
        let z = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
        let phi = i as f64 * std::f64::consts::PI * (3.0 - 5f64.sqrt());
        let s = (1.0 - z * z).sqrt();
        let u = DVec3::new(s * phi.cos(), s * phi.sin(), z);
        let mut extent = f64::INFINITY;
        for c in centres {
            let d = c.length();
            let half = (1.0 / d).asin() + slack;
            let axis = -*c / d;
            let inside = |t: f64| {
                let v = (u * t - *c).normalize();
                v.dot(axis).clamp(-1.0, 1.0).acos() <= half
            };
            let (mut lo, mut hi) = (0.0, 10.0);
            if inside(hi) {
                continue;
            }
            for _ in 0..60 {
                let m = 0.5 * (lo + hi);
                if inside(m) { lo = m } else { hi = m }
            }
            extent = extent.min(lo);
        }
        worst = worst.max(extent - 1.0);
    }
    worst
}

fn sphere() -> TriMesh {
    lodkit_mesh::shapes::icosphere(5)
}

/// Sphere colours: a smooth field of the position.
fn colour_at(p: Vec3) -> [f32; 3] {
    [
        128.0 + 100.0 * p.x,
        128.0 + 100.0 * p.y,
        128.0 + 100.0 * p.z,
    ]
}

fn coloured_sphere() -> TriMesh {
    let mut m = sphere();
    m.colors = Some(
        m.positions
            .iter()
            .map(|p| {
                let c = colour_at(*p);
                [c[0] as u8, c[1] as u8, c[2] as u8, 255]
            })
            .collect(),
    );
    m
}

const ELEVATIONS: [f32; 3] = [-45.0, 0.0, 45.0];

#[test]
fn a_carved_sphere_lies_within_the_cube_diagonal_plus_the_hull_error() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = sphere();
    let size = 128;
    write_ring(&mesh, dir.path(), 8, &ELEVATIONS, size);
    let set = ImageSet::load(&dir.path().join("transforms.json"), SilhouetteSource::Auto).unwrap();
    let depth = 6;
    let opts = EncodeOptions {
        depth: Some(depth),
        ..EncodeOptions::DEFAULT
    };
    let (e, report) = encode_silhouettes(&set, &SilhouetteOptions::DEFAULT, &opts).unwrap();
    assert_eq!(report.views, 24);
    // The hull error: the mask marks any pixel a sample of it covers
    // (up to a pixel beyond the silhouette), and the point test takes a
    // one-pixel margin: 2 pixels of slack, 3 to be safe, over the focal
    // length.
    let f = set.calibration.views[0].lens.fx;
    let centres: Vec<DVec3> = set.calibration.views.iter().map(|v| v.centre()).collect();
    let hull = sphere_hull_error(&centres, 3.0 / f);
    let frame_size = {
        let b = report.bbox;
        (0..3).map(|a| b[1][a] - b[0][a]).fold(0.0f32, f32::max) as f64
    };
    let eps = frame_size * (1.0 + 1.0 / 1024.0) / f64::from(1u32 << depth) * 3f64.sqrt();
    let pts = finest_points(&e.bytes);
    assert!(pts.len() > 500, "{} particles", pts.len());
    let (mut lo, mut hi, mut sum) = (f64::MAX, f64::MIN, 0.0);
    for p in &pts {
        let d = f64::from(p.length()) - 1.0;
        lo = lo.min(d);
        hi = hi.max(d);
        sum += d.abs();
    }
    eprintln!(
        "sphere, 24 views of {size}²: R = {depth}, {} particles, distance to the sphere in [{lo:.4}, {hi:.4}], mean |d| {:.4}; ε_R = {eps:.4}, hull error {hull:.4}",
        pts.len(),
        sum / pts.len() as f64
    );
    // The icosphere's faces sit inside the unit sphere by up to 0.0005.
    assert!(
        lo >= -eps - 1e-3,
        "a particle {lo} inside the sphere (ε_R {eps})"
    );
    assert!(
        hi <= eps + hull,
        "a particle {hi} outside (ε_R {eps} + hull {hull})"
    );
}

#[test]
fn particle_colours_match_the_mesh_colour_at_the_nearest_surface_point() {
    let dir = tempfile::tempdir().unwrap();
    write_ring(&coloured_sphere(), dir.path(), 8, &ELEVATIONS, 128);
    let set = ImageSet::load(&dir.path().join("transforms.json"), SilhouetteSource::Auto).unwrap();
    let opts = EncodeOptions {
        depth: Some(6),
        ..EncodeOptions::DEFAULT
    };
    let c = carve_octree(&set, &SilhouetteOptions::DEFAULT, &opts).unwrap();
    let pc = c.particles();
    let cols = pc.colors.as_ref().unwrap();
    let mut err = 0.0f64;
    for (p, got) in pc.positions.iter().zip(cols) {
        // The nearest point of the sphere is along the radius.
        let want = colour_at(p.normalize());
        let e: f32 = (0..3)
            .map(|k| (f32::from(got[k]) - want[k].clamp(0.0, 255.0)).abs())
            .sum::<f32>()
            / 3.0;
        err += f64::from(e);
    }
    let mean = err / pc.positions.len() as f64;
    eprintln!(
        "mean per-particle colour error: {mean:.2} of 255 per channel over {} particles",
        pc.positions.len()
    );
    // The renderer shades with a headlight (ambient 0.22 + 0.78 cos): the
    // best-aligned views of 24 see a point within about 25° (cos ≥ 0.9,
    // ≤ 8 % darker, about 10 units on these colours), plus pixel blur.
    assert!(mean < 16.0, "mean colour error {mean:.2}");
}

#[test]
fn colmap_and_nerf_layouts_of_a_ring_read_the_same_cameras() {
    let dir = tempfile::tempdir().unwrap();
    write_ring(&sphere(), dir.path(), 6, &[20.0], 64);
    let a = ImageSet::load(&dir.path().join("transforms.json"), SilhouetteSource::Auto).unwrap();
    let b = ImageSet::load(
        &dir.path().join("sparse/0/cameras.txt"),
        SilhouetteSource::Auto,
    )
    .unwrap();
    assert_eq!(a.calibration.views.len(), b.calibration.views.len());
    for (u, v) in a.calibration.views.iter().zip(&b.calibration.views) {
        assert!(
            v.mask.is_some(),
            "{}: the COLMAP layout's masks/ folder",
            v.label
        );
        for p in [DVec3::ZERO, DVec3::new(0.5, -0.3, 0.2)] {
            let (x, y) = u.project(p).unwrap();
            let (s, t) = v.project(p).unwrap();
            assert!(
                (x - s).abs() < 1e-3 && (y - t).abs() < 1e-3,
                "{} vs {}",
                u.label,
                v.label
            );
        }
    }
    // Alpha and mask silhouettes of a render agree.
    let c = ImageSet::load(&dir.path().join("transforms.json"), SilhouetteSource::Alpha).unwrap();
    for i in 0..a.calibration.views.len() {
        assert_eq!(a.images[i].silhouette, c.images[i].silhouette);
    }
    // The same input twice: the same bytes.
    let opts = EncodeOptions {
        depth: Some(5),
        ..EncodeOptions::DEFAULT
    };
    let (e1, _) = encode_silhouettes(&a, &SilhouetteOptions::DEFAULT, &opts).unwrap();
    let c2 = carve_octree(&a, &SilhouetteOptions::DEFAULT, &opts).unwrap();
    assert_eq!(e1.bytes, encode_carved(&c2, &opts).unwrap().bytes);
}

#[test]
fn a_colour_key_gives_the_masks_silhouette_on_an_opaque_render() {
    let dir = tempfile::tempdir().unwrap();
    write_ring(&sphere(), dir.path(), 4, &[20.0], 64);
    // Flatten the images onto a green background, drop the masks.
    let json = dir.path().join("transforms.json");
    let text = std::fs::read_to_string(&json).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for f in v["frames"].as_array_mut().unwrap() {
        let p = dir.path().join(f["file_path"].as_str().unwrap());
        f.as_object_mut().unwrap().remove("mask_path");
        let img = decode_png_rgba(&p);
        std::fs::write(&p, img.over([0, 255, 0]).to_png().unwrap()).unwrap();
    }
    std::fs::write(&json, serde_json::to_string(&v).unwrap()).unwrap();
    let keyed = ImageSet::load(
        &json,
        SilhouetteSource::Key {
            colour: [0, 255, 0],
            tolerance: 8,
        },
    )
    .unwrap();
    for img in &keyed.images {
        assert!(img.silhouette.iter().any(|&s| s));
    }
    // Without a key the opaque images have no silhouette source.
    let e = ImageSet::load(&json, SilhouetteSource::Auto)
        .err()
        .unwrap()
        .to_string();
    assert!(
        e.contains("transforms.json") && e.contains("frame 0") && e.contains("--key-colour"),
        "{e}"
    );
}

fn decode_png_rgba(p: &Path) -> lodkit_render::Image {
    let d = png::Decoder::new(std::io::Cursor::new(std::fs::read(p).unwrap()));
    let mut r = d.read_info().unwrap();
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let info = r.next_frame(&mut buf).unwrap();
    assert_eq!(info.color_type, png::ColorType::Rgba);
    lodkit_render::Image {
        width: info.width,
        height: info.height,
        pixels: buf,
    }
}

/// Rewrites `transforms.json` of a ring with `edit`, returns its path.
fn edited_ring(dir: &Path, edit: impl Fn(&mut serde_json::Value)) -> PathBuf {
    write_ring(&sphere(), dir, 4, &[20.0], 32);
    let json = dir.join("transforms.json");
    let mut v: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&json).unwrap()).unwrap();
    edit(&mut v);
    std::fs::write(&json, serde_json::to_string(&v).unwrap()).unwrap();
    json
}

fn carve_error(json: &Path) -> String {
    let set = match ImageSet::load(json, SilhouetteSource::Auto) {
        Ok(s) => s,
        Err(e) => return e.to_string(),
    };
    match carve_octree(
        &set,
        &SilhouetteOptions::DEFAULT,
        &EncodeOptions {
            depth: Some(4),
            ..EncodeOptions::DEFAULT
        },
    ) {
        Ok(_) => panic!("{} carved", json.display()),
        Err(e) => e.to_string(),
    }
}

#[test]
fn bad_calibrations_are_one_line_errors_naming_the_file_and_the_camera() {
    // Every camera turned round: the object lies behind all of them.
    let d = tempfile::tempdir().unwrap();
    let json = edited_ring(d.path(), |v| {
        for f in v["frames"].as_array_mut().unwrap() {
            let m = &mut f["transform_matrix"];
            for r in 0..3 {
                for c in [0, 2] {
                    let x = m[r][c].as_f64().unwrap();
                    m[r][c] = serde_json::json!(-x);
                }
            }
        }
    });
    let e = carve_error(&json);
    assert!(
        e.contains("transforms.json") && e.contains("frame 0") && e.contains("behind"),
        "{e}"
    );
    // An image missing.
    let d = tempfile::tempdir().unwrap();
    let json = edited_ring(d.path(), |v| {
        v["frames"][2]["file_path"] = "images/nothere.png".into()
    });
    let e = carve_error(&json);
    assert!(
        e.contains("frame 2 (images/nothere.png)") && e.contains("missing"),
        "{e}"
    );
    // Image sizes disagreeing with the intrinsics.
    let d = tempfile::tempdir().unwrap();
    let json = edited_ring(d.path(), |v| v["w"] = 40.into());
    let e = carve_error(&json);
    assert!(
        e.contains("frame 0") && e.contains("32x32") && e.contains("40x32"),
        "{e}"
    );
    // A path leaving the folder, percent-encoded.
    let d = tempfile::tempdir().unwrap();
    let json = edited_ring(d.path(), |v| {
        v["frames"][1]["file_path"] = "%2e%2e/x.png".into()
    });
    let e = carve_error(&json);
    assert!(e.contains("frame 1") && e.contains("'..'"), "{e}");
    assert_eq!(e.lines().count(), 1, "{e}");
}

/// The fuzz target's entries (`crates/mesh/fuzz`, `cameras`) on
/// every prefix of the malformed corpus's calibrations and a PNG: an error
/// or a count, never a panic.
#[test]
fn the_readers_survive_every_prefix_of_the_malformed_corpus() {
    use lodkit_mesh::io::cameras as calibration;
    let decode = |b: &[u8]| lodkit_mesh::image::decode_rgba(b).map(|d| (d.width, d.height));
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/malformed/calibrations");
    let mut cases: Vec<PathBuf> = std::fs::read_dir(&root)
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    cases.sort();
    for case in cases {
        let json = case.join("transforms.json");
        if json.is_file() {
            let b = std::fs::read(&json).unwrap();
            for n in 0..=b.len() {
                let _ = calibration::parse_for_fuzzing(true, &b[..n]);
            }
        } else {
            let mut b = std::fs::read(case.join("sparse/0/cameras.txt")).unwrap();
            b.push(0);
            b.extend(std::fs::read(case.join("sparse/0/images.txt")).unwrap());
            for n in 0..=b.len() {
                let _ = calibration::parse_for_fuzzing(false, &b[..n]);
            }
        }
        let png = std::fs::read(case.join("images/000.png")).unwrap();
        for n in 0..=png.len() {
            let _ = decode(&png[..n]);
        }
        assert_eq!(decode(&png).unwrap(), (8, 8));
    }
}

/// The carving's work is bounded by its inputs: a depth whose leaves are
/// far under a pixel is refused at once with the depth that fits, and a
/// depth that fits runs.
#[test]
fn a_depth_finer_than_the_images_resolve_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    write_ring(&sphere(), dir.path(), 8, &[20.0], 32);
    let set = ImageSet::load(&dir.path().join("transforms.json"), SilhouetteSource::Auto).unwrap();
    let carve = |depth: u8| {
        carve_octree(
            &set,
            &SilhouetteOptions::DEFAULT,
            &EncodeOptions {
                depth: Some(depth),
                ..EncodeOptions::DEFAULT
            },
        )
    };
    let e = carve(12)
        .err()
        .expect("depth 12 on 32-pixel views")
        .to_string();
    assert!(
        e.contains("transforms.json")
            && e.contains("depth 12 is finer")
            && e.contains("or less fits"),
        "{e}"
    );
    let fits: u8 = e
        .split("depth ")
        .nth(2)
        .and_then(|t| t.split(' ').next())
        .and_then(|t| t.parse().ok())
        .unwrap();
    assert!((6..12).contains(&fits), "{e}");
    assert!(carve(fits).is_ok());
}

/// A photograph named through a symlink that leads out of the folder —
/// the file or a folder on its way — is refused, in both layouts.
#[cfg(unix)]
#[test]
fn images_symlinked_out_of_the_folder_are_refused() {
    use std::os::unix::fs::symlink;
    let root = tempfile::tempdir().unwrap();
    let outside = root.path().join("outside");
    std::fs::create_dir(&outside).unwrap();
    let dir = root.path().join("ring");
    write_ring(&sphere(), &dir, 4, &[20.0], 32);
    let images = dir.join(IMAGES_DIR);
    let first = std::fs::read_dir(&images)
        .unwrap()
        .map(|e| e.unwrap().path())
        .min()
        .unwrap();
    std::fs::rename(&first, outside.join("x.png")).unwrap();
    symlink(outside.join("x.png"), &first).unwrap();
    for calibration in [
        dir.join("transforms.json"),
        dir.join(COLMAP_DIR).join("images.txt"),
    ] {
        let e = ImageSet::load(&calibration, SilhouetteSource::Auto)
            .err()
            .expect("a symlink out of the folder")
            .to_string();
        assert!(e.contains("symlink"), "{e}");
        assert_eq!(e.lines().count(), 1);
    }
    // The same through a folder symlink.
    std::fs::remove_file(&first).unwrap();
    std::fs::rename(outside.join("x.png"), &first).unwrap();
    let moved = root.path().join("images_elsewhere");
    std::fs::rename(&images, &moved).unwrap();
    symlink(&moved, &images).unwrap();
    for calibration in [
        dir.join("transforms.json"),
        dir.join(COLMAP_DIR).join("images.txt"),
    ] {
        let e = ImageSet::load(&calibration, SilhouetteSource::Auto)
            .err()
            .expect("a folder symlink out of the folder")
            .to_string();
        assert!(e.contains("symlink"), "{e}");
    }
}

/// Thousands of views: finding their common view is bounded by the
/// carving's work limit, refused in one line rather than run for minutes.
#[test]
fn ten_thousand_views_are_refused_by_the_work_bound() {
    let dir = tempfile::tempdir().unwrap();
    let json = edited_ring(dir.path(), |v| {
        let frames = v["frames"].as_array().unwrap().clone();
        v["frames"] = serde_json::Value::Array(
            (0..10_000)
                .map(|i| frames[i % frames.len()].clone())
                .collect(),
        );
    });
    let e = carve_error(&json);
    assert!(
        e.contains("transforms.json") && e.contains("units of work") && e.contains("10000 views"),
        "{e}"
    );
    assert_eq!(e.lines().count(), 1);
}
