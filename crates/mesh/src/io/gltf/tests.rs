//! Round trips, the container's structure, conventions on read, and one
//! line per kind of bad input.

use glam::{Vec2, Vec3};

use super::buffers::decode_base64;
use super::color::{linear_to_srgb8, srgb8_to_linear, unit8};
use super::glb::u32_at;
use super::write::vec3_bytes;
use super::{read, write_glb};
use crate::mesh::TriMesh;

fn b64(data: &[u8]) -> String {
    use base64::Engine as _;
    base64::engine::general_purpose::STANDARD.encode(data)
}

/// The bytes behind [`BODY`]: a unit quad's positions (0..48), u8
/// indices (48..54), normalised u8 RGB colours (56..68) and normalised
/// u16 UVs (68..84).
fn quad_bin() -> Vec<u8> {
    let mut v = vec3_bytes(&[Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]);
    v.extend_from_slice(&[0, 1, 2, 0, 2, 3, 0, 0]);
    v.extend_from_slice(&[255, 0, 0, 0, 0, 0, 128, 128, 128, 0, 255, 0]);
    for uv in [[0u16, 0], [65535, 0], [65535, 65535], [0, 65535]] {
        for c in uv {
            v.extend_from_slice(&c.to_le_bytes());
        }
    }
    v
}

const BODY: &str = r#""bufferViews":[{"buffer":0,"byteOffset":0,"byteLength":48},{"buffer":0,"byteOffset":48,"byteLength":6},{"buffer":0,"byteOffset":56,"byteLength":12},{"buffer":0,"byteOffset":68,"byteLength":16}],
"accessors":[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,0]},
{"bufferView":1,"componentType":5121,"count":6,"type":"SCALAR"},
{"bufferView":2,"componentType":5121,"normalized":true,"count":4,"type":"VEC3"},
{"bufferView":3,"componentType":5123,"normalized":true,"count":4,"type":"VEC2"}],
"meshes":[{"primitives":[{"attributes":{"POSITION":0,"COLOR_0":2,"TEXCOORD_0":3},"indices":1}]}],
"nodes":[{"mesh":0,"translation":[10,0,0],"scale":[-1,1,1]}],
"scenes":[{"nodes":[0]}],"scene":0"#;

/// A glTF JSON document with `body` and the quad's bytes as a data URI.
fn doc(body: &str) -> String {
    let bin = quad_bin();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],{body}}}"#,
        bin.len(),
        b64(&bin)
    )
}

fn sample() -> TriMesh {
    let positions = vec![
        Vec3::new(0.0, 0.0, 0.0),
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(1.0, 1.0, -1.0e-7),
        Vec3::new(0.0, 1.0, 3.5),
    ];
    TriMesh {
        normals: Some(
            positions
                .iter()
                .map(|p| (*p - Vec3::splat(0.4)).normalize())
                .collect(),
        ),
        colors: Some(vec![
            [0, 0, 0, 0],
            [255, 255, 255, 255],
            [1, 2, 3, 4],
            [188, 60, 250, 128],
        ]),
        uvs: Some(vec![
            Vec2::ZERO,
            Vec2::new(1.0, 0.25),
            Vec2::new(0.3, 0.7),
            Vec2::ONE,
        ]),
        faces: vec![[0, 1, 2], [0, 2, 3]],
        positions,
    }
}

#[test]
fn glb_round_trips_with_every_attribute_subset() {
    for mask in 0..8 {
        let mut m = sample();
        if mask & 1 == 0 {
            m.normals = None;
        }
        if mask & 2 == 0 {
            m.colors = None;
        }
        if mask & 4 == 0 {
            m.uvs = None;
        }
        let glb = write_glb(&[("LOD0", &m)]).unwrap();
        let back = read(&glb, None).unwrap();
        assert_eq!(back, m, "mask {mask}");
        assert_eq!(write_glb(&[("LOD0", &m)]).unwrap(), glb, "deterministic");
    }
}

#[test]
fn every_rgba8_colour_survives_the_linear_encoding() {
    for c in 0..=255u8 {
        let lin = (srgb8_to_linear(c) * 65535.0).round() as u16;
        assert_eq!(linear_to_srgb8(lin as f32 / 65535.0), c);
        assert_eq!(unit8((c as u16 * 257) as f32 / 65535.0), c);
    }
}

/// Checks the container and JSON of a GLB; returns the parsed JSON.
fn check_glb_structure(glb: &[u8]) -> serde_json::Value {
    assert_eq!(&glb[..4], b"glTF");
    assert_eq!(u32_at(glb, 4), 2);
    assert_eq!(u32_at(glb, 8) as usize, glb.len());
    let jl = u32_at(glb, 12) as usize;
    assert_eq!(&glb[16..20], b"JSON");
    assert_eq!(jl % 4, 0);
    let js = &glb[20..20 + jl];
    let bl = u32_at(glb, 20 + jl) as usize;
    assert_eq!(&glb[24 + jl..28 + jl], b"BIN\0");
    assert_eq!((28 + jl) % 4, 0);
    assert_eq!(bl % 4, 0);
    assert_eq!(28 + jl + bl, glb.len());
    let v: serde_json::Value = serde_json::from_slice(js).unwrap();
    assert!(js.ends_with(b"}") || js.ends_with(b" "));
    assert_eq!(v["buffers"][0]["byteLength"].as_u64().unwrap() as usize, bl);
    for view in v["bufferViews"].as_array().unwrap() {
        let o = view["byteOffset"].as_u64().unwrap();
        let l = view["byteLength"].as_u64().unwrap();
        assert_eq!(o % 4, 0);
        assert!(o + l <= bl as u64);
    }
    v
}

#[test]
fn glb_levels_structure_names_and_extras() {
    let small = sample();
    // 70000 vertices: needs u32 indices.
    let n = 70_000u32;
    let big = TriMesh::new(
        (0..n)
            .map(|i| Vec3::new(i as f32, (i % 7) as f32, 0.0))
            .collect(),
        (0..n - 2).map(|i| [i, i + 1, i + 2]).collect(),
    );
    let glb = write_glb(&[("LOD0", &big), ("LOD1", &small)]).unwrap();
    let v = check_glb_structure(&glb);
    assert_eq!(v["scene"], 0);
    assert_eq!(v["scenes"][0]["nodes"], serde_json::json!([0, 1]));
    assert_eq!(v["nodes"][0]["name"], "LOD0 (69998 triangles)");
    assert_eq!(v["meshes"][1]["name"], "LOD1 (2 triangles)");
    assert_eq!(
        v["nodes"][1]["extras"],
        serde_json::json!({"triangles": 2, "vertices": 4})
    );
    let acc = &v["accessors"];
    assert_eq!(acc[0]["min"], serde_json::json!([0.0, 0.0, 0.0]));
    assert_eq!(acc[0]["max"], serde_json::json!([69999.0, 6.0, 0.0]));
    assert_eq!(acc[1]["componentType"], 5125); // u32 indices
    let small_idx = v["meshes"][1]["primitives"][0]["indices"].as_u64().unwrap() as usize;
    assert_eq!(acc[small_idx]["componentType"], 5123); // u16 indices
    assert_eq!(v["meshes"][1]["primitives"][0]["attributes"]["COLOR_0"], 4);
    assert_eq!(acc[4]["normalized"], true);
    // Reading merges all levels into one mesh.
    let back = read(&glb, None).unwrap();
    assert_eq!(back.faces.len(), 69_998 + 2);
    assert_eq!(back.positions[n as usize..], small.positions[..]);
}

#[test]
fn json_gltf_with_transform_u8_indices_and_normalised_attributes() {
    let m = read(doc(BODY).as_bytes(), None).unwrap();
    assert_eq!(
        m.positions,
        vec![
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(9.0, 0.0, 0.0),
            Vec3::new(9.0, 1.0, 0.0),
            Vec3::new(10.0, 1.0, 0.0)
        ]
    );
    // The mirror (scale x = -1) flips the winding back to CCW.
    assert_eq!(m.faces, vec![[0, 2, 1], [0, 3, 2]]);
    let c = m.colors.unwrap();
    assert_eq!(c[0], [255, 0, 0, 255]);
    assert_eq!(c[2], [linear_to_srgb8(128.0 / 255.0), 188, 188, 255]);
    assert_eq!(
        m.uvs.unwrap(),
        vec![Vec2::Y, Vec2::ONE, Vec2::X, Vec2::ZERO]
    );
}

#[test]
fn strips_fans_and_normals_under_rotation() {
    let strip = BODY.replace(r#","indices":1"#, r#","mode":5"#).replace(
        r#""translation":[10,0,0],"scale":[-1,1,1]"#,
        r#""rotation":[0,0,0.7071068,0.7071068]"#,
    );
    let m = read(doc(&strip).as_bytes(), None).unwrap();
    assert_eq!(m.faces, vec![[0, 1, 2], [1, 3, 2]]);
    assert!((m.positions[1] - Vec3::Y).length() < 1e-6);
    let fan = strip.replace(r#""mode":5"#, r#""mode":6"#);
    let m = read(doc(&fan).as_bytes(), None).unwrap();
    assert_eq!(m.faces, vec![[1, 2, 0], [2, 3, 0]]);
    // Normals: a non-uniform scale uses the inverse transpose.
    let mut s = sample();
    s.colors = None;
    s.uvs = None;
    s.normals = Some(vec![Vec3::new(1.0, 1.0, 0.0).normalize(); 4]);
    let glb = write_glb(&[("n", &s)]).unwrap();
    let v = check_glb_structure(&glb);
    let mut root = v.clone();
    root["nodes"][0]["scale"] = serde_json::json!([2.0, 1.0, 1.0]);
    let js = serde_json::to_vec(&root).unwrap();
    let bin = &glb[28 + u32_at(&glb, 12) as usize..];
    let mut re = Vec::new();
    re.extend_from_slice(b"glTF");
    re.extend_from_slice(&2u32.to_le_bytes());
    let pad = (4 - js.len() % 4) % 4;
    re.extend_from_slice(&((28 + js.len() + pad + bin.len()) as u32).to_le_bytes());
    re.extend_from_slice(&((js.len() + pad) as u32).to_le_bytes());
    re.extend_from_slice(b"JSON");
    re.extend_from_slice(&js);
    re.extend(std::iter::repeat_n(b' ', pad));
    re.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    re.extend_from_slice(b"BIN\0");
    re.extend_from_slice(bin);
    let m = read(&re, None).unwrap();
    let want = Vec3::new(0.5, 1.0, 0.0).normalize();
    assert!((m.normals.unwrap()[0] - want).length() < 1e-6);
    assert_eq!(m.positions[1], Vec3::new(2.0, 0.0, 0.0));
}

#[test]
fn attribute_missing_from_one_primitive_is_dropped_but_uvs_are_zero_filled() {
    // Normals and colours missing from one primitive are dropped; UVs are
    // kept, (0, 0) where a primitive has none (writers leave TEXCOORD_0 off
    // an untextured primitive, and the textured ones keep their mapping).
    let two = BODY.replace(
        r#"{"attributes":{"POSITION":0,"COLOR_0":2,"TEXCOORD_0":3},"indices":1}"#,
        r#"{"attributes":{"POSITION":0,"COLOR_0":2,"TEXCOORD_0":3},"indices":1},{"attributes":{"POSITION":0},"indices":1}"#,
    );
    let m = read(doc(&two).as_bytes(), None).unwrap();
    assert_eq!(m.positions.len(), 8);
    assert!(m.colors.is_none());
    let uvs = m.uvs.unwrap();
    assert_eq!(uvs.len(), 8);
    assert!(uvs[4..].iter().all(|t| *t == glam::Vec2::ZERO));
}

#[test]
fn external_buffer_resolved_against_base_dir() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("quad data.bin"), quad_bin()).unwrap();
    let body = format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":84,"uri":"quad%20data.bin"}}],{BODY}}}"#
    );
    let m = read(body.as_bytes(), Some(dir.path())).unwrap();
    assert_eq!(m.faces.len(), 2);
    let e = read(body.as_bytes(), None).unwrap_err().to_string();
    assert!(e.contains("no directory to resolve it"), "{e}");
    let http = body.replace("quad%20data.bin", "http://example.invalid/q.bin");
    let e = read(http.as_bytes(), Some(dir.path()))
        .unwrap_err()
        .to_string();
    assert!(e.contains("is a URI"), "{e}");
}

#[test]
fn bad_input_is_a_one_line_error() {
    let glb = write_glb(&[("x", &sample())]).unwrap();
    let mut short_len = glb.clone();
    short_len[8..12].copy_from_slice(&3u32.to_le_bytes());
    let mut long_chunk = glb.clone();
    long_chunk[12..16].copy_from_slice(&u32::MAX.to_le_bytes());
    let s = |x: &str| x.as_bytes().to_vec();
    let cases: Vec<(Vec<u8>, &str)> = vec![
        (vec![], "empty file"),
        (s("glTX...."), "neither GLB"),
        (glb[..10].to_vec(), "GLB truncated"),
        (glb[..glb.len() - 4].to_vec(), "GLB header says"),
        (short_len, "GLB header says 3 bytes"),
        (long_chunk, "chunk at byte 12 says 4294967295 bytes"),
        (s("{ not json"), "glTF JSON"),
        (s(&doc(&BODY.replace(r#""byteLength":16"#, r#""byteLength":64"#))), "outside buffer 0"),
        (s(&doc(&BODY.replace(r#""count":4,"type":"VEC2""#, r#""count":5,"type":"VEC2""#))), "do not fit in buffer view 3"),
        (s(&doc(&BODY.replace(r#""count":6"#, r#""count":0"#))), "empty (count 0)"),
        (s(&doc(&BODY.replace("[0, 1, 2, 0, 2, 3", "x").replace(r#""POSITION":0"#, r#""POSITION":9"#))), "uses accessor 9 but there are 4"),
        (s(&doc(&BODY.replace(r#""componentType":5121,"count":6"#, r#""componentType":5126,"count":1"#))), "not allowed there"),
        (s(&doc(&BODY.replace(r#""byteOffset":0,"byteLength":48"#, r#""byteOffset":0,"byteLength":48,"byteStride":8"#))), "stride 8"),
        (s(&doc(&BODY.replace(r#""scenes":[{"nodes":[0]}]"#, r#""scenes":[{"nodes":[0,0]}]"#))), "reached twice"),
        (s(&doc(&BODY.replace(r#""mesh":0,"#, r#""mesh":0,"children":[0],"#))), "reached twice"),
        (s(&doc(&BODY.replace(r#""bufferView":1,"#, r#""sparse":{"count":1,"indices":{"bufferView":1,"componentType":5121},"values":{"bufferView":1}},"bufferView":1,"#))), "sparse"),
        (s(&doc(BODY).replace(";base64,", ",")), "data URI is not base64"),
        (s(&doc(BODY).replace(";base64,", ";base64,%%")), "not valid base64"),
        (s(&(BODY.replace(r#""bufferViews""#, r#"{"asset":{"version":"2.0"},"buffers":[{"byteLength":84}],"bufferViews""#) + "}")), "no GLB BIN chunk"),
        (s(&doc(&BODY.replace(r#""mode""#, "x").replace(r#""indices":1"#, r#""indices":1,"mode":1"#))), "no triangle primitives"),
        (s(&doc(&BODY.replace(r#""max":[1,1,0]"#, r#""max":[1,1]"#))), "invalid glTF"),
    ];
    for (input, want) in cases {
        let e = read(&input, None).unwrap_err().to_string();
        assert!(e.contains(want), "{e:?} should contain {want:?}");
        assert!(!e.contains('\n'), "{e:?}");
    }
    // Index out of range.
    let mut bin = quad_bin();
    bin[50] = 7;
    let d = format!(
        r#"{{"asset":{{"version":"2.0"}},"buffers":[{{"byteLength":84,"uri":"data:application/octet-stream;base64,{}"}}],{BODY}}}"#,
        b64(&bin)
    );
    let e = read(d.as_bytes(), None).unwrap_err().to_string();
    assert!(e.contains("index 7 out of range (4 vertices)"), "{e}");
}

#[test]
fn json_with_a_byte_order_mark_is_read() {
    let with_bom = [b"\xEF\xBB\xBF".as_slice(), doc(BODY).as_bytes()].concat();
    assert_eq!(read(&with_bom, None).unwrap().faces.len(), 2);
}

#[test]
fn base64_decoder() {
    for n in 0..20u8 {
        let data: Vec<u8> = (0..n).map(|i| i.wrapping_mul(37)).collect();
        assert_eq!(decode_base64(&b64(&data)).unwrap(), data);
    }
    assert!(decode_base64("A").is_err());
    assert!(decode_base64("AB=C").is_err());
    assert!(decode_base64("A=").is_err());
}

/// A scene placing one mesh with `nodes` nodes (the quad of [`BODY`]).
fn instanced(nodes: usize) -> String {
    let body = BODY.replace(
        r#""nodes":[{"mesh":0,"translation":[10,0,0],"scale":[-1,1,1]}],
"scenes":[{"nodes":[0]}],"scene":0"#,
        &format!(
            r#""nodes":[{}],"scenes":[{{"nodes":[{}]}}],"scene":0"#,
            vec![r#"{"mesh":0}"#; nodes].join(","),
            (0..nodes)
                .map(|i| i.to_string())
                .collect::<Vec<_>>()
                .join(",")
        ),
    );
    assert_ne!(body, BODY);
    doc(&body)
}

/// Instancing is expanded within its stated limit: many copies of a small
/// mesh are read, and a file whose instances would expand past the limit
/// is refused before anything is allocated (one 4-vertex quad placed by
/// 1.1M nodes would need 4.4M vertices, over the 4M floor).
#[test]
fn instancing_expansion_is_bounded_before_allocating() {
    let m = read(instanced(1000).as_bytes(), None).unwrap();
    assert_eq!((m.positions.len(), m.faces.len()), (4000, 2000));
    let n = (super::INSTANCING_FLOOR / 4 + 1) as usize;
    let e = read(instanced(n).as_bytes(), None).unwrap_err().0;
    assert!(
        e.contains("primitive instances expand 4 stored vertices to")
            && e.contains("over the limit of 4194304"),
        "{e}"
    );
}
