//! One pass over the cloud on every thread: the file is decoded in
//! chunks on a thread of its own while the pool works on the chunks read
//! before, and each chunk's result is handed back in input order, so a
//! pass's outcome does not depend on the thread count.

use std::sync::mpsc::sync_channel;

use rayon::prelude::*;

use super::SPILL_PASS;
use super::cloud_stream::{Point, Source};
use crate::{Error, OutOfCoreEvent, Result};

/// What the reader returns when the pass stopped it (the pass's own
/// error is the one reported).
const STOPPED: &str = "pass stopped";

/// Points per chunk and chunks per batch of a pass in about `bytes` of
/// memory: a batch being worked on, a batch queued, the chunk being read.
pub(super) fn chunking(bytes: u64) -> (usize, usize) {
    let batch = (2 * rayon::current_num_threads()).clamp(2, 16);
    let per_chunk = bytes / (2 * batch as u64 + 1) / std::mem::size_of::<Point>() as u64;
    (per_chunk.clamp(1 << 10, 1 << 15) as usize, batch)
}

/// Calls `work` with every chunk of `chunk` points (the last may be
/// shorter) and the input index of its first point, `batch` chunks at a
/// time on the pool, while the next chunks are decoded (with positions
/// only, the rest zero, unless `attributes`); then `merge` with each
/// chunk and its result, in input order, on this thread. Errors: the
/// first of the reader's (the stream readers' checks) and `work`'s or
/// `merge`'s. Memory: `2 · batch + 1` chunks of [`Point`]s and `batch`
/// results.
pub(super) fn parallel_pass<R: Send>(
    source: &Source,
    attributes: bool,
    (chunk, batch): (usize, usize),
    work: &(dyn Fn(u32, &[Point]) -> Result<R> + Sync),
    merge: &mut dyn FnMut(&[Point], R) -> Result<()>,
) -> Result<()> {
    std::thread::scope(|s| {
        let (tx, rx) = sync_channel::<Vec<Point>>(batch);
        let reader = s.spawn(move || {
            let mut buf = Vec::with_capacity(chunk);
            source.for_each(attributes, &mut |_, p| {
                buf.push(*p);
                if buf.len() == chunk {
                    let full = std::mem::replace(&mut buf, Vec::with_capacity(chunk));
                    tx.send(full).map_err(|_| Error::Input(STOPPED.into()))?;
                }
                Ok(())
            })?;
            if !buf.is_empty() {
                tx.send(buf).map_err(|_| Error::Input(STOPPED.into()))?;
            }
            Ok(())
        });
        let mut first = 0u32;
        let mut run = || -> Result<()> {
            loop {
                let mut got: Vec<(u32, Vec<Point>)> = Vec::with_capacity(batch);
                while got.len() < batch {
                    let Ok(c) = rx.recv() else { break };
                    let n = c.len() as u32;
                    got.push((first, c));
                    first = first.wrapping_add(n);
                }
                if got.is_empty() {
                    return Ok(());
                }
                let results: Vec<Result<R>> = got
                    .par_iter()
                    .map(|(start, points)| work(*start, points))
                    .collect();
                for ((_, points), r) in got.iter().zip(results) {
                    merge(points, r?)?;
                }
            }
        };
        let ours = run();
        // Stops the reader if it is still sending.
        drop(rx);
        let theirs = reader
            .join()
            .unwrap_or_else(|p| std::panic::resume_unwind(p));
        // The pass saw only chunks read before any error of the reader's:
        // its own error comes first in input order.
        ours.and(theirs)
    })
}

/// The passes of one build: each over the whole cloud, on every thread
/// ([`parallel_pass`]), with its progress.
pub(super) struct Passes<'a> {
    pub(super) source: &'a Source,
    pub(super) total: u64,
    pub(super) chunking: (usize, usize),
    pub(super) named: &'a dyn Fn(Error) -> Error,
    pub(super) progress: &'a (dyn Fn(OutOfCoreEvent) + Sync),
}

impl Passes<'_> {
    /// [`parallel_pass`] under the phase `name`; only the spill reads
    /// more than positions.
    pub(super) fn run<R: Send>(
        &self,
        name: &str,
        work: &(dyn Fn(u32, &[Point]) -> Result<R> + Sync),
        merge: &mut dyn FnMut(&[Point], R) -> Result<()>,
    ) -> Result<()> {
        (self.progress)(OutOfCoreEvent::Phase(name, self.total));
        let attributes = name == SPILL_PASS;
        parallel_pass(
            self.source,
            attributes,
            self.chunking,
            work,
            &mut |points, r| {
                merge(points, r)?;
                (self.progress)(OutOfCoreEvent::Advance(points.len() as u64));
                Ok(())
            },
        )
        .map_err(self.named)
    }
}
