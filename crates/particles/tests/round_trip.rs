use lodkit_mesh::Model;
use lodkit_particles::{DecodeOptions, EncodeOptions, Mode, decode, encode};

fn sphere() -> Model {
    Model::Mesh(lodkit_mesh::shapes::icosphere(4))
}

#[test]
fn both_modes_round_trip_the_hierarchy_and_vertices() {
    for mode in [Mode::Baseline, Mode::Entropy] {
        let opts = EncodeOptions {
            depth: Some(6),
            mode,
            ..EncodeOptions::DEFAULT
        };
        let e = encode(&sphere(), &opts).unwrap();
        let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
        assert_eq!(d.levels.len(), 7);
        assert_eq!(d.precision, 12);
        for (r, l) in e.report.levels.iter().enumerate() {
            assert_eq!(d.levels[r].kept(), l.kept, "{mode:?} level {r}");
            assert_eq!(d.levels[r].phantoms(), l.phantoms);
        }
        eprintln!(
            "{mode:?}: {} bytes, {:.2} structure bits/particle, {} particles",
            e.bytes.len(),
            e.report.structure_bits_per_particle(),
            e.report.particles
        );
    }
}

#[test]
fn triangles_are_about_twice_the_particles_per_level() {
    use lodkit_particles::{TriangulateOptions, triangulate};
    for outer in [false, true] {
        let thinning = lodkit_particles::ThinningOptions {
            outer,
            relax_below: 3,
        };
        let opts = EncodeOptions {
            depth: Some(6),
            thinning,
            ..EncodeOptions::DEFAULT
        };
        let e = encode(&sphere(), &opts).unwrap();
        let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
        for r in 3..=6u8 {
            let s = d.surface(r).unwrap();
            let t = triangulate(&s, &TriangulateOptions::DEFAULT);
            let ratio = t.stats.triangles as f64 / s.cells.len() as f64;
            assert!(
                (1.8..=2.3).contains(&ratio),
                "outer={outer} r={r}: {ratio:.2} triangles per particle"
            );
            let configs: u64 = t.stats.configurations.iter().sum();
            assert!(
                t.stats.fallbacks * 100 <= configs,
                "outer={outer} r={r}: {} fallbacks",
                t.stats.fallbacks
            );
        }
    }
}

#[test]
fn with_outer_thinning_non_manifold_local_triangulations_stay_under_one_percent() {
    // Table 1's "non-manifold" column: local triangulations left whole.
    use lodkit_particles::{TriangulateOptions, triangulate};
    let torus = Model::Mesh(lodkit_mesh::shapes::torus(1.0, 0.35, 96, 48));
    let thinning = lodkit_particles::ThinningOptions {
        outer: true,
        relax_below: 4,
    };
    let opts = EncodeOptions {
        depth: Some(7),
        thinning,
        ..EncodeOptions::DEFAULT
    };
    let e = encode(&torus, &opts).unwrap();
    let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
    for r in 4..=7u8 {
        let t = triangulate(&d.surface(r).unwrap(), &TriangulateOptions::DEFAULT);
        let share = t.stats.fallbacks as f64 / t.stats.triangles as f64;
        assert!(
            share <= 0.01,
            "level {r}: {} of {} triangles",
            t.stats.fallbacks,
            t.stats.triangles
        );
        // C6 is the frequent ambiguous class and nearly always resolved.
        let c6 = t.stats.configurations[6];
        assert!(t.stats.disambiguated >= c6 * 9 / 10, "level {r}");
    }
}
