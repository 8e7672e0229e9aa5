//! The point tileset of a cloud too big for memory, built in passes over
//! the file: the same tree, the same tiles and the same bytes as
//! [`tileset_from_points`](crate::tileset_from_points) then
//! [`write_point_tileset`](crate::write_point_tileset), in about the
//! memory budget given, whatever the cloud's size.
//!
//! # Why passes, then subtrees in core
//! The in-core rule is top-down: a node keeps, per cell of its
//! [`PointTilesOptions::CELLS`]³ grid, the point nearest the cell's
//! centre (ties: the lower input index) and passes the rest to its
//! children. A node's choice depends only on the points that reach it,
//! and a node's reaching points in input order give exactly its in-core
//! subtree (`point_tiles::subdivide`: ties by input order, which a subset
//! keeps). So:
//!
//! 1. **Bounds** (one pass): the box, hence the root cube and every cell.
//! 2. **Streamed nodes** (one pass per depth, more when the depth's
//!    winner maps exceed the budget): a node whose reaching points do not
//!    fit the budget ([`IN_CORE_BYTES_PER_POINT`] each) is decided in a
//!    pass: each point walks down from the root through the nodes
//!    already decided (kept by one: it stops), and at the depth being
//!    decided competes for its cell in a map of winners (one entry per
//!    occupied cell: bounded by `CELLS³` per node, not by the points)
//!    and is counted in its child octant. The counts less each octant's
//!    winners are the children's reaching points; a child that fits the
//!    budget (or holds at most `leaf_points`, or sits at [`MAX_DEPTH`])
//!    becomes the root of a subtree built in core. When an average child
//!    will not fit either, the same pass decides the children too: each
//!    point also claims its cell of its child, whose two best claims are
//!    kept (a child's cell lies in one cell of the parent, which keeps at
//!    most one point, so the child's winner is the better of the two the
//!    parent did not keep): a pass per two streamed depths. Where those
//!    maps pass their own quarter of the budget, or a cell's two claims
//!    were both kept above, the children get a pass of their own.
//! 3. **Spill** (one pass): each point walks down again and is appended,
//!    in input order, to the file of the streamed node that keeps it or
//!    of the subtree root it reaches.
//! 4. **Subtrees** (`subtree.rs`; as many at once as the threads and
//!    half the budget allow): read back and tiled in core by the in-core
//!    code, each tile staged as raw points; a streamed node's file is its
//!    tile already.
//! 5. **Write**: the nodes in the in-core breadth-first order, boxes and
//!    errors through the in-core code, then every staged tile encoded on
//!    its depth's grid into the output folder, atomically, by up to
//!    eight threads at once (`tileset_folder.rs`, as every tileset).
//!
//! Every pass runs on every thread (`parallel_pass.rs`): the file is decoded
//! in chunks on a thread of its own while the pool walks the chunks read
//! before, and each chunk's result is merged in input order. The winner
//! of a cell is its least `(distance, index)`, so winners offered from
//! any thread in any order (`winners.rs`: sharded maps) are those of one
//! pass in input order, and the bytes do not depend on the thread count.
//!
//! Rejected: spilling by a fixed depth's cells first (a dense part of a
//! scan would need a deeper depth than the rest, and a fixed depth needs
//! the counts first: one pass more), and deciding every node in passes
//! (a pass per depth of the whole tree instead of the few depths that do
//! not fit).
//!
//! # Inputs
//! A binary PLY whose only element is `vertex` (positions as float or
//! double; normals and colours kept, converted as the in-core reader
//! converts them), read by [`PlyStream`] and checked as the in-core
//! reader checks it (counts against the file size, finite coordinates
//! within range, no byte after the last vertex). LAS/LAZ through
//! [`lodkit_mesh::io::LasStream`]: the in-core reader's checks, origin
//! and colour rule (it reads the file once more to find them), turned
//! to y-up as the job turns an in-core LAS cloud, the origin the root
//! `transform`.
//!
//! # Guarantees
//! The same bytes as the in-core path for the same input and options
//! (`tests/point_tiles_out_of_core.rs`); so every input point is stored
//! exactly once and each node's `geometricError` bounds the distance from
//! any point below it to one it keeps, as in core. The output folder is
//! written whole or not at all, never over a user's files. Everything
//! staged lives in the staging folder the caller names, locked for the
//! run and removed after success and after a failure; a run that was
//! killed leaves it, and the next run with the same folder starts it
//! over (nothing is resumed: the passes are cheap next to a restart's
//! bookkeeping).
//!
//! # Cost
//! Memory: the subtrees tiled at once (half the budget at
//! [`IN_CORE_BYTES_PER_POINT`], or one subtree of `leaf_points` points),
//! the winner maps of one pass (a quarter of the budget, at least one
//! node's: up to `CELLS³` cells, 80 MB, for a node of that many points)
//! and its children's claims (another quarter), 8 B per point a
//! streamed node keeps (held until the spill), the spill buffers (an
//! eighth of the budget), the chunks in flight (a sixteenth), the tiles
//! being written (a quarter, at most eight); one malloc arena, so what
//! one thread frees another reuses. Disk: the points twice (spills, then staged tiles: 12 B a
//! point, plus 12 with normals and 4 with colours). Time: three passes
//! over the file plus one per streamed depth, or per two where the
//! children are decided with their parents (more where a depth's maps
//! exceed their quarter), one in-core tiling of every subtree, one
//! encoding of every tile, all on every thread: 5·10⁷ coloured points in
//! 19–26 s at `--memory 512M` on two shared cores (docs/benchmarks.md).

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use lodkit_mesh::Aabb;
use rayon::prelude::*;

mod cloud_stream;
mod parallel_pass;
mod subtree;
mod winners;

use self::cloud_stream::{Layout, Source, Spill, io_err};
use self::parallel_pass::Passes;
use self::subtree::{TiledNode, TiledSubtree, tile_subtree};
use self::winners::{Runners, Winner, Winners};
use crate::octree_partition::{CellKey, Grid, MAX_DEPTH, Node, Octree};
use crate::point_tiles::{
    PointTilesOptions, PointTilesReport, Subtree, cell_and_distance, cell_diagonal, node_info,
    octant, subdivide,
};
use crate::tileset_json::Refine;
use crate::{Error, OutOfCoreEvent, Result, check_option};

/// Bytes per point the in-core path
/// ([`tileset_from_points`](crate::tileset_from_points) then
/// [`write_point_tileset`](crate::write_point_tileset), from reading
/// the file to the last tile) peaks at, about: measured 33 (peak RSS over
/// points) on a 10⁷-point binary PLY with colours and the default leaves
/// (the cloud, 16 B a point, the index lists of a node and its
/// children, the tiles' copy of the cloud); normals add 24. Front-ends go out of core when a
/// cloud's points times this exceed the memory budget; out of core, a
/// node whose reaching points times this fit half the budget is tiled
/// in core.
pub const IN_CORE_BYTES_PER_POINT: u64 = 48;

/// Bytes of a winner map per occupied cell (the entry and the table's
/// slack): what groups a depth's streamed nodes into passes.
const WINNER_BYTES: u64 = 40;

/// Bytes per point of a tile being written: its raw record, its cloud
/// and its GLB, about (what bounds the tiles written at once to a quarter
/// of the budget: nothing else of note is held by then).
const WRITE_BYTES_PER_POINT: u64 = 96;

/// Bytes of the best two claims of a child's cell (the entry and the
/// table's slack): what bounds the children decided with their parents.
const RUNNER_BYTES: u64 = 64;

/// Decides the streamed node `n` from its pass: `reach`, the points
/// passed on per child octant, `occupied`, its kept points per octant
/// (what bounds each child's cells), `kept`, how many it keeps. Makes its
/// children (`new_node(key, count, cells)`) and returns them by octant.
fn decide(
    top: &mut Vec<Top>,
    n: usize,
    (reach, occupied, kept): ([u64; 8], [u64; 8], u64),
    new_node: &mut dyn FnMut(CellKey, u64, u64) -> Top,
) -> [Option<usize>; 8] {
    let key = top[n].key;
    let mut kids = [None; 8];
    for (oct, &count) in reach.iter().enumerate() {
        if count > 0 {
            kids[oct] = Some(top.len());
            let child = new_node(key.child(oct), count, 8 * occupied[oct]);
            top.push(child);
        }
    }
    if let Kind::Streamed {
        decided,
        children,
        kept: k,
        ..
    } = &mut top[n].kind
    {
        *k = kept;
        *decided = true;
        *children = kids;
    }
    kids
}

/// The name of the pass that spills points, the one that reads their
/// attributes.
const SPILL_PASS: &str = "points: to their subtrees";

/// Where and in how much memory an out-of-core point tileset is built.
#[derive(Clone, Debug)]
pub struct PointsOutOfCoreOptions {
    /// Memory budget in bytes.
    pub memory: u64,
    /// The staging folder: created and locked for the run, removed after
    /// it (`lodkit_scale::staging_dir` gives one keyed by input and
    /// options).
    pub staging: PathBuf,
}

/// How a node of the top of the tree is made.
enum Kind {
    /// Decided in a pass (once `decided`): its children by octant, the
    /// spill slot of the points it keeps, how many it keeps.
    Streamed {
        decided: bool,
        children: [Option<usize>; 8],
        slot: usize,
        kept: u64,
    },
    /// Tiled in core from the spill slot of its reaching points.
    Subtree { slot: usize },
}

struct Top {
    key: CellKey,
    count: u64,
    /// At least the cells its winner map will hold: its points, and 8
    /// per cell its parent's map held in its octant (a parent's cell
    /// holds 8 of its child's).
    cells: u64,
    kind: Kind,
}

/// Where a point goes among the top nodes: the streamed node at `depth`
/// it reaches (still undecided), the streamed node that keeps it, or the
/// subtree root it reaches.
enum Reach {
    Undecided(usize),
    Kept(usize),
    Subtree(usize),
}

/// Where point `i` at `p` goes. `kept` lists every decided node's kept
/// points by input index with the node (sorted); `cursor` is where the
/// points before `i` left it (points come in input order, so a point is
/// found kept in O(1) instead of by a lookup per depth).
fn walk(
    top: &[Top],
    (kept, cursor): (&[(u32, u32)], &mut usize),
    grid: &Grid,
    i: u32,
    p: Vec3,
) -> Result<Reach> {
    if let Some(&(k, n)) = kept.get(*cursor)
        && k == i
    {
        *cursor += 1;
        return Ok(Reach::Kept(n as usize));
    }
    let mut n = 0usize;
    loop {
        let node = &top[n];
        match &node.kind {
            Kind::Subtree { .. } => return Ok(Reach::Subtree(n)),
            Kind::Streamed {
                decided, children, ..
            } => {
                if !decided {
                    return Ok(Reach::Undecided(n));
                }
                let o = octant(grid, p, node.key.depth);
                n = children[o as usize]
                    .ok_or_else(|| Error::Input("the input changed while it was read".into()))?;
            }
        }
    }
}

/// Builds the point tileset of the cloud in `input` (a vertex-only binary
/// PLY, LAS or LAZ) into the folder `out` in about `o.memory` bytes; see
/// the module docs. `out` follows
/// [`write_point_tileset`](crate::write_point_tileset)'s rule. Returns
/// the report and the origin the root transform holds (a LAS/LAZ file's;
/// none for a PLY).
///
/// Guarantees: the bytes of the in-core path for the same input and
/// options; nothing staged is left after the call. Errors: an input the
/// stream readers refuse (one line naming the file), no points, more than
/// `u32::MAX` points, `leaf_points` out of range or an output folder that
/// is not lodkit's ([`Error::Usage`]), another run holding the staging
/// folder, I/O. Cost: see the module docs; runs on the current rayon
/// pool (the bytes do not depend on its size) and, on glibc, caps the
/// process's malloc arenas at one for good (the budget holds whatever the
/// threads).
pub fn point_tileset_out_of_core(
    input: &Path,
    out: &Path,
    opts: &PointTilesOptions,
    o: &PointsOutOfCoreOptions,
    progress: &(dyn Fn(OutOfCoreEvent) + Sync),
) -> Result<(PointTilesReport, Option<[f64; 3]>)> {
    tuned(input, out, opts, o, &Tuning::default(), progress)
}

/// [`point_tileset_out_of_core`] with `tuning`.
fn tuned(
    input: &Path,
    out: &Path,
    opts: &PointTilesOptions,
    o: &PointsOutOfCoreOptions,
    tuning: &Tuning,
    progress: &(dyn Fn(OutOfCoreEvent) + Sync),
) -> Result<(PointTilesReport, Option<[f64; 3]>)> {
    check_option(
        "leaf points",
        opts.leaf_points,
        &PointTilesOptions::LEAF_POINTS,
    )?;
    few_malloc_arenas();
    let source = Source::open(input)?;
    drop(lodkit_mesh::io::out_folder::Staging::new(out, Some(input))?);
    let lock = lodkit_scale::StagingLock::take(&o.staging).map_err(Error::Input)?;
    // A killed run's files: start over.
    for sub in ["spill", "tiles"] {
        let p = o.staging.join(sub);
        if p.exists() {
            std::fs::remove_dir_all(&p).map_err(io_err(&p))?;
        }
    }
    let result = build(&source, (input, out), opts, o, tuning, progress);
    drop(lock);
    let removed = lodkit_scale::remove_staging(&o.staging).map_err(Error::Input);
    let report = result?;
    removed?;
    Ok((report, source.origin()))
}

/// Malloc arenas at most, process-wide, once a build has run: glibc
/// gives each thread that allocates an arena of its own (up to 8 per
/// core) and keeps what is freed in it for that arena, so the passes',
/// subtrees' and writers' threads together held twice the live memory
/// (5·10⁷ points at `--memory 128M`: 158 MiB peak with the default, 118
/// with two arenas, 70 with one, no slower: the threads allocate per
/// chunk and per node, not per point).
const MALLOC_ARENAS: i32 = 1;

/// Caps glibc's malloc arenas at [`MALLOC_ARENAS`] (elsewhere: nothing),
/// so the budget holds whatever the threads. Process-wide and lasting:
/// the arenas made before stay.
fn few_malloc_arenas() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // glibc's `mallopt` parameter for the arena cap (malloc.h).
        const M_ARENA_MAX: i32 = -8;
        unsafe extern "C" {
            fn mallopt(param: i32, value: i32) -> i32;
        }
        // SAFETY: `mallopt` only sets an allocator parameter; glibc
        // takes it at any time, from any thread.
        unsafe {
            mallopt(M_ARENA_MAX, MALLOC_ARENAS);
        }
    }
}

/// What tests set to reach paths the budgets of small clouds do not.
#[derive(Clone, Copy, Debug, Default)]
struct Tuning {
    /// The keys the children decided with their parents may hold
    /// (default: a quarter of the budget at [`RUNNER_BYTES`]).
    runners: Option<u64>,
}

fn build(
    source: &Source,
    (input, out): (&Path, &Path),
    opts: &PointTilesOptions,
    o: &PointsOutOfCoreOptions,
    tuning: &Tuning,
    progress: &(dyn Fn(OutOfCoreEvent) + Sync),
) -> Result<PointTilesReport> {
    let t0 = Instant::now();
    let named = |e: Error| match e {
        Error::Input(m) if !m.starts_with(&input.display().to_string()) => {
            Error::Input(format!("{}: {m}", input.display()))
        }
        e => e,
    };
    let total = source.len();
    if total == 0 {
        return Err(named(Error::Input(
            "the cloud has no points to tile".into(),
        )));
    }
    if total > u64::from(u32::MAX) {
        return Err(named(Error::Input(format!(
            "{total} points: at most {} in one tileset",
            u32::MAX
        ))));
    }
    let layout = source.layout();
    let passes = Passes {
        source,
        total,
        chunking: parallel_pass::chunking(o.memory / 16),
        named: &named,
        progress,
    };
    // 1. Bounds.
    let mut bounds = Aabb::EMPTY;
    passes.run(
        "points: bounds",
        &|_, points| Ok(bbox_of(points.iter().map(|p| p.position))),
        &mut |_, b| {
            bounds.min = bounds.min.min(b.min);
            bounds.max = bounds.max.max(b.max);
            Ok(())
        },
    )?;
    let grid = Grid::around(&bounds);
    let leaf = opts.leaf_points as u64;
    let fits = |count: u64, depth: u8| {
        count <= leaf
            || depth >= MAX_DEPTH
            || count.saturating_mul(IN_CORE_BYTES_PER_POINT) <= o.memory / 2
    };

    // 2. Streamed nodes, one depth at a time.
    let mut slots = 0usize;
    let new_node = |key: CellKey, count: u64, cells: u64, slots: &mut usize| -> Top {
        let slot = *slots;
        *slots += 1;
        Top {
            key,
            count,
            cells: cells
                .min(count)
                .min(u64::from(PointTilesOptions::CELLS).pow(3)),
            kind: if fits(count, key.depth) {
                Kind::Subtree { slot }
            } else {
                Kind::Streamed {
                    decided: false,
                    children: [None; 8],
                    slot,
                    kept: 0,
                }
            },
        }
    };
    let mut top = vec![new_node(CellKey::ROOT, total, u64::MAX, &mut slots)];
    let mut kept_by: Vec<(u32, u32)> = Vec::new();
    let mut frontier: Vec<usize> = match top[0].kind {
        Kind::Streamed { .. } => vec![0],
        Kind::Subtree { .. } => Vec::new(),
    };
    while !frontier.is_empty() {
        let depth = top[frontier[0]].key.depth;
        // Groups whose winner maps fit a quarter of the budget.
        let mut groups: Vec<Vec<usize>> = Vec::new();
        let mut held = u64::MAX;
        for &n in &frontier {
            let need = top[n].cells * WINNER_BYTES;
            if held.saturating_add(need) > o.memory / 4 {
                groups.push(Vec::new());
                held = 0;
            }
            held += need;
            groups.last_mut().expect("a group").push(n);
        }
        let mut next = Vec::new();
        for group in groups {
            let mut local = vec![u32::MAX; top.len()];
            for (g, &n) in group.iter().enumerate() {
                local[n] = g as u32;
            }
            // The children decided in the same pass when an average
            // child will not fit (at least one is streamed, most likely
            // all), within their own quarter of the budget.
            let fuse = group.iter().all(|&n| {
                let (count, depth) = (top[n].count, top[n].key.depth);
                depth + 1 < MAX_DEPTH && !fits(count / 8, depth + 1)
            });
            let winners = Winners::new();
            let runners = Runners::new(if fuse {
                tuning.runners.unwrap_or(o.memory / 4 / RUNNER_BYTES)
            } else {
                0
            });
            let mut reach = vec![[0u64; 8]; group.len()];
            let mut below = vec![[[0u64; 8]; 8]; group.len()];
            passes.run(
                &format!("points: choosing at depth {depth}"),
                &|first, points| {
                    let mut cursor = kept_by.partition_point(|&(k, _)| k < first);
                    let mut counts = vec![[0u64; 8]; group.len()];
                    let mut counts_below = vec![[[0u64; 8]; 8]; if fuse { group.len() } else { 0 }];
                    let mut found = Vec::with_capacity(points.len());
                    let mut found_below = Vec::with_capacity(if fuse { points.len() } else { 0 });
                    for (k, p) in points.iter().enumerate() {
                        let i = first + k as u32;
                        let at = (&kept_by[..], &mut cursor);
                        let Reach::Undecided(n) = walk(&top, at, &grid, i, p.position)? else {
                            continue;
                        };
                        let g = local[n];
                        if g == u32::MAX {
                            continue;
                        }
                        let key = top[n].key;
                        let (cell, d) = cell_and_distance(&grid, key, p.position);
                        let octant = octant(&grid, p.position, key.depth);
                        counts[g as usize][octant as usize] += 1;
                        let next = if fuse {
                            let child = key.child(octant as usize);
                            let (cell, d) = cell_and_distance(&grid, child, p.position);
                            let next = crate::point_tiles::octant(&grid, p.position, child.depth);
                            counts_below[g as usize][octant as usize][next as usize] += 1;
                            found_below.push((
                                (((u64::from(g) << 3) | u64::from(octant)) << 32) | u64::from(cell),
                                Winner {
                                    d,
                                    index: i,
                                    octant: next,
                                    next: 0,
                                },
                            ));
                            next
                        } else {
                            0
                        };
                        found.push((
                            (u64::from(g) << 32) | u64::from(cell),
                            Winner {
                                d,
                                index: i,
                                octant,
                                next,
                            },
                        ));
                    }
                    winners.offer(found);
                    if fuse {
                        runners.offer(found_below);
                    }
                    Ok((counts, counts_below))
                },
                &mut |_, (counts, counts_below)| {
                    for (r, c) in reach.iter_mut().zip(counts.iter()) {
                        for (a, b) in r.iter_mut().zip(c) {
                            *a += b;
                        }
                    }
                    for (r, c) in below.iter_mut().zip(counts_below.iter()) {
                        for (r, c) in r.iter_mut().zip(c) {
                            for (a, b) in r.iter_mut().zip(c) {
                                *a += b;
                            }
                        }
                    }
                    Ok(())
                },
            )?;
            let mut occupied = vec![[0u64; 8]; group.len()];
            let mut kept = vec![0u64; group.len()];
            let mut taken = Vec::new();
            for (key, w) in winners.into_iter() {
                let g = (key >> 32) as usize;
                reach[g][w.octant as usize] -= 1;
                occupied[g][w.octant as usize] += 1;
                below[g][w.octant as usize][w.next as usize] =
                    below[g][w.octant as usize][w.next as usize].saturating_sub(1);
                kept[g] += 1;
                kept_by.push((w.index, group[g] as u32));
                taken.push(w.index);
            }
            let mut kids = Vec::with_capacity(group.len());
            for (g, &n) in group.iter().enumerate() {
                let made = decide(
                    &mut top,
                    n,
                    (reach[g], occupied[g], kept[g]),
                    &mut |key, count, cells| new_node(key, count, cells, &mut slots),
                );
                kids.push(made);
            }
            // The children decided from the claims on their cells.
            taken.sort_unstable();
            let mut undecided = vec![false; group.len() * 8];
            let decided_below = runners.winners(&|i| taken.binary_search(&i).is_ok(), &mut |key| {
                undecided[(key >> 32) as usize] = true
            });
            let streamed = |top: &[Top], c: usize| matches!(top[c].kind, Kind::Streamed { .. });
            if let Some(found) = decided_below.filter(|_| fuse) {
                let mut occupied = vec![[0u64; 8]; group.len() * 8];
                let mut kept = vec![0u64; group.len() * 8];
                let mut mine = Vec::new();
                for (key, w) in found {
                    let go = (key >> 32) as usize;
                    let (g, oct) = (go / 8, go % 8);
                    let Some(c) = kids[g][oct].filter(|&c| streamed(&top, c) && !undecided[go])
                    else {
                        continue;
                    };
                    below[g][oct][w.octant as usize] -= 1;
                    occupied[go][w.octant as usize] += 1;
                    kept[go] += 1;
                    mine.push((w.index, c as u32));
                }
                kept_by.extend(mine);
                for (g, k) in kids.iter().enumerate() {
                    for (oct, c) in k.iter().enumerate() {
                        let Some(c) = *c else { continue };
                        if !streamed(&top, c) {
                            continue;
                        }
                        let go = g * 8 + oct;
                        if undecided[go] {
                            next.push(c);
                            continue;
                        }
                        let grand = decide(
                            &mut top,
                            c,
                            (below[g][oct], occupied[go], kept[go]),
                            &mut |key, count, cells| new_node(key, count, cells, &mut slots),
                        );
                        next.extend(grand.iter().flatten().filter(|&&x| streamed(&top, x)));
                    }
                }
            } else {
                for k in &kids {
                    next.extend(k.iter().flatten().filter(|&&x| streamed(&top, x)));
                }
            }
            kept_by.sort_unstable();
        }
        frontier = next;
    }

    // 3. Spill: each point to the node that keeps it or its subtree.
    let spill_dir = o.staging.join("spill");
    let tiles_dir = o.staging.join("tiles");
    std::fs::create_dir_all(&tiles_dir).map_err(io_err(&tiles_dir))?;
    let cap = (o.memory / 8).clamp(1 << 16, 1 << 30) as usize;
    let slot_of: Vec<usize> = top
        .iter()
        .map(|t| match t.kind {
            Kind::Streamed { slot, .. } | Kind::Subtree { slot } => slot,
        })
        .collect();
    let mut spill = Spill::new(&spill_dir, slots, cap)?;
    passes.run(
        SPILL_PASS,
        &|first, points| {
            let mut cursor = kept_by.partition_point(|&(k, _)| k < first);
            let mut to = Vec::with_capacity(points.len());
            for (k, p) in points.iter().enumerate() {
                let i = first + k as u32;
                let n = match walk(&top, (&kept_by, &mut cursor), &grid, i, p.position)? {
                    Reach::Kept(n) | Reach::Subtree(n) => n,
                    Reach::Undecided(_) => {
                        return Err(Error::Input("the input changed while it was read".into()));
                    }
                };
                to.push(((slot_of[n] as u64) << 32) | k as u64);
            }
            // The chunk's records grouped by slot, input order within
            // each: the merge appends whole runs.
            to.sort_unstable();
            let mut bytes = Vec::with_capacity(points.len() * layout.size());
            let mut runs: Vec<(u32, usize)> = Vec::new();
            for &sk in &to {
                let (slot, k) = ((sk >> 32) as u32, sk as u32);
                if runs.last().is_none_or(|&(s, _)| s != slot) {
                    runs.push((slot, bytes.len()));
                }
                layout.put(&points[k as usize], &mut bytes);
            }
            Ok((runs, bytes))
        },
        &mut |_, (runs, bytes)| {
            for (r, &(slot, start)) in runs.iter().enumerate() {
                let end = runs.get(r + 1).map_or(bytes.len(), |&(_, e)| e);
                spill.put_bytes(slot as usize, &bytes[start..end])?;
            }
            Ok(())
        },
    )?;
    spill.flush()?;
    drop(spill);
    drop(kept_by);

    // 4. Tiles: streamed nodes' kept points, subtrees tiled in core. All
    // nodes in one list; `tile` names each content's staged file.
    struct Made {
        node: Node,
        /// The staged file of its content and the byte range in it.
        tile: Option<(PathBuf, Option<(u64, u64)>)>,
        bbox: Aabb,
        error: f64,
        points: usize,
    }
    let mut made: Vec<Made> = Vec::new();
    // Top nodes keep their index in `made`; subtree nodes follow.
    for t in &top {
        made.push(Made {
            node: Node {
                key: t.key,
                children: Vec::new(),
                input_faces: t.count as usize,
            },
            tile: None,
            bbox: Aabb::EMPTY,
            error: 0.0,
            points: 0,
        });
    }
    let subtrees = top
        .iter()
        .filter(|t| matches!(t.kind, Kind::Subtree { .. }))
        .count() as u64;
    progress(OutOfCoreEvent::Phase("points: subtrees in core", subtrees));
    let mut jobs: Vec<(usize, usize, u64, CellKey)> = Vec::new();
    for (n, t) in top.iter().enumerate() {
        match &t.kind {
            Kind::Streamed {
                children,
                slot,
                kept,
                ..
            } => {
                let path = Spill::file(&spill_dir, *slot);
                let cloud = layout.read(&path, None)?;
                made[n].bbox = bbox_of(cloud.positions.iter().copied());
                made[n].points = cloud.positions.len();
                made[n].tile = Some((path, None));
                made[n].node.children = children.iter().flatten().copied().collect();
                made[n].error = if t.count > *kept {
                    cell_diagonal(&grid, t.key.depth)
                } else {
                    0.0
                };
            }
            Kind::Subtree { slot } => jobs.push((n, *slot, t.count, t.key)),
        }
    }
    // Subtrees in core, as many at once as the threads and the budget
    // allow (their points at IN_CORE_BYTES_PER_POINT within the half one
    // subtree may take), each batch's nodes appended in the order of the
    // jobs, so the tree does not depend on the thread count.
    let threads = rayon::current_num_threads().max(1);
    let mut rest = &jobs[..];
    while !rest.is_empty() {
        let mut take = 1;
        let mut bytes = rest[0].2.saturating_mul(IN_CORE_BYTES_PER_POINT);
        while take < rest.len().min(threads) {
            bytes = bytes.saturating_add(rest[take].2.saturating_mul(IN_CORE_BYTES_PER_POINT));
            if bytes > o.memory / 2 {
                break;
            }
            take += 1;
        }
        let (batch, after) = rest.split_at(take);
        rest = after;
        let tiled: Vec<Result<TiledSubtree>> = batch
            .par_iter()
            .map(|&(_, slot, count, key)| {
                tile_subtree(
                    (&spill_dir, &tiles_dir),
                    layout,
                    &grid,
                    opts.leaf_points,
                    (slot, count, key),
                )
            })
            .collect();
        for (&(n, ..), t) in batch.iter().zip(tiled) {
            let t = t.map_err(named)?;
            let base = made.len();
            let id = |k: usize| if k == 0 { n } else { base + k - 1 };
            for (
                k,
                TiledNode {
                    node,
                    range,
                    bbox,
                    error,
                    points,
                },
            ) in t.nodes.into_iter().enumerate()
            {
                let m = Made {
                    node: Node {
                        key: node.key,
                        children: node.children.iter().map(|&c| id(c)).collect(),
                        input_faces: node.input_faces,
                    },
                    tile: range.map(|r| (t.staged.clone(), Some(r))),
                    bbox,
                    error,
                    points,
                };
                if k == 0 {
                    made[n] = m;
                } else {
                    made.push(m);
                }
            }
            progress(OutOfCoreEvent::Advance(1));
        }
    }
    drop(top);

    // 5. The nodes in the in-core order (breadth-first, children in
    // octant order), then the folder.
    let mut order = vec![0usize];
    let mut new_id = vec![usize::MAX; made.len()];
    new_id[0] = 0;
    let mut head = 0;
    while head < order.len() {
        let m = order[head];
        head += 1;
        for &c in &made[m].node.children {
            new_id[c] = order.len();
            order.push(c);
        }
    }
    let nodes: Vec<Node> = order
        .iter()
        .map(|&m| Node {
            key: made[m].node.key,
            children: made[m].node.children.iter().map(|&c| new_id[c]).collect(),
            input_faces: made[m].node.input_faces,
        })
        .collect();
    let boxes: Vec<Aabb> = order.iter().map(|&m| made[m].bbox).collect();
    let errors: Vec<f64> = order.iter().map(|&m| made[m].error).collect();
    let info = node_info(&nodes, &boxes, &errors);
    let depth = nodes.iter().map(|n| n.key.depth).max().unwrap_or(0);
    let content: Vec<usize> = order
        .iter()
        .enumerate()
        .filter(|&(_, &m)| made[m].tile.is_some())
        .map(|(i, _)| i)
        .collect();
    let mut report = PointTilesReport {
        input_points: total as usize,
        tiles: content.len(),
        depth,
        max_tile_points: made.iter().map(|m| m.points).max().unwrap_or(0),
        root_error: info[0].error,
        seconds: [t0.elapsed().as_secs_f64(), 0.0],
        bytes: 0,
    };
    let tree = Octree {
        grid,
        nodes,
        leaf_of_face: Vec::new(),
        depth,
    };
    let t1 = Instant::now();
    progress(OutOfCoreEvent::Phase("writing tiles", content.len() as u64));
    let names: Vec<(String, u8)> = content
        .iter()
        .map(|&i| {
            (
                made[order[i]].node.key.name(),
                made[order[i]].node.key.depth,
            )
        })
        .collect();
    // A tile in flight holds its raw points, its cloud and its GLB.
    let per_tile = (report.max_tile_points as u64).saturating_mul(WRITE_BYTES_PER_POINT);
    let writers =
        (o.memory / 4 / per_tile.max(1)).clamp(1, crate::tileset_folder::MAX_WRITERS as u64);
    report.bytes = crate::tileset_folder::write_folder(
        out,
        Some(input),
        (&tree, &info),
        (Refine::Add, source.origin()),
        &names,
        writers as usize,
        &|k, grid| {
            let m = &made[order[content[k]]];
            let (path, at) = m.tile.as_ref().expect("a tile with content");
            let cloud = layout.read(path, *at)?;
            crate::tile_content::encode_point_tile(&names[k].0, &cloud, opts.compress, grid)
        },
        &mut || progress(OutOfCoreEvent::Advance(1)),
    )?;
    report.seconds[1] = t1.elapsed().as_secs_f64();
    Ok(report)
}

fn bbox_of(points: impl IntoIterator<Item = Vec3>) -> Aabb {
    let mut b = Aabb::EMPTY;
    for p in points {
        b.min = b.min.min(p);
        b.max = b.max.max(p);
    }
    b
}

#[cfg(test)]
mod tests;
