//! `lodkit generate blob --triangles N -o big.ply` and `lodkit generate
//! subdivided SCAN --triangles N -o big.ply`: test meshes of any size,
//! streamed to disk (never held in memory), for the out-of-core
//! simplifier and its benchmarks.
use std::path::PathBuf;

use anyhow::Result;
use clap::{Args, Subcommand};

use crate::ui::Ui;
use crate::ui::value;

/// Most triangles of a generated blob: 32-bit indices (6 n² + 2 vertices).
const MAX_TRIANGLES: u64 = 8_000_000_000;

#[derive(Subcommand, Debug)]
pub enum GenerateCmd {
    /// The noise-displaced sphere of the benchmarks, as binary PLY.
    Blob(BlobArgs),
    /// A real scan (any mesh lodkit reads) subdivided to about N
    /// triangles, new points displaced by fine noise, as binary PLY.
    Subdivided(SubdividedArgs),
}

#[derive(Args, Debug)]
pub struct SubdividedArgs {
    /// The mesh to subdivide (PLY, OBJ, STL, glTF/GLB; read in core).
    pub input: PathBuf,
    /// At least this many triangles (each input triangle split into an
    /// m × m grid), in 1..=8000000000.
    #[arg(long, value_name = "N", value_parser = value::int(1u64, MAX_TRIANGLES))]
    pub triangles: u64,
    /// Noise seed, in 0..=4294967295.
    #[arg(long, default_value_t = lodkit_mesh::shapes::DEFAULT_NOISE_SEED, value_parser = value::int(0u32, u32::MAX))]
    pub seed: u32,
    /// Output file (.ply).
    #[arg(short, long, value_parser = value::output(&["ply"], "the generated mesh"))]
    pub output: PathBuf,
}

#[derive(Args, Debug)]
pub struct BlobArgs {
    /// About this many triangles (12 n², rounded), in 12..=8000000000.
    #[arg(long, value_name = "N", value_parser = value::int(12u64, MAX_TRIANGLES))]
    pub triangles: u64,
    /// Noise seed, in 0..=4294967295.
    #[arg(long, default_value_t = lodkit_mesh::shapes::DEFAULT_NOISE_SEED, value_parser = value::int(0u32, u32::MAX))]
    pub seed: u32,
    /// Output file (.ply).
    #[arg(short, long, value_parser = value::output(&["ply"], "the generated mesh"))]
    pub output: PathBuf,
}

pub fn run(ui: &Ui, cmd: &GenerateCmd) -> Result<()> {
    let (output, write): (&PathBuf, Box<dyn Fn() -> Result<_>>) = match cmd {
        GenerateCmd::Blob(a) => (
            &a.output,
            Box::new(|| {
                Ok(lodkit_mesh::shapes::write_blob_ply(
                    &a.output,
                    a.triangles,
                    a.seed,
                )?)
            }),
        ),
        GenerateCmd::Subdivided(a) => {
            let mesh =
                lodkit_mesh::io::load_mesh(&a.input).map_err(|e| anyhow::anyhow!("{}", e))?;
            (
                &a.output,
                Box::new(move || {
                    lodkit_mesh::shapes::write_subdivided_ply(&mesh, a.triangles, a.seed, &a.output)
                        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))
                }),
            )
        }
    };
    let step = ui.spinner(&format!("writing {}", output.display()));
    let c = write()?;
    let t = step.finish();
    ui.status(format!(
        "wrote {} ({} triangles, {} vertices, {:.1} s)",
        output.display(),
        c.triangles,
        c.vertices,
        t.as_secs_f64()
    ));
    Ok(())
}
