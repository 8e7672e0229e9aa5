//! A scene's materials as the renderer draws them (base colours and
//! decoded textures), and the pixel budget they are checked against.
use lodkit_mesh::Scene;

use crate::progress::Progress;

/// Checks that the base-colour textures `render_materials` would decode
/// fit in one run's pixel budget
/// ([`lodkit_mesh::image::MAX_RUN_PIXELS`]), from their
/// headers alone (nothing is decoded). Errors: one line naming `name` and
/// the texture image that does not fit. Cost: one header parse a texture.
pub fn texture_budget(name: &str, scene: &Scene) -> anyhow::Result<()> {
    use lodkit_mesh::image as images;
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
                    lodkit_mesh::escape(what)
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
    events: &Progress,
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
                    match lodkit_mesh::image::decode_rgba(&image.bytes) {
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
                            events.status(format!(
                                "warning: {name}: texture {} ({}): {e}; drawn without it",
                                r.texture,
                                lodkit_mesh::escape(what)
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
