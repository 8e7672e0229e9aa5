//! The out-of-core path against the in-core one on a small blob, with a
//! memory budget tiny enough to force many blocks and both rounds.

use std::path::Path;

use lodkit_mesh::TriMesh;
use lodkit_mesh::metrics::{CompareOptions, SymmetricStats, compare};
use lodkit_scale::{Event, ScaleOptions, simplify_file};
use lodkit_simplify::{Options, simplify};

fn quiet(_: Event) {}

fn opts(dir: &Path, ratio: f32, memory: u64) -> ScaleOptions {
    ScaleOptions {
        simplify: Options::ratio(ratio),
        memory,
        staging: dir.join("staging"),
        runner: Default::default(),
    }
}

/// Faces whose normal points inward (the blob is star-shaped around 0).
fn inward(m: &TriMesh) -> usize {
    m.faces
        .iter()
        .filter(|f| {
            let [a, b, c] = f.map(|i| m.positions[i as usize]);
            (b - a).cross(c - a).dot(a + b + c) < 0.0
        })
        .count()
}

/// Asserts the out-of-core error `ea` within `mean`× and `max`× the
/// in-core `eb` (symmetric Metro distances), naming `at`.
fn within(ea: &SymmetricStats, eb: &SymmetricStats, mean: f64, max: f64, at: &str) {
    assert!(
        ea.mean <= mean * eb.mean,
        "{at}: mean {} vs in core {}",
        ea.mean,
        eb.mean
    );
    assert!(
        ea.max <= max * eb.max,
        "{at}: max {} vs in core {}",
        ea.max,
        eb.max
    );
}

fn faces_off(n: usize, target: usize) -> f64 {
    (n as f64 - target as f64).abs() / target as f64
}

#[test]
fn out_of_core_hits_the_target_deterministically() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 60_000, 1).unwrap();
    let mesh = lodkit_mesh::io::load_mesh(&input).unwrap();
    for ratio in [0.1f32, 0.02] {
        // 400 kB: ~16 blocks of a few thousand faces, two rounds, and a
        // final pass that holds less than the target (the budget is then
        // exceeded there, and quality is not promised: see the next test).
        let o = opts(dir.path(), ratio, 400_000);
        let (a, rep) = simplify_file(&input, &o, &quiet).unwrap();
        assert!(rep.round_blocks[0] > 4, "{rep:?}");
        let target = (mesh.faces.len() as f32 * ratio) as usize;
        assert!(
            faces_off(a.faces.len(), target) <= 0.005,
            "{} faces for {target}",
            a.faces.len()
        );
        // Same again from scratch: same mesh, bit for bit.
        std::fs::remove_dir_all(&o.staging).unwrap();
        let (b, _) = simplify_file(&input, &o, &quiet).unwrap();
        assert_eq!(a, b);
        std::fs::remove_dir_all(&o.staging).unwrap();
    }
}

/// The out-of-core quality bound (mean error within 1.1× in core, max within
/// 1.2×), on a mesh small enough to run both ways in a test: budgets that
/// force blocks (one round of 8 blocks; two rounds of 26 and 25) but let
/// the final pass hold more than the target, which is what the block goal
/// (`run.rs`, `round_goal`) leaves it. The runs are deterministic, so the
/// ratios are the same on every run.
#[test]
fn out_of_core_error_stays_within_the_in_core_bounds() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 60_000, 1).unwrap();
    let mesh = lodkit_mesh::io::load_mesh(&input).unwrap();
    let cmp = CompareOptions {
        samples: Some(200_000),
        ..CompareOptions::default()
    };
    for ratio in [0.1f32, 0.02] {
        let in_core = simplify(&mesh, &Options::ratio(ratio)).unwrap().mesh;
        let eb = compare(&mesh, &in_core, &cmp).unwrap().symmetric;
        for (memory, rounds) in [(3 << 20, 1), (2 << 20, 2)] {
            let o = opts(dir.path(), ratio, memory);
            let (a, rep) = simplify_file(&input, &o, &quiet).unwrap();
            std::fs::remove_dir_all(&o.staging).unwrap();
            assert_eq!(rep.round_blocks.len(), rounds, "{rep:?}");
            assert!(rep.round_blocks[0] >= 8, "{rep:?}");
            let target = (mesh.faces.len() as f32 * ratio) as usize;
            assert!(
                faces_off(a.faces.len(), target) <= 0.005,
                "{} faces for {target}",
                a.faces.len()
            );
            let ea = compare(&mesh, &a, &cmp).unwrap().symmetric;
            let at = format!("ratio {ratio}, memory {memory}");
            within(&ea, &eb, 1.1, 1.2, &at);
        }
    }
}

#[test]
fn a_rerun_resumes_from_finished_blocks() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 20_000, 2).unwrap();
    let o = opts(dir.path(), 0.1, 150_000);
    let (a, first) = simplify_file(&input, &o, &quiet).unwrap();
    assert_eq!(first.resumed_blocks, 0);
    // As if killed after the blocks: the staging folder is still there,
    // and finished_blocks counts what the rerun skips.
    let done = lodkit_scale::finished_blocks(&o.staging);
    assert!(done > 0);
    let (b, again) = simplify_file(&input, &o, &quiet).unwrap();
    assert_eq!(again.resumed_blocks, done);
    assert_eq!(a, b);
}

#[test]
fn bad_input_is_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("bad.ply");
    std::fs::write(&input, b"ply\nformat binary_little_endian 1.0\nelement vertex 1000\nproperty float x\nproperty float y\nproperty float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n").unwrap();
    let e = simplify_file(&input, &opts(dir.path(), 0.5, 1000), &quiet).unwrap_err();
    assert!(e.contains("bad.ply") && !e.contains('\n'), "{e}");
}

/// No fold-over beyond what the in-core path leaves: blocks keep their
/// interiors at the target density (the border-aware goal, `block.rs`)
/// and the final pass, which frees the seams, has room to work. Inward
/// faces are a count of a few (in core leaves 0–12 on blobs of 1 k–200 k
/// output faces), so the allowance is 0.25 % of the output.
#[test]
fn no_more_inward_faces_than_in_core() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 60_000, 1).unwrap();
    let mesh = lodkit_mesh::io::load_mesh(&input).unwrap();
    for ratio in [0.1f32, 0.02] {
        let in_core = simplify(&mesh, &Options::ratio(ratio)).unwrap().mesh;
        let o = opts(dir.path(), ratio, 2 << 20);
        let (a, _) = simplify_file(&input, &o, &quiet).unwrap();
        std::fs::remove_dir_all(&o.staging).unwrap();
        assert!(
            inward(&a) <= inward(&in_core) + a.faces.len() / 400,
            "ratio {ratio}: inward faces: {} vs in core {}",
            inward(&a),
            inward(&in_core)
        );
    }
}

/// A budget whose final pass holds under twice the target (here 1.5×):
/// round 0 stops at twice what the final pass holds and the round on the
/// shifted grid does the rest, so round 0's cuts are re-simplified inside
/// round-1 blocks. Quality is short of the in-core bounds here (the
/// known gap, ARCHITECTURE.md), but within a looser one that the straight
/// round missed.
#[test]
fn a_tight_budget_takes_a_shifted_round_before_the_final_pass() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 60_000, 1).unwrap();
    let mesh = lodkit_mesh::io::load_mesh(&input).unwrap();
    let cmp = CompareOptions {
        samples: Some(200_000),
        ..CompareOptions::default()
    };
    let ratio = 0.1f32;
    let target = (mesh.faces.len() as f32 * ratio) as usize;
    // The final pass holds 9000 faces at 80 B each: 1.5× the target.
    let o = opts(dir.path(), ratio, 9000 * 80);
    let (a, rep) = simplify_file(&input, &o, &quiet).unwrap();
    assert_eq!(rep.round_blocks.len(), 2, "{rep:?}");
    assert!(rep.round_faces[0] >= 2 * 8100, "{rep:?}");
    assert!(
        faces_off(a.faces.len(), target) <= 0.005,
        "{} faces for {target}",
        a.faces.len()
    );
    let in_core = simplify(&mesh, &Options::ratio(ratio)).unwrap().mesh;
    let eb = compare(&mesh, &in_core, &cmp).unwrap().symmetric;
    let ea = compare(&mesh, &a, &cmp).unwrap().symmetric;
    // One straight round to the goal (round 0 overflowing into a second
    // round at the final goal) gave 1.16× / 1.47× here; this way 1.10× /
    // 1.32×.
    within(&ea, &eb, 1.15, 1.4, "shifted round");
}

/// Edges with other than two faces: 0 on a closed manifold (the blob), so
/// a welded level has no crack along the block cuts.
fn open_edges(m: &TriMesh) -> usize {
    lodkit_mesh::topology::edge_multiplicities(m)
        .into_iter()
        .filter(|e| e.count != 2)
        .count()
}

/// An out-of-core chain: levels too big for the budget as block soups
/// (written as PLY, crack-free, within 0.5 % of their target), the rest in
/// core to the exact target; the same bytes on a second run and on a
/// resumed one.
#[test]
fn an_out_of_core_chain_gives_crack_free_levels_on_target() {
    use lodkit_scale::{ChainLevel, lod_chain_file, write_soups_ply};
    use lodkit_simplify::Target;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 60_000, 2).unwrap();
    let n = lodkit_mesh::io::load_mesh(&input).unwrap().faces.len();
    let targets = [0.5f32, 0.25, 0.1, 0.02].map(Target::Ratio);
    // 400 kB: the final pass holds 5 k faces, so 0.5, 0.25 and 0.1 of
    // 60 k are made out of core (64 blocks), 0.02 in core after one more
    // block round (the 6 k of level 3 do not fit either).
    let o = opts(dir.path(), 1.0, 400_000);
    // Each level's bytes (empty for a level resumed, not rewritten) and
    // whether it was made out of core; `fail_at`: the level whose hand-over
    // fails, as if the disk filled there.
    let run = |tag: &str, fail_at: Option<usize>| -> Result<Vec<(Vec<u8>, bool)>, String> {
        let mut levels = Vec::new();
        lod_chain_file(&input, &targets, &o, &quiet, &mut |i, l| {
            if Some(i) == fail_at {
                return Err("disk full".into());
            }
            let path = dir.path().join(format!("{tag}{i}.ply"));
            let out_of_core = match l {
                ChainLevel::Soups {
                    faces,
                    layout,
                    files,
                } => {
                    let (f, _) = write_soups_ply(files, layout, &path)?;
                    assert_eq!(f, faces);
                    true
                }
                ChainLevel::Resumed { .. } => {
                    levels.push((Vec::new(), true));
                    return Ok(());
                }
                ChainLevel::Mesh { mesh, .. } => {
                    lodkit_mesh::io::save_mesh(&path, mesh, Default::default())
                        .map_err(|e| e.to_string())?;
                    false
                }
            };
            levels.push((std::fs::read(&path).unwrap(), out_of_core));
            Ok(())
        })?;
        Ok(levels)
    };
    let a = run("a", None).unwrap();
    assert_eq!(
        a.iter().map(|l| l.1).collect::<Vec<_>>(),
        [true, true, true, false]
    );
    for (i, (bytes, _)) in a.iter().enumerate() {
        let path = dir.path().join(format!("a{i}.ply"));
        assert_eq!(&std::fs::read(&path).unwrap(), bytes);
        let m = lodkit_mesh::io::load_mesh(&path).unwrap();
        let target = targets[i].faces(n);
        assert!(
            faces_off(m.faces.len(), target) <= 0.005,
            "level {i}: {} for {target}",
            m.faces.len()
        );
        assert_eq!(open_edges(&m), 0, "level {i}");
    }
    let last = lodkit_mesh::io::load_mesh(&dir.path().join("a3.ply")).unwrap();
    assert!(last.faces.len() <= targets[3].faces(n));
    std::fs::remove_dir_all(&o.staging).unwrap();
    assert_eq!(run("b", None).unwrap(), a);
    // A run that fails handing level 3 over keeps its blocks; the rerun
    // hands levels 1 and 2 over as resumed and makes the rest to the
    // same bytes.
    std::fs::remove_dir_all(&o.staging).unwrap();
    assert_eq!(run("c", Some(2)).unwrap_err(), "disk full");
    let c = run("c", None).unwrap();
    assert!(c[..2].iter().all(|l| l.0.is_empty()));
    assert_eq!(c[2..], a[2..]);
}

/// A blob whose colours, normals and UVs are smooth functions of the
/// position, written as binary PLY.
fn attributed_blob(path: &Path, triangles: usize) -> TriMesh {
    let mut m = lodkit_mesh::shapes::blob_with_seed(triangles, 4);
    let f = |p: glam::Vec3| [(p.x * 0.5 + 0.5), (p.y * 0.5 + 0.5), (p.z * 0.5 + 0.5)];
    m.colors = Some(
        m.positions
            .iter()
            .map(|&p| {
                let c = f(p).map(|x| (x.clamp(0.0, 1.0) * 255.0).round() as u8);
                [c[0], c[1], c[2], 255]
            })
            .collect(),
    );
    m.normals = Some(m.positions.iter().map(|p| p.normalize()).collect());
    m.uvs = Some(
        m.positions
            .iter()
            .map(|p| glam::Vec2::new(p.x, p.y))
            .collect(),
    );
    lodkit_mesh::io::save_mesh(path, &m, Default::default()).unwrap();
    m
}

/// Normals, colours and UVs go through the blocks and the final pass: the
/// out-of-core result has them, and each vertex's colour and UV still
/// match its position as closely as the in-core result's do.
#[test]
fn attributes_go_through_the_blocks() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("colored.ply");
    let mesh = attributed_blob(&input, 40_000);
    let o = opts(dir.path(), 0.1, 400_000);
    let (out, rep) = simplify_file(&input, &o, &quiet).unwrap();
    assert!(rep.round_blocks[0] > 4, "{rep:?}");
    let (colors, uvs, normals) = (
        out.colors.as_ref().expect("colours kept"),
        out.uvs.as_ref().expect("UVs kept"),
        out.normals.as_ref().expect("normals kept"),
    );
    assert_eq!(colors.len(), out.positions.len());
    assert_eq!(uvs.len(), out.positions.len());
    let in_core = simplify(&mesh, &Options::ratio(0.1)).unwrap().mesh;
    // Worst distance of a vertex's UV from (x, y) and of its red channel
    // from its x: the simplifier moves attributes with the geometry.
    let drift = |m: &TriMesh| {
        let (c, u) = (m.colors.as_ref().unwrap(), m.uvs.as_ref().unwrap());
        m.positions
            .iter()
            .enumerate()
            .fold((0f32, 0f32), |(a, b), (i, p)| {
                let red = (p.x * 0.5 + 0.5).clamp(0.0, 1.0) * 255.0;
                (
                    a.max((u[i] - glam::Vec2::new(p.x, p.y)).length()),
                    b.max((c[i][0] as f32 - red).abs()),
                )
            })
    };
    let (ou, oc) = drift(&out);
    let (iu, ic) = drift(&in_core);
    eprintln!("drift: uv {ou} (in core {iu}), red {oc} (in core {ic})");
    assert!(
        ou <= 2.0 * iu + 1e-3 && oc <= 2.0 * ic + 2.0,
        "uv {ou} vs {iu}, red {oc} vs {ic}"
    );
    assert!(normals.iter().all(|n| n.is_finite()));
    // The same bytes again (deterministic with attributes too).
    std::fs::remove_dir_all(&o.staging).unwrap();
    assert_eq!(simplify_file(&input, &o, &quiet).unwrap().0, out);
}

/// A binary STL goes through the same pipeline (streamed facets instead
/// of a vertex table): the same result as the same mesh in PLY.
#[test]
fn a_binary_stl_simplifies_out_of_core_like_the_same_ply() {
    let dir = tempfile::tempdir().unwrap();
    let m = lodkit_mesh::shapes::blob_with_seed(30_000, 6);
    let (ply, stl) = (dir.path().join("m.ply"), dir.path().join("m.stl"));
    lodkit_mesh::io::save_mesh(&ply, &m, Default::default()).unwrap();
    lodkit_mesh::io::save_mesh(&stl, &m, Default::default()).unwrap();
    let mut o = opts(dir.path(), 0.1, 300_000);
    let (a, ra) = simplify_file(&ply, &o, &quiet).unwrap();
    o.staging = dir.path().join("staging-stl");
    let (b, rb) = simplify_file(&stl, &o, &quiet).unwrap();
    assert_eq!(ra.input_faces, rb.input_faces);
    assert!(rb.round_blocks[0] > 4, "{rb:?}");
    assert_eq!(a, b);
}

/// A real scan's open rim (the Stanford bunny's base, shipped in
/// `data/models`) simplifies in the blocks as in core: only the vertices
/// that may lie on a cut are locked, so the final pass does not thin a
/// full-density rim from a coarse neighbourhood (which gave 2.8× the
/// in-core maximum error on a 20 M-triangle subdivided bunny at 1 %).
#[test]
fn an_open_scan_keeps_its_rim_as_in_core() {
    let dir = tempfile::tempdir().unwrap();
    let input = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/models/stanford_bunny.ply");
    let mesh = lodkit_mesh::io::load_mesh(&input).unwrap();
    let cmp = CompareOptions {
        samples: Some(200_000),
        ..CompareOptions::default()
    };
    for ratio in [0.1f32, 0.02] {
        let in_core = simplify(&mesh, &Options::ratio(ratio)).unwrap().mesh;
        let eb = compare(&mesh, &in_core, &cmp).unwrap().symmetric;
        let o = opts(dir.path(), ratio, 5 << 20);
        let (a, rep) = simplify_file(&input, &o, &quiet).unwrap();
        std::fs::remove_dir_all(&o.staging).unwrap();
        assert!(rep.round_blocks[0] >= 8, "{rep:?}");
        let ea = compare(&mesh, &a, &cmp).unwrap().symmetric;
        within(&ea, &eb, 1.1, 1.2, &format!("ratio {ratio}"));
    }
}

/// A staging folder one run holds refuses a second run at once, in one
/// line naming it; free again, the run goes through.
#[test]
fn a_held_staging_folder_refuses_a_second_run() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 20_000, 2).unwrap();
    let o = opts(dir.path(), 0.1, 150_000);
    let held = lodkit_scale::StagingLock::take(&o.staging).unwrap();
    let e = simplify_file(&input, &o, &quiet).unwrap_err();
    assert!(
        e.contains("another lodkit run is using this staging folder")
            && e.contains(&o.staging.display().to_string())
            && !e.contains('\n'),
        "{e}"
    );
    assert_eq!(lodkit_scale::remove_staging(&o.staging), Ok(false));
    drop(held);
    simplify_file(&input, &o, &quiet).unwrap();
    assert_eq!(lodkit_scale::remove_staging(&o.staging), Ok(true));
    assert!(!o.staging.exists());
}

/// The files of the last round folder, by extension.
fn round_files(staging: &Path, ext: &str) -> Vec<std::path::PathBuf> {
    let mut rounds: Vec<_> = std::fs::read_dir(staging)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.is_dir())
        .collect();
    rounds.sort();
    let last = rounds.last().unwrap();
    let mut v: Vec<_> = std::fs::read_dir(last)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == ext))
        .collect();
    v.sort();
    v
}

/// A staging folder damaged or tampered with after a run (a block
/// output emptied, zeroed or turned into a link to /dev/zero or to a
/// user's file, a block input of 0 bytes in place of an output, a
/// manifest cut short or with NaN bounds) is found out and redone: the
/// rerun gives the same mesh as a clean run, promptly, and writes
/// through no link.
#[test]
fn a_tampered_staging_folder_is_redone_to_the_same_bytes() {
    use lodkit_scale::soup::Sum;
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 20_000, 2).unwrap();
    let victim = dir.path().join("victim.txt");
    std::fs::write(&victim, b"a user's file").unwrap();
    let o = opts(dir.path(), 0.1, 150_000);
    let (clean, _) = simplify_file(&input, &o, &quiet).unwrap();
    type Tamper = fn(&Path, &Path);
    let cases: [(&str, Tamper); 7] = [
        ("an output emptied", |s, _| {
            std::fs::write(&round_files(s, "out")[0], b"").unwrap()
        }),
        ("an output zeroed", |s, _| {
            let p = &round_files(s, "out")[1];
            let n = std::fs::metadata(p).unwrap().len() as usize;
            std::fs::write(p, vec![0u8; n]).unwrap()
        }),
        ("an output a link to /dev/zero", |s, _| {
            let p = &round_files(s, "out")[0];
            std::fs::remove_file(p).unwrap();
            std::os::unix::fs::symlink("/dev/zero", p).unwrap()
        }),
        ("an output a link to a user's file", |s, v| {
            let p = &round_files(s, "out")[0];
            std::fs::remove_file(p).unwrap();
            std::os::unix::fs::symlink(v, p).unwrap();
            // And the name the next write of that block uses.
            std::os::unix::fs::symlink(v, p.with_extension("partial")).unwrap()
        }),
        ("an input of 0 bytes instead of an output", |s, _| {
            let p = &round_files(s, "out")[0];
            std::fs::remove_file(p).unwrap();
            std::fs::write(p.with_extension("in"), b"").unwrap()
        }),
        ("a manifest cut short", |s, _| {
            let p = s.join("r0/parted");
            let t = std::fs::read(&p).unwrap();
            std::fs::write(&p, &t[..t.len() / 2]).unwrap()
        }),
        ("a manifest with NaN bounds", |s, _| {
            let p = s.join("r0/parted");
            let t = std::fs::read_to_string(&p).unwrap();
            let mut lines: Vec<&str> = t.lines().collect();
            lines.pop();
            let first = lines[0].replacen(&lines[0][..8], "7fc00000", 1);
            lines[0] = &first;
            let body: String = lines.iter().map(|l| format!("{l}\n")).collect();
            let mut h = Sum::NEW;
            h.add(body.as_bytes());
            std::fs::write(&p, format!("{body}end {:016x}\n", h.0)).unwrap()
        }),
    ];
    for (what, tamper) in cases {
        simplify_file(&input, &o, &quiet).unwrap();
        tamper(&o.staging, &victim);
        let t = std::time::Instant::now();
        let (again, _) =
            simplify_file(&input, &o, &quiet).unwrap_or_else(|e| panic!("{what}: {e}"));
        assert!(t.elapsed().as_secs() < 60, "{what}");
        assert!(again == clean, "{what}: another mesh");
        assert_eq!(std::fs::read(&victim).unwrap(), b"a user's file", "{what}");
        std::fs::remove_dir_all(&o.staging).unwrap();
    }
}

/// Staging folders an earlier run left beside an output are removed by
/// `remove_abandoned` when they are lodkit's and no run holds them; the
/// run's own, a held one and one lodkit did not make are kept.
#[test]
fn abandoned_staging_folders_are_removed_and_others_kept() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("blob.ply");
    lodkit_mesh::shapes::write_blob_ply(&input, 20_000, 2).unwrap();
    let output = dir.path().join("out.ply");
    let at = |settings: &str| lodkit_scale::staging_dir(&input, &output, settings);
    let (old, held, mine) = (at("a"), at("b"), at("c"));
    for s in [&old, &held, &mine] {
        drop(lodkit_scale::StagingLock::take(s).unwrap());
    }
    let lock = lodkit_scale::StagingLock::take(&held).unwrap();
    let foreign = dir.path().join(".out.ply.lodkit-staging-00000000000000ff");
    std::fs::create_dir(&foreign).unwrap();
    std::fs::write(foreign.join("lock"), b"mine").unwrap();
    assert_eq!(
        lodkit_scale::remove_abandoned(&output, &mine),
        vec![old.clone()]
    );
    assert!(!old.exists() && held.exists() && mine.exists() && foreign.exists());
    drop(lock);
    assert_eq!(
        lodkit_scale::remove_abandoned(&output, &mine),
        vec![held.clone()]
    );
    assert!(mine.exists() && foreign.join("lock").exists());
}
