//! `metrics::compare` on analytic cases whose distances are known: a mesh
//! against itself, two concentric spheres, a grid against the same grid
//! shifted, a big square against a small one inside it; plus determinism,
//! degenerate input and the error cases.

use lodkit_mesh::TriMesh;
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::metrics::{CompareOptions, DEFAULT_MIN_SAMPLES, SurfaceIndex, compare, one_sided};

/// A UV sphere of radius `r` with `rings × segments` quads (poles fanned).
fn uv_sphere(r: f32, rings: u32, segments: u32) -> TriMesh {
    let mut positions = vec![Vec3::new(0.0, 0.0, r)];
    for i in 1..rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            positions.push(
                r * Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.sin() * phi.sin(),
                    theta.cos(),
                ),
            );
        }
    }
    positions.push(Vec3::new(0.0, 0.0, -r));
    let south = positions.len() as u32 - 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * segments + j % segments;
    let mut faces = Vec::new();
    for j in 0..segments {
        faces.push([0, ring(1, j), ring(1, j + 1)]);
        faces.push([south, ring(rings - 1, j + 1), ring(rings - 1, j)]);
    }
    for i in 1..rings - 1 {
        for j in 0..segments {
            let (a, b) = (ring(i, j), ring(i, j + 1));
            let (c, d) = (ring(i + 1, j), ring(i + 1, j + 1));
            faces.push([a, c, d]);
            faces.push([a, d, b]);
        }
    }
    TriMesh::new(positions, faces)
}

/// An `n × n`-cell grid covering `[x0, x1]²` at height `z`.
fn grid(n: u32, x0: f32, x1: f32, z: f32) -> TriMesh {
    let mut positions = Vec::new();
    for i in 0..=n {
        for j in 0..=n {
            let t = |k: u32| x0 + (x1 - x0) * k as f32 / n as f32;
            positions.push(Vec3::new(t(j), t(i), z));
        }
    }
    let v = |i: u32, j: u32| i * (n + 1) + j;
    let mut faces = Vec::new();
    for i in 0..n {
        for j in 0..n {
            faces.push([v(i, j), v(i, j + 1), v(i + 1, j + 1)]);
            faces.push([v(i, j), v(i + 1, j + 1), v(i + 1, j)]);
        }
    }
    TriMesh::new(positions, faces)
}

fn opts(samples: usize) -> CompareOptions {
    CompareOptions {
        samples: Some(samples),
        ..CompareOptions::default()
    }
}

#[test]
fn a_mesh_against_itself_is_at_distance_zero() {
    let m = uv_sphere(1.0, 24, 48);
    let r = compare(&m, &m, &opts(50_000)).unwrap();
    for d in [&r.a_to_b, &r.b_to_a] {
        assert!(d.max < 1e-6, "{d:?}");
        assert!(d.mean < 1e-7, "{d:?}");
        assert_eq!(d.vertex_samples, m.positions.len() as u64);
        assert_eq!(d.edge_samples, 50_000);
        assert_eq!(d.face_samples, 50_000);
        assert_eq!(d.samples, d.vertex_samples + 100_000);
    }
    assert!(r.symmetric.max < 1e-6);
}

#[test]
fn concentric_spheres_are_a_tenth_apart() {
    // Same tessellation scaled: the inner surface's samples are 0.1 from
    // the outer one up to the chord sagitta, r (1 - cos(half step)) ≈ 2e-3
    // here, and vice versa.
    let a = uv_sphere(1.0, 32, 64);
    let b = uv_sphere(1.1, 32, 64);
    let r = compare(&a, &b, &opts(100_000)).unwrap();
    for d in [&r.a_to_b, &r.b_to_a, &r.a_to_b] {
        for v in [d.min, d.max, d.mean, d.rms] {
            assert!((v - 0.1).abs() < 3e-3, "{v} in {d:?}");
        }
    }
    // Relative figures: 0.1 over the 2√3 (resp. 2.2√3) box diagonal.
    let diag_a = 2.0 * 3f64.sqrt();
    assert!((r.a_to_b.diagonal - diag_a).abs() < 1e-5);
    assert!((r.a_to_b.max_pct - 100.0 * r.a_to_b.max / diag_a).abs() < 1e-6);
    assert!((r.b_to_a.diagonal - 1.1 * diag_a).abs() < 1e-5);
    assert!((r.symmetric.diagonal - 1.1 * diag_a).abs() < 1e-5);
    assert_eq!(r.symmetric.max, r.a_to_b.max.max(r.b_to_a.max));
}

#[test]
fn a_grid_against_the_same_grid_shifted_is_at_the_shift() {
    let d = 0.037f32;
    let a = grid(16, -1.0, 1.0, 0.0);
    let b = grid(16, -1.0, 1.0, d);
    let r = compare(&a, &b, &opts(20_000)).unwrap();
    for s in [&r.a_to_b, &r.b_to_a] {
        for v in [s.min, s.max, s.mean, s.rms] {
            assert!((v - d as f64).abs() < 1e-6, "{v} in {s:?}");
        }
    }
    assert!((r.symmetric.mean - d as f64).abs() < 1e-6);
}

#[test]
fn a_small_square_inside_a_big_one_is_one_sided() {
    let big = grid(4, -1.0, 1.0, 0.0);
    let small = grid(3, -0.5, 0.5, 0.0);
    let r = compare(&small, &big, &opts(20_000)).unwrap();
    // Every point of the small square lies on the big one.
    assert!(r.a_to_b.max < 1e-6, "{:?}", r.a_to_b);
    // The big square's corners are √0.5 from the small one's corners.
    let corner = 0.5f64.sqrt();
    assert!((r.b_to_a.max - corner).abs() < 1e-6, "{:?}", r.b_to_a);
    assert_eq!(r.symmetric.max, r.b_to_a.max);
    // A quarter of the big square is covered (distance 0); the mean over
    // the rest is well inside (0, corner).
    assert!(
        r.b_to_a.mean > 0.1 && r.b_to_a.mean < corner,
        "{:?}",
        r.b_to_a
    );
    assert!(r.b_to_a.rms > r.b_to_a.mean);
    assert_eq!(r.b_to_a.min, 0.0);
    assert_eq!(r.symmetric.mean, r.b_to_a.mean);
}

#[test]
fn reports_are_byte_identical_across_runs_and_thread_counts() {
    let a = uv_sphere(1.0, 16, 32);
    let b = uv_sphere(1.05, 12, 20);
    let o = opts(40_000);
    let first = serde_json::to_string(&compare(&a, &b, &o).unwrap()).unwrap();
    let again = serde_json::to_string(&compare(&a, &b, &o).unwrap()).unwrap();
    assert_eq!(first, again);
    let one_thread = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap()
        .install(|| serde_json::to_string(&compare(&a, &b, &o).unwrap()).unwrap());
    assert_eq!(first, one_thread);
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap()
        .install(|| serde_json::to_string(&compare(&a, &b, &o).unwrap()).unwrap());
    assert_eq!(first, three);
    // Another seed moves the face samples, so the figures change a little.
    let other = compare(&a, &b, &CompareOptions { seed: 99, ..o }).unwrap();
    assert_ne!(first, serde_json::to_string(&other).unwrap());
}

#[test]
fn default_sample_count_is_ten_per_face_or_a_million() {
    let o = CompareOptions::default();
    assert_eq!(o.samples, None);
    assert!(o.vertex_samples && o.edge_samples && o.face_samples);
    assert_eq!(o.resolved_samples(100, 2_000), DEFAULT_MIN_SAMPLES);
    assert_eq!(o.resolved_samples(69_451, 5_000), DEFAULT_MIN_SAMPLES);
    assert_eq!(o.resolved_samples(5_000, 250_000), 2_500_000);
    // A default run on small meshes really uses a million per kind.
    let a = grid(2, 0.0, 1.0, 0.0);
    let b = grid(2, 0.0, 1.0, 0.25);
    let r = compare(&a, &b, &o).unwrap();
    assert_eq!(r.samples_per_kind, 1_000_000);
    assert_eq!(r.a_to_b.face_samples, 1_000_000);
    assert_eq!(r.a_to_b.edge_samples, 1_000_000);
    assert_eq!(r.a_to_b.vertex_samples, 9);
    assert!((r.a_to_b.mean - 0.25).abs() < 1e-6);
}

#[test]
fn unreferenced_vertices_are_not_sampled_nor_boxed() {
    let mut a = grid(4, 0.0, 1.0, 0.0);
    let b = grid(4, 0.0, 1.0, 0.0);
    a.positions.push(Vec3::new(50.0, 50.0, 50.0)); // referenced by no face
    let r = compare(&a, &b, &opts(10_000)).unwrap();
    assert!(
        r.a_to_b.max < 1e-6,
        "the stray vertex was sampled: {:?}",
        r.a_to_b
    );
    assert_eq!(r.a_to_b.vertex_samples, 25);
    assert!((r.a_to_b.diagonal - 2f64.sqrt()).abs() < 1e-6);
    assert!((r.symmetric.diagonal - 2f64.sqrt()).abs() < 1e-6);
}

#[test]
fn degenerate_faces_do_not_break_anything() {
    let mut a = grid(4, 0.0, 1.0, 0.0);
    let n = a.positions.len() as u32;
    // A zero-area sliver (collinear), a face repeating an index, and a
    // face collapsed to a point, all 0.5 above the grid.
    a.positions.extend([
        Vec3::new(0.2, 0.2, 0.5),
        Vec3::new(0.4, 0.2, 0.5),
        Vec3::new(0.6, 0.2, 0.5),
        Vec3::new(0.3, 0.3, 0.5),
        Vec3::new(0.3, 0.3, 0.5),
    ]);
    a.faces
        .extend([[n, n + 1, n + 2], [n, n, n + 1], [n + 3, n + 4, n + 3]]);
    let b = grid(4, 0.0, 1.0, 0.0);
    let r = compare(&a, &b, &opts(10_000)).unwrap();
    // The degenerate faces' vertices and edges are sampled and are 0.5
    // above B; nothing is NaN.
    assert!((r.a_to_b.max - 0.5).abs() < 1e-6, "{:?}", r.a_to_b);
    assert!(r.a_to_b.mean.is_finite() && r.b_to_a.mean.is_finite());
    // B's samples find A's grid at 0 (the slivers are never closer).
    assert!(r.b_to_a.max < 1e-6);
    // Only degenerate faces: edge and vertex samples still measure.
    let sliver = TriMesh::new(
        vec![
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 1.0),
            Vec3::new(0.5, 0.0, 1.0),
        ],
        vec![[0, 1, 2]],
    );
    let r = compare(&sliver, &b, &opts(1_000)).unwrap();
    assert_eq!(r.a_to_b.face_samples, 0);
    assert!((r.a_to_b.max - 1.0).abs() < 1e-6 && (r.a_to_b.min - 1.0).abs() < 1e-6);
    // B's points project onto A's segment: at least 1 away, at most √2.
    assert!(r.b_to_a.min >= 1.0 - 1e-6 && r.b_to_a.max <= 2f64.sqrt() + 1e-6);
}

#[test]
fn empty_meshes_and_empty_sampling_are_errors() {
    let g = grid(2, 0.0, 1.0, 0.0);
    let empty = TriMesh::default();
    let err = compare(&empty, &g, &opts(100)).unwrap_err();
    assert!(err.to_string().contains("mesh A"), "{err}");
    let err = compare(&g, &TriMesh::new(g.positions.clone(), vec![]), &opts(100)).unwrap_err();
    assert!(err.to_string().contains("mesh B"), "{err}");
    let none = CompareOptions {
        vertex_samples: false,
        edge_samples: false,
        face_samples: false,
        ..opts(100)
    };
    assert!(compare(&g, &g, &none).is_err());
    assert!(compare(&g, &g, &opts(0)).is_err());
    // Absurd counts are refused up front rather than overflowing.
    let err = compare(&g, &g, &opts(usize::MAX)).unwrap_err();
    assert!(err.to_string().contains("over the limit"), "{err}");
}

#[test]
fn one_sided_reuses_a_target_index() {
    let reference = uv_sphere(1.0, 24, 48);
    let index = SurfaceIndex::new(&reference).unwrap();
    let o = opts(20_000);
    let near = one_sided(&uv_sphere(1.01, 10, 20), &index, &o).unwrap();
    let far = one_sided(&uv_sphere(1.2, 10, 20), &index, &o).unwrap();
    assert!(near.mean < far.mean);
    // 0.2 less the coarse (10-ring) tessellation's sag, up to ~0.03.
    assert!(far.mean > 0.17 && far.mean <= 0.2, "{far:?}");
    // Same figures as the A→B half of compare.
    let full = compare(&uv_sphere(1.2, 10, 20), &reference, &o).unwrap();
    assert_eq!(full.a_to_b, far);
}
