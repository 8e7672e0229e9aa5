//! The 48 symmetries of the cube (6 axis permutations × 8 reflections),
//! acting on its corners: the group both 256-case tables are generated
//! under — marching cubes' (`lodkit-mco`) and the octree particles' direct
//! triangulation (`lodkit-particles`).
//!
//! Corner `v` (`0..8`) of the unit cube has coordinate `i` equal to bit `i`
//! of `v` (x lowest); a configuration is a set of corners, bit `v` of a
//! `u8`. A symmetry maps new coordinate `i` to old coordinate `perm[i]`,
//! flipped when bit `i` of `flip` is set.

/// One of the 48 symmetries of the cube (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub struct CubeSymmetry {
    /// New coordinate `i` is old coordinate `perm[i]`.
    pub perm: [u8; 3],
    /// Bit `i`: coordinate `i` is mirrored.
    pub flip: u8,
}

/// The axis permutations, even ones first (identity first).
const PERMS: [[u8; 3]; 6] = [
    [0, 1, 2],
    [1, 2, 0],
    [2, 0, 1],
    [0, 2, 1],
    [2, 1, 0],
    [1, 0, 2],
];

impl CubeSymmetry {
    /// The identity.
    pub const IDENTITY: CubeSymmetry = CubeSymmetry {
        perm: [0, 1, 2],
        flip: 0,
    };

    /// All 48, identity first: per axis permutation (even ones first),
    /// the eight reflections `flip = 0..8`. Table generators that break
    /// ties by the first symmetry found depend on this order; it is fixed.
    pub const ALL: [CubeSymmetry; 48] = {
        let mut out = [CubeSymmetry::IDENTITY; 48];
        let mut k = 0;
        while k < 48 {
            out[k] = CubeSymmetry {
                perm: PERMS[k / 8],
                flip: (k % 8) as u8,
            };
            k += 1;
        }
        out
    };

    /// All 48 (as [`CubeSymmetry::ALL`]).
    pub fn all() -> Vec<CubeSymmetry> {
        Self::ALL.to_vec()
    }

    /// Image of corner `v`.
    #[inline]
    pub const fn vertex(&self, v: u8) -> u8 {
        let mut out = 0;
        let mut i = 0;
        while i < 3 {
            let bit = ((v >> self.perm[i]) & 1) ^ ((self.flip >> i) & 1);
            out |= bit << i;
            i += 1;
        }
        out
    }

    /// The image of every corner, `map[v]` = [`vertex`](Self::vertex)`(v)`.
    pub const fn corner_map(&self) -> [u8; 8] {
        let mut map = [0u8; 8];
        let mut v = 0;
        while v < 8 {
            map[v as usize] = self.vertex(v);
            v += 1;
        }
        map
    }

    /// Image of a configuration (the corner set mapped corner by corner).
    pub const fn config(&self, c: u8) -> u8 {
        let mut out = 0u8;
        let mut v = 0;
        while v < 8 {
            if c & (1 << v) != 0 {
                out |= 1 << self.vertex(v);
            }
            v += 1;
        }
        out
    }

    /// Whether the symmetry is a reflection (reverses orientation, so a
    /// mapped triangle's winding must be reversed).
    pub const fn reverses(&self) -> bool {
        let odd_perm = matches!(self.perm, [0, 2, 1] | [2, 1, 0] | [1, 0, 2]);
        odd_perm ^ (self.flip.count_ones() % 2 == 1)
    }
}

/// Smallest image of the configuration `c` under the 48 symmetries: the
/// representative of its class.
pub fn canonical(c: u8) -> u8 {
    CubeSymmetry::ALL
        .iter()
        .map(|g| g.config(c))
        .min()
        .unwrap_or(c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_48_symmetries_are_distinct_corner_permutations() {
        let maps: std::collections::BTreeSet<[u8; 8]> =
            CubeSymmetry::ALL.iter().map(|g| g.corner_map()).collect();
        assert_eq!(maps.len(), 48);
        for m in &maps {
            let mut sorted = *m;
            sorted.sort_unstable();
            assert_eq!(sorted, [0, 1, 2, 3, 4, 5, 6, 7]);
        }
        assert_eq!(CubeSymmetry::ALL[0], CubeSymmetry::IDENTITY);
    }

    #[test]
    fn half_reverse_orientation_and_edges_stay_edges() {
        let n = CubeSymmetry::ALL.iter().filter(|g| g.reverses()).count();
        assert_eq!(n, 24);
        for g in CubeSymmetry::ALL {
            for a in 0..8u8 {
                for i in 0..3 {
                    let b = a ^ (1 << i);
                    assert_eq!((g.vertex(a) ^ g.vertex(b)).count_ones(), 1);
                }
            }
        }
    }

    #[test]
    fn the_256_configurations_fall_into_22_classes() {
        let classes: std::collections::BTreeSet<u8> = (0..=255u8).map(canonical).collect();
        assert_eq!(classes.len(), 22);
    }
}
