//! PLY reader/writer tests: round trips, every layout the reader accepts,
//! every kind of bad input, and (when `../shared/data` exists) real scans.

use std::path::PathBuf;

use glam::{Vec2, Vec3};

use super::{read, write_mesh, write_points};
use crate::io::{Format, decode};
use crate::mesh::{Model, PointCloud, TriMesh};

/// Header text (lines joined with `\n`, `end_header` appended) + body.
fn ply(header: &[&str], body: &[u8]) -> Vec<u8> {
    let mut out = header.join("\n").into_bytes();
    out.extend_from_slice(b"\nend_header\n");
    out.extend_from_slice(body);
    out
}

/// Full decode (read + validate), as `io::load` does.
fn load(bytes: &[u8]) -> Result<Model, String> {
    decode(Format::Ply, bytes, None).map_err(|e| e.0)
}

fn mesh(bytes: &[u8]) -> TriMesh {
    match load(bytes) {
        Ok(Model::Mesh(m)) => m,
        other => panic!("expected a mesh, got {other:?}"),
    }
}

fn points(bytes: &[u8]) -> PointCloud {
    match load(bytes) {
        Ok(Model::Points(p)) => p,
        other => panic!("expected points, got {other:?}"),
    }
}

/// Asserts decoding fails and the message contains `needle`.
fn fails(bytes: &[u8], needle: &str) -> String {
    match load(bytes) {
        Ok(m) => panic!(
            "expected an error containing {needle:?}, got a {}",
            m.kind()
        ),
        Err(msg) => {
            assert!(
                msg.contains(needle),
                "error {msg:?} does not contain {needle:?}"
            );
            assert!(!msg.contains('\n'), "error is not one line: {msg:?}");
            msg
        }
    }
}

fn le_f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

/// A 2×3 vertex grid with two triangles per quad and every attribute.
fn sample_mesh() -> TriMesh {
    let positions: Vec<Vec3> = (0..6)
        .map(|i| {
            Vec3::new(
                (i % 3) as f32 * 0.1,
                (i / 3) as f32 / 3.0,
                1e-7 * i as f32 - 2.5,
            )
        })
        .collect();
    TriMesh {
        normals: Some(
            (0..6)
                .map(|i| Vec3::new(0.0, (i as f32).sin(), (i as f32).cos()))
                .collect(),
        ),
        colors: Some((0..6).map(|i| [i * 40, 255 - i * 40, 7, 200 + i]).collect()),
        uvs: Some(
            (0..6)
                .map(|i| Vec2::new(i as f32 / 7.0, 1.0 - i as f32 / 3.0))
                .collect(),
        ),
        faces: vec![[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]],
        positions,
    }
}

// --- round trips -----------------------------------------------------------

#[test]
fn mesh_round_trips_binary_and_ascii_with_every_attribute() {
    let m = sample_mesh();
    for ascii in [false, true] {
        let mut bytes = Vec::new();
        write_mesh(&mut bytes, &m, ascii).unwrap();
        assert_eq!(mesh(&bytes), m, "ascii = {ascii}");
        // Deterministic: the same mesh gives the same bytes.
        let mut again = Vec::new();
        write_mesh(&mut again, &m, ascii).unwrap();
        assert_eq!(bytes, again);
    }
}

#[test]
fn bare_mesh_round_trips_and_has_no_attribute_properties() {
    let m = TriMesh::new(
        vec![Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(1.0, 1.0, -3.25)],
        vec![[0, 1, 2], [2, 1, 3]],
    );
    for ascii in [false, true] {
        let mut bytes = Vec::new();
        write_mesh(&mut bytes, &m, ascii).unwrap();
        let text = String::from_utf8_lossy(&bytes);
        assert!(!text.contains("property float nx") && !text.contains("red"));
        assert!(text.contains("property list uchar int vertex_indices"));
        assert_eq!(mesh(&bytes), m);
    }
}

#[test]
fn points_round_trip_binary_and_ascii_with_every_attribute() {
    let m = sample_mesh();
    let p = PointCloud {
        positions: m.positions.clone(),
        normals: m.normals.clone(),
        colors: m.colors.clone(),
    };
    for ascii in [false, true] {
        let mut bytes = Vec::new();
        write_points(&mut bytes, &p, ascii).unwrap();
        assert!(!String::from_utf8_lossy(&bytes).contains("element face"));
        assert_eq!(points(&bytes), p, "ascii = {ascii}");
    }
}

#[test]
fn binary_header_is_exactly_the_documented_layout() {
    let mut bytes = Vec::new();
    write_mesh(&mut bytes, &sample_mesh(), false).unwrap();
    let expected = "ply\nformat binary_little_endian 1.0\ncomment written by lodkit\n\
        element vertex 6\nproperty float x\nproperty float y\nproperty float z\n\
        property float nx\nproperty float ny\nproperty float nz\n\
        property uchar red\nproperty uchar green\nproperty uchar blue\nproperty uchar alpha\n\
        property float s\nproperty float t\n\
        element face 4\nproperty list uchar int vertex_indices\nend_header\n";
    assert!(bytes.starts_with(expected.as_bytes()));
    assert_eq!(bytes.len(), expected.len() + 6 * (12 + 12 + 4 + 8) + 4 * 13);
}

#[test]
fn writer_refuses_inconsistent_models() {
    let mut m = sample_mesh();
    m.faces.push([0, 1, 6]);
    let err = write_mesh(&mut Vec::new(), &m, false).unwrap_err();
    assert!(err.to_string().contains("face 4 has index 6"), "{err}");
    let mut m = sample_mesh();
    m.uvs.as_mut().unwrap().pop();
    let mut out = Vec::new();
    let err = write_mesh(&mut out, &m, true).unwrap_err();
    assert!(
        err.to_string().contains("uvs has 5 entries for 6 vertices"),
        "{err}"
    );
    assert!(out.is_empty(), "nothing is written on failure");
}

// --- layouts the reader accepts --------------------------------------------

#[test]
fn ascii_any_property_order_aliases_crlf_comments_and_polygons() {
    let text = "ply\r\nformat ascii 1.0\r\ncomment made by hand\r\nobj_info anything goes\r\n\
        element vertex 5\r\nproperty uint8 blue\r\nproperty float32 z\r\nproperty float64 y\r\n\
        property int16 x\r\nproperty uint8 green\r\nproperty uint8 red\r\n\
        element face 2\r\nproperty list uint16 int32 vertex_index\r\nend_header\r\n\
        1 0.5 0 0 2 3\r\n4 1.5 0 1 5 6\r\n7 2.5 1 1 8 9\r\n10 3.5 1 0 11 12\r\n13 4.5 2 0 14 15\r\n\
        4 0 1 2 3\r\n3 1 4 2\r\n";
    let m = mesh(text.as_bytes());
    assert_eq!(m.positions[1], Vec3::new(1.0, 0.0, 1.5));
    assert_eq!(m.colors.as_ref().unwrap()[1], [6, 5, 4, 255]);
    // The quad is fanned from its first corner.
    assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [1, 4, 2]]);
}

#[test]
fn every_scalar_type_in_both_byte_orders() {
    let header = |fmt: &str| {
        vec![
            "ply".to_string(),
            format!("format {fmt} 1.0"),
            "element vertex 1".into(),
            "property char a".into(),
            "property uchar b".into(),
            "property short c".into(),
            "property ushort d".into(),
            "property int e".into(),
            "property uint f".into(),
            "property float x".into(),
            "property double y".into(),
            "property int8 z".into(),
            "property uint16 nx".into(),
            "property int32 ny".into(),
            "property uint32 nz".into(),
        ]
    };
    for big in [false, true] {
        let mut body = Vec::new();
        macro_rules! put {
            ($v:expr) => {
                body.extend_from_slice(&if big {
                    $v.to_be_bytes()
                } else {
                    $v.to_le_bytes()
                })
            };
        }
        put!(-5i8);
        put!(250u8);
        put!(-300i16);
        put!(60000u16);
        put!(-70000i32);
        put!(3_000_000_000u32);
        put!(1.25f32);
        put!(-2.5f64);
        put!(-7i8);
        put!(65535u16);
        put!(-1i32);
        put!(4_000_000_000u32);
        let fmt = if big {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let h = header(fmt);
        let h: Vec<&str> = h.iter().map(String::as_str).collect();
        let p = points(&ply(&h, &body));
        assert_eq!(
            p.positions,
            vec![Vec3::new(1.25, -2.5, -7.0)],
            "big = {big}"
        );
        assert_eq!(
            p.normals,
            Some(vec![Vec3::new(65535.0, -1.0, 4_000_000_000.0)])
        );
    }
}

#[test]
fn face_lists_with_any_count_and_index_type() {
    for (count_ty, index_ty, size) in [
        ("uchar", "int", 4),
        ("uchar", "uint", 4),
        ("ushort", "ushort", 2),
        ("int", "uint8", 1),
        ("char", "short", 2),
        ("uint", "int", 4),
    ] {
        let list = format!("property list {count_ty} {index_ty} vertex_indices");
        let header = [
            "ply",
            "format binary_big_endian 1.0",
            "element vertex 4",
            "property float x",
            "property float y",
            "property float z",
            "element face 2",
            &list,
        ];
        let mut body: Vec<u8> = [0.0f32, 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0.]
            .iter()
            .flat_map(|x| x.to_be_bytes())
            .collect();
        let count_size = super::header::ScalarType::from_name(count_ty)
            .unwrap()
            .size();
        for poly in [&[0u8, 1, 2, 3][..], &[3, 2, 1]] {
            body.extend(std::iter::repeat_n(0, count_size - 1));
            body.push(poly.len() as u8);
            for &i in poly {
                body.extend(std::iter::repeat_n(0, size - 1));
                body.push(i);
            }
        }
        let m = mesh(&ply(&header, &body));
        assert_eq!(m.faces, vec![[0, 1, 2], [0, 2, 3], [3, 2, 1]], "{list}");
    }
}

#[test]
fn triangle_fast_path_falls_back_on_polygons() {
    // Little-endian `uchar int` is the fast layout; a quad forces the
    // general path, which must give the same fan.
    let header = [
        "ply",
        "format binary_little_endian 1.0",
        "element vertex 5",
        "property float x",
        "property float y",
        "property float z",
        "element face 2",
        "property list uchar int vertex_indices",
    ];
    let mut body = le_f32s(&[0., 0., 0., 1., 0., 0., 1., 1., 0., 0., 1., 0., 2., 2., 2.]);
    body.push(3);
    body.extend([4i32, 0, 1].iter().flat_map(|i| i.to_le_bytes()));
    body.push(4);
    body.extend([0i32, 1, 2, 3].iter().flat_map(|i| i.to_le_bytes()));
    assert_eq!(
        mesh(&ply(&header, &body)).faces,
        vec![[4, 0, 1], [0, 1, 2], [0, 2, 3]]
    );
}

#[test]
fn float_and_diffuse_colours_become_rgba8() {
    let text = ply(
        &[
            "ply",
            "format ascii 1.0",
            "element vertex 2",
            "property float x",
            "property float y",
            "property float z",
            "property float diffuse_red",
            "property double diffuse_green",
            "property float diffuse_blue",
            "property float diffuse_alpha",
        ],
        b"0 0 0 1 0.5 0 0.2\n1 1 1 2 -1 0.003 1\n",
    );
    let p = points(&text);
    assert_eq!(p.colors, Some(vec![[255, 128, 0, 51], [255, 0, 1, 255]]));
}

#[test]
fn ushort_colours_scale_to_8_bits() {
    let text = ply(
        &[
            "ply",
            "format ascii 1.0",
            "element vertex 1",
            "property float x",
            "property float y",
            "property float z",
            "property ushort red",
            "property ushort green",
            "property ushort blue",
        ],
        b"0 0 0 65535 0 32896\n",
    );
    assert_eq!(points(&text).colors, Some(vec![[255, 0, 128, 255]]));
}

#[test]
fn uv_names_are_all_recognised() {
    for (u, v) in [
        ("u", "v"),
        ("s", "t"),
        ("texture_u", "texture_v"),
        ("texture_s", "texture_t"),
    ] {
        let (pu, pv) = (format!("property float {u}"), format!("property float {v}"));
        let text = ply(
            &[
                "ply",
                "format ascii 1.0",
                "element vertex 3",
                "property float x",
                "property float y",
                "property float z",
                &pu,
                &pv,
                "element face 1",
                "property list uchar int vertex_indices",
            ],
            b"0 0 0 0.25 0.5\n1 0 0 1 0\n0 1 0 0 1\n3 0 1 2\n",
        );
        let uvs = mesh(&text).uvs.expect("uvs read");
        assert_eq!(uvs[0], Vec2::new(0.25, 0.5), "{u} {v}");
    }
}

#[test]
fn extra_properties_and_elements_are_skipped_in_binary_and_ascii() {
    let header = [
        "ply",
        "format binary_little_endian 1.0",
        "element material 2",
        "property list uchar float coefficients",
        "property uchar id",
        "element vertex 3",
        "property double quality",
        "property float x",
        "property list uchar int neighbours",
        "property float y",
        "property float z",
        "element face 1",
        "property uchar flags",
        "property list uchar int vertex_indices",
        "property list uchar float texcoord",
        "element empty_thing 1000000000000",
        "element edge 1",
        "property int vertex1",
        "property int vertex2",
    ];
    let mut body = Vec::new();
    // material: [2 floats] id, [0 floats] id
    body.push(2);
    body.extend(le_f32s(&[0.5, 0.25]));
    body.push(9);
    body.push(0);
    body.push(8);
    for (i, xyz) in [[0.0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]]
        .iter()
        .enumerate()
    {
        body.extend(7.0f64.to_le_bytes());
        body.extend(xyz[0].to_le_bytes());
        body.push(i as u8); // i neighbours
        body.extend(std::iter::repeat_n(0u8, 4 * i));
        body.extend(le_f32s(&xyz[1..]));
    }
    body.push(1);
    body.push(3);
    body.extend([2i32, 1, 0].iter().flat_map(|i| i.to_le_bytes()));
    body.push(6);
    body.extend(le_f32s(&[0.0; 6]));
    body.extend([0i32, 1].iter().flat_map(|i| i.to_le_bytes()));
    let m = mesh(&ply(&header, &body));
    assert_eq!(m.positions, vec![Vec3::ZERO, Vec3::X, Vec3::Y]);
    assert_eq!(m.faces, vec![[2, 1, 0]]);

    let mut ascii_header = header;
    ascii_header[1] = "format ascii 1.0";
    let body =
        "2 0.5 0.25 9\n0 8\n7 0 0 0 0\n7 1 1 5 0 0\n7 0 2 5 6 1 0\n1 3 2 1 0 6 0 0 0 0 0 0\n0 1\n";
    let m2 = mesh(&ply(&ascii_header, body.as_bytes()));
    assert_eq!(m2, m);
}

#[test]
fn range_grid_becomes_a_range_image() {
    // 3 × 2 lattice: cells 0, 2, 5 hold samples (vertices 0, 1, 2).
    let header = [
        "ply",
        "format ascii 1.0",
        "obj_info num_cols 3",
        "obj_info num_rows 2",
        "element vertex 3",
        "property float x",
        "property float y",
        "property float z",
        "property uchar red",
        "property uchar green",
        "property uchar blue",
        "element range_grid 6",
        "property list uchar int vertex_indices",
    ];
    let body = b"0 0 1 10 20 30\n2 0 1 40 50 60\n2 1 1 70 80 90\n1 0\n0\n1 1\n0\n0\n1 2\n";
    let Ok(Model::Range(r)) = load(&ply(&header, body)) else {
        panic!("expected a range image");
    };
    assert_eq!((r.cols, r.rows), (3, 2));
    assert_eq!(r.valid, vec![true, false, true, false, false, true]);
    assert_eq!(r.cell(1, 2), Some(Vec3::new(2.0, 1.0, 1.0)));
    assert_eq!(r.cell(0, 1), None);
    let colors = r.colors.as_ref().unwrap();
    assert_eq!(colors[2], [40, 50, 60, 255]);
    assert_eq!(colors[1], [0, 0, 0, 0]);
    assert_eq!(r.pose, None);
}

#[test]
fn faces_win_over_a_range_grid_and_an_empty_face_element_gives_points() {
    let base = [
        "ply",
        "format ascii 1.0",
        "element vertex 3",
        "property float x",
        "property float y",
        "property float z",
    ];
    let mut h = base.to_vec();
    h.extend(["element face 0", "property list uchar int vertex_indices"]);
    assert_eq!(points(&ply(&h, b"0 0 0\n1 0 0\n0 1 0\n")).len(), 3);
    let mut h = base.to_vec();
    h.extend([
        "obj_info num_cols 1",
        "obj_info num_rows 1",
        "element face 1",
        "property list uchar int vertex_indices",
        "element range_grid 1",
        "property list uchar int vertex_indices",
    ]);
    assert_eq!(
        mesh(&ply(&h, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n1 0\n")).faces,
        vec![[0, 1, 2]]
    );
}

// --- bad input ---------------------------------------------------------------

const XYZ: [&str; 6] = [
    "ply",
    "format binary_little_endian 1.0",
    "element vertex 2",
    "property float x",
    "property float y",
    "property float z",
];

#[test]
fn empty_file_and_wrong_magic() {
    fails(b"", "empty file");
    fails(b"solid cube\nfacet normal 0 0 1\n", "not a PLY file");
    fails(b"\x89PNG\r\n\x1a\n", "not a PLY file");
}

#[test]
fn unknown_or_missing_format_and_version() {
    fails(
        &ply(&["ply", "format binary_middle_endian 1.0"], b""),
        "unknown format 'binary_middle_endian'",
    );
    fails(
        &ply(&["ply", "format ascii 2.0"], b""),
        "unsupported PLY version '2.0'",
    );
    fails(
        &ply(&["ply", "element vertex 0", "property float x"], b""),
        "no format line",
    );
}

#[test]
fn missing_end_header() {
    fails(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n",
        "no end_header",
    );
    fails(
        b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n0 0 0\n",
        "unknown keyword '0'",
    );
}

#[test]
fn unknown_property_type_and_malformed_header_lines() {
    let mut h = XYZ.to_vec();
    h.push("property quaternion q");
    fails(&ply(&h, b""), "unknown property type 'quaternion'");
    fails(
        &ply(&["ply", "format ascii 1.0", "property float x"], b""),
        "property before any element",
    );
    fails(
        &ply(&["ply", "format ascii 1.0", "element vertex -1"], b""),
        "invalid count '-1'",
    );
    let mut h = XYZ.to_vec();
    h.push("property list float int vertex_indices");
    fails(
        &ply(&h, b""),
        "list count type 'float' is not an integer type",
    );
    let mut h = XYZ.to_vec();
    h.push("property float x");
    fails(&ply(&h, b""), "two properties named x");
}

#[test]
fn counts_far_larger_than_the_file_are_refused_before_allocating() {
    let mut h = XYZ.to_vec();
    h[2] = "element vertex 4000000000";
    let msg = fails(
        &ply(&h, &[0; 120]),
        "header declares 4000000000 vertex elements",
    );
    assert!(
        msg.contains("≥ 48000000000 bytes") && msg.contains("only 120 bytes"),
        "{msg}"
    );
    // ASCII: 2 bytes per value at least.
    h[1] = "format ascii 1.0";
    fails(
        &ply(&h, b"0 0 0\n"),
        "header declares 4000000000 vertex elements",
    );
    // Faces: 1 byte per record at least.
    let mut h = XYZ.to_vec();
    h.extend([
        "element face 1000",
        "property list uchar int vertex_indices",
    ]);
    fails(&ply(&h, &[0; 24 + 999]), "1000 face elements");
}

#[test]
fn count_times_size_overflow() {
    let h = [
        "ply",
        "format binary_little_endian 1.0",
        "element vertex 18446744073709551615",
        "property double x",
        "property double y",
        "property double z",
    ];
    fails(&ply(&h, &[0; 64]), "more than 2^64 bytes");
    // Two elements whose sizes only overflow when added.
    let h = [
        "ply",
        "format binary_little_endian 1.0",
        "element vertex 1537228672809129301",
        "property double x",
        "property double y",
        "property double z",
        "element other 1537228672809129301",
        "property double w",
    ];
    fails(&ply(&h, &[0; 64]), "header declares");
}

#[test]
fn truncated_binary_body() {
    fails(
        &ply(&XYZ, &le_f32s(&[0.0; 5])),
        "header declares 2 vertex elements",
    );
    let mut h = XYZ.to_vec();
    h.extend(["element face 1", "property list uchar int vertex_indices"]);
    let mut body = le_f32s(&[0.0; 6]);
    body.extend([3, 0, 0, 0, 0, 1, 0]);
    fails(
        &ply(&h, &body),
        "face 0: has a list of 3 items that runs past the end",
    );
}

#[test]
fn list_counts_that_overrun() {
    let mut h = XYZ.to_vec();
    h.extend(["element face 1", "property list uint int vertex_indices"]);
    let mut body = le_f32s(&[0.0; 6]);
    body.extend(4_000_000_000u32.to_le_bytes());
    fails(&ply(&h, &body), "list of 4000000000 items");
    h[1] = "format ascii 1.0";
    fails(
        &ply(&h, b"0 0 0\n1 1 1\n2000000000 1 2 3\n"),
        "list of 2000000000 items",
    );
    let mut h = XYZ.to_vec();
    h.extend(["element face 1", "property list short int vertex_indices"]);
    let mut body = le_f32s(&[0.0; 6]);
    body.extend((-3i16).to_le_bytes());
    fails(&ply(&h, &body), "negative list length -3");
}

#[test]
fn out_of_range_and_negative_indices() {
    let mut h = XYZ.to_vec();
    h.extend(["element face 1", "property list uchar int vertex_indices"]);
    let verts = le_f32s(&[0., 0., 0., 1., 0., 0.]);
    for (tri, needle) in [
        (
            [0i32, 1, 7],
            "face 0: has vertex index 7 but the file has 2 vertices",
        ),
        ([0, 1, -1], "face 0: has vertex index 4294967295"),
    ] {
        let mut body = verts.clone();
        body.push(3);
        body.extend(tri.iter().flat_map(|i| i.to_le_bytes()));
        fails(&ply(&h, &body), needle);
        // The reader itself refuses it, as the streaming reader does.
        assert!(read(&ply(&h, &body)).is_err());
    }
    // Big-endian takes the general path, which rejects negatives itself.
    let mut h = h.clone();
    h[1] = "format binary_big_endian 1.0";
    let mut body: Vec<u8> = [0.0f32, 0., 0., 1., 0., 0.]
        .iter()
        .flat_map(|x| x.to_be_bytes())
        .collect();
    body.push(3);
    body.extend([0i32, 1, -1].iter().flat_map(|i| i.to_be_bytes()));
    fails(&ply(&h, &body), "face 0: has invalid vertex index -1");
}

#[test]
fn non_finite_coordinates() {
    fails(
        &ply(&XYZ, &le_f32s(&[0., 0., 0., 1., f32::NAN, 0.])),
        "point 1 is not finite",
    );
    let mut h = XYZ.to_vec();
    h[1] = "format ascii 1.0";
    h.extend(["element face 0", "property list uchar int vertex_indices"]);
    fails(&ply(&h, b"0 0 0\ninf 0 0\n"), "point 1 is not finite");
    h[6] = "element face 1";
    h[2] = "element vertex 3";
    fails(
        &ply(&h, b"0 0 0\ninf 0 0\n0 1 0\n3 0 1 2\n"),
        "vertex 1 is not finite",
    );
}

#[test]
fn face_element_without_an_index_list() {
    let mut h = XYZ.to_vec();
    h.extend(["element face 1", "property uchar flags"]);
    fails(
        &ply(&h, &[0; 25]),
        "face element has no vertex_indices list property",
    );
    let mut h = XYZ.to_vec();
    h.extend(["element face 1", "property int vertex_indices"]);
    fails(
        &ply(&h, &[0; 28]),
        "face property vertex_indices is a single value",
    );
    let mut h = XYZ.to_vec();
    h.extend(["element face 1", "property list uchar float vertex_indices"]);
    fails(&ply(&h, &[0; 40]), "non-integer index type float");
}

#[test]
fn vertex_element_problems() {
    fails(
        &ply(
            &[
                "ply",
                "format ascii 1.0",
                "element vertex 1",
                "property float x",
                "property float y",
            ],
            b"0 0\n",
        ),
        "lacks one of the x, y, z",
    );
    fails(
        &ply(&["ply", "format ascii 1.0", "element stuff 0"], b""),
        "no vertex element",
    );
    let mut h = XYZ.to_vec();
    h.push("property list uchar float red");
    fails(&ply(&h, &[0; 64]), "vertex property red is a list");
}

#[test]
fn bad_ascii_values() {
    let mut h = XYZ.to_vec();
    h[1] = "format ascii 1.0";
    fails(
        &ply(&h, b"0 0 0\n1 zero 0\n"),
        "vertex 1: expected a number, found 'zero'",
    );
    fails(
        &ply(&h, b"0 0 0\n1 0     \n"),
        "vertex 1: has too few values on its line",
    );
    h.push("property uchar red");
    fails(
        &ply(&h, b"0 0 0 255\n1 0 0 256\n"),
        "vertex 1: value 256 is out of range for uchar",
    );
    fails(
        &ply(&h, b"0 0 0 255\n1 0 0 2.5\n"),
        "vertex 1: expected an integer, found '2.5'",
    );
    fails(&ply(&h, b"0 0 0 255\n1 0 0 \xff\xfe\n"), "not text");
}

#[test]
fn range_grid_problems() {
    let mut h = vec![
        "ply",
        "format ascii 1.0",
        "element vertex 1",
        "property float x",
        "property float y",
        "property float z",
        "element range_grid 2",
        "property list uchar int vertex_indices",
    ];
    fails(&ply(&h, b"0 0 0\n1 0\n0\n"), "needs 'obj_info num_cols'");
    h.insert(2, "obj_info num_cols 3");
    h.insert(2, "obj_info num_rows 1");
    fails(
        &ply(&h, b"0 0 0\n1 0\n0\n"),
        "range_grid has 2 cells but obj_info says num_cols 3 × num_rows 1",
    );
    h[2] = "obj_info num_rows 2";
    h[3] = "obj_info num_cols 1";
    fails(
        &ply(&h, b"0 0 0\n1 0\n1 5\n"),
        "range_grid cell 1 refers to vertex 5 but there are 1 vertices",
    );
    h[3] = "obj_info num_cols 18446744073709551615";
    fails(&ply(&h, b"0 0 0\n1 0\n0\n"), "range_grid has 2 cells");
}

#[test]
fn elements_without_properties_cost_nothing_whatever_their_count() {
    let mut h = XYZ.to_vec();
    h.insert(2, "element nothing 18446744073709551615");
    h[1] = "format ascii 1.0";
    assert_eq!(points(&ply(&h, b"0 0 0\n1 1 1")).len(), 2);
}

/// Every prefix and many single-byte corruptions of valid files decode to
/// a model or an error, never a panic.
#[test]
fn no_panic_on_truncation_or_corruption() {
    let m = sample_mesh();
    let mut files = Vec::new();
    for ascii in [false, true] {
        let mut b = Vec::new();
        write_mesh(&mut b, &m, ascii).unwrap();
        files.push(b);
    }
    let mut be = Vec::new();
    write_mesh(&mut be, &m, false).unwrap();
    let text = String::from_utf8_lossy(&be).replace("binary_little_endian", "binary_big_endian");
    files.push(text.into_bytes());
    use rand_xoshiro::SplitMix64;
    use rand_xoshiro::rand_core::{Rng, SeedableRng};
    let mut rng = SplitMix64::seed_from_u64(0x9e37_79b9_7f4a_7c15);
    for f in &files {
        for len in 0..=f.len() {
            let _ = read(&f[..len]);
            let _ = load(&f[..len]);
        }
        for _ in 0..3000 {
            let r = rng.next_u64();
            let mut g = f.clone();
            let at = (r >> 33) as usize % g.len();
            g[at] = (r >> 17) as u8;
            let _ = load(&g);
        }
    }
}

/// The streaming reader's verdict on `bytes`: the whole file read as the
/// out-of-core path reads it (header, vertices, faces).
fn stream(bytes: &[u8]) -> Result<u64, String> {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("s.ply");
    std::fs::write(&path, bytes).unwrap();
    let s = super::stream::PlyStream::open(&path).map_err(|e| e.to_string())?;
    s.for_each_vertex(|_| {}).map_err(|e| e.to_string())?;
    let mut n = 0;
    s.for_each_face(|_| {
        n += 1;
        Ok(())
    })
    .map_err(|e| e.to_string())?;
    Ok(n)
}

/// Binary triangle meshes for the readers' agreement: `verts` vertices
/// declared as `declared.0`, `faces` declared as `declared.1`, then
/// `extra` bytes.
fn tri_file(verts: usize, faces: &[[i32; 3]], declared: (usize, usize), extra: &[u8]) -> Vec<u8> {
    let h = [
        "ply",
        "format binary_little_endian 1.0",
        &format!("element vertex {}", declared.0),
        "property float x",
        "property float y",
        "property float z",
        &format!("element face {}", declared.1),
        "property list uchar int vertex_indices",
    ];
    let mut body = Vec::new();
    for i in 0..verts {
        body.extend(le_f32s(&[i as f32, (i * i) as f32, (i % 3) as f32]));
    }
    for f in faces {
        body.push(3);
        body.extend(f.iter().flat_map(|i| i.to_le_bytes()));
    }
    body.extend_from_slice(extra);
    ply(&h, &body)
}

/// One set of header, face and end checks for the in-core reader and the
/// streaming (out-of-core) one: each file below is refused by both, with
/// the same message; the good file is read alike by both.
#[test]
fn in_core_and_streaming_readers_refuse_the_same_files() {
    let faces: Vec<[i32; 3]> = (0..1_200)
        .map(|i| [i % 8, (i + 1) % 8, (i + 3) % 8])
        .collect();
    let good = tri_file(8, &faces, (8, 1_200), b"");
    assert_eq!(mesh(&good).faces.len(), 1_200);
    assert_eq!(stream(&good), Ok(1_200));
    for (what, bytes, needle) in [
        (
            "a vertex count one too high",
            tri_file(8, &faces, (9, 1_200), b""),
            "",
        ),
        (
            "a face count below the data",
            tri_file(8, &faces, (8, 200), b""),
            "13000 bytes follow the last element the header declares",
        ),
        (
            "a face repeating a corner",
            tri_file(8, &[[0, 1, 2], [7, 7, 7]], (8, 2), b""),
            "face 1: repeats a vertex index (7 7 7)",
        ),
        (
            "an index past the vertices",
            tri_file(8, &[[0, 1, 8]], (8, 1), b""),
            "face 0: has vertex index 8 but the file has 8 vertices",
        ),
        (
            "trailing bytes",
            tri_file(8, &faces, (8, 1_200), b"junk!"),
            "5 bytes follow the last element the header declares",
        ),
    ] {
        let in_core = load(&bytes).map(|_| ()).unwrap_err();
        let streamed = stream(&bytes).unwrap_err();
        assert!(in_core.contains(needle), "{what}: in core: {in_core}");
        assert!(streamed.contains(needle), "{what}: streamed: {streamed}");
        if !needle.is_empty() {
            assert!(
                streamed.ends_with(&in_core),
                "{what}: {streamed} / {in_core}"
            );
        }
    }
    // A face of two indices: the same words in both.
    let mut two = tri_file(8, &[], (8, 1), b"");
    two.extend([2, 0, 0, 0, 0, 1, 0, 0, 0]);
    let needle = "face 0: has 2 vertex indices (a face needs at least 3)";
    assert!(load(&two).unwrap_err().contains(needle));
    assert!(stream(&two).unwrap_err().contains(needle));
}

/// The corpus files of these classes are refused by both readers, each
/// with its one line.
#[test]
fn malformed_corpus_binary_faces_and_ends() {
    let dir = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../tests/malformed");
    for (file, needle) in [
        (
            "ply_trailing_bytes_binary.ply",
            "7 bytes follow the last element",
        ),
        (
            "ply_face_count_below_data_binary.ply",
            "13 bytes follow the last element",
        ),
        (
            "ply_repeated_face_index_binary.ply",
            "face 0: repeats a vertex index (2 2 2)",
        ),
        ("ply_vertex_count_one_high_binary.ply", "face 0: has "),
    ] {
        let bytes = std::fs::read(dir.join(file)).unwrap();
        let in_core = load(&bytes).map(|_| ()).unwrap_err();
        assert!(in_core.contains(needle), "{file}: {in_core}");
        let streamed = stream(&bytes).unwrap_err();
        assert!(streamed.contains(needle), "{file}: {streamed}");
    }
}

// --- real data (skipped when ../shared/data is absent) ---------------------

fn shared(rel: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../../../shared/data")
        .join(rel);
    if p.exists() {
        Some(p)
    } else {
        eprintln!("skipping: {} is absent", p.display());
        None
    }
}

#[test]
fn shipped_bunny() {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../data/models/stanford_bunny.ply");
    let m = crate::io::load_mesh(&path).unwrap();
    assert_eq!((m.vertex_count(), m.face_count()), (35_947, 69_451));
    // Re-encoding and decoding reproduces it exactly.
    let mut bytes = Vec::new();
    write_mesh(&mut bytes, &m, false).unwrap();
    assert_eq!(mesh(&bytes), m);
}

#[test]
fn shared_meshes_and_points() {
    if let Some(p) = shared("meshes/stanford_bunny.ply") {
        let m = crate::io::load_mesh(&p).unwrap();
        assert_eq!((m.vertex_count(), m.face_count()), (35_947, 69_451));
    }
    if let Some(p) = shared("meshes/table_scene_mug_stereo_textured_gridmesh.ply") {
        let m = crate::io::load_mesh(&p).unwrap();
        assert_eq!((m.vertex_count(), m.face_count()), (209_190, 408_812));
        assert_eq!(m.colors.as_ref().map(Vec::len), Some(209_190));
    }
    if let Some(p) = shared("points/table_scene_lms400.ply") {
        let Model::Points(pc) = crate::io::load(&p).unwrap() else {
            panic!("expected points");
        };
        assert_eq!(pc.len(), 460_400);
    }
}

#[test]
fn shared_range_images() {
    if let Some(p) = shared("range/stanford_bunny/bun000.ply") {
        let Model::Range(r) = crate::io::load(&p).unwrap() else {
            panic!("expected a range image");
        };
        assert_eq!((r.cols, r.rows), (512, 400));
        assert_eq!(r.valid_count(), 40_256);
        assert!(r.colors.is_none());
    }
    if let Some(p) = shared("range/pcl/table_scene_mug_stereo_textured.ply") {
        let Model::Range(r) = crate::io::load(&p).unwrap() else {
            panic!("expected a range image");
        };
        assert_eq!((r.cols, r.rows), (640, 480));
        assert_eq!(r.valid_count(), 209_280);
        let colors = r.colors.as_ref().expect("colours kept");
        let first = r.valid.iter().position(|v| *v).unwrap();
        assert_eq!(colors[first][3], 255);
        // Metres, in front of the camera.
        assert!(
            r.to_point_cloud()
                .positions
                .iter()
                .all(|p| p.z > 0.0 && p.z < 5.0)
        );
    }
}

/// ASCII PLY is line-structured: one record per line, never spread over
/// several, and every error names the file line.
#[test]
fn ascii_records_are_lines() {
    let mut h = XYZ.to_vec();
    h[1] = "format ascii 1.0";
    // XYZ is 6 header lines + "end_header": the body starts on line 8.
    assert_eq!(points(&ply(&h, b"0 0 0\n\n1 1 1\r\n\n")).len(), 2);
    fails(
        &ply(&h, b"0 0 0 1\n1 1\n"),
        "line 8: vertex 0: has more values",
    );
    fails(
        &ply(&h, b"0 0\n0 1 1 1\n"),
        "line 8: vertex 0: has too few values",
    );
    fails(
        &ply(&h, b"0 0 0\n\n1 1\n"),
        "line 10: vertex 1: has too few values",
    );
    fails(
        &ply(&h, b"0 0 0\n1 1 1\n2 2 2\n"),
        "line 10: more data lines",
    );
    fails(&ply(&h, b"0 0 0\n\n\n\n\n\n\n\n"), "vertex 1: is missing");
    h.extend(["element face 1", "property list uchar int vertex_indices"]);
    let h = {
        let mut h = h;
        h[2] = "element vertex 3";
        h
    };
    // The body starts on line 10 now.
    fails(
        &ply(&h, b"0 0 0\n1 0 0\n0 1 0\n3 0 1\n2\n"),
        "line 13: face 0: has a list of 3 items but its line holds fewer",
    );
    fails(
        &ply(&h, b"0 0 0\n1 0 0\n0 1 0\n2 0 1\n"),
        "line 13: face 0: has 2 vertex indices",
    );
    fails(
        &ply(&h, b"0 0 0\n1 0 0\n0 1 0\n0\n"),
        "face 0: has no vertex indices",
    );
    let m = mesh(&ply(&h, b"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"));
    assert_eq!(m.faces, vec![[0, 1, 2]]);
}
