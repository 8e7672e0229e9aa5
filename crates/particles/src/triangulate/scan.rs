//! The brick/window scan — §6.1.1 of Yemez & Schmitt, with the
//! construction rules of §6.1.3 and the disambiguation of §6.2 applied to
//! each neighbourhood as it is met.
//!
//! Every occupied brick of the level is loaded into a [`Window`]; its
//! neighbourhood origins with three ON cubes or more are found four rows at
//! a time with a bit-sliced count, and each one's configuration (the 256
//! cases of [`crate::triangulation_table`]) says what to build: a triangle
//! (`C_1–C_3`), a quad split ([`super::quad_choice`]), or a solid, whose
//! hull is cut by [`super::hamiltonian_split`] from the edges it shares
//! with its neighbours ([`super::shared_edges`]) or left to
//! [`super::settle`].
use super::decimate::merge_short_edge;
use super::hamiltonian_split::{Split, smoother_disc, split_by_cycle};
use super::quad_choice::{choose_quad, defer_face};
use super::settle::{SETTLE_SKIP_CLASS, Scanned, Trial, all_bits};
use super::shared_edges::{SHARED_MEMO_BITS, shared_edges};
use super::window::{Bricks, EXT, ROW_GROUPS, Window, owns};
use super::{NONE, TriangulateOptions, TriangulationStats};
use crate::level_surface::LevelSurface;
use crate::triangulation_table::{CLASS_COUNT, Compact, Shape, table};

/// Scans every occupied brick of the level (`cells`: strictly increasing
/// Morton codes; `order`: the surface's vertex of each when it was not
/// sorted). `trace` gets, per triangle built, its neighbourhood's class.
#[inline]
pub(super) fn scan(
    s: &LevelSurface,
    cells: &[u64],
    order: Option<&[u32]>,
    level: &Bricks,
    opts: &TriangulateOptions,
    mut trace: Option<&mut Vec<u8>>,
) -> Scanned {
    let mut stats = TriangulationStats {
        configurations: vec![0; CLASS_COUNT + 1],
        ..Default::default()
    };
    // Vertex (sorted order) → vertex of `s`.
    let vid = |v: u32| order.map_or(v, |o| o[v as usize]);
    // A closed surface has about two triangles per cube; duplicates
    // (dropped at the end) and non-manifold hulls add a few: room for
    // them, so the vector is never regrown (a copy plus fresh pages).
    let mut faces: Vec<[u32; 3]> = Vec::with_capacity(cells.len() * 2 + cells.len() / 8 + 64);
    let mut merges: Vec<(u32, u32)> = Vec::new();
    // Triangles built by solid configurations: the only ones two
    // neighbourhoods can both build (planar faces have one owner).
    let mut from_solids: Vec<u32> = Vec::new();
    // Cubes already merged (§6.3 merges pairs of nodes; chains of merges
    // would drift by more than a cube).
    let mut merged = vec![
        false;
        if opts.decimate.is_some() {
            s.cells.len()
        } else {
            0
        }
    ];
    let cube = s.frame.cube(s.level);
    let min_edge = opts.decimate.map(|f| f * cube);
    let t = table();
    // Direct-mapped memo of `split_by_cycle` (1024 slots; key never 0 for
    // a solid, whose mask has four cubes or more).
    let mut cycles: Vec<(u64, Split)> = vec![(0, Split::Whole); 1 << 10];
    // Direct-mapped memo of `shared_edges` and the split it leads to,
    // keyed by the 4×4×4 cubes around the neighbourhood, which are all its
    // overlapping neighbourhoods read (key never 0 around a solid).
    let mut shared_memo: Vec<(u64, Split)> = vec![(0, Split::Whole); 1 << SHARED_MEMO_BITS];
    let mut trials: Vec<Trial> = Vec::new();
    let Bricks {
        bricks,
        keys,
        index,
    } = level;
    let mut w = Window::new();
    // First face each brick built (see [`super::settle::settle_ranges`]).
    let mut brick_faces: Vec<u32> = Vec::with_capacity(keys.len() + 1);
    // Neighbourhoods per class (a fixed array: no bounds check per count).
    let mut configurations = [0u64; 32];
    for (qi, &q) in keys.iter().enumerate() {
        brick_faces.push(faces.len() as u32);
        let first = bricks[qi].base[0] as usize;
        let end = bricks
            .get(qi + 1)
            .map_or(cells.len(), |b| b.base[0] as usize);
        w.load(q, bricks, index, first, &cells[first..end]);
        for oz in 1..10usize {
            // Origins y = −1..8 (1..10 extended) four at a time
            // (`oy0..oy0 + 4`), a row of 16 bits each ([`Window::rows4`]).
            for (oy0, lanes) in ROW_GROUPS {
                let r = [
                    w.rows4(oy0 + EXT * oz),
                    w.rows4(oy0 + 1 + EXT * oz),
                    w.rows4(oy0 + EXT * (oz + 1)),
                    w.rows4(oy0 + 1 + EXT * (oz + 1)),
                ];
                // Most rows of a window miss the surface.
                if (r[0] | r[1] | r[2] | r[3]) & (lanes * 0x7fe) == 0 {
                    continue;
                }
                // Origins x = −1..8 (1..10 extended) whose neighbourhood
                // has three ON cubes or more: a bit-sliced count of the
                // eight cubes of all origins of the four rows at once
                // (bitwise: the bit a shift moves across rows lands on
                // no origin).
                let (mut ones, mut twos, mut fours) = (0u64, 0u64, 0u64);
                for x in [
                    r[0],
                    r[0] >> 1,
                    r[1],
                    r[1] >> 1,
                    r[2],
                    r[2] >> 1,
                    r[3],
                    r[3] >> 1,
                ] {
                    let carry = ones & x;
                    ones ^= x;
                    fours |= twos & carry;
                    twos ^= carry;
                }
                let mut any = (fours | (twos & ones)) & (lanes * 0x3fe);
                // Origins in a brick below (extended 1 on an axis): only
                // those this brick owns are kept, tested first so that the
                // loop below has no test.
                let mut lower = any
                    & match (oz, oy0) {
                        (1, _) => u64::MAX,
                        (_, 1) => (lanes * 2) | 0x3fe,
                        _ => lanes * 2,
                    };
                while lower != 0 {
                    let bit = lower.trailing_zeros() as usize;
                    lower &= lower - 1;
                    let (ox, oy) = (bit & 15, oy0 + (bit >> 4));
                    let below =
                        u8::from(ox == 1) | (u8::from(oy == 1) << 1) | (u8::from(oz == 1) << 2);
                    if !owns(&w, [ox, oy, oz], below) {
                        any &= !(1 << bit);
                    }
                }
                while any != 0 {
                    let bit = any.trailing_zeros() as usize;
                    any &= any - 1;
                    let (ox, oy) = (bit & 15, oy0 + (bit >> 4));
                    let o = [ox, oy, oz];
                    // `w.mask(o)`, from the rows at hand.
                    let pair = |r: u64| ((r >> bit) & 3) as u8;
                    let mask =
                        pair(r[0]) | (pair(r[1]) << 2) | (pair(r[2]) << 4) | (pair(r[3]) << 6);
                    debug_assert_eq!(mask, w.mask(o));
                    // Three ON cubes or more (`any`): a class.
                    let c = t.compact[mask as usize];
                    debug_assert!(c.class != 0);
                    configurations[usize::from(c.class) & 31] += 1;
                    if c.face != 0 && defer_face(t, &w, o, c.face) {
                        continue;
                    }
                    let mut vs = w.corners(o, mask);
                    if order.is_some() {
                        for v in &mut vs {
                            if *v != NONE {
                                *v = vid(*v);
                            }
                        }
                    }
                    // Corners index `vs` masked: no bounds check.
                    let vertex = |j: u8| vs[usize::from(j & 7)];
                    let mut emit = |tri: [u8; 3], faces: &mut Vec<[u32; 3]>| -> bool {
                        let f = [vertex(tri[0]), vertex(tri[1]), vertex(tri[2])];
                        if let Some(min) = min_edge
                            && merge_short_edge(f, min, &s.positions, &mut merged, &mut merges)
                        {
                            return false;
                        }
                        faces.push(f);
                        true
                    };
                    // A solid left whole (no unique cycle).
                    let mut whole = false;
                    let q = c.corners;
                    if c.kind == Compact::TRIANGLE {
                        emit([q[0], q[1], q[2]], &mut faces);
                    } else if c.kind == Compact::QUAD {
                        let vq = [0, 1, 2, 3].map(|k| vertex(q[k]) as usize);
                        let pos = [0, 1, 2, 3].map(|k| s.positions[vq[k]]);
                        let nrm = s.normals.as_ref().map(|n| [0, 1, 2, 3].map(|k| n[vq[k]]));
                        let (t1, t2) = choose_quad(q, pos, nrm);
                        emit(t1, &mut faces);
                        emit(t2, &mut faces);
                    } else {
                        let cfg = &t.configs[mask as usize];
                        let Shape::Solid(tris) = &cfg.shape else {
                            unreachable!("three ON cubes or more, not planar")
                        };
                        {
                            let around = w.block(o);
                            let slot = &mut shared_memo[(around.wrapping_mul(0x9e37_79b9_7f4a_7c15)
                                >> (64 - SHARED_MEMO_BITS))
                                as usize];
                            if slot.0 != around {
                                let (shared, twice) = shared_edges(around, mask);
                                // §6.2's cycle search depends on the
                                // configuration and its shared edges only:
                                // memoised too, over all blocks.
                                let key = u64::from(shared)
                                    | (u64::from(twice) << 28)
                                    | (u64::from(mask) << 56);
                                let cycle = &mut cycles
                                    [(key.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 54) as usize];
                                if cycle.0 != key {
                                    *cycle = (key, split_by_cycle(mask, shared, twice, tris));
                                }
                                *slot = (around, cycle.1);
                            }
                            let split = slot.1;
                            // Triangles on a face of the neighbourhood (three
                            // cubes sharing a coordinate) may be built by the
                            // solid across that face too.
                            let mut solid_emit = |tri: [u8; 3], faces: &mut Vec<[u32; 3]>| {
                                if emit(tri, faces)
                                    && !((tri[0] ^ tri[1]) | (tri[0] ^ tri[2])) & 7 != 0
                                {
                                    from_solids.push(faces.len() as u32 - 1);
                                }
                            };
                            // With decimation, whose merges follow the
                            // scan, every solid is built at once; without,
                            // the choices are settled once the level is
                            // scanned (see [`settle`]).
                            let settled = opts.decimate.is_none()
                                && (cfg.class != SETTLE_SKIP_CLASS
                                    || matches!(split, Split::Holding(..) | Split::Whole));
                            let mut resolved = |keep: u16, faces: &mut Vec<[u32; 3]>| {
                                let keep = keep & all_bits(tris.len());
                                if settled {
                                    trials.push(Trial { vs, mask, keep });
                                    return;
                                }
                                stats.disambiguated += 1;
                                for (i, &tri) in tris.iter().enumerate() {
                                    if keep & (1 << i) != 0 {
                                        solid_emit(tri, faces);
                                    }
                                }
                            };
                            match split {
                                Split::Either(disc) => {
                                    // Hull corners are ON: `vs` holds their
                                    // vertices.
                                    let pos = |j: u8| s.positions[vs[usize::from(j & 7)] as usize];
                                    let keep = if smoother_disc(tris, &cfg.adjacent, disc, &pos) {
                                        disc
                                    } else {
                                        !disc
                                    };
                                    resolved(keep, &mut faces);
                                }
                                Split::Only(keep) => resolved(keep, &mut faces),
                                Split::Holding(keep, _) if settled => resolved(keep, &mut faces),
                                Split::Whole if settled => resolved(u16::MAX, &mut faces),
                                Split::Whole | Split::Holding(..) => {
                                    whole = true;
                                    stats.fallbacks += 1;
                                    for &tri in tris {
                                        solid_emit(tri, &mut faces);
                                    }
                                }
                            }
                        }
                    }
                    if let Some(tr) = trace.as_deref_mut() {
                        tr.resize(faces.len(), c.class | if whole { 0x80 } else { 0 });
                    }
                }
            }
        }
    }
    stats
        .configurations
        .copy_from_slice(&configurations[..=CLASS_COUNT]);
    // The ambiguous solids, settled against everything else built.
    brick_faces.push(faces.len() as u32);
    Scanned {
        faces,
        merges,
        from_solids,
        trials,
        brick_faces,
        stats,
    }
}
