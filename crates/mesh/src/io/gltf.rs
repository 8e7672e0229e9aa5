//! glTF 2.0 / GLB (stub: replaced by the formats work).
use std::path::Path;

use crate::error::ParseError;
use crate::mesh::TriMesh;

pub fn read(_bytes: &[u8], _base_dir: Option<&Path>) -> Result<TriMesh, ParseError> {
    Err(ParseError::new("glTF reading is not implemented yet"))
}

/// Writes one node per `(name, mesh)` level into a single GLB.
pub fn write_glb(_levels: &[(&str, &TriMesh)]) -> Result<Vec<u8>, ParseError> {
    Err(ParseError::new("GLB writing is not implemented yet"))
}
