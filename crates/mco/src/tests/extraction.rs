//! Extraction by LOD number: the birth/death tables ([`McoModel::extract_lod`])
//! draw exactly what the §6.1 reverse-order traversal draws, both over the
//! prepared stream ([`McoModel::extract_lod_traversal`]) and over the nodes
//! ([`McoModel::extract_lod_nodes`]), for many LOD numbers on several
//! shapes; the triangle-count lookup matches the accumulation table's.

use crate::McoModel;
use crate::pipeline::{Options, build_from_mesh};
use lodkit_mesh::{TriMesh, shapes};

fn model(mesh: &TriMesh, resolution: u32) -> McoModel {
    build_from_mesh(
        mesh,
        &Options {
            resolution: Some(resolution),
        },
    )
    .unwrap()
}

fn sorted(v: &[u32]) -> Vec<[u32; 3]> {
    let mut t: Vec<[u32; 3]> = v.chunks_exact(3).map(|t| [t[0], t[1], t[2]]).collect();
    t.sort_unstable();
    t
}

/// Every LOD number on small models, 200 spread ones on larger ones.
fn lods(m: &McoModel) -> Vec<usize> {
    let n = m.max_lod();
    if n <= 400 {
        (0..=n).collect()
    } else {
        (0..200)
            .map(|i| i * n / 199)
            .chain([1, 2, 3, n - 1])
            .collect()
    }
}

fn assert_same_as_traversal(name: &str, m: &McoModel) {
    let (mut bd, mut tr, mut nodes) = (Vec::new(), Vec::new(), Vec::new());
    // Versions of a triangle that change with a neighbour make records of
    // their own: there are more records than stored triangles.
    assert!(m.lifetimes.birth.len() >= m.tris.len() / 3, "{name}");
    for k in lods(m) {
        m.extract_lod(k, &mut bd);
        m.extract_lod_traversal(k, &mut tr);
        m.extract_lod_nodes(k, &mut nodes);
        assert_eq!(bd.len(), 3 * m.triangles_at_lod(k), "{name} lod {k}");
        let want = sorted(&nodes);
        assert_eq!(sorted(&tr), want, "{name} lod {k}: stream traversal");
        assert_eq!(sorted(&bd), want, "{name} lod {k}: birth/death");
    }
}

#[test]
fn birth_death_tables_draw_what_the_traversal_draws_on_a_sphere() {
    assert_same_as_traversal("sphere", &model(&shapes::icosphere(4), 24));
}

#[test]
fn birth_death_tables_draw_what_the_traversal_draws_on_a_torus() {
    assert_same_as_traversal("torus", &model(&shapes::torus(1.0, 0.35, 96, 48), 40));
}

#[test]
fn birth_death_tables_draw_what_the_traversal_draws_on_blobs() {
    assert_same_as_traversal("blob 20k", &model(&shapes::blob(20_000), 32));
    assert_same_as_traversal("blob 80k", &model(&shapes::blob(80_000), 72));
}

#[test]
fn extraction_is_deterministic() {
    let mesh = shapes::blob(20_000);
    let (a, b) = (model(&mesh, 32), model(&mesh, 32));
    assert_eq!(a.lifetimes, b.lifetimes);
    let (mut x, mut y) = (Vec::new(), Vec::new());
    for k in lods(&a) {
        a.extract_lod(k, &mut x);
        b.extract_lod(k, &mut y);
        assert_eq!(x, y, "lod {k}");
    }
}

#[test]
fn triangle_count_lookup_matches_the_drawn_counts() {
    let m = model(&shapes::blob(20_000), 32);
    let full = m.full_triangles();
    for target in (0..=full + 10).step_by(7).chain([0, 1, full, usize::MAX]) {
        assert_eq!(
            m.lod_for_triangles(target),
            crate::priority_numbering::lod_for_triangles(m.drawn_table(), target),
            "target {target}"
        );
    }
}

#[test]
fn running_the_traversal_does_not_change_model_equality() {
    let a = model(&shapes::icosphere(3), 16);
    let b = a.clone();
    let mut idx = Vec::new();
    a.extract_lod_traversal(a.max_lod() / 2, &mut idx);
    assert!(!idx.is_empty());
    assert_eq!(a, b);
}
