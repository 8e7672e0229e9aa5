use glam::Vec3;

use super::dedupe::dedupe_face_triangles;
use super::hamiltonian_split::{Split, split_by_cycle};
use super::*;
use crate::octree::{Frame, morton, unmorton};
use crate::stats::non_manifold_triangles;
use crate::triangulation_table::{Shape, corner, pair, table};

/// A thin spherical shell of cubes at `level`, Morton-sorted, crossing
/// many bricks (and the grid's lower faces when `offset` is 0).
fn shell(level: u8, offset: f32) -> LevelSurface {
    let side = 1u32 << level;
    let c = side as f32 * 0.5 - offset;
    let r = side as f32 * 0.42;
    let mut cells = Vec::new();
    for z in 0..side {
        for y in 0..side {
            for x in 0..side {
                let p = Vec3::new(x as f32, y as f32, z as f32) + 0.5 - c;
                if (p.length() - r).abs() < 0.5 {
                    cells.push(morton([x, y, z]));
                }
            }
        }
    }
    cells.sort_unstable();
    let frame = Frame {
        origin: Vec3::ZERO,
        size: 1.0,
    };
    let positions = cells
        .iter()
        .map(|&m| frame.cell_centre(unmorton(m), u32::from(level)))
        .collect();
    LevelSurface {
        level,
        frame,
        cells,
        positions,
        colours: None,
        normals: None,
    }
}

/// Configuration counts by brute force: every origin next to an ON cube.
fn brute_force_configurations(s: &LevelSurface) -> Vec<u64> {
    let on: std::collections::HashSet<[i64; 3]> = s
        .cells
        .iter()
        .map(|&m| unmorton(m).map(i64::from))
        .collect();
    let mut origins = std::collections::BTreeSet::new();
    for c in &on {
        for j in 0..8u8 {
            let k = corner(j);
            origins.insert([
                c[0] - i64::from(k[0]),
                c[1] - i64::from(k[1]),
                c[2] - i64::from(k[2]),
            ]);
        }
    }
    let mut counts = vec![0u64; CLASS_COUNT + 1];
    for o in origins {
        let mut mask = 0u8;
        for j in 0..8u8 {
            let k = corner(j);
            let p = [
                o[0] + i64::from(k[0]),
                o[1] + i64::from(k[1]),
                o[2] + i64::from(k[2]),
            ];
            if on.contains(&p) {
                mask |= 1 << j;
            }
        }
        counts[table().configs[mask as usize].class as usize] += 1;
    }
    counts[0] = 0;
    counts
}

#[test]
fn brick_scan_visits_every_neighbourhood_exactly_once() {
    // Shells touching the grid's lower faces and shells away from
    // them, at levels below, at and above one brick per axis.
    for (level, offset) in [(3, 0.0), (4, 0.3), (5, 0.0), (6, 1.7), (6, 0.0)] {
        let s = shell(level, offset);
        let t = triangulate(&s, &TriangulateOptions::DEFAULT);
        assert_eq!(
            t.stats.configurations,
            brute_force_configurations(&s),
            "level {level}, offset {offset}"
        );
        assert!(t.stats.triangles > 0);
    }
}

#[test]
fn unsorted_cells_triangulate_like_sorted_ones() {
    let s = shell(5, 0.3);
    let opts = TriangulateOptions {
        orient: false,
        ..TriangulateOptions::DEFAULT
    };
    let sorted = triangulate(&s, &opts);
    // Reverse the cubes: vertex i becomes n − 1 − i.
    let n = s.cells.len() as u32;
    let mut rev = s.clone();
    rev.cells.reverse();
    rev.positions.reverse();
    let reversed = triangulate(&rev, &opts);
    let canon = |faces: &[[u32; 3]], map: &dyn Fn(u32) -> u32| {
        let mut f: Vec<[u32; 3]> = faces
            .iter()
            .map(|t| {
                let mut t = t.map(map);
                t.sort_unstable();
                t
            })
            .collect();
        f.sort_unstable();
        f
    };
    assert_eq!(
        canon(&sorted.mesh.faces, &|v| v),
        canon(&reversed.mesh.faces, &|v| n - 1 - v)
    );
    assert_eq!(sorted.stats.configurations, reversed.stats.configurations);
}

#[test]
fn tetrahedron_with_a_fifth_shared_edge_builds_the_disc_that_leaves_it_to_two_neighbours() {
    // C_6: a face triangle 0, 1, 2 and the opposite corner 7.
    let mask = 0b1000_0111u8;
    let cfg = &table().configs[mask as usize];
    assert_eq!(cfg.class, 6);
    let Shape::Solid(tris) = &cfg.shape else {
        panic!("C_6 is solid")
    };
    let e = |a: u8, b: u8| 1u32 << pair(a, b);
    let cycle = e(0, 1) | e(1, 7) | e(7, 2) | e(2, 0);
    // The paper's case: either disc, chosen by dihedral angle.
    assert!(matches!(
        split_by_cycle(mask, cycle, 0, tris),
        Split::Either(_)
    ));
    // The face diagonal 1–2 shared too, by two neighbours: build the
    // disc around the body diagonal 0–7, which no neighbour has.
    let shared = cycle | e(1, 2);
    let Split::Only(keep) = split_by_cycle(mask, shared, e(1, 2), tris) else {
        panic!("one disc left")
    };
    let built: Vec<[u8; 3]> = (0..tris.len())
        .filter(|i| keep & (1 << i) != 0)
        .map(|i| tris[i])
        .collect();
    assert_eq!(built.len(), 2);
    assert!(built.iter().all(|t| t.contains(&0) && t.contains(&7)));
    // Shared by one neighbour only: leaving it would open a hole, so
    // the disc holding it is built on trial, its rim the cycle.
    let Split::Holding(keep, rim) = split_by_cycle(mask, shared, 0, tris) else {
        panic!("the disc holding 1–2 is tried")
    };
    assert_eq!(rim, cycle);
    assert_eq!(keep.count_ones(), 2);
    assert!(
        (0..tris.len())
            .filter(|i| keep & (1 << i) != 0)
            .all(|i| tris[i].contains(&1) && tris[i].contains(&2))
    );
    // Every edge shared: several cycles, no choice.
    assert_eq!(
        split_by_cycle(mask, cfg.edges, cfg.edges, tris),
        Split::Whole
    );
}

#[test]
fn face_triangle_dedupe_keeps_the_first_copy_in_any_vertex_order() {
    let mut faces = vec![
        [0, 1, 2],
        [5, 6, 7],
        [2, 0, 1],
        [1, 2, 3],
        [7, 5, 6],
        [0, 2, 1],
    ];
    // Triangle 1 is not a candidate: its copy 4 is kept.
    let dropped = dedupe_face_triangles(&mut faces, &[0, 2, 3, 4, 5]);
    assert_eq!(dropped, [2, 5]);
    assert_eq!(faces, [[0, 1, 2], [5, 6, 7], [1, 2, 3], [7, 5, 6]]);
}

#[test]
fn owned_surfaces_triangulate_like_borrowed_ones() {
    use crate::{DecodeOptions, EncodeOptions, decode, encode};
    let model = lodkit_mesh::Model::Mesh(lodkit_mesh::shapes::blob(5_000));
    let opts = EncodeOptions {
        depth: Some(5),
        ..EncodeOptions::DEFAULT
    };
    let bytes = encode(&model, &opts).unwrap().bytes;
    let d = decode(&bytes, &DecodeOptions::default()).unwrap();
    // Coarse levels hold phantoms (their cells are filtered), the
    // finest none (its cells move).
    for r in [3u8, 5] {
        let s = d.surface(r).unwrap();
        let owned = d.clone().into_surface(r).unwrap();
        assert_eq!(owned.cells, s.cells, "level {r}");
        assert_eq!(owned.positions, s.positions, "level {r}");
        let t = triangulate(&s, &TriangulateOptions::DEFAULT);
        let u = triangulate_owned(owned, &TriangulateOptions::DEFAULT);
        assert!(!t.mesh.faces.is_empty());
        assert_eq!(u.mesh.faces, t.mesh.faces, "level {r}");
        assert_eq!(u.mesh.positions, t.mesh.positions, "level {r}");
    }
}

/// Edges used by one triangle.
fn boundary_edges(faces: &[[u32; 3]]) -> usize {
    let mesh = TriMesh {
        faces: faces.to_vec(),
        ..TriMesh::default()
    };
    lodkit_mesh::topology::edge_multiplicities(&mesh)
        .iter()
        .filter(|e| e.count == 1)
        .count()
}

#[test]
fn settled_levels_are_manifold_where_thinned_and_open_no_hole() {
    use crate::{DecodeOptions, EncodeOptions, ThinningOptions, decode, encode};
    let thinning = ThinningOptions {
        outer: true,
        relax_below: 5,
    };
    for (name, mesh) in [
        ("blob", lodkit_mesh::shapes::blob(20_000)),
        ("torus", lodkit_mesh::shapes::torus(1.0, 0.3, 96, 48)),
    ] {
        let opts = EncodeOptions {
            depth: Some(7),
            thinning,
            ..EncodeOptions::DEFAULT
        };
        let e = encode(&lodkit_mesh::Model::Mesh(mesh), &opts).unwrap();
        let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
        for r in 2..=7u8 {
            let s = d.surface(r).unwrap();
            let plain = TriangulateOptions {
                orient: false,
                ..TriangulateOptions::DEFAULT
            };
            let t = triangulate(&s, &plain);
            // Decimation with a zero threshold merges nothing but
            // builds every solid at scan time, ambiguous ones whole:
            // the hole-free reference of §6.2.
            let whole = triangulate(
                &s,
                &TriangulateOptions {
                    decimate: Some(0.0),
                    ..plain
                },
            );
            let nm = non_manifold_triangles(&t.mesh);
            let f = t.mesh.faces.len();
            assert!(
                boundary_edges(&t.mesh.faces) <= boundary_edges(&whole.mesh.faces),
                "{name} r={r}: settling opened a hole"
            );
            assert!(
                nm <= non_manifold_triangles(&whole.mesh),
                "{name} r={r}: {nm} non-manifold triangles"
            );
            if r >= thinning.relax_below {
                assert!(nm * 100 <= f, "{name} r={r}: {nm} of {f} non-manifold");
                let per = f as f64 / s.cells.len() as f64;
                assert!(
                    (1.8..=2.3).contains(&per),
                    "{name} r={r}: {per} per particle"
                );
            }
            // Same input, same triangles.
            assert_eq!(triangulate(&s, &plain).mesh.faces, t.mesh.faces);
        }
    }
}
