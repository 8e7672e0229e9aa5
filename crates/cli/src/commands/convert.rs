//! `lodkit convert IN OUT`.
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::Model;
use lodkit_mesh::io::{Format, WriteOptions, save};

use super::scene::Input;
use crate::ui::Ui;

pub fn run(
    ui: &Ui,
    input: &Path,
    output: &Path,
    ascii: bool,
    weld: Option<f32>,
    merge: bool,
) -> Result<()> {
    // Welding works on one mesh: --weld merges a scene's parts.
    let keeps = !merge && weld.is_none() && super::scene::holds_scenes(output);
    let mut model = match super::scene::load_input(ui, input, keeps)? {
        Input::Model(m) => m,
        Input::Scene(scene) => return write_scene(ui, &scene, output, ascii),
    };
    if weld.is_some() && !matches!(model, Model::Mesh(_)) {
        return Err(crate::ui::usage(format!(
            "--weld applies to meshes; {} holds a {}",
            input.display(),
            model.kind()
        )));
    }
    if let (Some(tol), Model::Mesh(m)) = (weld, &mut model) {
        let before = m.positions.len();
        let (welded, dropped) = lodkit_mesh::weld::weld(m, tol);
        ui.status(format!(
            "welded {} vertices into {} ({} degenerate faces dropped)",
            before,
            welded.positions.len(),
            dropped
        ));
        *m = welded;
    }
    let format = Format::from_path(output);
    if ascii && !matches!(format, Some(Format::Ply | Format::Stl)) {
        return Err(crate::ui::usage(format!(
            "--ascii applies to .ply and .stl outputs, not to {}",
            output.display()
        )));
    }
    let step = ui.spinner(&format!("writing {}", output.display()));
    save(output, &model, WriteOptions { ascii })?;
    step.finish();
    ui.status(format!(
        "wrote {} ({})",
        output.display(),
        super::written_as(&model, format)
    ));
    Ok(())
}

/// Writes a scene (materials, parts, nodes) to .glb or .obj.
fn write_scene(ui: &Ui, scene: &lodkit_mesh::Scene, output: &Path, ascii: bool) -> Result<()> {
    if ascii {
        return Err(crate::ui::usage(format!(
            "--ascii applies to .ply and .stl outputs, not to {}",
            output.display()
        )));
    }
    let step = ui.spinner(&format!("writing {}", output.display()));
    lodkit_mesh::io::save_scene(output, scene, WriteOptions::default())?;
    step.finish();
    ui.status(format!(
        "wrote {} ({})",
        output.display(),
        super::scene::describe(scene)
    ));
    Ok(())
}
