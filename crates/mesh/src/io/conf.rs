//! Stanford `.conf` alignment files (stub: replaced by the formats work).
use crate::error::ParseError;
use crate::mesh::Pose;

/// One `bmesh FILE tx ty tz qx qy qz qw` line.
#[derive(Debug, Clone, PartialEq)]
pub struct ConfEntry {
    pub file: String,
    /// Scan-to-world transform.
    pub pose: Pose,
}

pub fn read(_text: &str) -> Result<Vec<ConfEntry>, ParseError> {
    Err(ParseError::new(".conf reading is not implemented yet"))
}
