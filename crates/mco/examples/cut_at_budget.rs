//! Build a continuous model from a mesh once, then cut it at any triangle
//! budget: each cut is an index buffer into the model's one vertex buffer,
//! made by copying (no arithmetic on geometry), so the same buffer can be
//! refilled every frame.
//!
//! ```text
//! cargo run --release -p lodkit-mco --example cut_at_budget
//! ```

use lodkit_mco::{Options, build_from_mesh};

fn main() -> Result<(), lodkit_mco::Error> {
    let mesh = lodkit_mesh::shapes::blob(40_000);
    let model = build_from_mesh(&mesh, &Options::default())?;
    println!(
        "model: {} LOD numbers, {} triangles at full resolution",
        model.max_lod(),
        model.full_triangles()
    );
    let mut indices = Vec::new(); // reused by every cut
    for budget in [500, 2_000, 10_000, model.full_triangles()] {
        let lod = model.extract_triangles(budget, &mut indices);
        println!(
            "budget {budget:>6}: LOD {lod:>5}, {:>6} triangles",
            indices.len() / 3
        );
    }
    // A standalone mesh of the last cut (only the vertices it uses).
    let cut = model.mesh_from_indices(&indices);
    println!("standalone mesh: {} vertices", cut.positions.len());
    Ok(())
}
