//! Load two meshes and measure how far apart they are (Metro distance).
//!
//! `cargo run --release -p lodkit-mesh --example compare -- A B`
//!
//! `A` and `B` are any meshes `lodkit_mesh::io::load_mesh` reads (PLY, OBJ,
//! STL, glTF/GLB), e.g. a scan and its simplified version. Prints the
//! symmetric Hausdorff distance and the mean distance, in the meshes' units
//! and as a percentage of the bounding-box diagonal, then the full report.

use std::path::Path;
use std::process::ExitCode;

use lodkit_mesh::io::load_mesh;
use lodkit_mesh::metrics::{CompareOptions, compare};

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [a, b] = args.as_slice() else {
        eprintln!("usage: compare A B");
        return ExitCode::from(2);
    };
    let run = || -> Result<(), Box<dyn std::error::Error>> {
        let a = load_mesh(Path::new(a))?;
        let b = load_mesh(Path::new(b))?;
        let r = compare(&a, &b, &CompareOptions::default())?;
        let s = &r.symmetric;
        println!(
            "Hausdorff {:.4e} ({:.3} % of the diagonal), mean {:.4e} ({:.3} %)",
            s.max, s.max_pct, s.mean, s.mean_pct
        );
        println!("{r}");
        Ok(())
    };
    match run() {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("compare: {e}");
            ExitCode::FAILURE
        }
    }
}
