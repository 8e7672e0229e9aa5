//! One file per subcommand.
pub mod bench;
pub mod bench_mco;
pub mod build;
pub mod compare;
pub mod convert;
pub mod info;
pub mod lods;
pub mod mco;
pub mod pop;
pub mod render;
pub mod scan;
pub mod serve;
pub mod simplify;

use std::path::Path;

use anyhow::Result;
use lodkit_mesh::Model;

use crate::ui::Ui;

/// The Stanford bunny (`data/models/stanford_bunny.ply`), built into the
/// binary so `lodkit build` and the benches work from any directory.
const BUILTIN_BUNNY: &[u8] = include_bytes!("../../../../data/models/stanford_bunny.ply");

/// Decodes the built-in bunny.
pub fn builtin_bunny() -> Result<lodkit_mesh::TriMesh> {
    match lodkit_mesh::io::decode(lodkit_mesh::io::Format::Ply, BUILTIN_BUNNY, None) {
        Ok(Model::Mesh(m)) => Ok(m),
        Ok(other) => anyhow::bail!("built-in bunny: holds a {}, not a mesh", other.kind()),
        Err(e) => anyhow::bail!("built-in bunny: {e}"),
    }
}

/// Loads any supported file behind a spinner.
pub fn load(ui: &Ui, path: &Path) -> Result<Model> {
    let step = ui.spinner(&format!("reading {}", path.display()));
    let model = lodkit_mesh::io::load(path)?;
    step.finish();
    Ok(model)
}

/// Loads a file that must be a triangle mesh.
pub fn load_mesh(ui: &Ui, path: &Path) -> Result<lodkit_mesh::TriMesh> {
    match load(ui, path)? {
        Model::Mesh(m) => Ok(m),
        other => anyhow::bail!(
            "{}: holds a {} with no faces, a mesh is needed",
            path.display(),
            other.kind()
        ),
    }
}

/// Pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> Result<()> {
    crate::outln!("{}", serde_json::to_string_pretty(value)?)?;
    Ok(())
}
