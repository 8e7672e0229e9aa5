//! The no-crack claim on real closed meshes (`../shared/data/meshes`):
//! every boundary edge of an extraction lies on another face, at 10
//! budgets. Known to fail today, so ignored: at the default resolution the
//! closed bunny leaves 14 gap edges (holes already in the full-resolution
//! reconstruction, where the vertex samples are sparser than the cubes)
//! and the armadillo 4 (at the two coarsest budgets). Run with
//! `cargo test -p lodkit-mco --test real_closed -- --ignored --nocapture`.

mod support;

use std::path::Path;

use lodkit_mco::pipeline::{Options, build_from_mesh};

#[test]
#[ignore = "known gaps on real closed meshes (see the file's doc)"]
fn no_cracks_on_the_closed_bunny_and_armadillo() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/meshes");
    for f in [
        "stanford_bunny_closed_glmark2.ply",
        "stanford_armadillo_cgal26k.ply",
    ] {
        let p = dir.join(f);
        if !p.exists() {
            eprintln!("skipped: {} is absent", p.display());
            continue;
        }
        let mesh = lodkit_mesh::io::load_mesh(&p).unwrap();
        let m = build_from_mesh(&mesh, &Options::default()).unwrap();
        let full = m.full_triangles();
        let tol = 1e-5 * m.mesh_at_lod(m.max_lod()).bbox().diagonal();
        let mut worst = 0;
        for i in 1..=10 {
            let lod = m.mesh_with_triangles(full * i / 10);
            let (_, gaps) = support::gap_edges(&lod, tol);
            worst = worst.max(gaps);
        }
        eprintln!(
            "{f}: resolution {}, {full} triangles, worst gap edges {worst}",
            m.grid.resolution
        );
        assert_eq!(worst, 0, "{f}");
    }
}
