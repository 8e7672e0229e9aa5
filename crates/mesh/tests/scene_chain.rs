//! Scene GLBs as engines read them: the LOD chain of a scene (one root
//! node per level, `MSFT_lod` on level 0, the tables written once) and
//! compressed scenes (`KHR_mesh_quantization` + `EXT_meshopt_compression`,
//! with the `meshopt` feature) that read back with every material and
//! image byte and every mesh in its place.
//! Inputs: `tests/data/textured` (made by its `make.py`).

use std::path::{Path, PathBuf};

use lodkit_mesh::io::gltf::{self, GlbOptions, SceneLodLevel};
use lodkit_mesh::io::load_scene;
use lodkit_mesh::scene::Scene;

fn data(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/textured")
        .join(name)
}

/// The GLB's JSON chunk.
fn json_of(glb: &[u8]) -> serde_json::Value {
    let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + len]).unwrap()
}

/// A coarser copy of `s`: every other face of each mesh (same tables).
fn coarser(s: &Scene) -> Scene {
    let mut c = s.clone();
    for m in &mut c.meshes {
        let keep: Vec<usize> = (0..m.mesh.faces.len()).step_by(2).collect();
        m.mesh.faces = keep.iter().map(|&f| m.mesh.faces[f]).collect();
        m.face_materials = keep.iter().map(|&f| m.face_materials[f]).collect();
    }
    c
}

fn level<'a>(name: &str, scene: &'a Scene, coverage: f64) -> SceneLodLevel<'a> {
    let mut extras = serde_json::Map::new();
    extras.insert("lod".into(), name.len().into());
    SceneLodLevel {
        name: name.into(),
        scene,
        extras,
        coverage,
    }
}

fn chain(s: &Scene, opts: &GlbOptions) -> Vec<u8> {
    let (a, b) = (coarser(s), coarser(&coarser(s)));
    let levels = [
        level("parts_LOD0", s, 0.5),
        level("parts_LOD1", &a, 0.7),
        level("parts_LOD2", &b, 0.0),
    ];
    gltf::write_scene_lod_glb(&levels, opts).unwrap()
}

#[test]
fn a_scene_chain_is_level_0_with_msft_lod_over_the_other_levels() {
    let s = load_scene(&data("parts.gltf")).unwrap();
    let glb = chain(&s, &GlbOptions::default());
    assert_eq!(glb, chain(&s, &GlbOptions::default()), "deterministic");
    let j = json_of(&glb);
    let nodes = j["nodes"].as_array().unwrap();
    let root = &j["scenes"][0]["nodes"];
    assert_eq!(root.as_array().unwrap().len(), 1);
    let base = &nodes[root[0].as_u64().unwrap() as usize];
    assert_eq!(base["name"], "parts_LOD0");
    let ids = base["extensions"]["MSFT_lod"]["ids"].as_array().unwrap();
    let names: Vec<_> = ids
        .iter()
        .map(|i| nodes[i.as_u64().unwrap() as usize]["name"].clone())
        .collect();
    assert_eq!(names, ["parts_LOD1", "parts_LOD2"]);
    // Made strictly decreasing by the levels' sizes; used, not required.
    let (a, b) = (coarser(&s), coarser(&coarser(&s)));
    let want = gltf::screen_coverages(
        &[0.5, 0.7, 0.0],
        &[s.face_count(), a.face_count(), b.face_count()],
    );
    assert_eq!(
        base["extras"]["MSFT_screencoverage"],
        serde_json::json!(want)
    );
    assert!(want[0] <= 0.5 && want[0] > want[1] && want[1] > want[2] && want[2] == 0.0);
    assert_eq!(base["extras"]["triangles"], s.face_count());
    assert!(
        j["extensionsUsed"]
            .as_array()
            .unwrap()
            .contains(&"MSFT_lod".into())
    );
    assert!(j.get("extensionsRequired").is_none());
    // Written once: the tables of one scene.
    assert_eq!(j["images"].as_array().unwrap().len(), s.images.len());
    assert_eq!(j["materials"].as_array().unwrap().len(), s.materials.len());
    // A reader without MSFT_lod sees level 0 alone: the input's scene
    // under one more root node, images byte for byte.
    let back = gltf::read_scene(&glb, None).unwrap();
    assert_eq!(back.face_count(), s.face_count());
    assert_eq!(back.materials, s.materials);
    for (x, y) in back.images.iter().zip(&s.images) {
        assert_eq!(x.bytes, y.bytes);
    }
    assert_eq!(back.roots.len(), 1);
    assert_eq!(
        back.nodes[back.roots[0]].name.as_deref(),
        Some("parts_LOD0")
    );
    let named: Vec<_> = back.nodes.iter().filter_map(|n| n.name.clone()).collect();
    for n in &s.nodes {
        assert!(named.contains(n.name.as_ref().unwrap()));
    }
}

#[test]
fn scene_chain_levels_must_share_their_tables_and_coverages_stay_in_range() {
    let s = load_scene(&data("parts.gltf")).unwrap();
    let mut other = coarser(&s);
    other.materials[0].metallic = 0.25;
    let levels = [level("a_LOD0", &s, 1.0), level("a_LOD1", &other, 0.0)];
    let e = gltf::write_scene_lod_glb(&levels, &GlbOptions::default()).unwrap_err();
    assert!(e.0.contains("tables differ"), "{}", e.0);
    let levels = [level("a_LOD0", &s, 1.5)];
    let e = gltf::write_scene_lod_glb(&levels, &GlbOptions::default()).unwrap_err();
    assert!(e.0.contains("outside [0, 1]"), "{}", e.0);
}

#[cfg(feature = "meshopt")]
mod compressed {
    use super::*;

    /// World-space box of the scene's merged mesh.
    fn world_box(s: &Scene) -> (glam::Vec3, glam::Vec3) {
        let m = s.merged().mesh;
        let b = m.bbox();
        (b.min, b.max)
    }

    fn assert_same_placement(a: &Scene, b: &Scene) {
        let ((a0, a1), (b0, b1)) = (world_box(a), world_box(b));
        let tol = (a1 - a0).max_element() * 2e-4;
        assert!((a0 - b0).abs().max_element() < tol, "{a0} {b0}");
        assert!((a1 - b1).abs().max_element() < tol, "{a1} {b1}");
        assert_eq!(a.face_count(), b.face_count());
        assert_eq!(a.materials, b.materials);
        assert_eq!(a.textures, b.textures);
        assert_eq!(a.samplers, b.samplers);
        for (x, y) in a.images.iter().zip(&b.images) {
            assert_eq!(x.bytes, y.bytes);
        }
        // UVs within the u16 grid of normalised TEXCOORD_0.
        let (ua, ub) = (a.merged().mesh, b.merged().mesh);
        let range = |m: &lodkit_mesh::TriMesh| {
            let uv = m.uvs.as_ref().unwrap();
            uv.iter().fold((f32::MAX, f32::MIN), |(lo, hi), t| {
                (lo.min(t.x.min(t.y)), hi.max(t.x.max(t.y)))
            })
        };
        let (ra, rb) = (range(&ua), range(&ub));
        assert!((ra.0 - rb.0).abs() < 1e-4 && (ra.1 - rb.1).abs() < 1e-4);
    }

    #[test]
    fn a_compressed_scene_reads_back_in_place_with_its_materials() {
        let s = load_scene(&data("parts.gltf")).unwrap();
        let opts = GlbOptions { compress: true };
        let glb = gltf::write_scene_glb_with(&s, &opts).unwrap();
        let j = json_of(&glb);
        let req = j["extensionsRequired"].as_array().unwrap();
        assert!(req.contains(&"EXT_meshopt_compression".into()));
        assert!(req.contains(&"KHR_mesh_quantization".into()));
        assert!(glb.len() < gltf::write_scene_glb(&s).unwrap().len());
        let back = gltf::read_scene(&glb, None).unwrap();
        assert_same_placement(&s, &back);
        // Nodes with no children take the grid into their own transform:
        // the same node tree, names in place.
        let names = |s: &Scene| s.nodes.iter().map(|n| n.name.clone()).collect::<Vec<_>>();
        assert_eq!(names(&back), names(&s));
    }

    #[test]
    fn a_compressed_mesh_under_a_node_with_children_moves_to_a_carrier_node() {
        let mut s = load_scene(&data("parts.gltf")).unwrap();
        // The root (which has children) places the ball too.
        s.nodes[0].mesh = Some(0);
        let glb = gltf::write_scene_glb_with(&s, &GlbOptions { compress: true }).unwrap();
        let back = gltf::read_scene(&glb, None).unwrap();
        assert_eq!(back.nodes.len(), s.nodes.len() + 1);
        assert_same_placement(&s, &back);
    }

    #[test]
    fn a_compressed_scene_chain_reads_back_as_level_0() {
        let s = load_scene(&data("mug_scan.obj")).unwrap();
        let glb = chain(&s, &GlbOptions { compress: true });
        let back = gltf::read_scene(&glb, None).unwrap();
        assert_same_placement(&s, &back);
    }
}
