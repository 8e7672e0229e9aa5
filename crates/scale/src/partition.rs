//! Spatial partition: a `g × g × g` grid of blocks over the bounding box;
//! a face goes to the block holding its centroid. Round `r` shifts the
//! grid by `r / 2` of a block along every axis (wrapping), so the cuts of
//! one round fall in the middle of the blocks of the next, and the faces
//! locked along a cut in round 0 are free in round 1.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use glam::{Vec3, Vec3A};

use crate::soup::{self, Corner, Layout, Sum};

/// The grid of one round.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// Lower corner of the bounding box.
    pub min: Vec3,
    /// Side of a block along each axis (positive).
    pub cell: Vec3,
    /// Blocks per axis.
    pub g: u32,
    /// Shift in blocks (0 or 0.5).
    pub shift: f32,
}

impl Grid {
    /// A grid of `g³` blocks over `[min, max]`, shifted by `shift` blocks.
    pub fn new(min: Vec3, max: Vec3, g: u32, shift: f32) -> Grid {
        let g = g.max(1);
        let cell = ((max - min) / g as f32).max(Vec3::splat(f32::MIN_POSITIVE));
        Grid {
            min,
            cell,
            g,
            shift,
        }
    }

    /// Blocks in the grid.
    pub fn blocks(&self) -> usize {
        (self.g as usize).pow(3)
    }

    /// The block of a face (by its centroid; NaN-free input).
    #[inline]
    pub fn block_of(&self, t: &[Corner; 3]) -> usize {
        let c = (t[0].position + t[1].position + t[2].position) / 3.0;
        let g = self.g as usize;
        let q = (c - self.min) / self.cell;
        (self.axis(q.z) * g + self.axis(q.y)) * g + self.axis(q.x)
    }

    /// The block index along one axis of a point at `q` cells from the
    /// grid's lower corner. `q` is clamped into the grid (a centroid
    /// rounded an ulp outside the box stays in the edge cell, so the
    /// grid's outer faces are never cuts), then shifted and wrapped.
    #[inline]
    fn axis(&self, q: f32) -> usize {
        // The largest float below `g` (g >= 1); `max` first takes a NaN
        // to 0.
        let g = self.g.max(1);
        let top = f32::from_bits((g as f32).to_bits() - 1);
        let k = (q.max(0.0).min(top) + self.shift).floor() as i64;
        k.rem_euclid(g as i64) as usize
    }
}

/// The cuts of one round: its grid, and `reach`, the largest distance
/// from a corner of a face of the round's input to the face's centroid.
///
/// Every face with a corner at `p` has its centroid within `reach` of
/// `p`, so where the box of half-side `reach` around `p` lies in one grid
/// cell, every such face is in that cell's block: a vertex there is used
/// by one block only, and a border edge through it is the mesh's own
/// border (a scan's rim, a hole), not a cut. A block locks only the
/// vertices that may lie on a cut ([`Cuts::may_cross`]); its real border
/// simplifies as in core.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Cuts {
    /// The round's grid.
    pub grid: Grid,
    /// The largest corner-to-centroid distance of the round's faces
    /// (object units; infinite or NaN: every vertex may cross).
    pub reach: f32,
}

impl Cuts {
    /// Whether a corner at `p` of a face in some block may also be a
    /// corner of a face in another block: whether the box of half-side
    /// `reach` around `p` (grown by 2⁻¹⁰ of itself and 2⁻²⁰ of the
    /// coordinates, far above the rounding of the centroid and of
    /// [`Grid::block_of`]'s arithmetic) meets more than one block's cells
    /// along an axis (the box clamped into the grid, as centroids are).
    /// True on NaN.
    pub fn may_cross(&self, p: Vec3) -> bool {
        let g = &self.grid;
        let size = p.abs().max_element() + g.min.abs().max_element();
        let r = self.reach * (1.0 + 1.0 / 1024.0) + size * (1.0 / (1u32 << 20) as f32);
        (0..3).any(|i| {
            let lo = (p[i] - r - g.min[i]) / g.cell[i];
            let hi = (p[i] + r - g.min[i]) / g.cell[i];
            // Under one cell long, the interval meets one or two cells;
            // one if its ends are in the same (`axis` is monotone up to
            // the wrap, which needs a whole cell).
            let short = hi - lo < 1.0; // false on NaN
            !short || g.axis(lo) != g.axis(hi)
        })
    }
}

/// Per-block soup writers of one round, opened on first use (as new
/// files: one found under a block's name is removed, never written
/// through), each file's [`Sum`] kept as it is written.
pub struct Writers {
    dir: PathBuf,
    layout: Layout,
    files: Vec<Option<BufWriter<File>>>,
    /// Faces written per block.
    pub counts: Vec<u64>,
    sums: Vec<Sum>,
    /// Nine times the largest squared corner-to-centroid distance of the
    /// faces written ([`Cuts::reach`]: `|3a − (a + b + c)|` is three times
    /// corner `a`'s distance to the centroid, without a division).
    reach2x9: f32,
}

/// The file of block `b` in round folder `dir`.
pub fn block_input(dir: &Path, b: usize) -> PathBuf {
    dir.join(format!("b{b:05}.in"))
}

/// The simplified output of block `b` in round folder `dir`.
pub fn block_output(dir: &Path, b: usize) -> PathBuf {
    dir.join(format!("b{b:05}.out"))
}

impl Writers {
    /// Writers for `blocks` blocks of `layout` in `dir` (which must exist).
    pub fn new(dir: &Path, blocks: usize, layout: Layout) -> Writers {
        Writers {
            dir: dir.to_path_buf(),
            layout,
            files: (0..blocks).map(|_| None).collect(),
            counts: vec![0; blocks],
            sums: vec![Sum::NEW; blocks],
            reach2x9: 0.0,
        }
    }

    /// [`Cuts::reach`] of the faces written so far.
    pub fn reach(&self) -> f32 {
        self.reach2x9.sqrt() / 3.0
    }

    /// Appends face `t` to block `b`.
    pub fn put(&mut self, b: usize, t: &[Corner; 3]) -> std::io::Result<()> {
        if self.files[b].is_none() {
            let f = soup::create_new(&block_input(&self.dir, b))?;
            self.files[b] = Some(BufWriter::with_capacity(1 << 16, f));
        }
        self.counts[b] += 1;
        // Vec3A: the four-lane form, one vector operation per step.
        let [p, q, s] = t.map(|c| Vec3A::from(c.position));
        let sum = p + q + s;
        let far = (3.0 * p - sum)
            .length_squared()
            .max((3.0 * q - sum).length_squared())
            .max((3.0 * s - sum).length_squared());
        self.reach2x9 = self.reach2x9.max(far);
        let mut bytes = [0u8; soup::MAX_FACE_BYTES];
        let k = soup::encode(self.layout, t, &mut bytes);
        self.sums[b].add(&bytes[..k]);
        match self.files[b].as_mut() {
            Some(w) => w.write_all(&bytes[..k]),
            None => unreachable!("opened above"),
        }
    }

    /// Flushes and syncs every file; returns the per-block face counts
    /// and the checksums of the block files ([`Sum::NEW`] for a block
    /// without faces, which has no file).
    pub fn finish(self) -> std::io::Result<(Vec<u64>, Vec<Sum>)> {
        for w in self.files.into_iter().flatten() {
            let mut w = w;
            w.flush()?;
            w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        }
        Ok((self.counts, self.sums))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A vertex whose reach stays inside its cell is not on a cut; one
    /// within reach of a cell face, or of the wrapped face of a shifted
    /// grid, may be; a NaN may be.
    #[test]
    fn a_vertex_may_cross_only_within_reach_of_a_cell_face() {
        let grid = Grid::new(Vec3::ZERO, Vec3::splat(3.0), 3, 0.0);
        let cuts = Cuts { grid, reach: 0.1 };
        assert!(!cuts.may_cross(Vec3::new(1.5, 0.5, 2.5)));
        assert!(cuts.may_cross(Vec3::new(1.95, 0.5, 2.5)));
        assert!(cuts.may_cross(Vec3::new(1.5, 1.02, 2.5)));
        // Half a block shifted: the cell faces are at 0.5, 1.5, 2.5.
        let shifted = Cuts {
            grid: Grid::new(Vec3::ZERO, Vec3::splat(3.0), 3, 0.5),
            reach: 0.1,
        };
        assert!(shifted.may_cross(Vec3::new(1.5, 1.0, 1.0)));
        assert!(!shifted.may_cross(Vec3::new(1.0, 1.0, 1.0)));
        assert!(cuts.may_cross(Vec3::new(f32::NAN, 0.5, 0.5)));
        // The grid's outer faces are not cuts, shifted or not.
        assert!(!cuts.may_cross(Vec3::new(0.01, 2.99, 1.5)));
        assert!(!shifted.may_cross(Vec3::new(0.01, 2.99, 1.0)));
        // But the shifted grid's wrapped block meets its neighbours.
        assert!(shifted.may_cross(Vec3::new(2.52, 1.0, 1.0)));
        let far = Cuts {
            grid,
            reach: f32::INFINITY,
        };
        assert!(far.may_cross(Vec3::new(1.5, 1.5, 1.5)));
    }

    /// Every corner of a face that lands in another block than one of its
    /// neighbours' is found by `may_cross`, with the reach the writers
    /// measured: on a fine random-ish triangle fan across the grid.
    #[test]
    fn every_shared_vertex_may_cross() {
        let grid = Grid::new(Vec3::ZERO, Vec3::splat(1.0), 4, 0.5);
        let d = tempfile::tempdir().unwrap();
        let mut w = Writers::new(d.path(), grid.blocks(), Layout::default());
        let n = 40;
        let at = |i: u32, j: u32| {
            let (x, y) = (i as f32 / n as f32, j as f32 / n as f32);
            Vec3::new(x, y, 0.5 + 0.3 * (7.0 * x).sin() * (5.0 * y).cos())
        };
        let mut faces = Vec::new();
        for i in 0..n {
            for j in 0..n {
                faces.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                faces.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
        let mut block_of_vertex = std::collections::HashMap::new();
        let mut shared = std::collections::HashSet::new();
        for f in &faces {
            let tri = f.map(|p| Corner {
                position: p,
                ..Default::default()
            });
            let b = grid.block_of(&tri);
            w.put(b, &tri).unwrap();
            for p in f {
                let key = p.to_array().map(f32::to_bits);
                if *block_of_vertex.entry(key).or_insert(b) != b {
                    shared.insert(key);
                }
            }
        }
        let cuts = Cuts {
            grid,
            reach: w.reach(),
        };
        assert!(shared.len() > 100, "{} shared", shared.len());
        for k in &shared {
            assert!(cuts.may_cross(Vec3::from_array(k.map(f32::from_bits))));
        }
        // Many vertices are not near a cut (cells 10 vertices wide).
        let free = block_of_vertex
            .keys()
            .filter(|k| !cuts.may_cross(Vec3::from_array(k.map(f32::from_bits))))
            .count();
        assert!(free > block_of_vertex.len() / 3, "{free}");
    }
}
