//! The multi-pass LOD chain (HQMS §4.1 step 3 and §4.4): the output of one
//! level is the input of the next, so level `i + 1` is simplified from level
//! `i`, and the per-vertex error estimate keeps accumulating across levels
//! (it is never reset between levels).
//!
//! The paper emits one level per pass; a game wants levels at chosen
//! budgets, so a level here is emitted when its target is reached, after as
//! many passes as that takes (each pass still ends in `OutputLOD`'s
//! compaction).

use lodkit_mesh::TriMesh;

use crate::output::export;
use crate::simplifier::Simplifier;
use crate::{Error, Options, Simplified, Target};

impl Simplifier {
    /// An LOD chain: one level per target, in order, each simplified from
    /// the previous one, so the per-vertex error estimate accumulates over
    /// the chain. `opts.target` is ignored; `max_error` applies to every
    /// level. Each level meets the single-call contract of the crate docs;
    /// the whole chain costs about as much as its first level (each level
    /// starts from a smaller mesh). Errors: as [`simplify`](crate::simplify),
    /// before any level is made.
    ///
    /// **Every level has fewer triangles than the one before**, so no
    /// level is ever returned twice: the chain ends at the first target
    /// that cannot remove a triangle from the previous level (the mesh has
    /// no valid collapse left, every collapse would exceed `max_error`, the
    /// pass limit, or a target no smaller than the previous level). Then
    /// fewer levels than targets come back, and the last one's
    /// [`LevelReport::chain_end`](crate::LevelReport::chain_end) says why.
    /// The first level is always returned (with no targets, none is).
    pub fn lod_chain(
        &mut self,
        mesh: &TriMesh,
        opts: &Options,
        targets: &[Target],
    ) -> Result<Vec<Simplified>, Error> {
        Ok(self
            .chain_with(mesh, None, opts, targets)?
            .into_iter()
            .map(|(s, _)| s)
            .collect())
    }

    /// [`Simplifier::lod_chain`] with one group id per vertex, as
    /// [`Simplifier::simplify_grouped`]: each level comes with the group of
    /// each of its vertices.
    pub fn lod_chain_grouped(
        &mut self,
        mesh: &TriMesh,
        groups: &[u32],
        opts: &Options,
        targets: &[Target],
    ) -> Result<Vec<(Simplified, Vec<u32>)>, Error> {
        self.chain_with(mesh, Some(groups), opts, targets)
    }

    fn chain_with(
        &mut self,
        mesh: &TriMesh,
        groups: Option<&[u32]>,
        opts: &Options,
        targets: &[Target],
    ) -> Result<Vec<(Simplified, Vec<u32>)>, Error> {
        let mut t0 = std::time::Instant::now();
        self.start(mesh, opts, groups, None)?;
        let mut out: Vec<(Simplified, Vec<u32>)> = Vec::with_capacity(targets.len());
        for &t in targets {
            let goal = t.faces(self.input_faces);
            let stop = self.run_to(goal, opts);
            if let Some((last, _)) = out.last_mut()
                && self.m.faces.len() >= last.mesh.faces.len()
            {
                // Stalled: this level would repeat the previous one.
                last.report.chain_end = Some(stop);
                break;
            }
            let level = export(&self.m);
            let estimated_error = self.m.max_error();
            let level_done = std::time::Instant::now();
            let level_groups = if groups.is_some() {
                self.m.group.clone()
            } else {
                Vec::new()
            };
            out.push((
                Simplified {
                    report: self.report(
                        goal,
                        &level,
                        estimated_error,
                        stop,
                        t0.elapsed().as_secs_f64(),
                    ),
                    mesh: level,
                },
                level_groups,
            ));
            t0 = level_done;
        }
        Ok(out)
    }
}

/// `levels` ratio targets halving the face count: 1/2, 1/4, … (the paper's
/// roughly-halving passes, eq. 6).
pub fn halving_targets(levels: usize) -> Vec<Target> {
    (1..=levels as i32)
        .map(|i| Target::Ratio(0.5f32.powi(i)))
        .collect()
}

/// An LOD chain with a fresh workspace; see [`Simplifier::lod_chain`].
///
/// ```
/// use lodkit_simplify::{halving_targets, lod_chain, Options};
/// let sphere = lodkit_mesh::shapes::icosphere(4); // 5,120 triangles
/// let levels = lod_chain(&sphere, &Options::DEFAULT, &halving_targets(3)).unwrap();
/// let faces: Vec<usize> = levels.iter().map(|l| l.mesh.faces.len()).collect();
/// assert!(faces[0] <= 2_560 && faces[1] <= 1_280 && faces[2] <= 640);
/// ```
pub fn lod_chain(
    mesh: &TriMesh,
    opts: &Options,
    targets: &[Target],
) -> Result<Vec<Simplified>, Error> {
    Simplifier::new().lod_chain(mesh, opts, targets)
}
