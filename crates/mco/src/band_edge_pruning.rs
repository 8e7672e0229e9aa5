//! Band-edge pruning: no surface may reach the edge of the signed-distance
//! band, so marching cubes closes every surface it draws.
//!
//! Marching cubes draws triangles only in cubes whose 8 corners are all in
//! the band ([`crate::marching_cubes`]); its surface is closed wherever no
//! cube has a sign change among its defined corners *and* a missing
//! corner. Near the data the band is complete, but a vertex at its edge
//! (two to three and a half cubes from its closest sample, reached only by
//! the stamp of the sample's 26 neighbour cubes) takes the side of a
//! tangent plane it lies far along, and that side can be wrong: on closed
//! meshes such a vertex, alone among vertices of the other side, drew a
//! small bubble that the band's edge left open (a boundary loop of real
//! area at full resolution, so in every cut: the closed bunny at
//! resolutions 36, 107, 108, 131–133, the armadillo at 77, 118, 119, 127,
//! 131).
//!
//! The rule: while some cube has a missing corner and defined corners on
//! both sides, the defined corner of that cube farthest from its sample
//! (the least trustworthy guess; ties to the lower lattice key) is dropped
//! from the band, if it lies more than [`RELIABLE`] cubes from its sample.
//! Every drop removes a vertex, so the loop ends; at the end no sign
//! change touches a missing corner unless its corners are all near data.
//! A band with no such cube (the usual case) is left exactly as it was, so
//! its model is unchanged. Only closed meshes are pruned (the builder's
//! [`crate::pipeline::IncrementalBuilder::with_band_edge_pruning`]): a
//! scan's or an open mesh's surface ends at the band's edge by design.
//!
//! Cost: one pass over the band's vertices (a 9³ neighbourhood per brick),
//! plus one more per round of drops (rounds are rare and few).

use crate::lattice::{BRICK, BRICK_BITS};
use crate::signed_distance::SignedDistanceField;

/// Vertices at most this many cubes from their sample are never dropped:
/// every corner of a cube the surface crosses lies within about
/// `√3 + ½` cubes of a sample (samples half a cube apart on the surface),
/// so the pruning cannot eat into the surface itself, only trim guesses
/// farther out (the bubbles seen were 2.6–3.3 cubes from their samples).
const RELIABLE: f32 = 2.25;

/// A vertex's state in a cube test: missing, or defined on one side.
#[derive(Clone, Copy, PartialEq, Eq)]
enum Side {
    Missing,
    Inside,
    Outside,
}

/// The vertices to drop in one round: for every cube with a missing corner
/// and defined corners on both sides, its defined corner with the largest
/// squared distance to its sample, as `(brick, x, y, z)`. Sorted, deduplicated.
fn round(field: &SignedDistanceField) -> Vec<(usize, u32, u32, u32)> {
    const P: usize = BRICK as usize + 1;
    let cells = field.grid.cells();
    let reliable2 = (RELIABLE * field.grid.cube).powi(2);
    let mut drops = Vec::new();
    let mut side = [Side::Missing; P * P * P];
    let mut far = [0f32; P * P * P];
    let mut at = [(0usize, 0u32, 0u32, 0u32); P * P * P];
    for b in 0..field.brick_count() {
        let [bx, by, bz] = field.brick_coords(b).map(|c| c << BRICK_BITS);
        // The brick's vertices and the high faces' neighbours: every corner
        // of the cubes whose lowest corner lies in the brick.
        let mut any_missing = false;
        for k in 0..P {
            for j in 0..P {
                for i in 0..P {
                    let (x, y, z) = (bx + i as u32, by + j as u32, bz + k as u32);
                    let n = i + P * (j + P * k);
                    let vb = if i < P - 1 && j < P - 1 && k < P - 1 {
                        Some(b)
                    } else {
                        field.brick_of(x, y, z)
                    };
                    side[n] = Side::Missing;
                    if let Some(vb) = vb {
                        let s = field.slot_in(vb, x, y, z);
                        if field.slot_defined(&s) {
                            side[n] = if s.distance < 0.0 {
                                Side::Inside
                            } else {
                                Side::Outside
                            };
                            far[n] = s.dist2;
                            at[n] = (vb, x, y, z);
                        }
                    }
                    any_missing |= side[n] == Side::Missing;
                }
            }
        }
        if !any_missing {
            continue;
        }
        for k in 0..P - 1 {
            for j in 0..P - 1 {
                for i in 0..P - 1 {
                    if bx + i as u32 >= cells || by + j as u32 >= cells || bz + k as u32 >= cells {
                        continue;
                    }
                    let (mut missing, mut inside, mut outside) = (false, false, false);
                    let mut worst: Option<usize> = None;
                    for c in 0..8 {
                        let n = (i + (c & 1)) + P * ((j + (c >> 1 & 1)) + P * (k + (c >> 2)));
                        match side[n] {
                            Side::Missing => missing = true,
                            s => {
                                inside |= s == Side::Inside;
                                outside |= s == Side::Outside;
                                if worst.is_none_or(|w| far[n] > far[w]) {
                                    worst = Some(n);
                                }
                            }
                        }
                    }
                    if missing
                        && inside
                        && outside
                        && let Some(w) = worst
                        && far[w] > reliable2
                    {
                        drops.push(at[w]);
                    }
                }
            }
        }
    }
    drops.sort_unstable();
    drops.dedup();
    drops
}

/// `field` with its band-edge sheets pruned (see the module notes), or
/// `None` when no cube needs it (then the field is used as it is).
pub fn pruned(field: &SignedDistanceField) -> Option<SignedDistanceField> {
    let mut drops = round(field);
    if drops.is_empty() {
        return None;
    }
    let mut f = field.clone();
    while !drops.is_empty() {
        for &(b, x, y, z) in &drops {
            f.clear(b, x, y, z);
        }
        drops = round(&f);
    }
    Some(f)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lattice::{Grid, pack};
    use crate::marching_cubes::march;
    use crate::signed_distance::FieldVertex;
    use glam::Vec3;

    /// A 5³ block of inside vertices (a band with edges all round), with
    /// vertex `odd` outside when given: its one-vertex bubble.
    fn block(odd: Option<[u32; 3]>) -> SignedDistanceField {
        let b = lodkit_mesh::Aabb {
            min: Vec3::ZERO,
            max: Vec3::splat(16.0),
        };
        let mut f = SignedDistanceField::new(Grid::new(b, 16).unwrap());
        for z in 2..7 {
            for y in 2..7 {
                for x in 2..7 {
                    let out = odd == Some([x, y, z]);
                    let distance = if out { 0.1 } else { -1.0 };
                    f.set(
                        pack(x, y, z),
                        FieldVertex {
                            dist2: if out { 9.0 } else { 1.0 },
                            distance,
                            normal: Vec3::Z,
                            color: [0; 4],
                        },
                    );
                }
            }
        }
        f
    }

    #[test]
    fn a_band_without_edge_crossings_is_kept() {
        assert!(pruned(&block(None)).is_none());
        // A bubble inside the band is a closed surface: kept.
        let f = block(Some([4, 4, 4]));
        assert!(pruned(&f).is_none());
        assert_eq!(march(&f).1.len(), 8);
    }

    #[test]
    fn a_bubble_at_the_band_edge_is_dropped() {
        // On the block's face: the cubes beyond it have missing corners,
        // so marching cubes drew an open half bubble.
        let f = block(Some([6, 4, 4]));
        assert!(!march(&f).1.is_empty());
        let p = pruned(&f).expect("the open bubble is pruned");
        assert!(p.slot(pack(6, 4, 4)).is_none());
        assert!(p.slot(pack(5, 4, 4)).is_some());
        assert!(march(&p).1.is_empty());
    }
}
