//! Reading a glTF document's materials, textures, samplers and images into
//! a [`Scene`]'s tables (see `io::gltf`'s module docs for what is kept).
//!
//! Images come from a buffer view (GLB), a base64 `data:` URI, or a file
//! beside the glTF: the URI is percent-decoded, then must pass
//! [`crate::io::input::resolve_inside`] (relative, no `..`, no scheme), and
//! is read through [`crate::io::input::read_file`]. Their bytes are kept as
//! stored; the MIME type comes from the bytes' signature, else from the
//! file's `mimeType`. Images that share their bytes — one byte range of a
//! buffer, one file named several ways — are kept once (textures are
//! pointed at the one copy), and the images' bytes together may not exceed
//! the input's bytes: aliased images cannot multiply memory.

use std::borrow::Cow;
use std::path::Path;

use super::buffers::{decode_base64, load_buffer, percent_decode};
use crate::error::{ParseError, clip};
use crate::parse_err;
use crate::scene::{
    AlphaMode, Image, Material, MtlExtras, Sampler, Scene, Texture, TextureRef, image_mime,
};

/// Fills `scene`'s material, texture, sampler and image tables from the
/// document, index for index (unused entries are dropped by the writer).
pub(super) fn read_tables(
    doc: &gltf::Document,
    bin: Option<&[u8]>,
    base_dir: Option<&Path>,
    source: u64,
    scene: &mut Scene,
) -> Result<(), ParseError> {
    for s in doc.samplers() {
        scene.samplers.push(Sampler {
            mag_filter: s.mag_filter().map(|f| f.as_gl_enum()),
            min_filter: s.min_filter().map(|f| f.as_gl_enum()),
            wrap_s: s.wrap_s().as_gl_enum(),
            wrap_t: s.wrap_t().as_gl_enum(),
        });
    }
    let mut buffers: Vec<Option<Cow<[u8]>>> = vec![None; doc.buffers().len()];
    let mut images = Images {
        by_source: std::collections::BTreeMap::new(),
        of_doc: Vec::with_capacity(doc.images().len()),
        bytes: 0,
        source,
    };
    for img in doc.images() {
        images.read(&img, bin, base_dir, &mut buffers, scene)?;
    }
    for t in doc.textures() {
        scene.textures.push(Texture {
            name: t.name().map(str::to_owned),
            image: images.of_doc[t.source().index()],
            sampler: t.sampler().index(),
        });
    }
    let info = |i: Option<gltf::texture::Info>| {
        i.map(|i| TextureRef {
            texture: i.texture().index(),
            tex_coord: i.tex_coord(),
        })
    };
    for m in doc.materials() {
        let pbr = m.pbr_metallic_roughness();
        let normal = m.normal_texture();
        let occlusion = m.occlusion_texture();
        scene.materials.push(Material {
            name: m.name().map(str::to_owned),
            base_color: pbr.base_color_factor(),
            base_color_texture: info(pbr.base_color_texture()),
            metallic: pbr.metallic_factor(),
            roughness: pbr.roughness_factor(),
            metallic_roughness_texture: info(pbr.metallic_roughness_texture()),
            normal_scale: normal.as_ref().map_or(1.0, |n| n.scale()),
            normal_texture: normal.map(|n| TextureRef {
                texture: n.texture().index(),
                tex_coord: n.tex_coord(),
            }),
            occlusion_strength: occlusion.as_ref().map_or(1.0, |o| o.strength()),
            occlusion_texture: occlusion.map(|o| TextureRef {
                texture: o.texture().index(),
                tex_coord: o.tex_coord(),
            }),
            emissive: m.emissive_factor(),
            emissive_texture: info(m.emissive_texture()),
            alpha_mode: match m.alpha_mode() {
                gltf::material::AlphaMode::Opaque => AlphaMode::Opaque,
                gltf::material::AlphaMode::Mask => AlphaMode::Mask,
                gltf::material::AlphaMode::Blend => AlphaMode::Blend,
            },
            alpha_cutoff: m.alpha_cutoff(),
            double_sided: m.double_sided(),
            mtl: mtl_extras(m.extras()),
        });
    }
    Ok(())
}

/// The MTL scalars lodkit's GLB writer keeps in `extras.mtl` (so OBJ →
/// GLB → OBJ keeps `Ka`, `Ks`, `Ns`, `Ni` and `illum`); anything else in
/// `extras` is ignored.
fn mtl_extras(extras: &gltf::json::Extras) -> MtlExtras {
    let mut out = MtlExtras::default();
    let Some(raw) = extras else { return out };
    let Ok(v) = serde_json::from_str::<serde_json::Value>(raw.get()) else {
        return out;
    };
    let Some(mtl) = v.get("mtl") else { return out };
    let rgb = |k: &str| -> Option<[f32; 3]> {
        let a = mtl.get(k)?.as_array()?;
        if a.len() != 3 {
            return None;
        }
        let f = |i: usize| a[i].as_f64().map(|x| x as f32).filter(|x| x.is_finite());
        Some([f(0)?, f(1)?, f(2)?])
    };
    let num = |k: &str| {
        mtl.get(k)?
            .as_f64()
            .map(|x| x as f32)
            .filter(|x| x.is_finite())
    };
    out.ambient = rgb("Ka");
    out.specular = rgb("Ks");
    out.shininess = num("Ns");
    out.optical_density = num("Ni");
    out.illum = mtl
        .get("illum")
        .and_then(|x| x.as_u64())
        .and_then(|x| u8::try_from(x).ok());
    out
}

/// The last path component of a URI (for naming a copy of the image).
fn file_name(uri: &str) -> Option<String> {
    let name = uri.rsplit(['/', '\\']).next()?;
    (!name.is_empty()).then(|| name.to_owned())
}

/// Where an image's bytes came from, to keep each source once.
#[derive(PartialEq, Eq, PartialOrd, Ord)]
enum ImageSource {
    /// Buffer, start, end.
    Range(usize, usize, usize),
    /// A file's real path.
    File(std::path::PathBuf),
}

/// The images read so far.
struct Images {
    /// Each kept image's source and its index in the scene.
    by_source: std::collections::BTreeMap<ImageSource, usize>,
    /// The scene image of each document image.
    of_doc: Vec<usize>,
    /// Bytes of the kept images.
    bytes: u64,
    /// Bytes of input (the file, external buffers and image files).
    source: u64,
}

impl Images {
    /// Reads document image `img` into `scene.images`, or points it at the
    /// image already read from the same bytes.
    fn read<'a>(
        &mut self,
        img: &gltf::Image<'_>,
        bin: Option<&'a [u8]>,
        base_dir: Option<&Path>,
        buffers: &mut [Option<Cow<'a, [u8]>>],
        scene: &mut Scene,
    ) -> Result<(), ParseError> {
        let i = img.index();
        let key = match img.source() {
            gltf::image::Source::View { view, .. } => Some(ImageSource::Range(
                view.buffer().index(),
                view.offset(),
                view.offset().saturating_add(view.length()),
            )),
            gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:") => {
                let rel = percent_decode(uri)?;
                base_dir
                    .and_then(|d| crate::io::input::resolve_inside(d, &rel).ok())
                    .map(|p| ImageSource::File(crate::io::input::real_path(&p)))
            }
            gltf::image::Source::Uri { .. } => None,
        };
        if let Some(at) = key.as_ref().and_then(|k| self.by_source.get(k)) {
            self.of_doc.push(*at);
            return Ok(());
        }
        if let gltf::image::Source::View { view, .. } = img.source() {
            let b = view.buffer().index();
            if buffers[b].is_none() {
                let data = load_buffer(view.buffer(), bin, base_dir)?;
                if let Cow::Owned(d) = &data {
                    self.source = self.source.saturating_add(d.len() as u64);
                }
                buffers[b] = Some(data);
            }
        }
        let (image, external) = read_image(img, bin, base_dir, buffers)?;
        if external {
            self.source = self.source.saturating_add(image.bytes.len() as u64);
        }
        self.bytes = self.bytes.saturating_add(image.bytes.len() as u64);
        if self.bytes > self.source {
            return Err(parse_err!(
                "image {i}: the images hold {} bytes, more than the {} bytes of the input \
                 (images that overlap in one buffer)",
                self.bytes,
                self.source
            ));
        }
        scene.images.push(image);
        let at = scene.images.len() - 1;
        if let Some(k) = key {
            self.by_source.insert(k, at);
        }
        self.of_doc.push(at);
        Ok(())
    }
}

/// Document image `img`, and whether its bytes came from a file of its own.
fn read_image<'a>(
    img: &gltf::Image<'_>,
    bin: Option<&'a [u8]>,
    base_dir: Option<&Path>,
    buffers: &mut [Option<Cow<'a, [u8]>>],
) -> Result<(Image, bool), ParseError> {
    let i = img.index();
    let external =
        matches!(img.source(), gltf::image::Source::Uri { uri, .. } if !uri.starts_with("data:"));
    let (bytes, declared, name) = match img.source() {
        gltf::image::Source::View { view, mime_type } => {
            let b = view.buffer().index();
            if buffers[b].is_none() {
                buffers[b] = Some(load_buffer(view.buffer(), bin, base_dir)?);
            }
            let data = buffers[b].as_deref().unwrap_or_default();
            let end = view.offset().checked_add(view.length());
            let bytes = end
                .and_then(|e| data.get(view.offset()..e))
                .ok_or_else(|| {
                    parse_err!(
                        "image {i}: buffer view {} (bytes {}..+{}) is outside buffer {b} ({} bytes)",
                        view.index(),
                        view.offset(),
                        view.length(),
                        data.len()
                    )
                })?;
            let name = img.name().filter(|n| n.contains('.')).and_then(file_name);
            (bytes.to_vec(), Some(mime_type.to_owned()), name)
        }
        gltf::image::Source::Uri { uri, mime_type } => {
            if let Some(rest) = uri.strip_prefix("data:") {
                let (meta, data) = rest
                    .split_once(',')
                    .ok_or_else(|| parse_err!("image {i}: data URI has no ','"))?;
                let Some(mime) = meta.strip_suffix(";base64") else {
                    return Err(parse_err!(
                        "image {i}: data URI is not base64 ('{}')",
                        clip(meta, 48)
                    ));
                };
                let bytes = decode_base64(data)
                    .map_err(|e| parse_err!("image {i}: data URI is not valid base64: {e}"))?;
                (bytes, Some(mime.to_owned()), None)
            } else {
                let rel = percent_decode(uri)?;
                let dir = base_dir.ok_or_else(|| {
                    parse_err!(
                        "image {i}: external file '{}' but no directory to resolve it against",
                        clip(&rel, 48)
                    )
                })?;
                let path = crate::io::input::resolve_inside(dir, &rel)
                    .map_err(|why| parse_err!("image {i}: URI {why}"))?;
                let bytes =
                    crate::io::input::read_file(&path).map_err(|e| parse_err!("image {i}: {e}"))?;
                (bytes, mime_type.map(str::to_owned), file_name(&rel))
            }
        }
    };
    let mime_type = match image_mime(&bytes) {
        Some(m) => m.to_owned(),
        None => declared.filter(|m| !m.is_empty()).ok_or_else(|| {
            parse_err!("image {i}: neither PNG nor JPEG, and no mimeType is given")
        })?,
    };
    Ok((
        Image {
            name: img.name().map(str::to_owned),
            file_name: name,
            mime_type,
            bytes,
        },
        external,
    ))
}
