//! Textured tilesets: every tile read back with its own texture, cropped
//! to its UVs and halved per level above the leaves, its UVs pointing at
//! the texels they pointed at in the source.

mod common;

use common::read_tileset;
use lodkit_mesh::TriMesh;
use lodkit_mesh::glam::{Vec2, Vec3};
use lodkit_mesh::image::decode_rgba;
use lodkit_mesh::scene::{Image, Material, Scene, Texture, TextureRef};
use lodkit_tiles::{TilesOptions, tileset_from_scene, write_tileset};

const SIDE: u32 = 512;

fn surface(x: f32, z: f32) -> f32 {
    0.05 * (6.0 * x).sin() * (4.0 * z).cos()
}

/// A gentle height field over `[0, 1]²` (x, z) with `n × n` quads, its UVs
/// the (x, z) position, so a texel's colour says where it belongs.
fn terrain(n: u32) -> TriMesh {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let (x, z) = (i as f32 / n as f32, j as f32 / n as f32);
            let y = surface(x, z);
            positions.push(Vec3::new(x, y, z));
            uvs.push(Vec2::new(x, z));
        }
    }
    let mut faces = Vec::new();
    let at = |i: u32, j: u32| j * (n + 1) + i;
    for j in 0..n {
        for i in 0..n {
            faces.push([at(i, j), at(i, j + 1), at(i + 1, j)]);
            faces.push([at(i + 1, j), at(i, j + 1), at(i + 1, j + 1)]);
        }
    }
    TriMesh {
        positions,
        uvs: Some(uvs),
        faces,
        ..Default::default()
    }
}

/// A `SIDE²` gradient: red counts columns, green rows (both /2).
fn gradient_png() -> Vec<u8> {
    let rgba = (0..SIDE * SIDE)
        .flat_map(|i| [((i % SIDE) / 2) as u8, ((i / SIDE) / 2) as u8, 128, 255])
        .collect();
    let image = lodkit_mesh::image::RgbaImage {
        width: SIDE,
        height: SIDE,
        rgba,
        has_alpha: false,
    };
    lodkit_mesh::image::encode_png(&image).unwrap()
}

fn textured_scene() -> Scene {
    let mut scene = Scene::from_mesh(terrain(96));
    scene.meshes[0]
        .face_materials
        .iter_mut()
        .for_each(|m| *m = 0);
    scene.images.push(Image {
        name: None,
        file_name: Some("gradient.png".into()),
        mime_type: "image/png".into(),
        bytes: gradient_png(),
    });
    scene.textures.push(Texture {
        name: None,
        image: 0,
        sampler: None,
    });
    scene.materials.push(Material {
        base_color_texture: Some(TextureRef::new(0)),
        ..Default::default()
    });
    scene
}

#[test]
fn every_tile_carries_the_texels_of_its_uvs_halved_per_level() {
    let scene = textured_scene();
    let source_bytes = scene.images[0].bytes.len();
    let opts = TilesOptions {
        leaf_triangles: 1_024,
        ..TilesOptions::DEFAULT
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("tiles");
    let ts = tileset_from_scene(&scene, &opts, &mut |_| {}).unwrap();
    let report = write_tileset(&ts, &out, None, &opts, &mut |_| {}).unwrap();
    assert!(report.depth >= 2, "{report:?}");
    let read = read_tileset(&out);
    // Height above the leaves of every tile read back.
    let mut height = vec![0u32; read.tiles.len()];
    for i in (0..read.tiles.len()).rev() {
        for &c in &read.tiles[i].children {
            height[i] = height[i].max(height[c] + 1);
        }
    }
    let mut largest_side_at = vec![0u32; report.depth as usize + 1];
    let mut checked = 0;
    for (t, &h) in read.tiles.iter().zip(&height) {
        if t.mesh.is_none() {
            continue;
        }
        let path = out.join("tiles").join(format!("{}.glb", t.name));
        let bytes = std::fs::read(&path).unwrap();
        let tile = lodkit_mesh::io::gltf::read_scene(&bytes, None).unwrap();
        assert_eq!(tile.images.len(), 1, "{}: one image", t.name);
        assert_eq!(tile.materials.len(), 1);
        let image = decode_rgba(&tile.images[0].bytes).unwrap();
        largest_side_at[h as usize] =
            largest_side_at[h as usize].max(image.width.max(image.height));
        if t.depth == 0 {
            assert!(
                tile.images[0].bytes.len() * 8 < source_bytes,
                "root image {} bytes, source {source_bytes}",
                tile.images[0].bytes.len()
            );
        }
        // Each vertex's UV finds, in the tile's image, the colour of the
        // source texel its position stands for (within a texel of the
        // level); skirt vertices, hung below the surface, copy their edge
        // vertex's UV and are left out.
        let mesh = &tile.merged().mesh;
        let uvs = mesh.uvs.as_ref().expect("UVs kept");
        let scale = (1u32 << h) as f32;
        for (p, uv) in mesh.positions.iter().zip(uvs) {
            if (p.y - surface(p.x, p.z)).abs() > 2e-3 {
                continue;
            }
            assert!((-1e-3..=1.0 + 1e-3).contains(&uv.x), "{}: {uv}", t.name);
            let x = ((uv.x * image.width as f32) as u32).min(image.width - 1);
            let y = (((1.0 - uv.y) * image.height as f32) as u32).min(image.height - 1);
            let texel = &image.rgba[((y * image.width + x) * 4) as usize..][..4];
            checked += 1;
            let want = [p.x * SIDE as f32 / 2.0, (1.0 - p.z) * SIDE as f32 / 2.0];
            for k in 0..2 {
                let got = f32::from(texel[k]);
                assert!(
                    (got - want[k].clamp(0.0, 255.0)).abs() <= 2.0 + scale,
                    "{} (height {h}): texel {texel:?} at {uv} for {p}",
                    t.name
                );
            }
        }
    }
    assert!(checked > 10_000, "{checked} vertices checked");
    eprintln!("largest image side by height above the leaves: {largest_side_at:?}");
    // Leaves keep the source resolution; each level up halves it.
    for h in 1..largest_side_at.len() {
        let (below, here) = (largest_side_at[h - 1], largest_side_at[h]);
        if below > 0 && here > 0 {
            assert!(
                here <= below.div_ceil(2) * 2 + 8,
                "height {h}: {here} px against {below} below"
            );
        }
    }
    let root_side = largest_side_at[report.depth as usize];
    assert!(
        root_side <= SIDE.div_ceil(1 << report.depth) + 4,
        "root image {root_side} px for depth {}",
        report.depth
    );
}

#[test]
fn textured_tilesets_are_byte_identical_on_rerun() {
    let scene = textured_scene();
    let opts = TilesOptions {
        leaf_triangles: 2_048,
        ..TilesOptions::DEFAULT
    };
    let tmp = tempfile::tempdir().unwrap();
    let mut files = Vec::new();
    for run in 0..2 {
        let out = tmp.path().join(format!("run{run}"));
        let ts = tileset_from_scene(&scene, &opts, &mut |_| {}).unwrap();
        write_tileset(&ts, &out, None, &opts, &mut |_| {}).unwrap();
        files.push(common::all_files(&out));
    }
    assert_eq!(files[0], files[1]);
}

/// Tiles `path` (a textured file) and reads every tile back: each face's
/// material textured as in the source, each textured material with its own
/// image; returns (source image bytes, root tile image bytes, tiles, the
/// tiles' image MIME types).
fn tile_file(path: &std::path::Path, leaf: usize) -> (usize, usize, usize, Vec<String>) {
    let scene = lodkit_mesh::io::load_scene(path).unwrap();
    let source_bytes: usize = scene.images.iter().map(|i| i.bytes.len()).sum();
    let opts = TilesOptions {
        leaf_triangles: leaf,
        ..TilesOptions::DEFAULT
    };
    let tmp = tempfile::tempdir().unwrap();
    let out = tmp.path().join("tiles");
    let ts = tileset_from_scene(&scene, &opts, &mut |_| {}).unwrap();
    let report = write_tileset(&ts, &out, None, &opts, &mut |_| {}).unwrap();
    let read = read_tileset(&out);
    let mut root_bytes = 0;
    let mut tiles = 0;
    let mut mimes = Vec::new();
    for t in read.tiles.iter().filter(|t| t.mesh.is_some()) {
        let glb = std::fs::read(out.join("tiles").join(format!("{}.glb", t.name))).unwrap();
        let tile = lodkit_mesh::io::gltf::read_scene(&glb, None).unwrap();
        tile.validate().unwrap();
        let textured = tile
            .materials
            .iter()
            .filter(|m| m.base_color_texture.is_some())
            .count();
        assert_eq!(
            tile.images.len(),
            textured,
            "{}: one image a textured material",
            t.name
        );
        assert!(textured > 0, "{}: textured", t.name);
        for im in &tile.images {
            decode_rgba(&im.bytes).unwrap();
            mimes.push(im.mime_type.clone());
        }
        if t.depth == 0 {
            root_bytes = tile.images.iter().map(|i| i.bytes.len()).sum();
        }
        tiles += 1;
    }
    assert_eq!(tiles, report.tiles);
    mimes.sort();
    mimes.dedup();
    (source_bytes, root_bytes, tiles, mimes)
}

fn test_data(name: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../mesh/tests/data/textured")
        .join(name)
}

#[test]
fn a_textured_scan_and_a_multi_material_scene_tile_with_their_textures() {
    let (source, root, tiles, _) = tile_file(&test_data("mug_scan.obj"), 256);
    assert!(tiles > 4, "{tiles} tiles");
    assert!(root < source, "root image {root} bytes, source {source}");
    // Two objects, three materials, a PNG and a JPEG texture: each tile's
    // crop in its source's format.
    let (_, _, tiles, mimes) = tile_file(&test_data("parts.gltf"), 64);
    assert!(tiles >= 1);
    assert_eq!(mimes, ["image/jpeg", "image/png"]);
}

#[test]
fn the_rgbd_mug_scan_tiles_with_its_texture_when_present() {
    let shared = std::env::var_os("LODKIT_SHARED_DATA").map_or_else(
        || std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
        std::path::PathBuf::from,
    );
    let path = shared.join("textured/table_scene_mug_rgbd.obj");
    if !path.exists() {
        eprintln!("skipped: {} is absent", path.display());
        return;
    }
    let (source, root, tiles, _) = tile_file(&path, 32_768);
    eprintln!(
        "RGB-D mug: {tiles} tiles, source image {source} bytes, root tile image {root} bytes"
    );
    assert!(
        root * 4 < source,
        "root image {root} bytes, source {source}"
    );
}
