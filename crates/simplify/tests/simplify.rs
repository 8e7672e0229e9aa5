//! Behaviour tests of the simplifier, named for what they pin.

use glam::{Vec2, Vec3};
use lodkit_mesh::TriMesh;
use lodkit_mesh::shapes::{blob, holey_sphere, icosphere, non_manifold, terrain, torus, uv_sphere};
use lodkit_mesh::topology::topology_stats;
use lodkit_simplify::{
    Options, Simplifier, StopReason, Target, halving_targets, lod_chain, simplify,
};

fn within_half_percent(got: usize, target: usize) {
    assert!(got <= target, "{got} faces for a target of {target}");
    assert!(
        (target - got) as f64 <= (target as f64 * 0.005).max(2.0),
        "{got} faces for a target of {target}"
    );
}

/// Every face of a star-shaped closed mesh around the origin faces outward.
fn all_outward(m: &TriMesh) -> bool {
    (0..m.faces.len()).all(|f| {
        let [a, b, c] = m.triangle(f);
        (b - a).cross(c - a).dot((a + b + c) / 3.0) > 0.0
    })
}

fn welded(m: &TriMesh) -> TriMesh {
    lodkit_mesh::weld::weld(m, 0.0).0
}

#[test]
fn reaches_the_target_within_half_a_percent() {
    let m = icosphere(5); // 20,480 faces
    for target in [10_240, 2_048, 1_000, 204, 100] {
        let out = simplify(&m, &Options::faces(target)).unwrap();
        assert_eq!(out.report.stop, StopReason::Reached);
        within_half_percent(out.mesh.faces.len(), target);
        assert_eq!(out.report.triangles, out.mesh.faces.len());
        out.mesh.validate().unwrap();
    }
}

#[test]
fn ratio_target_counts_input_faces() {
    let m = blob(20_000);
    let out = simplify(&m, &Options::ratio(0.1)).unwrap();
    within_half_percent(out.mesh.faces.len(), m.faces.len() / 10);
}

#[test]
fn closed_manifold_stays_closed_manifold_and_unflipped() {
    for (m, convex) in [(icosphere(4), true), (blob(30_000), false)] {
        for r in [0.5, 0.1, 0.01] {
            let out = simplify(&m, &Options::ratio(r)).unwrap();
            let s = topology_stats(&out.mesh);
            assert_eq!(s.boundary_edges, 0, "ratio {r}");
            assert_eq!(s.non_manifold_edges, 0, "ratio {r}");
            assert_eq!(s.non_manifold_vertices, 0, "ratio {r}");
            assert_eq!(s.components, 1);
            let chi =
                out.mesh.positions.len() as i64 - s.edges as i64 + out.mesh.faces.len() as i64;
            assert_eq!(chi, 2, "genus changed at ratio {r}");
            // On a convex input no face may turn inward.
            assert!(
                !convex || all_outward(&out.mesh),
                "a face flipped at ratio {r}"
            );
        }
    }
}

#[test]
fn torus_keeps_its_genus() {
    let m = torus(1.0, 0.3, 64, 32);
    let out = simplify(&m, &Options::faces(200)).unwrap();
    within_half_percent(out.mesh.faces.len(), 200);
    let s = topology_stats(&out.mesh);
    let chi = out.mesh.positions.len() as i64 - s.edges as i64 + out.mesh.faces.len() as i64;
    assert_eq!((chi, s.boundary_edges, s.non_manifold_edges), (0, 0, 0));
}

#[test]
fn output_is_deterministic() {
    let m = blob(20_000);
    let a = simplify(&m, &Options::ratio(0.05)).unwrap();
    let b = simplify(&m, &Options::ratio(0.05)).unwrap();
    assert_eq!(a.mesh, b.mesh);
    // The reused workspace gives the same answer as a fresh one.
    let mut w = Simplifier::new();
    w.simplify(&icosphere(3), &Options::ratio(0.5)).unwrap();
    let c = w.simplify(&m, &Options::ratio(0.05)).unwrap();
    assert_eq!(a.mesh, c.mesh);
}

#[test]
fn empty_mesh_is_fine() {
    let out = simplify(&TriMesh::default(), &Options::faces(10)).unwrap();
    assert_eq!(out.mesh.faces.len(), 0);
    assert_eq!(out.report.stop, StopReason::Reached);
    let out = simplify(&TriMesh::default(), &Options::faces(0)).unwrap();
    assert_eq!(out.mesh.faces.len(), 0);
}

#[test]
fn single_triangle_is_never_erased() {
    let m = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]]);
    let out = simplify(&m, &Options::faces(0)).unwrap();
    assert_eq!(out.mesh.faces.len(), 1);
    assert!(matches!(out.report.stop, StopReason::Blocked { .. }));
    let out = simplify(&m, &Options::faces(5)).unwrap();
    assert_eq!(out.mesh, m);
}

#[test]
fn bad_indices_and_nan_are_errors_not_panics() {
    let m = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 7]]);
    assert!(simplify(&m, &Options::faces(0)).is_err());
    let m = TriMesh::new(vec![Vec3::ZERO, Vec3::X, Vec3::NAN], vec![[0, 1, 2]]);
    assert!(simplify(&m, &Options::faces(0)).is_err());
}

#[test]
fn non_manifold_input_simplifies_without_panic_or_new_non_manifold_edges() {
    let m = non_manifold();
    let before = topology_stats(&m).non_manifold_edges;
    for t in [0, 2, 4] {
        let out = simplify(&m, &Options::faces(t)).unwrap();
        out.mesh.validate().unwrap();
        assert!(topology_stats(&out.mesh).non_manifold_edges <= before);
    }
    // A larger one: a fin glued onto a sphere.
    let mut s = icosphere(3);
    s.normals = None;
    let a = s.faces[0];
    let apex = s.positions.len() as u32;
    s.positions.push(Vec3::new(0.0, 3.0, 0.0));
    s.faces.push([a[0], a[1], apex]);
    let out = simplify(&s, &Options::faces(100)).unwrap();
    out.mesh.validate().unwrap();
    within_half_percent(out.mesh.faces.len(), 100);
}

#[test]
fn degenerate_faces_are_collapsed_first() {
    // An icosphere with every 10th face's corner moved onto another corner's
    // position (zero area, distinct indices).
    let mut m = icosphere(3);
    m.normals = None;
    for f in (0..m.faces.len()).step_by(50) {
        let [a, b, _] = m.faces[f];
        m.positions[b as usize] = m.positions[a as usize];
    }
    let out = simplify(&m, &Options::ratio(0.5)).unwrap();
    out.mesh.validate().unwrap();
    within_half_percent(out.mesh.faces.len(), m.faces.len() / 2);
}

#[test]
fn unwelded_soup_reaches_the_target() {
    // Every face with its own three vertices, no attributes.
    let src = icosphere(4);
    let mut soup = TriMesh::default();
    for f in 0..src.faces.len() {
        let base = soup.positions.len() as u32;
        soup.positions.extend(src.triangle(f));
        soup.faces.push([base, base + 1, base + 2]);
    }
    let out = simplify(&soup, &Options::faces(500)).unwrap();
    within_half_percent(out.mesh.faces.len(), 500);
    assert_eq!(topology_stats(&out.mesh).boundary_edges, 0);
    assert!(all_outward(&out.mesh));
}

#[test]
fn unwelded_smooth_soup_with_normals_reaches_the_target() {
    // Duplicated corners that agree on their normal are one wedge.
    let src = icosphere(4);
    let mut soup = TriMesh::default();
    let mut normals = Vec::new();
    for f in 0..src.faces.len() {
        let base = soup.positions.len() as u32;
        for p in src.triangle(f) {
            soup.positions.push(p);
            normals.push(p.normalize());
        }
        soup.faces.push([base, base + 1, base + 2]);
    }
    soup.normals = Some(normals);
    let out = simplify(&soup, &Options::faces(500)).unwrap();
    within_half_percent(out.mesh.faces.len(), 500);
    let n = out.mesh.normals.as_ref().unwrap();
    assert!(n.iter().all(|v| (v.length() - 1.0).abs() < 1e-3));
}

#[test]
fn flat_shaded_soup_says_why_it_stops() {
    // Per-face normals: every vertex is a seam of six wedges; collapsing any
    // edge would tear one, so the simplifier must stop and say so.
    let src = icosphere(2);
    let mut soup = TriMesh::default();
    let mut normals = Vec::new();
    for f in 0..src.faces.len() {
        let base = soup.positions.len() as u32;
        let [a, b, c] = src.triangle(f);
        let n = (b - a).cross(c - a).normalize();
        soup.positions.extend([a, b, c]);
        normals.extend([n; 3]);
        soup.faces.push([base, base + 1, base + 2]);
    }
    soup.normals = Some(normals);
    let out = simplify(&soup, &Options::faces(50)).unwrap();
    match out.report.stop {
        StopReason::Blocked { seam, .. } => assert!(seam > 0),
        other => panic!("{other:?}"),
    }
    assert!(out.report.stop.to_string().contains("seam"));
}

/// A UV sphere whose seam column is duplicated (u = 0 and u = 1 sides).
fn seamed_uv_sphere(segments: u32, rings: u32) -> TriMesh {
    let mut m = uv_sphere(segments, rings);
    let at = |r: u32, s: u32| 1 + (r - 1) * segments + s;
    let mut dup = vec![0u32; rings as usize];
    for r in 1..rings {
        let v = at(r, 0) as usize;
        dup[r as usize] = m.positions.len() as u32;
        m.positions.push(m.positions[v]);
        let n = m.normals.as_ref().unwrap()[v];
        m.normals.as_mut().unwrap().push(n);
        let uv = m.uvs.as_ref().unwrap()[v];
        m.uvs.as_mut().unwrap().push(Vec2::new(1.0, uv.y));
    }
    // Faces of the last column use the u = 1 copies.
    let last = segments - 1;
    let uvs = m.uvs.clone().unwrap();
    for f in &mut m.faces {
        let in_last_column = f
            .iter()
            .any(|&v| v >= 1 && v < 1 + (rings - 1) * segments && (v - 1) % segments == last);
        if in_last_column {
            for v in f.iter_mut() {
                if *v >= 1 && *v < 1 + (rings - 1) * segments && (*v - 1) % segments == 0 {
                    let r = (*v - 1) / segments + 1;
                    *v = dup[r as usize];
                }
            }
        }
    }
    let _ = uvs;
    m
}

#[test]
fn attribute_seams_are_kept_not_torn() {
    let m = seamed_uv_sphere(48, 24);
    assert!(
        topology_stats(&m).boundary_edges > 0,
        "the test mesh has a seam"
    );
    assert_eq!(topology_stats(&welded(&m)).boundary_edges, 0);
    let out = simplify(&m, &Options::ratio(0.1)).unwrap();
    within_half_percent(out.mesh.faces.len(), m.faces.len() / 10);
    // Welded by position, the output is still closed: no tear.
    let w = welded(&out.mesh);
    assert_eq!(topology_stats(&w).boundary_edges, 0);
    // And the seam is still there: some positions carry two UVs.
    assert!(out.mesh.positions.len() > w.positions.len());
    let uv = out.mesh.uvs.as_ref().unwrap();
    assert!(uv.iter().any(|t| t.x > 0.99) && uv.iter().any(|t| t.x < 0.01));
}

#[test]
fn attributes_survive_and_are_interpolated() {
    let m = terrain(40, 40); // UVs = grid coordinates
    let out = simplify(&m, &Options::ratio(0.2)).unwrap();
    let uv = out.mesh.uvs.as_ref().expect("UVs kept");
    for (p, t) in out.mesh.positions.iter().zip(uv) {
        // On this terrain u = x and v = y: interpolation must keep that.
        assert!(
            (p.x - t.x).abs() < 0.05 && (p.y - t.y).abs() < 0.05,
            "{p} {t}"
        );
    }
}

#[test]
fn lock_border_keeps_every_border_vertex_in_place() {
    let m = terrain(30, 30);
    let border_before = border_positions(&m);
    let mut o = Options::ratio(0.2);
    o.lock_border = true;
    let out = simplify(&m, &o).unwrap();
    let border_after = border_positions(&out.mesh);
    assert_eq!(border_before, border_after);
}

/// `simplify_locked` keeps the chosen vertices, bit for bit, and
/// simplifies the rest of the border: here the left half of the rim is
/// locked and the right half is free.
#[test]
fn locked_vertices_stay_and_the_rest_of_the_border_simplifies() {
    let m = terrain(30, 30);
    let border: Vec<bool> = {
        let mut b = vec![false; m.positions.len()];
        for e in lodkit_mesh::topology::edge_multiplicities(&m) {
            if e.count == 1 {
                b[e.a as usize] = true;
                b[e.b as usize] = true;
            }
        }
        b
    };
    let mid = m.bbox().center().x;
    let locked: Vec<bool> = (0..m.positions.len())
        .map(|v| border[v] && m.positions[v].x < mid)
        .collect();
    let bits = |p: &Vec3| p.to_array().map(f32::to_bits);
    let mut kept: Vec<[u32; 3]> = (0..m.positions.len())
        .filter(|&v| locked[v])
        .map(|v| bits(&m.positions[v]))
        .collect();
    kept.sort_unstable();
    let out = lodkit_simplify::Simplifier::new()
        .simplify_locked(&m, &locked, &Options::ratio(0.2))
        .unwrap();
    let after: std::collections::HashSet<[u32; 3]> = out.mesh.positions.iter().map(bits).collect();
    assert!(
        kept.iter().all(|k| after.contains(k)),
        "a locked vertex moved"
    );
    // The free half of the rim lost vertices.
    let free_before = border_positions(&m).len() - kept.len();
    let free_after = border_positions(&out.mesh).len() - kept.len();
    assert!(
        free_after < free_before / 2,
        "{free_after} of {free_before}"
    );
    let short =
        lodkit_simplify::Simplifier::new().simplify_locked(&m, &locked[1..], &Options::ratio(0.2));
    assert!(short.is_err());
}

fn border_positions(m: &TriMesh) -> Vec<[u32; 3]> {
    let mut v: Vec<[u32; 3]> = lodkit_mesh::topology::edge_multiplicities(m)
        .iter()
        .filter(|e| e.count == 1)
        .flat_map(|e| [e.a, e.b])
        .map(|i| m.positions[i as usize].to_array().map(f32::to_bits))
        .collect();
    v.sort_unstable();
    v.dedup();
    v
}

#[test]
fn open_terrain_keeps_its_rim_on_the_rim() {
    let m = terrain(40, 40);
    let mut o = Options::ratio(0.1);
    o.fill_holes = false;
    let out = simplify(&m, &o).unwrap();
    within_half_percent(out.mesh.faces.len(), m.faces.len() / 10);
    let s = topology_stats(&out.mesh);
    assert_eq!(s.boundary_loops, 1);
    // The rim stays where it was: the footprint on the xy plane keeps its
    // area (a rim pulled inward would shrink it; corners may be cut by a
    // chord, which costs little).
    let footprint: f32 = (0..out.mesh.faces.len())
        .map(|f| {
            let [a, b, c] = out.mesh.triangle(f);
            0.5 * ((b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y))
        })
        .sum();
    assert!(footprint > 0.995, "footprint {footprint}");
    // Border vertices are never inside the square by more than a cell.
    for e in lodkit_mesh::topology::edge_multiplicities(&out.mesh) {
        if e.count == 1 {
            let p = out.mesh.positions[e.a as usize];
            let inside = p.x.min(p.y).min(1.0 - p.x).min(1.0 - p.y);
            assert!(inside < 0.025, "{p}");
        }
    }
}

#[test]
fn hole_filling_closes_small_holes_and_no_fill_keeps_them() {
    let m = holey_sphere(4, 6);
    assert_eq!(topology_stats(&m).boundary_loops, 6);
    // The holes are one vertex fan wide: they close once the triangles
    // around them are larger than that.
    let filled = simplify(&m, &Options::ratio(0.02)).unwrap();
    let s = topology_stats(&filled.mesh);
    assert_eq!(s.boundary_loops, 0, "{} loops", s.boundary_loops);
    let mut o = Options::ratio(0.02);
    o.fill_holes = false;
    let kept = simplify(&m, &o).unwrap();
    assert_eq!(topology_stats(&kept.mesh).boundary_loops, 6);
}

#[test]
fn max_error_stops_short_and_says_so() {
    let m = blob(20_000);
    let mut o = Options::faces(0);
    o.max_error = Some(0.01);
    let out = simplify(&m, &o).unwrap();
    assert_eq!(out.report.stop, StopReason::MaxError);
    assert!(out.report.estimated_error <= 0.01);
    assert!(out.mesh.faces.len() < m.faces.len());
    // A looser bound goes further.
    o.max_error = Some(0.05);
    let further = simplify(&m, &o).unwrap();
    assert!(further.mesh.faces.len() < out.mesh.faces.len());
}

#[test]
fn prune_removes_small_components() {
    let mut m = icosphere(3);
    m.normals = None;
    let base = m.positions.len() as u32;
    // A speck far away: 1% of the sphere's size.
    m.positions.extend([
        Vec3::new(3.0, 0.0, 0.0),
        Vec3::new(3.02, 0.0, 0.0),
        Vec3::new(3.0, 0.02, 0.0),
    ]);
    m.faces.push([base, base + 1, base + 2]);
    let mut o = Options::faces(usize::MAX);
    o.prune = Some(0.05);
    let out = simplify(&m, &o).unwrap();
    assert_eq!(out.mesh.faces.len(), m.faces.len() - 1);
    assert_eq!(topology_stats(&out.mesh).components, 1);
}

#[test]
fn lod_chain_levels_shrink_and_errors_accumulate() {
    let m = blob(40_000);
    let levels = lod_chain(&m, &Options::DEFAULT, &halving_targets(5)).unwrap();
    assert_eq!(levels.len(), 5);
    let mut prev_faces = m.faces.len();
    let mut prev_err = 0.0;
    for l in &levels {
        within_half_percent(l.mesh.faces.len(), l.report.target_faces);
        assert!(l.mesh.faces.len() < prev_faces);
        assert!(l.report.estimated_error >= prev_err);
        prev_faces = l.mesh.faces.len();
        prev_err = l.report.estimated_error;
    }
    assert!(levels.iter().all(|l| l.report.chain_end.is_none()));
    // A target above the previous level would repeat it: the chain ends.
    let rep = lod_chain(
        &m,
        &Options::DEFAULT,
        &[Target::Ratio(0.25), Target::Ratio(0.5)],
    )
    .unwrap();
    assert_eq!(rep.len(), 1);
    assert_eq!(rep[0].report.chain_end, Some(StopReason::Reached));
}

#[test]
fn a_chain_that_stalls_ends_at_the_last_level_that_changed() {
    // 80 faces halved ten times: the octahedron-like floor of a closed
    // genus-0 mesh is reached long before 80 / 1024.
    let m = icosphere(1);
    let levels = lod_chain(&m, &Options::DEFAULT, &halving_targets(10)).unwrap();
    let faces: Vec<usize> = levels.iter().map(|l| l.mesh.faces.len()).collect();
    assert!(levels.len() < 10, "{faces:?}");
    assert!(faces.windows(2).all(|w| w[1] < w[0]), "{faces:?}");
    let (last, before) = levels.split_last().unwrap();
    assert!(before.iter().all(|l| l.report.chain_end.is_none()));
    assert!(
        matches!(last.report.chain_end, Some(StopReason::Blocked { .. })),
        "{:?}",
        last.report
    );
    // The same through a reused workspace, and the levels are the first
    // levels of the full request.
    let again = Simplifier::new()
        .lod_chain(&m, &Options::DEFAULT, &halving_targets(10))
        .unwrap();
    assert_eq!(again.len(), levels.len());
    // An error bound that stops every collapse: one level, which says why.
    let mut o = Options::DEFAULT;
    o.max_error = Some(0.0);
    let capped = lod_chain(&m, &o, &halving_targets(4)).unwrap();
    assert_eq!(capped.len(), 1);
    assert_eq!(capped[0].report.chain_end, Some(StopReason::MaxError));
    // No targets, no levels.
    assert!(lod_chain(&m, &Options::DEFAULT, &[]).unwrap().is_empty());
}

#[test]
fn heap_size_one_still_works() {
    let m = icosphere(4);
    let mut o = Options::faces(300);
    o.heap_size = 1;
    let out = simplify(&m, &o).unwrap();
    within_half_percent(out.mesh.faces.len(), 300);
}

#[test]
fn replacement_selection_heap_keeps_the_topology_and_the_target() {
    // The default collapses each record at once; a real heap (the paper's
    // pipeline) goes through the dependency re-costing path instead.
    let m = blob(30_000);
    for heap_size in [2, 64, 512] {
        let mut o = Options::ratio(0.05);
        o.heap_size = heap_size;
        let out = simplify(&m, &o).unwrap();
        within_half_percent(out.mesh.faces.len(), o.target.faces(m.faces.len()));
        let s = topology_stats(&out.mesh);
        assert_eq!(s.boundary_edges, 0, "heap {heap_size}");
        assert_eq!(s.non_manifold_edges, 0, "heap {heap_size}");
        assert_eq!(simplify(&m, &o).unwrap().mesh, out.mesh, "heap {heap_size}");
    }
}

fn scaled(m: &TriMesh, k: f32) -> TriMesh {
    let mut m = m.clone();
    m.positions.iter_mut().for_each(|p| *p *= k);
    m
}

/// Simplification works in a frame normalised to the model's extent: the
/// same mesh at 1e-10, 1 and 1e15 gives the same faces, `max_error`
/// binds the same way and the estimated error scales with the model (it
/// used to be ignored at 1e-15 and read 0 past 1e20). A power-of-two scale
/// gives bit-for-bit the same result, scaled.
#[test]
fn the_result_does_not_depend_on_the_scale() {
    let m = blob(3);
    let opts = Options {
        target: Target::Ratio(0.1),
        ..Options::DEFAULT
    };
    let one = simplify(&m, &opts).unwrap();
    let bound = one.report.estimated_error * 0.25;
    let bounded_one = simplify(
        &m,
        &Options {
            max_error: Some(bound),
            ..opts.clone()
        },
    )
    .unwrap();
    assert!(bounded_one.mesh.faces.len() > one.mesh.faces.len());
    for k in [1e-10f32, 1e15, 2f32.powi(-60), 2f32.powi(50)] {
        let s = simplify(&scaled(&m, k), &opts).unwrap();
        let rel = s.report.estimated_error / k / one.report.estimated_error;
        assert!((rel - 1.0).abs() < 1e-3, "scale {k}: error ratio {rel}");
        let b = simplify(
            &scaled(&m, k),
            &Options {
                max_error: Some(bound * k),
                ..opts.clone()
            },
        )
        .unwrap();
        assert!(b.report.estimated_error <= bound * k * 1.0001, "scale {k}");
        let (f, g) = (
            b.mesh.faces.len() as f64,
            bounded_one.mesh.faces.len() as f64,
        );
        assert!(
            (f - g).abs() <= 0.02 * g,
            "scale {k}: {f} faces against {g}"
        );
        if k.log2().fract() == 0.0 {
            assert_eq!(s.mesh.faces, one.mesh.faces, "scale {k}");
            assert_eq!(
                s.mesh.positions,
                scaled(&one.mesh, k).positions,
                "scale {k}"
            );
        }
    }
}
