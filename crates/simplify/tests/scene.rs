//! Scenes through the simplifier: material borders are seams (no crack
//! between primitives), every material, texture image and sampler and the
//! node transforms survive GLB → simplify → GLB, and vertex groups do not
//! change the result where there is no border.

use std::path::{Path, PathBuf};

use lodkit_mesh::io::gltf;
use lodkit_mesh::scene::{NO_MATERIAL, Scene, SceneMesh};
use lodkit_mesh::{TriMesh, glam::Vec3, shapes};
use lodkit_simplify::scene::{scene_lod_chain, simplify_scene, split_by_material};
use lodkit_simplify::{Options, Simplifier, Target, simplify};

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../mesh/tests/data/textured")
        .join(name)
}

/// Edges (by exact position) with other than two faces: the open or
/// cracked ones. Zero for a closed, crack-free surface.
fn open_edges(m: &TriMesh) -> usize {
    let key = |p: Vec3| p.to_array().map(|x| (x + 0.0).to_bits());
    let mut ids = std::collections::BTreeMap::new();
    let id: Vec<usize> = m
        .positions
        .iter()
        .map(|&p| {
            let n = ids.len();
            *ids.entry(key(p)).or_insert(n)
        })
        .collect();
    let mut edges = std::collections::BTreeMap::new();
    for f in &m.faces {
        for c in 0..3 {
            let (a, b) = (id[f[c] as usize], id[f[(c + 1) % 3] as usize]);
            *edges.entry((a.min(b), a.max(b))).or_insert(0) += 1;
        }
    }
    edges.values().filter(|&&n| n != 2).count()
}

/// A closed sphere, three materials in bands, vertices shared across the
/// borders (as an OBJ with `usemtl` stores it) and, second, split per
/// material with UVs (as glTF primitives store it).
fn banded_sphere(split: bool) -> Scene {
    let mut m = shapes::icosphere(4);
    let face_materials: Vec<u32> = (0..m.faces.len())
        .map(|f| {
            let y = m.triangle(f).iter().map(|p| p.y).sum::<f32>() / 3.0;
            if y > 0.3 {
                0
            } else if y > -0.2 {
                1
            } else {
                NO_MATERIAL
            }
        })
        .collect();
    m.uvs = Some(m.positions.iter().map(|p| p.truncate() * 0.5).collect());
    let mut sm = SceneMesh {
        name: Some("ball".into()),
        mesh: m,
        face_materials,
    };
    if split {
        let (mesh, groups) = split_by_material(&sm);
        sm.face_materials = mesh.faces.iter().map(|f| groups[f[0] as usize]).collect();
        sm.mesh = mesh;
    }
    let mut s = Scene::from_mesh(TriMesh::default());
    s.meshes[0] = sm;
    s.materials = vec![Default::default(), Default::default()];
    s
}

#[test]
fn material_borders_do_not_crack_at_any_level() {
    for split in [false, true] {
        let s = banded_sphere(split);
        assert_eq!(open_edges(&s.meshes[0].mesh), 0);
        let targets = [Target::Ratio(0.5), Target::Ratio(0.1), Target::Ratio(0.02)];
        let levels = scene_lod_chain(&s, &Options::DEFAULT, &targets).unwrap();
        for (level, reports) in &levels {
            let sm = &level.meshes[0];
            assert_eq!(sm.face_materials.len(), sm.mesh.faces.len());
            assert_eq!(open_edges(&sm.mesh), 0, "split {split}: {:?}", reports[0]);
            // Every material is still there.
            for id in [0, 1, NO_MATERIAL] {
                assert!(sm.face_materials.contains(&id), "material {id} lost");
            }
            // Each vertex belongs to one material (the seam rule).
            let mut owner = vec![None; sm.mesh.positions.len()];
            for (f, &id) in sm.mesh.faces.iter().zip(&sm.face_materials) {
                for &v in f {
                    assert!(owner[v as usize].is_none_or(|o| o == id));
                    owner[v as usize] = Some(id);
                }
            }
        }
        let faces: Vec<usize> = levels.iter().map(|(l, _)| l.face_count()).collect();
        assert!(faces[2] <= 5_120 / 50 + 2, "{faces:?}");
    }
}

#[test]
fn a_scene_chain_never_repeats_a_level_and_small_parts_wait_for_big_ones() {
    // A big sphere and a tetrahedron (which no collapse can shrink).
    let mut s = banded_sphere(false);
    let tetra = TriMesh::new(
        vec![
            Vec3::new(3.0, 0.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(3.0, 1.0, 0.0),
            Vec3::new(3.0, 0.0, 1.0),
        ],
        vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
    );
    s.meshes.push(SceneMesh {
        name: Some("tetra".into()),
        face_materials: vec![0; 4],
        mesh: tetra.clone(),
    });
    let targets: Vec<Target> = (1..=12).map(|i| Target::Ratio(0.5f32.powi(i))).collect();
    let levels = scene_lod_chain(&s, &Options::DEFAULT, &targets).unwrap();
    let faces: Vec<usize> = levels.iter().map(|(l, _)| l.face_count()).collect();
    assert!(levels.len() < targets.len(), "{faces:?}");
    assert!(faces.windows(2).all(|w| w[1] < w[0]), "{faces:?}");
    for (level, reports) in &levels {
        assert_eq!(level.meshes.len(), 2);
        assert_eq!(reports.len(), 2);
        assert_eq!(level.meshes[1].mesh.faces.len(), 4);
    }
    let (_, last) = levels.last().unwrap();
    assert!(last.iter().all(|r| r.chain_end.is_some()), "{last:?}");
    let combined = lodkit_simplify::scene::combined_report(last).unwrap();
    assert!(combined.chain_end.is_some());
    for (_, reports) in &levels[..levels.len() - 1] {
        assert!(reports.iter().all(|r| r.chain_end.is_none()));
    }
}

#[test]
fn groups_without_borders_change_nothing() {
    let m = shapes::icosphere(3);
    let plain = simplify(&m, &Options::ratio(0.2)).unwrap();
    let (grouped, g) = Simplifier::new()
        .simplify_grouped(&m, &vec![7; m.positions.len()], &Options::ratio(0.2))
        .unwrap();
    assert_eq!(plain.mesh, grouped.mesh);
    assert_eq!(g, vec![7; grouped.mesh.positions.len()]);
    let bad = Simplifier::new().simplify_grouped(&m, &[0, 1], &Options::ratio(0.2));
    assert!(bad.is_err());
}

#[test]
fn glb_simplify_glb_keeps_materials_images_samplers_and_nodes() {
    let s = lodkit_mesh::io::load_scene(&data("parts.gltf")).unwrap();
    let (lod, reports) = simplify_scene(&s, &Options::ratio(0.5)).unwrap();
    assert_eq!(reports.len(), 2);
    assert!(lod.face_count() < s.face_count());
    let glb = gltf::write_scene_glb(&lod).unwrap();
    let back = gltf::read_scene(&glb, None).unwrap();
    assert_eq!(back.materials, s.materials);
    assert_eq!(back.samplers, s.samplers);
    assert_eq!(back.textures, s.textures);
    for (a, b) in back.images.iter().zip(&s.images) {
        assert_eq!(a.bytes, b.bytes);
        assert_eq!(a.mime_type, b.mime_type);
    }
    assert_eq!(back.nodes, s.nodes);
    let prims = |s: &Scene| -> Vec<Vec<u32>> {
        s.meshes
            .iter()
            .map(|m| {
                let mut v = m.face_materials.clone();
                v.dedup();
                v
            })
            .collect()
    };
    assert_eq!(prims(&back), prims(&s));
    // The ball is closed and stays closed across its two primitives.
    assert_eq!(open_edges(&s.meshes[0].mesh), 0);
    assert_eq!(open_edges(&back.meshes[0].mesh), 0);
}

#[test]
fn a_face_budget_is_shared_among_meshes() {
    let s = lodkit_mesh::io::load_scene(&data("parts.gltf")).unwrap();
    let (lod, _) = simplify_scene(&s, &Options::faces(s.face_count() / 2)).unwrap();
    assert!(
        lod.face_count() <= s.face_count() / 2,
        "{}",
        lod.face_count()
    );
    assert!(lod.meshes.iter().all(|m| !m.mesh.faces.is_empty()));
}
