//! OBJ (stub: replaced by the formats work).
use crate::error::ParseError;
use crate::mesh::TriMesh;

pub fn read(_bytes: &[u8]) -> Result<TriMesh, ParseError> {
    Err(ParseError::new("not implemented yet"))
}

pub fn write(_out: &mut Vec<u8>, _m: &TriMesh) -> std::io::Result<()> {
    Err(std::io::Error::other("not implemented yet"))
}
