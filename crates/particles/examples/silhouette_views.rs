//! The bunny carved from 12, 36 and 72 views: symmetric mean and max
//! distance of the finest decoded level (triangulated) to the true
//! surface (`lodkit_mesh::metrics::compare`), as the view count grows.
//!
//! ```text
//! cargo run --release -p lodkit-particles --features silhouettes \
//!     --example silhouette_views -- [SIZE] [DEPTH]    # default 256 8
//! ```
//!
//! Rings of three elevations (−30°, 10°, 50°), `N / 3` azimuths each,
//! rendered by `lodkit-render` into a temporary folder and read back
//! through `transforms.json`. A figure for the report, not a test.
use std::time::Instant;

use lodkit_mesh::io::cameras::{COLMAP_DIR, IMAGES_DIR, MASKS_DIR};
use lodkit_mesh::metrics::{CompareOptions, compare};
use lodkit_particles::silhouette::{
    ImageSet, SilhouetteOptions, SilhouetteSource, encode_silhouettes,
};
use lodkit_particles::{DecodeOptions, EncodeOptions, TriangulateOptions, decode};
use lodkit_render::{CameraRing, RenderOptions, render};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let size: u32 = args.get(1).and_then(|s| s.parse().ok()).unwrap_or(256);
    let depth: u8 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(8);
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/models/stanford_bunny.ply");
    let bunny = lodkit_mesh::io::load_mesh(&path).expect("the shipped bunny");
    let diag = bunny.bbox().diagonal();
    println!(
        "bunny, {size}x{size} images, R = {depth}; distances in % of the bbox diagonal ({diag:.4})"
    );
    println!("| views | particles | sym. mean | sym. max | carve+encode s |");
    println!("|---:|---:|---:|---:|---:|");
    for views in [12u32, 36, 72] {
        let dir = tempfile::tempdir().expect("temp dir");
        let r = CameraRing::new(
            &bunny.bbox(),
            views / 3,
            &[-30.0, 10.0, 50.0],
            35.0,
            size,
            size,
        )
        .expect("ring");
        for sub in [IMAGES_DIR, MASKS_DIR, COLMAP_DIR] {
            std::fs::create_dir_all(dir.path().join(sub)).expect("folders");
        }
        let opts = RenderOptions {
            width: size,
            height: size,
            ..RenderOptions::DEFAULT
        };
        for (i, v) in r.views.iter().enumerate() {
            let img = render(&bunny, &v.camera, &opts).expect("render");
            let name = r.file_name(i);
            std::fs::write(
                dir.path().join(IMAGES_DIR).join(&name),
                img.to_png().expect("png"),
            )
            .expect("write");
            std::fs::write(
                dir.path().join(MASKS_DIR).join(&name),
                img.mask().to_png().expect("png"),
            )
            .expect("write");
        }
        for (p, text) in r.calibration_files() {
            std::fs::write(dir.path().join(p), text).expect("write");
        }
        let t = Instant::now();
        let set = ImageSet::load(&dir.path().join("transforms.json"), SilhouetteSource::Auto)
            .expect("image set");
        let eo = EncodeOptions {
            depth: Some(depth),
            ..EncodeOptions::DEFAULT
        };
        let (e, rep) = encode_silhouettes(&set, &SilhouetteOptions::DEFAULT, &eo).expect("carve");
        let secs = t.elapsed().as_secs_f64();
        let d = decode(&e.bytes, &DecodeOptions::default()).expect("decode");
        let mesh = d
            .triangulate(d.finest_level(), &TriangulateOptions::DEFAULT)
            .expect("triangulate")
            .mesh;
        let c = compare(
            &bunny,
            &mesh,
            &CompareOptions {
                samples: Some(200_000),
                ..Default::default()
            },
        )
        .expect("compare");
        println!(
            "| {views} | {} | {:.3} % | {:.3} % | {secs:.2} |",
            rep.particles,
            100.0 * c.symmetric.mean / f64::from(diag),
            100.0 * c.symmetric.max / f64::from(diag),
        );
    }
}
