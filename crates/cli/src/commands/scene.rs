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

/// The discrete LOD chain of a scene, materials kept, for `lodkit lods`
/// and `lodkit build`: each level made by
/// `lodkit_simplify::scene::scene_lod_chain` (each from the previous, face
/// budgets shared by face count, material borders kept as seams), measured
/// merged against `reference` (the merged input), written as
/// `STEM_lodN.glb` (materials and images embedded); `STEM_lods.glb` holds
/// the input as level 0 and every non-empty level, one root node
/// `STEM_LODk` per level over that level's node tree, linked by `MSFT_lod`
/// as the one-mesh chain is (`lodkit_mesh::io::gltf::write_scene_lod_glb`;
/// screen coverages and error extras from `build::lod_chain`), tables
/// written once; and `lods.json`. `on_level` sees each level as it is
/// measured. Returns what the one-mesh chain returns: the levels, each
/// level merged into one mesh (for renders), and their measurements, with
/// each merged level's face materials.
#[allow(clippy::too_many_arguments)]
pub fn write_scene_chain(
    ui: &Ui,
    reference: &lodkit_mesh::metrics::Reference,
    input: &str,
    stem: &str,
    out: &Path,
    scene: &Scene,
    targets: &[Target],
    opts: &Options,
    sampling: super::build::Sampling,
    output: &crate::ui::OutputArgs,
    on_level: &mut dyn FnMut(&super::lods::Level),
) -> Result<super::build::lod_chain::Chain> {
    use super::build::lod_chain::{level_coverages, level_extras};
    use anyhow::Context as _;
    use lodkit_mesh::io::write_atomic;
    std::fs::create_dir_all(out)
        .with_context(|| format!("{}: cannot create output directory", out.display()))?;
    let step = ui.spinner("simplifying");
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
        let r = lodkit_simplify::scene::combined_report(&reports)
            .ok_or_else(|| anyhow::anyhow!("{input}: the scene has no meshes"))?;
        let file = format!("{stem}_lod{}.glb", i + 1);
        let merged_level = level.merged();
        face_materials.push(merged_level.face_materials);
        let level_mesh = merged_level.mesh;
        let step = ui.spinner(&format!("measuring level {}", i + 1));
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
        levels.push(super::lods::Level {
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
    let bytes = lodkit_mesh::io::gltf::write_scene_lod_glb(&glb_levels, &output.glb())
        .map_err(|e| anyhow::anyhow!("{}: {e}", glb_path.display()))?;
    write_atomic(&glb_path, &bytes)?;
    let lods = super::lods::Lods {
        input: input.to_string(),
        input_triangles: merged.faces.len(),
        input_vertices: merged.positions.len(),
        glb: glb_name,
        levels,
    };
    let json = serde_json::to_string_pretty(&lods)? + "\n";
    write_atomic(&out.join("lods.json"), json.as_bytes())?;
    Ok(super::build::lod_chain::Chain {
        lods,
        meshes,
        measured,
        face_materials: Some(face_materials),
    })
}

/// Checks that the base-colour textures `render_materials` would decode
/// fit in one run's pixel budget
/// ([`lodkit_particles::silhouette::images::MAX_RUN_PIXELS`]), from their
/// headers alone (nothing is decoded). Errors: one line naming `name` and
/// the texture image that does not fit. Cost: one header parse a texture.
pub fn texture_budget(name: &str, scene: &Scene) -> anyhow::Result<()> {
    use lodkit_particles::silhouette::images;
    let mut budget = images::PixelBudget::run();
    let mut charged = vec![false; scene.images.len()];
    for m in &scene.materials {
        let Some(image) = m
            .base_color_texture
            .and_then(|r| scene.textures.get(r.texture))
            .map(|t| t.image)
            .filter(|&i| i < scene.images.len())
        else {
            continue;
        };
        if std::mem::replace(&mut charged[image], true) {
            continue;
        }
        let im = &scene.images[image];
        if let Ok((w, h)) = images::image_size(&im.bytes) {
            budget.charge(w, h).map_err(|e| {
                let what = im.file_name.as_deref().unwrap_or("an embedded image");
                anyhow::anyhow!(
                    "{name}: texture image {image} ({}): {e}",
                    lodkit_mesh::error::escape(what)
                )
            })?;
        }
    }
    Ok(())
}

/// What `lodkit_render` needs to draw `scene`'s faces with their materials:
/// each material's base colour factor and base colour texture, decoded
/// (PNG or JPEG, by the one decoder, size-bounded before allocating), for
/// a merged mesh whose faces have `face_materials`. A texture that does not
/// decode is said in a warning naming `name` and left out (its faces show
/// the factor alone). Errors: the textures' pixels together over the
/// run's budget ([`texture_budget`], from their headers, before any is
/// decoded), naming `name` and the texture.
pub fn render_materials(
    ui: &Ui,
    name: &str,
    scene: &Scene,
    face_materials: Vec<u32>,
) -> anyhow::Result<lodkit_render::Materials> {
    use lodkit_render::{Look, TextureImage, Wrap};
    texture_budget(name, scene)?;
    let mut textures = Vec::new();
    // Scene texture index -> renderer texture index (decoded once).
    let mut decoded: Vec<Option<Option<usize>>> = vec![None; scene.textures.len()];
    let looks = scene
        .materials
        .iter()
        .map(|m| {
            let texture = m.base_color_texture.and_then(|r| {
                let slot = decoded.get_mut(r.texture)?;
                *slot.get_or_insert_with(|| {
                    let t = &scene.textures[r.texture];
                    let image = scene.images.get(t.image)?;
                    match lodkit_particles::silhouette::images::decode_rgba(&image.bytes) {
                        Ok(d) => {
                            let s = t.sampler.and_then(|i| scene.samplers.get(i));
                            textures.push(TextureImage {
                                width: d.width,
                                height: d.height,
                                rgba: d.rgba,
                                wrap: s.map_or([Wrap::Repeat; 2], |s| {
                                    [Wrap::from_gltf(s.wrap_s), Wrap::from_gltf(s.wrap_t)]
                                }),
                            });
                            Some(textures.len() - 1)
                        }
                        Err(e) => {
                            let what = image.file_name.as_deref().unwrap_or("an embedded image");
                            ui.status(format!(
                                "warning: {name}: texture {} ({}): {e}; drawn without it",
                                r.texture,
                                lodkit_mesh::error::escape(what)
                            ));
                            None
                        }
                    }
                })
            });
            let [r, g, b, _] = m.base_color;
            Look {
                factor: [r, g, b],
                texture,
            }
        })
        .collect();
    Ok(lodkit_render::Materials {
        face_looks: face_materials,
        looks,
        textures,
    })
}
