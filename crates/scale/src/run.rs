//! The out-of-core pipeline: read → partition → block rounds → final
//! in-core pass. Every file it writes lives in the staging folder; a
//! finished step leaves a marker (`parted` per round, a block's `.out`,
//! both written atomically), so a rerun after a kill skips them.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::block::Goal;
use crate::partition::{Cuts, Grid, Writers, block_input, block_output};
use crate::round_manifest::{Manifest, check_staging, read_manifest, write_manifest};
use crate::runner::{BLOCKS_IN_FLIGHT, Runner};
use crate::soup::{self, Layout, Welder};
use crate::staging::{StagingLock, io_err};
use crate::tasks::BlockTask;
use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::io::ply::stream::PlyStream;
use lodkit_mesh::io::stl_stream::StlStream;
use lodkit_simplify::{Options, Simplified, Simplifier, Target};

/// Bytes per block face while a block is simplified: the soup welded
/// (12 B per face, 12 per vertex, the weld map), the simplifier's
/// workspace (68–69 B per vertex).
const BLOCK_BYTES_PER_FACE: u64 = 100;
/// Most blocks per axis (at most 512 files open while partitioning).
const MAX_GRID: u32 = 8;

/// The block rounds aim at this share of what the final pass holds in
/// the budget: a block's border excess (`block.rs`) comes on top of its
/// goal, and a round that overshoots the budget costs a second round.
const FINAL_PASS_SHARE: f64 = 0.9;

/// When the final pass holds under this many times the target, round 0
/// stops at twice the final pass's goal and the round on the shifted grid
/// takes it the rest of the way: round 0's cuts, locked at full density,
/// then lie inside round-1 blocks while half the reduction is still to
/// come, instead of being cleaned up by a final pass with little room
/// (2M-face blob at 10 % in 16 MiB, the final pass holding 1.05× the
/// target: max error 2.6× in core in one straight round, 1.4× this way).
const SHIFTED_ROUND_BELOW: u64 = 2;

/// The input of the pipeline: a binary PLY or a binary STL, streamed.
enum Source {
    Ply(Box<PlyStream>),
    Stl(StlStream),
}

impl Source {
    /// `.stl` (any case) is read as STL, anything else as PLY.
    fn open(input: &Path) -> Result<Source, String> {
        let stl = input
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("stl"));
        if stl {
            StlStream::open(input).map(Source::Stl)
        } else {
            PlyStream::open(input).map(|s| Source::Ply(Box::new(s)))
        }
        .map_err(|e| e.to_string())
    }
}

/// Round 0 from a binary PLY: the bounding box, then each face to its
/// block, its corners from a vertex table or a bounded cache.
fn partition_ply(
    s: &PlyStream,
    r0: &Path,
    layout: Layout,
    g: u32,
    o: &ScaleOptions,
    progress: &(dyn Fn(Event) + Sync),
    rep: &mut Report,
) -> Result<(Vec3, Vec3), String> {
    let t = Instant::now();
    progress(Event::Phase("reading vertices", s.vertex_count()));
    // Pass 1: the bounding box (and every coordinate checked),
    // and the vertex table when it fits the budget.
    let table_bytes = s
        .vertex_count()
        .saturating_mul(layout.corner_bytes() as u64);
    let mut table = (table_bytes as f64 <= o.memory as f64 * TABLE_SHARE).then(|| {
        let mut t = Welder::new(layout).finish();
        let n = s.vertex_count() as usize;
        t.positions.reserve_exact(n);
        if let Some(v) = t.normals.as_mut() {
            v.reserve_exact(n);
        }
        if let Some(v) = t.colors.as_mut() {
            v.reserve_exact(n);
        }
        if let Some(v) = t.uvs.as_mut() {
            v.reserve_exact(n);
        }
        t
    });
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    let mut n = 0u64;
    s.for_each_vertex(|v| {
        lo = lo.min(v.position);
        hi = hi.max(v.position);
        if let Some(t) = table.as_mut() {
            soup::push_vertex(t, v);
        }
        n += 1;
        if n.is_multiple_of(1 << 20) {
            progress(Event::Advance(1 << 20));
        }
    })
    .map_err(|e| e.to_string())?;
    rep.phases
        .push(("read vertices".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    progress(Event::Phase("partitioning faces", s.face_records()));
    let grid = Grid::new(lo, hi, g, 0.0);
    let mut w = Writers::new(r0, grid.blocks(), layout);
    // Pass 2: each face's corners from the table, or, for an
    // input whose vertices alone exceed the budget, through a
    // bounded cache (PlyStream::vertex_reader), so memory stays
    // within the budget whatever the input's size.
    let mut cache = match table {
        Some(_) => None,
        None => Some(
            s.vertex_reader(vertex_cache(o.memory))
                .map_err(|e| e.to_string())?,
        ),
    };
    let mut corner = |i: u32| -> lodkit_mesh::Result<soup::Corner> {
        match (&table, cache.as_mut()) {
            (Some(t), _) => Ok(soup::corner(t, i)),
            (None, Some(c)) => c.get(i),
            (None, None) => unreachable!("a table or a cache is made above"),
        }
    };
    let mut n = 0u64;
    s.for_each_face(|f| {
        let tri = [corner(f[0])?, corner(f[1])?, corner(f[2])?];
        put_face(&mut w, &grid, &tri, &mut n, progress, r0)
    })
    .map_err(|e| e.to_string())?;
    drop(table);
    finish_partition(w, r0, (lo, hi), layout, rep, t)
}

/// Round 0 from a binary STL: the bounding box, then each facet to its
/// block (STL corners are positions already: no vertex table).
fn partition_stl(
    s: &StlStream,
    r0: &Path,
    g: u32,
    progress: &(dyn Fn(Event) + Sync),
    rep: &mut Report,
) -> Result<(Vec3, Vec3), String> {
    let t = Instant::now();
    progress(Event::Phase("reading facets", s.triangles()));
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    s.for_each_triangle(|t| {
        for p in t {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        Ok(())
    })
    .map_err(|e| e.to_string())?;
    rep.phases
        .push(("read facets".into(), t.elapsed().as_secs_f64()));
    let t = Instant::now();
    progress(Event::Phase("partitioning faces", s.triangles()));
    let layout = Layout::default();
    let grid = Grid::new(lo, hi, g, 0.0);
    let mut w = Writers::new(r0, grid.blocks(), layout);
    let mut n = 0u64;
    s.for_each_triangle(|t| {
        let tri = t.map(|p| soup::Corner {
            position: p,
            ..Default::default()
        });
        put_face(&mut w, &grid, &tri, &mut n, progress, r0)
    })
    .map_err(|e| e.to_string())?;
    finish_partition(w, r0, (lo, hi), layout, rep, t)
}

/// One face of round 0's partition to its block, with progress every
/// 2²⁰ faces (`n` counts them).
#[inline]
fn put_face(
    w: &mut Writers,
    grid: &Grid,
    tri: &[soup::Corner; 3],
    n: &mut u64,
    progress: &(dyn Fn(Event) + Sync),
    r0: &Path,
) -> lodkit_mesh::Result<()> {
    *n += 1;
    if n.is_multiple_of(1 << 20) {
        progress(Event::Advance(1 << 20));
    }
    w.put(grid.block_of(tri), tri)
        .map_err(|e| lodkit_mesh::Error::Invalid(format!("{}: {e}", r0.display())))
}

/// Closes round 0's writers: the manifest (bounding box `lo..hi`, reach,
/// counts), and the partition's line in the report.
fn finish_partition(
    w: Writers,
    r0: &Path,
    (lo, hi): (Vec3, Vec3),
    layout: Layout,
    rep: &mut Report,
    started: Instant,
) -> Result<(Vec3, Vec3), String> {
    let reach = w.reach();
    let (counts, sums) = w.finish().map_err(io_err(r0))?;
    rep.input_faces = counts.iter().sum();
    let m = Manifest {
        min: lo,
        max: hi,
        reach,
        counts,
        sums,
    };
    write_manifest(r0, &m).map_err(io_err(r0))?;
    rep.bytes_written += rep.input_faces * layout.face_bytes();
    rep.phases
        .push(("partition".into(), started.elapsed().as_secs_f64()));
    Ok((lo, hi))
}

/// The share of the budget the partition's vertex table may take; an
/// input with more vertices reads them through a cache instead. A table
/// is faster: the cache's misses read the file, and at a billion faces
/// the staging writes evict those pages from the OS cache (partition
/// 339 s through the cache, 128 s with the table).
const TABLE_SHARE: f64 = 0.9;

/// Bytes of the partition's vertex cache for a budget of `memory`: an
/// eighth of it, within 16 MiB..=512 MiB (a scan's faces reach back a few
/// rows of vertices; 16 MiB holds a million of them).
fn vertex_cache(memory: u64) -> usize {
    (memory / 8).clamp(16 << 20, 512 << 20) as usize
}

/// Faces block round `round` should leave (before its blocks' border
/// excess) out of `before`, for a final target of `target` in `memory`
/// bytes: as many as the final in-core pass holds in the budget, never
/// fewer than the target, never more than `before`; twice that in round
/// 0 when the final pass has little room ([`SHIFTED_ROUND_BELOW`]).
///
/// Why not the target itself: the final pass is the only stage that
/// chooses collapses over the whole mesh with every seam free. Blocks
/// taken to the target leave it nothing to choose (at 10 % it made no
/// collapse at all) and their per-block ratio stands in for the global
/// error order, so the result was coarser than in core (2M-face blob at
/// 1 %: mean 22× in core; with the border-aware goal alone, max 1.8×).
/// Leaving the final pass as much as the budget allows makes the blocks
/// a cheap first stretch and the final pass the in-core run it is.
fn round_goal(before: u64, target: u64, memory: u64, round: u32) -> u64 {
    let holds = memory / crate::IN_CORE_BYTES_PER_FACE;
    let goal = ((holds as f64 * FINAL_PASS_SHARE) as u64).max(target);
    let goal = if round == 0 && goal < SHIFTED_ROUND_BELOW.saturating_mul(target) {
        goal.saturating_mul(2)
    } else {
        goal
    };
    goal.min(before)
}

/// Options of [`simplify_file`].
#[derive(Debug, Clone)]
pub struct ScaleOptions {
    /// The simplifier's options; `target` applies to the whole input.
    pub simplify: Options,
    /// Memory budget in bytes (blocks are sized so the blocks being
    /// simplified at once fit it).
    pub memory: u64,
    /// The staging folder (created and locked for the run, see
    /// [`StagingLock`](crate::StagingLock); the caller removes it, with
    /// [`remove_staging`](crate::remove_staging)).
    pub staging: PathBuf,
    /// Where the blocks run; the result is the same either way.
    pub runner: Runner,
}

/// Progress of [`simplify_file`].
#[derive(Debug, Clone, Copy)]
pub enum Event<'a> {
    /// A phase starts, with its amount of work (faces or vertices).
    Phase(&'a str, u64),
    /// This much of the current phase is done.
    Advance(u64),
}

/// What [`simplify_file`] did.
#[derive(Debug, Clone, Default)]
pub struct Report {
    /// Input triangles.
    pub input_faces: u64,
    /// Seconds per phase, in order.
    pub phases: Vec<(String, f64)>,
    /// Faces after each block round.
    pub round_faces: Vec<u64>,
    /// Blocks per round (non-empty ones).
    pub round_blocks: Vec<usize>,
    /// Blocks a rerun found already done.
    pub resumed_blocks: usize,
    /// Bytes read from the input and from staging files.
    pub bytes_read: u64,
    /// Bytes written to staging files.
    pub bytes_written: u64,
    /// The final in-core pass's report.
    pub last: Option<lodkit_simplify::LevelReport>,
}

/// Simplifies the binary PLY mesh `input` to `o.simplify.target` faces
/// (a ratio applies to the input's triangles) in about `o.memory` bytes
/// whatever the input's size (the partition keeps a table of the
/// vertices when it takes under 0.9 × the budget, else reads them
/// through a cache of an eighth of it, at most 512 MiB). The blocks stop at what the final in-core pass holds in
/// `o.memory` (at [`IN_CORE_BYTES_PER_FACE`](crate::IN_CORE_BYTES_PER_FACE)),
/// so it fits too, but for a target that does not fit itself or block
/// borders (kept to the final pass) that overshoot even after the second
/// round.
///
/// Guarantees: the final pass is the in-core simplifier on the whole
/// reduced mesh, so its target, fold-over, topology and border checks all
/// hold; locked cut vertices keep their bits, so blocks weld back without
/// cracks. Quality: with `o.memory` at least
/// [`quality_memory`](crate::quality_memory) of the target, the error is
/// expected within 1.1× (mean) and 1.2× (max) of the in-core path's
/// (measured, not proven); with less, coarser. Deterministic: blocks are independent and merged in block
/// order, so the result does not depend on thread count or scheduling
/// (nor on whether blocks ran here or as Ray tasks). Normals, colours
/// and UVs the file carries (as the in-core PLY reader finds them) go
/// through the blocks with each corner and are simplified as in core
/// (`o.simplify.weights`); corners that differ in an attribute stay
/// apart (seams).
///
/// Errors: a message naming the file: an input the stream reader refuses
/// ([`PlyStream`]), I/O in the staging folder, the simplifier refusing a
/// block. Cost: linear in the input; disk: 36 bytes per input face
/// (positions alone; 108 with normals, colours and UVs).
pub fn simplify_file(
    input: &Path,
    o: &ScaleOptions,
    progress: &(dyn Fn(Event) + Sync),
) -> Result<(TriMesh, Report), String> {
    let mut p = Pipeline::start(input, o, progress)?;
    let target = o.simplify.target.faces(p.rep.input_faces as usize) as u64;
    let out = p.reduce_then_final_pass(target)?;
    p.rep.last = Some(out.report);
    Ok((out.mesh, p.rep))
}

/// One level of [`lod_chain_file`], as it is made.
#[derive(Debug)]
pub enum ChainLevel<'a> {
    /// A level too big for the final in-core pass: the soup files whose
    /// faces together make it (write it with
    /// [`write_soups_ply`](crate::write_soups_ply) before returning: the
    /// files are gone once the next level is made).
    Soups {
        /// Faces in all of them.
        faces: u64,
        /// Their corners' attributes.
        layout: Layout,
        /// The block outputs, in block order.
        files: &'a [PathBuf],
    },
    /// A level an interrupted earlier run of the same job already handed
    /// over (its blocks are gone); its faces.
    Resumed {
        /// Faces of the level as it was made.
        faces: u64,
    },
    /// A level made in core (the final pass, then the in-core chain).
    Mesh {
        /// The level.
        mesh: &'a TriMesh,
        /// The simplifier's report of it (its estimated error covers the
        /// in-core passes only).
        report: &'a lodkit_simplify::LevelReport,
    },
}

/// An LOD chain of the binary PLY mesh `input` in about `o.memory` bytes:
/// one level per target of `targets` (ratios apply to the input's
/// triangles; a target over the previous level's repeats it), each made
/// from the previous one, handed to `on_level(i, level)` in order.
///
/// Levels over 0.9 × what the final in-core pass holds in `o.memory` (80
/// B per face) are made out of core, one block round each on a grid
/// shifted by half a block from the previous round's (so no cut stays
/// locked for two levels), and handed over as soup files
/// ([`ChainLevel::Soups`]); the first level that fits is made as
/// [`simplify_file`] makes its result (block rounds down to what the final
/// pass holds, then the final in-core pass to the target), and the
/// levels after it by the in-core chain from it ([`ChainLevel::Mesh`]).
///
/// Guarantees: in-core levels as [`simplify_file`]; an out-of-core level
/// has its target plus the excess of the block borders it had to keep
/// (`(1 − ratio)` of each block's border vertices: about 0.1 % of a
/// 500 M-face level in 64 blocks); blocks weld back crack-free; the same
/// input, options and budget give the same levels, wherever the blocks
/// run. Resumable as [`simplify_file`]: a rerun redoes no finished block
/// and hands over a level an earlier run finished as
/// [`ChainLevel::Resumed`]. Errors: those of [`simplify_file`], and the
/// first error `on_level` returns. Cost: linear in the input and in each
/// level; disk: 36 B per face of the largest level (more with
/// attributes, as [`simplify_file`]), twice.
pub fn lod_chain_file(
    input: &Path,
    targets: &[Target],
    o: &ScaleOptions,
    progress: &(dyn Fn(Event) + Sync),
    on_level: &mut dyn FnMut(usize, ChainLevel) -> Result<(), String>,
) -> Result<Report, String> {
    let mut p = Pipeline::start(input, o, progress)?;
    let n = p.rep.input_faces;
    let holds = o.memory / crate::IN_CORE_BYTES_PER_FACE;
    let fits = |t: u64| (t as f64) <= holds as f64 * FINAL_PASS_SHARE;
    let mut previous = n;
    let mut i = 0;
    while i < targets.len() {
        let t = (targets[i].faces(n as usize) as u64).min(previous);
        if fits(t) {
            break;
        }
        // Level i out of core: one block round to `t`.
        let round = p.round;
        let next = o.staging.join(format!("r{}", round + 1));
        if let Some(m) = read_manifest(&next, p.blocks()) {
            // An earlier run handed this level over and moved on.
            previous = m.counts.iter().sum();
            on_level(i, ChainLevel::Resumed { faces: previous })?;
            p.current = None;
            p.current_faces = previous;
            p.round += 1;
            i += 1;
            continue;
        }
        p.prepare_round()?;
        let ratio = if p.current_faces == 0 {
            1.0
        } else {
            t as f64 / p.current_faces as f64
        };
        let label = format!("level {} out of core", i + 1);
        let (faces, files) = p.block_round(Goal::Total(ratio), &label)?;
        on_level(
            i,
            ChainLevel::Soups {
                faces,
                layout: p.layout,
                files: &files,
            },
        )?;
        previous = faces;
        p.round += 1;
        i += 1;
    }
    if i == targets.len() {
        return Ok(p.rep);
    }
    // The first level that fits: as simplify_file, then the rest in core.
    let first = (targets[i].faces(n as usize) as u64).min(previous);
    let out = p.reduce_then_final_pass(first)?;
    on_level(
        i,
        ChainLevel::Mesh {
            mesh: &out.mesh,
            report: &out.report,
        },
    )?;
    let rest: Vec<Target> = targets[i + 1..]
        .iter()
        .map(|t| Target::Faces(t.faces(n as usize)))
        .collect();
    if !rest.is_empty() {
        let t = Instant::now();
        progress(Event::Phase("in-core levels", out.mesh.faces.len() as u64));
        let levels = Simplifier::new()
            .lod_chain(&out.mesh, &o.simplify, &rest)
            .map_err(|e| format!("{}: {e}", input.display()))?;
        progress(Event::Advance(out.mesh.faces.len() as u64));
        for (k, l) in levels.iter().enumerate() {
            on_level(
                i + 1 + k,
                ChainLevel::Mesh {
                    mesh: &l.mesh,
                    report: &l.report,
                },
            )?;
        }
        p.rep
            .phases
            .push(("in-core levels".into(), t.elapsed().as_secs_f64()));
    }
    p.rep.last = Some(out.report);
    Ok(p.rep)
}

/// The staged pipeline's state: the input partitioned into round 0, then
/// rounds `r1`, `r2`, … each on the grid shifted by half a block from the
/// one before.
struct Pipeline<'a> {
    /// The staging folder, held by this run until it ends.
    _lock: StagingLock,
    input: &'a Path,
    o: &'a ScaleOptions,
    progress: &'a (dyn Fn(Event) + Sync),
    rep: Report,
    /// The bounding box of the input and the blocks per axis.
    min: Vec3,
    max: Vec3,
    g: u32,
    /// The attributes the input carries, through every soup.
    layout: Layout,
    /// The round whose folder holds (or will hold) the next block inputs.
    round: u32,
    /// The soup files holding the current mesh when they are the outputs
    /// of the previous round (None: the current round's inputs hold it).
    current: Option<(PathBuf, Vec<usize>)>,
    /// Faces of the current mesh.
    current_faces: u64,
}

impl<'a> Pipeline<'a> {
    /// Reads and partitions `input` into round 0 (or finds an earlier
    /// run's partition in the staging folder).
    fn start(
        input: &'a Path,
        o: &'a ScaleOptions,
        progress: &'a (dyn Fn(Event) + Sync),
    ) -> Result<Pipeline<'a>, String> {
        let source = Source::open(input)?;
        o.runner.check()?;
        let lock = StagingLock::take(&o.staging)?;
        let mut rep = Report::default();
        let (faces, layout) = match &source {
            Source::Ply(s) => {
                let a = s.attributes();
                let layout = Layout {
                    normals: a.normals,
                    colors: a.colors,
                    uvs: a.uvs,
                };
                (s.face_records(), layout)
            }
            Source::Stl(s) => (s.triangles(), Layout::default()),
        };
        let block_faces = (o.memory / (BLOCK_BYTES_PER_FACE * BLOCKS_IN_FLIGHT)).max(256);
        let blocks = faces.div_ceil(block_faces).max(2);
        let g = ((blocks as f64).cbrt().ceil() as u32).clamp(2, MAX_GRID);
        let blocks = (g as usize).pow(3);
        check_staging(&o.staging, blocks, layout)?;
        let r0 = o.staging.join("r0");
        let (min, max) = match read_manifest(&r0, blocks) {
            Some(m) => {
                rep.input_faces = m.counts.iter().sum();
                (m.min, m.max)
            }
            None => {
                std::fs::create_dir_all(&r0).map_err(io_err(&r0))?;
                let parted = match &source {
                    Source::Ply(s) => partition_ply(s, &r0, layout, g, o, progress, &mut rep),
                    Source::Stl(s) => partition_stl(s, &r0, g, progress, &mut rep),
                };
                // A partition cut short (a bad input found late, a full
                // disk) leaves nothing to resume from (`check_staging`
                // left no other round): the folder goes, while still held.
                if parted.is_err() {
                    let _ = std::fs::remove_dir_all(&o.staging);
                }
                parted?
            }
        };
        rep.bytes_read += std::fs::metadata(input).map_or(0, |m| m.len());
        let current_faces = rep.input_faces;
        Ok(Pipeline {
            _lock: lock,
            input,
            o,
            progress,
            rep,
            min,
            max,
            g,
            layout,
            round: 0,
            current: None,
            current_faces,
        })
    }

    fn dir(&self, round: u32) -> PathBuf {
        self.o.staging.join(format!("r{round}"))
    }

    /// Blocks in every round's grid.
    fn blocks(&self) -> usize {
        (self.g as usize).pow(3)
    }

    /// The grid of `round`: shifted by half a block on odd rounds.
    fn grid(&self, round: u32) -> Grid {
        let shift = if round % 2 == 1 { 0.5 } else { 0.0 };
        Grid::new(self.min, self.max, self.g, shift)
    }

    /// Makes sure the folder of `self.round` holds the current mesh as
    /// block inputs: re-partitions the previous round's outputs on this
    /// round's grid (shifted by half a block on odd rounds) unless an
    /// earlier run did, then deletes those outputs.
    fn prepare_round(&mut self) -> Result<(), String> {
        let Some((prev, todo)) = self.current.take() else {
            return Ok(());
        };
        let next = self.dir(self.round);
        if read_manifest(&next, self.blocks()).is_none() {
            let t = Instant::now();
            std::fs::create_dir_all(&next).map_err(io_err(&next))?;
            (self.progress)(Event::Phase(
                "re-partitioning on the shifted grid",
                self.current_faces,
            ));
            let grid = self.grid(self.round);
            let mut w = Writers::new(&next, grid.blocks(), self.layout);
            for &b in &todo {
                let p = block_output(&prev, b);
                let mut err = Ok(());
                soup::for_each(&p, self.layout, |tri| {
                    if err.is_ok() {
                        err = w.put(grid.block_of(tri), tri);
                    }
                })
                .and(err)
                .map_err(io_err(&p))?;
            }
            let reach = w.reach();
            let (counts, sums) = w.finish().map_err(io_err(&next))?;
            let m = Manifest {
                min: self.min,
                max: self.max,
                reach,
                counts,
                sums,
            };
            write_manifest(&next, &m).map_err(io_err(&next))?;
            self.rep.bytes_read += self.current_faces * self.layout.face_bytes();
            self.rep.bytes_written += self.current_faces * self.layout.face_bytes();
            self.rep
                .phases
                .push(("re-partition".into(), t.elapsed().as_secs_f64()));
        }
        // The outputs are in the new round's inputs now.
        for &b in &todo {
            let _ = std::fs::remove_file(block_output(&prev, b));
        }
        Ok(())
    }

    /// Runs the blocks of `self.round` (prepared) at `ratio`, skipping
    /// those an earlier run finished; returns the faces out and the
    /// output files, which become the current mesh.
    fn block_round(&mut self, goal: Goal, label: &str) -> Result<(u64, Vec<PathBuf>), String> {
        let dir = self.dir(self.round);
        let Manifest { counts, reach, .. } = read_manifest(&dir, self.blocks())
            .ok_or_else(|| format!("{}: staging manifest unreadable", dir.display()))?;
        let cuts = Cuts {
            grid: self.grid(self.round),
            reach,
        };
        let before: u64 = counts.iter().sum();
        let todo: Vec<usize> = (0..counts.len()).filter(|&b| counts[b] > 0).collect();
        let t = Instant::now();
        (self.progress)(Event::Phase(label, before));
        let mut tasks = Vec::new();
        for &b in &todo {
            let output = block_output(&dir, b);
            if output.exists() {
                self.rep.resumed_blocks += 1;
                (self.progress)(Event::Advance(counts[b]));
            } else {
                tasks.push(BlockTask {
                    input: block_input(&dir, b),
                    output,
                    goal,
                    cuts,
                    faces: counts[b],
                });
            }
        }
        let progress = self.progress;
        self.o
            .runner
            .run(&dir, &tasks, &self.o.simplify, self.layout, &|i| {
                progress(Event::Advance(tasks[i].faces))
            })?;
        let mut total = 0;
        let mut files = Vec::with_capacity(todo.len());
        for &b in &todo {
            let out = block_output(&dir, b);
            total += soup::faces_in(&out, self.layout).map_err(io_err(&out))?;
            files.push(out);
        }
        self.rep.bytes_read += before * self.layout.face_bytes();
        self.rep.bytes_written += total * self.layout.face_bytes();
        self.rep.round_faces.push(total);
        self.rep.round_blocks.push(todo.len());
        self.rep
            .phases
            .push((label.to_string(), t.elapsed().as_secs_f64()));
        self.current = Some((dir, todo));
        self.current_faces = total;
        Ok((total, files))
    }

    /// Block rounds until the current mesh fits the final pass (at most
    /// two, the second on the shifted grid), then the final in-core pass
    /// to `target` faces.
    fn reduce_then_final_pass(&mut self, target: u64) -> Result<Simplified, String> {
        let o = self.o;
        for k in 0..2 {
            // Round 0 of simplify_file always runs (its input did not fit);
            // after a round, or after the out-of-core levels of a chain,
            // a mesh that fits goes straight to the final pass.
            let fits = self.current_faces * crate::IN_CORE_BYTES_PER_FACE <= o.memory;
            if fits && (k > 0 || self.round > 0) {
                break;
            }
            if let Some(m) = read_manifest(&self.dir(self.round + 1), self.blocks()) {
                // An earlier run finished this round and re-partitioned
                // its output (then deleted it): go on from there.
                self.current = None;
                self.current_faces = m.counts.iter().sum();
                self.round += 1;
                continue;
            }
            self.prepare_round()?;
            let goal = round_goal(self.current_faces, target, o.memory, k);
            let ratio = if self.current_faces == 0 {
                1.0
            } else {
                goal as f64 / self.current_faces as f64
            };
            let label = format!("simplifying blocks (round {})", self.round + 1);
            self.block_round(Goal::Interior(ratio), &label)?;
            self.round += 1;
        }
        // Final pass: the whole reduced mesh in core, to the target.
        let t = Instant::now();
        (self.progress)(Event::Phase(
            "final pass on the merged blocks",
            self.current_faces,
        ));
        let mut w = Welder::new(self.layout);
        let files: Vec<PathBuf> = match &self.current {
            Some((dir, todo)) => todo.iter().map(|&b| block_output(dir, b)).collect(),
            None => Vec::new(),
        };
        for p in &files {
            soup::for_each(p, self.layout, |tri| w.add(tri)).map_err(io_err(p))?;
        }
        let merged = w.finish();
        let opts = Options {
            target: Target::Faces(target as usize),
            ..o.simplify.clone()
        };
        let out = Simplifier::new()
            .simplify(&merged, &opts)
            .map_err(|e| format!("{}: {e}", self.input.display()))?;
        (self.progress)(Event::Advance(self.current_faces));
        self.rep
            .phases
            .push(("final pass".into(), t.elapsed().as_secs_f64()));
        Ok(out)
    }
}
