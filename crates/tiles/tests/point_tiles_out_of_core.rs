//! The out-of-core point tiler forced on small clouds by tiny budgets:
//! the in-core tileset's bytes (ties, duplicates, normals and colours
//! included) whatever the budget and the thread count, every tile read
//! back, the same bytes on a rerun, nothing staged left, bad inputs
//! refused with one line.

mod common;

use std::path::Path;

use common::all_files;
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::io::{WriteOptions, save};
use lodkit_mesh::{Model, PointCloud};
use lodkit_tiles::{
    PointTilesOptions, PointsOutOfCoreOptions, point_tileset_out_of_core, tileset_from_points,
    write_point_tileset,
};

/// A bumpy sheet folded into an arc, with colours and normals, and
/// every 50th point repeated exactly (ties broken by input order) and a
/// run of points on one cell corner.
fn cloud(n: usize) -> PointCloud {
    let mut c = PointCloud {
        positions: Vec::new(),
        normals: Some(Vec::new()),
        colors: Some(Vec::new()),
    };
    let side = (n as f64).sqrt() as usize;
    for i in 0..n {
        let (u, v) = (
            (i % side) as f32 / side as f32,
            (i / side) as f32 / side as f32,
        );
        let a = 3.0 * u;
        let p = Vec3::new(a.cos(), a.sin(), v) * (1.0 + 0.05 * (17.0 * u * v).sin());
        let k = if i % 50 == 7 { i - 1 } else { i };
        let q = if k == i { p } else { c.positions[k] };
        c.positions.push(q);
        c.normals
            .as_mut()
            .unwrap()
            .push(Vec3::new(a.cos(), a.sin(), 0.0));
        c.colors
            .as_mut()
            .unwrap()
            .push([(u * 255.0) as u8, (v * 255.0) as u8, (i % 7) as u8, 255]);
    }
    for _ in 0..300 {
        c.positions.push(Vec3::new(0.5, 0.5, 0.5));
        c.normals.as_mut().unwrap().push(Vec3::Y);
        c.colors.as_mut().unwrap().push([1, 2, 3, 255]);
    }
    c
}

fn in_core(input: &Path, out: &Path, opts: &PointTilesOptions) {
    let Model::Points(c) = lodkit_mesh::io::load(input).unwrap() else {
        panic!("a cloud")
    };
    let t = tileset_from_points(&c, opts, &mut |_| {}).unwrap();
    write_point_tileset(&t, out, Some(input), opts, None, &mut |_| {}).unwrap();
}

fn out_of_core(
    input: &Path,
    out: &Path,
    opts: &PointTilesOptions,
    memory: u64,
) -> lodkit_tiles::Result<lodkit_tiles::PointTilesReport> {
    let staging = out.with_extension("staging");
    let o = PointsOutOfCoreOptions {
        memory,
        staging: staging.clone(),
    };
    let r = point_tileset_out_of_core(input, out, opts, &o, &|_| {});
    assert!(!staging.exists(), "the staging folder is removed");
    r.map(|(report, origin)| {
        assert_eq!(origin, None);
        report
    })
}

/// Every tile of `dir` read back as a cloud: the points of all tiles.
fn points_of(dir: &Path) -> Vec<[u32; 3]> {
    let mut all = Vec::new();
    let doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(dir.join("tileset.json")).unwrap()).unwrap();
    assert_eq!(doc["root"]["refine"], "ADD");
    for e in std::fs::read_dir(dir.join("tiles")).unwrap() {
        let p = e.unwrap().path();
        let bytes = std::fs::read(&p).unwrap();
        if p.extension().is_some_and(|x| x == "json") {
            serde_json::from_slice::<serde_json::Value>(&bytes).expect("valid JSON");
            continue;
        }
        let Model::Points(c) = lodkit_mesh::io::gltf::read_model(&bytes, None).unwrap() else {
            panic!("{}: a point tile", p.display())
        };
        assert!(c.colors.is_some() && c.normals.is_some());
        all.extend(c.positions.iter().map(|v| v.to_array().map(f32::to_bits)));
    }
    all
}

#[test]
fn every_budget_gives_the_in_core_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cloud.ply");
    let c = cloud(40_000);
    save(&input, &Model::Points(c.clone()), WriteOptions::DEFAULT).unwrap();
    for leaf_points in [256, 3_000] {
        let opts = PointTilesOptions {
            leaf_points,
            ..PointTilesOptions::DEFAULT
        };
        let want = dir.path().join(format!("in{leaf_points}"));
        in_core(&input, &want, &opts);
        let want = all_files(&want);
        // 16 KiB: streamed to depth 4 and more; 1 MiB: the root alone;
        // 64 MiB: one subtree, the whole cloud.
        for memory in [16 << 10, 1 << 20, 64 << 20] {
            let out = dir.path().join(format!("out{leaf_points}-{memory}"));
            let r = out_of_core(&input, &out, &opts, memory).unwrap();
            assert_eq!(r.input_points, c.positions.len());
            let got = all_files(&out);
            assert_eq!(got.len(), want.len(), "leaf {leaf_points}, memory {memory}");
            for (g, w) in got.iter().zip(&want) {
                assert!(
                    g == w,
                    "{} differs (leaf {leaf_points}, memory {memory})",
                    g.0
                );
            }
            // The same call again over its own output: the same bytes.
            out_of_core(&input, &out, &opts, memory).unwrap();
            assert!(all_files(&out) == got);
        }
    }
    // Read back: every input point in exactly one tile (positions as the
    // tiles quantise them, so compared as a count and a multiset size).
    let out = dir.path().join("out256-16384");
    assert_eq!(points_of(&out).len(), c.positions.len());
}

/// The passes split the cloud into chunks over the threads, subtrees are
/// tiled several at once and tiles written by several threads: one
/// thread or many, the in-core bytes.
#[test]
fn one_thread_or_many_give_the_in_core_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("cloud.ply");
    save(&input, &Model::Points(cloud(30_000)), WriteOptions::DEFAULT).unwrap();
    let opts = PointTilesOptions {
        leaf_points: 256,
        ..PointTilesOptions::DEFAULT
    };
    let want = dir.path().join("in");
    in_core(&input, &want, &opts);
    let want = all_files(&want);
    for threads in [1, 3, 8] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        // 16 KiB: chunks of the fewest points, streamed to depth 4 and
        // more; 1 MiB: the root streamed, its subtrees tiled several at
        // once.
        for memory in [16 << 10, 1 << 20] {
            let out = dir.path().join(format!("out{threads}-{memory}"));
            pool.install(|| out_of_core(&input, &out, &opts, memory))
                .unwrap();
            assert!(
                all_files(&out) == want,
                "{threads} threads, memory {memory}: the in-core bytes"
            );
        }
    }
}

#[test]
fn bad_inputs_are_refused_with_one_line_and_leave_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let opts = PointTilesOptions {
        leaf_points: 256,
        ..PointTilesOptions::DEFAULT
    };
    let good = dir.path().join("c.ply");
    save(&good, &Model::Points(cloud(2_000)), WriteOptions::DEFAULT).unwrap();
    let bytes = std::fs::read(&good).unwrap();
    // Truncated, one byte too many, a mesh, an ASCII file, no points.
    let truncated = dir.path().join("truncated.ply");
    std::fs::write(&truncated, &bytes[..bytes.len() - 5]).unwrap();
    let long = dir.path().join("long.ply");
    std::fs::write(&long, [&bytes[..], b"x"].concat()).unwrap();
    let mesh = dir.path().join("mesh.ply");
    save(
        &mesh,
        &Model::Mesh(lodkit_mesh::shapes::icosphere(1)),
        WriteOptions::DEFAULT,
    )
    .unwrap();
    let ascii = dir.path().join("ascii.ply");
    save(
        &ascii,
        &Model::Points(cloud(100)),
        WriteOptions { ascii: true },
    )
    .unwrap();
    let empty = dir.path().join("empty.ply");
    std::fs::write(
        &empty,
        "ply\nformat binary_little_endian 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\nend_header\n",
    )
    .unwrap();
    for input in [&truncated, &long, &mesh, &ascii, &empty] {
        let out = dir.path().join("out");
        let e = out_of_core(input, &out, &opts, 1 << 14)
            .unwrap_err()
            .to_string();
        let name = input.file_name().unwrap().to_str().unwrap();
        assert!(e.contains(name) && !e.contains('\n'), "{e}");
        assert!(!out.exists(), "{name}: no output");
    }
    // A leaf option out of range.
    let e = out_of_core(
        &good,
        &dir.path().join("out"),
        &PointTilesOptions {
            leaf_points: 3,
            ..opts
        },
        1 << 14,
    )
    .unwrap_err();
    assert!(matches!(e, lodkit_tiles::Error::Usage(_)), "{e}");
}

/// The shared Autzen LAZ (z-up, far from zero) forced out of core: the
/// in-core bytes, its origin the root transform. Skips when the shared
/// data is absent.
#[test]
fn a_laz_cloud_gives_the_in_core_bytes() {
    let data = std::env::var_os("LODKIT_SHARED_DATA").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
        std::path::PathBuf::from,
    );
    let input = data.join("points/autzen_trim.laz");
    if !input.is_file() {
        eprintln!("skipped: {} is absent", input.display());
        return;
    }
    let opts = PointTilesOptions {
        leaf_points: 2_000,
        ..PointTilesOptions::DEFAULT
    };
    let dir = tempfile::tempdir().unwrap();
    let (want, got) = (dir.path().join("in"), dir.path().join("out"));
    let located = lodkit_mesh::io::load_located(&input).unwrap();
    let Model::Points(c) = located.model else {
        panic!("a cloud")
    };
    // The job's turn to y-up.
    let c = PointCloud {
        positions: c
            .positions
            .iter()
            .map(|v| Vec3::new(v.x, v.z, -v.y))
            .collect(),
        ..c
    };
    let t = tileset_from_points(&c, &opts, &mut |_| {}).unwrap();
    write_point_tileset(&t, &want, Some(&input), &opts, located.origin, &mut |_| {}).unwrap();
    let o = PointsOutOfCoreOptions {
        memory: 1 << 16,
        staging: dir.path().join("staging"),
    };
    let (r, origin) = point_tileset_out_of_core(&input, &got, &opts, &o, &|_| {}).unwrap();
    assert_eq!(origin, located.origin);
    assert_eq!(r.input_points, c.positions.len());
    assert!(all_files(&got) == all_files(&want), "the in-core bytes");
    assert!(!dir.path().join("staging").exists());
    // Cut short: one line naming the file, nothing written.
    let bytes = std::fs::read(&input).unwrap();
    let short = dir.path().join("short.laz");
    std::fs::write(&short, &bytes[..bytes.len() * 2 / 3]).unwrap();
    let out = dir.path().join("short");
    let e = point_tileset_out_of_core(&short, &out, &opts, &o, &|_| {})
        .expect_err("refused")
        .to_string();
    assert!(e.contains("short.laz") && !e.contains('\n'), "{e}");
    assert!(!out.exists() && !dir.path().join("staging").exists());
}
