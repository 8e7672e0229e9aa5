//! Benchmark: each depth's cut of a tileset beside in-core simplification
//! to the same triangle count, both measured against the input.
//!
//! ```sh
//! lodkit tiles IN.ply --out T --no-skirts      # skirts would be measured too
//! cargo run --release -p lodkit-tiles --features meshopt --example level_quality -- IN.ply T
//! ```
//!
//! The cut at depth `k` is every tile of that depth and every shallower
//! leaf. Both meshes are measured with the input's index built once
//! ([`Reference::compare_level`], symmetric mean and maximum). The finest
//! depth is the input itself and is skipped. A cut that holds leaves
//! (input at full resolution beside simplified tiles) is no level of one
//! resolution: its row gives the leaves' share and no ratio, since
//! in-core simplification spreads the same count evenly. Prints a
//! Markdown table.

#[path = "../tests/common/mod.rs"]
mod common;

use std::path::Path;

use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::Reference;
use lodkit_simplify::{Options, Simplifier, Target};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().collect();
    let [_, input, dir] = args.as_slice() else {
        return Err("usage: level_quality INPUT TILESET_DIR".into());
    };
    let input = lodkit_mesh::io::load_mesh(Path::new(input))?;
    let tileset = common::read_tileset(Path::new(dir));
    let deepest = tileset.tiles.iter().map(|t| t.depth).max().unwrap_or(0);
    let reference = Reference::new(&input)?;
    let mut simplifier = Simplifier::new();
    println!(
        "| depth | cut triangles | of which leaves | tiles: mean / max | simplify: mean / max | mean ratio |"
    );
    println!("|---:|---:|---:|---|---|---:|");
    for depth in 0..deepest {
        let mut cut = TriMesh::default();
        let mut in_leaves = 0;
        for t in &tileset.tiles {
            if t.depth == depth || (t.depth < depth && t.children.is_empty()) {
                let m = t.mesh.as_ref().ok_or("a tile of the cut has no content")?;
                if t.children.is_empty() {
                    in_leaves += m.faces.len();
                }
                let base = cut.positions.len() as u32;
                cut.positions.extend_from_slice(&m.positions);
                cut.faces
                    .extend(m.faces.iter().map(|f| f.map(|v| v + base)));
            }
        }
        let opts = Options {
            target: Target::Faces(cut.faces.len()),
            ..Options::DEFAULT
        };
        let simplified = simplifier.simplify(&input, &opts)?.mesh;
        let a = reference.compare_level(&cut, None)?.symmetric;
        let b = reference.compare_level(&simplified, None)?.symmetric;
        let ratio = if in_leaves == 0 {
            format!("{:.2}", a.mean / b.mean)
        } else {
            "—".into()
        };
        println!(
            "| {depth} | {} | {in_leaves} | {:.3e} / {:.3e} | {:.3e} / {:.3e} | {ratio} |",
            cut.faces.len(),
            a.mean,
            a.max,
            b.mean,
            b.max,
        );
    }
    Ok(())
}
