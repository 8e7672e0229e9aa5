//! Unit tests of the out-of-core point tiler's private paths.
use super::*;

/// Every file of a folder and its bytes, by path.
fn files(dir: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    let mut all = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else {
                all.push((
                    p.strip_prefix(dir).unwrap().to_path_buf(),
                    std::fs::read(&p).unwrap(),
                ));
            }
        }
    }
    all.sort();
    all
}

/// Children decided in their parents' pass (the claims' limit lifted,
/// so small budgets take that path at every streamed depth), on a
/// cloud of many duplicates (ties by input order), clusters and a
/// spread: the in-core bytes, in fewer passes.
#[test]
fn children_decided_with_their_parents_give_the_in_core_bytes() {
    use lodkit_mesh::{Model, PointCloud};
    let mut c = PointCloud {
        positions: Vec::new(),
        normals: None,
        colors: Some(Vec::new()),
    };
    let mut x = 99u64;
    for i in 0..30_000u32 {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let f = |s: u64| ((x >> s) & 0xffff) as f32 / 65535.0;
        let p = match i % 3 {
            // A coarse lattice: many points on the same spot.
            0 => Vec3::new(f(0), f(16), f(32)).map(|v| (v * 6.0).floor() / 6.0),
            1 => Vec3::new(f(0), f(16), f(32)) * 0.01 + Vec3::splat(0.3),
            _ => Vec3::new(f(0), f(16), f(32)),
        };
        c.positions.push(p);
        c.colors
            .as_mut()
            .unwrap()
            .push([(i % 251) as u8, 0, 0, 255]);
    }
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("c.ply");
    lodkit_mesh::io::save(&input, &Model::Points(c.clone()), Default::default()).unwrap();
    let opts = PointTilesOptions {
        leaf_points: 256,
        ..PointTilesOptions::DEFAULT
    };
    let want = dir.path().join("in");
    let t = crate::tileset_from_points(&c, &opts, &mut |_| {}).unwrap();
    crate::write_point_tileset(&t, &want, Some(&input), &opts, None, &mut |_| {}).unwrap();
    let want = files(&want);
    for memory in [16 << 10, 256 << 10] {
        let out = dir.path().join(format!("out{memory}"));
        let o = PointsOutOfCoreOptions {
            memory,
            staging: dir.path().join("staging"),
        };
        let passes = std::sync::atomic::AtomicUsize::new(0);
        let tuning = Tuning {
            runners: Some(u64::MAX),
        };
        tuned(&input, &out, &opts, &o, &tuning, &|e| {
            if let OutOfCoreEvent::Phase(name, _) = e
                && name.starts_with("points: choosing")
            {
                passes.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
        })
        .unwrap();
        assert!(files(&out) == want, "memory {memory}: the in-core bytes");
        // Without the lift: the same bytes, in more passes.
        let slow = dir.path().join(format!("slow{memory}"));
        let more = std::sync::atomic::AtomicUsize::new(0);
        tuned(&input, &slow, &opts, &o, &Tuning::default(), &|e| {
            if let OutOfCoreEvent::Phase(name, _) = e
                && name.starts_with("points: choosing")
            {
                more.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            }
        })
        .unwrap();
        assert!(files(&slow) == want, "memory {memory}: the in-core bytes");
        let (fused, plain) = (passes.into_inner(), more.into_inner());
        assert!(
            fused < plain,
            "memory {memory}: {fused} passes, {plain} without"
        );
    }
}

/// `octant` is the in-core routing (`cell_of`'s low bits), also for
/// points on cell borders and outside the cube (clamped).
#[test]
fn octant_routes_as_cell_of() {
    let grid = Grid::around(&Aabb {
        min: Vec3::new(-1.0, -2.0, 0.5),
        max: Vec3::new(3.0, 1.0, 0.75),
    });
    let mut x = 12345u64;
    for k in 0..100_000 {
        x = x
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        let f = |s: u64| ((x >> s) & 0xffff) as f32 / 65535.0 * 6.0 - 2.5;
        let mut p = Vec3::new(f(0), f(16), f(32));
        if k % 3 == 0 {
            // On a cell border of some depth.
            let d = (x >> 48) as u8 % 8;
            let c = grid.size / f64::from(1u32 << d);
            p.x = (grid.origin.x + c * ((x >> 52) % 4) as f64) as f32;
        }
        for depth in [0u8, 1, 3, 7, 12] {
            let c = grid.cell_of(p, depth + 1);
            let want = (c.xyz[0] & 1) | ((c.xyz[1] & 1) << 1) | ((c.xyz[2] & 1) << 2);
            assert_eq!(u32::from(octant(&grid, p, depth)), want, "{p} at {depth}");
        }
    }
}
