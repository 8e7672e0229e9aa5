//! The build folder: written as a whole or not at all, and never over a
//! user's files — `lodkit_mesh::io::out_folder`'s rule (its docs say what
//! a build may replace), with a refusal as a [`Usage`] error (exit 2).

use std::path::Path;

use anyhow::Result;
use lodkit_mesh::io::out_folder::{self, FolderError};

use crate::usage::Usage;

/// A build's temporary output folder (see `out_folder::Staging`).
pub struct Staging(out_folder::Staging);

fn job_error(e: FolderError) -> anyhow::Error {
    match e {
        FolderError::Refused(m) => Usage(m).into(),
        e => anyhow::Error::new(e),
    }
}

impl Staging {
    /// Checks `target` (absent, empty, or a lodkit build that does not
    /// hold `input`) and creates the temporary sibling. Errors: a
    /// [`Usage`] naming what is not lodkit's, or I/O creating the folders.
    pub fn new(target: &Path, input: Option<&Path>) -> Result<Self> {
        out_folder::Staging::new(target, input)
            .map(Staging)
            .map_err(job_error)
    }

    /// The temporary folder every output is written into.
    pub fn dir(&self) -> &Path {
        self.0.dir()
    }

    /// Lists every file in the manifest and moves the folder into place.
    pub fn commit(self) -> Result<()> {
        self.0.commit().map_err(job_error)
    }
}
