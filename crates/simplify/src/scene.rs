//! Simplifying a [`Scene`]: each mesh on its own, its materials kept.
//!
//! Each mesh is simplified in its own frame (instances share the result,
//! so a mesh placed twice is simplified once). Its faces' material ids
//! become vertex groups ([`Simplifier::simplify_grouped`]): a vertex
//! shared by faces of several materials is split into one copy per
//! material, so a material border is a seam like a UV seam — both sides
//! collapse together, no crack opens between the primitives written for
//! each material, and every output face keeps its material. A face budget
//! ([`Target::Faces`]) is shared among the meshes in proportion to their
//! face counts; a ratio applies to each mesh. Nodes, materials, textures,
//! images and samplers are carried over unchanged.

use lodkit_mesh::TriMesh;
use lodkit_mesh::scene::{Scene, SceneMesh};

use crate::{Error, LevelReport, Options, Simplifier, Target};

/// A mesh with every vertex in one material: vertices shared by faces of
/// several materials are copied (attributes too), one copy per material.
/// Returns the mesh and the material of each vertex.
pub fn split_by_material(sm: &SceneMesh) -> (TriMesh, Vec<u32>) {
    let m = &sm.mesh;
    let n = m.positions.len();
    const UNSET: u32 = u32::MAX - 1;
    // First material seen per vertex; copies for the others, looked up in
    // a small per-vertex list (borders are short).
    let mut first = vec![UNSET; n];
    let mut extra: rustc_hash::FxHashMap<(u32, u32), u32> = Default::default();
    let mut out = m.clone();
    let mut groups: Vec<u32> = vec![0; n];
    for (fi, &mat) in sm.face_materials.iter().enumerate() {
        for c in 0..3 {
            let v = m.faces[fi][c];
            let vi = v as usize;
            if first[vi] == UNSET {
                first[vi] = mat;
                groups[vi] = mat;
            } else if first[vi] != mat {
                let copy = *extra.entry((v, mat)).or_insert_with(|| {
                    let k = out.positions.len() as u32;
                    out.positions.push(m.positions[vi]);
                    if let (Some(d), Some(s)) = (out.normals.as_mut(), &m.normals) {
                        d.push(s[vi]);
                    }
                    if let (Some(d), Some(s)) = (out.colors.as_mut(), &m.colors) {
                        d.push(s[vi]);
                    }
                    if let (Some(d), Some(s)) = (out.uvs.as_mut(), &m.uvs) {
                        d.push(s[vi]);
                    }
                    groups.push(mat);
                    k
                });
                out.faces[fi][c] = copy;
            }
        }
    }
    (out, groups)
}

/// The face material of each face: the group of its first corner.
fn face_groups(mesh: &TriMesh, groups: &[u32]) -> Vec<u32> {
    mesh.faces.iter().map(|f| groups[f[0] as usize]).collect()
}

/// The target of mesh `i` of `scene` for a scene-wide target.
fn share(t: Target, faces: usize, total: usize) -> Target {
    match t {
        Target::Faces(n) if total > 0 => {
            Target::Faces(((n as u128 * faces as u128) / total as u128) as usize)
        }
        other => other,
    }
}

/// Simplifies every mesh of `scene` to `opts.target` (see the module
/// docs); returns the simplified scene and one report per mesh. Errors:
/// as [`crate::simplify`], for the first mesh that fails. Cost: the sum
/// of the meshes' simplifications.
pub fn simplify_scene(scene: &Scene, opts: &Options) -> Result<(Scene, Vec<LevelReport>), Error> {
    let total = scene.face_count();
    let mut s = Simplifier::new();
    let mut out = Scene {
        meshes: Vec::with_capacity(scene.meshes.len()),
        ..scene.clone_tables()
    };
    let mut reports = Vec::with_capacity(scene.meshes.len());
    for sm in &scene.meshes {
        let (mesh, groups) = split_by_material(sm);
        let o = Options {
            target: share(opts.target, sm.mesh.faces.len(), total),
            ..opts.clone()
        };
        let (r, g) = s.simplify_grouped(&mesh, &groups, &o)?;
        out.meshes.push(SceneMesh {
            name: sm.name.clone(),
            face_materials: face_groups(&r.mesh, &g),
            mesh: r.mesh,
        });
        reports.push(r.report);
    }
    Ok((out, reports))
}

/// An LOD chain of `scene`: one scene per target, each mesh's levels made
/// by [`Simplifier::lod_chain_grouped`] (see the module docs). Returns the
/// levels and, per level, one report per mesh.
///
/// As [`Simplifier::lod_chain`], every level has fewer triangles (summed
/// over the meshes) than the one before, so no level repeats: a mesh whose
/// own chain ends early keeps its last level in the later scene levels
/// (its report repeated, time zero), and the scene's chain ends at the
/// first target that removes no triangle from the whole scene; the last
/// level's reports then carry each stalled mesh's
/// [`LevelReport::chain_end`] ([`combined_report`] keeps the first).
pub fn scene_lod_chain(
    scene: &Scene,
    opts: &Options,
    targets: &[Target],
) -> Result<Vec<(Scene, Vec<LevelReport>)>, Error> {
    let total = scene.face_count();
    let mut s = Simplifier::new();
    let mut levels: Vec<(Scene, Vec<LevelReport>)> = targets
        .iter()
        .map(|_| (scene.clone_tables(), Vec::new()))
        .collect();
    // Per mesh: why its own chain ended, if it did.
    let mut ends: Vec<Option<crate::StopReason>> = Vec::with_capacity(scene.meshes.len());
    for sm in &scene.meshes {
        let (mesh, groups) = split_by_material(sm);
        let ts: Vec<Target> = targets
            .iter()
            .map(|&t| share(t, sm.mesh.faces.len(), total))
            .collect();
        let chain = s.lod_chain_grouped(&mesh, &groups, opts, &ts)?;
        ends.push(chain.last().and_then(|(r, _)| r.report.chain_end));
        let mut last: Option<SceneMesh> = None;
        let mut last_report: Option<LevelReport> = None;
        let mut chain = chain.into_iter();
        for (level, reports) in levels.iter_mut() {
            let (m, mut r) = match chain.next() {
                Some((r, g)) => {
                    let m = SceneMesh {
                        name: sm.name.clone(),
                        face_materials: face_groups(&r.mesh, &g),
                        mesh: r.mesh,
                    };
                    (m, r.report)
                }
                // This mesh's chain ended: it stays as it last was.
                None => match (&last, last_report) {
                    (Some(m), Some(mut r)) => {
                        r.seconds = 0.0;
                        (m.clone(), r)
                    }
                    _ => break,
                },
            };
            r.chain_end = None;
            level.meshes.push(m.clone());
            reports.push(r);
            last = Some(m);
            last_report = Some(r);
        }
    }
    // The scene's chain ends where its face count stops falling.
    let faces: Vec<usize> = levels.iter().map(|(l, _)| l.face_count()).collect();
    if let Some(k) = (1..faces.len()).find(|&k| faces[k] >= faces[k - 1]) {
        levels.truncate(k);
        if let Some((_, reports)) = levels.last_mut() {
            for (r, end) in reports.iter_mut().zip(&ends) {
                r.chain_end = Some(end.unwrap_or(crate::StopReason::Reached));
            }
        }
    }
    Ok(levels)
}

/// The scene-level sums of per-mesh reports: total triangles and
/// vertices, the largest estimated error, and the first mesh's stop
/// reason that is not [`crate::StopReason::Reached`] (or `Reached`); the
/// same for [`LevelReport::chain_end`].
pub fn combined_report(reports: &[LevelReport]) -> Option<LevelReport> {
    let mut it = reports.iter();
    let mut acc = *it.next()?;
    for r in it {
        acc.target_faces += r.target_faces;
        acc.triangles += r.triangles;
        acc.vertices += r.vertices;
        acc.estimated_error = acc.estimated_error.max(r.estimated_error);
        acc.passes = acc.passes.max(r.passes);
        acc.collapses += r.collapses;
        acc.seconds += r.seconds;
        if acc.stop == crate::StopReason::Reached {
            acc.stop = r.stop;
        }
        if matches!(acc.chain_end, None | Some(crate::StopReason::Reached)) && r.chain_end.is_some()
        {
            acc.chain_end = r.chain_end;
        }
    }
    Some(acc)
}
