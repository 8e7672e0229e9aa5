//! Scenes: meshes with their materials, textures and nodes, beside
//! [`TriMesh`].
//!
//! A [`Scene`] is what a textured or multi-part file holds once decoded:
//! several meshes, each a plain [`TriMesh`] plus one material id per face
//! ([`SceneMesh`]), placed by a node hierarchy ([`Node`]), and the
//! material, texture, image and sampler tables they refer to (the glTF 2.0
//! model, which OBJ + MTL and PLY's `TextureFile` map onto).
//!
//! Why beside `TriMesh` and not inside it: every crate builds `TriMesh`
//! literals, and every stage (welding, simplification, marching cubes,
//! metrics) works on one mesh of geometry and per-vertex attributes. A
//! per-face material id array next to the mesh keeps all of that
//! unchanged, and the stages that must know about materials (the
//! simplifier's material seams, the scene readers and writers) take the
//! pair.
//!
//! Invariants ([`Scene::validate`]): every mesh passes
//! [`TriMesh::validate`] and has one material id per face, each
//! [`NO_MATERIAL`] or `< materials.len()`; every index (texture → image and
//! sampler, material → texture, node → mesh and children) is in range; the
//! node graph is a forest (no cycle, no node with two parents).
//!
//! Images are kept as the file stored them (PNG / JPEG bytes, never decoded
//! or re-encoded), so a round trip through lodkit gives the same image
//! bytes back.

use glam::Mat4;

use crate::error::ParseError;
use crate::mesh::TriMesh;
use crate::parse_err;

/// The material id of a face without a material.
pub const NO_MATERIAL: u32 = u32::MAX;

/// Meshes, materials and the nodes that place them (see the module docs).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Scene {
    /// The meshes, each with one material id per face.
    pub meshes: Vec<SceneMesh>,
    /// The nodes; `roots` lists the top-level ones.
    pub nodes: Vec<Node>,
    /// Indices of the nodes of the scene's top level, in order.
    pub roots: Vec<usize>,
    /// The materials faces refer to.
    pub materials: Vec<Material>,
    /// Textures: an image and how to sample it.
    pub textures: Vec<Texture>,
    /// Encoded images (PNG, JPEG…), as stored in the input.
    pub images: Vec<Image>,
    /// Texture samplers (filters and wrapping).
    pub samplers: Vec<Sampler>,
    /// Problems that did not stop reading (a texture file that is missing,
    /// an unknown material name), one line each, for the caller to show.
    pub warnings: Vec<String>,
}

/// One mesh of a scene: geometry plus a material id per face.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SceneMesh {
    /// The mesh's name, when the file gave one.
    pub name: Option<String>,
    /// The geometry and per-vertex attributes.
    pub mesh: TriMesh,
    /// One entry per face: an index into [`Scene::materials`], or
    /// [`NO_MATERIAL`].
    pub face_materials: Vec<u32>,
}

/// A node of the scene graph.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Node {
    /// The node's name, when the file gave one.
    pub name: Option<String>,
    /// The local transform, as the file stored it.
    pub transform: Transform,
    /// The mesh this node places, if any.
    pub mesh: Option<usize>,
    /// Child nodes.
    pub children: Vec<usize>,
}

/// A node's local transform, kept in the form the file used (so a glTF
/// round trip writes the same numbers).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Transform {
    /// A column-major 4×4 matrix.
    Matrix([f32; 16]),
    /// Translation, rotation (unit quaternion x, y, z, w), scale; applied
    /// scale first.
    Trs {
        /// Translation.
        translation: [f32; 3],
        /// Rotation quaternion `[x, y, z, w]`.
        rotation: [f32; 4],
        /// Scale.
        scale: [f32; 3],
    },
}

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// No translation, rotation or scale.
    pub const IDENTITY: Transform = Transform::Trs {
        translation: [0.0; 3],
        rotation: [0.0, 0.0, 0.0, 1.0],
        scale: [1.0; 3],
    };
    /// The transform as a matrix.
    pub fn matrix(&self) -> Mat4 {
        match *self {
            Transform::Matrix(m) => Mat4::from_cols_array(&m),
            Transform::Trs {
                translation,
                rotation,
                scale,
            } => Mat4::from_scale_rotation_translation(
                scale.into(),
                glam::Quat::from_array(rotation),
                translation.into(),
            ),
        }
    }
    /// Whether this is the identity (written as no transform at all).
    pub fn is_identity(&self) -> bool {
        self.matrix() == Mat4::IDENTITY
    }
}

/// How a material's alpha is used (glTF `alphaMode`).
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    #[default]
    Opaque,
    /// Alpha below the cutoff is fully transparent, above fully opaque.
    Mask,
    /// Alpha blends with what is behind.
    Blend,
}

/// A texture slot of a material: which texture and which UV set.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TextureRef {
    /// Index into [`Scene::textures`].
    pub texture: usize,
    /// Which `TEXCOORD_n` set (lodkit keeps set 0 only).
    pub tex_coord: u32,
}

impl TextureRef {
    /// Texture `texture` on UV set 0.
    pub fn new(texture: usize) -> Self {
        TextureRef {
            texture,
            tex_coord: 0,
        }
    }
}

/// A metallic-roughness PBR material (glTF 2.0), with the MTL values that
/// have no glTF slot kept beside it for OBJ output ([`MtlExtras`]).
/// Factors are linear, as in glTF.
#[derive(Debug, Clone, PartialEq)]
pub struct Material {
    /// The material's name (`newmtl` in MTL).
    pub name: Option<String>,
    /// Base colour RGBA factor (MTL `Kd` and `d`).
    pub base_color: [f32; 4],
    /// Base colour texture (MTL `map_Kd`).
    pub base_color_texture: Option<TextureRef>,
    /// Metalness factor (MTL `Pm`).
    pub metallic: f32,
    /// Roughness factor (MTL `Pr`).
    pub roughness: f32,
    /// Metallic (B) and roughness (G) texture.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// Tangent-space normal map (MTL `norm`, `bump`, `map_Bump`).
    pub normal_texture: Option<TextureRef>,
    /// Normal map scale.
    pub normal_scale: f32,
    /// Ambient occlusion texture (R).
    pub occlusion_texture: Option<TextureRef>,
    /// Occlusion strength.
    pub occlusion_strength: f32,
    /// Emissive RGB factor (MTL `Ke`).
    pub emissive: [f32; 3],
    /// Emissive texture (MTL `map_Ke`).
    pub emissive_texture: Option<TextureRef>,
    /// Alpha mode.
    pub alpha_mode: AlphaMode,
    /// Alpha cutoff of [`AlphaMode::Mask`] (glTF's default is 0.5).
    pub alpha_cutoff: Option<f32>,
    /// Whether back faces are shown.
    pub double_sided: bool,
    /// MTL values without a glTF slot.
    pub mtl: MtlExtras,
}

impl Default for Material {
    /// glTF's defaults (white, metallic 1, roughness 1, opaque).
    fn default() -> Self {
        Material {
            name: None,
            base_color: [1.0; 4],
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive: [0.0; 3],
            emissive_texture: None,
            alpha_mode: AlphaMode::Opaque,
            alpha_cutoff: None,
            double_sided: false,
            mtl: MtlExtras::default(),
        }
    }
}

impl Material {
    /// Every texture slot in use, in a fixed order.
    pub fn texture_refs(&self) -> impl Iterator<Item = TextureRef> + '_ {
        [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.normal_texture,
            self.occlusion_texture,
            self.emissive_texture,
        ]
        .into_iter()
        .flatten()
    }
}

/// MTL statements with no glTF material slot (kept for OBJ → OBJ, and in a
/// GLB material's `extras.mtl` for the scalar ones).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MtlExtras {
    /// `Ka`.
    pub ambient: Option<[f32; 3]>,
    /// `Ks`.
    pub specular: Option<[f32; 3]>,
    /// `Ns`.
    pub shininess: Option<f32>,
    /// `Ni`.
    pub optical_density: Option<f32>,
    /// `illum`.
    pub illum: Option<u8>,
    /// `map_Ks`.
    pub specular_texture: Option<usize>,
    /// `map_Ns`.
    pub shininess_texture: Option<usize>,
    /// `map_d`.
    pub dissolve_texture: Option<usize>,
}

/// A texture: an image and its sampler.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Texture {
    /// The texture's name, when the file gave one.
    pub name: Option<String>,
    /// Index into [`Scene::images`].
    pub image: usize,
    /// Index into [`Scene::samplers`]; `None` = repeat, auto filtering.
    pub sampler: Option<usize>,
}

/// An encoded image, kept byte for byte.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct Image {
    /// The image's name, when the file gave one.
    pub name: Option<String>,
    /// The file name it had (last path component of its URI or MTL path),
    /// used to name the copy beside an OBJ output.
    pub file_name: Option<String>,
    /// `image/png` or `image/jpeg` (from the bytes' signature when known).
    pub mime_type: String,
    /// The encoded bytes.
    pub bytes: Vec<u8>,
}

/// A glTF sampler: filters and wrap modes as glTF's enum values.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Sampler {
    /// Magnification filter (9728 nearest, 9729 linear), `None` = auto.
    pub mag_filter: Option<u32>,
    /// Minification filter (9728…9987), `None` = auto.
    pub min_filter: Option<u32>,
    /// Wrap mode in U (10497 repeat, 33071 clamp, 33648 mirrored).
    pub wrap_s: u32,
    /// Wrap mode in V.
    pub wrap_t: u32,
}

/// The MIME type of encoded image bytes, from their signature: PNG, JPEG,
/// WebP or KTX2; `None` when unknown.
pub fn image_mime(bytes: &[u8]) -> Option<&'static str> {
    if bytes.starts_with(b"\x89PNG\r\n\x1a\n") {
        Some("image/png")
    } else if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        Some("image/jpeg")
    } else if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        Some("image/webp")
    } else if bytes.starts_with(b"\xabKTX 20\xbb") {
        Some("image/ktx2")
    } else {
        None
    }
}

impl Scene {
    /// A scene of one mesh without materials, placed by one node.
    pub fn from_mesh(mesh: TriMesh) -> Scene {
        let faces = mesh.faces.len();
        Scene {
            meshes: vec![SceneMesh {
                name: None,
                mesh,
                face_materials: vec![NO_MATERIAL; faces],
            }],
            nodes: vec![Node {
                mesh: Some(0),
                ..Default::default()
            }],
            roots: vec![0],
            ..Default::default()
        }
    }

    /// A copy of everything but the meshes and warnings (for stages that
    /// replace the meshes and keep the rest).
    pub fn clone_tables(&self) -> Scene {
        Scene {
            meshes: Vec::new(),
            nodes: self.nodes.clone(),
            roots: self.roots.clone(),
            materials: self.materials.clone(),
            textures: self.textures.clone(),
            images: self.images.clone(),
            samplers: self.samplers.clone(),
            warnings: Vec::new(),
        }
    }

    /// Whether the scene carries anything a plain mesh would lose:
    /// materials, more than one mesh, or a node with a name or transform.
    pub fn is_plain_mesh(&self) -> bool {
        self.materials.is_empty()
            && self.meshes.len() == 1
            && self.nodes.len() == 1
            && self.nodes[0].name.is_none()
            && self.nodes[0].transform.is_identity()
            && self.meshes[0].name.is_none()
    }

    /// Total triangles over the meshes (each mesh once, however many nodes
    /// place it).
    pub fn face_count(&self) -> usize {
        self.meshes.iter().map(|m| m.mesh.faces.len()).sum()
    }

    /// Every placed mesh: (mesh index, world matrix), depth first from the
    /// roots in order.
    pub fn instances(&self) -> Vec<(usize, Mat4)> {
        let mut out = Vec::new();
        let mut stack: Vec<(usize, Mat4)> = self
            .roots
            .iter()
            .rev()
            .map(|&r| (r, Mat4::IDENTITY))
            .collect();
        while let Some((n, parent)) = stack.pop() {
            let node = &self.nodes[n];
            let world = parent * node.transform.matrix();
            if let Some(m) = node.mesh {
                out.push((m, world));
            }
            stack.extend(node.children.iter().rev().map(|&c| (c, world)));
        }
        out
    }

    /// Every instance in world space, merged into one mesh with one
    /// material id per face (what `--merge` writes). An attribute is kept
    /// only when every mesh has it, as the glTF reader does; a mirroring
    /// transform has its winding swapped.
    pub fn merged(&self) -> SceneMesh {
        let inst = self.instances();
        let all = |f: &dyn Fn(&TriMesh) -> bool| inst.iter().all(|(m, _)| f(&self.meshes[*m].mesh));
        let (has_n, has_c, has_uv) = (
            all(&|m| m.normals.is_some()),
            all(&|m| m.colors.is_some()),
            all(&|m| m.uvs.is_some()),
        );
        let mut out = TriMesh {
            normals: has_n.then(Vec::new),
            colors: has_c.then(Vec::new),
            uvs: has_uv.then(Vec::new),
            ..Default::default()
        };
        let mut mats = Vec::new();
        for (mi, world) in inst {
            let sm = &self.meshes[mi];
            let m = &sm.mesh;
            let base = out.positions.len() as u32;
            out.positions
                .extend(m.positions.iter().map(|&p| world.transform_point3(p)));
            let m3 = glam::Mat3::from_mat4(world);
            let mirrored = m3.determinant() < 0.0;
            if let (Some(dst), Some(src)) = (out.normals.as_mut(), &m.normals) {
                let cof = glam::Mat3::from_cols(
                    m3.y_axis.cross(m3.z_axis),
                    m3.z_axis.cross(m3.x_axis),
                    m3.x_axis.cross(m3.y_axis),
                ) * if mirrored { -1.0 } else { 1.0 };
                if world == Mat4::IDENTITY {
                    dst.extend_from_slice(src);
                } else {
                    dst.extend(src.iter().map(|&n| (cof * n).normalize_or_zero()));
                }
            }
            if let (Some(dst), Some(src)) = (out.colors.as_mut(), &m.colors) {
                dst.extend_from_slice(src);
            }
            if let (Some(dst), Some(src)) = (out.uvs.as_mut(), &m.uvs) {
                dst.extend_from_slice(src);
            }
            out.faces.extend(m.faces.iter().map(|&[a, b, c]| {
                let f = if mirrored { [a, c, b] } else { [a, b, c] };
                f.map(|i| base + i)
            }));
            mats.extend_from_slice(&sm.face_materials);
        }
        SceneMesh {
            name: None,
            mesh: out,
            face_materials: mats,
        }
    }

    /// Checks the invariants of the module docs; the message names the
    /// first offending element.
    pub fn validate(&self) -> Result<(), ParseError> {
        let nm = self.materials.len();
        for (i, sm) in self.meshes.iter().enumerate() {
            sm.mesh
                .validate()
                .map_err(|e| parse_err!("mesh {i}: {e}"))?;
            if sm.face_materials.len() != sm.mesh.faces.len() {
                return Err(parse_err!(
                    "mesh {i} has {} material ids for {} faces",
                    sm.face_materials.len(),
                    sm.mesh.faces.len()
                ));
            }
            if let Some(&m) = sm
                .face_materials
                .iter()
                .find(|&&m| m != NO_MATERIAL && m as usize >= nm)
            {
                return Err(parse_err!("mesh {i} uses material {m} but there are {nm}"));
            }
        }
        let nt = self.textures.len();
        for (i, m) in self.materials.iter().enumerate() {
            // Every factor finite: JSON has no infinity (a writer would put
            // `null`) and MTL's `inf` reads back as nothing.
            let mut numbers: Vec<f32> = m.base_color.to_vec();
            numbers.extend(m.emissive);
            numbers.extend([
                m.metallic,
                m.roughness,
                m.normal_scale,
                m.occlusion_strength,
            ]);
            numbers.extend(m.alpha_cutoff);
            numbers.extend(m.mtl.ambient.into_iter().flatten());
            numbers.extend(m.mtl.specular.into_iter().flatten());
            numbers.extend(m.mtl.shininess);
            numbers.extend(m.mtl.optical_density);
            if let Some(x) = numbers.iter().find(|x| !x.is_finite()) {
                return Err(parse_err!(
                    "material {i} has a factor of {x}, which is not a finite number"
                ));
            }
            let extra = [
                m.mtl.specular_texture,
                m.mtl.shininess_texture,
                m.mtl.dissolve_texture,
            ];
            let bad = m
                .texture_refs()
                .map(|t| t.texture)
                .chain(extra.into_iter().flatten())
                .find(|&t| t >= nt);
            if let Some(t) = bad {
                return Err(parse_err!(
                    "material {i} uses texture {t} but there are {nt}"
                ));
            }
        }
        for (i, t) in self.textures.iter().enumerate() {
            if t.image >= self.images.len() {
                return Err(parse_err!(
                    "texture {i} uses image {} but there are {}",
                    t.image,
                    self.images.len()
                ));
            }
            if let Some(s) = t.sampler.filter(|&s| s >= self.samplers.len()) {
                return Err(parse_err!(
                    "texture {i} uses sampler {s} but there are {}",
                    self.samplers.len()
                ));
            }
        }
        let mut parent = vec![false; self.nodes.len()];
        for (i, n) in self.nodes.iter().enumerate() {
            if let Some(m) = n.mesh.filter(|&m| m >= self.meshes.len()) {
                return Err(parse_err!(
                    "node {i} uses mesh {m} but there are {}",
                    self.meshes.len()
                ));
            }
            for &c in &n.children {
                if c >= self.nodes.len() || std::mem::replace(&mut parent[c], true) {
                    return Err(parse_err!(
                        "node {i} has child {c}, which is out of range or has another parent"
                    ));
                }
            }
        }
        for &r in &self.roots {
            if r >= self.nodes.len() || std::mem::replace(&mut parent[r], true) {
                return Err(parse_err!("scene root {r} is out of range or also a child"));
            }
        }
        // Every node reachable exactly once from the roots: no cycle.
        let mut seen = vec![false; self.nodes.len()];
        let mut stack: Vec<usize> = self.roots.clone();
        while let Some(n) = stack.pop() {
            if std::mem::replace(&mut seen[n], true) {
                return Err(parse_err!("node {n} is reached twice (a cycle)"));
            }
            stack.extend(&self.nodes[n].children);
        }
        Ok(())
    }
}
