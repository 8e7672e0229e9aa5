//! The reusable workspace and the pass loop (HQMS §4.1,
//! `HighQualityMeshSimplification`): ring construction → simplification
//! pass → output, repeated until the goal.
//!
//! A [`Simplifier`] keeps every buffer between calls — ring table, flags,
//! errors, heap, scratch — so simplifying many meshes allocates only when
//! a mesh is larger than any before it. The one exception is the final
//! mesh of [`Simplifier::simplify`], which takes the working vertex and face
//! arrays instead of copying them (that copy would be the peak).

use lodkit_mesh::TriMesh;

use crate::cost::{Record, Scratch};
use crate::options::Options;
use crate::output::{compact, take};
use crate::pass::{pass_threshold, run_pass};
use crate::prune::prune_small_components;
use crate::ring_table::RingTable;
use crate::rs_heap::RsHeap;
use crate::work_mesh::WorkMesh;
use crate::{Error, LevelReport, Simplified, StopReason};

/// Reusable simplification workspace: [`Simplifier::simplify`] and
/// [`Simplifier::lod_chain`] give the same results as the free functions
/// [`simplify`](crate::simplify) and [`lod_chain`](crate::lod_chain), and
/// keep every buffer for the next call. Not shared between threads at once
/// (`&mut self`); use one per thread.
#[derive(Debug)]
pub struct Simplifier {
    pub(crate) m: WorkMesh,
    pub(crate) rings: RingTable,
    pub(crate) heap: RsHeap<Record>,
    pub(crate) sc: Scratch,
    pub(crate) input_faces: usize,
    pub(crate) passes: u32,
    pub(crate) collapses: usize,
    pub(crate) peak_bytes: usize,
    /// Fraction of admitted records that collapsed in the last pass.
    pub(crate) success: f64,
    /// Whether the working mesh is compacted (no deleted face, no
    /// unreferenced vertex).
    pub(crate) compacted: bool,
}

impl Default for Simplifier {
    fn default() -> Self {
        Self::new()
    }
}

impl Simplifier {
    /// An empty workspace (allocates nothing until the first call).
    pub fn new() -> Self {
        Simplifier {
            m: WorkMesh::default(),
            rings: RingTable::default(),
            heap: RsHeap::new(Options::DEFAULT_HEAP_SIZE),
            sc: Scratch::default(),
            input_faces: 0,
            passes: 0,
            collapses: 0,
            peak_bytes: 0,
            success: 0.5,
            compacted: true,
        }
    }

    /// Simplifies `mesh` to `opts.target` (and `opts.max_error`); the
    /// contract is in the crate docs. The output takes the workspace's
    /// vertex and face arrays instead of copying them (that copy would be
    /// the peak), so the next call allocates those two again.
    pub fn simplify(&mut self, mesh: &TriMesh, opts: &Options) -> Result<Simplified, Error> {
        self.simplify_with(mesh, None, None, opts)
    }

    /// [`Simplifier::simplify`] with the vertices flagged in `locked` (one
    /// flag per input vertex) kept where they are: never contracted, and a
    /// collapse onto one leaves it in place. Like `opts.lock_border`, but
    /// for any chosen set: the vertices a part shares with its neighbours,
    /// say, while the rest of its border simplifies freely. The target
    /// may then be out of reach (the locked vertices stay). Errors: as
    /// [`Simplifier::simplify`], and [`Error::AttributeLength`] when
    /// `locked` is not one per vertex. Cost: as `simplify`, plus one byte
    /// per vertex.
    pub fn simplify_locked(
        &mut self,
        mesh: &TriMesh,
        locked: &[bool],
        opts: &Options,
    ) -> Result<Simplified, Error> {
        self.simplify_with(mesh, None, Some(locked), opts)
    }

    /// [`Simplifier::simplify`] with one group id per vertex (a material,
    /// a part): a border between groups is treated as an attribute seam,
    /// so both sides move together (no crack opens between groups) and
    /// every output vertex belongs to exactly one group. Returns the output
    /// and the group of each output vertex. For a face to keep its group,
    /// its three corners should be in it (split shared vertices per
    /// group first); a face's group is then that of any corner. Errors: as
    /// [`Simplifier::simplify`], and [`Error::AttributeLength`] when
    /// `groups` is not one per vertex. Cost: as `simplify`, plus the
    /// wedge table every grouped mesh needs.
    pub fn simplify_grouped(
        &mut self,
        mesh: &TriMesh,
        groups: &[u32],
        opts: &Options,
    ) -> Result<(Simplified, Vec<u32>), Error> {
        let out = self.simplify_with(mesh, Some(groups), None, opts)?;
        Ok((out, std::mem::take(&mut self.m.group)))
    }

    /// [`Simplifier::simplify_grouped`] with the vertices flagged in
    /// `locked` kept where they are, as [`Simplifier::simplify_locked`]:
    /// a part of a textured mesh simplified alone, its shared border
    /// fixed and its materials kept. Errors: as both. Cost: as both.
    pub fn simplify_grouped_locked(
        &mut self,
        mesh: &TriMesh,
        groups: &[u32],
        locked: &[bool],
        opts: &Options,
    ) -> Result<(Simplified, Vec<u32>), Error> {
        let out = self.simplify_with(mesh, Some(groups), Some(locked), opts)?;
        Ok((out, std::mem::take(&mut self.m.group)))
    }

    fn simplify_with(
        &mut self,
        mesh: &TriMesh,
        groups: Option<&[u32]>,
        locked: Option<&[bool]>,
        opts: &Options,
    ) -> Result<Simplified, Error> {
        let t0 = std::time::Instant::now();
        self.start(mesh, opts, groups, locked)?;
        let goal = opts.target.faces(self.input_faces);
        let stop = self.run_to(goal, opts);
        let estimated_error = self.m.max_error();
        let mesh = take(&mut self.m);
        Ok(Simplified {
            report: self.report(
                goal,
                &mesh,
                estimated_error,
                stop,
                t0.elapsed().as_secs_f64(),
            ),
            mesh,
        })
    }

    /// Largest number of bytes the workspace held at once during the last
    /// call (exact accounting of its arrays' capacities).
    pub fn peak_bytes(&self) -> usize {
        self.peak_bytes
    }

    pub(crate) fn start(
        &mut self,
        mesh: &TriMesh,
        opts: &Options,
        groups: Option<&[u32]>,
        locked: Option<&[bool]>,
    ) -> Result<(), Error> {
        self.peak_bytes = 0;
        self.passes = 0;
        self.collapses = 0;
        self.success = 0.5;
        self.input_faces = mesh.faces.len();
        // The ring table's offset array is free until the first pass: it
        // serves as the weld map here and as the vertex index table of
        // every compaction (it is rebuilt at the start of each pass).
        self.m
            .load(mesh, &opts.weights, groups, locked, &mut self.rings.off)?;
        self.m.border_weight = crate::quadric::BORDER_WEIGHT;
        self.note_memory();
        if let Some(p) = opts.prune {
            prune_small_components(&mut self.m, p);
        }
        // No compaction here: the first pass works on the loaded mesh as
        // it is (deleted faces and unreferenced vertices have empty rings)
        // and compacts after itself; `run_to` compacts when no pass ran.
        // On a clean input the compaction would renumber nothing.
        self.compacted = false;
        Ok(())
    }

    fn note_memory(&mut self) {
        let b = self.m.heap_bytes()
            + self.rings.heap_bytes()
            + self.sc.samples.capacity() * 4
            + self.heap.capacity() * std::mem::size_of::<Record>();
        self.peak_bytes = self.peak_bytes.max(b);
    }

    /// Passes until `goal` faces (or a stop condition); the working mesh
    /// is compacted afterwards.
    pub(crate) fn run_to(&mut self, goal: usize, opts: &Options) -> StopReason {
        let stop = self.run_passes(goal, opts);
        if !self.compacted {
            compact(&mut self.m, &mut self.rings.off);
            self.compacted = true;
        }
        stop
    }

    fn run_passes(&mut self, goal: usize, opts: &Options) -> StopReason {
        let mut unbounded = false;
        let mut passes_here = 0;
        loop {
            if self.m.live_faces <= goal {
                return StopReason::Reached;
            }
            if passes_here >= opts.max_passes {
                return StopReason::PassLimit;
            }
            let n = self.m.pos.len();
            self.rings.rebuild(n, &self.m.faces);
            let tau = if unbounded {
                f32::INFINITY
            } else {
                pass_threshold(&self.m, &self.rings, opts, goal, self.success, &mut self.sc)
            };
            self.note_memory();
            let st = run_pass(
                &mut self.m,
                &self.rings,
                &mut self.heap,
                opts,
                goal,
                tau,
                &mut self.sc,
            );
            compact(&mut self.m, &mut self.rings.off);
            self.compacted = true;
            self.passes += 1;
            passes_here += 1;
            self.collapses += st.collapses;
            let admitted = st.collapses
                + st.rejected_dependency
                + st.rejected_topology
                + st.rejected_flip
                + st.rejected_seam
                + st.rejected_max_error;
            if admitted > 0 {
                self.success = (st.collapses as f64 / admitted as f64).clamp(0.1, 1.0);
            }
            if st.faces_removed == 0 {
                if tau.is_finite() {
                    unbounded = true;
                    continue;
                }
                return if st.rejected_max_error > 0 {
                    StopReason::MaxError
                } else {
                    StopReason::Blocked {
                        topology: st.rejected_topology,
                        flip: st.rejected_flip,
                        seam: st.rejected_seam,
                    }
                };
            }
            unbounded = false;
        }
    }

    pub(crate) fn report(
        &self,
        goal: usize,
        mesh: &TriMesh,
        estimated_error: f32,
        stop: StopReason,
        seconds: f64,
    ) -> LevelReport {
        LevelReport {
            target_faces: goal,
            triangles: mesh.faces.len(),
            vertices: mesh.positions.len(),
            estimated_error,
            passes: self.passes,
            collapses: self.collapses,
            stop,
            chain_end: None,
            seconds,
        }
    }
}
