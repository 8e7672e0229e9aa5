//! Spatial partition: a `g × g × g` grid of blocks over the bounding box;
//! a face goes to the block holding its centroid. Round `r` shifts the
//! grid by `r / 2` of a block along every axis (wrapping), so the cuts of
//! one round fall in the middle of the blocks of the next, and the faces
//! locked along a cut in round 0 are free in round 1.

use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::soup::{self, Corner, Layout};

/// The grid of one round.
#[derive(Debug, Clone, Copy)]
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
    pub fn block_of(&self, t: &[Corner; 3]) -> usize {
        let c = (t[0].position + t[1].position + t[2].position) / 3.0;
        let g = self.g as i64;
        let axis = |x: f32| -> i64 {
            let k = (x + self.shift).floor() as i64;
            k.rem_euclid(g)
        };
        let q = (c - self.min) / self.cell;
        ((axis(q.z) * g + axis(q.y)) * g + axis(q.x)) as usize
    }
}

/// Per-block soup writers of one round, opened on first use.
pub struct Writers {
    dir: PathBuf,
    layout: Layout,
    files: Vec<Option<BufWriter<File>>>,
    /// Faces written per block.
    pub counts: Vec<u64>,
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
        }
    }

    /// Appends face `t` to block `b`.
    pub fn put(&mut self, b: usize, t: &[Corner; 3]) -> std::io::Result<()> {
        if self.files[b].is_none() {
            let f = File::create(block_input(&self.dir, b))?;
            self.files[b] = Some(BufWriter::with_capacity(1 << 16, f));
        }
        self.counts[b] += 1;
        match self.files[b].as_mut() {
            Some(w) => soup::put(w, self.layout, t),
            None => unreachable!("opened above"),
        }
    }

    /// Flushes and syncs every file; returns the per-block face counts.
    pub fn finish(self) -> std::io::Result<Vec<u64>> {
        for w in self.files.into_iter().flatten() {
            let mut w = w;
            w.flush()?;
            w.into_inner().map_err(|e| e.into_error())?.sync_all()?;
        }
        Ok(self.counts)
    }
}
