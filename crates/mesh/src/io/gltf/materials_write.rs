//! Writing a [`Scene`] as one GLB: its meshes (one primitive per material),
//! nodes with their names and transforms, and the materials, textures,
//! samplers and images the faces use, images embedded in the BIN chunk.
//!
//! Layout: per mesh, one set of vertex accessors (POSITION with min/max,
//! NORMAL, COLOR_0, TEXCOORD_0 as `write_glb` writes them) shared by its
//! primitives, and one index accessor per primitive; primitives follow the
//! order in which their material first appears among the mesh's faces.
//! Only what is used is written (glTF-Validator reports unused objects):
//! materials some face uses, the textures those materials use, and those
//! textures' images and samplers, renumbered in their original order.
//! Each image is a buffer view of its unchanged bytes with its MIME type.
//! MTL scalars with no glTF slot (`Ka`, `Ks`, `Ns`, `Ni`, `illum`) go to
//! the material's `extras.mtl`, which the reader takes back.
//! Deterministic: the same scene always gives the same bytes.

use std::collections::BTreeMap;

use glam::Vec2;
use gltf::json;
use json::validation::Checked::Valid;

use super::color::srgb8_to_linear;
use super::glb::join_glb;
use super::write::{le_bytes, vec3_bytes};
use crate::error::ParseError;
use crate::mesh::TriMesh;
use crate::parse_err;
use crate::scene::{AlphaMode, Material, NO_MATERIAL, Scene, TextureRef, Transform};

/// Renumbering of a table: `new[old]` is the written index, if written.
fn renumber(used: &[bool]) -> Vec<Option<u32>> {
    let mut next = 0u32;
    used.iter()
        .map(|&u| {
            u.then(|| {
                next += 1;
                next - 1
            })
        })
        .collect()
}

/// The vertex accessors of `m` (see the module docs).
fn vertex_attributes(
    b: &mut Builder,
    m: &TriMesh,
) -> BTreeMap<json::validation::Checked<json::mesh::Semantic>, json::Index<json::Accessor>> {
    use json::accessor::{ComponentType as C, Type as T};
    use json::buffer::Target::ArrayBuffer;
    let n = m.positions.len();
    let bbox = m.bbox();
    let mut attributes = BTreeMap::new();
    let pos = b.accessor(
        &vec3_bytes(&m.positions),
        n,
        C::F32,
        T::Vec3,
        false,
        ArrayBuffer,
        Some((
            json::Value::from(bbox.min.to_array().to_vec()),
            json::Value::from(bbox.max.to_array().to_vec()),
        )),
    );
    attributes.insert(Valid(json::mesh::Semantic::Positions), pos);
    if let Some(normals) = &m.normals {
        let a = b.accessor(
            &vec3_bytes(normals),
            n,
            C::F32,
            T::Vec3,
            false,
            ArrayBuffer,
            None,
        );
        attributes.insert(Valid(json::mesh::Semantic::Normals), a);
    }
    if let Some(colors) = &m.colors {
        let q = |c: u8| ((srgb8_to_linear(c) * 65535.0).round() as u16).to_le_bytes();
        let bytes = le_bytes(colors, |c: [u8; 4]| {
            let [r0, r1] = q(c[0]);
            let [g0, g1] = q(c[1]);
            let [b0, b1] = q(c[2]);
            let [a0, a1] = (c[3] as u16 * 257).to_le_bytes();
            [r0, r1, g0, g1, b0, b1, a0, a1]
        });
        let a = b.accessor(&bytes, n, C::U16, T::Vec4, true, ArrayBuffer, None);
        attributes.insert(Valid(json::mesh::Semantic::Colors(0)), a);
    }
    if let Some(uvs) = &m.uvs {
        let bytes = le_bytes(uvs, |t: Vec2| {
            let [u0, u1, u2, u3] = t.x.to_le_bytes();
            let [v0, v1, v2, v3] = (1.0 - t.y).to_le_bytes();
            [u0, u1, u2, u3, v0, v1, v2, v3]
        });
        let a = b.accessor(&bytes, n, C::F32, T::Vec2, false, ArrayBuffer, None);
        attributes.insert(Valid(json::mesh::Semantic::TexCoords(0)), a);
    }
    attributes
}

/// One index accessor over `faces` (u16 when every index fits, else u32).
fn index_accessor(b: &mut Builder, faces: &[[u32; 3]], n: usize) -> json::Index<json::Accessor> {
    use json::accessor::{ComponentType as C, Type as T};
    use json::buffer::Target::ElementArrayBuffer;
    let flat: Vec<u32> = faces.iter().flatten().copied().collect();
    if n < u16::MAX as usize {
        let bytes = le_bytes(&flat, |i: u32| (i as u16).to_le_bytes());
        b.accessor(
            &bytes,
            flat.len(),
            C::U16,
            T::Scalar,
            false,
            ElementArrayBuffer,
            None,
        )
    } else {
        let bytes = le_bytes(&flat, |i: u32| i.to_le_bytes());
        b.accessor(
            &bytes,
            flat.len(),
            C::U32,
            T::Scalar,
            false,
            ElementArrayBuffer,
            None,
        )
    }
}

/// The vertices `faces` use, in their order in `m`, and the faces
/// renumbered to them: each primitive holds only its own vertices.
fn sub_mesh(m: &TriMesh, faces: &[[u32; 3]]) -> TriMesh {
    let n = m.positions.len();
    let mut remap = vec![u32::MAX; n];
    for f in faces {
        for &v in f {
            remap[v as usize] = 0;
        }
    }
    let mut keep = Vec::new();
    for (v, r) in remap.iter_mut().enumerate() {
        if *r == 0 {
            *r = keep.len() as u32;
            keep.push(v);
        }
    }
    TriMesh {
        positions: keep.iter().map(|&v| m.positions[v]).collect(),
        normals: m
            .normals
            .as_ref()
            .map(|a| keep.iter().map(|&v| a[v]).collect()),
        colors: m
            .colors
            .as_ref()
            .map(|a| keep.iter().map(|&v| a[v]).collect()),
        uvs: m.uvs.as_ref().map(|a| keep.iter().map(|&v| a[v]).collect()),
        faces: faces.iter().map(|f| f.map(|v| remap[v as usize])).collect(),
    }
}

/// A buffer view over `bytes` (4-byte aligned, no target), for an image.
fn raw_view(b: &mut Builder, bytes: &[u8]) -> json::Index<json::buffer::View> {
    let offset = b.bin.len();
    b.bin.extend_from_slice(bytes);
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    b.root.push(json::buffer::View {
        buffer: json::Index::new(0),
        byte_length: bytes.len().into(),
        byte_offset: Some(offset.into()),
        byte_stride: None,
        name: None,
        target: None,
        extensions: None,
        extras: None,
    })
}

/// A glTF enum value as its `gltf-json` type (serde does the mapping).
fn gl_enum<T: serde::de::DeserializeOwned>(v: u32) -> Result<T, ParseError> {
    serde_json::from_value(serde_json::Value::from(v))
        .map_err(|_| parse_err!("GLB: sampler value {v} is not a glTF enum value"))
}

fn material_json(
    m: &Material,
    tex: &[Option<u32>],
    uv: bool,
) -> Result<json::Material, ParseError> {
    // A texture slot is written only when its texture is, and only with
    // UVs to sample it by (lodkit keeps TEXCOORD_0 alone).
    let slot = |r: Option<TextureRef>| {
        r.filter(|_| uv)
            .and_then(|r| tex[r.texture].map(json::Index::new))
    };
    let info = |r: Option<TextureRef>| {
        slot(r).map(|index| json::texture::Info {
            index,
            tex_coord: 0,
            extensions: None,
            extras: None,
        })
    };
    let x = &m.mtl;
    let mut mtl = serde_json::Map::new();
    if let Some(v) = x.ambient {
        mtl.insert("Ka".into(), serde_json::json!(v));
    }
    if let Some(v) = x.specular {
        mtl.insert("Ks".into(), serde_json::json!(v));
    }
    if let Some(v) = x.shininess {
        mtl.insert("Ns".into(), serde_json::json!(v));
    }
    if let Some(v) = x.optical_density {
        mtl.insert("Ni".into(), serde_json::json!(v));
    }
    if let Some(v) = x.illum {
        mtl.insert("illum".into(), serde_json::json!(v));
    }
    let extras = if mtl.is_empty() {
        None
    } else {
        Some(
            serde_json::value::to_raw_value(&serde_json::json!({ "mtl": mtl }))
                .map_err(|e| parse_err!("GLB: {e}"))?,
        )
    };
    Ok(json::Material {
        alpha_cutoff: match m.alpha_mode {
            AlphaMode::Mask => m.alpha_cutoff.map(json::material::AlphaCutoff),
            _ => None,
        },
        alpha_mode: Valid(match m.alpha_mode {
            AlphaMode::Opaque => json::material::AlphaMode::Opaque,
            AlphaMode::Mask => json::material::AlphaMode::Mask,
            AlphaMode::Blend => json::material::AlphaMode::Blend,
        }),
        double_sided: m.double_sided,
        name: m.name.clone(),
        pbr_metallic_roughness: json::material::PbrMetallicRoughness {
            base_color_factor: json::material::PbrBaseColorFactor(m.base_color),
            base_color_texture: info(m.base_color_texture),
            metallic_factor: json::material::StrengthFactor(m.metallic),
            roughness_factor: json::material::StrengthFactor(m.roughness),
            metallic_roughness_texture: info(m.metallic_roughness_texture),
            extensions: None,
            extras: None,
        },
        normal_texture: slot(m.normal_texture).map(|index| json::material::NormalTexture {
            index,
            scale: m.normal_scale,
            tex_coord: 0,
            extensions: None,
            extras: None,
        }),
        occlusion_texture: slot(m.occlusion_texture).map(|index| {
            json::material::OcclusionTexture {
                index,
                strength: json::material::StrengthFactor(m.occlusion_strength),
                tex_coord: 0,
                extensions: None,
                extras: None,
            }
        }),
        emissive_texture: info(m.emissive_texture),
        emissive_factor: json::material::EmissiveFactor(m.emissive),
        extensions: None,
        extras,
    })
}

/// Builds a scene GLB's BIN chunk and the JSON objects that point into
/// it: plain accessors only (a scene GLB is written uncompressed).
struct Builder {
    bin: Vec<u8>,
    root: json::Root,
}

impl Builder {
    /// Appends `bytes` as a new 4-byte-aligned buffer view and an accessor
    /// over it; returns the accessor's index.
    #[allow(clippy::too_many_arguments)]
    fn accessor(
        &mut self,
        bytes: &[u8],
        count: usize,
        component: json::accessor::ComponentType,
        ty: json::accessor::Type,
        normalized: bool,
        target: json::buffer::Target,
        min_max: Option<(json::Value, json::Value)>,
    ) -> json::Index<json::Accessor> {
        debug_assert!(self.bin.len().is_multiple_of(4));
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let view = self.root.push(json::buffer::View {
            buffer: json::Index::new(0),
            byte_length: bytes.len().into(),
            byte_offset: Some(offset.into()),
            byte_stride: None,
            name: None,
            target: Some(json::validation::Checked::Valid(target)),
            extensions: None,
            extras: None,
        });
        let (min, max) = match min_max {
            Some((a, b)) => (Some(a), Some(b)),
            None => (None, None),
        };
        self.root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: None,
            count: count.into(),
            component_type: json::validation::Checked::Valid(json::accessor::GenericComponentType(
                component,
            )),
            extensions: None,
            extras: None,
            type_: json::validation::Checked::Valid(ty),
            min,
            max,
            name: None,
            normalized,
            sparse: None,
        })
    }
}

/// Writes `scene` as one GLB (see the module docs for the layout).
///
/// Errors: a scene that breaks [`Scene::validate`], a mesh with no faces,
/// a sampler value that is not a glTF enum, or more data than a GLB holds
/// (4 GiB). Cost: one pass over the geometry plus a copy of each image.
pub fn write_scene_glb(scene: &Scene) -> Result<Vec<u8>, ParseError> {
    scene.validate()?;
    let mut b = Builder {
        bin: Vec::new(),
        root: json::Root {
            asset: json::Asset {
                generator: Some(format!("lodkit {}", env!("CARGO_PKG_VERSION"))),
                ..Default::default()
            },
            ..Default::default()
        },
    };
    // What is used: materials by faces of meshes with UVs or not; textures
    // only by materials on meshes with UVs.
    let mut mat_used = vec![false; scene.materials.len()];
    let mut mat_uv = vec![false; scene.materials.len()];
    for sm in &scene.meshes {
        for &f in &sm.face_materials {
            if f != NO_MATERIAL {
                mat_used[f as usize] = true;
                mat_uv[f as usize] |= sm.mesh.uvs.is_some();
            }
        }
    }
    let mut tex_used = vec![false; scene.textures.len()];
    for (i, m) in scene.materials.iter().enumerate() {
        if mat_uv[i] {
            for r in m.texture_refs() {
                tex_used[r.texture] = true;
            }
        }
    }
    let mut img_used = vec![false; scene.images.len()];
    let mut smp_used = vec![false; scene.samplers.len()];
    for (i, t) in scene.textures.iter().enumerate() {
        if tex_used[i] {
            img_used[t.image] = true;
            if let Some(s) = t.sampler {
                smp_used[s] = true;
            }
        }
    }
    let (mat_new, tex_new, img_new, smp_new) = (
        renumber(&mat_used),
        renumber(&tex_used),
        renumber(&img_used),
        renumber(&smp_used),
    );

    for (i, s) in scene.samplers.iter().enumerate() {
        if smp_used[i] {
            b.root.samplers.push(json::texture::Sampler {
                mag_filter: s.mag_filter.map(gl_enum).transpose()?,
                min_filter: s.min_filter.map(gl_enum).transpose()?,
                name: None,
                wrap_s: gl_enum(s.wrap_s)?,
                wrap_t: gl_enum(s.wrap_t)?,
                extensions: None,
                extras: None,
            });
        }
    }
    for (i, im) in scene.images.iter().enumerate() {
        if img_used[i] {
            let view = raw_view(&mut b, &im.bytes);
            b.root.images.push(json::Image {
                buffer_view: Some(view),
                mime_type: Some(json::image::MimeType(im.mime_type.clone())),
                // The file name names the copy beside a later OBJ output.
                name: im.name.clone().or_else(|| im.file_name.clone()),
                uri: None,
                extensions: None,
                extras: None,
            });
        }
    }
    for (i, t) in scene.textures.iter().enumerate() {
        if tex_used[i] {
            b.root.textures.push(json::Texture {
                name: t.name.clone(),
                sampler: t.sampler.and_then(|s| smp_new[s]).map(json::Index::new),
                source: json::Index::new(img_new[t.image].unwrap_or(0)),
                extensions: None,
                extras: None,
            });
        }
    }
    for (i, m) in scene.materials.iter().enumerate() {
        if mat_used[i] {
            let j = material_json(m, &tex_new, mat_uv[i])?;
            b.root.materials.push(j);
        }
    }

    let mut mesh_index = Vec::with_capacity(scene.meshes.len());
    for (mi, sm) in scene.meshes.iter().enumerate() {
        let m = &sm.mesh;
        if m.faces.is_empty() {
            return Err(parse_err!("GLB: mesh {mi} has no faces"));
        }
        // Materials in order of first appearance; faces grouped by them.
        let mut order: Vec<u32> = Vec::new();
        let mut group: BTreeMap<u32, Vec<[u32; 3]>> = BTreeMap::new();
        for (f, &id) in m.faces.iter().zip(&sm.face_materials) {
            let g = group.entry(id).or_insert_with(|| {
                order.push(id);
                Vec::new()
            });
            g.push(*f);
        }
        let mut primitives = Vec::with_capacity(order.len());
        for id in order {
            let mut sub = sub_mesh(m, &group[&id]);
            // UVs only where a texture samples them: an untextured
            // primitive's TEXCOORD_0 would be an unused object.
            let textured =
                id != NO_MATERIAL && scene.materials[id as usize].texture_refs().next().is_some();
            if !textured {
                sub.uvs = None;
            }
            let attributes = vertex_attributes(&mut b, &sub);
            let indices = index_accessor(&mut b, &sub.faces, sub.positions.len());
            primitives.push(json::mesh::Primitive {
                attributes,
                extensions: None,
                extras: None,
                indices: Some(indices),
                material: (id != NO_MATERIAL)
                    .then(|| mat_new[id as usize])
                    .flatten()
                    .map(json::Index::new),
                mode: Valid(json::mesh::Mode::Triangles),
                targets: None,
            });
        }
        mesh_index.push(b.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: sm.name.clone(),
            primitives,
            weights: None,
        }));
    }
    for n in &scene.nodes {
        let (mut matrix, mut translation, mut rotation, mut scale) = (None, None, None, None);
        match n.transform {
            _ if n.transform.is_identity() => {}
            Transform::Matrix(m) => matrix = Some(m),
            Transform::Trs {
                translation: t,
                rotation: r,
                scale: s,
            } => {
                translation = (t != [0.0; 3]).then_some(t);
                rotation = (r != [0.0, 0.0, 0.0, 1.0]).then_some(json::scene::UnitQuaternion(r));
                scale = (s != [1.0; 3]).then_some(s);
            }
        }
        b.root.nodes.push(json::Node {
            camera: None,
            children: (!n.children.is_empty()).then(|| {
                n.children
                    .iter()
                    .map(|&c| json::Index::new(c as u32))
                    .collect()
            }),
            extensions: None,
            extras: None,
            matrix,
            mesh: n.mesh.map(|m| mesh_index[m]),
            name: n.name.clone(),
            rotation,
            scale,
            translation,
            skin: None,
            weights: None,
        });
    }
    let bin_len = b.bin.len();
    if bin_len > u32::MAX as usize - 1024 {
        return Err(parse_err!(
            "GLB: {bin_len} bytes of geometry and images, over the 4 GiB GLB limit"
        ));
    }
    b.root.push(json::Buffer {
        byte_length: bin_len.into(),
        name: None,
        uri: None,
        extensions: None,
        extras: None,
    });
    let root_nodes = scene
        .roots
        .iter()
        .map(|&r| json::Index::new(r as u32))
        .collect();
    let s = b.root.push(json::Scene {
        extensions: None,
        extras: None,
        name: None,
        nodes: root_nodes,
    });
    b.root.scene = Some(s);
    let js = serde_json::to_vec(&b.root).map_err(|e| parse_err!("GLB: {e}"))?;
    join_glb(js, &b.bin)
}
