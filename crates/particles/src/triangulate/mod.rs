//! Direct triangulation of an octree surface — §6 of Yemez & Schmitt,
//! "Multilevel representation and transmission of real objects with
//! progressive octree particles" (IEEE TVCG 2003).
//!
//! The stages, in the order [`triangulate`] runs them (one file each):
//! 1. [`window`] — the level's cubes as bricks of 8×8×8 bits, and the
//!    window of a brick and two layers around it (§6.1.1's 3×3×3 parent
//!    window, at brick scale);
//! 2. [`scan`] — every neighbourhood of 2×2×2 cubes with three ON cubes or
//!    more, brick by brick, classed by the 256-case table
//!    ([`crate::triangulation_table`]); each brick triangulates the
//!    neighbourhoods whose origin (lowest cube) lies in it, plus those whose
//!    origin lies in an empty brick below when it is the first occupied
//!    brick, in child-code order, the neighbourhood reaches — the paper's
//!    back-neighbour rule, made unique;
//! 3. [`quad_choice`] — §6.1.3's construction rules for the planar
//!    configurations (triangles, quad diagonals, who owns a face patch);
//! 4. [`shared_edges`] and [`hamiltonian_split`] — §6.2's disambiguation
//!    of the solid configurations by the edges they share with their
//!    neighbours;
//! 5. [`settle`] — (departure) the ambiguous solids, built last against
//!    everything else the level built;
//! 6. [`dedupe`] — identical triangles two solids both built on a shared
//!    face are kept once;
//! 7. [`decimate`] — §6.3's optional merge of cubes joined by short edges;
//! 8. orientation (not in the paper, which renders without culling):
//!    [`crate::orientation`], when [`TriangulateOptions::orient`] asks.
//!
//! Every stage is deterministic: the same surface and options give the same
//! triangles in the same order.
use std::borrow::Cow;
use std::time::Instant;

use crate::level_surface::LevelSurface;
use crate::triangulation_table::CLASS_COUNT;
use lodkit_mesh::TriMesh;

mod decimate;
mod dedupe;
mod hamiltonian_split;
mod quad_choice;
mod scan;
mod settle;
mod shared_edges;
#[cfg(test)]
mod tests;
mod window;

/// Options of [`triangulate`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TriangulateOptions {
    /// §6.3: skip triangles with an edge shorter than this fraction of the
    /// level's cube size and merge the two cubes. `None`: no decimation.
    pub decimate: Option<f32>,
    /// Orient the triangles (see the module docs).
    pub orient: bool,
}

impl TriangulateOptions {
    /// No decimation, oriented.
    pub const DEFAULT: TriangulateOptions = TriangulateOptions {
        decimate: None,
        orient: true,
    };
}

impl Default for TriangulateOptions {
    fn default() -> Self {
        TriangulateOptions::DEFAULT
    }
}

/// Table 1's triangulation columns for one level.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct TriangulationStats {
    /// Triangles built.
    pub triangles: usize,
    /// Neighbourhoods of each class `C_1..C_17` (index 0 unused).
    pub configurations: Vec<u64>,
    /// Ambiguous neighbourhoods resolved by a unique Hamiltonian cycle.
    pub disambiguated: u64,
    /// Ambiguous neighbourhoods triangulated whole (the non-manifold local
    /// triangulations of Table 1).
    pub fallbacks: u64,
    /// Wall time of the triangulation (seconds; the only field that varies between runs).
    pub seconds: f64,
}

impl TriangulationStats {
    /// Percentages of `C_1–3`, `C_4–5`, `C_6`, `C_>6` (Table 1).
    pub fn distribution(&self) -> [f64; 4] {
        let total: u64 = self.configurations.iter().sum();
        let t = total.max(1) as f64;
        let sum =
            |a: usize, b: usize| self.configurations[a..=b].iter().sum::<u64>() as f64 * 100.0 / t;
        [sum(1, 3), sum(4, 5), sum(6, 6), sum(7, CLASS_COUNT)]
    }
}

/// A triangulated level.
#[derive(Debug, Clone)]
pub struct Triangulation {
    /// The particles as vertices, with the triangles.
    pub mesh: TriMesh,
    /// What the triangulation did.
    pub stats: TriangulationStats,
}

/// No vertex, no brick.
const NONE: u32 = u32::MAX;

/// Triangulates one decoded level (§6): one vertex per particle, the
/// triangles of every 2×2×2 neighbourhood of cells from the 256-case
/// table.
///
/// - **Input**: a [`LevelSurface`] (from [`Decoded::surface`](crate::Decoded::surface),
///   or made by a caller: cells need not be sorted, duplicates are
///   ignored); `opts`: §6.3 decimation (off by default) and orientation
///   (on by default).
/// - **Output**: a mesh whose vertices are the surface's particles, in
///   order (attributes carried over), about two triangles per particle
///   (at most 16 per neighbourhood); with `orient`, triangles wound
///   counter-clockwise seen from outside (by the particle normals when
///   present, else consistently across manifold edges and outwards by
///   signed volume per component).
/// - **Guarantees**: deterministic (the same triangles in the same order
///   for the same input); a closed thinned surface gives a hole-free mesh,
///   non-manifold only where an ambiguous neighbourhood is left whole
///   ([`TriangulationStats::fallbacks`]; under 1 % of the triangles with
///   outer thinning). Never panics.
/// - **Cost**: linear in the cells (a bit-parallel scan of 8×8×8 bricks);
///   no allocation per neighbourhood.
pub fn triangulate(s: &LevelSurface, opts: &TriangulateOptions) -> Triangulation {
    triangulate_impl(Cow::Borrowed(s), opts, None)
}

/// [`triangulate`] (same contract), the mesh taking over the surface's particles instead
/// of copying them (for a level built only to be triangulated, as
/// [`crate::Decoded::into_surface`] gives it).
pub fn triangulate_owned(s: LevelSurface, opts: &TriangulateOptions) -> Triangulation {
    triangulate_impl(Cow::Owned(s), opts, None)
}

/// [`triangulate`] plus, per output triangle, the class `C_i` of the
/// neighbourhood that built it, plus 128 when that neighbourhood was an
/// ambiguous one left whole (for diagnosing non-manifold triangles).
pub fn triangulate_traced(s: &LevelSurface, opts: &TriangulateOptions) -> (Triangulation, Vec<u8>) {
    let mut classes = Vec::new();
    let t = triangulate_impl(Cow::Borrowed(s), opts, Some(&mut classes));
    (t, classes)
}

/// Runs the stages of the module docs in order.
fn triangulate_impl(
    surface: Cow<'_, LevelSurface>,
    opts: &TriangulateOptions,
    mut trace: Option<&mut Vec<u8>>,
) -> Triangulation {
    // wasm32-unknown-unknown has no clock (`Instant::now` panics there):
    // the browser build reports zero seconds and times itself.
    let start = (!cfg!(target_family = "wasm")).then(Instant::now);
    let s: &LevelSurface = &surface;
    // The scan needs the cubes in strict Morton order (as decoded); a
    // caller-made surface that is not gets a sorted view.
    let sorted = s.cells.windows(2).all(|w| w[0] < w[1]);
    let (order, cells_sorted): (Option<Vec<u32>>, Vec<u64>) = if sorted {
        (None, Vec::new())
    } else {
        let mut o: Vec<u32> = (0..s.cells.len() as u32).collect();
        o.sort_by_key(|&i| s.cells[i as usize]);
        o.dedup_by_key(|i| s.cells[*i as usize]);
        let c = o.iter().map(|&i| s.cells[i as usize]).collect();
        (Some(o), c)
    };
    let cells: &[u64] = if sorted { &s.cells } else { &cells_sorted };
    // 1. Bricks.
    let bricks = window::Bricks::of(s.level, cells);
    // 2–4. The scan, with the construction rules and §6.2 per
    // neighbourhood.
    let mut built = scan::scan(
        s,
        cells,
        order.as_deref(),
        &bricks,
        opts,
        trace.as_deref_mut(),
    );
    // 5. The ambiguous solids, settled against everything else built.
    let ranges = if order.is_none() {
        settle::settle_ranges(&built.trials, cells, &bricks.index, &built.brick_faces)
    } else {
        vec![(0, built.faces.len() as u32)]
    };
    settle::settle(
        &built.faces,
        &ranges,
        &built.from_solids,
        &mut built.trials,
        s.cells.len(),
    );
    settle::build_trials(&mut built, trace.as_deref_mut());
    // 6. A triangle whose three cubes share a coordinate lies on the face
    // between two neighbourhoods; two solid ones may both have built it:
    // keep one.
    let settle::Scanned {
        mut faces,
        merges,
        from_solids,
        mut stats,
        ..
    } = built;
    let dropped = dedupe::dedupe_face_triangles(&mut faces, &from_solids);
    if let Some(tr) = trace {
        dedupe::remove_sorted(tr, &dropped);
    }
    let mut mesh = match surface {
        Cow::Borrowed(s) => s.vertices_only(),
        Cow::Owned(s) => s.into_vertices(),
    };
    // 7. Decimation.
    if !merges.is_empty() {
        decimate::decimate_merge(&mut mesh, &mut faces, &merges);
    }
    mesh.faces = faces;
    // 8. Orientation.
    if opts.orient {
        crate::orientation::orient(&mut mesh);
    }
    stats.triangles = mesh.faces.len();
    stats.seconds = start.map_or(0.0, |t| t.elapsed().as_secs_f64());
    Triangulation { mesh, stats }
}

/// Key of the undirected edge `a b`.
#[inline]
fn edge_key(a: u32, b: u32) -> u64 {
    (u64::from(a.min(b)) << 32) | u64::from(a.max(b))
}
