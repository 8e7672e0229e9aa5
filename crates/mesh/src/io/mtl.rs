//! OBJ + MTL as a [`Scene`]: reading an OBJ with its material libraries and
//! texture files, and writing a scene as OBJ + MTL (+ texture files).
//!
//! **Reading** ([`read_scene`]): the OBJ is checked and parsed as
//! [`super::obj::read`] does; each `mtllib` is resolved against the OBJ's
//! folder with [`crate::io::input::resolve_inside`] (relative, inside the
//! folder) and parsed by `tobj`. Objects (`o`/`g` names) become one
//! [`SceneMesh`] and one node each, in order of first appearance; each
//! face gets the material of its `usemtl`. MTL → PBR material:
//! - `Kd` → base colour, `d` (or `1 − Tr`) → its alpha (`Blend` when < 1),
//!   `map_Kd` → base colour texture;
//! - `Ke` / `map_Ke` → emissive; `norm`, `bump`, `map_Bump` → normal map;
//! - `Pm` / `Pr` → metallic / roughness (defaults 0 and 1: an MTL material
//!   is not metal);
//! - `Ka`, `Ks`, `Ns`, `Ni`, `illum`, `map_Ks`, `map_Ns`, `map_d` are kept
//!   in [`crate::scene::MtlExtras`] for OBJ output.
//!
//! Texture paths may carry MTL options (`-bm 0.5 file.png`: the last word
//! is the file). Each distinct file is read once (one image, one texture,
//! no sampler: repeat). A missing `.mtl`, an unknown material name, or a
//! texture that is missing, escapes the folder, or is neither PNG nor
//! JPEG is not an error: the slot is dropped and a warning recorded
//! ([`Scene::warnings`]).
//!
//! **Writing** ([`write_scene`]): every placed mesh in world space, one `o`
//! per node, faces grouped by material with `usemtl`; the MTL holds the
//! used materials (`Kd`, `d`, `Ke`, `Pr`, `Pm`, the kept MTL values, and
//! `map_Kd`, `map_Bump`, `map_Ke`, `map_Ks`, `map_Ns`, `map_d` naming the
//! image files). Vertex colours are written only when every mesh has them
//! (OBJ's `v` lines must agree).

use std::cell::RefCell;
use std::collections::BTreeMap;
use std::io::Write;
use std::path::Path;

use glam::Mat4;

use crate::error::{ParseError, clip};
use crate::parse_err;
use crate::scene::{
    AlphaMode, Image, Material, MtlExtras, NO_MATERIAL, Node, Scene, SceneMesh, Texture,
    TextureRef, image_mime,
};

/// The file named by an MTL map statement's value (options dropped).
fn map_file(value: &str) -> &str {
    let v = value.trim();
    if v.starts_with('-') {
        v.split_whitespace().last().unwrap_or(v)
    } else {
        v
    }
}

/// Reads texture files once each and hands out texture indices: a file
/// named several ways (`a.png`, `./a.png`, through a link) is one image,
/// keyed by its real path.
struct Textures<'a> {
    dir: Option<&'a Path>,
    by_name: BTreeMap<String, Option<usize>>,
    by_path: BTreeMap<std::path::PathBuf, usize>,
}

impl Textures<'_> {
    fn get(&mut self, value: Option<&str>, scene: &mut Scene) -> Option<usize> {
        let name = map_file(value?).to_owned();
        if let Some(&t) = self.by_name.get(&name) {
            return t;
        }
        let t = self.load(&name, scene);
        self.by_name.insert(name, t);
        t
    }

    fn load(&mut self, name: &str, scene: &mut Scene) -> Option<usize> {
        let shown = clip(name, 64);
        let Some(dir) = self.dir else {
            scene.warnings.push(format!(
                "texture '{shown}' skipped: no folder to resolve it against"
            ));
            return None;
        };
        let path = match crate::io::input::resolve_inside(dir, name) {
            Ok(p) => p,
            Err(why) => {
                scene.warnings.push(format!("texture {why}: skipped"));
                return None;
            }
        };
        let real = crate::io::input::real_path(&path);
        if let Some(&t) = self.by_path.get(&real) {
            return Some(t);
        }
        let bytes = match crate::io::input::read_file(&path) {
            Ok(b) => b,
            Err(e) => {
                scene.warnings.push(format!("texture skipped: {e}"));
                return None;
            }
        };
        let Some(mime) = image_mime(&bytes) else {
            scene.warnings.push(format!(
                "texture '{shown}' skipped: neither PNG, JPEG, WebP nor KTX2, which glTF cannot hold"
            ));
            return None;
        };
        scene.images.push(Image {
            name: None,
            file_name: name.rsplit('/').next().map(str::to_owned),
            mime_type: mime.to_owned(),
            bytes,
        });
        scene.textures.push(Texture {
            name: None,
            image: scene.images.len() - 1,
            sampler: None,
        });
        self.by_path.insert(real, scene.textures.len() - 1);
        Some(scene.textures.len() - 1)
    }
}

/// The first number of an MTL value (`None` when absent or not a number);
/// an infinite or NaN number is an error (`1e39` in an `f32` is infinite).
fn float(m: &tobj::Material, key: &str) -> Result<Option<f32>, ParseError> {
    let x = m
        .unknown_param
        .get(key)
        .and_then(|s| s.split_whitespace().next()?.parse::<f32>().ok());
    finite(m, key, x.map(|x| [x]).as_ref()).map(|_| x)
}

/// `v` unchanged when every value is finite, else an error naming the
/// material and the statement.
fn finite<const N: usize>(
    m: &tobj::Material,
    key: &str,
    v: Option<&[f32; N]>,
) -> Result<Option<[f32; N]>, ParseError> {
    match v {
        Some(c) if !c.iter().all(|x| x.is_finite()) => Err(parse_err!(
            "MTL material '{}': {key} {c:?} is not a finite number",
            clip(&m.name, 64)
        )),
        v => Ok(v.copied()),
    }
}

fn material(
    m: &tobj::Material,
    tex: &mut Textures,
    scene: &mut Scene,
) -> Result<Material, ParseError> {
    let p = &m.unknown_param;
    // A colour factor outside [0, 1] means nothing in glTF's PBR model and
    // is refused by its readers: clamped here, as MTL has no range rule.
    let kd = finite(m, "Kd", m.diffuse.as_ref())?
        .unwrap_or([1.0; 3])
        .map(|x| x.clamp(0.0, 1.0));
    let d = finite(m, "d", m.dissolve.map(|d| [d]).as_ref())?.map(|[d]| d);
    let alpha = d
        .or(float(m, "Tr")?.map(|t| 1.0 - t))
        .unwrap_or(1.0)
        .clamp(0.0, 1.0);
    let tref = |t: Option<usize>| t.map(TextureRef::new);
    let normal = m
        .normal_texture
        .as_deref()
        .or(p.get("norm").map(String::as_str));
    Ok(Material {
        name: Some(m.name.clone()),
        base_color: [kd[0], kd[1], kd[2], alpha],
        base_color_texture: tref(tex.get(m.diffuse_texture.as_deref(), scene)),
        metallic: float(m, "Pm")?.unwrap_or(0.0).clamp(0.0, 1.0),
        roughness: float(m, "Pr")?.unwrap_or(1.0).clamp(0.0, 1.0),
        normal_texture: tref(tex.get(normal, scene)),
        emissive: finite(m, "Ke", m.emissive.as_ref())?
            .unwrap_or([0.0; 3])
            .map(|x| x.clamp(0.0, 1.0)),
        emissive_texture: tref(tex.get(p.get("map_Ke").map(String::as_str), scene)),
        alpha_mode: if alpha < 1.0 {
            AlphaMode::Blend
        } else {
            AlphaMode::Opaque
        },
        mtl: MtlExtras {
            ambient: finite(m, "Ka", m.ambient.as_ref())?,
            specular: finite(m, "Ks", m.specular.as_ref())?,
            shininess: finite(m, "Ns", m.shininess.map(|x| [x]).as_ref())?.map(|[x]| x),
            optical_density: finite(m, "Ni", m.optical_density.map(|x| [x]).as_ref())?.map(|[x]| x),
            illum: m.illumination_model,
            specular_texture: tex.get(m.specular_texture.as_deref(), scene),
            shininess_texture: tex.get(m.shininess_texture.as_deref(), scene),
            dissolve_texture: tex.get(m.dissolve_texture.as_deref(), scene),
        },
        ..Default::default()
    })
}

/// Reads an OBJ and its MTL files as a scene (see the module docs).
/// `base_dir` (the OBJ's folder) resolves `mtllib` and texture files;
/// `None` reads the geometry with no materials. Errors: as
/// [`super::obj::read`].
pub fn read_scene(bytes: &[u8], base_dir: Option<&Path>) -> Result<Scene, ParseError> {
    read_scene_with(bytes, base_dir, &|name| {
        let dir = base_dir.ok_or("no folder to resolve it against")?;
        let path = crate::io::input::resolve_inside(dir, name)?;
        crate::io::input::read_file(&path).map_err(|e| e.to_string())
    })
}

/// [`read_scene`] of an OBJ whose every `mtllib` reads as `mtl`, with no
/// folder (so no texture file is read): the fuzz target's entry.
#[doc(hidden)]
pub fn read_scene_for_fuzzing(obj: &[u8], mtl: &[u8]) -> Result<Scene, ParseError> {
    read_scene_with(obj, None, &|_| Ok(mtl.to_vec()))
}

/// [`read_scene`] with `library` giving the bytes of an `mtllib` name
/// (or why it cannot).
fn read_scene_with(
    bytes: &[u8],
    base_dir: Option<&Path>,
    library: &dyn Fn(&str) -> Result<Vec<u8>, String>,
) -> Result<Scene, ParseError> {
    let bytes = crate::io::input::strip_bom(bytes);
    let text = std::str::from_utf8(bytes)
        .map_err(|e| parse_err!("not a text file: invalid UTF-8 at byte {}", e.valid_up_to()))?;
    let scan = super::obj::prescan(text)?;
    let text = super::obj::rewritten(text, &scan);
    let opts = tobj::LoadOptions {
        triangulate: true,
        single_index: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let warnings = RefCell::new(Vec::new());
    let (models, materials) = tobj::load_obj_buf(&mut text.as_bytes(), &opts, |p| {
        let name = p.to_string_lossy();
        let shown = clip(&name, 64).to_string();
        let fail = |why: String| {
            warnings
                .borrow_mut()
                .push(format!("material library '{shown}' skipped: {why}"));
            Err(tobj::LoadError::OpenFileFailed)
        };
        match library(&name) {
            Ok(b) => tobj::load_mtl_buf(&mut b.as_slice()).or_else(|e| fail(e.to_string())),
            Err(why) => fail(why),
        }
    })
    .map_err(|e| parse_err!("OBJ: {e}"))?;
    let mut scene = Scene {
        warnings: warnings.into_inner(),
        ..Default::default()
    };
    let mut tex = Textures {
        dir: base_dir,
        by_name: BTreeMap::new(),
        by_path: BTreeMap::new(),
    };
    for m in materials.unwrap_or_default() {
        let mat = material(&m, &mut tex, &mut scene)?;
        scene.materials.push(mat);
    }
    // Objects by name, in order of first appearance.
    let mut names: Vec<&str> = Vec::new();
    for m in &models {
        if !names.contains(&m.name.as_str()) {
            names.push(&m.name);
        }
    }
    for name in names {
        let group: Vec<tobj::Model> = models
            .iter()
            .filter(|m| m.name == name && !m.mesh.indices.is_empty())
            .cloned()
            .collect();
        if group.is_empty() {
            continue;
        }
        let mesh = super::obj::merge(&group)?;
        let mut face_materials = Vec::with_capacity(mesh.faces.len());
        for m in &group {
            let id = m
                .mesh
                .material_id
                .filter(|&i| i < scene.materials.len())
                .map_or(NO_MATERIAL, |i| i as u32);
            face_materials.extend(std::iter::repeat_n(id, m.mesh.indices.len() / 3));
        }
        let name = (!name.is_empty() && name != "unnamed_object").then(|| name.to_owned());
        scene.nodes.push(Node {
            name: name.clone(),
            mesh: Some(scene.meshes.len()),
            ..Default::default()
        });
        scene.roots.push(scene.nodes.len() - 1);
        scene.meshes.push(SceneMesh {
            name,
            mesh,
            face_materials,
        });
    }
    if scene.meshes.is_empty() {
        return Err(ParseError::new("no faces"));
    }
    scene.validate()?;
    Ok(scene)
}

/// A name safe on one MTL/OBJ line (no line breaks, no surrounding space).
fn line_safe(s: &str) -> String {
    let t: String = s
        .chars()
        .map(|c| if c.is_control() { '_' } else { c })
        .collect();
    let t = t.trim();
    if t.is_empty() {
        "_".into()
    } else {
        t.to_owned()
    }
}

/// The OBJ and MTL texts of `scene`: `mtl_name` is the MTL file's name for
/// `mtllib`, `image_files[i]` the file name written for image `i` (when it
/// is used). Returns (OBJ bytes, MTL bytes or `None` without materials).
pub fn write_scene(
    scene: &Scene,
    mtl_name: &str,
    image_files: &[Option<String>],
) -> std::io::Result<(Vec<u8>, Option<Vec<u8>>)> {
    let inst = scene.instances();
    let mut used = vec![false; scene.materials.len()];
    for (m, _) in &inst {
        for &f in &scene.meshes[*m].face_materials {
            if f != NO_MATERIAL {
                used[f as usize] = true;
            }
        }
    }
    // Unique material names, in table order.
    let mut names: Vec<String> = Vec::with_capacity(used.len());
    for (i, m) in scene.materials.iter().enumerate() {
        let base = m
            .name
            .as_deref()
            .map(line_safe)
            .unwrap_or_else(|| format!("material_{i}"));
        let mut n = base.clone();
        let mut k = 1;
        while names.contains(&n) {
            n = format!("{base}_{k}");
            k += 1;
        }
        names.push(n);
    }
    let all = |f: &dyn Fn(&crate::mesh::TriMesh) -> bool| {
        inst.iter().all(|(m, _)| f(&scene.meshes[*m].mesh))
    };
    let colors = all(&|m| m.colors.is_some());
    let vcount: usize = inst
        .iter()
        .map(|(m, _)| scene.meshes[*m].mesh.positions.len())
        .sum();
    let fcount: usize = inst
        .iter()
        .map(|(m, _)| scene.meshes[*m].mesh.faces.len())
        .sum();
    let mut out = Vec::new();
    writeln!(out, "# lodkit OBJ: {vcount} vertices, {fcount} faces")?;
    let any_mtl = used.iter().any(|&u| u);
    if any_mtl {
        writeln!(out, "mtllib {mtl_name}")?;
    }
    let (mut nv, mut nt, mut nn) = (0u64, 0u64, 0u64);
    for (k, (mi, world)) in inst.iter().enumerate() {
        let sm = &scene.meshes[*mi];
        let m = &sm.mesh;
        let node_name = sm.name.as_deref().map(line_safe);
        writeln!(
            out,
            "o {}",
            node_name.unwrap_or_else(|| format!("mesh_{k}"))
        )?;
        let m3 = glam::Mat3::from_mat4(*world);
        let mirrored = m3.determinant() < 0.0;
        for (i, p) in m.positions.iter().enumerate() {
            let p = world.transform_point3(*p);
            write!(out, "v {} {} {}", p.x, p.y, p.z)?;
            if let (true, Some(c)) = (colors, &m.colors) {
                let f = |x: u8| x as f32 / 255.0;
                write!(out, " {} {} {}", f(c[i][0]), f(c[i][1]), f(c[i][2]))?;
            }
            out.push(b'\n');
        }
        if let Some(uvs) = &m.uvs {
            for t in uvs {
                writeln!(out, "vt {} {}", t.x, t.y)?;
            }
        }
        if let Some(normals) = &m.normals {
            let cof = glam::Mat3::from_cols(
                m3.y_axis.cross(m3.z_axis),
                m3.z_axis.cross(m3.x_axis),
                m3.x_axis.cross(m3.y_axis),
            ) * if mirrored { -1.0 } else { 1.0 };
            for n in normals {
                let n = if *world == Mat4::IDENTITY {
                    *n
                } else {
                    (cof * *n).normalize_or_zero()
                };
                writeln!(out, "vn {} {} {}", n.x, n.y, n.z)?;
            }
        }
        let (uv, nrm) = (m.uvs.is_some(), m.normals.is_some());
        let mut order: Vec<u32> = Vec::new();
        for &id in &sm.face_materials {
            if !order.contains(&id) {
                order.push(id);
            }
        }
        for id in order {
            if id != NO_MATERIAL {
                writeln!(out, "usemtl {}", names[id as usize])?;
            } else if any_mtl {
                // Faces without a material after faces with one.
                writeln!(out, "usemtl default")?;
            }
            for (f, _) in m
                .faces
                .iter()
                .zip(&sm.face_materials)
                .filter(|(_, x)| **x == id)
            {
                let f = if mirrored { [f[0], f[2], f[1]] } else { *f };
                out.push(b'f');
                for i in f {
                    let i = i as u64;
                    let (v, t, n) = (nv + i + 1, nt + i + 1, nn + i + 1);
                    match (uv, nrm) {
                        (false, false) => write!(out, " {v}")?,
                        (true, false) => write!(out, " {v}/{t}")?,
                        (false, true) => write!(out, " {v}//{n}")?,
                        (true, true) => write!(out, " {v}/{t}/{n}")?,
                    }
                }
                out.push(b'\n');
            }
        }
        nv += m.positions.len() as u64;
        if uv {
            nt += m.positions.len() as u64;
        }
        if nrm {
            nn += m.positions.len() as u64;
        }
    }
    if !any_mtl {
        return Ok((out, None));
    }
    let mut mtl = Vec::new();
    writeln!(mtl, "# lodkit MTL")?;
    let file = |t: Option<usize>| {
        t.and_then(|t| image_files.get(scene.textures[t].image).cloned().flatten())
    };
    for (i, m) in scene.materials.iter().enumerate() {
        if !used[i] {
            continue;
        }
        writeln!(mtl, "newmtl {}", names[i])?;
        let [r, g, b, a] = m.base_color;
        let x = &m.mtl;
        if let Some([r, g, b]) = x.ambient {
            writeln!(mtl, "Ka {r} {g} {b}")?;
        }
        writeln!(mtl, "Kd {r} {g} {b}")?;
        if let Some([r, g, b]) = x.specular {
            writeln!(mtl, "Ks {r} {g} {b}")?;
        }
        if let Some(ns) = x.shininess {
            writeln!(mtl, "Ns {ns}")?;
        }
        if let Some(ni) = x.optical_density {
            writeln!(mtl, "Ni {ni}")?;
        }
        if a != 1.0 {
            writeln!(mtl, "d {a}")?;
        }
        if let Some(il) = x.illum {
            writeln!(mtl, "illum {il}")?;
        }
        if m.emissive != [0.0; 3] {
            let [r, g, b] = m.emissive;
            writeln!(mtl, "Ke {r} {g} {b}")?;
        }
        writeln!(mtl, "Pr {}", m.roughness)?;
        writeln!(mtl, "Pm {}", m.metallic)?;
        let maps = [
            ("map_Kd", m.base_color_texture.map(|t| t.texture)),
            ("map_Ks", x.specular_texture),
            ("map_Ns", x.shininess_texture),
            ("map_d", x.dissolve_texture),
            ("map_Bump", m.normal_texture.map(|t| t.texture)),
            ("map_Ke", m.emissive_texture.map(|t| t.texture)),
        ];
        for (key, t) in maps {
            if let Some(f) = file(t) {
                writeln!(mtl, "{key} {f}")?;
            }
        }
        mtl.push(b'\n');
    }
    Ok((out, Some(mtl)))
}

/// The images an OBJ output refers to: those of the textures that used
/// materials name in a slot OBJ writes.
pub fn used_images(scene: &Scene) -> Vec<bool> {
    let mut mat = vec![false; scene.materials.len()];
    for (m, _) in scene.instances() {
        for &f in &scene.meshes[m].face_materials {
            if f != NO_MATERIAL {
                mat[f as usize] = true;
            }
        }
    }
    let mut img = vec![false; scene.images.len()];
    for (i, m) in scene.materials.iter().enumerate() {
        if !mat[i] {
            continue;
        }
        let x = &m.mtl;
        let slots = [
            m.base_color_texture.map(|t| t.texture),
            x.specular_texture,
            x.shininess_texture,
            x.dissolve_texture,
            m.normal_texture.map(|t| t.texture),
            m.emissive_texture.map(|t| t.texture),
        ];
        for t in slots.into_iter().flatten() {
            img[scene.textures[t].image] = true;
        }
    }
    img
}
