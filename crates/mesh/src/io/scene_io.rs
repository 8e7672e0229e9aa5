//! Scenes in and out of files: [`load_scene`] and [`save_scene`].
//!
//! Which formats hold what: glTF / GLB (everything: meshes, primitives per
//! material, nodes, PBR materials, embedded or external images), OBJ + MTL
//! (objects, materials, texture files; no node transforms: placed meshes
//! are written in world space), PLY (one mesh; `comment TextureFile NAME`
//! becomes one material with that base colour texture). Any other mesh
//! format reads as a one-mesh scene without materials and is written from
//! [`Scene::merged`].

use std::path::{Path, PathBuf};

use crate::error::{Error, ParseError, Result};
use crate::mesh::Model;
use crate::scene::{Image, Material, Scene, Texture, TextureRef, image_mime};

use super::{Format, WriteOptions};

/// Reads a mesh file as a [`Scene`] (see the module docs).
///
/// Same checks and one-line errors as [`super::load`] (every mesh is
/// validated and its coordinates bounded); files a scene names (MTL,
/// textures, glTF buffers and images) are resolved inside the file's own
/// folder ([`super::input::resolve_inside`]). Problems that do not stop
/// reading (a missing texture) are in [`Scene::warnings`]. A point cloud
/// or range image is refused: a scene holds meshes. Cost: one read of the
/// file and of each file it names, plus one linear decode.
pub fn load_scene(path: &Path) -> Result<Scene> {
    let format = Format::from_path(path).ok_or_else(|| {
        Error::unsupported(
            path,
            "unknown file extension (expected .ply, .obj, .stl, .gltf, .glb, .xyz, .pts, .las or .laz)",
        )
    })?;
    let bytes = super::input::read_file(path)?;
    let dir = path.parent().map(|d| {
        if d.as_os_str().is_empty() {
            Path::new(".")
        } else {
            d
        }
    });
    let scene = match format {
        Format::Gltf | Format::Glb => super::gltf::read_scene(&bytes, dir),
        Format::Obj => super::mtl::read_scene(&bytes, dir),
        _ => match super::decode(format, &bytes, dir).map_err(|e| Error::parse(path, e))? {
            Model::Mesh(m) => {
                let mut s = Scene::from_mesh(m);
                if format == Format::Ply {
                    ply_texture(&bytes, dir, &mut s);
                }
                Ok(s)
            }
            other => {
                return Err(Error::unsupported(
                    path,
                    format!("holds a {} with no faces, a mesh is needed", other.kind()),
                ));
            }
        },
    }
    .map_err(|e| Error::parse(path, e))?;
    check_scene_coordinates(scene).map_err(|e| Error::parse(path, e))
}

/// `mesh`, read from the PLY file `path`, as a scene: with one textured
/// material when the header has `comment TextureFile NAME` (see
/// [`load_scene`]), else without materials. Reads at most the first MiB
/// of `path` again (the header); an unreadable header means no texture.
pub fn ply_scene(path: &Path, mesh: crate::mesh::TriMesh) -> Scene {
    use std::io::Read as _;
    let mut head = Vec::new();
    if let Ok(f) = std::fs::File::open(path) {
        let _ = f.take(1 << 20).read_to_end(&mut head);
    }
    let dir = path.parent().map(|d| {
        if d.as_os_str().is_empty() {
            Path::new(".")
        } else {
            d
        }
    });
    let mut s = Scene::from_mesh(mesh);
    ply_texture(&head, dir, &mut s);
    s
}

/// [`super::check_coordinates`] on every mesh of the scene.
fn check_scene_coordinates(mut scene: Scene) -> std::result::Result<Scene, ParseError> {
    for (i, sm) in scene.meshes.iter_mut().enumerate() {
        let model = Model::Mesh(std::mem::take(&mut sm.mesh));
        let r = super::check_coordinates(&model);
        if let Model::Mesh(m) = model {
            sm.mesh = m;
        }
        r.map_err(|e| crate::parse_err!("mesh {i}: {e}"))?;
    }
    Ok(scene)
}

/// PLY's `comment TextureFile NAME` (MeshLab, photogrammetry tools): the
/// texture beside the file becomes one material for every face. A file
/// that is missing or not an image is a warning.
fn ply_texture(bytes: &[u8], dir: Option<&Path>, scene: &mut Scene) {
    let end = bytes
        .windows(10)
        .position(|w| w == b"end_header")
        .unwrap_or(0);
    let header = String::from_utf8_lossy(&bytes[..end]);
    let Some(name) = header.lines().find_map(|l| {
        l.trim()
            .strip_prefix("comment")
            .map(str::trim_start)
            .and_then(|r| r.strip_prefix("TextureFile"))
            .map(str::trim)
            .filter(|n| !n.is_empty())
    }) else {
        return;
    };
    let shown = crate::error::clip(name, 64).to_string();
    let loaded = dir
        .ok_or_else(|| "no folder to resolve it against".to_string())
        .and_then(|d| super::input::resolve_inside(d, name))
        .and_then(|p| super::input::read_file(&p).map_err(|e| e.to_string()))
        .and_then(|b| match image_mime(&b) {
            Some(m) => Ok((b, m)),
            None => Err("neither PNG nor JPEG".into()),
        });
    match loaded {
        Ok((bytes, mime)) => {
            scene.images.push(Image {
                name: None,
                file_name: name.rsplit('/').next().map(str::to_owned),
                mime_type: mime.to_owned(),
                bytes,
            });
            scene.textures.push(Texture {
                image: 0,
                ..Default::default()
            });
            scene.materials.push(Material {
                name: Some("texture".into()),
                base_color_texture: Some(TextureRef::new(0)),
                metallic: 0.0,
                ..Default::default()
            });
            for f in &mut scene.meshes[0].face_materials {
                *f = 0;
            }
        }
        Err(why) => scene
            .warnings
            .push(format!("TextureFile '{shown}' skipped: {why}")),
    }
}

/// The extension of an image's MIME type.
fn image_ext(mime: &str) -> &'static str {
    match mime {
        "image/jpeg" => "jpg",
        "image/webp" => "webp",
        "image/ktx2" => "ktx2",
        _ => "png",
    }
}

/// `name` when its extension is an image's (`png`, `jpg`, `jpeg`, `webp`,
/// `ktx2`, any case), else `name.ext`: a texture copy never takes the
/// name of a mesh, material or manifest file.
fn with_image_ext(name: &str, ext: &str) -> String {
    let is_image = name.rsplit_once('.').is_some_and(|(_, e)| {
        ["png", "jpg", "jpeg", "webp", "ktx2"]
            .iter()
            .any(|k| e.eq_ignore_ascii_case(k))
    });
    if is_image {
        name.to_owned()
    } else {
        format!("{name}.{ext}")
    }
}

/// A file name with no folder part and nothing a path rule would refuse.
fn plain_file_name(name: &str) -> Option<&str> {
    let ok = !name.is_empty()
        && !name.starts_with('.')
        && !name.contains(['/', '\\', ':', '\0'])
        && !name.chars().any(char::is_control)
        && !name.contains(char::is_whitespace);
    ok.then_some(name)
}

/// Where image `bytes` go beside `dir`: `wanted` if it is free or already
/// holds these bytes, else `stem_1.ext`, `stem_2.ext`… — never a file
/// that holds other bytes (an input, another texture), never a name
/// `taken` by this run. `first` is the first suffix to try (the names
/// before it were tried for this `wanted` already). Returns the name,
/// whether it must be written, and its suffix.
fn place_image(
    dir: &Path,
    wanted: &str,
    bytes: &[u8],
    taken: &std::collections::BTreeSet<String>,
    first: u32,
) -> (String, bool, u32) {
    let (stem, ext) = match wanted.rsplit_once('.') {
        Some((s, e)) => (s.to_owned(), format!(".{e}")),
        None => (wanted.to_owned(), String::new()),
    };
    for k in first.. {
        let name = if k == 0 {
            wanted.to_owned()
        } else {
            format!("{stem}_{k}{ext}")
        };
        if taken.contains(&name) {
            continue;
        }
        let p = dir.join(&name);
        match std::fs::symlink_metadata(&p) {
            Err(_) => return (name, true, k),
            Ok(md) if md.is_file() && std::fs::read(&p).is_ok_and(|b| b == bytes) => {
                return (name, false, k);
            }
            Ok(_) => continue,
        }
    }
    unreachable!("u32 names run out only after 4 billion files")
}

/// Writes `scene` to `path` (format from the extension), atomically:
/// GLB embeds the images; OBJ writes `STEM.mtl` beside it and each used
/// texture image as a file beside it, unless a file there already holds
/// the same bytes (an input's own texture is then referenced, not
/// copied); a name that holds other bytes is never overwritten (the image
/// gets `NAME_1.png`, …). Other formats get the merged mesh
/// ([`Scene::merged`]), materials dropped. Each file is written with
/// [`super::write_atomic`]; images first, the OBJ last, so an OBJ never
/// names a file that is not there. Deterministic for the same scene and
/// folder contents.
pub fn save_scene(path: &Path, scene: &Scene, opts: WriteOptions) -> Result<()> {
    save_scene_with(path, scene, opts, &super::gltf::GlbOptions::default())
}

/// [`save_scene`] with the GLB writer's options (`glb`: compression, for
/// a `.glb` path; other formats ignore it).
pub fn save_scene_with(
    path: &Path,
    scene: &Scene,
    opts: WriteOptions,
    glb: &super::gltf::GlbOptions,
) -> Result<()> {
    let format = Format::from_path(path).ok_or_else(|| {
        Error::unsupported(
            path,
            "unknown output extension (expected .ply, .obj, .stl, .glb, .xyz or .pts)",
        )
    })?;
    match format {
        Format::Glb => {
            let bytes = super::gltf::write_scene_glb_with(scene, glb)
                .map_err(|e| Error::unsupported(path, e.0))?;
            super::write_atomic(path, &bytes)
        }
        Format::Obj => save_obj(path, scene),
        _ => super::save(path, &Model::Mesh(scene.merged().mesh), opts),
    }
}

fn save_obj(path: &Path, scene: &Scene) -> Result<()> {
    scene
        .validate()
        .map_err(|e| Error::unsupported(path, e.0))?;
    if scene.face_count() == 0 {
        return Err(Error::unsupported(
            path,
            "cannot write this mesh as OBJ: it has no faces, so the file could not be read back",
        ));
    }
    let dir: PathBuf = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "mesh".into());
    let stem_safe: String = stem
        .chars()
        .map(|c| {
            if c.is_whitespace() || c.is_control() {
                '_'
            } else {
                c
            }
        })
        .collect();
    let used = super::mtl::used_images(scene);
    let mut files: Vec<Option<String>> = vec![None; scene.images.len()];
    let mtl_name = format!("{stem_safe}.mtl");
    // The files this run writes are never a texture's name.
    let mut taken = std::collections::BTreeSet::from([mtl_name.clone()]);
    taken.extend(path.file_name().map(|n| n.to_string_lossy().into_owned()));
    // Per wanted name, the next suffix to try: many images wanting one
    // name cost one probe each, not one per earlier image.
    let mut next: std::collections::BTreeMap<String, u32> = std::collections::BTreeMap::new();
    for (i, im) in scene.images.iter().enumerate() {
        if !used[i] {
            continue;
        }
        let fallback = format!("{stem_safe}_{i}.{}", image_ext(&im.mime_type));
        let ext = image_ext(&im.mime_type);
        let wanted = im
            .file_name
            .as_deref()
            .and_then(plain_file_name)
            .map(|n| with_image_ext(n, ext))
            .unwrap_or(fallback);
        let first = next.get(&wanted).copied().unwrap_or(0);
        let (name, write, k) = place_image(&dir, &wanted, &im.bytes, &taken, first);
        next.insert(wanted, k);
        if write {
            super::write_atomic(&dir.join(&name), &im.bytes)?;
        }
        taken.insert(name.clone());
        files[i] = Some(name);
    }
    let (obj, mtl) =
        super::mtl::write_scene(scene, &mtl_name, &files).map_err(|e| Error::io(path, e))?;
    if let Some(mtl) = mtl {
        super::write_atomic(&dir.join(&mtl_name), &mtl)?;
    }
    super::write_atomic(path, &obj)
}

/// Whether faces of `scene` use any material.
pub fn has_materials(scene: &Scene) -> bool {
    scene.meshes.iter().any(|m| {
        m.face_materials
            .iter()
            .any(|&f| f != crate::scene::NO_MATERIAL)
    })
}
