//! The tileset of a binary PLY too big for memory, built without ever
//! holding the input or a whole level: the same octree, levels, skirts
//! and files as [`tileset_from_mesh`](crate::tileset_from_mesh), with the
//! differences below.
//!
//! 1. **Partition** (one stream over the input's faces): faces are
//!    counted per cell of a fixed fine depth (a map of occupied cells,
//!    bounded by the cells, not the faces; the depth is deepened while a
//!    fine cell still holds more than a leaf and the map stays under an
//!    eighth of the budget), and the adaptive octree is built from the
//!    counts. Cells by centroid at the fine depth nest exactly into the
//!    cells of every shallower depth (the grid scales by powers of two),
//!    so the tree is the in-core one wherever that one stops above the
//!    fine depth.
//! 2. **Levels** ([`lodkit_scale::lod_chain_file`]): level `D` is the
//!    input file itself, no copy; each level above is the whole previous
//!    level simplified in one global error order as far as memory allows
//!    (block rounds on shifted grids for levels over the budget, the in-
//!    core chain once a level fits). The targets are fixed before the
//!    chain starts, so each depth's ratio is the in-core rule applied to
//!    the input's counts scaled by the ratios below it, not to the
//!    previous level's own counts.
//! 3. **Spill** (`cell_spill.rs`): the input, then each level as the
//!    chain hands it over, is streamed once and its faces distributed by
//!    centroid into one soup file per cell of its depth, through buffers
//!    of an eighth of the budget. Tiles are then made two at a time (one
//!    depth after the other, the tiles of a depth in parallel): a
//!    cell's faces welded, refitted to the budget with the border locked
//!    when over it (as in core), normals where the input has none.
//! 4. **Cuts** for the skirts: no whole level is ever in memory to tell a
//!    cut from a border of the input, so a tile's border edge counts as
//!    a cut when it lies within twice its face's longest edge of the
//!    cell's boundary (a cut edge's other face has its centroid across
//!    that boundary). A rim of the input near a cell's boundary gets a
//!    skirt too, which hangs below the surface and costs four triangles
//!    per edge.
//! 5. **Errors** without the whole input (`tile_error.rs`), once every
//!    tile of a depth is staged: a tile whose cell holds few enough input
//!    faces (an eighth of the budget at `MEASURE_BYTES_PER_FACE`, twice
//!    over for the neighbourhood) is measured as in core: against the
//!    input near its cell (its own and its neighbours' leaves' tiles,
//!    cropped), and the input of its cell against its depth's staged
//!    tiles near it (and the level's faces spilled under leaves at or
//!    above that depth). A tile `N` above that is measured the same way
//!    with the tiles one depth down `R` standing for the input, and
//!    `geometricError(N) = d(N, R) + max over the tiles of R used of
//!    their geometricError`. By the triangle inequality this bounds `N`'s
//!    distance from the input from above: an honest `geometricError`,
//!    looser than in core by the errors of the levels below. Leaves 0
//!    (plus rounding, as in core). Measured on a 10⁷-face blob at
//!    `--memory 1G`: the root's `geometricError` 0.0057 (the in-core
//!    path's measure on a 10⁶-face blob is 0.0030).
//! 6. **Write**: each staged tile is read back, its skirts hung, encoded
//!    on its depth's grid, through the same output-folder rule as in
//!    core. Bounding boxes include where skirts may hang (each tile's box
//!    widened by the skirt depth along the range of its cut vertices'
//!    normals), known before any skirt is made.
//!
//! # Resuming
//! Everything lives in the staging folder the caller names, locked for
//! the run ([`lodkit_scale::StagingLock`]): `chain/` (the scale chain's
//! blocks), `cells/` (spills, each marked done when complete), `tiles/`
//! (staged tiles, each depth marked done with its nodes' errors and
//! boxes). A rerun skips every finished spill and depth and redoes the
//! rest; the bytes are the same. The folder is removed once the tileset
//! is in place.
//!
//! # Cost
//! Memory: the cell map, the octree, one level in core once it fits the
//! budget (the chain's rule), the spill buffers (an eighth of the
//! budget), two tiles and their neighbourhoods. Disk: the chain's (36 B
//! per face of the largest level, twice) plus each level once more as
//! spills (36 B per face) and the staged tiles. Time: the chain, four
//! streams over the input, one weld of every tile and one measurement of
//! every internal tile against its neighbourhood (the staged tiles
//! around it are read again for it).

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use glam::Vec3;
use lodkit_mesh::Aabb;
use lodkit_mesh::io::ply::stream::PlyStream;
use lodkit_scale::soup::{Corner, Layout};
use lodkit_scale::{ChainLevel, Event as ScaleEvent, Runner, ScaleOptions, StagingLock};
use lodkit_simplify::{Options, Simplifier, Target};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

mod tile_pass;

use self::tile_pass::{IN_FLIGHT, TileCtx, tile_file};
use crate::cell_spill::{Spill, StagedTile};
use crate::octree_partition::{CellKey, Grid, MAX_DEPTH, Node, Octree};
use crate::tileset_json::{NodeInfo, Refine};
use crate::{Error, Result, TilesOptions, TilesReport, check_option, skirts};

/// Where and in how much memory an out-of-core tileset is built.
#[derive(Clone, Debug)]
pub struct OutOfCoreOptions {
    /// Memory budget in bytes (`lodkit_scale::default_memory` by default
    /// in the front-ends).
    pub memory: u64,
    /// The staging folder: created and locked for the run, removed after
    /// success, kept after a failure so that the same call resumes
    /// (`lodkit_scale::staging_dir` gives one keyed by input and options).
    pub staging: PathBuf,
    /// Where the chain's blocks run; the bytes are the same either way.
    pub runner: Runner,
}

/// Bytes per input face the in-core tiler
/// ([`tileset_from_mesh`](crate::tileset_from_mesh) then
/// [`write_tileset`](crate::write_tileset)) peaks at, about: measured 380
/// on a 10⁶-face blob with the default leaves (the input, the levels, the
/// edge tables of the cut, one copy of the input per depth while
/// measuring). Front-ends go out of core when a file's faces times this
/// exceed the memory budget.
pub const IN_CORE_BYTES_PER_FACE: u64 = 400;

/// What a progress callback of [`tileset_out_of_core`] receives: a phase
/// with its amount of work (faces or tiles), then advances.
pub type OutOfCoreEvent<'a> = ScaleEvent<'a>;

/// The message by which a level handler asks for a restart (a level an
/// interrupted run handed over before its spill was complete).
const RESTART: &str = "lodkit-tiles: staging spill incomplete, restart";

/// Bytes per face of a measurement region (the mesh and its distance
/// index, about 150, with room): a tile whose cell's input fits a
/// quarter of the budget at this rate, shared by the tiles in flight, is
/// measured against that input
/// directly, as in core; one above it through its children's tiles.
const MEASURE_BYTES_PER_FACE: u64 = 200;

/// Bytes a tile being written holds per face (its staged mesh with
/// normals, its skirts, the encoder's buffers and the GLB), with room.
const WRITE_BYTES_PER_FACE: u64 = 200;

/// A stream of faces handed to a sink (which may fail).
type Faces<'a> = dyn FnMut(&mut dyn FnMut(&[Corner; 3]) -> Result<()>) -> Result<()> + 'a;

/// Faces between progress advances.
const ADVANCE_EVERY: u64 = 1 << 16;

/// Builds the tileset of the binary PLY mesh `input` (y-up, object units)
/// into the folder `out` in about `o.memory` bytes, whatever the input's
/// size; see the module docs for the pipeline, the errors and the
/// resume. `out` follows [`write_tileset`](crate::write_tileset)'s rule
/// (absent, empty or lodkit's; written whole or not at all).
///
/// Guarantees: leaves are the input at full resolution; every tile's
/// `geometricError` is at least its measured distances, both ways (see
/// `tile_error.rs`; an upper bound through the tiles below, see the
/// module docs); the same input, options and budget give the same bytes, also
/// after an interrupted run is resumed; nothing is left in the staging
/// folder after success. Errors: an input the stream reader refuses (not
/// a binary PLY, a bad face), no faces, a leaf option out of range
/// ([`Error::Usage`]), another run holding the staging folder, I/O, a
/// failed simplification. Cost: see the module docs.
pub fn tileset_out_of_core(
    input: &Path,
    out: &Path,
    opts: &TilesOptions,
    o: &OutOfCoreOptions,
    progress: &(dyn Fn(OutOfCoreEvent) + Sync),
) -> Result<TilesReport> {
    check_option(
        "leaf triangles",
        opts.leaf_triangles,
        &TilesOptions::LEAF_TRIANGLES,
    )?;
    // A file the stream reader refuses, or an output folder that is not
    // lodkit's, is refused before any staging.
    PlyStream::open(input)?;
    drop(lodkit_mesh::io::out_folder::Staging::new(out, Some(input))?);
    let lock = StagingLock::take(&o.staging).map_err(Error::Input)?;
    let report = match build(input, out, opts, o, progress)? {
        Some(r) => r,
        None => {
            // A level handed over by an interrupted run whose spill is
            // gone: start this staging folder over, once.
            for sub in ["chain", "cells", "tiles"] {
                let p = o.staging.join(sub);
                if p.exists() {
                    std::fs::remove_dir_all(&p).map_err(|source| Error::Io { path: p, source })?;
                }
            }
            build(input, out, opts, o, progress)?
                .ok_or_else(|| Error::Input(format!("{}: {RESTART}", o.staging.display())))?
        }
    };
    drop(lock);
    lodkit_scale::remove_staging(&o.staging).map_err(Error::Input)?;
    Ok(report)
}

fn io_err(path: &Path) -> impl Fn(std::io::Error) -> Error + '_ {
    move |source| Error::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// One face's centroid, as the in-core partition computes it.
fn centroid(t: &[Corner; 3]) -> Vec3 {
    (t[0].position + t[1].position + t[2].position) / 3.0
}

/// A cell's Morton code at its depth (x in the lowest bit of each
/// triple), so codes sorted group every cell's children in octant order.
fn morton(k: CellKey) -> u64 {
    let mut code = 0u64;
    for b in 0..k.depth as u32 {
        for (a, v) in k.xyz.iter().enumerate() {
            code |= (((v >> b) & 1) as u64) << (3 * b as usize + a);
        }
    }
    code
}

/// Calls `f` with every face of `stream` as three corners.
fn for_each_corners(
    stream: &PlyStream,
    cache: usize,
    mut f: impl FnMut(&[Corner; 3]) -> Result<()>,
) -> Result<()> {
    let mut reader = stream.vertex_reader(cache)?;
    let mut failed = None;
    let r = stream.for_each_face(|face| {
        let t = [
            reader.get(face[0])?,
            reader.get(face[1])?,
            reader.get(face[2])?,
        ];
        if let Err(e) = f(&t) {
            failed = Some(e);
            return Err(lodkit_mesh::Error::Invalid("stopped".into()));
        }
        Ok(())
    });
    match (failed, r) {
        (Some(e), _) => Err(e),
        (None, r) => Ok(r?),
    }
}

/// The octree from face counts per cell of depth `fine` (Morton codes),
/// and the leaf of each fine cell. Nodes in breadth-first order, children
/// in octant order, split while over `leaf` faces and above `fine`: the
/// in-core rule.
fn octree_from_counts(
    grid: Grid,
    counts: FxHashMap<u64, u64>,
    fine: u8,
    leaf: usize,
) -> (Octree, FxHashMap<u64, u32>) {
    let mut cells: Vec<(u64, u64)> = counts.into_iter().collect();
    cells.sort_unstable();
    let total: u64 = cells.iter().map(|c| c.1).sum();
    let mut nodes = vec![Node {
        key: CellKey::ROOT,
        children: Vec::new(),
        input_faces: total as usize,
    }];
    let mut leaf_of = FxHashMap::default();
    let mut queue = std::collections::VecDeque::from([(0usize, 0..cells.len())]);
    let mut depth = 0;
    while let Some((n, range)) = queue.pop_front() {
        let key = nodes[n].key;
        depth = depth.max(key.depth);
        if nodes[n].input_faces <= leaf || key.depth >= fine {
            for c in &cells[range] {
                leaf_of.insert(c.0, n as u32);
            }
            continue;
        }
        let shift = 3 * (fine - key.depth - 1) as u32;
        let mut start = range.start;
        while start < range.end {
            let octant = (cells[start].0 >> shift) & 7;
            let mut end = start;
            let mut faces = 0;
            while end < range.end && (cells[end].0 >> shift) & 7 == octant {
                faces += cells[end].1;
                end += 1;
            }
            let id = nodes.len();
            nodes.push(Node {
                key: key.child(octant as usize),
                children: Vec::new(),
                input_faces: faces as usize,
            });
            nodes[n].children.push(id);
            queue.push_back((id, start..end));
            start = end;
        }
    }
    (
        Octree {
            grid,
            nodes,
            leaf_of_face: Vec::new(),
            depth,
        },
        leaf_of,
    )
}

/// Per node, what the write needs from the tile pass.
#[derive(Clone, Copy, Debug)]
struct Staged {
    error: f64,
    /// How far its border may lie from a neighbour's (`skirts::border_reach`).
    reach: f64,
    bbox: Aabb,
    /// Range of the cut vertices' normals (empty box: no cuts).
    normals: Aabb,
    faces: usize,
    cuts: usize,
}

impl Staged {
    fn line(&self, node: usize) -> String {
        let mut s = format!(
            "{node} {:016x} {:016x} {} {}",
            self.error.to_bits(),
            self.reach.to_bits(),
            self.faces,
            self.cuts
        );
        for v in [
            self.bbox.min,
            self.bbox.max,
            self.normals.min,
            self.normals.max,
        ] {
            for x in v.to_array() {
                s += &format!(" {:08x}", x.to_bits());
            }
        }
        s
    }

    fn parse(line: &str) -> Option<(usize, Staged)> {
        let w: Vec<&str> = line.split(' ').collect();
        if w.len() != 17 {
            return None;
        }
        let f = |i: usize| u32::from_str_radix(w[i], 16).ok().map(f32::from_bits);
        let v = |i: usize| Some(Vec3::new(f(i)?, f(i + 1)?, f(i + 2)?));
        let f64_at = |i: usize| u64::from_str_radix(w[i], 16).ok().map(f64::from_bits);
        Some((
            w[0].parse().ok()?,
            Staged {
                error: f64_at(1)?,
                reach: f64_at(2)?,
                faces: w[3].parse().ok()?,
                cuts: w[4].parse().ok()?,
                bbox: Aabb {
                    min: v(5)?,
                    max: v(8)?,
                },
                normals: Aabb {
                    min: v(11)?,
                    max: v(14)?,
                },
            },
        ))
    }
}

fn bbox_of<'a>(points: impl IntoIterator<Item = &'a Vec3>) -> Aabb {
    let mut b = Aabb::EMPTY;
    for p in points {
        b.min = b.min.min(*p);
        b.max = b.max.max(*p);
    }
    b
}

/// The whole build; `None` when the staging folder must start over.
fn build(
    input: &Path,
    out: &Path,
    opts: &TilesOptions,
    o: &OutOfCoreOptions,
    progress: &(dyn Fn(OutOfCoreEvent) + Sync),
) -> Result<Option<TilesReport>> {
    let leaf = opts.leaf_triangles;
    let t0 = Instant::now();
    let stream = PlyStream::open(input)?;
    let attrs = stream.attributes();
    // Tiles carry positions, normals and colours (as in core, UVs aside).
    let layout = Layout {
        normals: attrs.normals,
        colors: attrs.colors,
        uvs: false,
    };
    let cache = (o.memory / 8).clamp(1 << 20, 512 << 20) as usize;
    let buffers = (o.memory / 8).clamp(1 << 20, 1 << 30) as usize;

    // 1. Partition: the bounding cube, then counts per fine cell.
    progress(ScaleEvent::Phase(
        "partition: bounds",
        stream.vertex_count(),
    ));
    let mut bounds = Aabb::EMPTY;
    stream.for_each_position(|p| {
        bounds.min = bounds.min.min(p);
        bounds.max = bounds.max.max(p);
    })?;
    progress(ScaleEvent::Advance(stream.vertex_count()));
    let grid = Grid::around(&bounds);
    let records = stream.face_records().max(1);
    let mut fine =
        (((records as f64 / leaf as f64).max(1.0).log(4.0).ceil() as u8) + 3).min(MAX_DEPTH);
    let max_cells = (o.memory / 8 / 48).max(1 << 16) as usize;
    let (counts, faces) = loop {
        progress(ScaleEvent::Phase("partition: faces per cell", records));
        let mut counts: FxHashMap<u64, u64> = FxHashMap::default();
        let mut faces = 0u64;
        for_each_corners(&stream, cache, |t| {
            *counts
                .entry(morton(grid.cell_of(centroid(t), fine)))
                .or_insert(0) += 1;
            faces += 1;
            if faces.is_multiple_of(ADVANCE_EVERY) {
                progress(ScaleEvent::Advance(ADVANCE_EVERY));
            }
            Ok(())
        })?;
        progress(ScaleEvent::Advance(faces % ADVANCE_EVERY));
        let over = counts.values().any(|&c| c as usize > leaf);
        if !over || fine >= MAX_DEPTH || counts.len().saturating_mul(16) > max_cells {
            break (counts, faces);
        }
        fine = (fine + 2).min(MAX_DEPTH);
    };
    if faces == 0 {
        return Err(Error::Input(format!(
            "{}: the mesh has no faces to tile",
            input.display()
        )));
    }
    let (tree, leaf_of) = octree_from_counts(grid, counts, fine, leaf);
    let t_partition = t0.elapsed().as_secs_f64();
    let d = tree.depth;
    let n = tree.nodes.len();
    let is_leaf = |i: usize| tree.nodes[i].children.is_empty();
    let cells = o.staging.join("cells");
    let tiles_dir = o.staging.join("tiles");
    for dir in [&cells, &tiles_dir] {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
    }

    // 2–3. Leaves: the input spilled by leaf.
    let t1 = Instant::now();
    let leaves_dir = cells.join("leaves");
    let leaves_done = cells.join("leaves.done");
    if !leaves_done.exists() {
        progress(ScaleEvent::Phase("leaves: the input by cell", faces));
        let mut spill = Spill::new(&leaves_dir, layout, n, buffers)?;
        let mut k = 0u64;
        for_each_corners(&stream, cache, |t| {
            let code = morton(grid.cell_of(centroid(t), fine));
            let node = leaf_of.get(&code).copied().ok_or_else(|| {
                Error::Input(format!("{}: changed while it was read", input.display()))
            })?;
            spill.put(node as usize, t)?;
            k += 1;
            if k.is_multiple_of(ADVANCE_EVERY) {
                progress(ScaleEvent::Advance(ADVANCE_EVERY));
            }
            Ok(())
        })?;
        progress(ScaleEvent::Advance(k % ADVANCE_EVERY));
        spill.finish(&leaves_done)?;
    }
    drop(leaf_of);

    // The levels: each depth's target from the in-core rule on scaled
    // input counts.
    let internal_at = |k: u8| -> Vec<usize> {
        (0..n)
            .filter(|&i| tree.nodes[i].key.depth == k && !is_leaf(i))
            .collect()
    };
    let mut targets = Vec::new();
    let mut scale = 1.0f64;
    for k in (0..d).rev() {
        let (mut want, mut have) = (0.0f64, 0.0f64);
        for i in internal_at(k) {
            let h = tree.nodes[i].input_faces as f64 * scale;
            want += (leaf as f64).min((h / 2.0).ceil());
            have += h;
        }
        scale *= if have > 0.0 { want / have } else { 0.5 };
        targets.push(Target::Faces(
            ((faces as f64 * scale).ceil() as usize).max(1),
        ));
    }
    let mut level_faces = vec![0usize; d as usize + 1];
    level_faces[d as usize] = faces as usize;
    if d > 0 {
        let so = ScaleOptions {
            simplify: Options::DEFAULT,
            memory: o.memory,
            staging: o.staging.join("chain"),
            runner: o.runner.clone(),
        };
        let spill_level = |k: u8, each: &mut Faces, total: u64| -> Result<()> {
            let dir = cells.join(format!("d{k}"));
            let slot: HashMap<CellKey, usize> = internal_at(k)
                .into_iter()
                .map(|i| (tree.nodes[i].key, i))
                .collect();
            progress(ScaleEvent::Phase(
                &format!("level {k}: faces by cell"),
                total,
            ));
            let mut spill = Spill::new(&dir, layout, n, buffers)?;
            let mut c = 0u64;
            each(&mut |t| {
                let key = tree.grid.cell_of(centroid(t), k);
                // Faces in the cell of a leaf at or above this depth are
                // kept under the leaf: what the level's tiles are measured
                // against there.
                if let Some(i) = slot.get(&key).copied().or_else(|| tree.leaf_holding(key)) {
                    spill.put(i, t)?;
                }
                c += 1;
                if c.is_multiple_of(ADVANCE_EVERY) {
                    progress(ScaleEvent::Advance(ADVANCE_EVERY));
                }
                Ok(())
            })?;
            progress(ScaleEvent::Advance(c % ADVANCE_EVERY));
            spill.finish(&cells.join(format!("d{k}.done")))
        };
        let result = lodkit_scale::lod_chain_file(input, &targets, &so, progress, &mut |i, l| {
            let k = d - 1 - i as u8;
            let done = cells.join(format!("d{k}.done"));
            let made = match l {
                ChainLevel::Resumed { faces } => {
                    level_faces[k as usize] = faces as usize;
                    if !done.exists() {
                        return Err(RESTART.into());
                    }
                    return Ok(());
                }
                ChainLevel::Soups {
                    faces,
                    layout: chain_layout,
                    files,
                } => {
                    level_faces[k as usize] = faces as usize;
                    if done.exists() {
                        return Ok(());
                    }
                    spill_level(
                        k,
                        &mut |put| {
                            for f in files {
                                let mut failed = None;
                                lodkit_scale::soup::for_each(f, chain_layout, |t| {
                                    if failed.is_none()
                                        && let Err(e) = put(t)
                                    {
                                        failed = Some(e);
                                    }
                                })
                                .map_err(io_err(f))?;
                                if let Some(e) = failed {
                                    return Err(e);
                                }
                            }
                            Ok(())
                        },
                        faces,
                    )
                }
                ChainLevel::Mesh { mesh, .. } => {
                    level_faces[k as usize] = mesh.faces.len();
                    if done.exists() {
                        return Ok(());
                    }
                    spill_level(
                        k,
                        &mut |put| {
                            for f in &mesh.faces {
                                put(&f.map(|v| lodkit_scale::soup::corner(mesh, v)))?;
                            }
                            Ok(())
                        },
                        mesh.faces.len() as u64,
                    )
                }
            };
            made.map_err(|e| e.to_string())
        });
        match result {
            Ok(_) => {}
            Err(e) if e == RESTART => return Ok(None),
            Err(e) => return Err(Error::Chain(e)),
        }
        // A chain that stalled (the simplifier could not go lower) made
        // fewer levels than the depths ask.
        if let Some(k) = (0..d).find(|k| !cells.join(format!("d{k}.done")).exists()) {
            return Err(Error::Chain(format!(
                "the level chain stopped before depth {k}'s level (the mesh cannot be simplified to {} faces); use a larger --leaf-triangles",
                level_target(&targets, d, k)
            )));
        }
    }
    let t_levels = t1.elapsed().as_secs_f64();

    // 4–5. Tiles, deepest depth first: weld, refit, cuts, measure.
    let t2 = Instant::now();
    let mut staged: Vec<Option<Staged>> = vec![None; n];
    let mut refitted = 0;
    let tile_path = |i: usize| tile_file(&tiles_dir, i);
    for k in (0..=d).rev() {
        let at: Vec<usize> = (0..n).filter(|&i| tree.nodes[i].key.depth == k).collect();
        let done = tiles_dir.join(format!("d{k}.done"));
        if let Ok(text) = std::fs::read_to_string(&done) {
            let mut ok = text.ends_with("end\n");
            for line in text.lines().filter(|l| *l != "end") {
                match Staged::parse(line) {
                    Some((i, s)) if i < n && tree.nodes[i].key.depth == k => staged[i] = Some(s),
                    _ => ok = false,
                }
            }
            if ok {
                continue;
            }
            at.iter().for_each(|&i| staged[i] = None);
        }
        // Each tile advances twice: made, then measured.
        progress(ScaleEvent::Phase(
            &format!("tiles at depth {k}: weld, refit, measure"),
            2 * at.len() as u64,
        ));
        // Tiles of one depth are independent (their children are staged):
        // made `IN_FLIGHT` at a time, then measured `IN_FLIGHT` at a time
        // (each against at most an `IN_FLIGHT`-th of the measurement
        // room), so the budget holds whatever the machine's thread count,
        // and the bytes too.
        let ctx = TileCtx {
            tree: &tree,
            leaves_dir: &leaves_dir,
            cells: &cells,
            tiles_dir: &tiles_dir,
            layout,
            leaf,
            direct_faces: o.memory / 4 / IN_FLIGHT as u64 / MEASURE_BYTES_PER_FACE,
        };
        for batch in at.chunks(IN_FLIGHT) {
            let part: Vec<Result<Option<(Staged, bool)>>> = batch
                .par_iter()
                .map_init(Simplifier::new, |simplifier, &i| {
                    let m = ctx.make(i, simplifier);
                    progress(ScaleEvent::Advance(1));
                    m
                })
                .collect();
            for (&i, m) in batch.iter().zip(part) {
                let m = m?;
                refitted += usize::from(m.is_some_and(|(_, r)| r));
                staged[i] = m.map(|(s, _)| s);
            }
        }
        // Then each internal tile's error, its neighbours staged.
        for batch in at.chunks(IN_FLIGHT) {
            let part: Vec<Result<f64>> = batch
                .par_iter()
                .map(|&i| {
                    let e = match staged[i] {
                        Some(_) if !is_leaf(i) => ctx.measure(i, &staged),
                        _ => Ok(0.0),
                    };
                    progress(ScaleEvent::Advance(1));
                    e
                })
                .collect();
            for (&i, e) in batch.iter().zip(part) {
                let e = e?;
                if let Some(s) = staged[i].as_mut() {
                    s.error = e;
                }
            }
        }
        let mut record = String::new();
        for &i in &at {
            if let Some(s) = staged[i] {
                record += &s.line(i);
                record.push('\n');
            }
        }
        record += "end\n";
        lodkit_mesh::io::write_atomic(&done, record.as_bytes())?;
        // This depth's spills are no longer needed.
        let spilled = if k == 0 && d == 0 {
            None
        } else {
            Some(cells.join(format!("d{k}")))
        };
        for &i in &at {
            if is_leaf(i) {
                let _ = std::fs::remove_file(Spill::file(&leaves_dir, i));
            }
        }
        if let Some(dir) = spilled {
            let _ = std::fs::remove_dir_all(dir);
        }
    }
    let t_measure = t2.elapsed().as_secs_f64();

    // 6. Boxes (with room for skirts), rounding, then the folder.
    let t3 = Instant::now();
    let mut parent = vec![0usize; n];
    for (i, node) in tree.nodes.iter().enumerate() {
        for &c in &node.children {
            parent[c] = i;
        }
    }
    let error = |i: usize| staged[i].map_or(0.0, |s| s.error);
    let skirt = |i: usize| {
        if i == 0 || !opts.skirts {
            0.0
        } else {
            let reach = |i: usize| staged[i].map_or(0.0, |s| s.reach);
            skirts::skirt_depth(
                [error(i), error(parent[i]), reach(i), reach(parent[i])],
                tree.grid.side(tree.nodes[i].key.depth),
            )
        }
    };
    let mut info: Vec<NodeInfo> = (0..n)
        .map(|i| {
            let bbox = staged[i].map_or(Aabb::EMPTY, |s| {
                let mut b = s.bbox;
                let depth = skirt(i) as f32;
                if s.cuts > 0 && depth > 0.0 {
                    b = b.union(&Aabb {
                        min: s.bbox.min - s.normals.max * depth,
                        max: s.bbox.max - s.normals.min * depth,
                    });
                }
                b
            });
            NodeInfo {
                bbox,
                error: if is_leaf(i) { 0.0 } else { error(i) },
                content: staged[i].is_some(),
            }
        })
        .collect();
    for i in (0..n).rev() {
        for c in tree.nodes[i].children.clone() {
            info[i].bbox = info[i].bbox.union(&info[c].bbox);
        }
    }
    crate::tile_content::add_rounding(&mut info, |i| tree.nodes[i].key.depth);
    let with_content: Vec<usize> = (0..n).filter(|&i| staged[i].is_some()).collect();
    let (mut max_tile, mut skirt_triangles) = (0, 0);
    for &i in &with_content {
        let s = staged[i].expect("content");
        max_tile = max_tile.max(s.faces);
        if skirt(i) as f32 > 0.0 {
            skirt_triangles += 4 * s.cuts;
        }
    }
    progress(ScaleEvent::Phase(
        "writing tiles",
        with_content.len() as u64,
    ));
    let names: Vec<(String, u8)> = with_content
        .iter()
        .map(|&i| (tree.nodes[i].key.name(), tree.nodes[i].key.depth))
        .collect();
    // A writer holds one staged tile, its skirts and its GLB.
    let per_tile = (max_tile as u64).saturating_mul(WRITE_BYTES_PER_FACE);
    let writers =
        (o.memory / 4 / per_tile.max(1)).clamp(1, crate::tileset_folder::MAX_WRITERS as u64);
    let bytes = crate::tileset_folder::write_folder(
        out,
        Some(input),
        (&tree, &info),
        (Refine::Replace, None),
        &names,
        writers as usize,
        &|k, grid| {
            let i = with_content[k];
            let t = StagedTile::read(&tile_path(i))?;
            let tile =
                crate::skirts::with_skirts(&t.mesh, &t.cuts, skirt(i) as f32, &mut Vec::new());
            crate::encode_tile(&names[k].0, &tile, opts.compress, grid)
        },
        &mut || progress(ScaleEvent::Advance(1)),
    )?;
    Ok(Some(TilesReport {
        input_triangles: faces as usize,
        tiles: with_content.len(),
        depth: d,
        level_triangles: level_faces,
        max_tile_triangles: max_tile,
        skirt_triangles,
        refitted_tiles: refitted,
        root_error: info[0].error,
        seconds: [t_partition, t_levels, t_measure, t3.elapsed().as_secs_f64()],
        bytes,
    }))
}

/// The face target of depth `k`'s level (`targets` run from depth
/// `d − 1` up to 0).
fn level_target(targets: &[Target], d: u8, k: u8) -> usize {
    match targets[(d - 1 - k) as usize] {
        Target::Faces(f) => f,
        Target::Ratio(_) => 0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_groups_children_in_octant_order() {
        let parent = CellKey {
            depth: 2,
            xyz: [1, 2, 3],
        };
        let codes: Vec<u64> = (0..8).map(|i| morton(parent.child(i))).collect();
        assert!(codes.windows(2).all(|w| w[0] < w[1]));
        assert!(codes.iter().all(|c| c >> 3 == morton(parent)));
    }
}
