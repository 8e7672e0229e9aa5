//! One file per subcommand.
pub mod bench;
pub mod bench_mco;
pub mod build;
pub mod compare;
pub mod convert;
pub mod generate;
pub mod info;
pub mod lods;
pub mod lods_out_of_core;
pub mod mco;
pub mod pop;
pub mod render;
pub mod scan;
pub mod scene;
pub mod serve;
pub mod simplify;
pub mod tiles;

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

/// Whether a path ends in `.txt`, which the readers take as XYZ.
fn is_txt(path: &Path) -> bool {
    path.extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("txt"))
}

/// Loads any supported file behind a spinner (a `.txt` is read as XYZ
/// points, and says so).
pub fn load(ui: &Ui, path: &Path) -> Result<Model> {
    if is_txt(path) {
        ui.status(format!(
            "reading {} as XYZ points (x y z [nx ny nz] per line)",
            path.display()
        ));
    }
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

/// What writing `model` as `format` keeps, in words for the `wrote` line:
/// a conversion that drops something (a mesh's faces into a point format)
/// is said, never silent.
pub fn written_as(model: &Model, format: Option<lodkit_mesh::io::Format>) -> String {
    use lodkit_mesh::io::Format;
    let points = matches!(format, Some(Format::Xyz | Format::Pts));
    match model {
        Model::Mesh(m) if points => format!(
            "{} points: the mesh's vertices; its {} faces are dropped, {} holds points only",
            m.positions.len(),
            m.faces.len(),
            format.map_or("the format", |f| f.name())
        ),
        Model::Range(r) if points => {
            format!("{} points of the range image", r.to_point_cloud().len())
        }
        other => other.kind().to_string(),
    }
}

/// Refuses (exit 2) to write a mesh result to a points-only format, where
/// its faces would be dropped.
pub fn mesh_output(path: &Path) -> Result<lodkit_mesh::io::Format> {
    use lodkit_mesh::io::Format;
    match Format::from_path(path) {
        Some(Format::Xyz | Format::Pts) => Err(crate::ui::usage(format!(
            "{}: this command writes a mesh; .xyz, .pts and .txt hold points only (use .ply, .obj, .stl or .glb)",
            path.display()
        ))),
        Some(Format::Gltf) => Err(crate::ui::usage(format!(
            "{}: meshes are written as .glb, not .gltf",
            path.display()
        ))),
        Some(f) => Ok(f),
        None => Err(crate::ui::usage(format!(
            "{}: unknown output extension (expected .ply, .obj, .stl or .glb)",
            path.display()
        ))),
    }
}

/// Pretty JSON on stdout.
pub fn print_json(value: &impl serde::Serialize) -> Result<()> {
    crate::outln!("{}", serde_json::to_string_pretty(value)?)?;
    Ok(())
}
