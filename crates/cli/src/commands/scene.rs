//! Inputs that may be scenes (meshes with materials, parts and nodes), for
//! `convert`, `simplify`, `lods` and `build`.
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::io::Format;
use lodkit_mesh::{Model, Scene};
use lodkit_simplify::{Options, Target};

use crate::ui::Ui;

/// What an input became: a scene to keep (materials, several meshes,
/// nodes), or a plain model for the one-mesh path.
pub enum Input {
    /// Materials, several parts or named / transformed nodes to keep.
    Scene(Scene),
    /// Everything else: the model exactly as `lodkit_mesh::io::load` reads it.
    Model(Model),
}

/// Whether `output`'s format holds scenes (.glb, .obj).
pub fn holds_scenes(output: &Path) -> bool {
    matches!(Format::from_path(output), Some(Format::Glb | Format::Obj))
}

/// Loads `input`: as a [`Scene`] when `keeps` (the output can hold one and
/// `--merge` is off) and the input has something a single mesh would
/// lose (materials, textures, several meshes, node names or transforms);
/// otherwise as a model, exactly as before. The scene's warnings (a
/// missing texture) are printed.
pub fn load_input(ui: &Ui, input: &Path, keeps: bool) -> Result<Input> {
    let fmt = Format::from_path(input);
    if !keeps
        || !matches!(
            fmt,
            Some(Format::Obj | Format::Gltf | Format::Glb | Format::Ply)
        )
    {
        return Ok(Input::Model(super::load(ui, input)?));
    }
    let scene = if fmt == Some(Format::Ply) {
        match super::load(ui, input)? {
            Model::Mesh(m) => lodkit_mesh::io::scene_io::ply_scene(input, m),
            other => return Ok(Input::Model(other)),
        }
    } else {
        // The one-mesh reader first: its checks (instancing bounded by the
        // file's size, world coordinates within ±MAX_COORDINATE after every
        // node transform) hold for the scene path too, and a scene that is
        // one plain mesh takes exactly the old path and bytes.
        let model = super::load(ui, input)?;
        let step = ui.spinner(&format!("reading {}", input.display()));
        let s = lodkit_mesh::io::load_scene(input)?;
        step.finish();
        if s.is_plain_mesh() {
            return Ok(Input::Model(model));
        }
        s
    };
    for w in &scene.warnings {
        ui.status(format!("warning: {}: {w}", input.display()));
    }
    if scene.is_plain_mesh() {
        let mut scene = scene;
        return Ok(Input::Model(Model::Mesh(scene.meshes.swap_remove(0).mesh)));
    }
    Ok(Input::Scene(scene))
}

/// A one-line summary of a scene for the `wrote` line.
pub fn describe(scene: &Scene) -> String {
    let prims: usize = scene
        .meshes
        .iter()
        .map(|m| {
            let mut ids = m.face_materials.clone();
            ids.sort_unstable();
            ids.dedup();
            ids.len()
        })
        .sum();
    let plural = |n: usize, w: &str| {
        let s = if n == 1 {
            ""
        } else if w.ends_with('h') {
            "es"
        } else {
            "s"
        };
        format!("{n} {w}{s}")
    };
    format!(
        "scene: {}, {}, {}, {}, {}",
        plural(scene.meshes.len(), "mesh"),
        plural(prims, "primitive"),
        plural(scene.face_count(), "triangle"),
        plural(scene.materials.len(), "material"),
        plural(scene.images.len(), "image")
    )
}

/// `lodkit lods` on a scene: each level made by
/// `lodkit_simplify::scene::scene_lod_chain`, written as `STEM_lodN.glb`
/// (materials and images embedded), measured against the merged input,
/// and `lods.json`; `STEM_lods.glb` holds the input as level 0 and every
/// non-empty level, one root node `STEM_LODk` per level over that level's
/// node tree, linked by `MSFT_lod` as the one-mesh chain is
/// (`lodkit_mesh::io::gltf::write_scene_lod_glb`; screen coverages and
/// error extras from `build::lod_chain`), tables written once.
pub fn run_lods(
    ui: &Ui,
    a: &super::lods::LodsArgs,
    scene: &Scene,
    targets: &[Target],
    opts: &Options,
) -> Result<()> {
    use anyhow::Context as _;
    use lodkit_mesh::io::write_atomic;
    let stem = a
        .input
        .file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("mesh")
        .to_string();
    std::fs::create_dir_all(&a.out)
        .with_context(|| format!("{}: cannot create output directory", a.out.display()))?;
    let merged = scene.merged().mesh;
    let reference = lodkit_mesh::metrics::Reference::new(&merged)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    let sampling = a.samples.map_or(
        super::build::Sampling::Adaptive,
        super::build::Sampling::PerKind,
    );
    let step = ui.spinner("simplifying");
    let chain = lodkit_simplify::scene::scene_lod_chain(scene, opts, targets)
        .map_err(|e| anyhow::anyhow!("{}: {e}", a.input.display()))?;
    step.finish();
    use super::build::lod_chain::{level_coverages, level_extras};
    let glb_path = a.out.join(format!("{stem}_lods.glb"));
    let diagonal = merged.bbox().diagonal() as f64;
    let level0 = a.output.scene(scene.clone(), &glb_path)?;
    // (lod, level, extras, error) of every level the chain GLB holds.
    let mut kept = vec![(
        0usize,
        level0,
        level_extras(0, Some((0.0, 0.0)), 0.0, diagonal),
        0.0f64,
    )];
    let mut levels = Vec::new();
    for (i, (level, reports)) in chain.into_iter().enumerate() {
        let level = a.output.scene(level, &glb_path)?;
        let r = lodkit_simplify::scene::combined_report(&reports)
            .ok_or_else(|| anyhow::anyhow!("{}: the scene has no meshes", a.input.display()))?;
        let file = format!("{stem}_lod{}.glb", i + 1);
        let m = sampling.measure(&reference, &level.merged().mesh)?;
        if level.meshes.iter().all(|m| !m.mesh.faces.is_empty()) {
            let path = a.out.join(&file);
            let bytes = lodkit_mesh::io::gltf::write_scene_glb_with(&level, &a.output.glb())
                .map_err(|e| anyhow::anyhow!("{}: {e}", path.display()))?;
            write_atomic(&path, &bytes)?;
            let est = r.estimated_error as f64;
            let measured = m.map(|x| (x.mean, x.max));
            let error = measured.map_or(est, |(_, max)| max);
            kept.push((
                i + 1,
                level,
                level_extras(i + 1, measured, est, diagonal),
                error,
            ));
        }
        let l = super::lods::Level {
            level: i + 1,
            file,
            target_triangles: r.target_faces,
            triangles: r.triangles,
            vertices: r.vertices,
            estimated_error: r.estimated_error,
            measured_mean_error: m.map_or(f64::NAN, |m| m.mean),
            measured_max_error: m.map_or(f64::NAN, |m| m.max),
            seconds: r.seconds,
            stop: r.stop.to_string(),
        };
        if !a.json {
            ui.status(format!(
                "level {}: {} triangles, {} vertices, error est. {:.3e} / measured mean {:.3e} max {:.3e}: {}",
                l.level, l.triangles, l.vertices, l.estimated_error, l.measured_mean_error, l.measured_max_error, l.stop
            ));
        }
        levels.push(l);
    }
    let glb_name = format!("{stem}_lods.glb");
    let errors: Vec<f64> = kept.iter().map(|k| k.3).collect();
    let glb_levels: Vec<lodkit_mesh::io::gltf::SceneLodLevel> = kept
        .iter()
        .zip(level_coverages(&errors, diagonal))
        .map(
            |((lod, level, extras, _), coverage)| lodkit_mesh::io::gltf::SceneLodLevel {
                name: format!("{stem}_LOD{lod}"),
                scene: level,
                extras: extras.clone(),
                coverage,
            },
        )
        .collect();
    let bytes = lodkit_mesh::io::gltf::write_scene_lod_glb(&glb_levels, &a.output.glb())
        .map_err(|e| anyhow::anyhow!("{}: {e}", glb_path.display()))?;
    write_atomic(&glb_path, &bytes)?;
    let report = super::lods::Lods {
        input: a.input.display().to_string(),
        input_triangles: merged.faces.len(),
        input_vertices: merged.positions.len(),
        glb: glb_name,
        levels,
    };
    let json = serde_json::to_string_pretty(&report)? + "\n";
    write_atomic(&a.out.join("lods.json"), json.as_bytes())?;
    if a.json {
        crate::out!("{json}")?;
        return Ok(());
    }
    ui.status(format!(
        "wrote {} levels, {} and lods.json to {} ({})",
        report.levels.len(),
        report.glb,
        a.out.display(),
        describe(scene)
    ));
    Ok(())
}
