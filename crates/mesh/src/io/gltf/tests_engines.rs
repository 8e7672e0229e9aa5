//! The engine-facing layouts: `MSFT_lod` chains, `POINTS`, quantised
//! files on read, compression (with the `meshopt` feature), refusals.

use glam::Vec3;

use super::{GlbOptions, LodLevel, read_model, write_lod_glb, write_points_glb};
use crate::mesh::{Model, PointCloud, TriMesh};

fn json_of(glb: &[u8]) -> serde_json::Value {
    let n = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    serde_json::from_slice(&glb[20..20 + n]).unwrap()
}

fn level<'a>(name: &str, mesh: &'a TriMesh, coverage: f64) -> LodLevel<'a> {
    LodLevel {
        name: name.into(),
        mesh,
        extras: serde_json::Map::new(),
        coverage,
    }
}

#[test]
fn an_lod_chain_has_one_root_and_msft_lod_over_the_rest() {
    let fine = crate::shapes::icosphere(3);
    let coarse = crate::shapes::icosphere(1);
    // A coverage that rises is made to fall, by the triangle ratio.
    let glb = write_lod_glb(
        &[level("s_LOD0", &fine, 0.5), level("s_LOD1", &coarse, 0.7)],
        &GlbOptions::default(),
    )
    .unwrap();
    let j = json_of(&glb);
    assert_eq!(j["scenes"][0]["nodes"], serde_json::json!([0]));
    assert_eq!(
        j["nodes"][0]["extensions"]["MSFT_lod"]["ids"],
        serde_json::json!([1])
    );
    assert_eq!(
        j["nodes"][0]["extras"]["MSFT_screencoverage"],
        serde_json::json!([0.0625, 0.003906])
    );
    assert_eq!(j["nodes"][1]["name"], "s_LOD1");
    // Read back: level 0 only (the others are outside the scene).
    let Model::Mesh(m) = read_model(&glb, None).unwrap() else {
        panic!("a mesh")
    };
    assert_eq!(m.faces.len(), fine.faces.len());
    // Bad coverage is refused.
    assert!(write_lod_glb(&[level("x", &fine, 1.5)], &GlbOptions::default()).is_err());
}

#[test]
fn screen_coverages_strictly_fall_so_a_switch_reaches_every_level() {
    use super::{error_coverage, screen_coverages};
    let strict = |c: &[f64]| c.windows(2).all(|w| w[1] < w[0]);
    // Fine levels whose errors are under a pixel all ask for 1: each gets
    // its share by size (a halving chain: halves of the coverage).
    let tris = [69_451, 34_725, 17_361, 8_680, 4_340, 2_170];
    let c = screen_coverages(&[1.0, 1.0, 1.0, 0.99, 0.02, 0.0], &tris);
    assert!(strict(&c), "{c:?}");
    assert_eq!(c, [0.4999, 0.2499, 0.1249, 0.06245, 0.02, 0.0]);
    // What a level asks below the size rule is kept (to 4 digits).
    assert_eq!(
        screen_coverages(&[0.01, 0.001_234_56, 0.0], &[100, 90, 80]),
        [0.01, 0.001234, 0.0]
    );
    // Levels of equal size, and values that would tie after rounding,
    // still fall.
    let c = screen_coverages(&[1.0, 1.0, 1.0, 0.0], &[10_000, 10_000, 9_999, 9_998]);
    assert!(strict(&c), "{c:?}");
    let c = screen_coverages(&[0.5, 0.5, 0.5, 0.5, 0.0], &[5, 5, 5, 5, 5]);
    assert!(strict(&c), "{c:?}");
    // One level: as asked.
    assert_eq!(screen_coverages(&[0.3], &[10]), [0.3]);
    // The error rule: under a pixel is full coverage; ten times the error
    // is a hundredth of the coverage.
    assert_eq!(error_coverage(0.0, 1.0), 1.0);
    assert_eq!(error_coverage(1e-4, 1.0), 1.0);
    let (a, b) = (error_coverage(1e-2, 1.0), error_coverage(1e-1, 1.0));
    assert!((a / b - 100.0).abs() < 1e-9, "{a} {b}");
}

#[test]
fn points_round_trip_through_a_points_primitive() {
    let cloud = PointCloud {
        positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(0.5, 2.0, -1.0)],
        normals: Some(vec![Vec3::Z, Vec3::Y, Vec3::X]),
        colors: Some(vec![[255, 0, 0, 255], [1, 2, 3, 255], [200, 100, 50, 128]]),
    };
    let glb = write_points_glb("p", &cloud, &GlbOptions::default()).unwrap();
    assert_eq!(json_of(&glb)["meshes"][0]["primitives"][0]["mode"], 0);
    assert_eq!(
        read_model(&glb, None).unwrap(),
        Model::Points(cloud.clone())
    );
    let empty = PointCloud::default();
    assert!(write_points_glb("p", &empty, &GlbOptions::default()).is_err());
}

/// A glTF with KHR_mesh_quantization: u16 positions under a scaling node,
/// normalised i8 normals; read as floats through the node's transform.
#[test]
fn quantised_attributes_are_read_as_floats() {
    use base64::Engine as _;
    let mut bin = Vec::new();
    for p in [[0u16, 0, 0, 0], [100, 0, 0, 0], [0, 100, 0, 0]] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for _ in 0..3 {
        bin.extend_from_slice(&[0, 0, 127, 0]);
    }
    let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
    let doc = format!(
        r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_mesh_quantization"],"extensionsRequired":["KHR_mesh_quantization"],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":24,"byteStride":8}},{{"buffer":0,"byteOffset":24,"byteLength":12,"byteStride":4}}],
"accessors":[{{"bufferView":0,"componentType":5123,"count":3,"type":"VEC3","min":[0,0,0],"max":[100,100,0]}},
{{"bufferView":1,"componentType":5120,"normalized":true,"count":3,"type":"VEC3"}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"NORMAL":1}}}}]}}],
"nodes":[{{"mesh":0,"scale":[0.01,0.01,0.01]}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
        bin.len()
    );
    let Model::Mesh(m) = read_model(doc.as_bytes(), None).unwrap() else {
        panic!("a mesh")
    };
    assert!(
        (m.positions[1] - Vec3::X).length() < 1e-6,
        "{:?}",
        m.positions
    );
    assert!((m.normals.unwrap()[0] - Vec3::Z).length() < 1e-6);
}

#[test]
fn compression_round_trips_or_names_the_feature() {
    let s = crate::shapes::icosphere(3);
    let r = write_lod_glb(&[level("s_LOD0", &s, 0.0)], &GlbOptions { compress: true });
    if !cfg!(feature = "meshopt") {
        assert!(r.unwrap_err().0.contains("--features compress"));
        return;
    }
    let glb = r.unwrap();
    let j = json_of(&glb);
    assert!(
        j["extensionsRequired"]
            .as_array()
            .unwrap()
            .contains(&"EXT_meshopt_compression".into())
    );
    let Model::Mesh(m) = read_model(&glb, None).unwrap() else {
        panic!("a mesh")
    };
    assert_eq!(m.faces.len(), s.faces.len());
    let step = 2.0 / 16383.0;
    let bb = m.bbox();
    assert!(
        (bb.max - s.bbox().max).abs().max_element() <= step,
        "{bb:?}"
    );
}

/// A triangle whose material scales and offsets its UVs with
/// KHR_texture_transform (as gltfpack dequantises UVs): the UVs read are
/// the transformed ones; slots that disagree on one set are refused.
#[test]
fn texture_transforms_are_baked_into_the_uvs() {
    use base64::Engine as _;
    let mut bin = Vec::new();
    for p in [[0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for c in p {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    for uv in [[0f32, 0.0], [1.0, 0.0], [0.0, 1.0]] {
        for c in uv {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    let b64 = base64::engine::general_purpose::STANDARD.encode(&bin);
    let doc = |normal: &str| {
        format!(
            r#"{{"asset":{{"version":"2.0"}},"extensionsUsed":["KHR_texture_transform"],
"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{b64}"}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":36}},{{"buffer":0,"byteOffset":36,"byteLength":24}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}},
{{"bufferView":1,"componentType":5126,"count":3,"type":"VEC2"}}],
"images":[{{"uri":"data:image/png;base64,AAAA"}}],"textures":[{{"source":0}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0,
"extensions":{{"KHR_texture_transform":{{"offset":[0.5,0.25],"scale":[0.5,0.5]}}}}}}}}{normal}}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":1}},"material":0}}]}}],
"nodes":[{{"mesh":0}}],"scenes":[{{"nodes":[0]}}],"scene":0}}"#,
            bin.len()
        )
    };
    let Model::Mesh(m) = read_model(doc("").as_bytes(), None).unwrap() else {
        panic!("a mesh")
    };
    // glTF UV (u, v) -> (0.5 + u/2, 0.25 + v/2); lodkit stores 1 - v.
    let want = [[0.5, 0.75], [1.0, 0.75], [0.5, 0.25]];
    for (uv, w) in m.uvs.unwrap().iter().zip(want) {
        assert!(
            (uv.x - w[0]).abs() < 1e-6 && (uv.y - w[1]).abs() < 1e-6,
            "{uv:?}"
        );
    }
    // A normal texture on the same set without the transform disagrees.
    let e = read_model(doc(r#","normalTexture":{"index":0}"#).as_bytes(), None).unwrap_err();
    assert!(e.0.contains("transform UV set 0 differently"), "{}", e.0);
}
