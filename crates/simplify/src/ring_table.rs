//! The vertex-ring construction stage (HQMS §4.2) and the three flag tables
//! of Table 1.
//!
//! A ring `r_i` is the list of faces around vertex `v_i` (§3.2). The paper
//! stores each ring as its own heap array, reallocated once per incident
//! face while the faces are scanned. We build the same table in compressed
//! row form instead — one count pass, one prefix sum, one fill pass over the
//! faces, two flat `u32` arrays (`4 |V| + 12 |F|` bytes, the paper's
//! 29 B/vertex on average) — rebuilt at the start of every pass from the
//! compacted faces: no per-ring allocation, and ring memory is contiguous
//! for the pipeline's scan.
//!
//! Flags: the face flag of the paper is a sentinel in the face table itself
//! ([`DEAD`] in the first index) instead of a byte per face; the vertex flag
//! and the contraction flag share one byte per vertex ([`Flag`]).

/// First index of a deleted face.
pub const DEAD: u32 = u32::MAX;

/// The contraction state of a vertex ring (§4), plus "removed" (the
/// paper's vertex flag).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[repr(u8)]
pub enum Flag {
    /// May be contracted in this pass.
    Valid = 0,
    /// A dependent ring of a collapse performed in this pass (Strategy I:
    /// the two rings of the collapsed edge); not contracted again until the
    /// next pass.
    Dirty = 1,
    /// No valid contraction exists (locked border, no edge, isolated).
    Null = 2,
    /// The vertex was collapsed away.
    Removed = 3,
}

/// Bits of a ring entry that hold the corner (the face index is above).
pub const CORNER_BITS: u32 = 2;
/// Faces a ring table can address (the corner takes two bits of the entry).
pub const MAX_FACES: usize = 1 << (32 - CORNER_BITS);

/// A ring entry: face `e >> CORNER_BITS`, centre at corner `e & 3`.
pub type RingEntry = u32;

/// The face of a ring entry.
#[inline]
pub fn entry_face(e: RingEntry) -> u32 {
    e >> CORNER_BITS
}

/// The centre's corner in the face of a ring entry.
#[inline]
pub fn entry_corner(e: RingEntry) -> usize {
    (e & ((1 << CORNER_BITS) - 1)) as usize
}

/// Vertex → incident faces, compressed rows: the ring of `v` is
/// `list[off[v]..off[v + 1]]`, faces in increasing index order. Each entry
/// is a [`RingEntry`]: the face and the corner of `v` in it, so a scan
/// never searches a face for its centre (a three-way, badly predicted
/// branch per face in the hottest loop). A
/// corner stays valid for the whole pass for every ring that is read:
/// a collapse only rewrites the corners of `s` (then removed) and flags
/// `t` dirty, and neither ring is read again before the next rebuild.
#[derive(Debug, Clone, Default)]
pub struct RingTable {
    pub off: Vec<u32>,
    pub list: Vec<u32>,
}

impl RingTable {
    /// Rebuilds the table for `n` vertices from the live faces, reusing
    /// the allocations.
    pub fn rebuild(&mut self, n: usize, faces: &[[u32; 3]]) {
        self.off.clear();
        self.off.resize(n + 1, 0);
        // Plain slices in the loops: their bounds stay in registers.
        let off = &mut self.off[..];
        for f in faces {
            if f[0] == DEAD {
                continue;
            }
            for &v in f {
                off[v as usize + 1] += 1;
            }
        }
        let mut acc = 0;
        for x in off.iter_mut() {
            acc += *x;
            *x = acc;
        }
        // Every entry is written below: only grow (zero-filling the new
        // part), never clear, so later, smaller passes skip the fill.
        let len = off[n] as usize;
        if self.list.len() >= len {
            self.list.truncate(len);
        } else {
            self.list.resize(len, 0);
        }
        let list = &mut self.list[..];
        // Fill using off[v] as the cursor of row v - 1 … shifted below: after
        // the fill, off[v] holds the end of row v, i.e. the start of v + 1.
        for (fi, f) in faces.iter().enumerate() {
            if f[0] == DEAD {
                continue;
            }
            let e = (fi as u32) << CORNER_BITS;
            for (k, &v) in f.iter().enumerate() {
                let c = &mut off[v as usize];
                list[*c as usize] = e | k as u32;
                *c += 1;
            }
        }
        off.copy_within(0..n, 1);
        off[0] = 0;
    }

    #[inline]
    pub fn ring(&self, v: u32) -> &[RingEntry] {
        let v = v as usize;
        &self.list[self.off[v] as usize..self.off[v + 1] as usize]
    }

    /// Bytes held (for the memory accounting of the bench).
    pub fn heap_bytes(&self) -> usize {
        (self.off.capacity() + self.list.capacity()) * 4
    }
}

/// A vertex of a ring's boundary (`b_i` of §4.3.2) and the multiplicity of
/// the internal edge to it: how many of the ring's live faces contain it
/// (collected by `cost::RingScan`).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Link {
    pub v: u32,
    pub m: u32,
}

/// Multiplicity of the edge `(center, w)` in a link list (0 = no edge).
#[inline]
pub fn multiplicity(links: &[Link], w: u32) -> u32 {
    links.iter().find(|l| l.v == w).map_or(0, |l| l.m)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rings_list_incident_faces_in_order_and_skip_dead_faces() {
        let faces = [[0, 1, 2], [0, 2, 3], [DEAD, DEAD, DEAD], [3, 2, 4]];
        let mut t = RingTable::default();
        t.rebuild(6, &faces);
        let faces_of =
            |t: &RingTable, v: u32| t.ring(v).iter().map(|&e| entry_face(e)).collect::<Vec<_>>();
        let corners_of = |t: &RingTable, v: u32| {
            t.ring(v)
                .iter()
                .map(|&e| entry_corner(e))
                .collect::<Vec<_>>()
        };
        assert_eq!(faces_of(&t, 0), [0, 1]);
        assert_eq!(corners_of(&t, 0), [0, 0]);
        assert_eq!(faces_of(&t, 2), [0, 1, 3]);
        assert_eq!(corners_of(&t, 2), [2, 1, 1]);
        assert_eq!(faces_of(&t, 4), [3]);
        assert_eq!(corners_of(&t, 4), [2]);
        assert!(t.ring(5).is_empty());
        // Rebuilding smaller reuses and truncates.
        t.rebuild(3, &faces[..1]);
        assert_eq!(faces_of(&t, 1), [0]);
        assert_eq!(corners_of(&t, 1), [1]);
        assert_eq!(t.off.len(), 4);
    }
}
