//! Textured tiles: each tile carries the texels its triangles use, at the
//! resolution its level needs.
//!
//! A textured input (a [`Scene`] whose materials have base-colour
//! textures) is tiled as one merged mesh whose faces' materials are vertex
//! groups: through every level's simplification a material border is a
//! seam, like a UV seam (`lodkit_simplify`'s grouped simplification), so
//! UV charts keep their borders and every tile face keeps its material.
//!
//! Each tile's content then gets, per material it uses, its own image:
//! the source texture cropped to the UV bounding rectangle of the tile's
//! faces of that material (plus a margin of [`MARGIN_TEXELS`] output
//! texels, so bilinear and mipmapped sampling near a chart's edge reads
//! the chart's own colours), box-filtered down by `2^h` where `h` is the
//! tile's height above the leaves (a leaf keeps the source resolution,
//! each level up halves it), and written inside the GLB in the source's
//! format (JPEG at quality 90 for a JPEG, else PNG); the
//! tile's UVs are remapped to the crop. The root of a scan with an 8K
//! texture so carries `8192 / 2^depth` texels a side at most. Where a
//! material's UVs leave `[0, 1]` (a repeating texture), cropping would
//! change what repeats: that material keeps the whole image (still
//! halved per level) and its sampler.
//!
//! Simplest honest version: the crop is one rectangle per material per
//! tile, so a tile whose charts are spread over the atlas keeps the texels
//! between them too; repacking the charts into an atlas per tile would
//! crop tighter. Only the base-colour texture is carried (normal,
//! metallic-roughness, occlusion and emissive maps are dropped from the
//! tiles).

use lodkit_mesh::image::{RgbaImage, decode_rgba, encode_like, resample};
use lodkit_mesh::io::gltf::{GlbOptions, QuantGrid, write_scene_glb_on_grid};
use lodkit_mesh::scene::{
    Image, Material, MtlExtras, NO_MATERIAL, Node, Sampler, Scene, SceneMesh, Texture, TextureRef,
};
use lodkit_mesh::{TriMesh, glam::Vec2};

use crate::{Error, Event, Result, TilesOptions, Tileset};

/// Margin around a tile's UV rectangle, in texels of the tile's image: two
/// texels cover bilinear sampling and the first mipmap level at a chart's
/// edge.
pub const MARGIN_TEXELS: u32 = 2;

/// glTF's `CLAMP_TO_EDGE`: a crop must not wrap to its opposite side.
const CLAMP_TO_EDGE: u32 = 33071;
/// glTF's `LINEAR` (magnification) and `LINEAR_MIPMAP_LINEAR`.
const LINEAR: u32 = 9729;
const LINEAR_MIPMAP_LINEAR: u32 = 9987;

/// UVs this far outside `[0, 1]` still count as inside (rounding).
const UV_SLACK: f32 = 1e-4;

/// The materials of a textured tileset: the input's tables and each
/// base-colour texture decoded once.
pub(crate) struct Textures {
    materials: Vec<Material>,
    textures: Vec<Texture>,
    samplers: Vec<Sampler>,
    /// Per texture: its image decoded and the bytes it was decoded from
    /// (base-colour textures only).
    decoded: Vec<Option<(RgbaImage, Vec<u8>)>>,
}

/// Builds the tileset of a scene (y-up, object units) with its materials
/// and base-colour textures: the placed meshes merged into one, each
/// face's material kept through every level, each tile's texture cropped
/// to its UVs and halved per level above the leaves (see the module
/// docs). A scene without materials gives [`crate::tileset_from_mesh`]'s
/// tileset of its merged mesh.
///
/// Errors: those of [`crate::tileset_from_mesh`], and [`Error::Input`]
/// for a base-colour texture whose image is not a readable PNG or JPEG
/// (naming the image). Cost: that of `tileset_from_mesh`, plus each
/// base-colour image decoded (`4 × width × height` bytes, bounded by
/// `lodkit_mesh::image::MAX_PIXELS` each; the caller bounds their sum) and
/// kept until the tileset is dropped.
pub fn tileset_from_scene(
    scene: &Scene,
    opts: &TilesOptions,
    progress: &mut dyn FnMut(Event),
) -> Result<Tileset> {
    scene.validate().map_err(|e| Error::Input(e.to_string()))?;
    let merged = scene.merged();
    if scene.materials.is_empty() {
        return crate::tileset_from_mesh(&merged.mesh, opts, progress);
    }
    let mut decoded: Vec<Option<(RgbaImage, Vec<u8>)>> = vec![None; scene.textures.len()];
    for m in &scene.materials {
        let Some(r) = m.base_color_texture else {
            continue;
        };
        let (Some(t), None) = (scene.textures.get(r.texture), &decoded[r.texture]) else {
            continue;
        };
        let image = scene
            .images
            .get(t.image)
            .ok_or_else(|| Error::Input(format!("texture {} names a missing image", r.texture)))?;
        let rgba = decode_rgba(&image.bytes).map_err(|e| {
            let what = image.file_name.as_deref().unwrap_or("an embedded image");
            Error::Input(format!(
                "texture image {} ({}): {e}",
                t.image,
                lodkit_mesh::escape(what)
            ))
        })?;
        decoded[r.texture] = Some((rgba, image.bytes.clone()));
    }
    let (mesh, groups) = lodkit_simplify::scene::split_by_material(&merged);
    let mut tileset = crate::build_tileset(&mesh, groups, opts, progress)?;
    tileset.textures = Some(Textures {
        materials: scene.materials.clone(),
        textures: scene.textures.clone(),
        samplers: scene.samplers.clone(),
        decoded,
    });
    Ok(tileset)
}

/// How many levels node `i`'s subtree has below it (a leaf: 0), for every
/// node; children come after their parents in `children`' order.
pub(crate) fn heights(children: &[Vec<usize>]) -> Vec<u32> {
    let mut h = vec![0u32; children.len()];
    for i in (0..children.len()).rev() {
        for &c in &children[i] {
            h[i] = h[i].max(h[c] + 1);
        }
    }
    h
}

impl Textures {
    /// One tile's GLB: `mesh` (with skirts) with the materials of its
    /// vertex `groups`, each textured material's image cropped to the
    /// tile's UVs and scaled by `2^-height`, positions on `grid`.
    pub(crate) fn encode(
        &self,
        name: &str,
        mesh: &TriMesh,
        groups: &[u32],
        height: u32,
        compress: bool,
        grid: &QuantGrid,
    ) -> Result<Vec<u8>> {
        let face_groups: Vec<u32> = mesh
            .faces
            .iter()
            .map(|f| groups.get(f[0] as usize).copied().unwrap_or(NO_MATERIAL))
            .collect();
        let mut used: Vec<u32> = face_groups
            .iter()
            .copied()
            .filter(|&g| (g as usize) < self.materials.len())
            .collect();
        used.sort_unstable();
        used.dedup();
        let mut out = Scene {
            meshes: Vec::new(),
            nodes: vec![Node {
                name: Some(name.to_string()),
                mesh: Some(0),
                ..Default::default()
            }],
            roots: vec![0],
            ..Default::default()
        };
        let mut mesh = mesh.clone();
        for &g in &used {
            let source = &self.materials[g as usize];
            let mut material = Material {
                base_color_texture: None,
                metallic_roughness_texture: None,
                normal_texture: None,
                occlusion_texture: None,
                emissive_texture: None,
                mtl: MtlExtras {
                    specular_texture: None,
                    shininess_texture: None,
                    dissolve_texture: None,
                    ..source.mtl.clone()
                },
                ..source.clone()
            };
            let texture = source
                .base_color_texture
                .filter(|r| r.tex_coord == 0)
                .and_then(|r| Some((r, self.decoded.get(r.texture)?.as_ref()?)));
            if let (Some((r, image)), Some(uvs)) = (texture, mesh.uvs.as_mut()) {
                let mut mine = vec![false; uvs.len()];
                for (f, _) in mesh.faces.iter().zip(&face_groups).filter(|p| *p.1 == g) {
                    for &v in f {
                        mine[v as usize] = true;
                    }
                }
                let (bytes, mime, sampler) = self.tile_image(r, image, uvs, &mine, height)?;
                out.samplers.push(sampler);
                out.images.push(Image {
                    name: Some(format!("{name}_{}", out.images.len())),
                    file_name: None,
                    mime_type: mime.into(),
                    bytes,
                });
                out.textures.push(Texture {
                    name: None,
                    image: out.images.len() - 1,
                    sampler: Some(out.samplers.len() - 1),
                });
                material.base_color_texture = Some(TextureRef::new(out.textures.len() - 1));
            }
            out.materials.push(material);
        }
        let face_materials = face_groups
            .iter()
            .map(|g| used.binary_search(g).map_or(NO_MATERIAL, |k| k as u32))
            .collect();
        if used.is_empty() {
            mesh.uvs = None;
        }
        out.meshes.push(SceneMesh {
            name: Some(name.to_string()),
            mesh,
            face_materials,
        });
        write_scene_glb_on_grid(&out, &GlbOptions { compress }, grid)
            .map_err(|e| Error::Encode(format!("tile {name}: {e}")))
    }

    /// The image of texture `r` for the vertices flagged in `mine`: cropped
    /// to their UV rectangle (their UVs remapped to it) unless they leave
    /// `[0, 1]`, and scaled by `2^-height`; its bytes (the source's format,
    /// `encode_like`), their MIME type and the sampler.
    fn tile_image(
        &self,
        r: TextureRef,
        (image, source): &(RgbaImage, Vec<u8>),
        uvs: &mut [Vec2],
        mine: &[bool],
        height: u32,
    ) -> Result<(Vec<u8>, &'static str, Sampler)> {
        let (w, h) = (image.width as f32, image.height as f32);
        let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
        for (uv, _) in uvs.iter().zip(mine).filter(|p| *p.1) {
            lo = lo.min(*uv);
            hi = hi.max(*uv);
        }
        let factor = 1u64 << height.min(24);
        let inside =
            lo.cmpge(Vec2::splat(-UV_SLACK)).all() && hi.cmple(Vec2::splat(1.0 + UV_SLACK)).all();
        let sampler;
        let rect = if inside {
            // Texel rectangle (rows top to bottom: UV origin is bottom-left).
            let margin = (u64::from(MARGIN_TEXELS) * factor) as f32;
            let x0 = ((lo.x * w - margin).floor().max(0.0) as u32).min(image.width - 1);
            let y0 = (((1.0 - hi.y) * h - margin).floor().max(0.0) as u32).min(image.height - 1);
            let x1 = ((hi.x * w + margin).ceil().min(w) as u32).max(x0 + 1);
            let y1 = (((1.0 - lo.y) * h + margin).ceil().min(h) as u32).max(y0 + 1);
            let (cw, ch) = ((x1 - x0) as f32, (y1 - y0) as f32);
            for (uv, _) in uvs.iter_mut().zip(mine).filter(|p| *p.1) {
                let tx = (uv.x * w - x0 as f32) / cw;
                let ty = ((1.0 - uv.y) * h - y0 as f32) / ch;
                *uv = Vec2::new(tx, 1.0 - ty);
            }
            sampler = Sampler {
                mag_filter: Some(LINEAR),
                min_filter: Some(LINEAR_MIPMAP_LINEAR),
                wrap_s: CLAMP_TO_EDGE,
                wrap_t: CLAMP_TO_EDGE,
            };
            [x0, y0, x1, y1]
        } else {
            let t = &self.textures[r.texture];
            sampler = t
                .sampler
                .and_then(|s| self.samplers.get(s).cloned())
                .unwrap_or(Sampler {
                    mag_filter: Some(LINEAR),
                    min_filter: Some(LINEAR_MIPMAP_LINEAR),
                    wrap_s: 10497,
                    wrap_t: 10497,
                });
            [0, 0, image.width, image.height]
        };
        let [x0, y0, x1, y1] = rect;
        let side = |n: u32| (u64::from(n).div_ceil(factor).max(1)) as u32;
        let scaled = resample(image, rect, side(x1 - x0), side(y1 - y0));
        let (bytes, mime) = encode_like(source, &scaled)
            .map_err(|e| Error::Encode(format!("a tile's image: {e}")))?;
        Ok((bytes, mime, sampler))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn heights_count_levels_below() {
        let children = vec![vec![1, 2], vec![3], vec![], vec![]];
        assert_eq!(heights(&children), vec![2, 1, 0, 0]);
    }
}
