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
    let mut bytes = Vec::new();
    let mut enc = png::Encoder::new(&mut bytes, SIDE, SIDE);
    enc.set_color(png::ColorType::Rgb);
    enc.set_depth(png::BitDepth::Eight);
    let data: Vec<u8> = (0..SIDE * SIDE)
        .flat_map(|i| [((i % SIDE) / 2) as u8, ((i / SIDE) / 2) as u8, 128])
        .collect();
    let mut w = enc.write_header().unwrap();
    w.write_image_data(&data).unwrap();
    w.finish().unwrap();
    bytes
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
