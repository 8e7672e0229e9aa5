//! A writer and its reader cannot drift apart: random small models, built
//! with each combination of attributes (from a mesh or from points; with or
//! without input normals; with or without colours; closed or open), are
//! written with `to_bytes` and read back with `from_bytes`, and every cut
//! of the model read back is the built model's cut, bit for bit: the same
//! triangles over the same vertices (positions, normals and colours
//! compared by their bits; the file renumbers vertices, so indices are
//! compared as a one-to-one correspondence that keeps every shared
//! vertex shared), by LOD number, by triangle budget and by view. The file read back also writes the same bytes again.
//!
//! Open surfaces (a height field) matter: there the root cube itself holds
//! triangles, whose vertices chunk 0's vertex section carries.

use std::collections::HashMap;

use lodkit_mco::{Camera, McoModel, Options, build_from_mesh, build_from_points};
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::{PointCloud, TriMesh, shapes};
use proptest::prelude::*;

/// The surface a random model samples.
#[derive(Debug, Clone, Copy)]
enum Shape {
    /// A closed bumpy sphere.
    Closed,
    /// An open wavy sheet (a height field over a square).
    Open,
}

/// How the model is built.
#[derive(Debug, Clone, Copy)]
enum Source {
    Mesh,
    Points,
}

#[derive(Debug, Clone)]
struct Case {
    shape: Shape,
    source: Source,
    normals: bool,
    colors: bool,
    /// Bump / wave parameters.
    waves: [f32; 4],
    resolution: u32,
}

fn case() -> impl Strategy<Value = Case> {
    (
        prop_oneof![Just(Shape::Closed), Just(Shape::Open)],
        prop_oneof![Just(Source::Mesh), Just(Source::Points)],
        any::<bool>(),
        any::<bool>(),
        [0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0, 0.0f32..1.0],
        6u32..20,
    )
        .prop_map(|(shape, source, normals, colors, waves, resolution)| Case {
            shape,
            source,
            normals,
            colors,
            waves,
            resolution,
        })
}

/// The case's surface as a mesh (normals and colours as the case asks).
fn mesh(c: &Case) -> TriMesh {
    let [a, b, f, g] = c.waves;
    let mut m = match c.shape {
        Shape::Closed => {
            let mut m = shapes::icosphere(3);
            for p in &mut m.positions {
                let d = p.normalize();
                let r = 1.0 + 0.25 * a * (3.0 * d.x + 7.0 * f).sin() * (2.0 * d.y + 5.0 * g).cos();
                *p = d * r * Vec3::new(1.0, 0.6 + 0.4 * b, 1.0);
            }
            m
        }
        Shape::Open => {
            let n = 24u32;
            let mut positions = Vec::new();
            for j in 0..=n {
                for i in 0..=n {
                    let (x, y) = (i as f32 / n as f32 - 0.5, j as f32 / n as f32 - 0.5);
                    let z =
                        0.2 * a * (6.0 * x + 9.0 * f).sin() + 0.15 * b * (5.0 * y + 4.0 * g).cos();
                    positions.push(Vec3::new(x, y, z));
                }
            }
            let mut faces = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    let v = j * (n + 1) + i;
                    faces.push([v, v + 1, v + n + 2]);
                    faces.push([v, v + n + 2, v + n + 1]);
                }
            }
            TriMesh {
                positions,
                faces,
                ..Default::default()
            }
        }
    };
    m.normals = c.normals.then(|| lodkit_mesh::normals::vertex_normals(&m));
    m.uvs = None;
    m.colors = c.colors.then(|| {
        m.positions
            .iter()
            .map(|p| {
                let k = |x: f32| ((x * 97.0).sin() * 127.0 + 128.0) as u8;
                [k(p.x), k(p.y + 0.3), k(p.z - 0.7), 255]
            })
            .collect()
    });
    m
}

fn build(c: &Case) -> McoModel {
    let opts = Options {
        resolution: Some(c.resolution),
    };
    let m = mesh(c);
    match c.source {
        Source::Mesh => build_from_mesh(&m, &opts).unwrap(),
        Source::Points => build_from_points(
            &PointCloud {
                positions: m.positions,
                normals: m.normals,
                colors: m.colors,
            },
            &opts,
        )
        .unwrap(),
    }
}

/// A vertex as bits: position, normal, colour.
type Key = [u32; 7];

/// The cut `idx` of `m`: each triangle as its vertices' bits (rotated to
/// to the smallest rotation, so orientation is kept) beside its indices,
/// sorted by the bits. Triangles with two equal indices (crack patching's
/// collapsed edges: no area, drawn as nothing) are left out.
fn canonical(m: &McoModel, idx: &[u32]) -> Vec<([Key; 3], [u32; 3])> {
    let key = |v: u32| -> Key {
        let (p, n) = (m.positions()[v as usize], m.normals()[v as usize]);
        let c = if m.has_colors() {
            u32::from_le_bytes(m.colors()[v as usize])
        } else {
            0
        };
        [
            p.x.to_bits(),
            p.y.to_bits(),
            p.z.to_bits(),
            n.x.to_bits(),
            n.y.to_bits(),
            n.z.to_bits(),
            c,
        ]
    };
    let mut out: Vec<([Key; 3], [u32; 3])> = idx
        .chunks_exact(3)
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .map(|t| {
            let k = [key(t[0]), key(t[1]), key(t[2])];
            // The smallest rotation as a whole: a triangle that crack
            // patching made degenerate has two equal vertices.
            let s = (0..3)
                .min_by_key(|&j| [k[j], k[(j + 1) % 3], k[(j + 2) % 3]])
                .unwrap();
            let r = [s, (s + 1) % 3, (s + 2) % 3];
            (r.map(|j| k[j]), r.map(|j| t[j]))
        })
        .collect();
    out.sort_unstable();
    out
}

/// The two cuts are the same triangles, bit for bit, over the same vertex
/// sharing: their indices correspond one to one.
fn same(m: &McoModel, a: &[u32], back: &McoModel, b: &[u32]) -> bool {
    let (ca, cb) = (canonical(m, a), canonical(back, b));
    if ca.len() != cb.len() || ca.iter().zip(&cb).any(|(x, y)| x.0 != y.0) {
        return false;
    }
    let (mut fwd, mut rev) = (HashMap::new(), HashMap::new());
    ca.iter().zip(&cb).all(|(x, y)| {
        (0..3).all(|j| {
            *fwd.entry(x.1[j]).or_insert(y.1[j]) == y.1[j]
                && *rev.entry(y.1[j]).or_insert(x.1[j]) == x.1[j]
        })
    })
}

/// Every cut of `back` equals the same cut of `m`, bit for bit.
fn same_cuts(m: &McoModel, back: &McoModel) -> Result<(), TestCaseError> {
    prop_assert_eq!(back.max_lod(), m.max_lod());
    prop_assert_eq!(back.full_triangles(), m.full_triangles());
    prop_assert_eq!(back.has_colors(), m.has_colors());
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let n = m.max_lod();
    for k in [0, 1, n / 5, n / 3, n / 2, n - n / 4, n] {
        let k = k.min(n);
        m.extract_lod(k, &mut a);
        back.extract_lod(k, &mut b);
        prop_assert!(same(m, &a, back, &b), "LOD {}", k);
    }
    let full = m.full_triangles();
    for t in [1, 50, full / 4, full / 2, 3 * full / 4, full] {
        let ka = m.extract_triangles(t, &mut a);
        let kb = back.extract_triangles(t, &mut b);
        prop_assert_eq!(ka, kb);
        prop_assert!(same(m, &a, back, &b), "budget {}", t);
    }
    let (lo, hi) = m.bounds();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length());
    for (eye, tol) in [
        (Vec3::new(0.0, 0.0, 1.5), 1.0),
        (Vec3::new(0.9, 0.3, -0.2), 4.0),
        (Vec3::new(0.2, -0.3, 0.3), 0.5),
    ] {
        let cam = Camera::looking_at(c + eye * r, c);
        let na = m.extract_view(&cam, tol, &mut a);
        let nb = back.extract_view(&cam, tol, &mut b);
        prop_assert_eq!(na, nb);
        prop_assert!(same(m, &a, back, &b), "view from {:?}", eye);
    }
    Ok(())
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 96, ..ProptestConfig::default() })]

    #[test]
    fn a_model_read_from_its_bytes_cuts_bit_for_bit_alike(c in case()) {
        let m = build(&c);
        let bytes = m.to_bytes();
        let back = McoModel::from_bytes(&bytes)
            .map_err(|e| TestCaseError::fail(format!("{c:?}: {e}")))?;
        same_cuts(&m, &back)?;
        prop_assert!(back.to_bytes() == bytes, "a read model writes other bytes");
        // A prefix of whole chunks serves its LOD numbers as the whole file.
        let table = McoModel::chunk_table(&bytes).unwrap();
        let first = &table[0];
        let p = McoModel::from_prefix(&bytes[..(first.offset + first.bytes) as usize]).unwrap();
        let (mut a, mut b) = (Vec::new(), Vec::new());
        m.extract_lod(p.max_lod, &mut a);
        p.model.extract_lod(p.max_lod, &mut b);
        prop_assert!(same(&m, &a, &p.model, &b), "prefix of chunk 0");
    }
}

/// Every combination of attributes once, on both shapes (the proptest
/// above draws them at random; this pins each).
#[test]
fn every_attribute_combination_reads_back() {
    for shape in [Shape::Closed, Shape::Open] {
        for source in [Source::Mesh, Source::Points] {
            for normals in [false, true] {
                for colors in [false, true] {
                    let c = Case {
                        shape,
                        source,
                        normals,
                        colors,
                        waves: [0.7, 0.4, 0.3, 0.9],
                        resolution: 14,
                    };
                    let m = build(&c);
                    assert_eq!(m.has_colors(), colors, "{c:?}");
                    let back = McoModel::from_bytes(&m.to_bytes())
                        .unwrap_or_else(|e| panic!("{c:?}: {e}"));
                    same_cuts(&m, &back).unwrap_or_else(|e| panic!("{c:?}: {e}"));
                }
            }
        }
    }
}
