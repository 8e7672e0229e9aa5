//! `lodkit build [INPUT] --out DIR`: the main job.
//!
//! Today it loads the model (the built-in Stanford bunny when no input is
//! given), writes it as GLB and PLY, and writes `report.md` with `info`.
//! Each capability (discrete LOD chains, continuous LOD, progressive
//! streams) adds its outputs and its section of the report here.

use std::fmt::Write as _;
use std::path::Path;

use anyhow::{Context, Result};
use lodkit_mesh::info::model_info;
use lodkit_mesh::io::{Format, WriteOptions, encode, write_atomic};
use lodkit_mesh::{Model, TriMesh};

use crate::ui::Ui;

/// The Stanford bunny (`data/models/stanford_bunny.ply`), built in so
/// `lodkit build` works from any directory with no input.
const BUILTIN_BUNNY: &[u8] = include_bytes!("../../../../data/models/stanford_bunny.ply");
const BUILTIN_NAME: &str = "stanford_bunny";

pub fn run(ui: &Ui, input: Option<&Path>, out: &Path, json: bool) -> Result<()> {
    let (name, model) = match input {
        Some(path) => {
            let stem = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "model".into());
            (stem, super::load(ui, path)?)
        }
        None => {
            ui.status("no input given: building the built-in Stanford bunny (Stanford 3D Scanning Repository)");
            let model = lodkit_mesh::io::decode(Format::Ply, BUILTIN_BUNNY, None)
                .map_err(|e| anyhow::anyhow!("built-in bunny: {e}"))?;
            (BUILTIN_NAME.to_string(), model)
        }
    };
    let mesh: &TriMesh = match &model {
        Model::Mesh(m) => m,
        other => anyhow::bail!(
            "{name}: holds a {} with no faces; `build` needs a mesh for now",
            other.kind()
        ),
    };
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output directory", out.display()))?;

    let mut outputs: Vec<(String, usize)> = Vec::new();
    for (format, ext) in [(Format::Glb, "glb"), (Format::Ply, "ply")] {
        let file = format!("{name}.{ext}");
        let step = ui.spinner(&format!("writing {file}"));
        let bytes = encode(format, &model, WriteOptions::default())
            .map_err(|e| anyhow::anyhow!("{file}: {e}"))?;
        write_atomic(&out.join(&file), &bytes)?;
        step.finish();
        outputs.push((file, bytes.len()));
    }

    let info = model_info(&model);
    let mut report = String::new();
    writeln!(report, "# lodkit build report: {name}\n")?;
    if input.is_none() {
        writeln!(
            report,
            "Input: the built-in Stanford Bunny (Stanford 3D Scanning Repository, Stanford University \
             Computer Graphics Laboratory).\n"
        )?;
    } else {
        writeln!(
            report,
            "Input: `{}`\n",
            input.map(|p| p.display().to_string()).unwrap_or_default()
        )?;
    }
    writeln!(report, "## Input\n\n```text\n{}```\n", info.to_text())?;
    writeln!(
        report,
        "## Outputs\n\n| file | bytes | triangles |\n|---|---:|---:|"
    )?;
    for (file, bytes) in &outputs {
        writeln!(report, "| `{file}` | {bytes} | {} |", mesh.faces.len())?;
    }
    write_atomic(&out.join("report.md"), report.as_bytes())?;
    outputs.push(("report.md".into(), report.len()));

    if json {
        let list: Vec<_> = outputs
            .iter()
            .map(|(file, bytes)| serde_json::json!({ "path": out.join(file), "bytes": bytes }))
            .collect();
        return super::print_json(&serde_json::json!({ "model": name, "outputs": list }));
    }
    for (file, bytes) in &outputs {
        ui.status(format!(
            "wrote {} ({bytes} bytes)",
            out.join(file).display()
        ));
    }
    Ok(())
}
