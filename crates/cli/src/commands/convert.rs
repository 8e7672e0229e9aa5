//! `lodkit convert IN OUT`.
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::Model;
use lodkit_mesh::io::{Format, WriteOptions, write_atomic};

use super::scene::Input;
use crate::ui::{OutputArgs, Ui};

pub fn run(
    ui: &Ui,
    input: &Path,
    output: &Path,
    ascii: bool,
    weld: Option<f32>,
    merge: bool,
    out: &OutputArgs,
) -> Result<()> {
    // Welding works on one mesh: --weld merges a scene's parts.
    let keeps = !merge && weld.is_none() && super::scene::holds_scenes(output);
    let mut model = match super::scene::load_input(ui, input, keeps)? {
        Input::Model(m) => m,
        Input::Scene(scene) => {
            return write_scene(ui, out.scene(scene, output)?, output, ascii, &out.glb());
        }
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
    out.check(format, &output.display().to_string())?;
    if ascii && !matches!(format, Some(Format::Ply | Format::Stl)) {
        return Err(crate::ui::usage(format!(
            "--ascii applies to .ply and .stl outputs, not to {}",
            output.display()
        )));
    }
    let step = ui.spinner(&format!("writing {}", output.display()));
    let format_known = format.ok_or_else(|| {
        crate::ui::usage(format!("{}: unknown output extension", output.display()))
    })?;
    let bytes = out
        .encode(format_known, &model, WriteOptions { ascii })
        .map_err(|e| anyhow::anyhow!("{}: {e}", output.display()))?;
    write_atomic(output, &bytes)?;
    step.finish();
    ui.status(format!(
        "wrote {} ({})",
        output.display(),
        super::written_as(&model, format)
    ));
    Ok(())
}

/// Writes a scene (materials, parts, nodes) to .glb or .obj.
fn write_scene(
    ui: &Ui,
    scene: lodkit_mesh::Scene,
    output: &Path,
    ascii: bool,
    glb: &lodkit_mesh::io::gltf::GlbOptions,
) -> Result<()> {
    if ascii {
        return Err(crate::ui::usage(format!(
            "--ascii applies to .ply and .stl outputs, not to {}",
            output.display()
        )));
    }
    let step = ui.spinner(&format!("writing {}", output.display()));
    lodkit_mesh::io::save_scene_with(output, &scene, WriteOptions::default(), glb)?;
    step.finish();
    ui.status(format!(
        "wrote {} ({})",
        output.display(),
        super::scene::describe(&scene)
    ));
    Ok(())
}
