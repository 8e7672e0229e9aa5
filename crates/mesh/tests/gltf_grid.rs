//! GLB content on a quantisation grid shared by several files (tiles):
//! border vertices of neighbouring files read back bit-for-bit equal;
//! points keep their colours; a grid that does not fit is an error.
//!
//! With `LODKIT_GLB_OUT=DIR`, the files written here are also copied into
//! DIR (scripts/check-gltf.sh runs the Khronos validator on them).

use std::collections::HashMap;

use glam::Vec3;
use lodkit_mesh::io::gltf::{self, GlbOptions, QuantGrid};
use lodkit_mesh::{Aabb, Model, PointCloud, TriMesh, shapes};

fn keep(name: &str, bytes: &[u8]) {
    if let Some(dir) = std::env::var_os("LODKIT_GLB_OUT") {
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(std::path::Path::new(&dir).join(name), bytes).unwrap();
    }
}

/// The faces of `m` whose centroid is on `side` of x = cut, as a mesh of
/// the vertices they use (border vertices land in both halves).
fn half(m: &TriMesh, cut: f32, side: bool) -> TriMesh {
    let mut map = HashMap::new();
    let mut out = TriMesh::default();
    let normals = m.normals.as_ref();
    let mut out_normals = Vec::new();
    for f in &m.faces {
        let c = f.iter().map(|&i| m.positions[i as usize].x).sum::<f32>() / 3.0;
        if (c < cut) != side {
            continue;
        }
        let face = f.map(|i| {
            *map.entry(i).or_insert_with(|| {
                out.positions.push(m.positions[i as usize]);
                if let Some(n) = normals {
                    out_normals.push(n[i as usize]);
                }
                (out.positions.len() - 1) as u32
            })
        });
        out.faces.push(face);
    }
    if normals.is_some() {
        out.normals = Some(out_normals);
    }
    out
}

fn compress_options() -> Vec<GlbOptions> {
    let mut v = vec![GlbOptions { compress: false }];
    if cfg!(feature = "meshopt") {
        v.push(GlbOptions { compress: true });
    }
    v
}

fn bits(v: Vec3) -> [u32; 3] {
    v.to_array().map(f32::to_bits)
}

/// Positions of the read-back mesh (the writer may reorder vertices).
fn read_back(bytes: &[u8]) -> Vec<Vec3> {
    match gltf::read_model(bytes, None).unwrap() {
        Model::Mesh(m) => m.positions,
        other => panic!("a {}", other.kind()),
    }
}

#[test]
fn border_vertices_of_two_tiles_read_back_bit_for_bit_equal() {
    let mut m = shapes::icosphere(4);
    // Off the origin and scaled, so no grid point is trivially round.
    for p in &mut m.positions {
        *p = *p * 37.3 + Vec3::new(1234.567, -89.1, 4.2);
    }
    m.normals = Some(lodkit_mesh::normals::vertex_normals(&m));
    let cut = 1234.567 + 3.1;
    let (left, right) = (half(&m, cut, true), half(&m, cut, false));
    let grid = QuantGrid::covering(m.bbox(), 16);
    for opts in compress_options() {
        let a = gltf::write_glb_on_grid(&[("left", &left)], &opts, &grid).unwrap();
        let b = gltf::write_glb_on_grid(&[("right", &right)], &opts, &grid).unwrap();
        keep(&format!("grid_left_c{}.glb", opts.compress as u8), &a);
        keep(&format!("grid_right_c{}.glb", opts.compress as u8), &b);
        let (pa, pb) = (read_back(&a), read_back(&b));
        // Every read-back position is the grid point of some source vertex.
        let on_grid = |p: Vec3| grid.point(grid.index(p));
        let sa: std::collections::HashSet<[u32; 3]> = pa.iter().map(|&p| bits(p)).collect();
        let sb: std::collections::HashSet<[u32; 3]> = pb.iter().map(|&p| bits(p)).collect();
        let mut shared = 0;
        for p in &left.positions {
            if right.positions.contains(p) {
                let q = bits(on_grid(*p));
                assert!(
                    sa.contains(&q) && sb.contains(&q),
                    "border vertex {p} split"
                );
                shared += 1;
            }
        }
        assert!(shared > 20, "only {shared} border vertices");
        // Within half a step of the input.
        let step = grid.step() as f32;
        for (src, back) in [(&left, &pa), (&right, &pb)] {
            for p in back {
                let near = src
                    .positions
                    .iter()
                    .map(|s| (*s - *p).abs().max_element())
                    .fold(f32::MAX, f32::min);
                assert!(near <= step * 0.5 + 1e-4, "{near} > half of {step}");
            }
        }
    }
}

/// Per-file grids (what `compress` alone does) split border vertices:
/// the reason for the shared grid.
#[cfg(feature = "meshopt")]
#[test]
fn per_file_grids_split_border_vertices() {
    let mut m = shapes::icosphere(4);
    for p in &mut m.positions {
        *p = *p * 37.3 + Vec3::new(1234.567, -89.1, 4.2);
    }
    let cut = 1234.567 + 3.1;
    let (left, right) = (half(&m, cut, true), half(&m, cut, false));
    let opts = GlbOptions { compress: true };
    let a = read_back(&gltf::write_glb_with(&[("l", &left)], &opts).unwrap());
    let b = read_back(&gltf::write_glb_with(&[("r", &right)], &opts).unwrap());
    let sb: std::collections::HashSet<[u32; 3]> = b.iter().map(|&p| bits(p)).collect();
    let border: Vec<Vec3> = left
        .positions
        .iter()
        .filter(|p| right.positions.contains(p))
        .copied()
        .collect();
    // The left tile's copy of each border vertex: its nearest read-back point.
    let split = border
        .iter()
        .filter(|p| {
            let near = a
                .iter()
                .min_by(|x, y| (**x - **p).length().total_cmp(&(**y - **p).length()))
                .unwrap();
            !sb.contains(&bits(*near))
        })
        .count();
    assert!(split > 0, "per-file grids kept every border vertex equal");
}

#[test]
fn points_on_the_grid_keep_colours_and_normals() {
    let n = 3000;
    let positions: Vec<Vec3> = (0..n)
        .map(|i| {
            let t = i as f32 * 0.618;
            Vec3::new(
                636_000.0 + t.sin() * 500.0,
                t.cos() * 200.0,
                (i % 97) as f32 * 0.3,
            ) - Vec3::new(636_000.0, 0.0, 0.0)
        })
        .collect();
    let colors: Vec<[u8; 4]> = (0..n)
        .map(|i| [(i % 256) as u8, (i * 7 % 256) as u8, 40, 255])
        .collect();
    let normals: Vec<Vec3> = (0..n)
        .map(|i| Vec3::new((i as f32).sin(), (i as f32).cos(), 0.5).normalize())
        .collect();
    let cloud = PointCloud {
        positions: positions.clone(),
        normals: Some(normals.clone()),
        colors: Some(colors.clone()),
    };
    let grid = QuantGrid::covering(Aabb::from_points(&positions), 16);
    for opts in compress_options() {
        let bytes = gltf::write_points_glb_on_grid("points", &cloud, &opts, &grid).unwrap();
        keep(&format!("grid_points_c{}.glb", opts.compress as u8), &bytes);
        let Model::Points(back) = gltf::read_model(&bytes, None).unwrap() else {
            panic!("points")
        };
        assert_eq!(back.len(), n);
        // The POINTS writer keeps the order: compare one to one.
        let step = grid.step() as f32;
        for (p, q) in positions.iter().zip(&back.positions) {
            assert_eq!(bits(*q), bits(grid.point(grid.index(*p))));
            assert!((*p - *q).abs().max_element() <= step * 0.5 + 1e-3);
        }
        assert_eq!(back.colors.as_ref().unwrap(), &colors);
        let tol = if opts.compress { 0.02 } else { 1e-6 };
        for (a, b) in normals.iter().zip(back.normals.as_ref().unwrap()) {
            assert!(a.dot(*b) > 1.0 - tol, "{a} vs {b}");
        }
        // Same input, same bytes.
        assert_eq!(
            bytes,
            gltf::write_points_glb_on_grid("points", &cloud, &opts, &grid).unwrap()
        );
    }
}

#[test]
fn a_grid_that_does_not_fit_is_a_one_line_error() {
    let m = shapes::icosphere(2);
    let opts = GlbOptions::default();
    // 24 bits over the whole box: a file spanning it needs > 16 bits.
    let fine = QuantGrid::covering(m.bbox(), 24);
    let e = gltf::write_glb_on_grid(&[("m", &m)], &opts, &fine)
        .unwrap_err()
        .0;
    assert!(e.contains("65,535") && !e.contains('\n'), "{e}");
    let off = QuantGrid {
        origin: Vec3::new(0.3, 0.0, 0.0),
        step_log2: -2,
    };
    let e = gltf::write_glb_on_grid(&[("m", &m)], &opts, &off)
        .unwrap_err()
        .0;
    assert!(e.contains("not a multiple of the step"), "{e}");
    let far = QuantGrid {
        origin: Vec3::ZERO,
        step_log2: -30,
    };
    let e = gltf::write_glb_on_grid(&[("m", &m)], &opts, &far)
        .unwrap_err()
        .0;
    assert!(e.contains("2^24"), "{e}");
}

/// The shipped bunny as one tile (vertex normals, on a 16-bit grid over
/// its box): read back whole. With `LODKIT_GLB_OUT`, also its plain GLB,
/// for a size comparison with `gltfpack -cc` (docs/gltf.md).
#[test]
fn the_bunny_as_a_tile_reads_back() {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/models/stanford_bunny.ply");
    let mut m = lodkit_mesh::io::load_mesh(&path).unwrap();
    m.normals = Some(lodkit_mesh::normals::vertex_normals(&m));
    let grid = QuantGrid::covering(m.bbox(), 16);
    for opts in compress_options() {
        let bytes = gltf::write_glb_on_grid(&[("bunny", &m)], &opts, &grid).unwrap();
        keep(&format!("grid_bunny_c{}.glb", opts.compress as u8), &bytes);
        let Model::Mesh(back) = gltf::read_model(&bytes, None).unwrap() else {
            panic!("a mesh")
        };
        assert_eq!(back.faces.len(), m.faces.len());
    }
    keep(
        "bunny_plain.glb",
        &gltf::write_glb(&[("bunny", &m)]).unwrap(),
    );
}
