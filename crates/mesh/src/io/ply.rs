//! PLY (stub: replaced by the formats work).
use crate::error::ParseError;
use crate::mesh::{Model, PointCloud, TriMesh};

pub fn read(_bytes: &[u8]) -> Result<Model, ParseError> {
    Err(ParseError::new("not implemented yet"))
}
pub fn write_mesh(_out: &mut Vec<u8>, _m: &TriMesh, _ascii: bool) -> std::io::Result<()> {
    Err(std::io::Error::other("not implemented yet"))
}
pub fn write_points(_out: &mut Vec<u8>, _p: &PointCloud, _ascii: bool) -> std::io::Result<()> {
    Err(std::io::Error::other("not implemented yet"))
}
