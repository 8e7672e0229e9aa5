//! Where a round's blocks run: on this process's threads, or as Ray tasks
//! over the shared staging folder. Both run the same [`simplify_block`]
//! on the same files, and the pipeline reads the outputs back from disk
//! either way, so the result is the same bytes wherever the blocks ran.

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use lodkit_simplify::Options;
use rayon::prelude::*;

use crate::block::simplify_block;
use crate::soup::Layout;
use crate::tasks::{BlockTask, write_tasks};

/// Blocks simplified at once on this machine, at most: the budget is
/// shared among this many, whatever the thread count, so the grid (and so
/// the output) depends on `--memory` alone; a machine with more threads
/// runs this many blocks at a time.
pub(crate) const BLOCKS_IN_FLIGHT: u64 = 4;

/// Where [`simplify_file`](crate::simplify_file)'s blocks run.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub enum Runner {
    /// On this process's threads (at most four blocks at once).
    #[default]
    Threads,
    /// As Ray tasks: `python -m pylodkit.blocks TASKS --address ADDRESS`,
    /// one task per block, over the staging folder, which every Ray node
    /// must see at the same path (a shared folder).
    Ray {
        /// `local` (a local cluster of `workers` CPUs, started and
        /// stopped by the run), `auto`, or `HOST:PORT` of a running one.
        address: String,
        /// The Python interpreter that has `pylodkit` and `ray`.
        python: PathBuf,
        /// CPUs of a local cluster (default: all).
        workers: Option<usize>,
    },
}

impl Runner {
    /// Checks, before any work, that the blocks can run: for Ray, that the
    /// interpreter starts and imports `pylodkit.blocks` and `ray` (so a
    /// missing package fails in a second, not after a long partition).
    pub fn check(&self) -> Result<(), String> {
        let Runner::Ray { python, .. } = self else {
            return Ok(());
        };
        let out = Command::new(python)
            .args(["-c", "import pylodkit.blocks, ray"])
            .stdin(Stdio::null())
            .output()
            .map_err(|e| {
                format!(
                    "--ray: cannot run {} (set LODKIT_PYTHON to a Python with pylodkit and ray): {e}",
                    python.display()
                )
            })?;
        if out.status.success() {
            return Ok(());
        }
        let err = String::from_utf8_lossy(&out.stderr);
        let last = err
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("");
        Err(format!(
            "--ray: {} cannot import pylodkit and ray ({last}): pip install 'pylodkit[batch]' there, \
             or set LODKIT_PYTHON to a Python that has them",
            python.display()
        ))
    }

    /// Runs `tasks` (files in the round folder `dir`) with `opts`,
    /// calling `done(i)` once each task `i` has written its output (from
    /// any thread, in any order). Returns when every output exists, or
    /// with the first error (one line). Outputs already there are not
    /// rerun: the caller passes only the missing ones.
    pub(crate) fn run(
        &self,
        dir: &Path,
        tasks: &[BlockTask],
        opts: &Options,
        layout: Layout,
        done: &(dyn Fn(usize) + Sync),
    ) -> Result<(), String> {
        match self {
            Runner::Threads => {
                let pool = rayon::ThreadPoolBuilder::new()
                    .num_threads(rayon::current_num_threads().clamp(1, BLOCKS_IN_FLIGHT as usize))
                    .build()
                    .map_err(|e| format!("cannot start the block threads: {e}"))?;
                pool.install(|| {
                    tasks.par_iter().enumerate().try_for_each(|(i, t)| {
                        simplify_block(&t.input, &t.output, t.goal, &t.cuts, opts, layout)?;
                        let _ = std::fs::remove_file(&t.input);
                        done(i);
                        Ok(())
                    })
                })
            }
            Runner::Ray {
                address,
                python,
                workers,
            } => run_on_ray(dir, tasks, opts, layout, address, python, *workers, done),
        }
    }
}

/// Writes the round's `tasks.json` and runs `python -m pylodkit.blocks`
/// on it; each `done I FACES_IN FACES_OUT` line it prints is task `I`
/// finished. Its stderr (Ray's own chatter) goes to `ray.log` in `dir`,
/// whose last line is the error when the run fails.
#[allow(clippy::too_many_arguments)]
fn run_on_ray(
    dir: &Path,
    tasks: &[BlockTask],
    opts: &Options,
    layout: Layout,
    address: &str,
    python: &Path,
    workers: Option<usize>,
    done: &(dyn Fn(usize) + Sync),
) -> Result<(), String> {
    let dir = std::path::absolute(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    let file = dir.join("tasks.json");
    let tasks: Vec<BlockTask> = tasks
        .iter()
        .map(|t| BlockTask {
            input: dir.join(t.input.file_name().unwrap_or_default()),
            output: dir.join(t.output.file_name().unwrap_or_default()),
            ..t.clone()
        })
        .collect();
    write_tasks(&file, opts, layout, &tasks)?;
    let log = dir.join("ray.log");
    let log_file = crate::soup::create_new(&log).map_err(|e| format!("{}: {e}", log.display()))?;
    let mut cmd = Command::new(python);
    cmd.arg("-m")
        .arg("pylodkit.blocks")
        .arg(&file)
        .arg("--address")
        .arg(address);
    if let Some(w) = workers {
        cmd.arg("--workers").arg(w.to_string());
    }
    let mut child = cmd
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(log_file)
        .spawn()
        .map_err(|e| {
            format!(
                "--ray: cannot run {} (set LODKIT_PYTHON to a Python with pylodkit and ray): {e}",
                python.display()
            )
        })?;
    if let Some(out) = child.stdout.take() {
        for line in BufReader::new(out).lines() {
            let Ok(line) = line else { break };
            let mut w = line.split_whitespace();
            if let (Some("done"), Some(i)) = (w.next(), w.next().and_then(|i| i.parse().ok()))
                && i < tasks.len()
            {
                done(i);
            }
        }
    }
    let status = child
        .wait()
        .map_err(|e| format!("{}: {e}", python.display()))?;
    if !status.success() {
        let text = std::fs::read_to_string(&log).unwrap_or_default();
        let last = text
            .lines()
            .rev()
            .find(|l| !l.trim().is_empty())
            .unwrap_or("no message");
        return Err(format!(
            "--ray: the block tasks failed ({status}): {last} (log: {})",
            log.display()
        ));
    }
    if let Some(t) = tasks.iter().find(|t| !t.output.exists()) {
        return Err(format!(
            "--ray: the block tasks ended without writing {} (log: {})",
            t.output.display(),
            log.display()
        ));
    }
    for t in &tasks {
        let _ = std::fs::remove_file(&t.input);
    }
    Ok(())
}
