//! What both `.mco` versions share: the signature and the limits a reader
//! holds every file to.

/// File signature.
pub(crate) const MAGIC: [u8; 8] = *b"LODKMCO\0";
/// Most triangles a node can have (the table's maximum is 12; the margin
/// keeps extraction records far below their 16-bit length field).
pub(crate) const MAX_NODE_TRIANGLES: usize = 16;
/// Most substitutions one patch can hold (a face has at most 4 crossing
/// edges per fine node).
pub(crate) const MAX_PATCH_SUBS: usize = 16;
/// Files larger than this are refused before reading.
pub(crate) const MAX_FILE_BYTES: u64 = 16 << 30;
