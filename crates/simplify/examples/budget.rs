//! Simplify a mesh to a triangle budget and save it.
//!
//! `cargo run --release -p lodkit-simplify --example budget -- IN OUT TRIANGLES`
//!
//! `IN` is any format `lodkit_mesh::io::load_mesh` reads (PLY, OBJ, STL,
//! glTF/GLB), `OUT` any it writes (by extension). Prints what the
//! simplifier did and why it stopped, e.g.
//! `69451 -> 1000 triangles in 8 passes, estimated error 6.6e-3 (reached the target)`
//! for `data/models/stanford_bunny.ply` at 1000.

use std::path::Path;
use std::process::ExitCode;

use lodkit_mesh::io::{WriteOptions, load_mesh, save_mesh};
use lodkit_simplify::{Options, simplify};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [input, output, budget] = args.as_slice() else {
        eprintln!("usage: budget IN OUT TRIANGLES");
        return ExitCode::from(2);
    };
    let Ok(budget) = budget.parse::<usize>() else {
        eprintln!("budget: TRIANGLES must be a whole number, got '{budget}'");
        return ExitCode::from(2);
    };
    let run = || -> Result<String, Box<dyn std::error::Error>> {
        let mesh = load_mesh(Path::new(input))?;
        let lod = simplify(&mesh, &Options::faces(budget))?;
        save_mesh(Path::new(output), &lod.mesh, WriteOptions::default())?;
        let r = &lod.report;
        Ok(format!(
            "{} -> {} triangles in {} passes, estimated error {:.1e} ({})",
            mesh.faces.len(),
            r.triangles,
            r.passes,
            r.estimated_error,
            r.stop
        ))
    };
    match run() {
        Ok(line) => {
            println!("{line}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("budget: {e}");
            ExitCode::FAILURE
        }
    }
}
