//! The out-of-core pipeline: read → partition → block rounds → final
//! in-core pass. Every file it writes lives in the staging folder; a
//! finished step leaves a marker (`parted` per round, a block's `.out`,
//! both written atomically), so a rerun after a kill skips them.

use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use lodkit_mesh::TriMesh;
use lodkit_mesh::io::ply::stream::PlyStream;
use lodkit_simplify::{Options, Simplifier, Target};
use crate::runner::{BLOCKS_IN_FLIGHT, Runner};
use crate::tasks::BlockTask;
use crate::partition::{Grid, Writers, block_input, block_output};
use crate::soup::{self, Welder};

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
    /// The staging folder (created; the caller removes it).
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
/// (a ratio applies to the input's triangles) in about `o.memory` bytes,
/// plus 12 bytes per input vertex while partitioning (the position
/// table). The blocks stop at what the final in-core pass holds in
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
/// (nor on whether blocks ran here or as Ray tasks). Positions only:
/// normals, colours and UVs are not carried through the blocks.
///
/// Errors: a message naming the file: an input the stream reader refuses
/// ([`PlyStream`]), I/O in the staging folder, the simplifier refusing a
/// block. Cost: linear in the input; disk: 36 bytes per input face.
pub fn simplify_file(
    input: &Path,
    o: &ScaleOptions,
    progress: &(dyn Fn(Event) + Sync),
) -> Result<(TriMesh, Report), String> {
    let s = PlyStream::open(input).map_err(|e| e.to_string())?;
    o.runner.check()?;
    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |e: std::io::Error| format!("{}: {e}", p.display())
    };
    std::fs::create_dir_all(&o.staging).map_err(io(&o.staging))?;
    let mut rep = Report::default();
    let faces = s.face_records();
    let block_faces = (o.memory / (BLOCK_BYTES_PER_FACE * BLOCKS_IN_FLIGHT)).max(256);
    let blocks = faces.div_ceil(block_faces).max(2);
    let g = ((blocks as f64).cbrt().ceil() as u32).clamp(2, MAX_GRID);

    // Round 0: read positions, cut the faces into blocks.
    let r0 = o.staging.join("r0");
    let (min, max) = match read_manifest(&r0) {
        Some((min, max, counts)) => {
            rep.input_faces = counts.iter().sum();
            (min, max)
        }
        None => {
            let t = Instant::now();
            std::fs::create_dir_all(&r0).map_err(io(&r0))?;
            progress(Event::Phase("reading vertices", s.vertex_count()));
            let mut pos = Vec::with_capacity(s.vertex_count() as usize);
            let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
            s.for_each_position(|p| {
                lo = lo.min(p);
                hi = hi.max(p);
                pos.push(p);
                if pos.len().is_multiple_of(1 << 20) {
                    progress(Event::Advance(1 << 20));
                }
            })
            .map_err(|e| e.to_string())?;
            rep.phases
                .push(("read vertices".into(), t.elapsed().as_secs_f64()));
            let t = Instant::now();
            progress(Event::Phase("partitioning faces", faces));
            let grid = Grid::new(lo, hi, g, 0.0);
            let mut w = Writers::new(&r0, grid.blocks());
            let mut n = 0u64;
            s.for_each_face(|f| {
                let tri = f.map(|i| pos[i as usize]);
                n += 1;
                if n.is_multiple_of(1 << 20) {
                    progress(Event::Advance(1 << 20));
                }
                w.put(grid.block_of(&tri), tri)
                    .map_err(|e| lodkit_mesh::Error::Invalid(format!("{}: {e}", r0.display())))
            })
            .map_err(|e| e.to_string())?;
            drop(pos);
            let counts = w.finish().map_err(io(&r0))?;
            write_manifest(&r0, lo, hi, &counts).map_err(io(&r0))?;
            rep.input_faces = counts.iter().sum();
            rep.phases
                .push(("partition".into(), t.elapsed().as_secs_f64()));
            (lo, hi)
        }
    };
    rep.bytes_read += s.file_len();
    let target = o.simplify.target.faces(rep.input_faces as usize) as u64;

    // Block rounds: round 0 on the first grid; round 1, on the grid shifted
    // by half a block, only if the result still does not fit in memory.
    let mut dir = r0;
    let mut round = 0u32;
    let mut total;
    loop {
        let (_, _, counts) = read_manifest(&dir)
            .ok_or_else(|| format!("{}: staging manifest unreadable", dir.display()))?;
        let before: u64 = counts.iter().sum();
        let goal = round_goal(before, target, o.memory, round);
        let ratio = if before == 0 {
            1.0
        } else {
            goal as f64 / before as f64
        };
        let todo: Vec<usize> = (0..counts.len()).filter(|&b| counts[b] > 0).collect();
        let t = Instant::now();
        progress(Event::Phase(
            &format!("simplifying blocks (round {})", round + 1),
            before,
        ));
        // Blocks an interrupted run finished are not run again.
        let mut tasks = Vec::new();
        for &b in &todo {
            let output = block_output(&dir, b);
            if output.exists() {
                rep.resumed_blocks += 1;
                progress(Event::Advance(counts[b]));
            } else {
                tasks.push(BlockTask {
                    input: block_input(&dir, b),
                    output,
                    ratio,
                    faces: counts[b],
                });
            }
        }
        o.runner.run(&dir, &tasks, &o.simplify, &|i| {
            progress(Event::Advance(tasks[i].faces))
        })?;
        total = 0;
        for &b in &todo {
            let out = block_output(&dir, b);
            total += soup::faces_in(&out).map_err(io(&out))?;
        }
        rep.bytes_read += before * soup::FACE_BYTES;
        rep.bytes_written += (before + total) * soup::FACE_BYTES;
        rep.round_faces.push(total);
        rep.round_blocks.push(todo.len());
        rep.phases.push((
            format!("blocks round {}", round + 1),
            t.elapsed().as_secs_f64(),
        ));
        if round == 1 || total * crate::IN_CORE_BYTES_PER_FACE <= o.memory {
            break;
        }
        // Re-partition the outputs on the shifted grid.
        let next = o.staging.join(format!("r{}", round + 1));
        if read_manifest(&next).is_none() {
            let t = Instant::now();
            std::fs::create_dir_all(&next).map_err(io(&next))?;
            progress(Event::Phase("re-partitioning on the shifted grid", total));
            let grid = Grid::new(min, max, g, 0.5);
            let mut w = Writers::new(&next, grid.blocks());
            for &b in &todo {
                let p = block_output(&dir, b);
                let mut err = Ok(());
                soup::for_each(&p, |tri| {
                    if err.is_ok() {
                        err = w.put(grid.block_of(&tri), tri);
                    }
                })
                .and(err)
                .map_err(io(&p))?;
            }
            let counts = w.finish().map_err(io(&next))?;
            write_manifest(&next, min, max, &counts).map_err(io(&next))?;
            rep.phases
                .push(("re-partition".into(), t.elapsed().as_secs_f64()));
        }
        dir = next;
        round += 1;
    }

    // Final pass: the whole reduced mesh in core, to the target.
    let t = Instant::now();
    progress(Event::Phase("final pass on the merged blocks", total));
    let (_, _, counts) = read_manifest(&dir)
        .ok_or_else(|| format!("{}: staging manifest unreadable", dir.display()))?;
    let mut w = Welder::default();
    for b in (0..counts.len()).filter(|&b| counts[b] > 0) {
        let p = block_output(&dir, b);
        soup::for_each(&p, |tri| w.add(tri)).map_err(io(&p))?;
    }
    let merged = w.finish();
    let opts = Options {
        target: Target::Faces(target as usize),
        ..o.simplify.clone()
    };
    let out = Simplifier::new()
        .simplify(&merged, &opts)
        .map_err(|e| format!("{}: {e}", input.display()))?;
    progress(Event::Advance(total));
    rep.phases
        .push(("final pass".into(), t.elapsed().as_secs_f64()));
    rep.last = Some(out.report);
    Ok((out.mesh, rep))
}

/// Writes a round's manifest (bounding box and per-block face counts)
/// atomically: its presence means the round's block inputs are complete.
fn write_manifest(dir: &Path, min: Vec3, max: Vec3, counts: &[u64]) -> std::io::Result<()> {
    let mut s = String::new();
    for c in min.to_array().into_iter().chain(max.to_array()) {
        s.push_str(&format!("{:08x} ", c.to_bits()));
    }
    s.push('\n');
    for c in counts {
        s.push_str(&format!("{c}\n"));
    }
    let tmp = dir.join("parted.partial");
    std::fs::write(&tmp, s)?;
    std::fs::rename(tmp, dir.join("parted"))
}

fn read_manifest(dir: &Path) -> Option<(Vec3, Vec3, Vec<u64>)> {
    let s = std::fs::read_to_string(dir.join("parted")).ok()?;
    let mut lines = s.lines();
    let bb: Vec<f32> = lines
        .next()?
        .split_whitespace()
        .map(|w| u32::from_str_radix(w, 16).map(f32::from_bits))
        .collect::<Result<_, _>>()
        .ok()?;
    if bb.len() != 6 {
        return None;
    }
    let counts = lines
        .map(|l| l.parse().ok())
        .collect::<Option<Vec<u64>>>()?;
    Some((
        Vec3::new(bb[0], bb[1], bb[2]),
        Vec3::new(bb[3], bb[4], bb[5]),
        counts,
    ))
}
