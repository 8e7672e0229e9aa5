//! Measurable claims of the paper as tests: every prefix decodes, damage is
//! an error, the error bound of §6.5, exact attributes (eq. 3–4).
use crate::attributes::{self, Channel};
use crate::container::ChunkReader;
use crate::octree::{BuildOptions, Octree};
use crate::ordering::Hierarchy;
use crate::thinning::thin;
use crate::{DecodeOptions, EncodeOptions, Mode, TriangulateOptions, decode, encode, triangulate};
use glam::Vec3;
use lodkit_mesh::metrics::SurfaceIndex;
use lodkit_mesh::{Model, TriMesh};

fn coloured_sphere() -> TriMesh {
    let mut m = lodkit_mesh::shapes::icosphere(4);
    m.colors = Some(
        m.positions
            .iter()
            .map(|p| {
                let c = (*p * 0.5 + 0.5) * 255.0;
                [c.x as u8, c.y as u8, c.z as u8, 255]
            })
            .collect(),
    );
    m
}

#[test]
fn every_prefix_of_whole_chunks_decodes_and_every_cut_inside_one_is_an_error() {
    for mode in [Mode::Baseline, Mode::Entropy] {
        let opts = EncodeOptions {
            depth: Some(5),
            precision: 8,
            mode,
            normals: true,
            ..EncodeOptions::DEFAULT
        };
        let e = encode(&Model::Mesh(coloured_sphere()), &opts).unwrap();
        let ends: Vec<usize> = ChunkReader::new(&e.bytes).map(|c| c.unwrap().end).collect();
        assert_eq!(*ends.last().unwrap(), e.bytes.len());
        let mut last_levels = 0;
        // Every chunk end, and cuts just inside, in the middle of and at
        // the last byte of every chunk (and of the header).
        let mut cuts = vec![0, 1, 20];
        let mut start = crate::container::HEADER_LEN;
        cuts.push(start);
        for &end in &ends {
            cuts.extend([start + 1, start + 10, (start + end) / 2, end - 1, end]);
            start = end;
        }
        cuts.sort_unstable();
        cuts.dedup();
        for cut in cuts {
            let got = decode(&e.bytes[..cut], &DecodeOptions::default());
            if ends.contains(&cut) || cut == crate::container::HEADER_LEN {
                if cut == crate::container::HEADER_LEN {
                    assert!(got.is_err(), "a header alone holds no level");
                    continue;
                }
                let d = got.unwrap_or_else(|err| panic!("{mode:?} prefix {cut}: {err}"));
                assert!(d.levels.len() >= last_levels);
                last_levels = d.levels.len();
                for r in 0..d.levels.len() {
                    let s = d.surface(r as u8).unwrap();
                    triangulate(&s, &TriangulateOptions::DEFAULT);
                }
            } else {
                assert!(
                    got.is_err(),
                    "{mode:?} cut at {cut} inside a chunk must be an error"
                );
            }
        }
        assert_eq!(last_levels, 6);
    }
}

#[test]
fn every_flipped_byte_is_reported_not_decoded() {
    let opts = EncodeOptions {
        depth: Some(4),
        ..EncodeOptions::DEFAULT
    };
    let e = encode(&Model::Mesh(lodkit_mesh::shapes::icosphere(3)), &opts).unwrap();
    for i in 0..e.bytes.len() {
        let mut b = e.bytes.clone();
        b[i] ^= 0x01;
        let err = decode(&b, &DecodeOptions::default()).expect_err("a flipped bit must be caught");
        assert!(err.to_string().contains(".pop"), "{err}");
    }
}

#[test]
fn decoded_levels_stay_within_the_interior_diagonal_of_their_cubes() {
    // §6.5: h(M_r, S) ≤ ε_r, the interior diagonal of a level-r cube —
    // with inner thinning (the default) and with outer thinning too, on a
    // sphere and on the shipped (open) bunny scan.
    let bunny_path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../data/models/stanford_bunny.ply");
    let Model::Mesh(bunny) = lodkit_mesh::io::load(&bunny_path).unwrap() else {
        panic!("the bunny is a mesh")
    };
    let outer = crate::ThinningOptions {
        outer: true,
        ..crate::ThinningOptions::DEFAULT
    };
    for (name, surface) in [
        ("sphere", lodkit_mesh::shapes::icosphere(5)),
        ("bunny", bunny),
    ] {
        let index = SurfaceIndex::new(&surface).unwrap();
        for thinning in [crate::ThinningOptions::DEFAULT, outer] {
            let opts = EncodeOptions {
                depth: Some(7),
                precision: 14,
                thinning,
                ..EncodeOptions::DEFAULT
            };
            let e = encode(&Model::Mesh(surface.clone()), &opts).unwrap();
            let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
            for r in 2..=7u8 {
                let s = d.surface(r).unwrap();
                let t = triangulate(&s, &TriangulateOptions::DEFAULT);
                let eps = 3f32.sqrt() * s.frame.cube(r);
                let mut worst = 0f32;
                for f in &t.mesh.faces {
                    let [a, b, c] = f.map(|v| t.mesh.positions[v as usize]);
                    for (u, v) in [
                        (0.0, 0.0),
                        (1.0, 0.0),
                        (0.0, 1.0),
                        (1.0 / 3.0, 1.0 / 3.0),
                        (0.5, 0.5),
                        (0.5, 0.0),
                        (0.0, 0.5),
                    ] {
                        let p: Vec3 = a + (b - a) * u + (c - a) * v;
                        worst = worst.max(index.distance(p));
                    }
                }
                assert!(
                    worst <= eps,
                    "{name}, outer thinning {}: level {r}: h(M_r, S) = {worst} > ε_r = {eps}",
                    thinning.outer
                );
            }
        }
    }
}

#[test]
fn colours_and_normals_decode_exactly_at_every_level() {
    let mesh = coloured_sphere();
    for mode in [Mode::Baseline, Mode::Entropy] {
        let opts = EncodeOptions {
            depth: Some(5),
            mode,
            normals: true,
            ..EncodeOptions::DEFAULT
        };
        let e = encode(&Model::Mesh(mesh.clone()), &opts).unwrap();
        let d = decode(&e.bytes, &DecodeOptions::default()).unwrap();
        // The encoder's side, recomputed through the public stages.
        let mut t = Octree::from_mesh(
            &mesh,
            &BuildOptions {
                depth: Some(5),
                sidedness: None,
            },
        )
        .unwrap();
        thin(&mut t, &opts.thinning);
        let (h, src) = Hierarchy::from_thinned(&t).unwrap();
        let leaf_c: Vec<[u32; 3]> = src
            .iter()
            .map(|&s| t.leaves.colour.as_ref().unwrap()[s as usize].map(u32::from))
            .collect();
        let leaf_n: Vec<[u32; 3]> = src
            .iter()
            .map(|&s| attributes::quantise_normal(t.leaves.normal.as_ref().unwrap()[s as usize]))
            .collect();
        let want_c = attributes::average_up(&h, &leaf_c);
        let want_n = attributes::average_up(&h, &leaf_n);
        let got_c = d.colours.as_ref().unwrap();
        let got_n = d.normals.as_ref().unwrap();
        for r in 0..=5usize {
            for i in 0..h.levels[r].cells.len() {
                if h.levels[r].phantom[i] {
                    continue;
                }
                assert_eq!(
                    got_c[r][i], want_c.values[r][i],
                    "{mode:?} colour level {r} node {i}"
                );
                assert_eq!(
                    got_n[r][i], want_n.values[r][i],
                    "{mode:?} normal level {r} node {i}"
                );
            }
        }
        let _ = Channel::Colour;
    }
}

#[test]
fn streams_are_byte_identical_for_the_same_input() {
    let m = Model::Mesh(lodkit_mesh::shapes::torus(1.0, 0.3, 40, 20));
    for mode in [Mode::Baseline, Mode::Entropy] {
        let opts = EncodeOptions {
            depth: Some(6),
            mode,
            ..EncodeOptions::DEFAULT
        };
        assert_eq!(
            encode(&m, &opts).unwrap().bytes,
            encode(&m, &opts).unwrap().bytes
        );
    }
}
