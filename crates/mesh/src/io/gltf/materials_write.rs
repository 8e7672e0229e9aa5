//! Writing a [`Scene`] as one GLB: its meshes (one primitive per material),
//! nodes with their names and transforms, and the materials, textures,
//! samplers and images the faces use, images embedded in the BIN chunk.
//!
//! Layout: per mesh, one glTF mesh with one primitive per material (in
//! the order in which the material first appears among the mesh's
//! faces), each primitive holding only its own vertices and its index
//! accessor, written by the one-mesh writer's builder (`write.rs`): plain
//! floats, or under [`GlbOptions::compress`] the same quantisation and
//! meshopt codecs as a one-mesh GLB (POSITION on one grid over every
//! mesh of every level, in mesh-local coordinates, undone by the node
//! that places the mesh: its transform composed with the grid's
//! translation and uniform scale, or, for a node with children, which
//! must not inherit the grid, a nameless child node that carries the
//! mesh and the grid's transform alone).
//! Only what is used is written (glTF-Validator reports unused objects):
//! materials some face uses, the textures those materials use, and those
//! textures' images and samplers, renumbered in their original order.
//! Each image is a plain buffer view of its unchanged bytes with its MIME
//! type (never compressed). MTL scalars with no glTF slot (`Ka`, `Ks`,
//! `Ns`, `Ni`, `illum`) go to the material's `extras.mtl`, which the
//! reader takes back.
//!
//! An LOD chain of scenes ([`write_scene_lod_glb`]) shares the tables and
//! gives each level one root node over a copy of its node tree, linked as
//! the one-mesh chain is (`MSFT_lod` on level 0, see `write_lod_glb`).
//! Deterministic: the same scene always gives the same bytes.

use std::collections::BTreeMap;

use glam::{Mat4, Quat, Vec3};
use gltf::json;
use json::validation::Checked::Valid;

use super::lod_links::check_coverage;
use super::write::{Builder, GlbOptions, Quantise, union_box};
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

/// One level of a scene LOD chain for [`write_scene_lod_glb`].
#[derive(Clone, Debug)]
pub struct SceneLodLevel<'a> {
    /// The level's root node name (`NAME_LOD0`, `NAME_LOD1`, …).
    pub name: String,
    /// The level; every level has the same material, texture, image and
    /// sampler tables.
    pub scene: &'a Scene,
    /// The root node's `extras` (an object; the writer adds `triangles`
    /// and `vertices`, summed over the level's meshes).
    pub extras: serde_json::Map<String, serde_json::Value>,
    /// The smallest screen coverage at which this level is to be shown
    /// (`MSFT_screencoverage`, in `[0, 1]`; lowered where needed as
    /// [`LodLevel::coverage`](super::LodLevel::coverage) is).
    pub coverage: f64,
}

/// The written material and texture numbering shared by every level.
struct Tables {
    mat_new: Vec<Option<u32>>,
}

/// A builder over the levels' common grid with the tables the levels use
/// written: samplers, images, textures, materials (in that order).
fn start(
    scenes: &[&Scene],
    opts: &GlbOptions,
    grid: Option<Quantise>,
) -> Result<(Builder, Tables), ParseError> {
    let first = scenes[0];
    for s in scenes {
        s.validate()?;
        if s.materials != first.materials
            || s.textures != first.textures
            || s.images != first.images
            || s.samplers != first.samplers
        {
            return Err(ParseError::new(
                "GLB: the levels' material, texture, image or sampler tables differ",
            ));
        }
    }
    let bbox = union_box(
        scenes
            .iter()
            .flat_map(|s| s.meshes.iter().map(|m| m.mesh.positions.as_slice())),
    );
    let mut b = Builder::new(opts, Some(bbox))?;
    if grid.is_some() {
        b.quantise = grid;
    }
    // What is used: materials by faces of meshes with UVs or not; textures
    // only by materials on meshes with UVs.
    let mut mat_used = vec![false; first.materials.len()];
    let mut mat_uv = vec![false; first.materials.len()];
    for sm in scenes.iter().flat_map(|s| &s.meshes) {
        for &f in &sm.face_materials {
            if f != NO_MATERIAL {
                mat_used[f as usize] = true;
                mat_uv[f as usize] |= sm.mesh.uvs.is_some();
            }
        }
    }
    let mut tex_used = vec![false; first.textures.len()];
    for (i, m) in first.materials.iter().enumerate() {
        if mat_uv[i] {
            for r in m.texture_refs() {
                tex_used[r.texture] = true;
            }
        }
    }
    let mut img_used = vec![false; first.images.len()];
    let mut smp_used = vec![false; first.samplers.len()];
    for (i, t) in first.textures.iter().enumerate() {
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
    for (i, s) in first.samplers.iter().enumerate() {
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
    for (i, im) in first.images.iter().enumerate() {
        if img_used[i] {
            let view = b.raw_view(&im.bytes);
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
    for (i, t) in first.textures.iter().enumerate() {
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
    for (i, m) in first.materials.iter().enumerate() {
        if mat_used[i] {
            let j = material_json(m, &tex_new, mat_uv[i])?;
            b.root.materials.push(j);
        }
    }
    Ok((b, Tables { mat_new }))
}

/// A node's transform fields (`matrix`, `translation`, `rotation`,
/// `scale`), each `None` where it is the identity's.
type NodeTransform = (
    Option<[f32; 16]>,
    Option<[f32; 3]>,
    Option<json::scene::UnitQuaternion>,
    Option<[f32; 3]>,
);

/// `t` followed (on the mesh side) by the grid's translation `origin` and
/// uniform scale `step`, as node fields; `None` grid: `t` alone. TRS stays
/// TRS (`T R S · T(o) S(k) = T(t + R(s∘o)) R S(s·k)`), a matrix stays a
/// matrix.
fn node_transform(t: &Transform, grid: Option<(Vec3, f32)>) -> NodeTransform {
    let t = if t.is_identity() {
        Transform::IDENTITY
    } else {
        *t
    };
    match (t, grid) {
        (Transform::Matrix(m), Some((o, k))) => {
            let d = Mat4::from_scale_rotation_translation(Vec3::splat(k), Quat::IDENTITY, o);
            (
                Some((Mat4::from_cols_array(&m) * d).to_cols_array()),
                None,
                None,
                None,
            )
        }
        (Transform::Matrix(m), None) => (Some(m), None, None, None),
        (
            Transform::Trs {
                translation,
                rotation,
                scale,
            },
            grid,
        ) => {
            let (t, s) = match grid {
                Some((o, k)) => {
                    let s = Vec3::from(scale);
                    let t = Vec3::from(translation) + Quat::from_array(rotation) * (s * o);
                    (t.to_array(), (s * k).to_array())
                }
                None => (translation, scale),
            };
            (
                None,
                (t != [0.0; 3]).then_some(t),
                (rotation != [0.0, 0.0, 0.0, 1.0]).then_some(json::scene::UnitQuaternion(rotation)),
                (s != [1.0; 3]).then_some(s),
            )
        }
    }
}

/// Writes `scene`'s meshes and nodes into `b` (tables already written by
/// [`start`]); returns its root nodes.
fn add_scene(
    b: &mut Builder,
    tables: &Tables,
    scene: &Scene,
) -> Result<Vec<json::Index<json::Node>>, ParseError> {
    let mut mesh_index = Vec::with_capacity(scene.meshes.len());
    for (mi, sm) in scene.meshes.iter().enumerate() {
        let m = &sm.mesh;
        if m.faces.is_empty() {
            return Err(parse_err!("GLB: mesh {mi} has no faces"));
        }
        let label = sm.name.clone().unwrap_or_else(|| format!("mesh {mi}"));
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
            let mut prim = b.primitive(&label, &sub)?;
            prim.material = (id != NO_MATERIAL)
                .then(|| tables.mat_new[id as usize])
                .flatten()
                .map(json::Index::new);
            primitives.push(prim);
        }
        mesh_index.push(b.root.push(json::Mesh {
            extensions: None,
            extras: None,
            name: sm.name.clone(),
            primitives,
            weights: None,
        }));
    }
    let grid = b.quantise.map(|q| (q.origin, q.step));
    let base = b.root.nodes.len();
    // Nameless nodes that carry a quantised mesh under a node with
    // children (so the children do not inherit the grid), after the
    // scene's own nodes.
    let mut carriers: Vec<json::Node> = Vec::new();
    for n in &scene.nodes {
        let carried = grid.is_some() && n.mesh.is_some() && !n.children.is_empty();
        let (matrix, translation, rotation, scale) = node_transform(
            &n.transform,
            if carried {
                None
            } else {
                grid.filter(|_| n.mesh.is_some())
            },
        );
        let mut children: Vec<json::Index<json::Node>> = n
            .children
            .iter()
            .map(|&c| json::Index::new((base + c) as u32))
            .collect();
        let mut mesh = n.mesh.map(|m| mesh_index[m]);
        if carried {
            children.push(json::Index::new(
                (base + scene.nodes.len() + carriers.len()) as u32,
            ));
            let (matrix, translation, rotation, scale) = node_transform(&Transform::IDENTITY, grid);
            carriers.push(json::Node {
                camera: None,
                children: None,
                extensions: None,
                extras: None,
                matrix,
                mesh: mesh.take(),
                name: None,
                rotation,
                scale,
                translation,
                skin: None,
                weights: None,
            });
        }
        b.root.nodes.push(json::Node {
            camera: None,
            children: (!children.is_empty()).then_some(children),
            extensions: None,
            extras: None,
            matrix,
            mesh,
            name: n.name.clone(),
            rotation,
            scale,
            translation,
            skin: None,
            weights: None,
        });
    }
    b.root.nodes.extend(carriers);
    Ok(scene
        .roots
        .iter()
        .map(|&r| json::Index::new((base + r) as u32))
        .collect())
}

/// Writes `scene` as one GLB, uncompressed (see the module docs for the
/// layout): [`write_scene_glb_with`] with default options.
pub fn write_scene_glb(scene: &Scene) -> Result<Vec<u8>, ParseError> {
    write_scene_glb_with(scene, &GlbOptions::default())
}

/// Writes `scene` as one GLB (see the module docs for the layout), plain
/// or compressed (`opts.compress`: `KHR_mesh_quantization` +
/// `EXT_meshopt_compression`, as for one mesh; images stay as stored).
///
/// Errors: a scene that breaks [`Scene::validate`], a mesh with no faces,
/// a sampler value that is not a glTF enum, more data than a GLB holds
/// (4 GiB), `compress` without the `meshopt` feature. Cost: one pass over
/// the geometry plus a copy of each image (compressing: plus
/// meshoptimizer's reordering and codecs, linear).
pub fn write_scene_glb_with(scene: &Scene, opts: &GlbOptions) -> Result<Vec<u8>, ParseError> {
    write_scene_with_quantise(scene, opts, None)
}

/// [`write_scene_glb_with`] with positions quantised as `grid` says (a
/// shared grid resolved for this file: `super::grid`), or as the options
/// say when `None`.
pub(super) fn write_scene_with_quantise(
    scene: &Scene,
    opts: &GlbOptions,
    grid: Option<Quantise>,
) -> Result<Vec<u8>, ParseError> {
    let (mut b, tables) = start(&[scene], opts, grid)?;
    let roots = add_scene(&mut b, &tables, scene)?;
    b.finish(roots, Vec::new())
}

/// Writes an LOD chain of scenes as one GLB that engines read as one
/// object: one root node per level, named [`SceneLodLevel::name`], whose
/// children are a copy of that level's root nodes (meshes, nodes, names
/// and transforms as [`write_scene_glb_with`] writes them; the tables
/// written once). Level 0's root node is the scene's only root and
/// carries `MSFT_lod` over the other levels' root nodes (finest first)
/// and `extras.MSFT_screencoverage` (the levels' coverages, made strictly
/// decreasing by their triangle counts:
/// [`screen_coverages`](super::screen_coverages)); the other levels are outside the scene, so a loader
/// without `MSFT_lod` shows level 0 alone. Root node extras are
/// [`SceneLodLevel::extras`] plus `triangles` and `vertices`.
///
/// Errors: no levels, levels whose tables differ, a coverage outside
/// `[0, 1]`, and those of [`write_scene_glb_with`].
pub fn write_scene_lod_glb(
    levels: &[SceneLodLevel<'_>],
    opts: &GlbOptions,
) -> Result<Vec<u8>, ParseError> {
    if levels.is_empty() {
        return Err(ParseError::new("GLB: no levels to write"));
    }
    for l in levels {
        check_coverage(&l.name, l.coverage)?;
    }
    let scenes: Vec<&Scene> = levels.iter().map(|l| l.scene).collect();
    let (mut b, tables) = start(&scenes, opts, None)?;
    let mut wrappers = Vec::with_capacity(levels.len());
    for l in levels {
        let roots = add_scene(&mut b, &tables, l.scene)?;
        let mut extras = l.extras.clone();
        extras.insert("triangles".into(), l.scene.face_count().into());
        let vertices: usize = l.scene.meshes.iter().map(|m| m.mesh.positions.len()).sum();
        extras.insert("vertices".into(), vertices.into());
        let extras = serde_json::value::to_raw_value(&serde_json::Value::Object(extras))
            .map_err(|e| parse_err!("GLB: {e}"))?;
        wrappers.push(b.root.push(json::Node {
            camera: None,
            children: (!roots.is_empty()).then_some(roots),
            extensions: None,
            extras: Some(extras),
            matrix: None,
            mesh: None,
            name: Some(l.name.clone()),
            rotation: None,
            scale: None,
            translation: None,
            skin: None,
            weights: None,
        }));
    }
    let coverage: Vec<f64> = levels.iter().map(|l| l.coverage).collect();
    let triangles: Vec<usize> = levels.iter().map(|l| l.scene.face_count()).collect();
    let ext = b.link_lods(&wrappers, &coverage, &triangles)?;
    b.finish(vec![wrappers[0]], ext)
}
