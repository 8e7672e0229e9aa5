//! View-dependent cuts: a [`ViewCut`] kept from frame to frame gives
//! exactly the cut made from scratch for each camera, and both give the
//! cut the plain scan of every node defines
//! ([`crate::view_dependent_cut::select`]), on built and on loaded models,
//! for camera paths that zoom in and out, orbit, look away and change the
//! tolerance; every cut of a closed shape is crack-free.

use super::support;

use crate::pipeline::{Options, build_from_mesh};
use crate::view_dependent_cut::{hairline_tolerances, has_layout, select};
use crate::{Camera, McoModel, ViewCut};
use lodkit_mesh::glam::Vec3;
use lodkit_mesh::shapes;

fn model(mesh: &lodkit_mesh::TriMesh, resolution: u32) -> McoModel {
    build_from_mesh(
        mesh,
        &Options {
            resolution: Some(resolution),
        },
    )
    .unwrap()
}

/// The 20k-triangle blob as read back from its `.mco` (nodes in LOD
/// order, as a reader sees them), its bounds' centre and diagonal.
fn loaded_blob() -> (McoModel, Vec3, f32) {
    let blob = McoModel::from_bytes(&model(&shapes::blob(20_000), 48).to_bytes()).unwrap();
    let (lo, hi) = blob.bounds();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length());
    (blob, c, r)
}

/// A camera path around the model's root cube: an orbit that zooms from
/// far outside to inside the cube, glances past it, looks away, and
/// changes the tolerance and viewport on the way.
fn camera_path(m: &McoModel) -> Vec<(Camera, f32)> {
    let (lo, hi) = m.bounds();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length());
    let mut out = Vec::new();
    for i in 0..48 {
        let a = i as f32 * 0.37;
        let dist = [30.0, 6.0, 2.0, 1.0, 0.55, 0.3, 0.12, 0.02][i % 8];
        let dir = Vec3::new(a.cos(), 0.4 * (1.3 * a).sin(), a.sin()).normalize();
        let eye = c + dir * r * dist;
        let target = match i % 5 {
            0 => c + dir * r * 10.0, // looking away
            1 => c + Vec3::new(0.3, -0.2, 0.1) * r,
            _ => c,
        };
        let mut cam = Camera::looking_at(eye, target);
        if i % 3 == 0 {
            cam.vfov_deg = 25.0;
            cam.aspect = 1.7;
            cam.viewport_height = 600.0;
        }
        let tol = [1.0, 0.5, 4.0, 20.0][i % 4];
        out.push((cam, tol));
    }
    out
}

/// `state` (kept across the path) against a fresh cut and the scan.
fn assert_same_cuts(name: &str, m: &McoModel, state: &mut ViewCut) {
    let mut fresh = Vec::new();
    let mut reference = Vec::new();
    let mut sizes = Vec::new();
    // Built and loaded models get the compact layout; the search on the
    // node arrays (any other model's) must give the same cuts.
    assert!(has_layout(m), "{name}: no compact layout");
    let mut nodes_state = ViewCut::new();
    let mut by_nodes = Vec::new();
    for (step, (cam, tol)) in camera_path(m).into_iter().enumerate() {
        let expanded = m.extract_view(&cam, tol, &mut fresh);
        let kept = state.update(m, &cam, tol).to_vec();
        let e = nodes_state.update_by_nodes(m, &cam, tol, &mut by_nodes);
        assert_eq!(by_nodes, kept, "{name}, step {step}: node arrays vs layout");
        assert_eq!(e, expanded, "{name}, step {step}");
        assert_eq!(kept, fresh, "{name}, step {step}: kept state vs fresh cut");
        assert_eq!(state.expanded_nodes(), expanded, "{name}, step {step}");
        assert_eq!(state.triangles() * 3, kept.len());
        let flags = select(m, &cam, tol);
        assert_eq!(
            flags.iter().filter(|&&f| f).count(),
            expanded,
            "{name}, step {step}: expanded nodes"
        );
        m.extract_expanded(&flags, &mut reference);
        assert_eq!(kept, reference, "{name}, step {step}: vs the scan");
        sizes.push(kept.len() / 3);
    }
    // The path is not trivial: it covers coarse and fine cuts.
    let (lo, hi) = (sizes.iter().min().unwrap(), sizes.iter().max().unwrap());
    assert!(hi > &(4 * lo), "{name}: cut sizes {sizes:?}");
}

#[test]
fn a_kept_view_cut_equals_a_fresh_cut_and_the_scan_of_every_node() {
    let mut state = ViewCut::new();
    let sphere = model(&shapes::icosphere(4), 40);
    assert_same_cuts("sphere", &sphere, &mut state);
    let blob = model(&shapes::blob(20_000), 48);
    assert_same_cuts("blob", &blob, &mut state);
    // The same state back on the first model, then on a loaded model (its
    // nodes renumbered in LOD order).
    assert_same_cuts("sphere again", &sphere, &mut state);
    let loaded = McoModel::from_bytes(&blob.to_bytes()).unwrap();
    assert_same_cuts("loaded blob", &loaded, &mut state);
    // A partial model (a prefix of the file).
    let bytes = blob.to_bytes();
    let table = McoModel::chunk_table(&bytes).unwrap();
    let cut = table[table.len() / 2];
    let part = McoModel::from_prefix(&bytes[..(cut.offset + cut.bytes) as usize]).unwrap();
    let mut fresh = Vec::new();
    for (cam, tol) in camera_path(&part.model) {
        part.model.extract_view(&cam, tol, &mut fresh);
        assert_eq!(state.update(&part.model, &cam, tol), &fresh[..]);
    }
}

#[test]
fn view_cuts_along_a_camera_path_are_crack_free() {
    let m = model(&shapes::icosphere(4), 32);
    let mut state = ViewCut::new();
    let tol = 1e-5 * 2.0 * 3f32.sqrt();
    let mut checked = 0;
    for (cam, px) in camera_path(&m) {
        let idx = state.update(&m, &cam, px);
        let mesh = m.mesh_from_indices(idx);
        let (_, gaps) = support::gap_edges(&mesh, tol);
        assert_eq!(gaps, 0, "camera {cam:?}, tolerance {px}");
        checked += 1;
    }
    assert_eq!(checked, 48);
}

#[test]
fn a_view_cut_of_an_empty_model_is_empty() {
    let mut state = ViewCut::new();
    let cam = Camera::looking_at(Vec3::Z, Vec3::ZERO);
    assert!(state.update(&McoModel::default(), &cam, 1.0).is_empty());
    assert_eq!(state.expanded_nodes(), 0);
}

/// A camera at NaN or infinity, or a NaN, infinite or negative tolerance,
/// gives the same cut as the scan.
#[test]
fn non_finite_cameras_give_the_scans_cut() {
    let m = model(&shapes::icosphere(3), 16);
    let mut state = ViewCut::new();
    let mut reference = Vec::new();
    for (pos, tol) in [
        (Vec3::splat(f32::NAN), 1.0),
        (Vec3::new(0.0, 0.0, f32::INFINITY), 1.0),
        (Vec3::new(0.0, 0.0, 3.0), f32::NAN),
        (Vec3::new(0.0, 0.0, 3.0), f32::INFINITY),
        (Vec3::new(0.0, 0.0, 3.0), -1.0),
    ] {
        let cam = Camera::looking_at(pos, Vec3::ZERO);
        let kept = state.update(&m, &cam, tol).to_vec();
        m.extract_expanded(&select(&m, &cam, tol), &mut reference);
        assert_eq!(kept, reference, "{pos} {tol}");
    }
}

/// A kept [`ViewCut`] along a path of small steps (what a viewer does
/// frame to frame, where it reuses the last cut's triangles and skips the
/// subtrees it found far away) gives the fresh cut and the scan's at every
/// step, with the view direction, the tolerance and the model changing on
/// the way.
#[test]
fn a_kept_view_cut_along_small_steps_equals_the_scan() {
    let blob = model(&shapes::blob(20_000), 48);
    let loaded = McoModel::from_bytes(&blob.to_bytes()).unwrap();
    let (lo, hi) = loaded.bounds();
    let (c, r) = ((lo + hi) * 0.5, (hi - lo).length());
    let mut state = ViewCut::new();
    let (mut fresh, mut reference) = (Vec::new(), Vec::new());
    let mut unchanged = 0;
    for step in 0..160 {
        let m = if (100..110).contains(&step) {
            &blob
        } else {
            &loaded
        };
        let a = step as f32 * 0.02;
        let dist = 0.4 + 0.5 * (0.5 + 0.5 * (step as f32 * 0.05).cos());
        let eye = c + Vec3::new(a.cos(), 0.3, a.sin()) * r * dist;
        let look = c + Vec3::new(0.2 * (a * 3.0).sin(), 0.0, 0.0) * r;
        let cam = Camera::looking_at(eye, look);
        let tol = if step < 80 { 1.0 } else { 2.0 };
        let before = state.indices().to_vec();
        let kept = state.update(m, &cam, tol).to_vec();
        m.extract_view(&cam, tol, &mut fresh);
        assert_eq!(kept, fresh, "step {step}: kept state vs fresh cut");
        m.extract_expanded(&select(m, &cam, tol), &mut reference);
        assert_eq!(kept, reference, "step {step}: vs the scan");
        if kept.len() == before.len() {
            unchanged += 1;
        }
    }
    // Steps this small often leave the cut as it was.
    assert!(unchanged > 0);
}

/// A camera that sees the whole model, orbiting in steps of a viewer
/// (0.75° to 6°, the distance changing too): no frustum plane is left to
/// test below the root, so a kept state updates its searched tree (see
/// `frontier`); the cut still equals the scan's at every step.
#[test]
fn a_kept_view_cut_orbiting_the_whole_model_equals_the_scan() {
    let (blob, c, r) = loaded_blob();
    let mut state = ViewCut::new();
    let mut reference = Vec::new();
    let mut a = 0.0f32;
    for step in 0..120 {
        a += (0.75 + 5.25 * ((step % 7) as f32 / 6.0)).to_radians();
        let dist = 1.1 + 0.3 * (step as f32 * 0.1).sin();
        let cam = Camera::looking_at(c + Vec3::new(a.cos(), 0.35, a.sin()) * r * dist, c);
        let kept = state.update(&blob, &cam, 8.0).to_vec();
        blob.extract_expanded(&select(&blob, &cam, 8.0), &mut reference);
        assert_eq!(kept, reference, "step {step}: kept state vs the scan");
    }
}

/// A subtree rejected with less to spare than the rounding margin
/// certifies nothing: a kept state cutting the same camera again (the
/// eye has not moved, so every certificate applies) gives the scan's cut.
/// The tolerances put one subtree's bound a hair short of its distance
/// each; one camera sees the whole model (the kept searched tree of
/// `frontier`), the other stands nearer, where the frustum cuts the
/// root's cube (the search with its certificates).
#[test]
fn a_subtree_rejected_by_a_hair_is_searched_again() {
    let (blob, c, r) = loaded_blob();
    for (dist, whole) in [(1.2, true), (0.75, false)] {
        let cam = Camera::looking_at(c + Vec3::new(0.8, 0.35, 0.5) * r * dist, c);
        let tols = hairline_tolerances(&blob, &cam, 40);
        assert!(tols.len() >= 20, "{} tolerances", tols.len());
        let mut reference = Vec::new();
        for tol in tols {
            let mut state = ViewCut::new();
            blob.extract_expanded(&select(&blob, &cam, tol), &mut reference);
            for pass in 0..2 {
                let kept = state.update(&blob, &cam, tol).to_vec();
                assert_eq!(
                    kept, reference,
                    "distance {dist}, tolerance {tol}, pass {pass}"
                );
                assert_eq!(state.used_frontier(), whole, "distance {dist}");
            }
        }
    }
}

/// A kept [`ViewCut`] whose camera sees the whole model keeps its
/// searched tree from cut to cut and tests again only what the eye's path
/// may have changed (see `frontier`): along a long path — orbits in steps
/// of 0.3° to 8°, steps of one unit in the last place, the same camera
/// again, jumps far away and back, an orbit farther than the expiry
/// queue's ring reaches, zooms
/// into the model (where frustum planes are tested, so the tree is
/// searched anew after) and a tolerance change, long enough that the
/// path is re-based several times — every cut equals a fresh one, and
/// every tenth the scan's.
#[test]
fn a_kept_frontier_along_a_long_path_equals_fresh_cuts() {
    let (blob, c, r) = loaded_blob();
    let mut state = ViewCut::new();
    let (mut fresh, mut reference) = (Vec::new(), Vec::new());
    let mut a = 0.0f32;
    let mut frontier = 0;
    let mut last = Camera::looking_at(c + Vec3::X * r, c);
    for step in 0..420 {
        let tol = if step < 300 { 6.0 } else { 9.0 };
        let cam = match step % 60 {
            // Far away (a re-based path), then back.
            20..=22 => Camera::looking_at(c + Vec3::new(0.3, 0.5, 1.0) * r * 60.0, c),
            // Away by more than the ring spans, and an orbit there
            // (expiries beyond the ring).
            25..=32 => {
                a += 8f32.to_radians();
                Camera::looking_at(c + Vec3::new(a.cos(), 0.35, a.sin()) * r * 12.0, c)
            }
            // Into the model: planes to test.
            40..=42 => Camera::looking_at(c + Vec3::new(a.cos(), 0.1, a.sin()) * r * 0.3, c),
            // One unit in the last place, and the same camera again.
            50 | 51 => {
                let mut cam = last;
                if step % 60 == 50 {
                    cam.position.x = f32::from_bits(cam.position.x.to_bits() + 1);
                }
                cam
            }
            k => {
                a += (0.3 + 7.7 * ((k % 9) as f32 / 8.0)).to_radians();
                let dist = 1.2 + 0.4 * (step as f32 * 0.07).sin();
                Camera::looking_at(c + Vec3::new(a.cos(), 0.35, a.sin()) * r * dist, c)
            }
        };
        last = cam;
        let kept = state.update(&blob, &cam, tol).to_vec();
        frontier += state.used_frontier() as usize;
        blob.extract_view(&cam, tol, &mut fresh);
        assert_eq!(kept, fresh, "step {step}: kept state vs fresh cut");
        if step % 10 == 0 {
            blob.extract_expanded(&select(&blob, &cam, tol), &mut reference);
            assert_eq!(kept, reference, "step {step}: vs the scan");
        }
    }
    assert!(frontier > 300, "{frontier} cuts through the kept frontier");
}
