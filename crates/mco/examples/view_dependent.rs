//! A view-dependent cut: fine where the surface is near the camera and
//! its error would show, coarse far away and outside the view, crack-free
//! between the two.
//!
//! ```text
//! cargo run --release -p lodkit-mco --example view_dependent
//! ```

use lodkit_mco::{Camera, Options, build_from_mesh};
use lodkit_mesh::glam::Vec3;

fn main() -> Result<(), lodkit_mco::Error> {
    let mesh = lodkit_mesh::shapes::blob(40_000);
    let model = build_from_mesh(&mesh, &Options::default())?;
    let mut indices = Vec::new(); // reused by every cut
    for distance in [1.5, 3.0, 10.0, 50.0] {
        // 60° vertical field of view, 1080 pixels high: the defaults.
        let camera = Camera::looking_at(Vec3::new(0.0, 0.0, distance), Vec3::ZERO);
        // Nodes whose error would cover more than one pixel are refined.
        let expanded = model.extract_view(&camera, 1.0, &mut indices);
        println!(
            "camera at z = {distance:>4}: {expanded:>5} nodes expanded, {:>6} triangles",
            indices.len() / 3
        );
    }
    Ok(())
}
