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
        ..lodkit_particles::ThinningOptions::DEFAULT
    };
    let opts = EncodeOptions {
        depth: Some(7),
        thinning,
        ..EncodeOptions::DEFAULT
    };
    let e = encode(&torus, &opts).unwrap();
    let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
    // From level 3, where the tube (0.7 across) spans two cubes; at level
    // 2 it is one cube thick and 16 of the 60 triangles share edges four
    // ways, as the paper's own coarsest levels (Table 1: 4.6 % and 6.1 %
    // at r = 4) — no manifold surface fits such a shell of cubes.
    for r in 3..=7u8 {
        let t = triangulate(&d.surface(r).unwrap(), &TriangulateOptions::DEFAULT);
        let share = t.stats.fallbacks as f64 / t.stats.triangles as f64;
        let strict = lodkit_particles::non_manifold_triangles(&t.mesh);
        // The strict count too: triangles on an edge used more than twice.
        assert!(
            strict * 100 <= t.stats.triangles,
            "level {r}: {strict} non-manifold triangles of {}",
            t.stats.triangles
        );
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

#[test]
fn thinning_on_keeps_every_level_of_the_scanned_bunny_under_one_percent_non_manifold() {
    // The issue's bound, "non-manifold triangles <= 1 % of each level's
    // triangles with thinning on", on a real open scan: inner and outer
    // thinning (relaxed below the default level 4, Table 1's setting).
    // Relaxed below 5 instead, levels 3 and 4 of this bunny reach 3.7 %
    // and 2.3 %, so the coarse levels are where this test bites.
    use lodkit_particles::{TriangulateOptions, triangulate};
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/models/stanford_bunny.ply");
    let bunny = lodkit_mesh::io::load(&path).unwrap();
    let opts = EncodeOptions {
        depth: Some(7),
        thinning: lodkit_particles::ThinningOptions {
            outer: true,
            ..lodkit_particles::ThinningOptions::DEFAULT
        },
        ..EncodeOptions::DEFAULT
    };
    let e = encode(&bunny, &opts).unwrap();
    let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
    for r in 0..=7u8 {
        let t = triangulate(&d.surface(r).unwrap(), &TriangulateOptions::DEFAULT);
        let strict = lodkit_particles::non_manifold_triangles(&t.mesh);
        assert!(
            strict * 100 <= t.stats.triangles,
            "level {r}: {strict} non-manifold triangles of {}",
            t.stats.triangles
        );
        if r >= 3 {
            assert!(t.stats.triangles >= 100, "level {r} has a surface");
        }
    }
}

#[test]
fn progressive_levels_report_growing_bytes_and_meshes_for_lodkit_build() {
    use lodkit_particles::{TriangulateOptions, progressive_levels};
    let e = encode(
        &sphere(),
        &EncodeOptions {
            depth: Some(6),
            ..EncodeOptions::DEFAULT
        },
    )
    .unwrap();
    let levels = progressive_levels(&e.bytes, &TriangulateOptions::DEFAULT).unwrap();
    // Levels 0..=6 at the precision their chunks give (N = R = 6), then
    // level 6 again at the stream's full 12 bits.
    assert_eq!(levels.len(), 8);
    for w in levels[..7].windows(2) {
        assert!(w[1].bytes_so_far > w[0].bytes_so_far);
        assert!(w[1].particles > w[0].particles);
        assert!(w[1].mesh.faces.len() > w[0].mesh.faces.len());
        assert_eq!(w[1].precision, 6);
    }
    assert_eq!(levels[6].particles, e.report.particles);
    assert!(levels[6].bytes_so_far < e.bytes.len());
    let full = &levels[7];
    assert_eq!((full.level, full.precision), (6, 12));
    assert_eq!(full.bytes_so_far, e.bytes.len());
    assert_eq!(full.particles, levels[6].particles);
    assert_eq!(full.mesh.faces.len(), levels[6].mesh.faces.len());
    assert_ne!(full.mesh.positions, levels[6].mesh.positions);
}

#[test]
fn decimation_during_triangulation_merges_close_particles() {
    // §6.3: triangles with an edge under the threshold are not built and
    // their two cubes merge; fewer triangles, no vertex moves more than a
    // half the threshold.
    use lodkit_particles::{TriangulateOptions, triangulate};
    let e = encode(
        &sphere(),
        &EncodeOptions {
            depth: Some(6),
            ..EncodeOptions::DEFAULT
        },
    )
    .unwrap();
    let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
    let s = d.surface(6).unwrap();
    let full = triangulate(&s, &TriangulateOptions::DEFAULT);
    let dec = triangulate(
        &s,
        &TriangulateOptions {
            decimate: Some(0.9),
            ..TriangulateOptions::DEFAULT
        },
    );
    assert!(
        dec.stats.triangles < full.stats.triangles * 9 / 10,
        "{} vs {}",
        dec.stats.triangles,
        full.stats.triangles
    );
    let cube = s.frame.cube(6);
    for (a, b) in dec.mesh.positions.iter().zip(&s.positions) {
        assert!(a.distance(*b) <= cube * 0.5, "merged pairs meet half way");
    }
}

#[test]
fn baseline_structure_bits_are_exactly_eq5_of_the_paper() {
    // B_r = 7 k_{r-1} + 8 m_{r-1} + n_r + m_r + 3 (R - r) n_r (no flags at
    // r = R), B_0 = 3 R n_0, with k the kept nodes, m the phantoms and n
    // the new particles, at N = R. (Outer thinning from level 3 also
    // empties level 1 here: the case where the root must keep a child.)
    let torus = Model::Mesh(lodkit_mesh::shapes::torus(1.0, 0.3, 64, 32));
    for outer in [false, true] {
        let thinning = lodkit_particles::ThinningOptions {
            outer,
            relax_below: 3,
        };
        let opts = EncodeOptions {
            depth: Some(6),
            mode: Mode::Baseline,
            thinning,
            ..EncodeOptions::DEFAULT
        };
        let rep = encode(&torus, &opts).unwrap().report;
        let depth = u64::from(rep.depth);
        assert!(
            rep.levels.iter().any(|l| l.phantoms > 0),
            "the case must exercise phantoms"
        );
        for (r, l) in rep.levels.iter().enumerate() {
            let r64 = r as u64;
            let n = l.new_particles as u64;
            let want = if r == 0 {
                3 * depth * n
            } else {
                let p = &rep.levels[r - 1];
                let flags = if r64 < depth {
                    n + l.phantoms as u64
                } else {
                    0
                };
                7 * p.kept as u64 + 8 * p.phantoms as u64 + flags + 3 * (depth - r64) * n
            };
            assert_eq!(l.structure_bits, want, "outer={outer} level {r}");
        }
    }
}

#[test]
fn point_clouds_with_normals_encode_and_decode() {
    // An open hemisphere of points with outward normals: IN/OUT from the
    // normals (§8.1.2's second option).
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    for i in 0..200 {
        for j in 0..100 {
            let (th, ph) = (
                i as f32 / 200.0 * std::f32::consts::TAU,
                j as f32 / 100.0 * std::f32::consts::FRAC_PI_2,
            );
            let n = glam::Vec3::new(th.cos() * ph.cos(), th.sin() * ph.cos(), ph.sin());
            positions.push(n);
            normals.push(n);
        }
    }
    let pc = lodkit_mesh::PointCloud {
        positions,
        normals: Some(normals),
        colors: None,
    };
    let e = encode(
        &Model::Points(pc),
        &EncodeOptions {
            depth: Some(5),
            ..EncodeOptions::DEFAULT
        },
    )
    .unwrap();
    let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
    assert_eq!(d.levels.len(), 6);
    let s = d.surface(5).unwrap();
    assert_eq!(s.cells.len(), e.report.particles);
    let t = lodkit_particles::triangulate(&s, &lodkit_particles::TriangulateOptions::DEFAULT);
    assert!(
        t.stats.triangles > s.cells.len(),
        "{} triangles",
        t.stats.triangles
    );
}

/// Decoded levels come out wound consistently and outwards: every edge
/// two triangles share is traversed once each way, and the closed level
/// encloses a positive volume.
#[test]
fn decoded_levels_are_wound_consistently_and_outwards() {
    use std::collections::HashMap;

    use lodkit_particles::{TriangulateOptions, triangulate};
    let opts = EncodeOptions {
        depth: Some(6),
        ..EncodeOptions::DEFAULT
    };
    let e = encode(&sphere(), &opts).unwrap();
    let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
    for r in 3..=6u8 {
        let m = triangulate(&d.surface(r).unwrap(), &TriangulateOptions::DEFAULT).mesh;
        let mut sides: HashMap<(u32, u32), [usize; 2]> = HashMap::new();
        for f in &m.faces {
            for k in 0..3 {
                let (a, b) = (f[k], f[(k + 1) % 3]);
                sides.entry((a.min(b), a.max(b))).or_default()[usize::from(a < b)] += 1;
            }
        }
        let shared = sides.values().filter(|u| u[0] + u[1] == 2).count();
        let same_way = sides
            .values()
            .filter(|u| u[0] + u[1] == 2 && (u[0] == 2 || u[1] == 2))
            .count();
        assert!(shared > 0);
        assert_eq!(
            same_way, 0,
            "level {r}: {same_way} of {shared} shared edges"
        );
        let volume: f64 = m
            .faces
            .iter()
            .map(|f| {
                let [a, b, c] = f.map(|v| m.positions[v as usize].as_dvec3());
                a.dot(b.cross(c))
            })
            .sum();
        assert!(volume > 0.0, "level {r}: volume {volume}");
    }
}
