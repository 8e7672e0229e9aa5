//! Quality against the peer, measured with `compare` (never timed): on
//! the same mesh and triangle count, lodkit's symmetric mean distance must
//! not exceed meshoptimizer's and its max must stay within 1.2× (lodkit
//! must be at least as good a simplifier as its peer). Small meshes keep
//! the test fast; the full-size table is `lodkit bench simplify`.

use lodkit_bench::simplify::{BenchConfig, run_case};
use lodkit_mesh::shapes::{blob, torus};
use lodkit_simplify::Target;

fn check(name: &str, mesh: &lodkit_mesh::TriMesh, target: Target) {
    let cfg = BenchConfig {
        runs: 1,
        samples: 200_000,
    };
    let r = run_case(name, mesh, "t", target, &cfg).unwrap();
    assert!(r.lodkit_triangles <= r.target_triangles, "{r:?}");
    assert!(
        r.lodkit_triangles as f64 >= r.target_triangles as f64 * 0.995 - 2.0,
        "{r:?}"
    );
    assert!(r.lodkit_mean <= r.meshopt_mean, "{name}: mean {r:?}");
    assert!(r.lodkit_max <= 1.2 * r.meshopt_max, "{name}: max {r:?}");
}

#[test]
fn blob_quality_is_at_least_meshopts() {
    let m = blob(60_000);
    for t in [Target::Ratio(0.5), Target::Ratio(0.1), Target::Faces(1000)] {
        check("blob", &m, t);
    }
}

#[test]
fn torus_quality_is_at_least_meshopts() {
    let mut m = torus(1.0, 0.35, 120, 60);
    // Geometry only: meshopt_simplify sees positions alone.
    m.normals = None;
    m.uvs = None;
    for t in [Target::Ratio(0.25), Target::Faces(500)] {
        check("torus", &m, t);
    }
}
