//! `lodkit convert IN OUT` (or `IN -o OUT`).
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::Model;
use lodkit_mesh::io::{Format, WriteOptions, write_atomic};

use super::Input;
use crate::ui::Ui;

/// The options of `convert` besides its paths and the output-format flags.
pub struct ConvertOptions {
    /// ASCII PLY/STL instead of binary.
    pub ascii: bool,
    /// Weld vertices closer than this (object units) before writing.
    pub weld: Option<f32>,
    /// Merge a scene into one mesh.
    pub merge: bool,
    /// Print what was written as JSON instead of a status line.
    pub json: bool,
}

/// What `convert --json` prints.
#[derive(serde::Serialize)]
struct Report<'a> {
    input: &'a Path,
    output: &'a Path,
    /// What the output holds: "mesh", "point cloud", "range image" or
    /// "scene".
    written: &'static str,
    vertices: usize,
    faces: usize,
    /// Faces of the input the output format cannot hold (a mesh written
    /// as points).
    faces_dropped: usize,
    bytes: u64,
}

pub fn run(
    ui: &Ui,
    input: &Path,
    output: &Path,
    opts: &ConvertOptions,
    out: &lodkit::output::OutputOptions,
) -> Result<()> {
    let ConvertOptions {
        ascii,
        weld,
        merge,
        json,
    } = *opts;
    // Welding works on one mesh: --weld merges a scene's parts.
    let keeps = !merge && weld.is_none() && super::holds_scenes(output);
    let mut model = match super::load_input(ui, input, keeps)? {
        Input::Model(m) => m,
        Input::Scene(scene) => {
            let scene = out.scene(scene, output)?;
            write_scene(ui, &scene, output, ascii, &out.glb())?;
            if json {
                return super::print_json(&Report {
                    input,
                    output,
                    written: "scene",
                    vertices: scene.meshes.iter().map(|m| m.mesh.positions.len()).sum(),
                    faces: scene.face_count(),
                    faces_dropped: 0,
                    bytes: std::fs::metadata(output).map_or(0, |m| m.len()),
                });
            }
            ui.status(format!(
                "wrote {} ({})",
                output.display(),
                super::describe(&scene)
            ));
            return Ok(());
        }
        other => anyhow::bail!(
            "{}: holds a {}; convert reads meshes, scenes, point clouds and range images",
            input.display(),
            other.kind()
        ),
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
    if json {
        let points = matches!(format, Some(Format::Xyz | Format::Pts));
        let (vertices, faces) = match &model {
            Model::Mesh(m) => (m.positions.len(), m.faces.len()),
            Model::Points(p) => (p.positions.len(), 0),
            Model::Range(r) => (r.to_point_cloud().len(), 0),
        };
        return super::print_json(&Report {
            input,
            output,
            written: if points { "point cloud" } else { model.kind() },
            vertices,
            faces: if points { 0 } else { faces },
            faces_dropped: if points { faces } else { 0 },
            bytes: bytes.len() as u64,
        });
    }
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
    scene: &lodkit_mesh::Scene,
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
    lodkit_mesh::io::save_scene_with(output, scene, WriteOptions::default(), glb)?;
    step.finish();
    Ok(())
}
