//! XYZ / PTS point clouds (stub: replaced by the formats work).
use crate::error::ParseError;
use crate::mesh::PointCloud;

pub fn read_xyz(_bytes: &[u8]) -> Result<PointCloud, ParseError> {
    Err(ParseError::new("not implemented yet"))
}
pub fn read_pts(_bytes: &[u8]) -> Result<PointCloud, ParseError> {
    Err(ParseError::new("not implemented yet"))
}
pub fn write_xyz(_out: &mut Vec<u8>, _p: &PointCloud) -> std::io::Result<()> {
    Err(std::io::Error::other("not implemented yet"))
}
pub fn write_pts(_out: &mut Vec<u8>, _p: &PointCloud) -> std::io::Result<()> {
    Err(std::io::Error::other("not implemented yet"))
}
