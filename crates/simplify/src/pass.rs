//! One simplification pass (HQMS §4.1 step 2 and §4.3): the single pipeline
//! cost computation → RS-heap insert / delete-root → full edge collapse.
//!
//! Vertices are scanned in index order. Each valid ring gets its
//! contraction record (`cost.rs`); the record replaces the heap's root, and
//! the root record is collapsed if it passes the dependency check
//! (Strategy I, `collapse.rs`). After the last ring, the finale stage
//! drains the heap. With a one-record heap (the default, see
//! `Options::DEFAULT_HEAP_SIZE`) there is nothing to reorder: each record
//! under the threshold is collapsed as soon as it is costed, reusing the
//! cost stage's read of its ring. The pass stops as soon as the face count reaches the
//! goal — inside the pass, so the goal is met exactly (within the one or
//! two faces the last collapse removes).
//!
//! Departure, and why: the paper contracts every ring it can in each pass,
//! so the choice of *which* rings collapse is driven only by the heap's
//! local order and the first pass of a 1% target decimates the whole mesh
//! uniformly. We bound each pass by an error threshold `τ`, like
//! meshoptimizer's per-pass error limit: before the pass the costs of about
//! [`SAMPLES`] rings spread evenly over the mesh (every ring of a small
//! mesh, at most one in [`MIN_SAMPLE_STRIDE`]) are computed, `τ` is [`PASS_SLACK`] × the
//! sample quantile at the fraction of rings the goal still needs, and
//! records above `τ` wait for a later pass (their ring is rebuilt anyway).
//! Cheap collapses everywhere come first; the pass count grows by a few.
//! The sample costs at most `4 ×` [`SAMPLES`] bytes and as many cost
//! computations per pass, whatever the mesh size.

use crate::collapse::{Reject, collapse};
use crate::cost::{Record, Scratch, best_contraction};
use crate::options::Options;
use crate::ring_table::{Flag, RingTable};
use crate::rs_heap::RsHeap;
use crate::work_mesh::WorkMesh;

/// About this many rings are costed to set the pass threshold: the
/// quantile of a 512-sample estimate is within about 2% (of the ranks) of
/// the mesh's, well inside [`PASS_SLACK`], and a fixed count keeps the
/// sample's time and memory out of the per-vertex budget (larger samples
/// cost more and do not lower the errors).
pub const SAMPLES: usize = 512;
/// Small meshes still sample at most one ring in this many: the late
/// passes of a deep target are small, and a denser sample would be a large
/// share of all their costings.
pub const MIN_SAMPLE_STRIDE: usize = 16;
/// The threshold is this many times the goal quantile of the sample: the
/// sample and the dependency rule are both approximate, and a pass that
/// falls short only costs another pass. The larger it is, the fewer rings
/// wait for the next pass (and are costed again there), and the less the
/// threshold orders the collapses; 2 balances the two (`lodkit bench
/// simplify` checks the errors against meshoptimizer's).
pub const PASS_SLACK: f32 = 2.0;

/// At most this fraction of the rings is admitted in one pass, however far
/// the goal is. Without it the first passes of a deep target admit every
/// ring and the choice between neighbours is left to the heap's local
/// order, which raises the max error; the cap costs one or two more passes.
pub const PASS_MAX_FRACTION: f64 = 0.6;

/// What a pass did.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct PassStats {
    pub collapses: usize,
    pub faces_removed: usize,
    pub rejected_dependency: usize,
    pub rejected_topology: usize,
    pub rejected_flip: usize,
    pub rejected_seam: usize,
    pub rejected_max_error: usize,
    /// Records above the pass threshold, left for a later pass.
    pub deferred: usize,
}

impl PassStats {
    fn count(&mut self, r: Reject) {
        match r {
            Reject::Dependency => self.rejected_dependency += 1,
            Reject::Topology => self.rejected_topology += 1,
            Reject::Flip => self.rejected_flip += 1,
            Reject::Seam => self.rejected_seam += 1,
            Reject::MaxError => self.rejected_max_error += 1,
        }
    }
}

/// The pass threshold `τ` for reaching `goal` faces (+∞ when every ring is
/// needed). `success` is the fraction of admitted records that collapsed in
/// the previous pass.
pub fn pass_threshold(
    m: &WorkMesh,
    rings: &RingTable,
    opts: &Options,
    goal: usize,
    success: f64,
    sc: &mut Scratch,
) -> f32 {
    let n = m.pos.len();
    let active = (0..n).filter(|&v| rings.off[v + 1] > rings.off[v]).count();
    let needed = m.live_faces.saturating_sub(goal).div_ceil(2);
    // Not every admitted record collapses (dependency, flips): aim higher
    // by the success rate of the previous pass.
    let q = needed as f64 / active.max(1) as f64 / success.clamp(0.1, 1.0);
    let q = q.min(PASS_MAX_FRACTION);
    if active == 0 || q >= 1.0 {
        return f32::INFINITY;
    }
    let mut samples = std::mem::take(&mut sc.samples);
    samples.clear();
    let stride = (n / SAMPLES).max(MIN_SAMPLE_STRIDE);
    for v in (0..n).step_by(stride) {
        if let Some(r) = best_contraction(m, rings, opts, v as u32, sc) {
            samples.push(r.cost);
        }
    }
    let tau = if samples.is_empty() {
        f32::INFINITY
    } else {
        let i = ((samples.len() as f64 * q) as usize).min(samples.len() - 1);
        let (_, x, _) = samples.select_nth_unstable_by(i, f32::total_cmp);
        // Zero-cost records (flat areas) would give τ = 0 and stall: let
        // every zero through, and at least a hair above.
        (*x * PASS_SLACK).max(f32::MIN_POSITIVE)
    };
    sc.samples = samples;
    tau
}

/// Runs one pass towards `goal` faces with threshold `tau`, on a ring
/// table already built from the current faces.
pub fn run_pass(
    m: &mut WorkMesh,
    rings: &RingTable,
    heap: &mut RsHeap<Record>,
    opts: &Options,
    goal: usize,
    tau: f32,
    sc: &mut Scratch,
) -> PassStats {
    let mut st = PassStats::default();
    let n = m.pos.len();
    // A one-record heap cannot reorder anything (it only delays each
    // record by one ring), so its records are collapsed at once: the
    // record is never stale, nothing is refused by the dependency check,
    // and nothing is costed twice.
    let immediate = opts.heap_size <= 1;
    if !immediate {
        heap.reset(opts.heap_size);
    }
    // Operation stage (the initial stage is the heap filling with records
    // while its null records come out).
    for s in 0..n as u32 {
        if m.live_faces <= goal {
            return st;
        }
        if m.flags[s as usize] != Flag::Valid {
            continue;
        }
        let Some(rec) = best_contraction(m, rings, opts, s, sc) else {
            m.flags[s as usize] = Flag::Null;
            continue;
        };
        if !(rec.cost <= tau) {
            st.deferred += 1;
            continue;
        }
        if immediate {
            // `best_contraction` left the ring of `s` read in its frame.
            match collapse(m, rings, opts, rec.s, rec.t, sc, true) {
                Ok(removed) => {
                    st.collapses += 1;
                    st.faces_removed += removed;
                }
                Err(r) => st.count(r),
            }
        } else if let Some(root) = heap.replace(rec) {
            apply(m, rings, heap, opts, tau, root, sc, &mut st);
        }
    }
    if immediate {
        return st;
    }
    // Finale stage.
    while m.live_faces > goal {
        let Some(root) = heap.drain() else { break };
        apply(m, rings, heap, opts, tau, root, sc, &mut st);
    }
    st
}

/// Collapses `root` if it passes the checks. A record refused by the
/// dependency check whose own ring is still valid (its target became dirty
/// while the record waited in the heap) is costed again at once, among the
/// targets still allowed, and goes back into the heap if it is under `τ`;
/// the root that comes out instead is applied in turn. Without this, those
/// rings — a third of the admitted records — waited for the next pass,
/// and each pass removed a third of the vertices instead of the paper's
/// half (eq. 6).
#[allow(clippy::too_many_arguments)]
#[inline]
fn apply(
    m: &mut WorkMesh,
    rings: &RingTable,
    heap: &mut RsHeap<Record>,
    opts: &Options,
    tau: f32,
    mut root: Record,
    sc: &mut Scratch,
    st: &mut PassStats,
) {
    loop {
        match collapse(m, rings, opts, root.s, root.t, sc, false) {
            Ok(removed) => {
                st.collapses += 1;
                st.faces_removed += removed;
                return;
            }
            Err(Reject::Dependency) if m.flags[root.s as usize] == Flag::Valid => {
                st.rejected_dependency += 1;
                let Some(rec) = best_contraction(m, rings, opts, root.s, sc) else {
                    m.flags[root.s as usize] = Flag::Null;
                    return;
                };
                if !(rec.cost <= tau) {
                    st.deferred += 1;
                    return;
                }
                match heap.replace(rec) {
                    Some(next) => root = next,
                    None => return,
                }
            }
            Err(r) => {
                st.count(r);
                return;
            }
        }
    }
}
