//! Per-level textures of a scene's LOD chain: each level's images at the
//! resolution its size on screen needs.
//!
//! A level is shown where its triangles are about as dense on screen as
//! the input's at full size, so it covers `√(level triangles / input
//! triangles)` of the input's size in each direction (the screen
//! coverages of the chain GLB follow the same rule); its textures then
//! need that fraction of their texels a side. Each image a texture uses is
//! box-filtered to `√(level / input)` of its sides, never below
//! [`MIN_SIDE`] texels on its longer side (nor above its own size), and
//! written in its source's format (`lodkit_mesh::image::encode_like`).
//! An image that does not decode is kept as it is (the renderer and the
//! readers say why elsewhere).
//!
//! One GLB holding the whole chain (`STEM_lods.glb`) writes its material,
//! texture and image tables once for all levels, so its levels' tables are
//! made one ([`share_tables`]): the union of every level's, equal entries
//! merged, each level's faces pointing at its own.

use lodkit_mesh::Scene;
use lodkit_mesh::image::{decode_rgba, encode_like, resample};
use lodkit_mesh::scene::{Material, NO_MATERIAL, TextureRef};

/// Fewest texels on a level image's longer side: below this a texture
/// stops telling its colours apart (a 64² image is 12 KiB as RGBA).
pub const MIN_SIDE: u32 = 64;

/// The size of a `w × h` image for a level of `faces` triangles out of the
/// input's `full`: `√(faces / full)` of each side, the longer side at
/// least [`MIN_SIDE`] (or its own size, if smaller), never larger.
pub fn level_size(w: u32, h: u32, faces: usize, full: usize) -> (u32, u32) {
    let ratio = if full == 0 {
        1.0
    } else {
        (faces as f64 / full as f64).clamp(0.0, 1.0).sqrt()
    };
    let longer = w.max(h).max(1);
    let floor = f64::from(MIN_SIDE.min(longer)) / f64::from(longer);
    let s = ratio.max(floor).min(1.0);
    let side = |n: u32| ((f64::from(n) * s).round() as u32).clamp(1, n.max(1));
    (side(w), side(h))
}

/// `scene` (a level of `faces` triangles of an input of `full`) with every
/// image a texture uses scaled to [`level_size`]; images already at that
/// size, and images that do not decode, are kept byte for byte. Errors:
/// an image the encoder refuses (naming it). Cost: one decode and one
/// encode per scaled image.
pub fn scale_textures(mut scene: Scene, faces: usize, full: usize) -> anyhow::Result<Scene> {
    let mut used = vec![false; scene.images.len()];
    for t in &scene.textures {
        if let Some(u) = used.get_mut(t.image) {
            *u = true;
        }
    }
    for (i, image) in scene.images.iter_mut().enumerate() {
        if !used[i] {
            continue;
        }
        let Ok((w, h)) = lodkit_mesh::image::image_size(&image.bytes) else {
            continue;
        };
        let (nw, nh) = level_size(w, h, faces, full);
        if (nw, nh) == (w, h) {
            continue;
        }
        let Ok(rgba) = decode_rgba(&image.bytes) else {
            continue;
        };
        let scaled = resample(&rgba, [0, 0, w, h], nw, nh);
        let (bytes, mime) = encode_like(&image.bytes, &scaled).map_err(|e| {
            let what = image.file_name.as_deref().unwrap_or("an embedded image");
            anyhow::anyhow!("level image {i} ({}): {e}", lodkit_mesh::escape(what))
        })?;
        image.bytes = bytes;
        image.mime_type = mime.to_string();
    }
    Ok(scene)
}

/// Makes the material, texture, image and sampler tables of every scene
/// in `levels` one: their union (equal entries merged, first seen first),
/// each scene's face materials and texture references remapped into it.
/// Scenes whose tables are already equal are left as they were.
pub fn share_tables(levels: &mut [Scene]) {
    let Some(first) = levels.first() else {
        return;
    };
    if levels.iter().all(|s| {
        s.materials == first.materials
            && s.textures == first.textures
            && s.images == first.images
            && s.samplers == first.samplers
    }) {
        return;
    }
    let mut all = Scene::default();
    fn index_of<T: PartialEq + Clone>(table: &mut Vec<T>, item: &T) -> usize {
        table.iter().position(|x| x == item).unwrap_or_else(|| {
            table.push(item.clone());
            table.len() - 1
        })
    }
    let mut maps = Vec::with_capacity(levels.len());
    for s in levels.iter() {
        let images: Vec<usize> = s
            .images
            .iter()
            .map(|i| index_of(&mut all.images, i))
            .collect();
        let samplers: Vec<usize> = s
            .samplers
            .iter()
            .map(|x| index_of(&mut all.samplers, x))
            .collect();
        let textures: Vec<usize> = s
            .textures
            .iter()
            .map(|t| {
                let mut t = t.clone();
                t.image = images.get(t.image).copied().unwrap_or(t.image);
                t.sampler = t.sampler.and_then(|x| samplers.get(x).copied());
                index_of(&mut all.textures, &t)
            })
            .collect();
        let materials: Vec<u32> = s
            .materials
            .iter()
            .map(|m| index_of(&mut all.materials, &remap_textures(m, &textures)) as u32)
            .collect();
        maps.push(materials);
    }
    for (s, materials) in levels.iter_mut().zip(maps) {
        for sm in &mut s.meshes {
            for f in &mut sm.face_materials {
                if *f != NO_MATERIAL {
                    *f = materials[*f as usize];
                }
            }
        }
        s.materials = all.materials.clone();
        s.textures = all.textures.clone();
        s.images = all.images.clone();
        s.samplers = all.samplers.clone();
    }
}

/// `m` with every texture index mapped through `textures`.
fn remap_textures(m: &Material, textures: &[usize]) -> Material {
    let r = |t: Option<TextureRef>| {
        t.map(|t| TextureRef {
            texture: textures.get(t.texture).copied().unwrap_or(t.texture),
            ..t
        })
    };
    let i = |t: Option<usize>| t.map(|t| textures.get(t).copied().unwrap_or(t));
    let mut out = m.clone();
    out.base_color_texture = r(m.base_color_texture);
    out.metallic_roughness_texture = r(m.metallic_roughness_texture);
    out.normal_texture = r(m.normal_texture);
    out.occlusion_texture = r(m.occlusion_texture);
    out.emissive_texture = r(m.emissive_texture);
    out.mtl.specular_texture = i(m.mtl.specular_texture);
    out.mtl.shininess_texture = i(m.mtl.shininess_texture);
    out.mtl.dissolve_texture = i(m.mtl.dissolve_texture);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_sizes_follow_the_square_root_of_the_triangles() {
        assert_eq!(level_size(1024, 512, 100, 100), (1024, 512));
        assert_eq!(level_size(1024, 512, 25, 100), (512, 256));
        // The longer side stays at MIN_SIDE at least, and never grows.
        assert_eq!(level_size(1024, 512, 1, 1_000_000), (64, 32));
        assert_eq!(level_size(32, 16, 1, 100), (32, 16));
    }
}
