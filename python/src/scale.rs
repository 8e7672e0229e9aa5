//! The out-of-core simplifier's block tasks (`lodkit_scale`): what a Ray
//! worker runs for `lodkit simplify --ray` (`pylodkit.blocks`).

use std::path::PathBuf;

use pyo3::prelude::*;

use crate::errors::input;

/// `block_task_count(path) -> int`: tasks in a block task file (one
/// round of an out-of-core simplification, written by lodkit).
#[pyfunction]
pub fn block_task_count(py: Python<'_>, path: PathBuf) -> PyResult<usize> {
    let (_, _, tasks) = py
        .detach(|| lodkit_scale::read_tasks(&path))
        .map_err(input)?;
    Ok(tasks.len())
}

/// `run_block_task(path, index) -> (faces_in, faces_out)`: simplifies
/// block `index` of the task file `path` and writes its output beside it
/// (atomically; a block already done is not run again).
#[pyfunction]
pub fn run_block_task(py: Python<'_>, path: PathBuf, index: usize) -> PyResult<(u64, u64)> {
    let r = py
        .detach(|| lodkit_scale::run_task(&path, index))
        .map_err(input)?;
    Ok((r.faces_in, r.faces_out))
}
