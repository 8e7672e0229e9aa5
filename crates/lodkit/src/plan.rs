//! In core or out of core: whether an input is simplified in memory or in
//! blocks staged on disk ([`lodkit_scale`]), with which budget, and the
//! staging folder's care (kept for a resume on failure, removed once the
//! outputs are in place). Scale's sizing constants stay behind
//! [`out_of_core_plan`].
use std::path::{Path, PathBuf};

use anyhow::Result;

use crate::progress::{Progress, human_bytes};

/// Where a job too big for memory runs: `--memory` and `--ray` of
/// `simplify` and `lods`.
#[derive(Debug, Clone, Default)]
pub struct OutOfCore {
    /// Memory budget in bytes, within [`crate::limits::MEMORY`]. A binary PLY or STL whose in-core estimate (80 bytes per face)
    /// exceeds it is simplified out of core, in blocks staged beside the
    /// output (--target or --ratio; normals, colours, UVs kept), with the in-core
    /// error when SIZE is at least 320 bytes per target face. Default: a
    /// third of the machine's memory.
    pub memory: Option<u64>,
    /// Run the blocks of an out-of-core run as Ray tasks: `local` starts a
    /// local cluster for the run, `auto` or HOST:PORT joins a running one
    /// (every node must see the output's folder at the same path). Needs a
    /// Python with pylodkit and ray (`python3`, or $LODKIT_PYTHON). The
    /// output is the same bytes as without.
    pub ray: Option<String>,
}

impl OutOfCore {
    /// Where the blocks run.
    pub fn runner(&self) -> lodkit_scale::Runner {
        match &self.ray {
            None => lodkit_scale::Runner::Threads,
            Some(address) => lodkit_scale::Runner::Ray {
                address: address.clone(),
                python: std::env::var_os("LODKIT_PYTHON")
                    .map_or_else(|| "python3".into(), PathBuf::from),
                workers: None,
            },
        }
    }
}

/// Why an input goes out of core: its estimated in-core bytes over the
/// budget.
pub struct Plan {
    pub memory: u64,
    pub in_core: u64,
    pub file_bytes: u64,
    /// Face records in the file's header.
    pub faces: u64,
}

/// Whether `a.input` is simplified out of core: a `.ply` that
/// [`lodkit_scale::needs_out_of_core`] says would not fit `--memory` and
/// that the stream reader accepts (binary, vertices then faces). A `.ply`
/// too big but not streamable (ASCII, another layout) is simplified in
/// core as before, with one line saying so; every other input takes the
/// in-core path untouched. Options the out-of-core path cannot honour are
/// refused here (exit 2), before anything is written: falling back in
/// core would risk exactly the memory exhaustion `--memory` guards.
pub fn out_of_core_plan(
    events: &Progress,
    input: &Path,
    scale: &OutOfCore,
    o: &lodkit_simplify::Options,
) -> Result<Option<Plan>> {
    use lodkit_mesh::io::Format;
    let per_face = match Format::from_path(input) {
        Some(Format::Ply) => lodkit_scale::PLY_BYTES_PER_FACE,
        Some(Format::Stl) => lodkit_scale::STL_BYTES_PER_FACE,
        _ => return Ok(None),
    };
    let Ok(meta) = std::fs::metadata(input) else {
        // The in-core reader reports a missing file as it always has.
        return Ok(None);
    };
    let memory = scale.memory.unwrap_or_else(lodkit_scale::default_memory);
    let file_bytes = meta.len();
    let in_core = lodkit_scale::in_core_bytes(file_bytes, per_face);
    if !meta.is_file() || in_core <= memory {
        return Ok(None);
    }
    let streamed = if per_face == lodkit_scale::STL_BYTES_PER_FACE {
        lodkit_mesh::io::stl_stream::StlStream::open(input).map(|s| s.triangles())
    } else {
        lodkit_mesh::io::ply::stream::PlyStream::open(input).map(|s| s.face_records())
    };
    let faces = match streamed {
        Ok(n) => n,
        Err(e) => {
            events.status(format!(
                "note: {} needs about {} in core, over --memory {}, but cannot be streamed ({e}); simplifying in core",
                input.display(),
                human_bytes(in_core),
                human_bytes(memory),
            ));
            return Ok(None);
        }
    };
    let refused = [
        (o.max_error.is_some(), "--max-error"),
        (o.prune.is_some(), "--prune"),
    ];
    let refused: Vec<&str> = refused.iter().filter(|r| r.0).map(|r| r.1).collect();
    if !refused.is_empty() {
        return Err(crate::usage::usage(format!(
            "{}: needs about {} in core, over --memory {}, so it would be simplified out of core, \
             which simplifies to a face budget and does not honour {}; drop {} \
             or give a --memory of at least {} to simplify in core",
            input.display(),
            human_bytes(in_core),
            human_bytes(memory),
            refused.join(", "),
            if refused.len() == 1 { "it" } else { "them" },
            human_bytes(in_core),
        )));
    }
    Ok(Some(Plan {
        memory,
        in_core,
        file_bytes,
        faces,
    }))
}

/// The error `e` of an out-of-core run whose staging folder is `staging`,
/// saying that the folder stays and what it is for (unless the error
/// names it already: another run holds it, it is not lodkit's). No
/// folder: refused before any block was staged (a bad input, `--ray`
/// without pylodkit), nothing to say.
pub(crate) fn kept(e: &dyn std::fmt::Display, staging: &Path) -> anyhow::Error {
    let e = e.to_string();
    if !staging.exists() || e.contains(&staging.display().to_string()) {
        return anyhow::anyhow!("{e}");
    }
    anyhow::anyhow!(
        "{e} (finished blocks are kept in {}: the same command resumes from them; \
         another run for this output removes them)",
        staging.display()
    )
}

/// Removes the staging folder once the outputs are in place; one that
/// cannot be removed (or that another run has taken since) is said, not
/// an error: the outputs are good.
pub(crate) fn remove_staging(events: &Progress, staging: &Path) {
    match lodkit_scale::remove_staging(staging) {
        Ok(true) => {}
        Ok(false) => events.status(format!(
            "note: the staging folder {} is left to the run that now holds it",
            staging.display()
        )),
        Err(e) => events.status(format!("note: could not remove the staging folder: {e}")),
    }
}
