//! The discrete LOD chain of a scene, materials kept.
use std::path::Path;

use anyhow::Result;
use lodkit_mesh::Scene;
use lodkit_simplify::{Options, Target};

use crate::measure::Sampling;
use crate::output::OutputOptions;
use crate::progress::Progress;

/// The discrete LOD chain of a scene, materials kept, for `lodkit lods`
/// and `lodkit build`: each level made by
/// `lodkit_simplify::scene::scene_lod_chain` (each from the previous, face
/// budgets shared by face count, material borders kept as seams), measured
/// merged against `reference` (the merged input), written as
/// `STEM_lodN.glb` (materials and images embedded, each image scaled to
/// the level's size: [`super::level_textures`]); `STEM_lods.glb` holds
/// the input as level 0 and every non-empty level, one root node
/// `STEM_LODk` per level over that level's node tree, linked by `MSFT_lod`
/// as the one-mesh chain is (`lodkit_mesh::io::gltf::write_scene_lod_glb`;
/// screen coverages and error extras from [`super::write`]), tables
/// written once; and `lods.json`. `on_level` sees each level as it is
/// measured. Returns what the one-mesh chain returns: the levels, each
/// level merged into one mesh (for renders), and their measurements, with
/// each merged level's face materials.
#[allow(clippy::too_many_arguments)]
pub fn write_scene_chain(
    events: &Progress,
    reference: &lodkit_mesh::metrics::Reference,
    input: &str,
    stem: &str,
    out: &Path,
    scene: &Scene,
    targets: &[Target],
    opts: &Options,
    sampling: Sampling,
    output: &OutputOptions,
    on_level: &mut dyn FnMut(&crate::report::Level),
) -> Result<super::write::Chain> {
    use super::write::{level_coverages, level_extras};
    use anyhow::Context as _;
    use lodkit_mesh::io::write_atomic;
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output directory", out.display()))?;
    let step = events.spinner("simplifying");
    let chain = lodkit_simplify::scene::scene_lod_chain(scene, opts, targets)
        .map_err(|e| anyhow::anyhow!("{input}: {e}"))?;
    step.finish();
    let glb_name = format!("{stem}_lods.glb");
    let glb_path = out.join(&glb_name);
    let merged = reference.mesh();
    let diagonal = merged.bbox().diagonal() as f64;
    let level0 = output.scene(scene.clone(), &glb_path)?;
    // (lod, level, extras, error) of every level the chain GLB holds.
    let mut kept = vec![(
        0usize,
        level0,
        level_extras(0, Some((0.0, 0.0)), 0.0, diagonal),
        0.0f64,
    )];
    let mut levels = Vec::new();
    let mut meshes = Vec::new();
    let mut measured = Vec::new();
    let mut face_materials = Vec::new();
    for (i, (level, reports)) in chain.into_iter().enumerate() {
        let level = output.scene(level, &glb_path)?;
        let faces = level.face_count();
        let level = super::level_textures::scale_textures(level, faces, scene.face_count())
            .map_err(|e| anyhow::anyhow!("{input}: {e}"))?;
        let r = lodkit_simplify::scene::combined_report(&reports)
            .ok_or_else(|| anyhow::anyhow!("{input}: the scene has no meshes"))?;
        let file = format!("{stem}_lod{}.glb", i + 1);
        let merged_level = level.merged();
        face_materials.push(merged_level.face_materials);
        let level_mesh = merged_level.mesh;
        let step = events.spinner(&format!("measuring level {}", i + 1));
        let m = sampling.measure(reference, &level_mesh)?;
        step.finish();
        if level.meshes.iter().all(|m| !m.mesh.faces.is_empty()) {
            let path = out.join(&file);
            let bytes = lodkit_mesh::io::gltf::write_scene_glb_with(&level, &output.glb())
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
        levels.push(crate::report::Level {
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
        });
        on_level(levels.last().expect("just pushed"));
        meshes.push(level_mesh);
        measured.push(m);
    }
    let errors: Vec<f64> = kept.iter().map(|k| k.3).collect();
    // One table of materials and images for the chain GLB: each level
    // keeps its own (smaller) images.
    let mut scenes: Vec<Scene> = kept.iter_mut().map(|k| std::mem::take(&mut k.1)).collect();
    super::level_textures::share_tables(&mut scenes);
    let glb_levels: Vec<lodkit_mesh::io::gltf::SceneLodLevel> = kept
        .iter()
        .zip(&scenes)
        .map(|((lod, _, extras, e), level)| (lod, level, extras, e))
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
    let bytes = lodkit_mesh::io::gltf::write_scene_lod_glb(&glb_levels, &output.glb())
        .map_err(|e| anyhow::anyhow!("{}: {e}", glb_path.display()))?;
    write_atomic(&glb_path, &bytes)?;
    let lods = crate::report::Lods {
        input: input.to_string(),
        input_triangles: merged.faces.len(),
        input_vertices: merged.positions.len(),
        glb: glb_name,
        levels,
    };
    let json = serde_json::to_string_pretty(&lods)? + "\n";
    write_atomic(&out.join("lods.json"), json.as_bytes())?;
    Ok(super::write::Chain {
        lods,
        meshes,
        measured,
        face_materials: Some(face_materials),
    })
}
